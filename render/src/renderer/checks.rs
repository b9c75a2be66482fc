//! What the device refuses, checked before any pass is created: sizes and atlases larger
//! than its limits, each with the largest value that fits.

use crate::gpu::GpuContext;
use crate::passes::knecht::ism::{IsmLayout, MAX_BOUNCES};
use crate::passes::knecht::stage::ism_splats;
use crate::passes::knecht::vpl_bounce::BounceMethod;
use crate::passes::reference::vpl_visibility::AtlasLayout;
use crate::pipeline::VplVisibility;
use crate::settings::{FieldError, LabSettings};

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
