//! The registry of named intermediate buffers (docs/principles.md principle 6).
//!
//! Every texture a pass writes is registered under a dotted name (`gbuffer.normal`,
//! `direct.shadow_map`, `final.ldr`). The same names feed the buffer viewer, the pixel
//! probe, captures, the CLI (`gi-lab render --buffer NAME`) and the tests, which read any
//! of them back to the CPU as f32 RGBA whatever its format.

use crate::counters::prelude::*;

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::gpu::GpuContext;

mod probe;

pub use probe::{DepthProbe, PROBE_INPUTS_BINDINGS, PROBE_MAX_POINTS, ProbeJobs};

/// How a buffer's values should be shown when turned into an 8-bit image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferKind {
    /// Display-ready colour (sRGB-encoded 8-bit).
    Ldr,
    /// Linear radiance: exposure and tone mapping apply.
    Hdr,
    /// A unit vector in xyz (normals): shown as 0.5 + 0.5·n.
    Direction,
    /// Colour-like data in [0, 1] (albedo): shown as is.
    Albedo,
    /// Scalar or vector data with arbitrary range: normalised per channel.
    Data,
    /// Depth buffer values in [0, 1].
    Depth,
    /// Screen-space offsets in pixels (the movement buffer).
    Motion,
}

/// One registered buffer.
#[derive(Clone, Debug)]
pub struct BufferEntry {
    pub name: String,
    pub description: String,
    pub kind: BufferKind,
    pub texture: wgpu::Texture,
}

/// An image read back from the GPU, as f32 RGBA rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageF32 {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[f32; 4]>,
}

impl ImageF32 {
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, data: vec![[0.0; 4]; (width * height) as usize] }
    }
    /// Texel at (x, y); panics when out of range (callers index their own images).
    pub fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.data[(y * self.width + x) as usize]
    }
    /// Per-channel minimum and maximum over finite values.
    pub fn channel_range(&self) -> ([f32; 4], [f32; 4]) {
        let mut lo = [f32::INFINITY; 4];
        let mut hi = [f32::NEG_INFINITY; 4];
        for p in &self.data {
            for c in 0..4 {
                if p[c].is_finite() {
                    lo[c] = lo[c].min(p[c]);
                    hi[c] = hi[c].max(p[c]);
                }
            }
        }
        (lo, hi)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BufferError {
    #[error("no buffer named '{name}'; known buffers: {known}")]
    Unknown { name: String, known: String },
    #[error("buffer '{name}' has format {format:?}, which cannot be read back")]
    Format { name: String, format: wgpu::TextureFormat },
    #[error("buffer '{name}' has {have} layers/levels; {what} {want} does not exist")]
    Range { name: String, what: &'static str, have: u32, want: u32 },
    #[error("reading back '{name}' failed: {message}")]
    Map { name: String, message: String },
}

/// A buffer that a pass fills only when something reads it (issue #53: the camera G-buffer's
/// position, rebuilt from its linear depth by `passes::gbuffer_position`). The registry
/// brings it up to date before it hands it out.
pub trait Derived: Send + Sync {
    /// Records and submits the pass that fills the buffer, when its content is stale.
    fn refresh(&self);
}

#[derive(Clone)]
struct DerivedHook(Arc<dyn Derived>);

impl std::fmt::Debug for DerivedHook {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("DerivedHook")
    }
}

/// Named textures of the current frame.
#[derive(Default, Debug)]
pub struct BufferRegistry {
    entries: BTreeMap<String, BufferEntry>,
    /// The buffers filled on demand ([`Derived`]), by name.
    derived: BTreeMap<String, DerivedHook>,
}

impl BufferRegistry {
    /// Forgets a buffer that no pass writes any more (nothing when it is not registered).
    pub fn remove(&mut self, name: &str) {
        self.entries.remove(name);
        self.derived.remove(name);
    }

    /// Registers (or replaces, after a resize) a buffer.
    pub fn register(&mut self, name: &str, kind: BufferKind, description: &str, texture: &wgpu::Texture) {
        self.entries.insert(
            name.to_string(),
            BufferEntry { name: name.into(), description: description.into(), kind, texture: texture.clone() },
        );
        self.derived.remove(name);
    }

    /// Registers a buffer that `hook` fills when it is read ([`Derived`]): every access
    /// through [`Self::get`] and [`Self::entries`] (the viewer, the probe, the read-backs)
    /// refreshes it first.
    pub fn register_derived(
        &mut self,
        name: &str,
        kind: BufferKind,
        description: &str,
        texture: &wgpu::Texture,
        hook: Arc<dyn Derived>,
    ) {
        self.register(name, kind, description, texture);
        self.derived.insert(name.to_string(), DerivedHook(hook));
    }

    /// Refreshes every derived buffer (before a read of all of them).
    fn refresh_all(&self) {
        self.derived.values().for_each(|h| h.0.refresh());
    }

    pub fn get(&self, name: &str) -> Result<&BufferEntry, BufferError> {
        if let Some(h) = self.derived.get(name) {
            h.0.refresh();
        }
        self.entries.get(name).ok_or_else(|| BufferError::Unknown {
            name: name.into(),
            known: self.entries.keys().cloned().collect::<Vec<_>>().join(", "),
        })
    }

    /// All names in sorted (tree) order.
    pub fn names(&self) -> Vec<String> {
        self.entries.keys().cloned().collect()
    }

    pub fn entries(&self) -> impl Iterator<Item = &BufferEntry> {
        self.refresh_all();
        self.entries.values()
    }

    /// Reads `layer` (array layer) at `mip` of a buffer back as f32 RGBA. Blocks.
    pub fn readback(&self, ctx: &GpuContext, name: &str, layer: u32, mip: u32) -> Result<ImageF32, BufferError> {
        let e = self.get(name)?;
        read_texture(ctx, name, &e.texture, layer, mip)
    }
}

/// One buffer's raw value at a probed pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct ProbeValue {
    pub name: String,
    /// The texel read: the probed pixel scaled to this buffer's size (layer 0, level 0).
    pub texel: (u32, u32),
    pub value: [f32; 4],
}

impl BufferRegistry {
    /// The raw value of every registered buffer at each of `pixels` (coordinates in a
    /// `frame_size` image; buffers of another size are read at the same relative position).
    /// One copy per buffer and point, one map; blocks (the window reads the probe without
    /// waiting, through `crate::readback`).
    pub fn probe(
        &self,
        ctx: &GpuContext,
        depth_probe: &DepthProbe,
        frame_size: (u32, u32),
        pixels: &[(u32, u32)],
    ) -> Result<Vec<Vec<ProbeValue>>, BufferError> {
        let plan = self.probe_plan(frame_size, pixels)?;
        if plan.bytes() == 0 {
            return Ok(vec![Vec::new(); pixels.len()]);
        }
        let bytes = copy_and_read(ctx, "buffers.probe", plan.bytes(), |enc, b| plan.record(ctx, enc, depth_probe, b))
            .map_err(|message| BufferError::Map { name: "probe".into(), message })?;
        Ok(plan.decode(&bytes))
    }

    /// What a probe of `pixels` copies and how its bytes decode (see [`Self::probe`]).
    pub fn probe_plan(&self, frame_size: (u32, u32), pixels: &[(u32, u32)]) -> Result<ProbePlan, BufferError> {
        let max = PROBE_MAX_POINTS;
        if pixels.len() > max {
            return Err(BufferError::Range {
                name: "probe".into(),
                what: "point",
                have: max as u32,
                want: pixels.len() as u32,
            });
        }
        self.refresh_all();
        let readable: Vec<(String, wgpu::Texture, u32, TexelDecoder)> = self
            .entries
            .values()
            .filter_map(|e| decoder(e.texture.format()).map(|(bpp, d)| (e.name.clone(), e.texture.clone(), bpp, d)))
            .collect();
        let (fw, fh) = (frame_size.0.max(1), frame_size.1.max(1));
        // texels[pi * n + bi]
        let mut texels = Vec::with_capacity(readable.len() * pixels.len());
        for &(px, py) in pixels {
            for (_, t, _, _) in &readable {
                let x = ((px.min(fw - 1) as u64 * t.width() as u64) / fw as u64) as u32;
                let y = ((py.min(fh - 1) as u64 * t.height() as u64) / fh as u64) as u32;
                texels.push((x, y));
            }
        }
        Ok(ProbePlan { readable, points: pixels.len(), texels })
    }
}

/// A probe's copies and decoding, recorded into any encoder ([`BufferRegistry::probe_plan`]).
pub struct ProbePlan {
    readable: Vec<(String, wgpu::Texture, u32, TexelDecoder)>,
    points: usize,
    texels: Vec<(u32, u32)>,
}

impl ProbePlan {
    const STRIDE: u64 = 256;

    /// Bytes of the staging buffer the copies land in.
    pub fn bytes(&self) -> u64 {
        (self.readable.len() * self.points) as u64 * Self::STRIDE
    }

    /// Records the copies into `enc`, landing in `staging` (COPY_DST, at least [`Self::bytes`]).
    pub fn record(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        depth_probe: &DepthProbe,
        staging: &wgpu::Buffer,
    ) {
        let n = self.readable.len();
        let count = (n * self.points) as u64;
        let has_depth = self.readable.iter().any(|(_, t, _, _)| t.format().is_depth_stencil_format());
        // Depth values land here first (one f32 per depth buffer and point).
        let depth_values = has_depth.then(|| {
            ctx.device.counted_buffer(&wgpu::BufferDescriptor {
                label: Some("buffers.probe_depth"),
                size: count * 4,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        });
        for (bi, (_, t, _, _)) in self.readable.iter().enumerate() {
            let slot = |pi: usize| (pi * n + bi) as u64;
            if let Some(depth_values) = depth_values.as_ref().filter(|_| t.format().is_depth_stencil_format()) {
                let mine: Vec<(u32, u32)> = (0..self.points).map(|pi| self.texels[slot(pi) as usize]).collect();
                let first = (bi * self.points) as u32;
                depth_probe.record(ctx, enc, t, &mine, depth_values, first);
                for pi in 0..self.points {
                    enc.copy_buffer_to_buffer(
                        depth_values,
                        (first as u64 + pi as u64) * 4,
                        staging,
                        slot(pi) * Self::STRIDE,
                        4,
                    );
                }
                continue;
            }
            for pi in 0..self.points {
                let (x, y) = self.texels[slot(pi) as usize];
                enc.copy_texture_to_buffer(
                    wgpu::TexelCopyTextureInfo {
                        texture: t,
                        mip_level: 0,
                        origin: wgpu::Origin3d { x, y, z: 0 },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::TexelCopyBufferInfo {
                        buffer: staging,
                        layout: wgpu::TexelCopyBufferLayout {
                            offset: slot(pi) * Self::STRIDE,
                            bytes_per_row: None,
                            rows_per_image: None,
                        },
                    },
                    wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
                );
            }
        }
    }

    /// The values per point, every buffer's in name order.
    pub fn decode(&self, bytes: &[u8]) -> Vec<Vec<ProbeValue>> {
        let n = self.readable.len();
        (0..self.points)
            .map(|pi| {
                self.readable
                    .iter()
                    .enumerate()
                    .map(|(bi, (name, _, bpp, decode))| {
                        let k = pi * n + bi;
                        let o = k * Self::STRIDE as usize;
                        let value = bytes.get(o..o + *bpp as usize).map_or([f32::NAN; 4], decode);
                        ProbeValue { name: name.clone(), texel: self.texels[k], value }
                    })
                    .collect()
            })
            .collect()
    }
}

impl BufferRegistry {
    /// The raw values of chosen texels: each (buffer, x, y) in that buffer's own texels
    /// (clamped to its size). One copy per texel, one map; blocks.
    pub fn read_texels(&self, ctx: &GpuContext, points: &[(&str, u32, u32)]) -> Result<Vec<[f32; 4]>, BufferError> {
        if points.is_empty() {
            return Ok(Vec::new());
        }
        let plan = self.texel_plan(points)?;
        let bytes = copy_and_read(ctx, "buffers.read_texels", plan.bytes(), |enc, b| plan.record(enc, b))
            .map_err(|message| BufferError::Map { name: "texels".into(), message })?;
        Ok(plan.decode(&bytes))
    }

    /// What [`Self::read_texels`] copies and how its bytes decode.
    pub fn texel_plan(&self, points: &[(&str, u32, u32)]) -> Result<TexelPlan, BufferError> {
        let mut texels = Vec::with_capacity(points.len());
        for &(name, x, y) in points {
            let t = &self.get(name)?.texture;
            let format = t.format();
            let (bpp, decode) = match decoder(format) {
                Some(d) if !format.is_depth_stencil_format() => d,
                _ => return Err(BufferError::Format { name: name.into(), format }),
            };
            texels.push((t.clone(), x.min(t.width() - 1), y.min(t.height() - 1), bpp as usize, decode));
        }
        Ok(TexelPlan { texels })
    }
}

/// Single texels' copies and decoding, recorded into any encoder ([`BufferRegistry::texel_plan`]).
pub struct TexelPlan {
    texels: Vec<(wgpu::Texture, u32, u32, usize, TexelDecoder)>,
}

impl TexelPlan {
    const STRIDE: u64 = 256;

    pub fn bytes(&self) -> u64 {
        self.texels.len().max(1) as u64 * Self::STRIDE
    }

    pub fn record(&self, enc: &mut wgpu::CommandEncoder, staging: &wgpu::Buffer) {
        for (i, (t, x, y, _, _)) in self.texels.iter().enumerate() {
            enc.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture: t,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: *x, y: *y, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: staging,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: i as u64 * Self::STRIDE,
                        bytes_per_row: None,
                        rows_per_image: None,
                    },
                },
                wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            );
        }
    }

    pub fn decode(&self, bytes: &[u8]) -> Vec<[f32; 4]> {
        let stride = Self::STRIDE as usize;
        self.texels
            .iter()
            .enumerate()
            .map(|(i, (_, _, _, bpp, decode))| bytes.get(i * stride..i * stride + bpp).map_or([f32::NAN; 4], decode))
            .collect()
    }
}

/// Decodes one texel's bytes to f32 RGBA.
type TexelDecoder = fn(&[u8]) -> [f32; 4];

/// Bytes per texel and a decoder to f32 RGBA for the formats the passes use.
fn decoder(format: wgpu::TextureFormat) -> Option<(u32, TexelDecoder)> {
    use wgpu::TextureFormat as F;
    fn f32_at(b: &[u8], i: usize) -> f32 {
        f32::from_le_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]])
    }
    fn f16_at(b: &[u8], i: usize) -> f32 {
        half_to_f32(u16::from_le_bytes([b[2 * i], b[2 * i + 1]]))
    }
    Some(match format {
        F::Rgba32Float => (16, |b| [f32_at(b, 0), f32_at(b, 1), f32_at(b, 2), f32_at(b, 3)]),
        F::Rg32Float => (8, |b| [f32_at(b, 0), f32_at(b, 1), 0.0, 1.0]),
        F::R32Float | F::Depth32Float => (4, |b| [f32_at(b, 0), 0.0, 0.0, 1.0]),
        F::R32Uint => (4, |b| [u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32, 0.0, 0.0, 1.0]),
        F::Rgba16Float => (8, |b| [f16_at(b, 0), f16_at(b, 1), f16_at(b, 2), f16_at(b, 3)]),
        F::Rg16Float => (4, |b| [f16_at(b, 0), f16_at(b, 1), 0.0, 1.0]),
        F::Rgba8Unorm | F::Rgba8UnormSrgb => {
            (4, |b| [b[0] as f32 / 255.0, b[1] as f32 / 255.0, b[2] as f32 / 255.0, b[3] as f32 / 255.0])
        }
        _ => return None,
    })
}

/// Texels of `format` (rows packed, `width` × `height`) decoded to f32 RGBA, for the formats
/// the read-backs decode (None for the others); a short `bytes` leaves the rest zero.
pub fn decode_texels(format: wgpu::TextureFormat, bytes: &[u8], width: u32, height: u32) -> Option<ImageF32> {
    let (bpp, decode) = decoder(format)?;
    let mut img = ImageF32::new(width, height);
    for (i, px) in img.data.iter_mut().enumerate() {
        if let Some(b) = bytes.get(i * bpp as usize..(i + 1) * bpp as usize) {
            *px = decode(b);
        }
    }
    Some(img)
}

/// IEEE 754 half → f32.
pub fn half_to_f32(h: u16) -> f32 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let man = (h & 0x3ff) as f32;
    match exp {
        0 => sign * man * 2f32.powi(-24),
        31 => {
            if man == 0.0 {
                sign * f32::INFINITY
            } else {
                f32::NAN
            }
        }
        _ => sign * (1.0 + man / 1024.0) * 2f32.powi(exp - 15),
    }
}

/// f32 → IEEE 754 binary16 bits, rounded to nearest even as a GPU stores a float into an
/// `Rgba16Float` texel (subnormals included; beyond the range: infinity).
pub fn f32_to_half(x: f32) -> u16 {
    let b = x.to_bits();
    let sign = ((b >> 16) & 0x8000) as u16;
    let exp = ((b >> 23) & 0xff) as i32;
    let man = b & 0x7f_ffff;
    if exp == 0xff {
        return sign | 0x7c00 | if man != 0 { 0x200 } else { 0 };
    }
    // The value as an integer multiple of 2^-24 (half's smallest subnormal) when small, or
    // with its exponent rebased to half's bias.
    let e = exp - 127 + 15;
    if e >= 31 {
        return sign | 0x7c00;
    }
    let (mantissa, shift) = if e <= 0 {
        // Subnormal half: the implicit bit joins the mantissa, shifted right by 1 − e more.
        if e < -10 {
            return sign;
        }
        (man | 0x80_0000, (14 - e) as u32)
    } else {
        (man, 13)
    };
    let mut h = if e <= 0 { mantissa >> shift } else { ((e as u32) << 10) | (mantissa >> shift) };
    let rest = mantissa & ((1 << shift) - 1);
    let half_way = 1 << (shift - 1);
    if rest > half_way || (rest == half_way && h & 1 == 1) {
        // A carry out of the mantissa raises the exponent, as it should.
        h += 1;
    }
    sign | h as u16
}

/// The value an `Rgba16Float` texel stores for `x`.
pub fn round_to_half(x: f32) -> f32 {
    half_to_f32(f32_to_half(x))
}

/// The spacing of binary16 values at `x` (one unit in the last place): what a GPU's store of
/// `x` into an `Rgba16Float` texel may change it by, since Vulkan lets the conversion round
/// to nearest or toward zero (lavapipe truncates).
pub fn half_step(x: f32) -> f32 {
    let a = x.abs();
    if a < 2f32.powi(-14) {
        return 2f32.powi(-24);
    }
    2f32.powi(a.log2().floor() as i32 - 10)
}

/// Copies one layer / mip of a texture to the CPU and decodes it; blocks.
pub fn read_texture(
    ctx: &GpuContext,
    name: &str,
    texture: &wgpu::Texture,
    layer: u32,
    mip: u32,
) -> Result<ImageF32, BufferError> {
    let plan = TexturePlan::new(name, texture, layer, mip)?;
    let bytes = copy_and_read(ctx, "buffers.readback", plan.bytes(), |enc, b| plan.record(enc, b))
        .map_err(|message| BufferError::Map { name: name.into(), message })?;
    Ok(plan.decode(&bytes))
}

/// The copy of one layer / mip of a texture and its decoding, recorded into any encoder.
pub struct TexturePlan {
    texture: wgpu::Texture,
    layer: u32,
    mip: u32,
    width: u32,
    height: u32,
    bpp: u32,
    padded: u32,
    decode: TexelDecoder,
}

impl TexturePlan {
    pub fn new(name: &str, texture: &wgpu::Texture, layer: u32, mip: u32) -> Result<Self, BufferError> {
        let format = texture.format();
        let (bpp, decode) = decoder(format).ok_or(BufferError::Format { name: name.into(), format })?;
        if layer >= texture.depth_or_array_layers() {
            return Err(BufferError::Range {
                name: name.into(),
                what: "layer",
                have: texture.depth_or_array_layers(),
                want: layer,
            });
        }
        if mip >= texture.mip_level_count() {
            return Err(BufferError::Range {
                name: name.into(),
                what: "level",
                have: texture.mip_level_count(),
                want: mip,
            });
        }
        let width = (texture.width() >> mip).max(1);
        let height = (texture.height() >> mip).max(1);
        let row = width * bpp;
        let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        Ok(Self { texture: texture.clone(), layer, mip, width, height, bpp, padded, decode })
    }

    /// Bytes of the staging buffer the copy lands in.
    pub fn bytes(&self) -> u64 {
        (self.padded * self.height) as u64
    }

    /// Records the copy into `enc`, landing in `staging` (COPY_DST, at least [`Self::bytes`]).
    pub fn record(&self, enc: &mut wgpu::CommandEncoder, staging: &wgpu::Buffer) {
        let format = self.texture.format();
        let aspect =
            if format.is_depth_stencil_format() { wgpu::TextureAspect::DepthOnly } else { wgpu::TextureAspect::All };
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &self.texture,
                mip_level: self.mip,
                origin: wgpu::Origin3d { x: 0, y: 0, z: self.layer },
                aspect,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
    }

    pub fn decode(&self, bytes: &[u8]) -> ImageF32 {
        let (width, height, bpp) = (self.width, self.height, self.bpp);
        let mut img = ImageF32::new(width, height);
        for y in 0..height {
            for x in 0..width {
                let o = (y * self.padded + x * bpp) as usize;
                if let Some(b) = bytes.get(o..o + bpp as usize) {
                    img.data[(y * width + x) as usize] = (self.decode)(b);
                }
            }
        }
        img
    }
}

/// The blocking read-backs' common path: a staging buffer of `bytes`, the copies `record`
/// makes into it in their own submission, and the wait for them (the window reads without
/// waiting instead, through `crate::readback`).
fn copy_and_read(
    ctx: &GpuContext,
    label: &str,
    bytes: u64,
    record: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::Buffer),
) -> Result<Vec<u8>, String> {
    let staging = ctx.device.counted_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    record(&mut enc, &staging);
    ctx.submit([enc.finish()]);
    map_read(ctx, &staging)
}

/// Maps a MAP_READ buffer, waits, and copies its contents out.
pub fn map_read(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, String> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.wait()?;
    rx.recv().map_err(|e| e.to_string())?.map_err(|e| e.to_string())?;
    let data = buffer.slice(..).get_mapped_range().map_err(|e| e.to_string())?.to_vec();
    buffer.unmap();
    Ok(data)
}

/// Copies the first `bytes` of a GPU buffer (which needs COPY_SRC) to the CPU; blocks.
pub fn read_storage(ctx: &GpuContext, src: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, String> {
    let bytes = bytes.min(src.size());
    let mut data = copy_and_read(ctx, "readback.storage", bytes.max(4), |enc, b| {
        enc.copy_buffer_to_buffer(src, 0, b, 0, bytes & !3)
    })?;
    data.truncate(bytes as usize);
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::{f32_to_half, half_step, half_to_f32, round_to_half};

    #[test]
    fn half_conversion() {
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0xc000), -2.0);
        assert_eq!(half_to_f32(0x0000), 0.0);
        assert!((half_to_f32(0x3555) - 0.333_251_95).abs() < 1e-6);
        assert!(half_to_f32(0x7c00).is_infinite());
        assert!(half_to_f32(0x7e00).is_nan());
    }

    #[test]
    fn rounding_to_half_is_to_nearest_even() {
        // Every finite half value (normal and subnormal, both signs) is its own rounding.
        for h in 0..=u16::MAX {
            let v = half_to_f32(h);
            if v.is_finite() {
                assert_eq!(f32_to_half(v), if v == 0.0 && h == 0x8000 { 0x8000 } else { h }, "{h:#06x} ({v})");
            }
        }
        // Between two neighbours: nearest; half way: the even one.
        let (a, b) = (half_to_f32(0x3c00), half_to_f32(0x3c01));
        assert_eq!(round_to_half(a + 0.4 * (b - a)), a);
        assert_eq!(round_to_half(a + 0.6 * (b - a)), b);
        assert_eq!(f32_to_half(a + 0.5 * (b - a)), 0x3c00);
        let c = half_to_f32(0x3c02);
        assert_eq!(f32_to_half(b + 0.5 * (c - b)), 0x3c02);
        // Subnormals, the largest finite value and overflow.
        assert_eq!(round_to_half(1e-7), half_to_f32(2));
        assert_eq!(round_to_half(65519.0), 65504.0);
        assert!(round_to_half(65520.0).is_infinite());
        assert_eq!(round_to_half(1e-9), 0.0);
        assert_eq!(round_to_half(1.2), half_to_f32(0x3ccd));
        // The spacing is the distance to the next half value up.
        for h in [0x0001u16, 0x03ff, 0x0400, 0x3c00, 0x3ccd, 0x7bfe] {
            let v = half_to_f32(h);
            assert_eq!(half_step(v), half_to_f32(h + 1) - v, "{h:#06x}");
        }
    }
}
