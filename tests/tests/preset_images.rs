//! Every shipped preset keeps its image while the frame is made leaner (issue #38: "images
//! stay what they were"). Each preset's `final.hdr` on the default scene at 128², after 16
//! frames with the animation paused, is compared with its recorded image (first recorded at
//! 256² before the lean-frame work began; `tests/data/presets/NAME.png`: half floats, their bits stored as a 16-bit RGB
//! PNG, lossless at half precision; Radiance RGBE alone already costs a FLIP of 0.012) by
//! FLIP at the recorded image's exposure; the mean must stay within 0.01.
//!
//! A new preset has no recorded image and fails here; record it (and only it) with
//! `GI_LAB_RECORD_PRESET_IMAGES=NAME cargo test -p gi-lab-tests --test preset_images`, and say
//! in the commit why its image is right.

use std::path::{Path, PathBuf};

use gi_lab_tests::{default_scene, gpu, images::exposed_flip, read};
use gi_render::{ImageF32, Renderer};

// 128² since issue #52 (the suite's time): the images were recorded again at 128² from commit
// 1742345's code, which kept every preset within the bound of its 256² image.
const SIZE: u32 = 128;
const FRAMES: u32 = 16;
const MAX_MEAN_FLIP: f64 = 0.01;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn render_preset(path: &Path) -> ImageF32 {
    let loaded = gi_render::preset::load_file(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut r = Renderer::new(gpu(), default_scene(), loaded.settings, SIZE, SIZE)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    r.clock.playing = false;
    for _ in 0..FRAMES {
        r.render_frame();
    }
    // The frame as a list (issue #52): a preset with indirect light has steps, and every step
    // found the pass its choice brought.
    let steps = r.frame_steps();
    let direct_only = r.settings().pipeline.gather == gi_render::settings::pipeline::Gather::None;
    assert_eq!(steps.is_empty(), direct_only, "{}: steps {steps:?}", path.display());
    assert_eq!(r.failed_step(), None, "{}: steps {steps:?}", path.display());
    read(&r, "final.hdr")
}

/// f32 → IEEE half bits (round to nearest; the renderer's HDR values are finite and ≥ 0).
fn f32_to_half(v: f32) -> u16 {
    let b = v.to_bits();
    let sign = ((b >> 16) & 0x8000) as u16;
    let exp = ((b >> 23) & 0xff) as i32 - 127 + 15;
    let man = b & 0x7f_ffff;
    if v.is_nan() {
        return 0x7e00;
    }
    if exp >= 31 {
        return sign | 0x7c00;
    }
    if exp <= 0 {
        if exp < -10 {
            return sign;
        }
        let m = (man | 0x80_0000) >> (1 - exp);
        return sign | ((m + 0x1000) >> 13) as u16;
    }
    let h = ((exp as u32) << 10) | (man >> 13);
    let round = (man >> 12) & 1;
    sign | (h + round) as u16
}

fn save_half_png(path: &Path, img: &ImageF32) {
    let data: Vec<u16> = img.data.iter().flat_map(|p| [p[0], p[1], p[2]].map(f32_to_half)).collect();
    let buf: image::ImageBuffer<image::Rgb<u16>, Vec<u16>> =
        image::ImageBuffer::from_raw(img.width, img.height, data).expect("image size");
    buf.save(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

fn load_half_png(path: &Path) -> Option<ImageF32> {
    let img = image::open(path).ok()?.into_rgb16();
    let h = |v: u16| gi_render::buffers::half_to_f32(v);
    let data = img.pixels().map(|p| [h(p.0[0]), h(p.0[1]), h(p.0[2]), 1.0]).collect();
    Some(ImageF32 { width: img.width(), height: img.height(), data })
}

#[test]
fn every_shipped_preset_keeps_its_image() {
    let record = std::env::var("GI_LAB_RECORD_PRESET_IMAGES").unwrap_or_default();
    let data = root().join("tests/data/presets");
    let presets = gi_lab_tests::shipped_presets();
    let mut failures = Vec::new();
    let mut report = Vec::new();
    for p in &presets {
        let name = p.file_stem().and_then(|s| s.to_str()).expect("preset name").to_string();
        let img = render_preset(p);
        let stored = data.join(format!("{name}.png"));
        if record.split(',').any(|r| r == name || r == "all") {
            std::fs::create_dir_all(&data).expect("tests/data/presets");
            save_half_png(&stored, &img);
            report.push(format!("{name}: recorded"));
            continue;
        }
        let Some(before) = load_half_png(&stored) else {
            failures.push(format!(
                "{name}: no recorded image at {}; record it with GI_LAB_RECORD_PRESET_IMAGES={name}",
                stored.display()
            ));
            continue;
        };
        assert_eq!((before.width, before.height), (SIZE, SIZE), "{name}: recorded image size");
        let f = exposed_flip(&img, &before);
        report.push(format!("{name}: mean FLIP {f:.4}"));
        if f.is_nan() || f > MAX_MEAN_FLIP {
            failures.push(format!("{name}: mean FLIP {f:.4} against the recorded image (at most {MAX_MEAN_FLIP})"));
        }
    }
    println!("{}", report.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The comparison can fail: the recorded image with its lower half twice as bright is far
/// from the recorded one.
#[test]
fn the_comparison_sees_a_changed_image() {
    let stored = root().join("tests/data/presets/default.png");
    let before = load_half_png(&stored).expect("tests/data/presets/default.png");
    let mut brighter = before.clone();
    for p in brighter.data.iter_mut().skip(before.data.len() / 2) {
        for c in &mut p[..3] {
            *c *= 2.0;
        }
    }
    assert!(exposed_flip(&brighter, &before) > MAX_MEAN_FLIP);
}

/// The stored form loses less than the comparison tolerates: half floats round-trip within
/// their precision.
#[test]
fn half_floats_round_trip() {
    for v in [0.0f32, 1.0, 0.5, 0.333, 1e-5, 7.25e-3, 123.4, 6e4] {
        let back = gi_render::buffers::half_to_f32(f32_to_half(v));
        assert!((back - v).abs() <= v.abs() * 1e-3 + 1e-7, "{v} -> {back}");
    }
}
