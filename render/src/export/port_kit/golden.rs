//! The port kit's goldens (issue #54 point 1; docs/port-kit.md, "Goldens"): for every frame
//! from a fresh start, the `input` resources as the frame's passes read them (what a host
//! uploads) and every pass's outputs, as read back right after the pass ran
//! ([`crate::counters::capture::start_with_goldens`]). Raw bytes in the resource's own format
//! (a texture's levels in order, layers in order, rows packed), and an EXR of level 0, layer 0
//! of float textures no larger than the image, to look at. Contents that repeat (a paused
//! frame's shadow maps) are written once; later frames name the first file.

use std::collections::{HashMap, HashSet};
use std::hash::{Hash, Hasher};
use std::path::PathBuf;

use super::manifest::{Built, GoldenFile, GoldenFrame, GoldenPass, file_name};
use crate::counters::capture::{Capture, PassCommands};

/// The golden frames of `built` from the captured `frames`, and their files.
pub fn goldens(
    built: &Built,
    frames: &[Vec<PassCommands>],
    objects: &Capture,
) -> (Vec<GoldenFrame>, Vec<(PathBuf, Vec<u8>)>) {
    let lifetime = |name: &str| built.manifest.resources.iter().find(|r| r.name == name).map(|r| r.lifetime);
    let mut out = Vec::new();
    let mut files = Vec::new();
    // Contents already written (a paused frame repeats many): their file, by hash and length.
    let mut written: HashMap<(u64, usize), String> = HashMap::new();
    let pixels = built.manifest.size[0] as u64 * built.manifest.size[1] as u64;
    for (k, (access, commands)) in built.frames.iter().zip(frames).enumerate() {
        let mut frame = GoldenFrame { frame: k as u32, inputs: Vec::new(), passes: Vec::new() };
        let mut inputs_done = HashSet::new();
        // Copies and clears recorded between the timed passes are not read back (no scope
        // ends after them); the next pass's outputs hold their effect.
        for pa in access.iter().filter(|pa| pa.name != "(between passes)") {
            let Some(pass) = commands.get(pa.source) else { continue };
            let mut file = |name: &str, dir: &str| -> Option<GoldenFile> {
                let &(texture, key) = built.keys.get(name)?;
                let snap = pass.snapshots.iter().find(|s| s.key == key && s.texture == texture)?;
                let canonical = format!("frame-{k}/{dir}/{}.bin", file_name(name));
                let mut h = std::collections::hash_map::DefaultHasher::new();
                snap.bytes.hash(&mut h);
                let id = (h.finish(), snap.bytes.len());
                if let Some(path) = written.get(&id) {
                    let exr = path.replace(".bin", ".exr");
                    let exr = files.iter().any(|(p, _): &(PathBuf, Vec<u8>)| p.to_string_lossy() == exr).then_some(exr);
                    let bytes = snap.bytes.len() as u64;
                    return Some(GoldenFile { resource: name.into(), path: canonical, file: path.clone(), exr, bytes });
                }
                let path = format!("golden/{canonical}");
                let exr = texture.then(|| exr_of(objects, key, &snap.bytes, pixels)).flatten().map(|bytes| {
                    let p = path.replace(".bin", ".exr");
                    files.push((PathBuf::from(&p), bytes));
                    p
                });
                files.push((PathBuf::from(&path), snap.bytes.clone()));
                written.insert(id, path.clone());
                Some(GoldenFile {
                    resource: name.into(),
                    path: canonical,
                    file: path,
                    exr,
                    bytes: snap.bytes.len() as u64,
                })
            };
            for name in &pa.read {
                if lifetime(name) == Some("input")
                    && inputs_done.insert(name.clone())
                    && let Some(f) = file(name, "inputs")
                {
                    frame.inputs.push(f);
                }
            }
            let dir = format!("{:02}-{}", pa.index, file_name(&pa.name));
            let outputs = pa.written.iter().filter_map(|name| file(name, &dir)).collect();
            frame.passes.push(GoldenPass { index: pa.index, name: pa.name.clone(), outputs });
        }
        out.push(frame);
    }
    (out, files)
}

/// An EXR of level 0, layer 0 of a 2D float texture's golden bytes, for textures no larger
/// than the image (`pixels`; an atlas's EXR would double the kit for a picture few look at).
fn exr_of(objects: &Capture, key: u64, bytes: &[u8], pixels: u64) -> Option<Vec<u8>> {
    let t = objects.textures.get(&key)?;
    if t.dimension != "D2" || t.size[0] as u64 * t.size[1] as u64 > pixels {
        return None;
    }
    let format = t.texture_format?;
    if !matches!(
        format.sample_type(None, None),
        Some(wgpu::TextureSampleType::Float { .. }) | Some(wgpu::TextureSampleType::Depth)
    ) {
        return None;
    }
    let img = crate::buffers::decode_texels(format, bytes, t.size[0], t.size[1])?;
    crate::image_io::exr_bytes(&img).ok()
}
