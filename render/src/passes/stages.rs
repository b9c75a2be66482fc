//! The typed data that flows between the stages of `frame.rs` (the pipeline table of
//! docs/principles.md): what every stage's passes read of the frame, and what stages 3 and 4
//! hand on.

use glam::Vec4;

use super::gbuffer::GBufferViews;
use super::shadow::{GpuLight, LightView};
use crate::camera::Camera;
use crate::gpu::GpuContext;
use crate::lab_settings::LabSettings;
use crate::scene::upload::GpuScene;
use crate::scene::{Scene, SceneState};
use crate::timing::PassRec;

/// What the stages read of the frame: the scene at this instant, the settings, the camera
/// and the G-buffer of stage 1.
pub struct FrameInputs<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a Scene,
    pub gpu_scene: &'a GpuScene,
    pub state: &'a SceneState,
    pub settings: &'a LabSettings,
    /// The camera uniform buffer (`passes::CameraUniform`).
    pub camera_buffer: &'a wgpu::Buffer,
    pub camera: &'a Camera,
    /// The camera's view-projection this frame.
    pub view_proj: glam::Mat4,
    pub gbuffer: &'a GBufferViews,
    /// The scene's bounding radius (the VPL maps' offsets and clip planes).
    pub radius: f32,
    /// The length scene-relative settings are fractions of (`scale::scale_radius`: the room
    /// the camera is in, else the scene's bounding radius).
    pub scale: f32,
    /// The centre of the scene's bounds.
    pub center: glam::Vec3,
    pub height: u32,
    /// The G-buffer's width and height.
    pub gbuffer_size: (u32, u32),
    /// The frame's index (per-frame sample rotations).
    pub frame: u32,
    /// Stage 2's pass (`passes::direct::DirectPass`): its lights and shadow maps also light
    /// Gautron's record hemispheres.
    pub direct: &'a dyn DirectAtlas,
    /// Stage 2's direct light (`direct.radiance`), the first bounce's source.
    pub direct_radiance: &'a wgpu::TextureView,
    /// Its diffuse part (`direct.diffuse`), when a stage asked for it (`soler.sender`).
    pub direct_diffuse: Option<&'a wgpu::TextureView>,
    /// Every light of the frame on the GPU, and the light views with their light's index.
    pub lights: Vec<GpuLight>,
    pub views: Vec<(u32, LightView)>,
    /// How many of `lights` (the last ones) are the sky's directions rotated this frame
    /// (`sky.rotate_each_frame`, issue #51): they change every frame by design, so the caches
    /// that restart when a light changes compare [`FrameInputs::steady_light_key`] instead.
    pub rotating_sky: usize,
    /// How many of `lights` (the last ones) are the sky's directions, rotating or not (the
    /// ray-traced stages sample the sky itself and take only the scene's own lights).
    pub sky_lights: usize,
    /// The room the camera stands in (`scale::ScaleSource::Room`), when it stands in one.
    pub room: Option<crate::maths::Aabb>,
    /// The pixel being explained (issue #42), when one is: stages that replay inside their
    /// run (Soler's, bounce by bounce) read it here.
    pub explain_pixel: Option<(u32, u32)>,
    /// Whether this frame kept the G-buffer and the direct light: nothing the screen depends
    /// on (camera, objects, lights, settings, size) changed since the last frame (issue #53).
    /// Steps that depend on nothing else keep their last result too (the hemispheres at the
    /// HCB's samples).
    pub unchanged: bool,
    /// The buffers this frame's recorded read-backs copy (a pass that leaves one to be filled
    /// when read fills it in the frame instead, issue #53).
    pub read_back: crate::readback::Wanted,
}

/// What the later stages ask of stage 2's direct light besides its image: the same lights and
/// shadow maps at an atlas of G-buffer tiles (Gautron et al.'s record hemispheres, 003 "Simple
/// plane sampling"). `passes::direct::DirectPass` implements it; the stages see only this, so
/// that the frame's data sits below every pass.
pub trait DirectAtlas {
    /// The direct light of this frame at an atlas of G-buffer tiles, tile k
    /// seen from `viewers[k]` (xyz; w = 0: an empty tile), into `out` (the direct light's
    /// radiance format, the atlas's `size`). `indirect`: the dispatch's workgroups from a
    /// buffer (x, y, 1 at the offset; the rows of the tiles in use, issue #53) instead of the
    /// whole atlas.
    #[allow(clippy::too_many_arguments)]
    fn shade_atlas(
        &self,
        r: PassRec<'_, '_>,
        atlas: &GBufferViews,
        out: &wgpu::TextureView,
        size: (u32, u32),
        params: &wgpu::Buffer,
        viewers: &wgpu::Buffer,
        indirect: Option<(&wgpu::Buffer, u64)>,
    );
}

impl FrameInputs<'_> {
    /// What the lights are, but for the rotation of the sky's directions: every light but
    /// the rotating sky's directions, and then the sky itself (on, colour, intensity, image
    /// rotation) when its directions rotate.
    pub fn steady_light_key(&self) -> Vec<f32> {
        let steady = &self.lights[..self.lights.len() - self.rotating_sky.min(self.lights.len())];
        let mut key: Vec<f32> = steady.iter().flat_map(|l| bytemuck::cast::<_, [f32; 20]>(*l)).collect();
        if self.rotating_sky > 0 {
            let sky = &self.scene.sky;
            let image = sky.image.as_ref().map_or(0.0, |(_, m)| std::sync::Arc::as_ptr(m) as usize as f32);
            key.extend([sky.color.x, sky.color.y, sky.color.z, sky.intensity, sky.rotation_deg, image]);
        }
        key
    }

    /// The radiance Soler et al.'s first bounce gathers (`soler.sender`): the direct light's
    /// diffuse part (004 §5.3) or the whole of it toward the camera.
    pub fn sender_radiance(&self) -> &wgpu::TextureView {
        match (self.settings.soler.sender, self.direct_diffuse) {
            (crate::settings::soler::Sender::Diffuse, Some(d)) => d,
            _ => self.direct_radiance,
        }
    }

    /// The depth range of the thesis' linear depth (Knecht 002 Eq. 4.2).
    pub fn depth_range(&self) -> f32 {
        self.camera.zfar - self.camera.znear
    }

    /// The split distance of the near field when a VPL gather has one (`pipeline.near_field`,
    /// scene units), else 0: the VPL gather skips senders closer, the screen-space gather
    /// skips senders farther.
    pub fn near_field_cut(&self) -> f32 {
        let p = &self.settings.pipeline;
        if p.uses_vpls() && p.near_field == crate::settings::pipeline::NearField::ScreenSpace {
            self.settings.soler.near_field_split(self.scale).max(0.0)
        } else {
            0.0
        }
    }

    /// The bounding radius the VPL passes scale their offsets and clip planes by (never 0).
    pub fn vpl_radius(&self) -> f32 {
        self.radius.max(1e-3)
    }
}

/// Stage 3's output: the VPLs the gather reads.
#[derive(Clone)]
pub struct VplSet {
    /// `vpl.list`: `passes::reference::vpl::GpuVpl` records, all bounces.
    pub list: wgpu::Buffer,
    /// Slots of the list to gather (all bounces).
    pub count: u32,
    /// The geometry term's distance clamp d_min (Knecht 002 Eq. 4.7).
    pub min_distance: f32,
    /// Senders closer than this are the near field's (`pipeline.near_field`): the gather
    /// skips them. 0: no near field.
    pub near_cut: f32,
    /// Where the slots come from, for explaining a pixel: (first slot, count, source) ranges
    /// ("light 0", "emitters", "bounce 1"); empty where the source does not say.
    pub sources: Vec<(u32, u32, String)>,
}

/// The visibility the gather reads: stage 4's output (views are shared handles, cheap to
/// clone).
#[derive(Clone)]
pub enum GatherVisibility {
    None,
    /// The ISM atlas (level 0 after pull-push), with columns, map size, eye offset, depth bias
    /// and receiver normal offset (texels).
    Ism {
        atlas: wgpu::TextureView,
        cols: u32,
        size: u32,
        eye_offset: f32,
        bias: f32,
        normal_offset: f32,
    },
    /// The exact cube-face atlas, with columns, face size and (near, far, eye offset).
    Exact {
        atlas: wgpu::TextureView,
        cols: u32,
        size: u32,
        clip: glam::Vec3,
    },
}

impl GatherVisibility {
    /// The shaders' encoding: (mode 0 none / 1 ISM / 2 exact, the ISM atlas or `no_ism`, the
    /// exact atlas or `no_exact`, atlas columns, map size, (0, eye offset or near, bias or
    /// far, normal offset or eye offset)).
    pub fn parts<'a>(
        &'a self,
        no_ism: &'a wgpu::TextureView,
        no_exact: &'a wgpu::TextureView,
    ) -> (u32, &'a wgpu::TextureView, &'a wgpu::TextureView, u32, u32, Vec4) {
        match self {
            GatherVisibility::None => (0, no_ism, no_exact, 1, 1, Vec4::ZERO),
            GatherVisibility::Ism { atlas, cols, size, eye_offset, bias, normal_offset } => {
                (1, atlas, no_exact, *cols, *size, Vec4::new(0.0, *eye_offset, *bias, *normal_offset))
            }
            GatherVisibility::Exact { atlas, cols, size, clip } => {
                (2, no_ism, atlas, *cols, *size, Vec4::new(0.0, clip.x, clip.y, clip.z))
            }
        }
    }
}

/// Stage 4's output under its stage's name.
pub use GatherVisibility as Visibility;

/// The clip planes of VPL depth maps in a scene of bounding radius `r`: (near, far, eye
/// offset, w).
pub fn vpl_clip(r: f32, w: f32) -> Vec4 {
    let (near, far) = ((r * 1e-3).max(1e-5), 2.2 * r);
    Vec4::new(near, far, 2.0 * near, w)
}
