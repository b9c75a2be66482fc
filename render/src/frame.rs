//! The whole frame, stage by stage, in the order of the pipeline table of docs/principles.md.
//! Stages 1, 2 and 7 are the same for every choice; stages 3–7's indirect light is the list of
//! steps the stage choices (`pipeline.*`) compose (`crate::chain`), built when they change and
//! run here as a list: no paper's name or logic lives in this file.
//! `docs/architecture.md` lists every choice, its steps, and how to add one.
//!
//! | stage | what runs |
//! |---|---|
//! | 1. G-buffer | `passes::gbuffer`: linear depth, normal, albedo, material, depth, movement buffer; the position rebuilt from the depth when read (`passes::gbuffer_position`) |
//! | 2. Direct light | `renderer::direct_stage`: shadow maps, the emitters' VPLs, the direct light, the rotating sky's mean |
//! | 3–7. Indirect light | `chain`: the steps of the stage choices (VPLs, their visibility, shading points, gather, reconstruction, temporal), then the near field's |
//! | 7. Compose | `passes::compose`: direct + indirect + near field + emission + sky, tone mapped |

use crate::chain::Recorder;
use crate::counters::prelude::CountedQueue;
use crate::fingerprint::{Fingerprint, Space};
use crate::passes::stages::FrameInputs;
use crate::renderer::{PrevFrame, Renderer, light_view_list};
use crate::timing::PassTiming;

impl Renderer {
    /// Renders one frame and advances the clock. Returns the per-pass timings (this frame's,
    /// or in interactive mode the newest available).
    pub fn render_frame(&mut self) -> Vec<PassTiming> {
        let ctx = self.ctx.clone();
        ctx.make_current();
        self.check_camera();
        // Whether `gbuffer.position` lags the linear depth (issue #53): this frame fills it
        // or leaves it to be filled when read, never before its camera is written below.
        let position_stale = self.gbuffer.position.as_ref().is_some_and(|p| p.fill.take_stale());
        let normal_stale = self.gbuffer.normal.as_ref().is_some_and(|p| p.take_stale());
        let emission_stale = self.gbuffer.no_emission.as_ref().is_some_and(|p| p.take_stale());
        let material_stale = self.gbuffer.material.as_ref().is_some_and(|p| p.take_stale());
        // What the read-backs recorded in this frame copy (a buffer filled only when read is
        // then filled in the frame).
        let read_back = self
            .readbacks
            .get_mut()
            .map(|r| r.wanted())
            .unwrap_or(crate::readback::Wanted { all: true, names: vec![] });
        // final.hdr only when this frame's read-backs copy it (issue #53; a read after the
        // frame composes it again, `ComposePass::compose`).
        let store_hdr = read_back.reads("final.hdr");

        // The scene at this instant; the sky's directions join its lights (`passes::sky`).
        let state = self.frame_state();
        let view_proj = self.camera.view_proj(self.width as f32 / self.height as f32);
        let cam = self.camera_uniform(view_proj);
        ctx.queue.upload(&self.camera_buffer, 0, bytemuck::bytes_of(&cam));
        self.gpu_scene.update_instances(&ctx, &state, self.prev.as_ref().map(|p| p.models.as_slice()));
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });

        // The passes and the list of steps the stage choices name (built when they change).
        self.ensure_passes_for(Some(&state));

        // Stage 1: G-buffer and movement buffer, kept while the camera and the objects stay
        // put (issue #53: the key holds everything its raster reads).
        if !self.reuse_unchanged {
            self.redo_kept_passes();
        }
        let prev_models = self.prev.as_ref().map(|p| p.models.as_slice()).unwrap_or(&[]);
        let gbuffer_key = Fingerprint::new()
            .pod(&[cam.view_proj, cam.prev_view_proj, cam.view])
            .pod(&[cam.position, cam.viewport, cam.lod])
            .draws(&state.draws)
            .pod(prev_models)
            .finish();
        self.kept.clear();
        let gbuffer_ran = self.gbuffer.last.needs_run(gbuffer_key, Space::Screen);
        if !gbuffer_ran {
            self.kept.push("gbuffer");
        } else {
            let (gbuffer, camera_group, gpu_scene) = (&self.gbuffer, &self.camera_group, &self.gpu_scene);
            self.timer
                .scope(&ctx, &mut enc, "gbuffer", |e, slot| gbuffer.run(e, slot, camera_group, gpu_scene, &state));
        }
        // The camera G-buffer's position, rebuilt from its linear depth when a step of this
        // frame or a read-back recorded in it reads it; otherwise when something reads it.
        let mut position_stale = position_stale || gbuffer_ran;
        if let Some(position) = self.gbuffer.position.clone() {
            if gbuffer_ran {
                position.keep_camera(&mut enc, &self.camera_buffer);
            }
            let pinned = self.stages.explain_pixel.is_some();
            let read = self.steps.needs_position(pinned) || read_back.reads("gbuffer.position");
            if position_stale && read {
                self.timer.scope(&ctx, &mut enc, "gbuffer.position", |e, slot| {
                    position.fill.record(e, slot.and_then(|s| s.compute(true, true)))
                });
                position_stale = false;
            }
        }
        // The same for the normals unpacked from their words (read by the same steps as the
        // position), for the emission a scene without emitters leaves out and for the
        // material's metallic and roughness, read back in this frame.
        let steps_unpack = self.steps.needs_position(self.stages.explain_pixel.is_some());
        // `steps`: whether a step of this frame reads the buffer.
        let mut fill_if_read =
            |fill: Option<&std::sync::Arc<crate::passes::gbuffer_position::Fill>>, stale, name, steps| {
                let stale = stale || gbuffer_ran;
                match fill.filter(|_| stale && (steps || read_back.reads(name))) {
                    Some(fill) => {
                        self.timer.scope(&ctx, &mut enc, fill.name(), |e, slot| {
                            fill.record(e, slot.and_then(|s| s.compute(true, true)))
                        });
                        false
                    }
                    None => stale,
                }
            };
        let normal_stale = fill_if_read(self.gbuffer.normal.as_ref(), normal_stale, "gbuffer.normal", steps_unpack);
        let emission_stale = fill_if_read(self.gbuffer.no_emission.as_ref(), emission_stale, "gbuffer.emission", false);
        let material_stale = fill_if_read(self.gbuffer.material.as_ref(), material_stale, "gbuffer.material", false);

        // Stage 2: shadow maps, the emitters' VPLs, direct light.
        let direct_view = self.direct_light(&mut enc, &state, (view_proj, gbuffer_key));

        // Stages 3–7: the indirect light of the stage choices' steps, then the near field's.
        let scale = self.scale();
        let f = FrameInputs {
            ctx: &ctx,
            scene: &self.scene,
            gpu_scene: &self.gpu_scene,
            state: &state,
            settings: &self.settings,
            camera_buffer: &self.camera_buffer,
            camera: &self.camera,
            view_proj,
            gbuffer: &self.gbuffer.targets.views,
            radius: self.bounds.radius(),
            scale: scale.0,
            center: self.bounds.center(),
            height: self.height,
            gbuffer_size: (self.width, self.height),
            frame: self.clock.frame as u32,
            direct: &self.direct,
            direct_radiance: &direct_view,
            direct_diffuse: self.direct.diffuse.as_ref().map(|(_, v)| v),
            lights: state.lights.iter().map(crate::passes::shadow::gpu_light).collect(),
            views: light_view_list(&state, self.bounds),
            rotating_sky: self.rotating_sky(),
            sky_lights: self.sky_lights.count(),
            room: match scale.1 {
                crate::scale::ScaleSource::Room(b) => Some(b),
                crate::scale::ScaleSource::Model => None,
            },
            explain_pixel: self.stages.explain_pixel,
            unchanged: self.kept.contains(&"gbuffer") && self.kept.contains(&"direct"),
            read_back,
        };
        let unchanged = f.unchanged;
        let mut rec = Recorder { enc: &mut enc, timer: &mut self.timer };
        let (indirect, near_field) = self.steps.run(&f, &mut self.stages, &mut rec);
        if let Some(k) = self.stages.knecht.as_ref().filter(|_| self.settings.pipeline.uses_knecht_vpls()) {
            self.kept.extend(k.kept(&self.settings));
        }
        if unchanged {
            self.kept.extend(self.steps.kept_when_unchanged());
        }
        // The temporal histories ping-pong: the registry names this frame's.
        self.stages.register_histories(&mut self.registry);

        // Stage 7: compose direct + indirect and tone map.
        self.sky_background.update(&ctx, &self.scene.sky, self.settings.sky.background);
        // The compose tone maps with the previous frame's exposure; a separate tone-mapping
        // pass runs only when there is none yet (the first frame of automatic exposure).
        let inputs = crate::passes::compose::ComposeInputs {
            emission: self.gbuffer.writes().emission.then_some(&self.gbuffer.targets.views.emission),
            direct: &direct_view,
            indirect: indirect.as_ref(),
            near_field: near_field.as_ref(),
            sky: (&self.sky_background, &self.camera_buffer, &self.gbuffer.targets.views.linear_depth),
        };
        let (compose, ts) = (&mut self.compose, &self.settings.tonemap);
        self.timer.pass(&ctx, &mut enc, "compose", |r| compose.compose(r, ts, &inputs, store_hdr));
        self.timer.scope(&ctx, &mut enc, "compose.luminance", |e, slot| compose.luminance(&ctx, e, slot, ts));
        if !compose.tone_mapped() {
            self.timer.scope(&ctx, &mut enc, "compose.tonemap", |e, slot| compose.tonemap(&ctx, e, slot, ts));
        }

        // The read-backs asked for since the last frame, copied in this frame's encoder.
        let readbacks = self.readbacks.get_mut().unwrap_or_else(|p| p.into_inner());
        if readbacks.pending() > 0 {
            crate::counters::traffic::begin_scope("readback");
            let probe = self.depth_probe.get_or_init(|| crate::buffers::DepthProbe::new(&ctx));
            let size = (self.width, self.height);
            readbacks.record(&ctx, &mut enc, &self.registry, probe, size, self.clock.frame);
            crate::counters::traffic::end_scope();
        }
        self.timer.resolve(&ctx, &mut enc);
        ctx.submit([enc.finish()]);
        if let Some(position) = self.gbuffer.position.as_ref() {
            position.fill.set_stale(position_stale);
        }
        if let Some(normal) = self.gbuffer.normal.as_ref() {
            normal.set_stale(normal_stale);
        }
        if let Some(no_emission) = self.gbuffer.no_emission.as_ref() {
            no_emission.set_stale(emission_stale);
        }
        if let Some(material) = self.gbuffer.material.as_ref() {
            material.set_stale(material_stale);
        }
        readbacks.start_maps();
        let timings = self.timer.collect(&ctx, !self.interactive).to_vec();

        self.traffic = crate::counters::traffic::end_frame();
        crate::counters::reuse::end_frame();
        self.prev = Some(PrevFrame { view_proj, models: state.draws.iter().map(|d| d.world).collect() });
        self.clock.tick();
        timings
    }
}
