//! What the device refuses, checked before any pass is created: sizes and atlases larger
//! than its limits, each with the largest value that fits.

use crate::gpu::GpuContext;
use crate::lab_settings::LabSettings;
use crate::passes::knecht::ism::{IsmLayout, MAX_BOUNCES};
use crate::passes::knecht::stage::ism_splats;
use crate::passes::knecht::vpl_bounce::BounceMethod;
use crate::passes::reference::vpl_visibility::AtlasLayout;
use crate::settings::FieldError;
use crate::settings::pipeline::VplVisibility;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("cannot render at {width}×{height}: both sides must be at least 1 pixel")]
    ZeroSize { width: u32, height: u32 },
    #[error("cannot render at {width}×{height}: the device allows at most {max}×{max}")]
    TooLarge { width: u32, height: u32, max: u32 },
    #[error("invalid settings:\n{}", .0.iter().map(|e| format!("  - {e}")).collect::<Vec<_>>().join("\n"))]
    Settings(Vec<FieldError>),
    #[error(
        "a shadow map of {size}×{size} with {layers} layers exceeds this device (max {max_dim}² texels, {max_layers} layers); the largest valid size is {largest}"
    )]
    ShadowMapTooLarge { size: u32, layers: u32, max_dim: u32, max_layers: u32, largest: u32 },
    #[error(
        "the exact-VPL visibility atlas for {vpls} VPLs per frame (all bounces) with {size}² faces needs {width}×{height} texels; this device allows {max_dim}²: at {size}² at most {largest} VPLs per frame fit"
    )]
    VplAtlasTooLarge { vpls: u32, size: u32, width: u64, height: u64, max_dim: u32, largest: u32 },
    #[error(
        "the imperfect shadow map atlas for {vpls} VPLs × {bounces} bounce(s) of {size}² needs {width}×{height} texels ({bytes} bytes to splat into); this device allows {max_dim}² texels and {max_buffer} bytes: at {size}² and {bounces} bounce(s) at most {largest_vpls} VPLs fit{}",
        match .largest_size { Some(s) => format!(", and {vpls} VPLs fit at map size {s}²"), None => String::new() }
    )]
    IsmAtlasTooLarge {
        vpls: u32,
        bounces: u32,
        size: u32,
        width: u64,
        height: u64,
        bytes: u64,
        max_dim: u32,
        max_buffer: u64,
        largest_vpls: u32,
        largest_size: Option<u32>,
    },
    #[error(
        "interleaved tiles n = {n} at {width}×{height} need a split G-buffer of {split_w}×{split_h} (whole tiles); this device allows {max}²: at n = {n} at most {largest_w}×{largest_h} fit"
    )]
    SplitTooLarge {
        n: u32,
        width: u32,
        height: u32,
        split_w: u32,
        split_h: u32,
        max: u32,
        largest_w: u32,
        largest_h: u32,
    },
    #[error(
        "the scene does not fit this device: its {what} need {bytes} bytes in one buffer, and this device allows {max} bytes per buffer"
    )]
    SceneTooLarge { what: &'static str, bytes: u64, max: u64 },
    #[error(
        "the IRSM atlas for {vpls} VPLs of {size}² needs {width}×{height} texels; this device allows {max_dim}² texels and {max_buffer} bytes per buffer: at {size}² at most {largest_vpls} VPLs fit"
    )]
    IrsmAtlasTooLarge {
        vpls: u32,
        size: u32,
        width: u64,
        height: u64,
        max_dim: u32,
        max_buffer: u64,
        largest_vpls: u32,
    },
}

impl RenderError {
    /// The largest value of `field` that the device limit behind this error allows, where the
    /// error names one (issue #19: the lab clamps a slider to it): the VPL count or map size of
    /// an ISM atlas, the VPL count of an IRSM or exact-map atlas, the reference's batch, the
    /// shadow map size. `settings` are the refused ones (the exact maps count every bounce).
    pub fn largest_value(&self, field: &str, settings: &LabSettings) -> Option<crate::settings::Value> {
        use crate::settings::Value;
        let positive = |v: u32| (v >= 1).then_some(Value::U32(v));
        match (self, field) {
            (RenderError::IsmAtlasTooLarge { largest_vpls, .. }, "vpl.count") => positive(*largest_vpls),
            (RenderError::IsmAtlasTooLarge { largest_size, .. }, "ism.map_size") => largest_size.and_then(positive),
            (RenderError::IrsmAtlasTooLarge { largest_vpls, .. }, "vpl.count") => positive(*largest_vpls),
            (RenderError::VplAtlasTooLarge { largest, .. }, "vpl.count") => {
                positive(largest / settings.vpl.bounces.clamp(1, MAX_BOUNCES))
            }
            (RenderError::VplAtlasTooLarge { largest, .. }, "reference.vpls_per_frame") => positive(*largest),
            (RenderError::ShadowMapTooLarge { largest, .. }, "direct.shadow_map_size") => positive(*largest),
            _ => None,
        }
    }
}

/// Refuses an exact-VPL atlas larger than the device allows, naming the largest batch that fits.
pub(crate) fn check_vpl_atlas(ctx: &GpuContext, settings: &LabSettings) -> Result<(), RenderError> {
    if !settings.pipeline.is_reference() {
        return Ok(());
    }
    let rs = &settings.reference;
    let l = AtlasLayout::new(rs.vpls_per_frame, rs.shadow_map_size);
    let max_dim = ctx.limits.max_texture_dimension_2d;
    if l.fits(max_dim) {
        return Ok(());
    }
    Err(RenderError::VplAtlasTooLarge {
        vpls: rs.vpls_per_frame,
        size: rs.shadow_map_size,
        width: l.width(),
        height: l.height(),
        max_dim,
        largest: AtlasLayout::largest_batch(rs.shadow_map_size, max_dim),
    })
}

/// Refuses an ISM (or exact-map) atlas of instant radiosity larger than the device allows,
/// naming the largest VPL count at this map size and the largest map size for this count.
pub(crate) fn check_ism_atlas(ctx: &GpuContext, settings: &LabSettings) -> Result<(), RenderError> {
    if !settings.pipeline.uses_knecht_vpls() {
        return Ok(());
    }
    let (vpls, size) = (settings.vpl.count, settings.ism.map_size);
    let bounces = settings.vpl.bounces.clamp(1, MAX_BOUNCES);
    let max_dim = ctx.limits.max_texture_dimension_2d;
    if ism_splats(settings) {
        let max_buffer = ctx.limits.max_storage_buffer_binding_size.min(ctx.limits.max_buffer_size);
        let l = IsmLayout::new(vpls * bounces, size);
        if !l.fits(max_dim, max_buffer) {
            return Err(RenderError::IsmAtlasTooLarge {
                vpls,
                bounces,
                size,
                width: l.width(),
                height: l.height(),
                bytes: l.width() * l.height() * 4,
                max_dim,
                max_buffer,
                largest_vpls: IsmLayout::largest_count(size, max_dim, max_buffer) / bounces,
                largest_size: IsmLayout::largest_size(vpls * bounces, max_dim, max_buffer),
            });
        }
    }
    if bounces > 1 && settings.vpl.bounce_method == BounceMethod::Irsm {
        let max_buffer = ctx.limits.max_storage_buffer_binding_size.min(ctx.limits.max_buffer_size);
        let size = crate::passes::knecht::irsm::irsm_size(settings.vpl.irsm_size);
        let l = IsmLayout::new(vpls, size);
        if !l.fits(max_dim, max_buffer) {
            return Err(RenderError::IrsmAtlasTooLarge {
                vpls,
                size,
                width: l.width(),
                height: l.height(),
                max_dim,
                max_buffer,
                largest_vpls: IsmLayout::largest_count(size, max_dim, max_buffer),
            });
        }
    }
    if settings.pipeline.vpl_visibility == VplVisibility::Exact {
        let l = AtlasLayout::new(vpls * bounces, size);
        if !l.fits(max_dim) {
            return Err(RenderError::VplAtlasTooLarge {
                vpls: vpls * bounces,
                size,
                width: l.width(),
                height: l.height(),
                max_dim,
                largest: AtlasLayout::largest_batch(size, max_dim),
            });
        }
    }
    Ok(())
}

/// Refuses a scene whose vertex, index or instance buffer would be larger than the device
/// allows, before anything is uploaded.
pub(crate) fn check_scene(ctx: &GpuContext, scene: &crate::scene::Scene) -> Result<(), RenderError> {
    let (mut vertices, mut indices) = (0u64, 0u64);
    for p in scene.meshes.iter().flat_map(|m| &m.primitives) {
        vertices += p.vertices.len() as u64;
        indices += p.indices.len() as u64;
    }
    let draws = scene.evaluate(0.0).draws.len() as u64;
    let max = ctx.limits.max_buffer_size;
    let max_storage = ctx.limits.max_storage_buffer_binding_size.min(max);
    let vertex = std::mem::size_of::<crate::scene::Vertex>() as u64;
    let instance = std::mem::size_of::<crate::passes::InstanceUniform>() as u64;
    for (what, bytes, max) in [
        ("vertices", vertices * vertex, max),
        ("triangle indices", indices * 4, max),
        ("instances (one per drawn primitive)", draws * instance, max_storage),
    ] {
        if bytes > max {
            return Err(RenderError::SceneTooLarge { what, bytes, max });
        }
    }
    Ok(())
}

/// Refuses a size at which the interleaved split G-buffer (n×n whole tiles, Knecht 002
/// §3.4.2; `passes::knecht::interleave`) would be wider or taller than the device allows:
/// a side just under the maximum rounds up past it.
pub(crate) fn check_split(
    ctx: &GpuContext,
    settings: &LabSettings,
    width: u32,
    height: u32,
) -> Result<(), RenderError> {
    let p = &settings.pipeline;
    if !(p.uses_knecht_vpls() && p.shading_points == crate::settings::pipeline::ShadingPoints::InterleavedTiles) {
        return Ok(());
    }
    let n = settings.interleave.n.max(1);
    let (tw, th) = crate::passes::knecht::interleave::InterleavePass::tile(width, height, n);
    let (split_w, split_h) = (tw as u64 * n as u64, th as u64 * n as u64);
    let max = ctx.limits.max_texture_dimension_2d;
    if split_w <= max as u64 && split_h <= max as u64 {
        return Ok(());
    }
    let largest = max / n * n;
    Err(RenderError::SplitTooLarge {
        n,
        width,
        height,
        split_w: split_w.min(u32::MAX as u64) as u32,
        split_h: split_h.min(u32::MAX as u64) as u32,
        max,
        largest_w: width.min(largest),
        largest_h: height.min(largest),
    })
}

pub(crate) fn check_size(ctx: &GpuContext, width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 {
        return Err(RenderError::ZeroSize { width, height });
    }
    let max = ctx.limits.max_texture_dimension_2d;
    if width > max || height > max {
        return Err(RenderError::TooLarge { width, height, max });
    }
    Ok(())
}
