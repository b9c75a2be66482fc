//! The whole frame, stage by stage, in the order of the pipeline table of docs/principles.md.
//! Each stage runs the pass its choice in `pipeline.*` names (`crate::pipeline`), from the
//! typed inputs of `crate::stages` to typed outputs; no paper's logic lives here.
//! `docs/architecture.md` lists every choice and how to add one.
//!
//! | stage | choices → pass |
//! |---|---|
//! | 1. G-buffer | `passes::gbuffer`: position, normal, albedo, material, depth, movement buffer |
//! | 2. Direct light | `passes::shadow`, `passes::direct`; the emitters' VPLs (`passes::emitters`) and the sky's directions (`passes::sky`) |
//! | 3. VPLs | none · importance warping → `passes::knecht::stage` · uniform batches → `passes::reference::stage` |
//! | 4. VPL visibility | none · imperfect shadow maps (`passes::knecht::ism`) · exact maps (`passes::reference::vpl_visibility`) |
//! | 5. Shading points | every pixel · interleaved tiles → `passes::knecht::interleave` · HCB samples → `passes::hcb::stage` · mip levels → `passes::soler::stage` · irradiance records → `passes::gautron::stage` |
//! | 6. Gather + reconstruction | VPL gather at the shading points, or the screen-space ring gather (`soler::gather`); none · geometry-aware filter (`knecht::interleave`) · coherence splatting (`hcb::splat`) · joint bilateral upsampling (`soler::upsample`) |
//! | 7. Temporal + compose | none · confidence merge (`knecht::temporal`) · HCB sample cache (`hcb::cache`) · running average (`reference`) · warped blend (`soler::temporal`); `passes::compose` |

use glam::Vec4;

use crate::passes::CameraUniform;
use crate::passes::direct_history::DirectHistory;
use crate::passes::knecht::temporal::MergeOrder;
use crate::passes::knecht::vpl_importance::ReceiverBrdf;
use crate::passes::shadow::{gpu_light, setup_lights};
use crate::pipeline::{Gather, Reconstruction, ShadingPoints, Temporal, VplSource, VplVisibility};
use crate::renderer::{PrevFrame, Renderer, StagePasses, light_view_list};
use crate::stages::{FrameInputs, Visibility};
use crate::timing::{GpuTimer, PassTiming};

impl Renderer {
    /// Renders one frame and advances the clock. Returns the per-pass timings (this frame's,
    /// or in interactive mode the newest available).
    pub fn render_frame(&mut self) -> Vec<PassTiming> {
        let ctx = self.ctx.clone();
        ctx.make_current();
        let aspect = self.width as f32 / self.height as f32;
        self.check_camera();

        // The scene at this instant; the sky's directions join its lights (`passes::sky`).
        let state = self.frame_state();
        let view_proj = self.camera.view_proj(aspect);
        let prev_view_proj = self.prev.as_ref().map(|p| p.view_proj).unwrap_or(view_proj);
        let cam = CameraUniform {
            view_proj,
            prev_view_proj,
            inv_view_proj: view_proj.inverse(),
            view: self.camera.view(),
            position: self.camera.position.extend(1.0),
            viewport: Vec4::new(
                self.width as f32,
                self.height as f32,
                1.0 / self.width as f32,
                1.0 / self.height as f32,
            ),
            params: Vec4::new(self.camera.znear, self.camera.zfar, self.clock.frame as f32, self.clock.time_s()),
            lod: Vec4::new(-1.0, 0.0, 0.0, 0.0),
        };
        ctx.queue.write_buffer(&self.camera_buffer, 0, bytemuck::bytes_of(&cam));
        self.gpu_scene.update_instances(&ctx, &state, self.prev.as_ref().map(|p| p.models.as_slice()));

        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });

        // The passes the stage choices name (stage 2's emitters, stages 3–7).
        self.ensure_passes_for(Some(&state));

        // Stage 1: G-buffer and movement buffer.
        let (gbuffer, camera_group, gpu_scene) = (&self.gbuffer, &self.camera_group, &self.gpu_scene);
        self.timer.scope(&ctx, &mut enc, "gbuffer", |e, slot| gbuffer.run(e, slot, camera_group, gpu_scene, &state));

        // Stage 2: shadow maps, the emitters' VPLs and their visibility, direct light.
        let ds = self.settings.direct.clone();
        let mut lights = setup_lights(&state.lights, self.bounds, ds.shadow_map_size, ds.shadows);
        let size = ds.shadow_map_size.min(ctx.limits.max_texture_dimension_2d);
        let layers = (lights.views.len() as u32).clamp(1, ctx.limits.max_texture_array_layers);
        if self.shadow.ensure(&ctx, size, layers) {
            self.shadow.register(&mut self.registry);
        }
        if self.shadow.size != ds.shadow_map_size {
            // Layers made smaller to fit the device: a texel covers more of the world.
            let k = ds.shadow_map_size as f32 / self.shadow.size as f32;
            lights.lights.iter_mut().for_each(|l| l.shadow.x *= k);
        }
        let shadow = &self.shadow;
        self.timer.scope(&ctx, &mut enc, "direct.shadow", |e, slot| {
            shadow.run(&ctx, e, slot, gpu_scene, &state, &lights.views)
        });
        let emitters = match self.stages.emitters.as_mut() {
            Some(pass) => {
                let (scene, radius) = (&self.scene, self.bounds.radius());
                pass.run(&ctx, &mut enc, &mut self.timer, scene, &state, gpu_scene, &self.settings, radius)
            }
            None => None,
        };
        let (direct, camera_buffer, gviews) = (&mut self.direct, &self.camera_buffer, &self.gbuffer.targets.views);
        let shadow_view = &self.shadow.array_view;
        self.timer.scope(&ctx, &mut enc, "direct", |e, slot| {
            direct.run(&ctx, e, slot, &ds, camera_buffer, gviews, &lights, shadow_view, emitters.as_ref())
        });
        // While the sky's directions rotate, the direct light is their running mean over the
        // still frames (issue #51, `passes::direct_history`).
        let rotating_sky = if self.settings.sky.rotate_each_frame { self.sky_lights.count() } else { 0 };
        let mut direct_view = crate::passes::view(&self.direct.radiance, "direct.radiance");
        if rotating_sky > 0 {
            let (w, h) = (self.width, self.height);
            let history = self.direct_history.get_or_insert_with(|| DirectHistory::new(&ctx, w, h));
            history.ensure(&ctx, w, h);
            let mut key: Vec<f32> = view_proj.to_cols_array().to_vec();
            let steady = &state.lights[..state.lights.len() - rotating_sky];
            key.extend(steady.iter().flat_map(|l| bytemuck::cast::<_, [f32; 20]>(gpu_light(l))));
            key.extend(state.draws.iter().flat_map(|d| d.world.to_cols_array()));
            let sky = &self.scene.sky;
            key.extend([sky.color.x, sky.color.y, sky.color.z, sky.intensity, sky.rotation_deg]);
            let settings = format!("{:?}", self.settings);
            let radiance = &direct_view;
            let averaged = self.timer.scope(&ctx, &mut enc, "direct.sky_history", |e, slot| {
                history.run(&ctx, e, slot, radiance, key, settings)
            });
            history.register(&mut self.registry);
            direct_view = averaged;
        } else if self.direct_history.take().is_some() {
            self.registry.remove("direct.sky_history");
        }
        // Stages 3–7's indirect light, as the stage choices say (`pipeline.*`).
        let f = FrameInputs {
            ctx: &ctx,
            scene: &self.scene,
            gpu_scene: &self.gpu_scene,
            state: &state,
            settings: &self.settings,
            camera_buffer: &self.camera_buffer,
            camera: &self.camera,
            gbuffer: &self.gbuffer.targets.views,
            radius: self.bounds.radius(),
            scale: self.scale_radius(),
            center: self.bounds.center(),
            height: self.height,
            gbuffer_size: (self.width, self.height),
            frame: self.clock.frame as u32,
            direct: &self.direct,
            direct_radiance: &direct_view,
            direct_diffuse: self.direct.diffuse.as_ref().map(|(_, v)| v),
            lights: state.lights.iter().map(gpu_light).collect(),
            views: light_view_list(&state, self.bounds),
            rotating_sky: if self.settings.sky.rotate_each_frame { self.sky_lights.count() } else { 0 },
            explain_pixel: self.stages.explain_pixel,
        };
        let indirect = indirect_light(&f, &mut self.stages, &mut enc, &mut self.timer, view_proj);
        let near_field = near_field_light(&f, &mut self.stages, &mut enc, &mut self.timer);
        // The temporal histories ping-pong: the registry names this frame's.
        if let Some(t) = &self.stages.temporal {
            t.register(&mut self.registry);
        }
        if let Some(t) = self.stages.soler.as_ref().and_then(|s| s.temporal.as_ref()) {
            t.register(&mut self.registry);
        }
        if let Some(g) = &self.stages.gautron {
            g.register_sums(&mut self.registry);
        }
        if let Some(h) = &self.stages.hcb {
            h.register_sums(&mut self.registry);
        }

        // Stage 7: compose direct + indirect and tone map.
        self.sky_background.update(&ctx, &self.scene.sky, self.settings.sky.background);
        // The compose tone maps with the previous frame's exposure; a separate tone-mapping
        // pass runs only when there is none yet (the first frame of automatic exposure).
        let (compose, ts, emission) = (&mut self.compose, &self.settings.tonemap, &self.gbuffer.targets.views.emission);
        let sky = (&self.sky_background, &self.camera_buffer, &self.gbuffer.targets.views.normal);
        self.timer.scope(&ctx, &mut enc, "compose", |e, slot| {
            compose.compose(&ctx, e, slot, ts, emission, &direct_view, indirect.as_ref(), near_field.as_ref(), sky)
        });
        self.timer.scope(&ctx, &mut enc, "compose.luminance", |e, slot| compose.luminance(&ctx, e, slot, ts));
        if !compose.tone_mapped() {
            self.timer.scope(&ctx, &mut enc, "compose.tonemap", |e, slot| compose.tonemap(&ctx, e, slot, ts));
        }

        // The read-backs asked for since the last frame, copied in this frame's encoder.
        let readbacks = self.readbacks.get_mut().unwrap_or_else(|p| p.into_inner());
        if readbacks.pending() > 0 {
            crate::counters::traffic::begin_scope("readback");
            let probe = self.depth_probe.get_or_init(|| crate::passes::view::DepthProbe::new(&ctx));
            let size = (self.width, self.height);
            readbacks.record(&ctx, &mut enc, &self.registry, probe, size, self.clock.frame);
            crate::counters::traffic::end_scope();
        }
        self.timer.resolve(&ctx, &mut enc);
        ctx.submit([enc.finish()]);
        readbacks.start_maps();
        let timings = self.timer.collect(&ctx, !self.interactive).to_vec();

        self.traffic = crate::counters::traffic::end_frame();
        crate::counters::reuse::end_frame();
        self.prev = Some(PrevFrame { view_proj, models: state.draws.iter().map(|d| d.world).collect() });
        self.clock.tick();
        timings
    }
}

/// Stages 3–7: the indirect light of the stage choices (None: direct light only).
fn indirect_light(
    f: &FrameInputs,
    x: &mut StagePasses,
    enc: &mut wgpu::CommandEncoder,
    timer: &mut GpuTimer,
    view_proj: glam::Mat4,
) -> Option<wgpu::TextureView> {
    let p = &f.settings.pipeline;
    if p.gather == Gather::None {
        return None;
    }
    // Gautron et al.'s choices: irradiance records (stage 5), their hemispheres (stage 6's
    // gather), Ward-weight splatting (stage 6's reconstruction) and the record cache (stage
    // 7), run together; no VPLs.
    if p.gather == Gather::Hemispheres {
        // GI Lab's mix with Nguyen et al.: the hemispheres at the HCB's samples, splatted by
        // coherence (stage 5 HcbSamples, stage 6 CoherenceSplatting).
        if p.shading_points == ShadingPoints::HcbSamples {
            let (hcb, gautron) = (x.hcb.as_ref()?, x.gautron.as_mut()?);
            hcb.build_only(f, enc, timer);
            if let Err(e) = gautron.gather_at_samples(f, enc, timer, hcb.sample_buffers()) {
                log::warn!("gautron: the HCB's sample count could not be read: {e}");
            }
            let view = hcb.splat_only(f, enc, timer);
            crate::renderer::explain::explain_hcb(f, x, enc, &view);
            return Some(view);
        }
        let view = x.gautron.as_mut()?.run(f, enc, timer, None);
        crate::renderer::explain::explain_gautron(f, x, enc, &view);
        return Some(view);
    }
    // Soler et al.'s screen-space choices: mip levels (stage 5), the ring gather and the
    // joint bilateral upsampling (stage 6), and the warped blend of Eq. 6 (stage 7) when
    // `pipeline.temporal` is WarpedBlend; no VPLs.
    if p.gather == Gather::ScreenSpace {
        // GI Lab's mix with Nguyen et al.: the ring gather at the HCB's samples, splatted by
        // coherence (stage 5 HcbSamples, stage 6 CoherenceSplatting).
        if p.shading_points == ShadingPoints::HcbSamples {
            let (hcb, soler) = (x.hcb.as_ref()?, x.soler.as_ref()?);
            hcb.build_only(f, enc, timer);
            soler.gather_at_samples(f, enc, timer, hcb.sample_buffers());
            let view = hcb.splat_only(f, enc, timer);
            crate::renderer::explain::explain_hcb(f, x, enc, &view);
            return Some(view);
        }
        return Some(x.soler.as_mut()?.run(f, enc, timer));
    }

    // Stage 3: VPLs.
    let vpls = match p.vpl_source {
        VplSource::None => return None,
        VplSource::ImportanceWarping => x.knecht.as_mut()?.vpls(f, enc, timer, x.emitters.as_mut()),
        VplSource::UniformBatches => {
            let emitters = x.emitters.as_ref().filter(|e| e.stats.vpls > 0).map(|e| &e.emitters);
            match x.reference.as_mut()?.vpls(f, enc, timer, view_proj, emitters) {
                Some(batch) => batch,
                // The running average is complete (or there is no light): stage 7's image stays.
                None => return Some(x.reference.as_ref()?.average()),
            }
        }
    };

    // Stage 4: VPL visibility, by the source's maps of its VPLs.
    let vis = match (p.vpl_visibility, p.vpl_source) {
        (VplVisibility::None, _) => Visibility::None,
        (_, VplSource::UniformBatches) => x.reference.as_mut()?.visibility(f, enc, timer, &vpls),
        _ => x.knecht.as_mut()?.visibility(f, enc, timer, &vpls)?,
    };
    let light = (&vpls, &vis);

    // GI Lab's mix with Gautron et al.: irradiance records lit by the VPLs (stages 5–7 are
    // Gautron's creation, splatting and cache).
    if p.shading_points == ShadingPoints::IrradianceRecords {
        let view = x.gautron.as_mut()?.run(f, enc, timer, Some(light));
        crate::renderer::explain::explain_gautron(f, x, enc, &view);
        return Some(view);
    }

    // Stage 5: shading points (the HCB sample cache, stage 7's choice, acts in the selection:
    // Nguyen §5, Fig. 5).
    match p.shading_points {
        // Mip levels belong to the screen-space gather, which returned above.
        ShadingPoints::EveryPixel
        | ShadingPoints::InterleavedTiles
        | ShadingPoints::MipLevels
        | ShadingPoints::IrradianceRecords => {}
        ShadingPoints::HcbSamples => x.hcb.as_mut()?.select(f, enc, timer, light),
    }

    // Stage 6: the VPL gather at the shading points, then the reconstruction.
    let gathered = match (p.vpl_source, p.shading_points) {
        // The reference's gather folds the batch into its running average (stage 7).
        (VplSource::UniformBatches, _) => {
            // A pinned pixel's replay reads the average before the gather folds the batch in.
            crate::renderer::explain::explain_reference(f, x, enc, &vpls, true);
            let average = x.reference.as_mut()?.gather(f, enc, timer, &vpls, &vis);
            crate::renderer::explain::explain_reference(f, x, enc, &vpls, false);
            average
        }
        (_, ShadingPoints::HcbSamples) => x.hcb.as_ref()?.gather_and_splat(f, enc, timer, light),
        _ => {
            let i = x.interleave.as_mut()?;
            let diffuse = f.settings.vpl.receiver_brdf == ReceiverBrdf::DiffuseOnly;
            let (camera, g) = (f.camera_buffer, f.gbuffer);
            i.shade(
                f.ctx,
                enc,
                timer,
                camera,
                g,
                &vpls.list,
                vpls.count,
                vpls.min_distance,
                vpls.near_cut,
                &vis,
                diffuse,
            );
            crate::passes::view(&i.merged, "indirect.merged")
        }
    };
    // Stages 6–7: reconstruction and temporal, in the order `temporal.order` says when the
    // filter and the merge both run.
    let last = if merges_first(f.settings) {
        let merged = temporal(f, x, enc, timer, gathered)?;
        reconstruct(f, x, enc, timer, merged)?
    } else {
        let reconstructed = reconstruct(f, x, enc, timer, gathered)?;
        temporal(f, x, enc, timer, reconstructed)?
    };
    // A pinned pixel's replay (issue #42), after the chain that lit it.
    if x.explain_pixel.is_some() && p.vpl_source == VplSource::ImportanceWarping {
        crate::renderer::explain::explain_vpl_gather(f, x, enc, &vpls, &vis, &last);
    }
    // The HCB's: its reconstruction (coherence splatting) ran in gather_and_splat and its
    // temporal choice is none, the sample cache (stages 5–6) or the confidence merge, so
    // `last` is `hcb.indirect` or `temporal.history`.
    if p.shading_points == ShadingPoints::HcbSamples {
        crate::renderer::explain::explain_hcb(f, x, enc, &last);
    }
    Some(last)
}

/// Stage 6's near field (`pipeline.near_field`): Soler's screen-space gather of the senders
/// closer than the split, added to the VPL gather's far field by the compose. Whenever stage
/// 7 filters the far field, Eq. 6's warped blend filters the near field
/// (`PipelineSettings::soler_temporal`).
fn near_field_light(
    f: &FrameInputs,
    x: &mut StagePasses,
    enc: &mut wgpu::CommandEncoder,
    timer: &mut GpuTimer,
) -> Option<wgpu::TextureView> {
    let p = &f.settings.pipeline;
    if p.gather != Gather::Vpl || !p.uses_soler() {
        return None;
    }
    Some(x.soler.as_mut()?.run(f, enc, timer))
}

/// Stage 6's reconstruction of the gathered light. Coherence splatting ran with the gather at
/// the samples; the reference needs none.
fn reconstruct(
    f: &FrameInputs,
    x: &mut StagePasses,
    enc: &mut wgpu::CommandEncoder,
    timer: &mut GpuTimer,
    src: wgpu::TextureView,
) -> Option<wgpu::TextureView> {
    Some(match f.settings.pipeline.reconstruction {
        // The upsampling belongs to the screen-space gather, which returned above.
        Reconstruction::None
        | Reconstruction::CoherenceSplatting
        | Reconstruction::BilateralUpsampling
        | Reconstruction::WeightSplatting => src,
        Reconstruction::GeometryAwareFilter => {
            // Knecht's thesis merges, then filters (§4 steps 11–12; `temporal.order`
            // MergeThenFilter); we filter first by default because the confidence's
            // illumination term (Eq. 3.3) then compares the filtered light, an estimate from
            // all N VPLs, with the history instead of one pixel's N/n² VPLs, whose noise
            // alone drove the confidence down and kept flicker high (measured in
            // tests/knecht_quality.rs).
            // The demodulated filter (issue #51) reads this frame's irradiance beside the
            // gathered light; after the thesis' merge its input is the history, which has none.
            let i = x.interleave.as_ref()?;
            let (ctx, s, depth_range) = (f.ctx, &f.settings.interleave, f.depth_range());
            let irradiance = (s.demodulate && !merges_first(f.settings))
                .then(|| crate::passes::view(&i.irradiance, "indirect.irradiance"));
            timer.scope(ctx, enc, "interleave.filter", |e, slot| {
                i.filter(ctx, e, slot, s, depth_range, &src, f.gbuffer, irradiance.as_ref())
            });
            crate::passes::view(&i.filtered, "indirect.filtered")
        }
    })
}

/// Stage 7's temporal choice on `src`.
fn temporal(
    f: &FrameInputs,
    x: &mut StagePasses,
    enc: &mut wgpu::CommandEncoder,
    timer: &mut GpuTimer,
    src: wgpu::TextureView,
) -> Option<wgpu::TextureView> {
    Some(match f.settings.pipeline.temporal {
        // The sample cache acted in stages 5–6, the running average in the reference's gather;
        // the warped blend belongs to the screen-space gather, which returned above.
        Temporal::None
        | Temporal::HcbSampleCache
        | Temporal::RunningAverage
        | Temporal::WarpedBlend
        | Temporal::RecordCache => src,
        Temporal::ConfidenceMerge => {
            // The demodulated merge (issue #51) keeps the irradiance beside the light.
            let irradiance = merge_irradiance(f, x);
            let t = x.temporal.as_mut()?;
            let (ctx, s, depth_range) = (f.ctx, &f.settings.temporal, f.depth_range());
            timer.scope(ctx, enc, "temporal", |e, slot| {
                t.run(ctx, e, slot, s, depth_range, &src, f.gbuffer, irradiance.as_ref())
            });
            crate::passes::view(t.history(), "temporal.history")
        }
    })
}

/// The irradiance the demodulated confidence merge keeps (`temporal.demodulate`, issue #51):
/// after the demodulated geometry-aware filter its window mean (`indirect.filtered_irradiance`),
/// after the HCB's coherence splatting the splatted irradiance (`hcb.irradiance`); None where
/// the merge blends the reflected light (the thesis' merge, or no irradiance to keep).
fn merge_irradiance(f: &FrameInputs, x: &StagePasses) -> Option<wgpu::TextureView> {
    let (s, p) = (f.settings, &f.settings.pipeline);
    if p.temporal != Temporal::ConfidenceMerge || !s.temporal.demodulate {
        return None;
    }
    match p.reconstruction {
        Reconstruction::GeometryAwareFilter if s.interleave.demodulate && !merges_first(s) => {
            x.interleave.as_ref().map(|i| crate::passes::view(&i.filtered_irradiance, "indirect.filtered_irradiance"))
        }
        Reconstruction::CoherenceSplatting if p.shading_points == ShadingPoints::HcbSamples => {
            x.hcb.as_ref().map(|h| crate::passes::view(&h.splat.irradiance, "hcb.irradiance"))
        }
        _ => None,
    }
}

/// Whether stage 7's confidence merge runs before the geometry-aware filter (`temporal.order`
/// MergeThenFilter, when both run).
pub(crate) fn merges_first(s: &crate::lab_settings::LabSettings) -> bool {
    let p = &s.pipeline;
    p.reconstruction == Reconstruction::GeometryAwareFilter
        && p.temporal == Temporal::ConfidenceMerge
        && s.temporal.order == MergeOrder::MergeThenFilter
}
