//! Memory traffic per pass, from what each pass binds (issue #38 point 4).
//!
//! A pass's traffic is the sum, over the distinct resources it binds, of their bytes: every
//! texture view of its bind groups (the view's levels and layers × the format's texel size),
//! every buffer binding (its size), its colour and depth attachments (twice when loaded:
//! read and written), and the texels or bytes of its copies (read and written). The sizes
//! come from the objects themselves, recorded when their views and bind groups are made
//! (`CountedTexture::counted_view`, `CountedDevice::counted_bind_group`), so a change of
//! format or size shows up without anyone counting by hand. It is the footprint a pass
//! touches: a shader that reads one level of a bound mip chain is charged the chain, and a
//! texture read by two passes is charged to both, as the hardware would fetch it twice.
//!
//! Passes are the timing scopes (`GpuTimer::scope` opens and closes them); work outside a
//! scope is charged to "(other)". Bind groups that no pass has used for
//! [`FORGET_AFTER_FRAMES`] frames are forgotten once more than [`KEEP`] are known (the
//! table holds their sizes, not the groups, so nothing stays alive for it).

use std::cell::RefCell;
use std::collections::{HashMap, HashSet};

/// Bind groups and views whose sizes are kept without pruning.
const KEEP: usize = 4096;
/// Frames after which an unused bind group's size may be forgotten.
pub const FORGET_AFTER_FRAMES: u64 = 64;

use super::key;

#[derive(Default)]
struct Ledger {
    frame: u64,
    /// View key → bytes of its levels and layers.
    views: HashMap<u64, (u64, u64)>,
    /// Bind group key → (resource key, bytes) of each entry, and the frame it was last used.
    groups: HashMap<u64, (Vec<(u64, u64)>, u64)>,
    /// The open pass: its name, the resources charged to it and its bytes so far.
    scope: Option<String>,
    seen: HashSet<u64>,
    bytes: u64,
    /// This frame's passes in order, with their bytes.
    passes: Vec<(String, u64)>,
}

thread_local! {
    static LEDGER: RefCell<Ledger> = RefCell::new(Ledger::default());
}

/// Bytes of one texel of `format` (the depth aspect for depth formats).
fn texel_bytes(format: wgpu::TextureFormat) -> u64 {
    format.block_copy_size(None).or_else(|| format.block_copy_size(Some(wgpu::TextureAspect::DepthOnly))).unwrap_or(4)
        as u64
}

/// Bytes of levels `mips` and `layers` layers of `t`.
fn texture_bytes(t: &wgpu::Texture, mips: std::ops::Range<u32>, layers: u32) -> u64 {
    let b = texel_bytes(t.format());
    let depth = if t.dimension() == wgpu::TextureDimension::D3 { t.depth_or_array_layers() } else { 1 };
    mips.map(|m| {
        let w = (t.width() >> m).max(1) as u64;
        let h = (t.height() >> m).max(1) as u64;
        let d = (depth >> m).max(1) as u64;
        w * h * d * layers as u64 * b
    })
    .sum()
}

fn view_bytes(l: &Ledger, view: &wgpu::TextureView) -> (u64, u64) {
    let k = key(view);
    match l.views.get(&k) {
        Some(&(_, bytes)) => (k, bytes),
        None => {
            let t = view.texture();
            let layers = if t.dimension() == wgpu::TextureDimension::D3 { 1 } else { t.depth_or_array_layers() };
            (k, texture_bytes(t, 0..t.mip_level_count(), layers))
        }
    }
}

/// Remembers the bytes a new view covers.
pub(crate) fn remember_view(view: &wgpu::TextureView, t: &wgpu::Texture, desc: &wgpu::TextureViewDescriptor) {
    let mips = t.mip_level_count();
    let base = desc.base_mip_level.min(mips.saturating_sub(1));
    let count = desc.mip_level_count.unwrap_or(mips - base).min(mips - base);
    let all_layers = if t.dimension() == wgpu::TextureDimension::D3 { 1 } else { t.depth_or_array_layers() };
    let layers = desc.array_layer_count.unwrap_or(all_layers.saturating_sub(desc.base_array_layer)).max(1);
    let bytes = texture_bytes(t, base..base + count.max(1), layers);
    LEDGER.with(|l| {
        let mut l = l.borrow_mut();
        let frame = l.frame;
        l.views.insert(key(view), (frame, bytes));
    });
}

/// Remembers the resources of a new bind group and their bytes.
pub(crate) fn remember_group(group: &wgpu::BindGroup, desc: &wgpu::BindGroupDescriptor) {
    LEDGER.with(|l| {
        let mut l = l.borrow_mut();
        let mut parts = Vec::new();
        for e in desc.entries {
            match &e.resource {
                wgpu::BindingResource::Buffer(b) => parts.push(buffer_part(b)),
                wgpu::BindingResource::BufferArray(bs) => parts.extend(bs.iter().map(buffer_part)),
                wgpu::BindingResource::TextureView(v) => parts.push(view_bytes(&l, v)),
                wgpu::BindingResource::TextureViewArray(vs) => parts.extend(vs.iter().map(|v| view_bytes(&l, v))),
                _ => {}
            }
        }
        let frame = l.frame;
        l.groups.insert(key(group), (parts, frame));
    });
}

fn buffer_part(b: &wgpu::BufferBinding) -> (u64, u64) {
    let size = b.size.map_or(b.buffer.size().saturating_sub(b.offset), |s| s.get());
    (key(&(key(b.buffer), b.offset)), size)
}

fn charge(l: &mut Ledger, resource: u64, bytes: u64) {
    if l.seen.insert(resource) {
        l.bytes += bytes;
    }
}

/// Opens the pass `name` (closing the open one).
pub(crate) fn begin_scope(name: &str) {
    end_scope();
    LEDGER.with(|l| l.borrow_mut().scope = Some(name.to_string()));
    super::capture::begin_scope(name);
}

/// Closes the open pass, adding its bytes to the frame's.
pub(crate) fn end_scope() {
    close_scope();
    super::capture::end_scope();
}

fn close_scope() {
    let bytes = LEDGER.with(|l| {
        let mut l = l.borrow_mut();
        let name = l.scope.take().unwrap_or_else(|| "(other)".into());
        let bytes = std::mem::take(&mut l.bytes);
        l.seen.clear();
        if bytes > 0 {
            match l.passes.iter_mut().find(|(n, _)| *n == name) {
                Some(p) => p.1 += bytes,
                None => l.passes.push((name, bytes)),
            }
        }
        bytes
    });
    super::bump(|c| c.traffic_bytes += bytes);
}

/// Ends the frame: returns its passes' bytes (in order) and forgets long-unused sizes.
pub(crate) fn end_frame() -> Vec<(String, u64)> {
    close_scope();
    LEDGER.with(|l| {
        let mut l = l.borrow_mut();
        l.frame += 1;
        let frame = l.frame;
        if l.groups.len() > KEEP {
            l.groups.retain(|_, (_, used)| frame.saturating_sub(*used) <= FORGET_AFTER_FRAMES);
        }
        if l.views.len() > KEEP {
            l.views.retain(|_, (made, _)| frame.saturating_sub(*made) <= FORGET_AFTER_FRAMES);
        }
        std::mem::take(&mut l.passes)
    })
}

fn charge_group(group: &wgpu::BindGroup) {
    let k = key(group);
    LEDGER.with(|l| {
        let mut l = l.borrow_mut();
        let Ledger { frame, groups, seen, bytes, .. } = &mut *l;
        if let Some((parts, used)) = groups.get_mut(&k) {
            *used = *frame;
            for &(resource, b) in parts.iter() {
                if seen.insert(resource) {
                    *bytes += b;
                }
            }
        }
    });
}

fn charge_view(view: &wgpu::TextureView, times: u64) {
    LEDGER.with(|l| {
        let mut l = l.borrow_mut();
        let (k, b) = view_bytes(&l, view);
        let frame = l.frame;
        if let Some((made, _)) = l.views.get_mut(&k) {
            // A view in use stays known.
            *made = frame;
        }
        charge(&mut l, k, b * times);
    });
}

fn charge_bytes(bytes: u64) {
    LEDGER.with(|l| l.borrow_mut().bytes += bytes);
}

/// Binding that charges the group's resources to the open pass, and pipelines, both
/// recorded by a capture ([`super::capture`]). Import `crate::counters::prelude::*`.
pub trait CountedPass {
    type Pipeline;
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup, offsets: &[wgpu::DynamicOffset]);
    fn set_pipe(&mut self, pipeline: &Self::Pipeline);
}

fn record_group(index: u32, group: &wgpu::BindGroup, offsets: &[wgpu::DynamicOffset]) {
    use super::capture::{Command, object_key, record};
    record(|_| Command::Group { index, group: object_key(group), offsets: offsets.to_vec() });
}

impl CountedPass for wgpu::ComputePass<'_> {
    type Pipeline = wgpu::ComputePipeline;
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup, offsets: &[wgpu::DynamicOffset]) {
        charge_group(group);
        record_group(index, group, offsets);
        self.set_bind_group(index, group, offsets);
    }
    fn set_pipe(&mut self, pipeline: &wgpu::ComputePipeline) {
        use super::capture::{Command, compute_key, record};
        record(|_| Command::Pipeline { pipeline: compute_key(pipeline) });
        self.set_pipeline(pipeline);
    }
}

impl CountedPass for wgpu::RenderPass<'_> {
    type Pipeline = wgpu::RenderPipeline;
    fn set_group(&mut self, index: u32, group: &wgpu::BindGroup, offsets: &[wgpu::DynamicOffset]) {
        charge_group(group);
        record_group(index, group, offsets);
        self.set_bind_group(index, group, offsets);
    }
    fn set_pipe(&mut self, pipeline: &wgpu::RenderPipeline) {
        use super::capture::{Command, record, render_key};
        record(|_| Command::Pipeline { pipeline: render_key(pipeline) });
        self.set_pipeline(pipeline);
    }
}

/// Dispatches a capture records.
pub trait CountedCompute {
    fn dispatch(&mut self, x: u32, y: u32, z: u32);
    fn dispatch_indirect(&mut self, buffer: &wgpu::Buffer, offset: u64);
}

impl CountedCompute for wgpu::ComputePass<'_> {
    fn dispatch(&mut self, x: u32, y: u32, z: u32) {
        use super::capture::{Command, record};
        record(|_| Command::Dispatch { workgroups: [x, y, z] });
        self.dispatch_workgroups(x, y, z);
    }
    fn dispatch_indirect(&mut self, buffer: &wgpu::Buffer, offset: u64) {
        use super::capture::{Command, buffer_key, record};
        record(|_| Command::DispatchIndirect { buffer: buffer_key(buffer), offset });
        self.dispatch_workgroups_indirect(buffer, offset);
    }
}

/// Draws and vertex input a capture records.
pub trait CountedRender {
    fn draw_counted(&mut self, vertices: std::ops::Range<u32>, instances: std::ops::Range<u32>);
    fn draw_indexed_counted(&mut self, indices: std::ops::Range<u32>, base: i32, instances: std::ops::Range<u32>);
    fn draw_indirect_counted(&mut self, buffer: &wgpu::Buffer, offset: u64);
    fn draw_indexed_indirect_counted(&mut self, buffer: &wgpu::Buffer, offset: u64);
    fn vertex_buffer(&mut self, slot: u32, buffer: &wgpu::Buffer);
    fn index_buffer(&mut self, buffer: &wgpu::Buffer, format: wgpu::IndexFormat);
}

impl CountedRender for wgpu::RenderPass<'_> {
    fn draw_counted(&mut self, vertices: std::ops::Range<u32>, instances: std::ops::Range<u32>) {
        use super::capture::{Command, record};
        record(|_| Command::Draw {
            vertices: [vertices.start, vertices.end],
            instances: [instances.start, instances.end],
        });
        self.draw(vertices, instances);
    }
    fn draw_indexed_counted(&mut self, indices: std::ops::Range<u32>, base: i32, instances: std::ops::Range<u32>) {
        use super::capture::{Command, record};
        record(|_| Command::DrawIndexed {
            indices: [indices.start, indices.end],
            base_vertex: base,
            instances: [instances.start, instances.end],
        });
        self.draw_indexed(indices, base, instances);
    }
    fn draw_indirect_counted(&mut self, buffer: &wgpu::Buffer, offset: u64) {
        use super::capture::{Command, buffer_key, record};
        record(|_| Command::DrawIndirect { buffer: buffer_key(buffer), offset, indexed: false });
        self.draw_indirect(buffer, offset);
    }
    fn draw_indexed_indirect_counted(&mut self, buffer: &wgpu::Buffer, offset: u64) {
        use super::capture::{Command, buffer_key, record};
        record(|_| Command::DrawIndirect { buffer: buffer_key(buffer), offset, indexed: true });
        self.draw_indexed_indirect(buffer, offset);
    }
    fn vertex_buffer(&mut self, slot: u32, buffer: &wgpu::Buffer) {
        use super::capture::{Command, buffer_key, record};
        record(|_| Command::VertexBuffer { slot, buffer: buffer_key(buffer) });
        self.set_vertex_buffer(slot, buffer.slice(..));
    }
    fn index_buffer(&mut self, buffer: &wgpu::Buffer, format: wgpu::IndexFormat) {
        use super::capture::{Command, buffer_key, record};
        record(|_| Command::IndexBuffer { buffer: buffer_key(buffer), format: format!("{format:?}") });
        self.set_index_buffer(buffer.slice(..), format);
    }
}

/// Uploads from the CPU, recorded by a capture (the port kit's `upload` steps: what a host
/// writes into a buffer, and when).
pub trait CountedQueue {
    fn upload(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]);
}

impl CountedQueue for wgpu::Queue {
    fn upload(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]) {
        {
            use super::capture::{Command, buffer_key, record};
            record(|_| Command::Upload { buffer: buffer_key(buffer), offset, data: data.to_vec() });
        }
        self.write_buffer(buffer, offset, data);
    }
}

/// Render passes and copies that charge their attachments and bytes to the open pass.
pub trait CountedEncoder {
    fn begin_counted_render_pass<'e>(&'e mut self, desc: &wgpu::RenderPassDescriptor<'_>) -> wgpu::RenderPass<'e>;
    fn counted_copy_texture(
        &mut self,
        src: wgpu::TexelCopyTextureInfo<'_>,
        dst: wgpu::TexelCopyTextureInfo<'_>,
        size: wgpu::Extent3d,
    );
    fn counted_copy_buffer(
        &mut self,
        src: &wgpu::Buffer,
        src_offset: u64,
        dst: &wgpu::Buffer,
        dst_offset: u64,
        size: u64,
    );
    fn counted_clear_buffer(&mut self, buffer: &wgpu::Buffer, offset: u64, size: Option<u64>);
}

impl CountedEncoder for wgpu::CommandEncoder {
    fn begin_counted_render_pass<'e>(&'e mut self, desc: &wgpu::RenderPassDescriptor<'_>) -> wgpu::RenderPass<'e> {
        for a in desc.color_attachments.iter().flatten() {
            charge_view(a.view, if matches!(a.ops.load, wgpu::LoadOp::Load) { 2 } else { 1 });
        }
        if let Some(d) = &desc.depth_stencil_attachment {
            let load = d.depth_ops.as_ref().is_some_and(|o| matches!(o.load, wgpu::LoadOp::Load));
            charge_view(d.view, if load { 2 } else { 1 });
        }
        super::capture::render_pass(desc);
        self.begin_render_pass(desc)
    }

    fn counted_copy_texture(
        &mut self,
        src: wgpu::TexelCopyTextureInfo<'_>,
        dst: wgpu::TexelCopyTextureInfo<'_>,
        size: wgpu::Extent3d,
    ) {
        let texels = size.width as u64 * size.height as u64 * size.depth_or_array_layers as u64;
        charge_bytes(texels * (texel_bytes(src.texture.format()) + texel_bytes(dst.texture.format())));
        {
            use super::capture::{Command, record, texture_key};
            let size = [size.width, size.height, size.depth_or_array_layers];
            let origin = |o: wgpu::Origin3d| [o.x, o.y, o.z];
            record(|_| Command::CopyTexture {
                src: texture_key(src.texture),
                src_mip: src.mip_level,
                src_origin: origin(src.origin),
                dst: texture_key(dst.texture),
                dst_mip: dst.mip_level,
                dst_origin: origin(dst.origin),
                size,
            });
        }
        self.copy_texture_to_texture(src, dst, size);
    }

    fn counted_copy_buffer(
        &mut self,
        src: &wgpu::Buffer,
        src_offset: u64,
        dst: &wgpu::Buffer,
        dst_offset: u64,
        size: u64,
    ) {
        charge_bytes(2 * size);
        {
            use super::capture::{Command, buffer_key, record};
            record(|_| Command::CopyBuffer {
                src: buffer_key(src),
                src_offset,
                dst: buffer_key(dst),
                dst_offset,
                size,
            });
        }
        self.copy_buffer_to_buffer(src, src_offset, dst, dst_offset, size);
    }

    /// A clear, recorded by a capture; not charged as traffic (the counter has never counted
    /// clears, and its figures stay comparable across runs).
    fn counted_clear_buffer(&mut self, buffer: &wgpu::Buffer, offset: u64, size: Option<u64>) {
        let bytes = size.unwrap_or(buffer.size().saturating_sub(offset));
        {
            use super::capture::{Command, buffer_key, record};
            record(|_| Command::ClearBuffer { buffer: buffer_key(buffer), offset, size: bytes });
        }
        self.clear_buffer(buffer, offset, size);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn texel_bytes_of_the_formats_the_passes_use() {
        assert_eq!(super::texel_bytes(wgpu::TextureFormat::Rgba32Float), 16);
        assert_eq!(super::texel_bytes(wgpu::TextureFormat::Rgba16Float), 8);
        assert_eq!(super::texel_bytes(wgpu::TextureFormat::Rg11b10Ufloat), 4);
        assert_eq!(super::texel_bytes(wgpu::TextureFormat::Depth32Float), 4);
    }
}
