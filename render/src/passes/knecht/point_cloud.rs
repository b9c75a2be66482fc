//! The point cloud of Knecht's imperfect shadow maps (002 §3.3, after Ritschel et al.):
//! points on the scene's triangles ∝ area × the object's sample weight, each with its
//! surface for the bounce selection (§3.6.1). A point where an alpha mask (glTF alphaMode
//! MASK) cuts the surface out is not placed (issue #37): a cut-out leaf gives no ISM points
//! where it is cut. Used by `ism` (splats) and `vpl_bounce` (point-cloud bounces).

use glam::Vec3;

use crate::maths::halton;
use crate::scene::{Scene, SceneState};

pub use crate::settings::knecht::PointPlacement;

/// One point of the cloud on the GPU; WGSL twin: `IsmPoint` in `shaders/knecht/ism/splat.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuPoint {
    /// Object-space position.
    pub position: [f32; 3],
    /// Index into the frame's instances (`SceneState::draws`).
    pub draw: u32,
    /// Object-space normal.
    pub normal: [f32; 3],
    /// Material index.
    pub material: u32,
}

/// What a point's surface reflects, for the bounce selection (Knecht 002 §3.6.1); WGSL twin:
/// `PointSurface` in `shaders/knecht/vpl/bounce.wgsl`: the base colour factor × the base colour texture
/// at the point (the path tracer of `cpu::pathtrace` reads it the same way).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuPointSurface {
    /// rgb: base colour c; a: W / w_s, the cloud's weighted area over the point's object
    /// weight (a point stands for W / (w_s · P_v) of surface among P_v points of one VPL).
    pub albedo: [f32; 4],
    /// DI, SI, SP, 0.
    pub material: [f32; 4],
}

/// One point of the cloud: where it lies as the thesis stores it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudPoint {
    /// Index into `SceneState::draws` (the instance the GPU transforms it with).
    pub draw: u32,
    /// Triangle index within the draw's primitive.
    pub triangle: u32,
    /// Barycentric coordinates (w0, w1, w2).
    pub barycentrics: Vec3,
}

/// The point cloud of a scene (built once per scene, count and placement).
#[derive(Clone, Debug)]
pub struct PointCloud {
    pub points: Vec<CloudPoint>,
    pub gpu: Vec<GpuPoint>,
    /// Reflectance and area share of each point (same order as `gpu`).
    pub surfaces: Vec<GpuPointSurface>,
    /// Total surface area of the scene at time 0 (unweighted).
    pub area: f32,
}

/// Small deterministic generator for random placement (SplitMix64).
struct SplitMix(u64);
impl SplitMix {
    fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

impl PointCloud {
    pub fn empty() -> Self {
        Self { points: Vec::new(), gpu: Vec::new(), surfaces: Vec::new(), area: 0.0 }
    }

    /// `count` points on the triangles of `state`'s draws, ∝ area × sample weight.
    pub fn build(scene: &Scene, state: &SceneState, count: u32, placement: PointPlacement) -> Self {
        struct Tri {
            draw: u32,
            prim: (usize, usize),
            triangle: u32,
            material: u32,
        }
        let mut tris = Vec::new();
        let mut cdf = Vec::new();
        let (mut total, mut area) = (0.0f64, 0.0f64);
        for (d, item) in state.draws.iter().enumerate() {
            let Some(prim) = scene.meshes.get(item.mesh).and_then(|m| m.primitives.get(item.primitive)) else {
                continue;
            };
            let weight = scene.materials.get(prim.material).map_or(1.0, |m| m.sample_weight.max(0.0));
            for (t, idx) in prim.indices.chunks_exact(3).enumerate() {
                let p = [idx[0], idx[1], idx[2]]
                    .map(|i| item.world.transform_point3(Vec3::from(prim.vertices[i as usize].position)));
                let a: f64 = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() as f64;
                if !a.is_finite() || a <= 0.0 {
                    continue;
                }
                area += a;
                total += a * weight as f64;
                tris.push(Tri {
                    draw: d as u32,
                    prim: (item.mesh, item.primitive),
                    triangle: t as u32,
                    material: prim.material as u32,
                });
                cdf.push(total);
            }
        }
        let mut cloud = Self { points: Vec::new(), gpu: Vec::new(), surfaces: Vec::new(), area: area as f32 };
        if total <= 0.0 {
            return cloud;
        }
        let mut rng = SplitMix(0x5EED);
        // A point where an alpha mask cuts the surface out is no point: the next sample
        // is drawn instead (at most 4 × `count` samples, for a scene that is mostly cut out).
        let mut accepted = 0u32;
        for i in 0..count.saturating_mul(4) {
            if accepted == count {
                break;
            }
            let (u, s, t) = match placement {
                PointPlacement::Halton => (halton(i + 1, 2), halton(i + 1, 3), halton(i + 1, 5)),
                PointPlacement::Random => (rng.next_f32(), rng.next_f32(), rng.next_f32()),
            };
            let target = u as f64 * total;
            let k = cdf.partition_point(|&c| c <= target).min(tris.len() - 1);
            let tri = &tris[k];
            // Uniform barycentrics: (1 − √s, √s(1 − t), √s·t).
            let r = s.sqrt();
            let b = Vec3::new(1.0 - r, r * (1.0 - t), r * t);
            let prim = &scene.meshes[tri.prim.0].primitives[tri.prim.1];
            let idx = &prim.indices[tri.triangle as usize * 3..tri.triangle as usize * 3 + 3];
            let v = idx.iter().map(|&i| prim.vertices[i as usize]).collect::<Vec<_>>();
            let pos =
                Vec3::from(v[0].position) * b.x + Vec3::from(v[1].position) * b.y + Vec3::from(v[2].position) * b.z;
            let nrm = (Vec3::from(v[0].normal) * b.x + Vec3::from(v[1].normal) * b.y + Vec3::from(v[2].normal) * b.z)
                .normalize_or(Vec3::Z);
            let m = scene.materials.get(tri.material as usize).cloned().unwrap_or_default();
            let uv =
                glam::Vec2::from(v[0].uv) * b.x + glam::Vec2::from(v[1].uv) * b.y + glam::Vec2::from(v[2].uv) * b.z;
            let texel = m.base_color_texture.and_then(|t| scene.textures.get(t)).map(|t| t.sample_rgba(uv, true));
            if let Some(cutoff) = m.alpha_cutoff
                && m.base_color.w * texel.map_or(1.0, |t| t.w) < cutoff
            {
                continue;
            }
            accepted += 1;
            cloud.points.push(CloudPoint { draw: tri.draw, triangle: tri.triangle, barycentrics: b });
            cloud.gpu.push(GpuPoint {
                position: pos.into(),
                draw: tri.draw,
                normal: nrm.into(),
                material: tri.material,
            });
            let weight = m.sample_weight.max(1e-6) as f64;
            // The point's colour is the material's there (factor × base colour texture).
            let c = m.base_color.truncate() * texel.map_or(Vec3::ONE, |t| t.truncate());
            cloud.surfaces.push(GpuPointSurface {
                albedo: c.extend((total / weight) as f32).to_array(),
                material: [m.diffuse_intensity(), m.specular_intensity(), m.specular_power(), 0.0],
            });
        }
        // Point j goes to ISM j mod N. Halton points whose indices share a residue modulo a
        // power of two share their leading digits in base 2, i.e. lie on the same few
        // triangles; a fixed shuffle makes every ISM's share a spread-out subset.
        let mut shuffle = SplitMix(0xC10D);
        for i in (1..cloud.points.len()).rev() {
            let k = ((shuffle.next_f32() * (i + 1) as f32) as usize).min(i);
            cloud.points.swap(i, k);
            cloud.gpu.swap(i, k);
            cloud.surfaces.swap(i, k);
        }
        cloud
    }
}
