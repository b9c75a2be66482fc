//! The scene as the GPU ray caster reads it (issue #56 point 1; docs/architecture.md "Rays on
//! the GPU"): a two-level bounding volume hierarchy. Each mesh primitive gets a bottom level
//! over its triangles in its own space, built once ([`super::sah`]); the top level over the
//! instances (one per draw, its world matrix and the inverse that takes a ray into the
//! primitive's space) is rebuilt whenever they move ([`TwoLevel::set_instances`]), which
//! costs O(instances log instances), not a rebuild of the triangles. The materials and every
//! texture (with its box-filtered mip levels, as the G-buffer samples them) travel with it,
//! so that a ray's hit can be shaded and alpha cutouts honoured.
//!
//! [`TwoLevel::intersect`] walks the same nodes on the CPU, step for step as
//! `shaders/rays/scene.wgsl` does: the twin of the kernel. The twin of the whole caster is the
//! path tracer's own traversal ([`super::bvh::SceneBvh`], obvhs's CWBVH over world-space
//! triangles): `tests/pathtrace/rays.rs` casts the same rays through both on every shipped scene.
//!
//! Fallbacks (no panic, no GPU error): a scene without triangles has no top level and every
//! ray misses; an instance whose matrix is not invertible (a zero scale) or not finite has no
//! area and is left out of the top level, as its triangles, degenerate in the world, meet no
//! ray on the CPU; a triangle with a coordinate that is not finite is left out of its mesh's
//! level; a texture index past the scene's textures reads as no texture (an alpha-masked
//! triangle then keeps its factor's alpha, as the path tracer reads it).

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::sah::{self, BvhNode};
use super::{Scene, SceneState};
use crate::maths::Aabb;

/// A vertex's shading attributes (48 bytes); WGSL twin: `RayVertex` in
/// `shaders/rays/scene.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayVertex {
    pub normal: [f32; 3],
    pub u: f32,
    /// Tangent (xyz) and bitangent sign (w), zero where the mesh has none.
    pub tangent: [f32; 4],
    pub v: f32,
    pub _pad: [f32; 3],
}

/// An instance of a bottom level (208 bytes); WGSL twin: `RayInstance`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayInstance {
    pub world_to_object: Mat4,
    pub object_to_world: Mat4,
    /// Inverse transpose of the world matrix (normals).
    pub normal_matrix: Mat4,
    /// The root node of the primitive's bottom level.
    pub blas_root: u32,
    /// The primitive's first index in [`TwoLevel::indices`].
    pub index_base: u32,
    pub material: u32,
    /// [`INSTANCE_DOUBLE_SIDED`], [`INSTANCE_MIRRORED`], [`INSTANCE_VALID`].
    pub flags: u32,
}

/// The material is `doubleSided` (back faces are seen by a camera ray).
pub const INSTANCE_DOUBLE_SIDED: u32 = 1;
/// The world matrix mirrors (negative determinant): the front face turns.
pub const INSTANCE_MIRRORED: u32 = 2;
/// The instance is in the top level (invertible, finite, with triangles).
pub const INSTANCE_VALID: u32 = 4;

/// "No texture" in [`RayMaterial::textures`].
pub const NO_TEXTURE: u32 = u32::MAX;

/// A material as rays read it (64 bytes); WGSL twin: `RayMaterial`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayMaterial {
    pub base_color: Vec4,
    /// Emitted radiance (xyz) and the normal texture's scale (w).
    pub emissive: Vec4,
    /// Metallic, roughness, alpha cutoff (< 0: opaque), specular intensity override (< 0: none).
    pub factors: Vec4,
    /// Texture entries ([`TwoLevel::texture_table`]) of the base colour, emissive, normal and
    /// metallic-roughness textures ([`NO_TEXTURE`]: none).
    pub textures: [u32; 4],
}

/// One mip level of a texture in [`TwoLevel::texels`] (16 bytes); WGSL twin: `RayTexture`. A
/// texture's levels are consecutive entries, level 0 first.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RayTexture {
    /// First texel (RGBA8 packed in a u32, red in the low byte).
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    /// Levels from this one to the last (1: the last level).
    pub levels: u32,
}

/// A mesh primitive's bottom level.
#[derive(Clone, Copy, Debug)]
pub struct Blas {
    pub root: u32,
    pub index_base: u32,
    pub triangles: u32,
    /// Bounds in the primitive's own space.
    pub bounds: Aabb,
}

/// A ray's closest hit in the two-level hierarchy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoLevelHit {
    pub t: f32,
    /// The instance (= the draw of the scene state).
    pub instance: u32,
    /// The triangle's index in its primitive (indices 3k … 3k + 2).
    pub triangle: u32,
    /// Barycentrics of the triangle's second and third vertices.
    pub bary: Vec2,
    /// Whether the ray met the triangle's front face (counter-clockwise in the world).
    pub front: bool,
}

/// Which hit a query wants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// The closest hit on any face.
    Closest,
    /// The closest hit as a camera sees it: back faces of single-sided materials skipped.
    Camera,
    /// Any hit (a shadow ray): the walk stops at the first.
    Any,
}

/// The scene's two-level hierarchy with its materials and textures, as uploaded.
#[derive(Clone, Debug, Default)]
pub struct TwoLevel {
    /// Every bottom level's nodes, then the top level's region ([`Self::tlas_base`]).
    pub nodes: Vec<BvhNode>,
    /// Three vec4 per triangle in bottom-level leaf order: the vertices in the primitive's
    /// space, the first's w the triangle's index in its primitive (bits of a u32).
    pub tris: Vec<[f32; 4]>,
    pub vertices: Vec<RayVertex>,
    /// Every primitive's indices, each offset to its vertices in [`Self::vertices`].
    pub indices: Vec<u32>,
    pub blas: Vec<Blas>,
    /// `blas_of[mesh][primitive]`: index into [`Self::blas`] (None: no triangle).
    pub blas_of: Vec<Vec<Option<usize>>>,
    /// One per draw of the scene state, in its order.
    pub instances: Vec<RayInstance>,
    pub materials: Vec<RayMaterial>,
    pub texture_table: Vec<RayTexture>,
    pub texels: Vec<u32>,
    /// `texture_entries[t]`: the entry of the scene's texture t's level 0 in
    /// [`Self::texture_table`].
    pub texture_entries: Vec<u32>,
    /// The first node of the top level; its root when [`Self::tlas_nodes`] > 0.
    pub tlas_base: u32,
    /// Nodes of the top level in use (0: no instance, every ray misses).
    pub tlas_nodes: u32,
    /// The deepest leaf of any level (the traversal's stack holds 64).
    pub depth: u32,
    /// Problems found while building (instances left out), for the user.
    pub warnings: Vec<String>,
}

impl TwoLevel {
    /// Builds every bottom level, the materials and textures of `scene`, and the top level
    /// of `state`.
    pub fn new(scene: &Scene, state: &SceneState) -> Self {
        let mut s = TwoLevel::default();
        for mesh in &scene.meshes {
            let mut of = Vec::with_capacity(mesh.primitives.len());
            for p in &mesh.primitives {
                of.push(s.add_primitive(p));
            }
            s.blas_of.push(of);
        }
        s.add_materials(scene);
        s.tlas_base = s.nodes.len() as u32;
        s.nodes.resize(s.nodes.len() + 2 * state.draws.len().max(1), BvhNode::default());
        s.set_instances(scene, state);
        s
    }

    fn add_primitive(&mut self, p: &super::Primitive) -> Option<usize> {
        let index_base = self.indices.len() as u32;
        let vertex_base = self.vertices.len() as u32;
        let mut boxes = Vec::new();
        let mut local = Vec::new();
        let mut extent = 0f32;
        for (k, t) in p.indices.chunks_exact(3).enumerate() {
            let v = [0, 1, 2].map(|j| p.vertices.get(t[j] as usize).map(|x| Vec3::from(x.position)));
            let [Some(a), Some(b), Some(c)] = v else { continue };
            if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                continue;
            }
            let mut bb = Aabb::EMPTY;
            [a, b, c].iter().for_each(|x| bb.grow(*x));
            extent = extent.max(bb.min.abs().max_element()).max(bb.max.abs().max_element());
            boxes.push(bb);
            local.push((k as u32, [a, b, c]));
        }
        if local.is_empty() {
            return None;
        }
        // Each box padded as the CPU's (`SceneBvh::new`): a flat wall's box has no thickness.
        let pad = Vec3::splat(extent * 1e-5);
        for b in &mut boxes {
            b.min -= pad;
            b.max += pad;
        }
        let built = sah::build(&boxes, 4);
        self.depth = self.depth.max(built.depth);
        let node_base = self.nodes.len() as u32;
        let tri_base = (self.tris.len() / 3) as u32;
        for n in &built.nodes {
            let first = if n.is_leaf() { n.first + tri_base } else { n.first + node_base };
            self.nodes.push(BvhNode { first, ..*n });
        }
        for &i in &built.order {
            let (k, v) = local[i as usize];
            self.tris.push(v[0].extend(f32::from_bits(k)).to_array());
            self.tris.push(v[1].extend(0.0).to_array());
            self.tris.push(v[2].extend(0.0).to_array());
        }
        self.vertices.extend(p.vertices.iter().map(|x| RayVertex {
            normal: x.normal,
            u: x.uv[0],
            tangent: x.tangent,
            v: x.uv[1],
            _pad: [0.0; 3],
        }));
        self.indices.extend(p.indices.iter().map(|i| i + vertex_base));
        let mut bounds = Aabb::EMPTY;
        boxes.iter().for_each(|b| {
            bounds.grow(b.min);
            bounds.grow(b.max)
        });
        self.blas.push(Blas { root: node_base, index_base, triangles: local.len() as u32, bounds });
        Some(self.blas.len() - 1)
    }

    fn add_materials(&mut self, scene: &Scene) {
        let mut entry_of = Vec::with_capacity(scene.textures.len());
        for t in &scene.textures {
            let levels: Vec<super::TextureImage> = std::iter::once(t.clone()).chain(t.box_mips()).collect();
            let well_formed = t.rgba8.len() == t.width.max(1) as usize * t.height.max(1) as usize * 4;
            entry_of.push(self.texture_table.len() as u32);
            if !well_formed {
                // A malformed image reads black, as `TextureImage::sample_rgba` reads it.
                self.texture_table.push(RayTexture {
                    offset: self.texels.len() as u32,
                    width: 1,
                    height: 1,
                    levels: 1,
                });
                self.texels.push(0);
                continue;
            }
            let n = levels.len() as u32;
            for (k, l) in levels.iter().enumerate() {
                let offset = self.texels.len() as u32;
                self.texture_table.push(RayTexture {
                    offset,
                    width: l.width.max(1),
                    height: l.height.max(1),
                    levels: n - k as u32,
                });
                self.texels.extend(l.rgba8.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])));
            }
        }
        self.texture_entries = entry_of.clone();
        let tex = |t: Option<usize>| t.and_then(|i| entry_of.get(i).copied()).unwrap_or(NO_TEXTURE);
        let defaults = [super::Material::default()];
        let materials = if scene.materials.is_empty() { &defaults[..] } else { &scene.materials[..] };
        self.materials = materials
            .iter()
            .map(|m| RayMaterial {
                base_color: m.base_color,
                emissive: m.emissive.extend(m.normal_scale),
                factors: Vec4::new(
                    m.metallic,
                    m.roughness,
                    m.alpha_cutoff.unwrap_or(-1.0),
                    m.specular_override.unwrap_or(-1.0),
                ),
                textures: [
                    tex(m.base_color_texture),
                    tex(m.emissive_texture),
                    tex(m.normal_texture),
                    tex(m.metallic_roughness_texture),
                ],
            })
            .collect();
    }

    /// The instances of `state` (one per draw; the draws must be those the hierarchy was
    /// built for: same meshes, same count) and the top level over them, rebuilt.
    pub fn set_instances(&mut self, scene: &Scene, state: &SceneState) {
        self.warnings.clear();
        self.instances.clear();
        let mut boxes = Vec::new();
        let mut ids = Vec::new();
        for (i, d) in state.draws.iter().enumerate() {
            let blas =
                self.blas_of.get(d.mesh).and_then(|m| m.get(d.primitive).copied().flatten()).map(|b| self.blas[b]);
            let material = scene.meshes[d.mesh].primitives[d.primitive].material;
            let double_sided = scene.materials.get(material).is_none_or(|m| m.double_sided);
            let det = d.world.determinant();
            let inverse = d.world.inverse();
            let mut flags = if double_sided { INSTANCE_DOUBLE_SIDED } else { 0 };
            if det < 0.0 {
                flags |= INSTANCE_MIRRORED;
            }
            let invertible = det != 0.0 && d.world.is_finite() && inverse.is_finite();
            if let Some(b) = blas.filter(|_| invertible) {
                let world = b.bounds.transformed(d.world);
                let inside = |v: Vec3| v.is_finite() && v.abs().max_element() < super::bvh::MAX_COORDINATE;
                if inside(world.min) && inside(world.max) {
                    flags |= INSTANCE_VALID;
                    boxes.push(world);
                    ids.push(i as u32);
                } else {
                    self.warnings.push(format!("draw {i}: its bounds reach past 1e18, left out of the rays' scene"));
                }
            } else if blas.is_some() {
                self.warnings.push(format!(
                    "draw {i} (node {}): its world matrix is not invertible (a zero scale?): no ray meets it",
                    d.node
                ));
            }
            self.instances.push(RayInstance {
                world_to_object: if invertible { inverse } else { Mat4::ZERO },
                object_to_world: d.world,
                normal_matrix: if invertible { inverse.transpose() } else { Mat4::ZERO },
                blas_root: blas.map_or(0, |b| b.root),
                index_base: blas.map_or(0, |b| b.index_base),
                material: material.min(self.materials.len().saturating_sub(1)) as u32,
                flags,
            });
        }
        let built = sah::build(&boxes, 1);
        self.depth = self.depth.max(built.depth);
        self.tlas_nodes = built.nodes.len() as u32;
        let base = self.tlas_base;
        let needed = base as usize + built.nodes.len();
        if self.nodes.len() < needed {
            self.nodes.resize(needed, BvhNode::default());
        }
        for (k, n) in built.nodes.iter().enumerate() {
            let first = if n.is_leaf() { ids[built.order[n.first as usize] as usize] } else { n.first + base };
            self.nodes[base as usize + k] = BvhNode { first, ..*n };
        }
    }

    /// The top level's nodes (the region [`Self::set_instances`] rewrites).
    pub fn tlas(&self) -> &[BvhNode] {
        &self.nodes[self.tlas_base as usize..]
    }

    /// The hit of a ray, as `shaders/rays/scene.wgsl` finds it: the top level's leaves take
    /// the ray into their instance's space (t is the same there: the direction is transformed,
    /// not normalised), the bottom level's leaves test their triangles (Möller–Trumbore, as
    /// `raycast::moller_trumbore`); `accept` may refuse a hit (alpha cutouts), given the
    /// instance, the triangle and the barycentrics.
    pub fn intersect(
        &self,
        o: Vec3,
        d: Vec3,
        (tmin, tmax): (f32, f32),
        query: Query,
        accept: impl Fn(u32, u32, Vec2) -> bool,
    ) -> Option<TwoLevelHit> {
        if self.tlas_nodes == 0 {
            return None;
        }
        let mut best: Option<TwoLevelHit> = None;
        let mut t_best = tmax;
        let inv = safe_inverse(d);
        let mut stack = vec![self.tlas_base];
        let mut blas = Vec::new();
        while let Some(i) = stack.pop() {
            let n = self.nodes[i as usize];
            if slab(&n, o, inv, t_best).is_none() {
                continue;
            }
            if !n.is_leaf() {
                stack.push(n.first + 1);
                stack.push(n.first);
                continue;
            }
            let inst = &self.instances[n.first as usize];
            let (ol, dl) = (inst.world_to_object.transform_point3(o), inst.world_to_object.transform_vector3(d));
            let inv_l = safe_inverse(dl);
            blas.clear();
            blas.push(inst.blas_root);
            while let Some(j) = blas.pop() {
                let m = self.nodes[j as usize];
                if slab(&m, ol, inv_l, t_best).is_none() {
                    continue;
                }
                if !m.is_leaf() {
                    blas.push(m.first + 1);
                    blas.push(m.first);
                    continue;
                }
                for k in m.first..m.first + m.count {
                    let v = [0, 1, 2].map(|q| Vec4::from(self.tris[3 * k as usize + q]));
                    let tri = [v[0].truncate(), v[1].truncate(), v[2].truncate()];
                    let Some((t, u, w)) = triangle_hit(ol, dl, tri) else { continue };
                    if !(t > tmin && t < t_best) {
                        continue;
                    }
                    let facing = (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(dl) < 0.0;
                    let front = facing != (inst.flags & INSTANCE_MIRRORED != 0);
                    if query == Query::Camera && !front && inst.flags & INSTANCE_DOUBLE_SIDED == 0 {
                        continue;
                    }
                    let triangle = v[0].w.to_bits();
                    if !accept(n.first, triangle, Vec2::new(u, w)) {
                        continue;
                    }
                    t_best = t;
                    best = Some(TwoLevelHit { t, instance: n.first, triangle, bary: Vec2::new(u, w), front });
                    if query == Query::Any {
                        return best;
                    }
                }
            }
        }
        best
    }
}

/// Barycentric slack of [`triangle_hit`]; WGSL twin: `RAY_EDGE_SLACK`.
pub const EDGE_SLACK: f32 = 1e-5;

/// Möller & Trumbore (1997) as `raycast::moller_trumbore`, each triangle reaching
/// [`EDGE_SLACK`] of its size past its edges: the walk transforms rays into each instance's
/// space, and that rounding could let a ray through the shared edge of two triangles (or the
/// corner where quads meet) that the world-space walk of the path tracer closes; seen on the
/// Cornell box's corners, where camera rays along the diagonals saw the sky. WGSL twin:
/// `ray_triangle`.
pub fn triangle_hit(o: Vec3, d: Vec3, v: [Vec3; 3]) -> Option<(f32, f32, f32)> {
    super::raycast::moller_trumbore_within(o, d, v, EDGE_SLACK)
}

/// 1/d with each zero component replaced by a tiny number of its sign (no 0·∞ in the slab
/// test); WGSL twin: `ray_safe_inverse`.
pub fn safe_inverse(d: Vec3) -> Vec3 {
    let f = |x: f32| {
        let x = if x.abs() < 1e-30 { 1e-30f32.copysign(x) } else { x };
        1.0 / x
    };
    Vec3::new(f(d.x), f(d.y), f(d.z))
}

/// The entry distance of a ray into a node's box within (−∞, `t_max`) (slab test; the box is
/// entered at max(0, …)), None when it misses; WGSL twin: `ray_slab`.
pub fn slab(n: &BvhNode, o: Vec3, inv: Vec3, t_max: f32) -> Option<f32> {
    let t0 = (Vec3::from(n.lo) - o) * inv;
    let t1 = (Vec3::from(n.hi) - o) * inv;
    let lo = t0.min(t1).max_element().max(0.0);
    let hi = t0.max(t1).min_element().min(t_max);
    (lo <= hi).then_some(lo)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::bvh::SceneBvh;

    /// Random rays from inside the scene's bounds (and from outside, toward it).
    fn rays(bounds: Aabb, n: usize, seed: u32) -> Vec<(Vec3, Vec3)> {
        let mut s = seed;
        let mut f = move || {
            s = crate::maths::pcg_hash(s);
            s as f32 / u32::MAX as f32
        };
        (0..n)
            .map(|_| {
                let o = bounds.min + (bounds.max - bounds.min) * Vec3::new(f(), f(), f()) * 1.4 - bounds.extent() * 0.2;
                let z = f() * 2.0 - 1.0;
                let phi = f() * std::f32::consts::TAU;
                let r = (1.0 - z * z).max(0.0).sqrt();
                (o, Vec3::new(r * phi.cos(), r * phi.sin(), z))
            })
            .collect()
    }

    #[test]
    fn the_walk_finds_what_the_path_tracers_bvh_finds() {
        let scene = crate::scene::cornell::default_scene().expect("the default scene");
        let mut tl = TwoLevel::new(&scene, &scene.evaluate(0.0));
        assert!(tl.depth <= 64 && tl.tlas_nodes > 0);
        // The second instant: the top level rebuilt over the moved instances.
        for time in [0.0, 1.3] {
            let state = scene.evaluate(time);
            tl.set_instances(&scene, &state);
            let bvh = SceneBvh::new(&scene, &state);
            let mut coplanar = 0;
            for (o, d) in rays(scene.bounds(time), 3000, 7 + time as u32) {
                let cpu = bvh.intersect(o, d, 0.0, f32::INFINITY);
                let gpu = tl.intersect(o, d, (0.0, f32::INFINITY), Query::Closest, |_, _, _| true);
                match (cpu, gpu) {
                    (None, None) => {}
                    (Some(c), Some(g)) => {
                        let tri = &bvh.tris[c.tri];
                        if (tri.draw, tri.index) == (g.instance, g.triangle) {
                            assert!((c.t - g.t).abs() <= 1e-4 * c.t.max(1.0), "{o} {d}: t {} vs {}", c.t, g.t);
                            assert_eq!(c.front, g.front, "{o} {d}");
                            assert!((c.bary - g.bary).abs().max_element() < 1e-3, "{} {}", c.bary, g.bary);
                        } else {
                            // Two surfaces in one plane (the Cornell boxes stand on the floor,
                            // their bottoms coincide with it): either may be named, at one t.
                            assert!((c.t - g.t).abs() <= 1e-5 * c.t.max(1.0), "{o} {d}: t {} vs {}", c.t, g.t);
                            coplanar += 1;
                        }
                    }
                    (c, g) => {
                        panic!("{o} {d}: the CPU's BVH {:?}, the two levels {:?}", c.map(|h| h.t), g.map(|h| h.t))
                    }
                }
                // Shadow rays and camera rays.
                let any = tl.intersect(o, d, (1e-3, 0.7), Query::Any, |_, _, _| true).is_some();
                assert_eq!(any, bvh.intersect(o, d, 1e-3, 0.7).is_some(), "{o} {d}");
                let cam = tl.intersect(o, d, (0.0, f32::INFINITY), Query::Camera, |_, _, _| true).map(|h| h.t);
                let cpu_cam = bvh.intersect_camera(o, d, 0.0, f32::INFINITY).map(|h| h.t);
                assert_eq!(cam.is_some(), cpu_cam.is_some(), "{o} {d}");
            }
            assert!(coplanar < 60, "{coplanar} of 3000 rays on coincident surfaces");
        }
    }

    #[test]
    fn a_zero_scale_and_an_empty_scene_meet_no_ray() {
        let mut scene = crate::scene::cornell::default_scene().expect("the default scene");
        scene.animations.clear();
        for n in &mut scene.nodes {
            n.transform.scale = Vec3::ZERO;
        }
        let tl = TwoLevel::new(&scene, &scene.evaluate(0.0));
        assert_eq!(tl.tlas_nodes, 0);
        assert!(!tl.warnings.is_empty() && tl.warnings[0].contains("not invertible"), "{:?}", tl.warnings);
        assert!(tl.intersect(Vec3::ZERO, Vec3::X, (0.0, f32::INFINITY), Query::Closest, |_, _, _| true).is_none());
        scene.meshes.clear();
        scene.nodes.iter_mut().for_each(|n| n.mesh = None);
        let empty = TwoLevel::new(&scene, &scene.evaluate(0.0));
        assert_eq!((empty.tlas_nodes, empty.instances.len()), (0, 0));
        assert!(!empty.nodes.is_empty(), "the buffers are never empty (a binding of zero bytes is an error)");
    }
}
