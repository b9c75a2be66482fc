//! Tangents for normal textures on meshes whose file gives none (glTF 2.0 §3.9.3: "client
//! implementations SHOULD calculate tangents using default MikkTSpace algorithms with the
//! specified vertex positions, normals, and texture coordinates associated with the normal
//! texture"), by the `bevy_mikktspace` crate (a safe port of Mikkelsen's reference code).

use glam::Vec3;

use crate::scene::Vertex;

/// The triangle list `indices` over `vertices`, as MikkTSpace reads and writes it.
struct Geometry<'a> {
    vertices: &'a [Vertex],
    indices: &'a [u32],
    /// Tangent sums per vertex (xyz) and the handedness votes (w).
    sums: Vec<[f32; 4]>,
}

impl bevy_mikktspace::Geometry for Geometry<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len() / 3
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.vertex(face, vert).map_or([0.0; 3], |v| v.position)
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.vertex(face, vert).map_or([0.0, 1.0, 0.0], |v| v.normal)
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.vertex(face, vert).map_or([0.0; 2], |v| v.uv)
    }
    fn set_tangent(&mut self, tangent_space: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        let (Some(t), Some(&i)) = (tangent_space, self.indices.get(face * 3 + vert)) else { return };
        let e = t.tangent_encoded();
        if let Some(s) = self.sums.get_mut(i as usize) {
            s[0] += e[0];
            s[1] += e[1];
            s[2] += e[2];
            s[3] += e[3];
        }
    }
}

impl Geometry<'_> {
    fn vertex(&self, face: usize, vert: usize) -> Option<&Vertex> {
        self.vertices.get(*self.indices.get(face * 3 + vert)? as usize)
    }
}

/// Writes MikkTSpace tangents into `vertices` (a vertex shared by faces gets the normalised
/// sum of its corners' tangents and their majority handedness; one no face gives a tangent
/// keeps zero, and the shaders then keep its normal).
pub(super) fn generate(vertices: &mut [Vertex], indices: &[u32]) {
    let mut g = Geometry { vertices, indices, sums: vec![[0.0; 4]; vertices.len()] };
    // The crate's error type has no values: generation cannot fail.
    let _ = bevy_mikktspace::generate_tangents(&mut g);
    let sums = g.sums;
    for (v, s) in vertices.iter_mut().zip(sums) {
        let t = Vec3::new(s[0], s[1], s[2]);
        v.tangent = if t.is_finite() && t.length_squared() > 1e-12 {
            t.normalize().extend(if s[3] < 0.0 { -1.0 } else { 1.0 }).to_array()
        } else {
            [0.0; 4]
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::vertex;
    use glam::Vec2;

    /// A quad in the plane with normal `n`, its u along `du` and v along `dv`.
    fn quad(n: Vec3, du: Vec3, dv: Vec3, flip_v: bool) -> (Vec<Vertex>, Vec<u32>) {
        let uv = |s: f32, t: f32| Vec2::new(s, if flip_v { 1.0 - t } else { t });
        let vs = vec![
            vertex(Vec3::ZERO, n, uv(0.0, 0.0)),
            vertex(du, n, uv(1.0, 0.0)),
            vertex(du + dv, n, uv(1.0, 1.0)),
            vertex(dv, n, uv(0.0, 1.0)),
        ];
        (vs, vec![0, 1, 2, 0, 2, 3])
    }

    /// The closed form: on a flat quad the tangent is the direction of increasing u, and
    /// the handedness says whether increasing v runs along n × t (+1) or against it (−1).
    #[test]
    fn a_flat_quad_has_the_closed_form_tangent_frame() {
        // Floor facing +y, u along +x, v along −z: n × t = y × x = −z, so v follows n × t.
        let (mut v, i) = quad(Vec3::Y, Vec3::X, Vec3::NEG_Z, false);
        generate(&mut v, &i);
        for x in &v {
            let t = glam::Vec4::from(x.tangent);
            assert!((t.truncate() - Vec3::X).length() < 1e-5, "tangent {t}");
            assert_eq!(t.w, 1.0);
        }
        // The same quad with v mirrored: the handedness flips, the tangent stays.
        let (mut v, i) = quad(Vec3::Y, Vec3::X, Vec3::NEG_Z, true);
        generate(&mut v, &i);
        for x in &v {
            let t = glam::Vec4::from(x.tangent);
            assert!((t.truncate() - Vec3::X).length() < 1e-5, "tangent {t}");
            assert_eq!(t.w, -1.0);
        }
    }

    #[test]
    fn degenerate_uvs_leave_zero_tangents_not_nan() {
        let mut v = vec![vertex(Vec3::ZERO, Vec3::Y, Vec2::ZERO); 3];
        v[1].position = [1.0, 0.0, 0.0];
        v[2].position = [0.0, 0.0, 1.0];
        generate(&mut v, &[0, 1, 2]);
        for x in &v {
            assert!(x.tangent.iter().all(|c| c.is_finite()), "{:?}", x.tangent);
        }
    }
}
