//! The node hierarchy (§3.5), and the lights (KHR_lights_punctual) and cameras (§3.10) nodes refer to.

use glam::{Mat4, Quat, Vec3};
use json::validation::Checked;

use super::{Loader, SceneError, json};
use crate::scene::{CameraDef, Light, LightKind, Node, Projection, Transform};

impl Loader<'_> {
    // -----------------------------------------------------------------------------------
    // Node hierarchy (§3.5)
    // -----------------------------------------------------------------------------------

    /// Checks that the nodes form a forest (§3.5.2: "node hierarchy MUST be a set of disjoint
    /// strict trees"), picks the root nodes of the default scene (or scene 0, or all parentless
    /// nodes when there are no scenes) and returns them with the set of nodes under them.
    pub(super) fn hierarchy(&self) -> Result<(Vec<usize>, Vec<bool>), SceneError> {
        let nodes = &self.root.nodes;
        let n = nodes.len();
        let cycle = |reason: String| SceneError::Cycle { file: self.file.to_string(), reason };
        let mut parent: Vec<Option<usize>> = vec![None; n];
        for (p, node) in nodes.iter().enumerate() {
            for c in node.children.iter().flatten() {
                let c = c.value();
                let Some(slot) = parent.get_mut(c) else {
                    return Err(self.invalid(format!("node {p} lists child {c}, which does not exist")));
                };
                if c == p {
                    return Err(cycle(format!("node {p} is its own child")));
                }
                if let Some(q) = *slot {
                    return Err(cycle(format!("node {c} is a child of both node {q} and node {p}")));
                }
                *slot = Some(p);
            }
        }
        // Every node now has at most one parent, so a node that is not below a parentless
        // node lies on (or below) a cycle.
        let parentless: Vec<usize> = (0..n).filter(|&i| parent.get(i).is_some_and(Option::is_none)).collect();
        let below_roots = self.reach(&parentless);
        if let Some(start) = below_roots.iter().position(|r| !r) {
            let mut path = vec![start];
            let mut cur = start;
            while let Some(Some(p)) = parent.get(cur) {
                if path.contains(p) || path.len() > n {
                    path.push(*p);
                    break;
                }
                path.push(*p);
                cur = *p;
            }
            let chain: Vec<String> = path.iter().map(usize::to_string).collect();
            return Err(cycle(format!("nodes form a cycle (child → parent: {})", chain.join(" → "))));
        }

        let scene_index = match self.root.scene {
            Some(s) => Some(s.value()),
            None if !self.root.scenes.is_empty() => Some(0),
            None => None,
        };
        let roots = match scene_index {
            Some(s) => {
                let scene = self
                    .root
                    .scenes
                    .get(s)
                    .ok_or_else(|| self.invalid(format!("the default scene {s} does not exist")))?;
                let mut roots = Vec::new();
                for r in &scene.nodes {
                    let r = r.value();
                    match parent.get(r) {
                        None => return Err(self.invalid(format!("scene {s} lists node {r}, which does not exist"))),
                        Some(Some(p)) => {
                            return Err(self.invalid(format!(
                                "scene {s} lists node {r} as a root, but it is a child of node {p} (§3.5.2: scene nodes must be roots)"
                            )));
                        }
                        Some(None) if !roots.contains(&r) => roots.push(r),
                        Some(None) => {}
                    }
                }
                roots
            }
            None => parentless,
        };
        let reachable = self.reach(&roots);
        Ok((roots, reachable))
    }

    /// Marks the nodes in the subtrees of `roots` (children indices must be valid).
    fn reach(&self, roots: &[usize]) -> Vec<bool> {
        let nodes = &self.root.nodes;
        let mut seen = vec![false; nodes.len()];
        let mut stack: Vec<usize> = roots.to_vec();
        while let Some(i) = stack.pop() {
            match seen.get_mut(i) {
                Some(s) if !*s => *s = true,
                _ => continue,
            }
            if let Some(node) = nodes.get(i) {
                stack.extend(node.children.iter().flatten().map(|c| c.value()));
            }
        }
        seen
    }

    /// A node's local transform: TRS, or a matrix decomposed into TRS (§3.5.3: matrices
    /// must be decomposable). Rotations are renormalised.
    fn node_transform(&mut self, i: usize, node: &json::Node) -> Result<Transform, SceneError> {
        let (scale, rotation, translation) = match node.matrix {
            Some(m) => {
                let m = Mat4::from_cols_array(&m);
                if !m.is_finite() {
                    return Err(self.invalid(format!("node {i} has a non-finite matrix")));
                }
                let (s, r, t) = m.to_scale_rotation_translation();
                (s, r, t)
            }
            None => (
                node.scale.map_or(Vec3::ONE, Vec3::from),
                node.rotation.map_or(Quat::IDENTITY, |q| Quat::from_array(q.0)),
                node.translation.map_or(Vec3::ZERO, Vec3::from),
            ),
        };
        if !(scale.is_finite() && translation.is_finite()) {
            return Err(self.invalid(format!("node {i} has a non-finite translation or scale")));
        }
        let len = rotation.length();
        let rotation = if rotation.is_finite() && len > 1e-6 {
            rotation / len
        } else {
            self.warn(format!("node {i} has an invalid rotation; using no rotation"));
            Quat::IDENTITY
        };
        Ok(Transform { translation, rotation, scale })
    }

    /// Builds all nodes (indices stay those of the file); meshes, lights and cameras are
    /// loaded for nodes in the active scene only.
    pub(super) fn load_nodes(&mut self, reachable: &[bool]) -> Result<(), SceneError> {
        let root = self.root;
        for (i, jn) in root.nodes.iter().enumerate() {
            let transform = self.node_transform(i, jn)?;
            let active = reachable.get(i).copied().unwrap_or(false);
            let mesh = match jn.mesh {
                Some(m) if active => Some(self.mesh(m.value())?),
                _ => None,
            };
            let light_ref = jn.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
            let light = match light_ref {
                Some(l) if active => Some(self.light(l.light.value())?),
                _ => None,
            };
            let camera = match jn.camera {
                Some(c) if active => self.camera(c.value())?,
                _ => None,
            };
            if jn.skin.is_some() {
                self.warn("skinned meshes are drawn in their bind pose (skins are not supported)".to_string());
            }
            self.scene.nodes.push(Node {
                name: jn.name.clone().unwrap_or_else(|| format!("node {i}")),
                transform,
                children: jn.children.iter().flatten().map(|c| c.value()).collect(),
                mesh,
                light,
                camera,
            });
        }
        Ok(())
    }

    /// The name of the active glTF scene, or a generic one.
    pub(super) fn scene_name(&self) -> String {
        let index = self.root.scene.map_or(0, |s| s.value());
        self.root.scenes.get(index).and_then(|s| s.name.clone()).unwrap_or_else(|| "glTF scene".to_string())
    }

    // -----------------------------------------------------------------------------------
    // Lights (KHR_lights_punctual) and cameras (§3.10)
    // -----------------------------------------------------------------------------------

    /// Loads KHR_lights_punctual light `index` (shared between nodes that use it).
    fn light(&mut self, index: usize) -> Result<usize, SceneError> {
        if let Some(&l) = self.light_map.get(&index) {
            return Ok(l);
        }
        use json::extensions::scene::khr_lights_punctual::Type;
        let lights = self.root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
        let l = lights.and_then(|k| k.lights.get(index)).ok_or_else(|| {
            self.invalid(format!("a node refers to KHR_lights_punctual light {index}, which does not exist"))
        })?;
        let kind = match l.type_ {
            Checked::Valid(Type::Directional) => LightKind::Directional,
            Checked::Valid(Type::Point) => LightKind::Point,
            Checked::Valid(Type::Spot) => {
                let (inner, outer) = l
                    .spot
                    .as_ref()
                    .map_or((0.0, std::f32::consts::FRAC_PI_4), |s| (s.inner_cone_angle, s.outer_cone_angle));
                let outer_ok = outer.clamp(1e-3, std::f32::consts::FRAC_PI_2);
                let inner_ok = inner.clamp(0.0, outer_ok);
                if outer_ok != outer || inner_ok != inner || l.spot.is_none() {
                    self.warn(format!(
                        "spot light {index} has invalid or missing cone angles (inner {inner}, outer {outer}); \
                         using inner {inner_ok}, outer {outer_ok}"
                    ));
                }
                LightKind::Spot { inner_cone: inner_ok, outer_cone: outer_ok }
            }
            Checked::Invalid => {
                return Err(self.invalid(format!("KHR_lights_punctual light {index} has an unknown type")));
            }
        };
        let light = Light {
            name: l.name.clone().unwrap_or_else(|| format!("light {index}")),
            kind,
            color: Vec3::from(l.color),
            intensity: l.intensity.max(0.0),
            range: l.range.filter(|r| *r > 0.0 && r.is_finite()),
        };
        self.scene.lights.push(light);
        let id = self.scene.lights.len() - 1;
        self.light_map.insert(index, id);
        Ok(id)
    }

    /// Loads camera `index`; a camera with unusable parameters is dropped with a warning.
    fn camera(&mut self, index: usize) -> Result<Option<usize>, SceneError> {
        if let Some(&c) = self.camera_map.get(&index) {
            return Ok(c);
        }
        use json::camera::Type;
        let cam = self
            .root
            .cameras
            .get(index)
            .ok_or_else(|| self.invalid(format!("a node refers to camera {index}, which does not exist")))?;
        let projection = match (cam.type_, &cam.perspective, &cam.orthographic) {
            (Checked::Valid(Type::Perspective), Some(p), _)
                if p.yfov > 0.0 && p.yfov < std::f32::consts::PI && p.znear > 0.0 =>
            {
                Some(Projection::Perspective { yfov: p.yfov, znear: p.znear, zfar: p.zfar.filter(|f| *f > p.znear) })
            }
            (Checked::Valid(Type::Orthographic), _, Some(o)) if o.xmag != 0.0 && o.ymag != 0.0 && o.zfar > o.znear => {
                Some(Projection::Orthographic { xmag: o.xmag, ymag: o.ymag, znear: o.znear, zfar: o.zfar })
            }
            _ => None,
        };
        let id = match projection {
            Some(projection) => {
                let name = cam.name.clone().unwrap_or_else(|| format!("camera {index}"));
                self.scene.cameras.push(CameraDef { name, projection });
                Some(self.scene.cameras.len() - 1)
            }
            None => {
                self.warn(format!("camera {index} has a missing or invalid projection and is ignored"));
                None
            }
        };
        self.camera_map.insert(index, id);
        Ok(id)
    }
}
