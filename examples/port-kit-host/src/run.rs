//! Running a kit's frames: each frame's golden inputs uploaded, its passes' steps encoded
//! in order (draws of one render pass together), each pass submitted alone and its outputs
//! read back to `OUT/frame-K/NN-pass/resource.bin` (docs/port-kit.md, "Verifying a port").

use std::path::Path;

use crate::host::{Host, Made};
use crate::kit::{Manifest, Pass, Step, Target};
use crate::names;

/// What a run did.
#[derive(Debug, Default)]
pub struct Summary {
    pub preset: String,
    pub frames: usize,
    pub passes: usize,
    pub steps: usize,
    pub outputs: usize,
    pub adapter: String,
}

/// Runs the kit at `kit` and writes every pass's outputs under `out`.
pub fn run(kit: &Path, out: &Path) -> Result<Summary, String> {
    let path = kit.join("manifest.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    if value["schema"] != "gi-lab-port-kit" || value["schema_version"] != 2 {
        return Err(format!(
            "{}: schema {} version {}, this host reads gi-lab-port-kit version 2 (export the kit again)",
            path.display(),
            value["schema"],
            value["schema_version"]
        ));
    }
    let m: Manifest = serde_json::from_value(value).map_err(|e| format!("{}: {e}", path.display()))?;
    if m.frame_passes.len() != m.frames as usize || m.golden.len() != m.frames as usize {
        return Err(format!(
            "{}: {} frames, but {} frame lists and {} golden frames",
            path.display(),
            m.frames,
            m.frame_passes.len(),
            m.golden.len()
        ));
    }
    let mut host = Host::new(kit, &m)?;
    let mut summary = Summary { preset: m.preset.clone(), adapter: host.adapter.get_info().name, ..Summary::default() };
    for (k, passes) in m.frame_passes.iter().enumerate() {
        let golden = m.golden.get(k).ok_or_else(|| format!("frame {k}: the kit has no goldens for it"))?;
        for input in &golden.inputs {
            let file = kit.join(&input.file);
            let bytes = std::fs::read(&file).map_err(|e| format!("frame {k}, input {}: {e}", input.resource))?;
            if bytes.len() as u64 != input.bytes {
                return Err(format!(
                    "frame {k}, input {}: {} bytes, the manifest says {}",
                    input.resource,
                    bytes.len(),
                    input.bytes
                ));
            }
            upload(&host, &input.resource, &bytes).map_err(|e| format!("frame {k}, input {}: {e}", input.resource))?;
        }
        for pass in passes {
            let at = |e: String| format!("frame {k}, pass {:02} {}: {e}", pass.index, pass.name);
            encode(&mut host, &m, pass).map_err(at)?;
            host.take_errors().map_err(|e| at(format!("wgpu: {e}")))?;
            summary.passes += 1;
            summary.steps += pass.steps.len();
            let Some(g) = golden.passes.iter().find(|g| g.index == pass.index) else { continue };
            for o in &g.outputs {
                let bytes = read_back(&host, &o.resource).map_err(|e| at(format!("{}: {e}", o.resource)))?;
                let file = out.join(&o.path);
                if let Some(dir) = file.parent() {
                    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
                }
                std::fs::write(&file, &bytes).map_err(|e| format!("{}: {e}", file.display()))?;
                summary.outputs += 1;
            }
        }
        summary.frames += 1;
    }
    Ok(summary)
}

/// The levels of a texture: (width, height, layers or depth) of each.
fn levels(t: &wgpu::Texture) -> Vec<(u32, u32, u32)> {
    (0..t.mip_level_count())
        .map(|l| {
            let (w, h) = ((t.width() >> l).max(1), (t.height() >> l).max(1));
            let d = if t.dimension() == wgpu::TextureDimension::D3 {
                (t.depth_or_array_layers() >> l).max(1)
            } else {
                t.depth_or_array_layers()
            };
            (w, h, d)
        })
        .collect()
}

/// Uploads a golden input: a buffer's bytes, or a texture's levels (layers in order, rows
/// packed).
fn upload(host: &Host, resource: &str, bytes: &[u8]) -> Result<(), String> {
    if let Some(b) = host.buffers.get(resource) {
        if bytes.len() as u64 > b.size() {
            return Err(format!("{} bytes for a buffer of {}", bytes.len(), b.size()));
        }
        host.queue.write_buffer(b, 0, bytes);
        return Ok(());
    }
    let t = host.textures.get(resource).ok_or("not a texture or buffer of the kit")?;
    if t.format.is_depth_stencil_format() {
        return upload_depth(host, t, bytes);
    }
    let texel = names::texel_bytes(t.format)? as usize;
    let mut at = 0usize;
    for (l, (w, h, d)) in levels(&t.texture).into_iter().enumerate() {
        let n = w as usize * h as usize * d as usize * texel;
        let data = bytes.get(at..at + n).ok_or_else(|| format!("{} bytes are too few for level {l}", bytes.len()))?;
        host.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &t.texture,
                mip_level: l as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            data,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(w * texel as u32), rows_per_image: Some(h) },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: d },
        );
        at += n;
    }
    Ok(())
}

/// A depth texture cannot be a copy's destination: one whose texels all hold the same depth
/// (the kits' 1×1 stand-ins) is cleared to it, level by level and layer by layer.
fn upload_depth(host: &Host, t: &crate::host::Texture, bytes: &[u8]) -> Result<(), String> {
    if t.format != wgpu::TextureFormat::Depth32Float || bytes.len() < 4 || !bytes.len().is_multiple_of(4) {
        return Err(format!("a {:?} input cannot be uploaded", t.format));
    }
    let first = &bytes[..4];
    if bytes.chunks_exact(4).any(|c| c != first) {
        return Err("a depth input whose texels differ cannot be uploaded (a copy cannot write depth): draw it".into());
    }
    let depth = f32::from_le_bytes([first[0], first[1], first[2], first[3]]);
    let mut enc = host.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("depth input") });
    let layers =
        if t.texture.dimension() == wgpu::TextureDimension::D3 { 1 } else { t.texture.depth_or_array_layers() };
    for mip in 0..t.texture.mip_level_count() {
        for layer in 0..layers {
            let view = t.texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some("depth input"),
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_mip_level: mip,
                mip_level_count: Some(1),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            });
            enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("depth input"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(depth), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
    }
    host.queue.submit([enc.finish()]);
    Ok(())
}

/// Encodes and submits one pass, and waits for it.
fn encode(host: &mut Host, m: &Manifest, pass: &Pass) -> Result<(), String> {
    let mut enc = host.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(&pass.name) });
    let mut i = 0;
    while i < pass.steps.len() {
        let step = &pass.steps[i];
        if step.kind.starts_with("draw") {
            // The draws of one render pass.
            let mut j = i + 1;
            while j < pass.steps.len()
                && pass.steps[j].kind.starts_with("draw")
                && pass.steps[j].render_pass == step.render_pass
            {
                j += 1;
            }
            raster(host, m, &mut enc, &pass.steps[i..j]).map_err(|e| format!("step {i} ({}): {e}", step.kind))?;
            i = j;
            continue;
        }
        other(host, m, &mut enc, step).map_err(|e| format!("step {i} ({}): {e}", step.kind))?;
        i += 1;
    }
    host.queue.submit([enc.finish()]);
    host.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| e.to_string())?;
    Ok(())
}

/// A dispatch, copy or clear.
fn other(host: &mut Host, m: &Manifest, enc: &mut wgpu::CommandEncoder, step: &Step) -> Result<(), String> {
    let made = match step.kind.as_str() {
        "dispatch" | "dispatch_indirect" => Some(host.pipeline(m, step)?),
        _ => None,
    };
    let buffer = |name: &str| host.buffers.get(name).cloned().ok_or_else(|| format!("no buffer `{name}`"));
    match step.kind.as_str() {
        "dispatch" | "dispatch_indirect" => {
            let (made, groups) = made.ok_or("no pipeline")?;
            let Made::Compute(pipe) = made else { return Err("a dispatch with a render pipeline".into()) };
            let indirect = step.indirect.as_ref().map(|(b, o)| buffer(b).map(|b| (b, *o))).transpose()?;
            let mut cp = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: step.pipeline.as_deref(),
                timestamp_writes: None,
            });
            cp.set_pipeline(&pipe);
            for (g, group) in groups.iter().enumerate() {
                cp.set_bind_group(g as u32, group, &[]);
            }
            match (step.workgroups, indirect) {
                (Some([x, y, z]), _) => cp.dispatch_workgroups(x, y, z),
                (None, Some((b, o))) => cp.dispatch_workgroups_indirect(&b, o),
                _ => return Err("a dispatch without workgroups or indirect arguments".into()),
            }
        }
        "copy" => {
            let c = step.copy.as_ref().ok_or("a copy step without `copy`")?;
            if let Some([w, h, d]) = c.texels {
                let tex = |n: &str| host.textures.get(n).map(|t| t.texture.clone()).ok_or(format!("no texture `{n}`"));
                let (src, dst) = (tex(&c.src)?, tex(&c.dst)?);
                let origin = |o: [u32; 3]| wgpu::Origin3d { x: o[0], y: o[1], z: o[2] };
                enc.copy_texture_to_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &src,
                        mip_level: c.src_mip,
                        origin: origin(c.src_origin),
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::TexelCopyTextureInfo {
                        texture: &dst,
                        mip_level: c.dst_mip,
                        origin: origin(c.dst_origin),
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::Extent3d { width: w, height: h, depth_or_array_layers: d },
                );
            } else {
                let bytes = c.bytes.ok_or("a copy without texels or bytes")?;
                enc.copy_buffer_to_buffer(&buffer(&c.src)?, c.src_offset, &buffer(&c.dst)?, c.dst_offset, bytes);
            }
        }
        "upload" => {
            // Queue writes land before the pass's commands, as they did in GI Lab.
            let u = step.upload.as_ref().ok_or("an upload step without `upload`")?;
            let file = host.kit.join(&u.file);
            let data = std::fs::read(&file).map_err(|e| format!("{}: {e}", file.display()))?;
            host.queue.write_buffer(&buffer(&u.buffer)?, u.offset, &data);
        }
        "clear" => {
            let (b, offset, size) = step.clear.as_ref().ok_or("a clear step without `clear`")?;
            enc.clear_buffer(&buffer(b)?, *offset, Some(*size));
        }
        other => return Err(format!("unknown step kind `{other}`")),
    }
    Ok(())
}

/// The draws of one render pass: its targets loaded or cleared as the first draw says.
fn raster(host: &mut Host, m: &Manifest, enc: &mut wgpu::CommandEncoder, draws: &[Step]) -> Result<(), String> {
    let first = &draws[0];
    let mut made = Vec::new();
    for d in draws {
        made.push(host.pipeline(m, d)?);
    }
    let view = |t: &Target| host.view(&t.resource, t.view.as_ref());
    let colors: Vec<wgpu::TextureView> = first.targets.iter().map(view).collect::<Result<_, _>>()?;
    let depth = first.depth_target.as_ref().map(view).transpose()?;
    let color_attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = first
        .targets
        .iter()
        .zip(&colors)
        .map(|(t, v)| {
            let [r, g, b, a] = t.clear;
            let load = if t.load { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }) };
            Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            })
        })
        .collect();
    let depth_stencil_attachment = first.depth_target.as_ref().zip(depth.as_ref()).map(|(t, v)| {
        let load = if t.load { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(t.clear[0] as f32) };
        wgpu::RenderPassDepthStencilAttachment {
            view: v,
            depth_ops: Some(wgpu::Operations { load, store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }
    });
    let buffer = |name: &str| host.buffers.get(name).cloned().ok_or_else(|| format!("no buffer `{name}`"));
    let mut bound = Vec::new();
    for d in draws {
        let vertex: Vec<(u32, wgpu::Buffer)> =
            d.vertex_buffers.iter().map(|(s, b)| buffer(b).map(|b| (*s, b))).collect::<Result<_, _>>()?;
        let index =
            d.index_buffer.as_ref().map(|(b, f)| Ok::<_, String>((buffer(b)?, names::index_format(f)?))).transpose()?;
        let indirect = d.indirect.as_ref().map(|(b, o)| buffer(b).map(|b| (b, *o))).transpose()?;
        bound.push((vertex, index, indirect));
    }
    let mut rp = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: first.pipeline.as_deref(),
        color_attachments: &color_attachments,
        depth_stencil_attachment,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    for (d, ((made, groups), (vertex, index, indirect))) in draws.iter().zip(made.iter().zip(&bound)) {
        let Made::Render(pipe) = made else { return Err("a draw with a compute pipeline".into()) };
        rp.set_pipeline(pipe);
        for (g, group) in groups.iter().enumerate() {
            rp.set_bind_group(g as u32, group, &[]);
        }
        for (slot, b) in vertex {
            rp.set_vertex_buffer(*slot, b.slice(..));
        }
        if let Some((b, f)) = index {
            rp.set_index_buffer(b.slice(..), *f);
        }
        match (d.kind.as_str(), &d.draw, indirect) {
            ("draw", Some(draw), _) => {
                let v = draw.vertices.ok_or("a draw without vertices")?;
                rp.draw(v[0]..v[1], draw.instances[0]..draw.instances[1]);
            }
            ("draw_indexed", Some(draw), _) => {
                let i = draw.indices.ok_or("an indexed draw without indices")?;
                rp.draw_indexed(i[0]..i[1], draw.base_vertex, draw.instances[0]..draw.instances[1]);
            }
            ("draw_indirect", _, Some((b, o))) => rp.draw_indirect(b, *o),
            ("draw_indexed_indirect", _, Some((b, o))) => rp.draw_indexed_indirect(b, *o),
            (kind, ..) => return Err(format!("a `{kind}` step without its arguments")),
        }
    }
    Ok(())
}

/// A read-back: the staging buffer, the level's size (a buffer: its bytes), the padded and
/// the packed row bytes (a buffer: 0).
type Plan = (wgpu::Buffer, (u32, u32, u32), u32, u32);

/// A texture's levels (layers in order, rows packed) or a buffer's bytes, as they are now.
fn read_back(host: &Host, resource: &str) -> Result<Vec<u8>, String> {
    let mut enc = host.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("read back") });
    let mut plans: Vec<Plan> = Vec::new();
    if let Some(b) = host.buffers.get(resource) {
        let size = b.size().div_ceil(4) * 4;
        let staging = staging(host, size);
        enc.copy_buffer_to_buffer(b, 0, &staging, 0, b.size() - b.size() % 4);
        plans.push((staging, (b.size() as u32, 1, 1), 0, 0));
    } else {
        let t = host.textures.get(resource).ok_or("not a texture or buffer of the kit")?;
        let texel = names::texel_bytes(t.format)?;
        for (l, (w, h, d)) in levels(&t.texture).into_iter().enumerate() {
            let row = w * texel;
            let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
            let staging = staging(host, padded as u64 * h as u64 * d as u64);
            let aspect = if t.format.is_depth_stencil_format() {
                wgpu::TextureAspect::DepthOnly
            } else {
                wgpu::TextureAspect::All
            };
            enc.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture: &t.texture,
                    mip_level: l as u32,
                    origin: wgpu::Origin3d::ZERO,
                    aspect,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &staging,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(padded),
                        rows_per_image: Some(h),
                    },
                },
                wgpu::Extent3d { width: w, height: h, depth_or_array_layers: d },
            );
            plans.push((staging, (w, h, d), padded, row));
        }
    }
    host.queue.submit([enc.finish()]);
    for (s, ..) in &plans {
        s.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    }
    host.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| e.to_string())?;
    host.take_errors().map_err(|e| format!("reading back: {e}"))?;
    let mut out = Vec::new();
    for (s, (w, h, d), padded, row) in plans {
        {
            let data = s.slice(..).get_mapped_range().map_err(|e| e.to_string())?;
            if padded == 0 {
                out.extend_from_slice(&data[..w as usize]);
            } else {
                for r in 0..(h * d) as usize {
                    let at = r * padded as usize;
                    out.extend_from_slice(&data[at..at + row as usize]);
                }
            }
        }
        s.unmap();
        if let Ok(mut pool) = host.staging.lock() {
            pool.insert(s.size(), s);
        }
    }
    Ok(out)
}

/// A staging buffer of `size` bytes, reused across read-backs (a kit reads the same large
/// buffers back every frame).
fn staging(host: &Host, size: u64) -> wgpu::Buffer {
    let size = size.max(4);
    if let Some(b) = host.staging.lock().ok().and_then(|mut pool| pool.remove(&size)) {
        return b;
    }
    host.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("port-kit-host.staging"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_kit_or_one_of_another_schema_is_a_clear_error() {
        let dir = std::env::temp_dir().join(format!("port-kit-host-bad-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let err = run(&dir, &dir.join("out")).expect_err("no kit");
        assert!(err.contains("manifest.json"), "{err}");
        std::fs::create_dir_all(&dir).expect("dir");
        std::fs::write(dir.join("manifest.json"), r#"{"schema": "gi-lab-port-kit", "schema_version": 1}"#).expect("w");
        let err = run(&dir, &dir.join("out")).expect_err("an old kit");
        assert!(err.contains("version 2") && err.contains("export the kit again"), "{err}");
        std::fs::write(dir.join("manifest.json"), r#"{"schema": "gi-lab-port-kit", "schema_version": 2}"#).expect("w");
        let err = run(&dir, &dir.join("out")).expect_err("a manifest without its fields");
        assert!(err.contains("missing field"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
