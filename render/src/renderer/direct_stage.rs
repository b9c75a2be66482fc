//! The camera of stage 1 and stage 2 of the frame (docs/principles.md, the pipeline table): the camera
//! uniform, the shadow maps, the emitters' VPLs and their visibility, the direct light, and
//! its running mean over the still frames while the sky's directions rotate (issue #51,
//! `passes::direct_history`).

use glam::{Mat4, Vec4};

use crate::fingerprint::{Fingerprint, Space};
use crate::passes::CameraUniform;
use crate::passes::direct_history::DirectHistory;
use crate::passes::shadow::{gpu_light, setup_lights};
use crate::renderer::Renderer;
use crate::scene::SceneState;
use crate::timing::PassRec;

impl Renderer {
    /// The camera uniform of this frame (`passes::CameraUniform`), with the previous frame's
    /// view-projection for the movement buffer.
    pub(crate) fn camera_uniform(&self, view_proj: Mat4) -> CameraUniform {
        let prev_view_proj = self.prev.as_ref().map(|p| p.view_proj).unwrap_or(view_proj);
        let (w, h) = (self.width as f32, self.height as f32);
        CameraUniform {
            view_proj,
            prev_view_proj,
            inv_view_proj: view_proj.inverse(),
            view: self.camera.view(),
            position: self.camera.position.extend(1.0),
            viewport: Vec4::new(w, h, 1.0 / w, 1.0 / h),
            params: Vec4::new(self.camera.znear, self.camera.zfar, self.clock.frame as f32, self.clock.time_s()),
            lod: Vec4::new(-1.0, 0.0, 0.0, 0.0),
        }
    }

    /// How many of the frame's lights (the last ones) are the sky's directions rotated this
    /// frame (`sky.rotate_each_frame`).
    pub(crate) fn rotating_sky(&self) -> usize {
        if self.settings.sky.rotate_each_frame { self.sky_lights.count() } else { 0 }
    }

    /// Stage 2: shadow maps, the emitters' VPLs and their visibility, direct light. Returns
    /// the direct light the later stages read (`direct.radiance`, or its running mean while
    /// the sky rotates).
    pub(crate) fn direct_light(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        state: &SceneState,
        (view_proj, gbuffer_key): (Mat4, u64),
    ) -> wgpu::TextureView {
        let ctx = self.ctx.clone();
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
        // The maps are kept while the lights, the objects and the settings stay as they were
        // (issue #53): the views and the draws are all the maps depend on.
        let shadow_key = Fingerprint::new()
            .pod(&lights.views)
            .draws(&state.draws)
            .debug(&ds)
            .u64s(&[self.shadow.size as u64])
            .finish();
        if !self.shadow.last.needs_run(shadow_key, Space::Light) {
            self.kept.push("direct.shadow");
        } else {
            let (shadow, gpu_scene) = (&self.shadow, &self.gpu_scene);
            self.timer.scope(&ctx, enc, "direct.shadow", |e, slot| {
                shadow.run(&ctx, e, slot, gpu_scene, state, &lights.views)
            });
        }
        let gpu_scene = &self.gpu_scene;
        let emitters = match self.stages.emitters.as_mut() {
            Some(pass) => {
                let (scene, radius) = (&self.scene, self.bounds.radius());
                let mut r = crate::timing::Recorder { enc, timer: &mut self.timer };
                pass.run(&ctx, &mut r, (scene, state, gpu_scene), &self.settings, radius)
            }
            None => None,
        };
        if let (Some(pass), Some(_)) = (self.stages.emitters.as_ref(), emitters.as_ref()) {
            self.kept.extend(pass.kept(&self.settings));
        }
        let inputs = crate::passes::direct::DirectInputs {
            settings: &ds,
            camera: &self.camera_buffer,
            gbuffer: &self.gbuffer.targets.views,
            lights: &lights,
            shadow_map: &self.shadow.array_view,
            emitters: emitters.as_ref(),
        };
        // The direct light is kept while the G-buffer, the shadow maps, the lights and the
        // settings are (issue #53). The emitters' VPLs and their maps follow from the objects
        // (in the G-buffer's key) and the settings: the same VPLs every frame.
        let key =
            Fingerprint::new().u64s(&[gbuffer_key, shadow_key]).pod(&lights.lights).debug(&self.settings).finish();
        if !self.direct.last.needs_run(key, Space::Screen) {
            self.kept.push("direct");
        } else {
            let direct = &mut self.direct;
            self.timer.pass(&ctx, enc, "direct", |r| direct.run(r, &inputs));
        }
        let direct_view = crate::passes::view(&self.direct.radiance, "direct.radiance");
        let rotating_sky = self.rotating_sky();
        if rotating_sky == 0 {
            if self.direct_history.take().is_some() {
                self.registry.remove("direct.sky_history");
            }
            return direct_view;
        }
        // While the sky's directions rotate, the direct light is their running mean over the
        // still frames (issue #51): it restarts when anything but the rotation changes.
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
        let averaged = self.timer.scope(&ctx, enc, "direct.sky_history", |e, slot| {
            history.run(PassRec { ctx: &ctx, enc: e, slot }, &direct_view, key, settings)
        });
        history.register(&mut self.registry);
        averaged
    }
}
