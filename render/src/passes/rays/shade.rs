//! Lighting a ray's hit on the GPU as the path tracers do (issue #56 points 2–3;
//! `shaders/rays/shade.wgsl`): the scene's punctual lights, emissive triangles and sky in
//! storage buffers, group 0's bindings 0–4 of the GPU truth (`rays/pathtrace.wgsl`) and of
//! DDGI's probe trace (`ddgi/trace.wgsl`). Twins: `cpu::brdf::punctual_radiance`,
//! `scene::emitters::Emitters::sample`, `scene::sky::SkySampler`.

use glam::{Vec3, Vec4};

use super::{RayScene, storage};
use crate::gpu::GpuContext;
use crate::scene::emitters::Emitters;
use crate::scene::sky::SkySampler;
use crate::scene::two_level::NO_TEXTURE;
use crate::scene::{LightKind, Scene, SceneState};

/// WGSL twin: `PtShade` in `shaders/rays/shade.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PtShade {
    eps: Vec4,
    counts: [u32; 4],
    config: [u32; 4],
    sky: Vec4,
    sky_more: Vec4,
    sky_total: Vec4,
}

/// WGSL twin: `PtLight` in `shaders/rays/lights.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PtLight {
    pub position: Vec4,
    pub direction: Vec4,
    /// Colour (rgb) and intensity (w).
    pub color: Vec4,
    pub cone: Vec4,
}

/// WGSL twin: `PtEmitter` in `shaders/rays/lights.wgsl` (see there).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PtEmitter {
    v0: Vec4,
    v1: Vec4,
    v2: Vec4,
    normal: Vec4,
    radiance: Vec4,
    factor: Vec4,
    uv01: Vec4,
    uv2_cut: Vec4,
    cut_uv01: Vec4,
    cut_uv2: Vec4,
    kept: Vec4,
}

pub(crate) const SKY_LIT: u32 = 1;
pub(crate) const SKY_BACKGROUND: u32 = 2;
pub(crate) const SKY_IMAGE: u32 = 4;

/// Each emitter's texture as an entry of the rays' texture table (the emitters hold clones
/// of the scene's textures: the same pixels, found by pointer).
fn texture_entry(rays: &RayScene, scene: &Scene, emitters: &Emitters, i: usize) -> u32 {
    let Some(t) = emitters.textures.get(i) else { return NO_TEXTURE };
    scene
        .textures
        .iter()
        .position(|s| std::sync::Arc::ptr_eq(&s.rgba8, &t.rgba8))
        .and_then(|k| rays.cpu.texture_entries.get(k).copied())
        .unwrap_or(NO_TEXTURE)
}

fn pack_emitters(rays: &RayScene, scene: &Scene, emitters: &Emitters) -> Vec<PtEmitter> {
    let n = emitters.triangles.len();
    // Running sums of the power shares, as `Emitters::pick` reads them.
    let cdf: Vec<f32> = (0..n).map(|i| emitters.cdf_at(i)).collect();
    emitters
        .triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let (tex, uv, factor) = match t.texture {
                Some((k, uv, factor)) => (texture_entry(rays, scene, emitters, k), uv, factor),
                None => (NO_TEXTURE, [glam::Vec2::ZERO; 3], Vec3::ZERO),
            };
            let (cut, cuv, cf, cc, kept) = match t.cutout {
                Some(c) => (texture_entry(rays, scene, emitters, c.texture), c.uv, c.factor, c.cutoff, c.kept),
                None => (NO_TEXTURE, [glam::Vec2::ZERO; 3], 0.0, 0.0, Vec3::ZERO),
            };
            PtEmitter {
                v0: t.v[0].extend(cdf[i]),
                v1: t.v[1].extend(t.area),
                v2: t.v[2].extend(t.sides as f32),
                normal: t.normal.extend(f32::from_bits(tex)),
                radiance: t.radiance.extend(0.0),
                factor: factor.extend(f32::from_bits(cut)),
                uv01: Vec4::new(uv[0].x, uv[0].y, uv[1].x, uv[1].y),
                uv2_cut: Vec4::new(uv[2].x, uv[2].y, cf, cc),
                cut_uv01: Vec4::new(cuv[0].x, cuv[0].y, cuv[1].x, cuv[1].y),
                cut_uv2: Vec4::new(cuv[2].x, cuv[2].y, 0.0, 0.0),
                kept: kept.extend(0.0),
            }
        })
        .collect()
}

/// The lights of a scene at one instant, ready for `rays/shade.wgsl`.
pub struct ShadeLights {
    lights: Vec<PtLight>,
    emitters: Vec<PtEmitter>,
    sky: Option<crate::scene::sky::Sky>,
    /// Whether camera rays that leave the scene see the sky (the truth's flag).
    pub sky_background: bool,
    /// The rays' offset from a surface (scene radius × 10⁻⁴).
    pub eps: f32,
    /// The uploaded inputs (parameters, lights, emitters, sky texels, sky tables), rebuilt
    /// when they change.
    inputs: Option<[wgpu::Buffer; 5]>,
}

/// The punctual lights as `rays/lights.wgsl` reads them.
fn pack_lights(lights: &[crate::scene::WorldLight]) -> Vec<PtLight> {
    lights
        .iter()
        .map(|wl| {
            let (kind, cone) = match wl.light.kind {
                LightKind::Point => (0.0, Vec4::ZERO),
                LightKind::Spot { inner_cone, outer_cone } => (1.0, Vec4::new(inner_cone, outer_cone, 0.0, 0.0)),
                LightKind::Directional => (2.0, Vec4::ZERO),
            };
            PtLight {
                position: wl.position.extend(kind),
                direction: wl.direction.extend(wl.light.range.unwrap_or(0.0)),
                color: wl.light.color.extend(wl.light.intensity),
                cone,
            }
        })
        .collect()
}

impl ShadeLights {
    /// The lights of `scene` at `time_s` (emitters one-sided and lighting, the sky's
    /// background on: the CPU tracer's defaults).
    pub fn new(rays: &RayScene, scene: &Scene, time_s: f32) -> Self {
        let state = scene.evaluate(time_s);
        Self {
            lights: pack_lights(&state.lights),
            emitters: pack_emitters(rays, scene, &Emitters::collect(scene, &state)),
            sky: scene.sky.is_lit().then(|| scene.sky.clone()),
            sky_background: true,
            eps: scene.bounds(time_s).radius().max(1e-3) * 1e-4,
            inputs: None,
        }
    }

    /// The emitters as the lab's `emitters.*` settings say (`PathTracer::use_emitter_settings`).
    pub fn use_emitter_settings(
        &mut self,
        rays: &RayScene,
        s: &crate::settings::emitters::EmitterSettings,
        scene: &Scene,
        state: &SceneState,
    ) {
        let e = if s.enabled { Emitters::collect_sides(scene, state, s.two_sided) } else { Emitters::default() };
        self.emitters = pack_emitters(rays, scene, &e);
        self.inputs = None;
    }

    /// The punctual lights (they move with the scene's animation); uploaded again only when
    /// they changed.
    pub fn set_lights(&mut self, lights: &[crate::scene::WorldLight]) {
        let lights = pack_lights(lights);
        if lights != self.lights {
            self.lights = lights;
            self.inputs = None;
        }
    }

    /// (lights, emitters).
    pub fn counts(&self) -> (u32, u32) {
        (self.lights.len() as u32, self.emitters.len() as u32)
    }

    /// The sky's flags (`SKY_*`) as the camera sees it.
    pub fn sky_flags(&self) -> u32 {
        match &self.sky {
            None => 0,
            Some(s) => {
                let background = if self.sky_background { SKY_BACKGROUND } else { 0 };
                SKY_LIT | background | if s.image.is_some() { SKY_IMAGE } else { 0 }
            }
        }
    }

    fn params(&self) -> PtShade {
        let (sky_more, sky_total, sky_rot, sky_size) = match &self.sky {
            None => (Vec4::ZERO, 0.0, 0.0, (0, 0)),
            Some(s) => {
                let constant = SkySampler::new(s).radiance(Vec3::Y);
                match &s.image {
                    Some((_, m)) => {
                        (constant.extend(s.intensity), m.tables().2, s.rotation_deg.to_radians(), (m.width, m.height))
                    }
                    None => (constant.extend(s.intensity), 0.0, 0.0, (0, 0)),
                }
            }
        };
        let (lights, emitters) = self.counts();
        PtShade {
            eps: Vec4::new(self.eps, 0.0, 0.0, 0.0),
            counts: [lights, emitters, sky_size.0, sky_size.1],
            // Whether the sky is drawn behind the scene is the camera's (`PtParams`), not the
            // shading's: left out, so that `sky_background` never makes these buffers stale.
            config: [0, 0, 0, self.sky_flags() & !SKY_BACKGROUND],
            sky: Vec4::new(0.0, 0.0, 0.0, sky_rot),
            sky_more,
            sky_total: Vec4::new(sky_total, 0.0, 0.0, 0.0),
        }
    }

    /// The five buffers of bindings 0–4, uploaded when first asked for after a change.
    pub fn buffers(&mut self, ctx: &GpuContext) -> &[wgpu::Buffer; 5] {
        if self.inputs.is_none() {
            let (texels, tables): (Vec<Vec4>, Vec<f32>) = match self.sky.as_ref().and_then(|s| s.image.as_ref()) {
                Some((_, m)) => {
                    let (rows, marginal, _) = m.tables();
                    (m.texels.iter().map(|t| t.extend(0.0)).collect(), rows.iter().chain(marginal).copied().collect())
                }
                None => (Vec::new(), Vec::new()),
            };
            self.inputs = Some([
                storage(ctx, "rays.shade.params", bytemuck::bytes_of(&self.params()), 16),
                storage(ctx, "rays.shade.lights", bytemuck::cast_slice(&self.lights), 64),
                storage(ctx, "rays.shade.emitters", bytemuck::cast_slice(&self.emitters), 176),
                storage(ctx, "rays.shade.sky_texels", bytemuck::cast_slice(&texels), 16),
                storage(ctx, "rays.shade.sky_tables", bytemuck::cast_slice(&tables), 4),
            ]);
        }
        self.inputs.as_ref().expect("made above")
    }

    /// Whether the buffers were made again since `buffers` was last called (bind groups over
    /// them must be made again).
    pub fn stale(&self) -> bool {
        self.inputs.is_none()
    }
}
