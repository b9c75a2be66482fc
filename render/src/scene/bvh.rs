//! A scene's world-space triangles in a BVH (the `obvhs` crate's CWBVH), for the rays the
//! CPU casts on real scenes: the path tracer's (`cpu::pathtrace`) and the framing's
//! (`scene::framing`, which probes rooms and views with a few thousand rays). The brute-force
//! [`super::raycast::TriangleSoup`] stays the reference of the G-buffer tests on small scenes.

use glam::{Mat4, Vec2, Vec3, Vec3A, Vec4Swizzles};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};

use super::raycast::moller_trumbore;
use crate::scene::{Scene, SceneState};

/// Triangles with a coordinate beyond this are left out of the BVH (no ray can meet them
/// meaningfully in f32, and the builder's arithmetic overflows).
pub const MAX_COORDINATE: f32 = 1e18;

/// One world-space triangle with what shading needs.
#[derive(Clone, Copy, Debug)]
pub struct BvhTri {
    pub v: [Vec3; 3],
    /// Vertex normals (world space, unit or zero).
    pub n: [Vec3; 3],
    /// Vertex tangents (world space xyz, handedness w), zero where the mesh has none.
    pub t: [glam::Vec4; 3],
    pub uv: [Vec2; 3],
    pub material: usize,
    /// glTF `doubleSided` of the material (back faces are seen).
    pub double_sided: bool,
    /// The draw of the scene state it comes from, and its index in that draw's primitive
    /// (indices 3k … 3k + 2): how the GPU ray caster names it (`two_level::TwoLevelHit`).
    pub draw: u32,
    pub index: u32,
}

/// A ray's closest hit.
#[derive(Clone, Copy, Debug)]
pub struct BvhHit {
    pub t: f32,
    pub p: Vec3,
    /// Interpolated vertex normal, turned to face the ray's origin.
    pub n: Vec3,
    /// Whether the ray met the triangle's front face (counter-clockwise, glTF).
    pub front: bool,
    /// Index into [`SceneBvh::tris`].
    pub tri: usize,
    /// Barycentrics of v1 and v2.
    pub bary: Vec2,
    pub uv: Vec2,
    pub material: usize,
}

/// The scene's triangles at one instant, in a BVH.
pub struct SceneBvh {
    pub tris: Vec<BvhTri>,
    bvh: CwBvh,
}

impl SceneBvh {
    /// The triangles of every draw of `state`.
    pub fn new(scene: &Scene, state: &SceneState) -> Self {
        let mut tris = Vec::new();
        for (draw, d) in state.draws.iter().enumerate() {
            let p = &scene.meshes[d.mesh].primitives[d.primitive];
            let nm: Mat4 = d.world.inverse().transpose();
            let double_sided = scene.materials.get(p.material).is_none_or(|m| m.double_sided);
            let flip = if d.world.determinant() < 0.0 { -1.0 } else { 1.0 };
            for (index, t) in p.indices.chunks_exact(3).enumerate() {
                let vert = |k: usize| &p.vertices[t[k] as usize];
                // A triangle with a vertex that is not a finite number (a broken file) cannot
                // be hit; the BVH builder refuses its box.
                if !(0..3).all(|k| Vec3::from(vert(k).position).is_finite()) {
                    continue;
                }
                let tangent = |k: usize| {
                    let tv = glam::Vec4::from(vert(k).tangent);
                    let xyz = d.world.transform_vector3(tv.xyz()).normalize_or_zero();
                    xyz.extend(tv.w * flip)
                };
                let v = [0, 1, 2].map(|k| d.world.transform_point3(Vec3::from(vert(k).position)));
                // Beyond 10¹⁸ the builder's box centres and their differences overflow to ∞
                // and NaN, and obvhs's child ordering panics (found by the fuzzer, #37).
                if !v.iter().all(|x| x.is_finite() && x.abs().max_element() < MAX_COORDINATE) {
                    continue;
                }
                tris.push(BvhTri {
                    v,
                    n: [0, 1, 2].map(|k| (nm * Vec3::from(vert(k).normal).extend(0.0)).xyz().normalize_or_zero()),
                    t: [0, 1, 2].map(tangent),
                    uv: [0, 1, 2].map(|k| Vec2::from(vert(k).uv)),
                    material: p.material,
                    double_sided,
                    draw: draw as u32,
                    index: index as u32,
                });
            }
        }
        // Each triangle's box, padded: an axis-aligned wall or floor has a box of zero
        // thickness, which the CWBVH's quantised child boxes can lose, so that a ray straight
        // at the floor found it in one build of a scene and missed it in another.
        let mut extent = 0f32;
        for t in &tris {
            for v in t.v {
                extent = extent.max(v.abs().max_element());
            }
        }
        let pad = glam::Vec3A::splat((extent * 1e-5).max(1e-6));
        let bvh_tris: Vec<obvhs::aabb::Aabb> = tris
            .iter()
            .map(|t| {
                let lo = Vec3A::from(t.v[0].min(t.v[1]).min(t.v[2]));
                let hi = Vec3A::from(t.v[0].max(t.v[1]).max(t.v[2]));
                obvhs::aabb::Aabb::new(lo - pad, hi + pad)
            })
            .collect();
        // obvhs's `build_cwbvh_from_tris` steps (PLOC, reinsertion, conversion), without its
        // debug-build validation of the intermediate binary BVH, which panics when that tree
        // is deeper than 96 (the hotel room's is 99): the traversal of the CWBVH does not
        // need that bound.
        let params = obvhs::BvhBuildParams::medium_build();
        let mut bvh2 = obvhs::ploc::PlocBuilder::with_capacity(bvh_tris.len()).build(
            params.ploc_search_distance,
            &bvh_tris,
            (0..bvh_tris.len() as u32).collect(),
            params.sort_precision,
            params.search_depth_threshold,
        );
        obvhs::bvh2::reinsertion::ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
        let bvh = obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(&bvh2, params.max_prims_per_leaf.clamp(1, 3), true, false);
        Self { tris, bvh }
    }

    /// Closest hit in (tmin, tmax) on every face.
    pub fn intersect(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<BvhHit> {
        self.intersect_where(o, d, tmin, tmax, |_, _, _| true)
    }

    /// Closest hit in (tmin, tmax) as a camera sees it: back faces of single-sided materials
    /// are skipped (the G-buffer culls them).
    pub fn intersect_camera(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<BvhHit> {
        self.intersect_where(o, d, tmin, tmax, |tri, front, _| front || tri.double_sided)
    }

    /// Closest hit in (tmin, tmax) among the triangles `accept` takes, given the triangle,
    /// whether the ray meets its front face and the hit's barycentrics (an alpha cutout, a
    /// culled back face).
    pub fn intersect_where(
        &self,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
        accept: impl Fn(&BvhTri, bool, Vec2) -> bool,
    ) -> Option<BvhHit> {
        if !(o.is_finite() && d.is_finite()) || self.tris.is_empty() {
            return None;
        }
        // −0 components become +0: obvhs's CWBVH traversal takes the sign bit of −0 for a
        // negative direction while its inverse is +∞ or −∞ by the same bit, and then misses
        // (a ray along −Y found no floor; seen on the framing cases).
        let d = d + Vec3::ZERO;
        let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), tmin, tmax);
        let mut hit = RayHit::none();
        let tris = &self.tris;
        let found = self.bvh.ray_traverse(ray, &mut hit, |r, id| {
            let tri = &tris[self.bvh.primitive_indices[id] as usize];
            match moller_trumbore(Vec3::from(r.origin), Vec3::from(r.direction), tri.v) {
                Some((t, u, v)) if t > r.tmin && t < r.tmax => {
                    let front = (tri.v[1] - tri.v[0]).cross(tri.v[2] - tri.v[0]).dot(d) < 0.0;
                    if accept(tri, front, Vec2::new(u, v)) { t } else { f32::INFINITY }
                }
                _ => f32::INFINITY,
            }
        });
        if !found {
            return None;
        }
        let index = self.bvh.primitive_indices[hit.primitive_id as usize] as usize;
        let tri = &self.tris[index];
        let (_, u, v) = moller_trumbore(o, d, tri.v)?;
        let geometric = (tri.v[1] - tri.v[0]).cross(tri.v[2] - tri.v[0]);
        let front = geometric.dot(d) < 0.0;
        let mut n = (tri.n[0] * (1.0 - u - v) + tri.n[1] * u + tri.n[2] * v).normalize_or_zero();
        if n == Vec3::ZERO {
            n = geometric.normalize_or(Vec3::Y);
        }
        if n.dot(d) > 0.0 {
            n = -n;
        }
        let uv = tri.uv[0] * (1.0 - u - v) + tri.uv[1] * u + tri.uv[2] * v;
        Some(BvhHit {
            t: hit.t,
            p: o + d * hit.t,
            n,
            front,
            tri: index,
            bary: Vec2::new(u, v),
            uv,
            material: tri.material,
        })
    }
}
