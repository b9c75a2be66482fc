//! `gi-lab verify` (issue #54 point 2; docs/port-kit.md, "Verifying a port"): a port's
//! per-pass outputs, written under the paths the manifest's goldens give
//! (`frame-K/NN-pass/resource.bin`, the resource's raw bytes in its own format), compared with
//! the kit's goldens pass by pass: FLIP for colour (image-sized four-channel textures, level 0),
//! relative RMS error for other float data, the share of differing 32-bit words for integer
//! textures and buffers.

use std::path::Path;

use serde_json::Value;

/// One compared output.
#[derive(Clone, Debug)]
pub struct Row {
    pub frame: u64,
    pub index: u64,
    pub pass: String,
    pub resource: String,
    /// `flip`, `relative`, `words`, `records` (an appended list compared as a set), or
    /// `identical` (the same bytes: 0 by every metric).
    pub metric: &'static str,
    pub value: f64,
    pub ok: bool,
}

/// Every compared output in the kit's order, and the first that exceeds the tolerance.
#[derive(Clone, Debug)]
pub struct Report {
    pub rows: Vec<Row>,
    pub tolerance: f64,
}

impl Report {
    pub fn first_divergence(&self) -> Option<&Row> {
        self.rows.iter().find(|r| !r.ok)
    }

    /// A Markdown table: per frame and pass, its outputs' worst value and whether it passes.
    pub fn table(&self) -> String {
        let mut s = format!(
            "| frame | pass | outputs | worst | metric | within {} |\n|---:|---|---:|---:|---|---|\n",
            self.tolerance
        );
        let mut i = 0;
        while i < self.rows.len() {
            let (f, p) = (self.rows[i].frame, self.rows[i].index);
            let group: Vec<&Row> = self.rows[i..].iter().take_while(|r| r.frame == f && r.index == p).collect();
            let worst = group.iter().max_by(|a, b| a.value.total_cmp(&b.value)).copied();
            if let Some(w) = worst {
                let ok = group.iter().all(|r| r.ok);
                s += &format!(
                    "| {f} | {:02} {} | {} | {:.5} ({}) | {} | {} |\n",
                    p,
                    w.pass,
                    group.len(),
                    w.value,
                    w.resource,
                    w.metric,
                    if ok { "yes" } else { "**no**" }
                );
            }
            i += group.len().max(1);
        }
        s
    }
}

/// The formats the goldens decode to floats, by the name the manifest writes.
fn format_named(name: &str) -> Option<wgpu::TextureFormat> {
    use wgpu::TextureFormat as F;
    Some(match name {
        "Rgba32Float" => F::Rgba32Float,
        "Rg32Float" => F::Rg32Float,
        "R32Float" => F::R32Float,
        "Depth32Float" => F::Depth32Float,
        "Rgba16Float" => F::Rgba16Float,
        "Rg16Float" => F::Rg16Float,
        "Rgba8Unorm" => F::Rgba8Unorm,
        "Rgba8UnormSrgb" => F::Rgba8UnormSrgb,
        _ => return None,
    })
}

/// Compares the port's outputs in `outputs` with the goldens of the kit in `kit`.
pub fn verify(kit: &Path, outputs: &Path, tolerance: f64) -> Result<Report, String> {
    let manifest_path = kit.join("manifest.json");
    let text = std::fs::read_to_string(&manifest_path)
        .map_err(|e| format!("{}: {e} (is this a port kit?)", manifest_path.display()))?;
    let m: Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", manifest_path.display()))?;
    if m["schema"] != "gi-lab-port-kit" {
        return Err(format!("{}: not a GI Lab port kit manifest", manifest_path.display()));
    }
    let size = (m["size"][0].as_u64().unwrap_or(0), m["size"][1].as_u64().unwrap_or(0));
    let resources = m["resources"].as_array().cloned().unwrap_or_default();
    let frames = m["golden"].as_array().cloned().unwrap_or_default();
    if frames.is_empty() {
        return Err(format!("{}: the kit has no goldens", kit.display()));
    }
    let mut rows = Vec::new();
    for f in &frames {
        let frame = f["frame"].as_u64().unwrap_or(0);
        for p in f["passes"].as_array().into_iter().flatten() {
            let (index, pass) = (p["index"].as_u64().unwrap_or(0), p["name"].as_str().unwrap_or("").to_string());
            for o in p["outputs"].as_array().into_iter().flatten() {
                let resource = o["resource"].as_str().unwrap_or("").to_string();
                let at = |what: &str| format!("frame {frame}, pass {index:02} {pass}, {resource}: {what}");
                let golden_path = kit.join(o["file"].as_str().unwrap_or(""));
                let golden = std::fs::read(&golden_path)
                    .map_err(|e| at(&format!("the kit's golden {}: {e}", golden_path.display())))?;
                let port_path = outputs.join(o["path"].as_str().unwrap_or(""));
                let port = std::fs::read(&port_path)
                    .map_err(|e| at(&format!("the port's output {}: {e}", port_path.display())))?;
                let r = resources.iter().find(|r| r["name"] == resource.as_str());
                let info =
                    r.map(|r| (r["kind"].as_str().unwrap_or(""), r["format"].as_str().unwrap_or(""), &r["size"]));
                if port.len() != golden.len() {
                    let what = match info {
                        Some((kind, format, size)) => format!("{kind} {format} {size}"),
                        None => "the resource".into(),
                    };
                    return Err(at(&format!(
                        "{} bytes, the golden has {} ({what}): wrong size, format or frame",
                        port.len(),
                        golden.len()
                    )));
                }
                let (metric, value) = match info {
                    // The same bytes: every metric is 0 (and a kit's largest buffers, the ISM's
                    // splats, are compared at the speed of a memory compare).
                    _ if port == golden => ("identical", 0.0),
                    Some(("texture", format, dims)) => {
                        let dims: Vec<u64> = dims.as_array().into_iter().flatten().filter_map(Value::as_u64).collect();
                        compare_texture(format, &dims, size, &port, &golden).map_err(|e| at(&e))?
                    }
                    _ => match r.and_then(|r| r["unordered_records"].as_u64()).filter(|&s| s > 0) {
                        Some(stride) => ("records", differing_records(&port, &golden, stride as usize)),
                        None => ("words", differing_words(&port, &golden)),
                    },
                };
                rows.push(Row { frame, index, pass: pass.clone(), resource, metric, value, ok: value <= tolerance });
            }
        }
    }
    Ok(Report { rows, tolerance })
}

/// A texture's metric: FLIP on level 0 of an image-sized four-channel texture, else the
/// relative RMS error of every texel; integer formats by differing words.
fn compare_texture(
    format: &str,
    dims: &[u64],
    image: (u64, u64),
    port: &[u8],
    golden: &[u8],
) -> Result<(&'static str, f64), String> {
    let Some(f) = format_named(format) else {
        return Ok(("words", differing_words(port, golden)));
    };
    let bpp = f.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)).or(f.block_copy_size(None)).unwrap_or(4) as usize;
    let texels = (golden.len() / bpp.max(1)) as u32;
    let all = |b: &[u8]| crate::buffers::decode_texels(f, b, texels, 1);
    let (Some(p), Some(g)) = (all(port), all(golden)) else {
        return Ok(("words", differing_words(port, golden)));
    };
    if p.data.iter().flatten().any(|x| x.is_nan()) {
        return Err("NaN in the port's output".into());
    }
    let four = f.components() == 4;
    let (w, h) = (dims.first().copied().unwrap_or(0), dims.get(1).copied().unwrap_or(0));
    if four && (w, h) == image && w > 0 && h > 0 {
        let level0 = |b: &[u8]| crate::buffers::decode_texels(f, b, w as u32, h as u32);
        if let (Some(p0), Some(g0)) = (level0(port), level0(golden)) {
            let display = |img: &crate::ImageF32| match f {
                wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb => img.clone(),
                _ => crate::image_io::hdr_display(img),
            };
            let (flip, _) = crate::metrics::flip(&display(&p0), &display(&g0)).map_err(|e| e.to_string())?;
            return Ok(("flip", flip));
        }
    }
    let (mut num, mut den) = (0f64, 0f64);
    for (a, b) in p.data.iter().flatten().zip(g.data.iter().flatten()) {
        let (a, b) = (*a as f64, *b as f64);
        if a.is_finite() && b.is_finite() {
            num += (a - b) * (a - b);
            den += b * b;
        } else if a.to_bits() != b.to_bits() {
            num += 1.0;
        }
    }
    Ok(("relative", if num == 0.0 { 0.0 } else { (num / den.max(1e-30)).sqrt() }))
}

/// A list filled by atomic appends, compared as a set: both sides' records (of `stride`
/// bytes) sorted, then the share of differing words.
fn differing_records(port: &[u8], golden: &[u8], stride: usize) -> f64 {
    let sorted = |b: &[u8]| {
        let mut records: Vec<&[u8]> = b.chunks(stride).collect();
        records.sort_unstable();
        records.concat()
    };
    differing_words(&sorted(port), &sorted(golden))
}

/// The share of 32-bit words that differ (floats within 1e-4 relative count as equal).
fn differing_words(port: &[u8], golden: &[u8]) -> f64 {
    let words = golden.len() / 4;
    if words == 0 {
        return if port == golden { 0.0 } else { 1.0 };
    }
    let word = |b: &[u8], i: usize| u32::from_le_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]);
    let differ = (0..words)
        .filter(|&i| {
            let (a, b) = (word(port, i), word(golden, i));
            if a == b {
                return false;
            }
            let (fa, fb) = (f32::from_bits(a), f32::from_bits(b));
            !(fa.is_normal() && fb.is_normal() && ((fa - fb).abs() <= 1e-4 * fa.abs().max(fb.abs())))
        })
        .count();
    differ as f64 / words as f64
}
