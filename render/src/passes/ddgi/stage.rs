//! DDGI as the gather of stages 5–7 (issue #56 point 3; Majercik et al. 2019 §3, 2021 §4–5):
//! the probe grid fitted to the scene or the camera's room, its buffers, and each frame the
//! trace (`trace`), the update (`blend`: irradiance, distance, borders, classification and
//! relocation) and the reading at every pixel (`apply`). The scene's rays come from its own
//! [`RayScene`], whose top level follows the moving draws; its lights from a [`ShadeLights`]
//! that follows the frame's punctual lights and the `emitters.*` settings.

use crate::counters::prelude::*;

use glam::{Mat3, Mat4, Vec3, Vec4};

use super::apply::{APPLY_BINDINGS, DdgiApplyPass, VIEW_BINDINGS};
use super::blend::{BLEND_BINDINGS, DdgiBlendPass, DdgiUpdateParams};
use super::trace::{DdgiTracePass, TRACE_BINDINGS};
use super::{DdgiGridParams, DdgiSettings, GridFit, asked_counts, max_probes};
use crate::buffers::{BufferKind, BufferRegistry};
use crate::cpu::ddgi::{Atlas, GridClamp, ProbeGrid, random_rotation};
use crate::gpu::GpuContext;
use crate::maths::Aabb;
use crate::passes::rays::shade::ShadeLights;
use crate::passes::rays::{RayScene, storage};
use crate::passes::stages::FrameInputs;
use crate::scene::{Scene, SceneState};
use crate::timing::GpuTimer;

const F32X4: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// What the probes' buffers are sized by: a change makes them anew (the probes start empty).
#[derive(Clone, Debug, PartialEq)]
struct ProbeKey {
    grid: ProbeGrid,
    rays: u32,
    irradiance_texels: u32,
    distance_texels: u32,
}

/// The probes' buffers and the groups over them.
struct Probes {
    key: ProbeKey,
    /// (tiles a row, width, height) of each atlas (`cpu::ddgi::Atlas::layout`).
    irradiance: (u32, u32, u32),
    distance: (u32, u32, u32),
    update: wgpu::Buffer,
    grid: wgpu::Buffer,
    /// Per probe: relocation offset (xyz), state (w: 0 active, 1 inactive).
    states: wgpu::Buffer,
    irradiance_atlas: wgpu::Buffer,
    distance_atlas: wgpu::Buffer,
    /// Per probe and ray: radiance (rgb), ±distance (w).
    records: wgpu::Buffer,
    /// The viewer's copies: irradiance atlas, distance atlas, rays (a row per probe), probes.
    views: [wgpu::Texture; 4],
    blend_group: wgpu::BindGroup,
    view_group: wgpu::BindGroup,
    /// Updates so far (the first ignores the old values).
    updates: u32,
}

/// The DDGI stage.
pub struct DdgiStage {
    rays: RayScene,
    shade: ShadeLights,
    trace: DdgiTracePass,
    blend: DdgiBlendPass,
    apply: DdgiApplyPass,
    probes: Option<Probes>,
    trace_group: Option<wgpu::BindGroup>,
    /// `ddgi.indirect` (c·DI/π·E) and `ddgi.irradiance` (E) at every pixel.
    indirect: wgpu::Texture,
    irradiance: wgpu::Texture,
    /// The draws' world matrices the top level was built for.
    draws: Vec<Mat4>,
    /// The `emitters.*` settings the shading's emitters follow (None: not applied yet).
    emitters: Option<(bool, bool)>,
    /// Why the grid is smaller than asked (the device's limits), for the panel and the log.
    pub clamp: Option<GridClamp>,
    /// The rotation of the rays of the last update (tests replay its rays on the CPU).
    pub last_rotation: Mat3,
}

/// What the probe overlay shows of a frame (`Renderer::ddgi_overlay_later`): the grid, the
/// frame's ray rotation, each probe's offset and state, and every probe's rays when asked.
#[derive(Clone, Debug)]
pub struct ProbeOverlay {
    pub grid: ProbeGrid,
    pub rotation: Mat3,
    pub rays_per_probe: u32,
    /// Per probe: relocation offset (xyz), state (w: 0 active, 1 inactive).
    pub probes: Vec<Vec4>,
    /// Per probe and ray: radiance (rgb), ±distance (w; negative: a back face; 1e30: a miss;
    /// `cpu::ddgi::UNTRACED`: a ray an inactive probe did not cast).
    pub rays: Option<Vec<Vec4>>,
}

impl ProbeOverlay {
    /// Probe `i`'s place (on the grid, moved by its offset).
    pub fn position(&self, i: usize) -> Vec3 {
        self.grid.position(i) + self.probes.get(i).map_or(Vec3::ZERO, |p| p.truncate())
    }

    pub fn active(&self, i: usize) -> bool {
        self.probes.get(i).is_some_and(|p| p.w < 0.5)
    }

    /// Probe `i`'s rays of the frame: (direction, radiance, distance; negative: back face),
    /// an inactive probe's few (`cpu::ddgi::lattice`).
    pub fn rays_of(&self, i: usize) -> Vec<(Vec3, Vec3, f32)> {
        let (Some(rays), n) = (&self.rays, self.rays_per_probe) else { return Vec::new() };
        let record = |k: u32| rays.get(i * n as usize + k as usize);
        let m = crate::cpu::ddgi::lattice(n, |k| record(k).map(|r| r.w));
        (0..m)
            .filter_map(|k| {
                let r = record(k)?;
                let d = (self.rotation * crate::cpu::ddgi::spherical_fibonacci(k, m)).normalize();
                Some((d, r.truncate(), r.w))
            })
            .collect()
    }
}

fn pixel_target(ctx: &GpuContext, label: &str, (w, h): (u32, u32)) -> wgpu::Texture {
    crate::passes::create_target(&ctx.device, label, w.max(1), h.max(1), F32X4, wgpu::TextureUsages::STORAGE_BINDING)
}

/// The box the grid spans: the camera's room when asked for and the camera stands in one,
/// else the scene's.
pub fn fit_box(s: &DdgiSettings, bounds: Aabb, room: Option<Aabb>) -> Aabb {
    match (s.grid_fit, room) {
        (GridFit::Room, Some(r)) => r,
        _ => bounds,
    }
}

impl DdgiStage {
    /// The stage for `scene` at `state`; a clear message when the scene does not fit the ray
    /// caster on this device.
    pub fn new(ctx: &GpuContext, scene: &Scene, state: &SceneState, size: (u32, u32)) -> Result<Self, String> {
        let rays = RayScene::new(ctx, scene, state)?;
        let shade = ShadeLights::new(&rays, scene, 0.0);
        Ok(Self {
            trace: DdgiTracePass::new(ctx, &rays.layout),
            blend: DdgiBlendPass::new(ctx),
            apply: DdgiApplyPass::new(ctx),
            shade,
            rays,
            probes: None,
            trace_group: None,
            indirect: pixel_target(ctx, "ddgi.indirect", size),
            irradiance: pixel_target(ctx, "ddgi.irradiance", size),
            draws: state.draws.iter().map(|d| d.world).collect(),
            emitters: None,
            clamp: None,
            last_rotation: Mat3::IDENTITY,
        })
    }

    /// The grid in use (None before the first `ensure`).
    pub fn grid(&self) -> Option<&ProbeGrid> {
        self.probes.as_ref().map(|p| &p.key.grid)
    }

    /// Fits the grid to `fit` and sizes the buffers for the settings and the G-buffer; true
    /// when buffers or textures were made anew (to be registered again).
    pub fn ensure(&mut self, ctx: &GpuContext, s: &DdgiSettings, fit: Aabb, size: (u32, u32)) -> bool {
        let mut fresh = false;
        if (self.indirect.width(), self.indirect.height()) != (size.0.max(1), size.1.max(1)) {
            self.indirect = pixel_target(ctx, "ddgi.indirect", size);
            self.irradiance = pixel_target(ctx, "ddgi.irradiance", size);
            fresh = true;
        }
        let (grid, clamp) = ProbeGrid::fit(fit, asked_counts(s), max_probes(&ctx.device.limits(), s));
        let key = ProbeKey {
            grid,
            rays: s.rays_per_probe.max(1),
            irradiance_texels: s.irradiance_texels.max(2),
            distance_texels: s.distance_texels.max(2),
        };
        if self.probes.as_ref().is_none_or(|p| p.key != key) {
            if let Some(c) = &clamp
                && self.clamp.as_ref() != Some(c)
            {
                log::warn!("ddgi: {}", c.reason);
            }
            self.clamp = clamp;
            self.probes = Some(self.make_probes(ctx, key));
            self.trace_group = None;
            fresh = true;
        }
        fresh
    }

    fn make_probes(&self, ctx: &GpuContext, key: ProbeKey) -> Probes {
        let n = key.grid.len();
        let irradiance = Atlas::layout(key.irradiance_texels, n);
        let distance = Atlas::layout(key.distance_texels, n);
        let zeros = |label: &str, texels: u64| storage(ctx, label, &vec![0u8; (texels * 16) as usize], 16);
        let update = zeros("ddgi.update_params", (std::mem::size_of::<DdgiUpdateParams>() / 16) as u64);
        let grid = zeros("ddgi.grid", (std::mem::size_of::<DdgiGridParams>() / 16) as u64);
        let states = zeros("ddgi.probes", n as u64);
        let irradiance_atlas = zeros("ddgi.atlas.irradiance", irradiance.1 as u64 * irradiance.2 as u64);
        let distance_atlas = zeros("ddgi.atlas.distance", distance.1 as u64 * distance.2 as u64);
        let records = zeros("ddgi.rays", n as u64 * key.rays as u64);
        let max = ctx.device.limits().max_texture_dimension_2d;
        let texture = |label: &str, w: u32, h: u32| {
            crate::passes::create_target(
                &ctx.device,
                label,
                w.clamp(1, max),
                h.clamp(1, max),
                F32X4,
                wgpu::TextureUsages::STORAGE_BINDING,
            )
        };
        let columns = (n.max(1) as f32).sqrt().ceil() as u32;
        let views = [
            texture("ddgi.atlas.irradiance", irradiance.1, irradiance.2),
            texture("ddgi.atlas.distance", distance.1, distance.2),
            texture("ddgi.rays", key.rays, n as u32),
            texture("ddgi.probes", columns, (n as u32).div_ceil(columns)),
        ];
        let device = &ctx.device;
        let blend_group = BLEND_BINDINGS.group(
            device,
            &self.blend.layout,
            [
                update.as_entire_binding(),
                records.as_entire_binding(),
                irradiance_atlas.as_entire_binding(),
                distance_atlas.as_entire_binding(),
                grid.as_entire_binding(),
                states.as_entire_binding(),
            ],
        );
        let tv: Vec<wgpu::TextureView> = views.iter().map(|t| crate::passes::view(t, "ddgi.view")).collect();
        let view_group = VIEW_BINDINGS.group(
            device,
            &self.apply.view_layout,
            [
                update.as_entire_binding(),
                records.as_entire_binding(),
                irradiance_atlas.as_entire_binding(),
                distance_atlas.as_entire_binding(),
                states.as_entire_binding(),
                wgpu::BindingResource::TextureView(&tv[0]),
                wgpu::BindingResource::TextureView(&tv[1]),
                wgpu::BindingResource::TextureView(&tv[2]),
                wgpu::BindingResource::TextureView(&tv[3]),
            ],
        );
        Probes {
            key,
            irradiance,
            distance,
            update,
            grid,
            states,
            irradiance_atlas,
            distance_atlas,
            records,
            views,
            blend_group,
            view_group,
            updates: 0,
        }
    }

    /// Names the stage's buffers in the registry.
    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "ddgi.indirect",
            BufferKind::Hdr,
            "DDGI's indirect light at every pixel, c·DI/π·E (Majercik et al. 2019 §3.4)",
            &self.indirect,
        );
        reg.register(
            "ddgi.irradiance",
            BufferKind::Hdr,
            "the irradiance E the eight probes of each pixel's cell give it (2019 Eq. 5–6)",
            &self.irradiance,
        );
        let Some(p) = &self.probes else { return };
        let [irr, dist, rays, probes] = &p.views;
        reg.register(
            "ddgi.atlas.irradiance",
            BufferKind::Hdr,
            "each probe's octahedral irradiance tile / π with its border (2019 §3.2)",
            irr,
        );
        reg.register(
            "ddgi.atlas.distance",
            BufferKind::Data,
            "each probe's octahedral distance moments: mean (r), mean² (g) (2019 §3.2)",
            dist,
        );
        reg.register(
            "ddgi.rays",
            BufferKind::Data,
            "this frame's rays, a row per probe: radiance toward the probe (rgb), distance (a; negative: a back face, 1e30: a miss, 3e38: not cast by an inactive probe)",
            rays,
        );
        reg.register(
            "ddgi.probes",
            BufferKind::Data,
            "the probes, a texel each: relocation offset (rgb), state (a: 0 active, 1 inactive; 2021 §5.2–5.3)",
            probes,
        );
    }

    /// Follows the frame: the draws' top level, the punctual lights, the emitters' settings.
    fn follow(&mut self, f: &FrameInputs) {
        let ctx = f.ctx;
        if f.state.draws.len() == self.draws.len() && f.state.draws.iter().zip(&self.draws).any(|(d, m)| d.world != *m)
        {
            self.rays.update(ctx, f.scene, f.state);
            self.draws = f.state.draws.iter().map(|d| d.world).collect();
        }
        // The sky's directions the direct light adds as lights are the sky's, which the
        // shading samples itself: only the scene's own lights.
        let own = f.state.lights.len().saturating_sub(f.sky_lights);
        self.shade.set_lights(&f.state.lights[..own]);
        let e = Some((f.settings.emitters.enabled, f.settings.emitters.two_sided));
        if e != self.emitters {
            self.emitters = e;
            self.shade.use_emitter_settings(&self.rays, &f.settings.emitters, f.scene, f.state);
        }
    }

    /// Stages 5–7: the probes' update and the reading at every pixel; the indirect light.
    pub fn run(&mut self, f: &FrameInputs, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) -> wgpu::TextureView {
        let ctx = f.ctx;
        let s = &f.settings.ddgi;
        self.follow(f);
        // The lights' buffers are made again when they changed: the trace's group with them.
        let remake = self.shade.stale() || self.trace_group.is_none();
        let Some(p) = self.probes.as_mut() else {
            return crate::passes::view(&self.indirect, "ddgi.indirect");
        };
        let n = p.key.grid.len() as u32;
        // The frame's rotation of the Fibonacci lattice (2019 §3.1), from the frame's index.
        let h = |k: u32| {
            let x = crate::maths::pcg_hash(f.frame.wrapping_mul(3).wrapping_add(k));
            (x >> 8) as f32 / 16_777_216.0
        };
        let rotation: Mat3 = random_rotation([h(0), h(1), h(2)]);
        self.last_rotation = rotation;
        let update = DdgiUpdateParams {
            rotation: [rotation.x_axis.extend(0.0), rotation.y_axis.extend(0.0), rotation.z_axis.extend(0.0)],
            counts: [n, p.key.rays, p.key.irradiance_texels, p.key.distance_texels],
            layout: [p.irradiance.0, p.distance.0, (p.updates > 0) as u32, f.frame.wrapping_mul(0x9E37_79B9)],
            blend: Vec4::new(
                crate::cpu::ddgi::blend_share(s.hysteresis, s.running_mean_start, p.updates),
                s.distance_sharpness,
                s.max_distance * p.key.grid.spacing.max_element(),
                0.0,
            ),
        };
        ctx.queue.upload(&p.update, 0, bytemuck::bytes_of(&update));
        let grid = DdgiGridParams::new(&p.key.grid, s, p.irradiance.0);
        ctx.queue.upload(&p.grid, 0, bytemuck::bytes_of(&grid));
        if remake {
            let shade = self.shade.buffers(ctx);
            self.trace_group = Some(TRACE_BINDINGS.group(
                &ctx.device,
                &self.trace.layout,
                shade.iter().map(|b| b.as_entire_binding()).chain([
                    p.update.as_entire_binding(),
                    p.grid.as_entire_binding(),
                    p.states.as_entire_binding(),
                    p.irradiance_atlas.as_entire_binding(),
                    p.distance_atlas.as_entire_binding(),
                    p.records.as_entire_binding(),
                ]),
            ));
        }
        let trace_group = self.trace_group.as_ref().expect("made above");
        let (trace, blend, apply) = (&self.trace, &self.blend, &self.apply);
        let scene_group = &self.rays.group;
        timer.scope(ctx, enc, "ddgi.trace", |e, slot| {
            trace.record(e, slot.and_then(|s| s.compute(true, true)), (trace_group, scene_group), n * p.key.rays)
        });
        let sizes = ((p.irradiance.1, p.irradiance.2), (p.distance.1, p.distance.2));
        timer.scope(ctx, enc, "ddgi.update", |e, slot| {
            blend.record(e, slot.and_then(|s| s.compute(true, true)), &p.blend_group, sizes, n)
        });
        p.updates = p.updates.saturating_add(1);
        let g = &f.gbuffer;
        let indirect = crate::passes::view(&self.indirect, "ddgi.indirect");
        let irradiance = crate::passes::view(&self.irradiance, "ddgi.irradiance");
        let group = APPLY_BINDINGS.group(
            &ctx.device,
            &apply.layout,
            [
                p.grid.as_entire_binding(),
                p.states.as_entire_binding(),
                p.irradiance_atlas.as_entire_binding(),
                p.distance_atlas.as_entire_binding(),
                wgpu::BindingResource::TextureView(&g.position),
                wgpu::BindingResource::TextureView(&g.normal),
                wgpu::BindingResource::TextureView(&g.albedo),
                f.camera_buffer.as_entire_binding(),
                wgpu::BindingResource::TextureView(&indirect),
                wgpu::BindingResource::TextureView(&irradiance),
                wgpu::BindingResource::TextureView(&g.material),
            ],
        );
        let size = f.gbuffer_size;
        timer.scope(ctx, enc, "ddgi.apply", |e, slot| {
            apply.record(e, slot.and_then(|s| s.compute(true, true)), &group, size)
        });
        let largest = p.views.iter().fold((1, 1), |a, t| (a.0.max(t.width()), a.1.max(t.height())));
        apply.record_view(enc, &p.view_group, largest);
        indirect
    }

    /// The probes' buffers for a read-back (tests and the pixel explanation): the grid, and
    /// the storage buffers of the probes, both atlases and the rays; None before `ensure`.
    pub fn buffers(&self) -> Option<(ProbeGrid, [&wgpu::Buffer; 4])> {
        let p = self.probes.as_ref()?;
        Some((p.key.grid, [&p.states, &p.irradiance_atlas, &p.distance_atlas, &p.records]))
    }

    /// What the pixel explanation's replay reads: the grid's parameters, the probes, both
    /// atlases, and `ddgi.indirect`.
    pub fn explain_parts(&self) -> Option<([&wgpu::Buffer; 4], wgpu::TextureView)> {
        let p = self.probes.as_ref()?;
        let indirect = crate::passes::view(&self.indirect, "ddgi.indirect");
        Some(([&p.grid, &p.states, &p.irradiance_atlas, &p.distance_atlas], indirect))
    }

    /// The buffers the probe overlay reads back: the update's parameters (the frame's ray
    /// rotation), the probes, and with `rays` every probe's rays of that frame.
    pub fn overlay_sources(&self, rays: bool) -> Option<Vec<(wgpu::Buffer, u64)>> {
        let p = self.probes.as_ref()?;
        let mut v = vec![
            (p.update.clone(), std::mem::size_of::<DdgiUpdateParams>() as u64),
            (p.states.clone(), p.key.grid.len() as u64 * 16),
        ];
        if rays {
            v.push((p.records.clone(), p.key.grid.len() as u64 * p.key.rays as u64 * 16));
        }
        Some(v)
    }

    /// The probe overlay's view of the parts [`Self::overlay_sources`] read (None when they
    /// do not match the grid any more).
    pub fn overlay_from(&self, parts: &[Vec<u8>]) -> Option<ProbeOverlay> {
        let p = self.probes.as_ref()?;
        let n = p.key.grid.len();
        let update: DdgiUpdateParams =
            bytemuck::pod_read_unaligned(parts.first()?.get(..std::mem::size_of::<DdgiUpdateParams>())?);
        if update.counts[0] as usize != n || update.counts[1] != p.key.rays {
            return None;
        }
        let probes: Vec<Vec4> = bytemuck::pod_collect_to_vec(parts.get(1)?.get(..n * 16)?);
        let rays = match parts.get(2) {
            Some(b) => Some(bytemuck::pod_collect_to_vec(b.get(..n * p.key.rays as usize * 16)?)),
            None => None,
        };
        let [x, y, z] = update.rotation;
        Some(ProbeOverlay {
            grid: p.key.grid,
            rotation: Mat3::from_cols(x.truncate(), y.truncate(), z.truncate()),
            rays_per_probe: p.key.rays,
            probes,
            rays,
        })
    }

    /// Each atlas's (interior texels, tiles a row).
    pub fn atlas_layout(&self) -> Option<((u32, u32), (u32, u32))> {
        let p = self.probes.as_ref()?;
        Some(((p.key.irradiance_texels, p.irradiance.0), (p.key.distance_texels, p.distance.0)))
    }
}
