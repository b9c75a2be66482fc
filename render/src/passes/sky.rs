//! Stage 2, the sky light (issue #18 point 2) as `sky.directions` directional VPLs.
//!
//! The sky has no pass of its own: its directions ([`crate::scene::sky`]: drawn by radiance on
//! a stratified Halton set, irradiance E_j = L(ω_j)/(p(ω_j)·n)) join the frame's punctual
//! lights, so `passes::shadow` renders an exact orthographic shadow map for each (the
//! "directional VPLs with visibility" of the issue), `passes::direct` adds their light at every
//! pixel and at Gautron's hemisphere texels, and stage 3 treats each as a light view (Knecht's
//! importance warping gives the sky its share of the VPL budget by power). What the sky is —
//! on or off, colour or image, intensity, rotation — belongs to the scene (`Scene::sky`, saved
//! in the scene overrides file); how finely the lab samples it is this group. Where the scene
//! leaves the screen empty, stage 7 draws the sky ([`SkyBackground`], `sky.background`).

use crate::counters::prelude::*;

use crate::scene::WorldLight;
use crate::scene::sky::Sky;
pub use crate::settings::sky::*;

/// The sky's directional lights, kept while neither the sky nor `sky.directions` changes
/// (an image sky's sampling tables are rebuilt only then).
#[derive(Default)]
pub struct SkyLights {
    key: Option<(Sky, u32, u32)>,
    lights: Vec<WorldLight>,
}

/// Whether two skies light alike (images compared by identity, not texel by texel).
fn same_sky(a: &Sky, b: &Sky) -> bool {
    let image = match (&a.image, &b.image) {
        (None, None) => true,
        (Some((pa, ma)), Some((pb, mb))) => pa == pb && std::sync::Arc::ptr_eq(ma, mb),
        _ => false,
    };
    image
        && a.enabled == b.enabled
        && a.color == b.color
        && a.intensity == b.intensity
        && a.rotation_deg == b.rotation_deg
}

impl SkyLights {
    /// The directional lights of `sky` sampled in `n` directions, the set's `rotation`-th
    /// shift (0: unrotated; empty when the sky is off).
    pub fn get(&mut self, sky: &Sky, n: u32, rotation: u32) -> &[WorldLight] {
        let fresh = self.key.as_ref().is_some_and(|(k, kn, kr)| *kn == n && *kr == rotation && same_sky(k, sky));
        if !fresh {
            self.lights = sky.world_lights_shifted(n, rotation);
            self.key = Some((sky.clone(), n, rotation));
        }
        &self.lights
    }

    /// How many lights the last [`Self::get`] gave.
    pub fn count(&self) -> usize {
        self.lights.len()
    }
}

/// Uniform of the compose's sky background; WGSL twin: `SkyParams` in
/// `shaders/compose/compose.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkyParams {
    /// rgb: the constant sky's radiance, or the image's scale; w: 0 none, 1 constant, 2 image.
    pub radiance: glam::Vec4,
    /// x: the image's rotation about +Y (radians).
    pub rotation: glam::Vec4,
}

/// The sky's image on the GPU for the background (stage 7), uploaded when the image changes.
pub struct SkyBackground {
    pub params: wgpu::Buffer,
    pub texture: wgpu::Texture,
    /// The uploaded image (compared by identity).
    image: Option<std::sync::Arc<crate::scene::sky::EnvMap>>,
}

impl SkyBackground {
    pub fn new(device: &wgpu::Device) -> Self {
        let params = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("sky.background.params"),
            size: std::mem::size_of::<SkyParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let texture = Self::texture(device, 1, 1);
        Self { params, texture, image: None }
    }

    fn texture(device: &wgpu::Device, width: u32, height: u32) -> wgpu::Texture {
        device.counted_texture(&wgpu::TextureDescriptor {
            label: Some("sky.background.image"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    }

    /// This frame's sky behind the scene (`draw`: `sky.background`). An image wider or taller
    /// than the device allows is uploaded at every k-th texel (the lights sample it whole).
    pub fn update(&mut self, ctx: &crate::gpu::GpuContext, sky: &Sky, draw: bool) {
        let mode = match (&sky.image, draw && sky.is_lit()) {
            (_, false) => 0.0,
            (None, true) => 1.0,
            (Some(_), true) => 2.0,
        };
        let scale = if sky.image.is_some() { glam::Vec3::splat(sky.intensity) } else { sky.color * sky.intensity };
        let p = SkyParams {
            radiance: scale.extend(mode),
            rotation: glam::Vec4::new(sky.rotation_deg.to_radians(), 0.0, 0.0, 0.0),
        };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let Some((_, map)) = sky.image.as_ref().filter(|_| mode == 2.0) else { return };
        if self.image.as_ref().is_some_and(|m| std::sync::Arc::ptr_eq(m, map)) {
            return;
        }
        let max = ctx.device.limits().max_texture_dimension_2d.max(1);
        let step = map.width.div_ceil(max).max(map.height.div_ceil(max)).max(1);
        let (w, h) = (map.width.div_ceil(step), map.height.div_ceil(step));
        let mut texels = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let t = map.texels[(y * step * map.width + x * step) as usize];
                texels.push([t.x, t.y, t.z, 1.0]);
            }
        }
        self.texture = Self::texture(&ctx.device, w, h);
        ctx.queue.write_texture(
            self.texture.as_image_copy(),
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(16 * w), rows_per_image: Some(h) },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        self.image = Some(map.clone());
    }
}
