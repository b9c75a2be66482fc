//! Meshes and their triangle primitives (§3.7).

use glam::{Vec2, Vec3, Vec4};
use json::accessor::Type as AccessorType;
use json::validation::Checked;

use super::{Loader, SceneError, Skipped, json};
use crate::scene::{Mesh, Primitive, Vertex};

impl Loader<'_> {
    // -----------------------------------------------------------------------------------
    // Meshes (§3.7)
    // -----------------------------------------------------------------------------------

    /// Loads mesh `index` (shared between nodes that use it).
    pub(super) fn mesh(&mut self, index: usize) -> Result<usize, SceneError> {
        if let Some(&m) = self.mesh_map.get(&index) {
            return Ok(m);
        }
        let root = self.root;
        let m = root
            .meshes
            .get(index)
            .ok_or_else(|| self.invalid(format!("a node refers to mesh {index}, which does not exist")))?;
        let name = m.name.clone().unwrap_or_else(|| format!("mesh {index}"));
        let mut primitives = Vec::new();
        for (p, jp) in m.primitives.iter().enumerate() {
            if let Some(prim) = self.primitive(&name, p, jp)? {
                primitives.push(prim);
            }
        }
        self.scene.meshes.push(Mesh { name, primitives });
        let id = self.scene.meshes.len() - 1;
        self.mesh_map.insert(index, id);
        Ok(id)
    }

    /// Loads one primitive as a triangle list (§3.7.2). Strips and fans are converted;
    /// points and lines are skipped with a warning. Missing normals become flat normals
    /// (§3.7.2.1: "client implementations MUST calculate flat normals").
    fn primitive(&mut self, mesh: &str, p: usize, jp: &json::mesh::Primitive) -> Result<Option<Primitive>, SceneError> {
        use json::mesh::{Mode, Semantic};
        let mode = match jp.mode {
            Checked::Valid(m) => m,
            Checked::Invalid => return Err(self.invalid(format!("mesh '{mesh}' primitive {p} has an unknown mode"))),
        };
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            let name = match mode {
                Mode::Points => "POINTS (mode 0)",
                Mode::Lines => "LINES (mode 1)",
                Mode::LineLoop => "LINE_LOOP (mode 2)",
                _ => "LINE_STRIP (mode 3)",
            };
            self.warn(format!("mesh '{mesh}' primitive {p} draws {name}, which cannot be rendered; it is skipped"));
            self.skipped.push(Skipped { mesh: mesh.to_string(), primitive: p, mode: name.to_string() });
            return Ok(None);
        }
        let material = self.material(jp.material.map(|m| m.value()))?;
        let uv_use = self.material_uv.get(material).copied().unwrap_or_default();
        let what = |attr: &str| format!("{attr} of mesh '{mesh}' primitive {p}");
        let attribute = |s: Semantic| jp.attributes.get(&Checked::Valid(s)).map(|a| a.value());

        let pos_index = attribute(Semantic::Positions)
            .ok_or_else(|| self.invalid(format!("mesh '{mesh}' primitive {p} has no POSITION attribute")))?;
        let positions = self.read_floats(pos_index, &what("POSITION"), &[AccessorType::Vec3])?;
        let n = positions.len() / 3;
        let normals = match attribute(Semantic::Normals) {
            Some(i) => {
                let v = self.read_floats(i, &what("NORMAL"), &[AccessorType::Vec3])?;
                if v.len() != positions.len() {
                    return Err(self.invalid(format!(
                        "mesh '{mesh}' primitive {p}: NORMAL has {} elements but POSITION has {n}",
                        v.len() / 3
                    )));
                }
                Some(v)
            }
            None => None,
        };
        let tangents = match attribute(Semantic::Tangents) {
            Some(i) if normals.is_some() => {
                let v = self.read_floats(i, &what("TANGENT"), &[AccessorType::Vec4])?;
                if v.len() / 4 != n {
                    return Err(self.invalid(format!(
                        "mesh '{mesh}' primitive {p}: TANGENT has {} elements but POSITION has {n}",
                        v.len() / 4
                    )));
                }
                Some(v)
            }
            _ => None,
        };
        let uv_name = format!("TEXCOORD_{}", uv_use.set);
        let uvs = match attribute(Semantic::TexCoords(uv_use.set)) {
            Some(i) => {
                let v = self.read_floats(i, &what(&uv_name), &[AccessorType::Vec2])?;
                if v.len() / 2 != n {
                    return Err(self.invalid(format!(
                        "mesh '{mesh}' primitive {p}: {uv_name} has {} elements but POSITION has {n}",
                        v.len() / 2
                    )));
                }
                Some(v)
            }
            None => None,
        };
        let raw_indices = match jp.indices {
            Some(i) => {
                let indices = self.read_indices(i.value(), &what("indices"))?;
                if let Some(&bad) = indices.iter().find(|&&x| x as usize >= n) {
                    return Err(SceneError::IndexOutOfRange {
                        file: self.file.to_string(),
                        mesh: mesh.to_string(),
                        primitive: p,
                        index: bad,
                        vertex_count: n,
                    });
                }
                indices
            }
            None => {
                let count = u32::try_from(n)
                    .map_err(|_| self.invalid(format!("mesh '{mesh}' primitive {p} has too many vertices ({n})")))?;
                (0..count).collect()
            }
        };
        // The vertices this primitive builds, its own (normals given) or three per triangle,
        // charged before the strip or fan becomes a list (three indices per triangle).
        let list_len = match mode {
            Mode::TriangleStrip | Mode::TriangleFan => raw_indices.len().saturating_sub(2).saturating_mul(3),
            _ => raw_indices.len() - raw_indices.len() % 3,
        };
        let built = if normals.is_some() { n } else { list_len };
        let over = |what: &str, count: usize, max: usize| SceneError::Unsupported {
            file: self.file.to_string(),
            message: format!(
                "mesh '{mesh}' primitive {p} builds {count} {what}, which would take the scene past the {max} {what} \
                 GI Lab loads per file"
            ),
        };
        self.budget.vertices = self
            .budget
            .vertices
            .checked_sub(built)
            .ok_or_else(|| over("vertices", built, super::MAX_VERTICES_PER_FILE))?;
        self.budget.indices = self
            .budget
            .indices
            .checked_sub(list_len)
            .ok_or_else(|| over("indices", list_len, super::MAX_INDICES_PER_FILE))?;
        let indices = match mode {
            Mode::TriangleStrip => strip_to_list(&raw_indices),
            Mode::TriangleFan => fan_to_list(&raw_indices),
            _ => {
                let mut list = raw_indices;
                if !list.len().is_multiple_of(3) {
                    self.warn(format!(
                        "mesh '{mesh}' primitive {p} has {} indices, not a multiple of 3; the last {} are ignored",
                        list.len(),
                        list.len() % 3
                    ));
                    list.truncate(list.len() - list.len() % 3);
                }
                list
            }
        };
        if indices.is_empty() {
            return Ok(None);
        }

        let vec3 = |v: &[f32], i: usize| match v.get(3 * i..3 * i + 3) {
            Some(&[x, y, z]) => [x, y, z],
            _ => [0.0; 3],
        };
        let uv = |i: usize| {
            let t = match uvs.as_deref().and_then(|v| v.get(2 * i..2 * i + 2)) {
                Some(&[u, v]) => Vec2::new(u, v),
                _ => Vec2::ZERO,
            };
            uv_use.transform.map_or(t, |m| m.transform_point2(t)).to_array()
        };
        let (vertices, indices) = match &normals {
            Some(normals) => {
                let vertices = (0..n)
                    .map(|i| Vertex {
                        position: vec3(&positions, i),
                        normal: vec3(normals, i),
                        uv: uv(i),
                        tangent: [0.0; 4],
                    })
                    .collect();
                (vertices, indices)
            }
            None => {
                let mut vertices = Vec::with_capacity(indices.len());
                for tri in indices.chunks_exact(3) {
                    let corners = tri.iter().map(|&i| i as usize);
                    let p: Vec<Vec3> = corners.clone().map(|i| Vec3::from(vec3(&positions, i))).collect();
                    let normal = match p.as_slice() {
                        [a, b, c] => (*b - *a).cross(*c - *a).normalize_or(Vec3::Y),
                        _ => Vec3::Y,
                    };
                    for i in corners {
                        vertices.push(Vertex {
                            position: vec3(&positions, i),
                            normal: normal.to_array(),
                            uv: uv(i),
                            tangent: [0.0; 4],
                        });
                    }
                }
                let count = u32::try_from(vertices.len())
                    .map_err(|_| self.invalid(format!("mesh '{mesh}' primitive {p} has too many triangles")))?;
                (vertices, (0..count).collect())
            }
        };
        let mut vertices: Vec<Vertex> = vertices;
        let wants_tangents = self.scene.materials.get(material).is_some_and(|m| m.normal_texture.is_some());
        if wants_tangents {
            match &tangents {
                // The file's tangents (with normals given, one per vertex).
                Some(t) => {
                    let mut bad = 0;
                    for (i, v) in vertices.iter_mut().enumerate() {
                        let tv = Vec4::new(t[4 * i], t[4 * i + 1], t[4 * i + 2], t[4 * i + 3]);
                        let xyz = tv.truncate();
                        if xyz.is_finite() && xyz.length_squared() > 1e-12 {
                            let w = if tv.w < 0.0 { -1.0 } else { 1.0 };
                            v.tangent = xyz.normalize().extend(w).to_array();
                        } else {
                            bad += 1;
                        }
                    }
                    if bad > 0 {
                        self.warn(format!(
                            "mesh '{mesh}' primitive {p}: {bad} tangents have zero length or are not numbers; MikkTSpace \
                             tangents are used for the primitive"
                        ));
                        super::tangents::generate(&mut vertices, &indices);
                    }
                }
                None => super::tangents::generate(&mut vertices, &indices),
            }
        }
        Ok(Some(Primitive { vertices, indices, material }))
    }
}

/// Triangle strip → list (§3.7.2.1: triangle i is {v_i, v_{i+1+i%2}, v_{i+2−i%2}}).
pub(super) fn strip_to_list(v: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(v.len().saturating_sub(2) * 3);
    for (i, w) in v.windows(3).enumerate() {
        if let &[a, b, c] = w {
            if i % 2 == 0 {
                out.extend([a, b, c]);
            } else {
                out.extend([a, c, b]);
            }
        }
    }
    out
}

/// Triangle fan → list (§3.7.2.1: triangle i is {v_{i+1}, v_{i+2}, v_0}).
pub(super) fn fan_to_list(v: &[u32]) -> Vec<u32> {
    let Some((&first, rest)) = v.split_first() else { return Vec::new() };
    let mut out = Vec::with_capacity(rest.len().saturating_sub(1) * 3);
    for w in rest.windows(2) {
        if let &[b, c] = w {
            out.extend([b, c, first]);
        }
    }
    out
}
