//! The files of the crash-safety test (issue #19 point 4): one generation `g` of a preset,
//! the session and captures, written through GI Lab's own saving code (`save_loop` runs it
//! in a loop and is killed), and the checks that each file on disk is one complete
//! generation.
//!
//! Every file encodes its generation so that a complete file names exactly one version:
//! the preset's `reference.seed`, the session's `time_s` (its `settings_ron` holds that
//! preset too), the PNG's RGB bytes and the EXR's red channel in every pixel.

use std::path::{Path, PathBuf};

use gi_lab::ui::session::Session;
use gi_render::image_io;
use gi_render::{BufferKind, ImageF32, LabSettings};

/// The preset the loop saves (`LabSettings::save`, with a `.bak`).
pub const PRESET: &str = "loop.ron";
/// The viewport capture as PNG and EXR (`image_io::save_png`, `image_io::save_exr`).
pub const CAPTURE_PNG: &str = "capture.png";
/// See [`CAPTURE_PNG`].
pub const CAPTURE_EXR: &str = "capture.exr";
/// The window screenshot (`gi_lab::ui::capture::save_color_image`).
pub const SCREENSHOT: &str = "screenshot.png";
/// The files that keep a `.bak` of the version they replaced.
pub const WITH_BACKUP: &[&str] = &[PRESET, "session.ron"];

/// Width and height of the captures: large enough that encoding and writing them take a
/// noticeable share of a generation, so that kills land inside those saves too.
const SIZE: u32 = 48;

/// The preset of generation `g`.
pub fn preset(g: u64) -> LabSettings {
    let mut s = LabSettings::default();
    s.reference.seed = g as u32;
    s
}

/// The session of generation `g`.
pub fn session(g: u64) -> Session {
    Session { time_s: g as f64, settings_ron: Some(preset(g).to_ron()), ..Session::default() }
}

fn rgb(g: u64) -> [u8; 3] {
    [(g & 0xff) as u8, ((g >> 8) & 0xff) as u8, ((g >> 16) & 0xff) as u8]
}

/// Saves generation `g` of every file in `dir` through the lab's saving code.
pub fn save_generation(dir: &Path, g: u64) -> Result<(), String> {
    preset(g).save(&dir.join(PRESET)).map_err(|e| e.to_string())?;
    session(g).save(dir)?;
    let [r, gr, b] = rgb(g).map(|c| c as f32 / 255.0);
    let ldr = ImageF32 { width: SIZE, height: SIZE, data: vec![[r, gr, b, 1.0]; (SIZE * SIZE) as usize] };
    image_io::save_png(&dir.join(CAPTURE_PNG), &ldr, BufferKind::Ldr).map_err(|e| e.to_string())?;
    let hdr = ImageF32 { width: SIZE, height: SIZE, data: vec![[g as f32, 0.5, 2.0, 1.0]; (SIZE * SIZE) as usize] };
    image_io::save_exr(&dir.join(CAPTURE_EXR), &hdr).map_err(|e| e.to_string())?;
    let [r, gr, b] = rgb(g);
    let shot = egui::ColorImage::filled([SIZE as usize, SIZE as usize], egui::Color32::from_rgb(r, gr, b));
    gi_lab::ui::capture::save_color_image(&dir.join(SCREENSHOT), &shot)
}

/// Every file the loop writes, `.bak`s included.
pub fn file_names() -> Vec<String> {
    let mut v: Vec<String> = [PRESET, "session.ron", CAPTURE_PNG, CAPTURE_EXR, SCREENSHOT].map(String::from).into();
    v.extend(WITH_BACKUP.iter().map(|n| format!("{n}.bak")));
    v
}

/// The generation of one of the loop's files (None: it does not exist), after checking
/// that it loads with the lab's own loaders and is byte for byte (text files) or pixel for
/// pixel (images) that generation's complete version.
pub fn generation(dir: &Path, name: &str) -> Result<Option<u64>, String> {
    let path = dir.join(name);
    if !path.exists() {
        return Ok(None);
    }
    let shown = path.display().to_string();
    let base = name.trim_end_matches(".bak");
    let g = match base {
        PRESET => {
            let s = LabSettings::load(&path).map_err(|e| format!("{shown}: {e}"))?;
            let g = u64::from(s.reference.seed);
            same_text(&path, &preset(g).to_ron())?;
            g
        }
        "session.ron" => {
            let text = std::fs::read_to_string(&path).map_err(|e| format!("{shown}: {e}"))?;
            let s: Session = ron::from_str(&text).map_err(|e| format!("{shown}: {e}"))?;
            if !(s.time_s >= 0.0 && s.time_s.fract() == 0.0) {
                return Err(format!("{shown}: time_s {} is no generation", s.time_s));
            }
            let g = s.time_s as u64;
            same_text(&path, &session(g).to_ron())?;
            g
        }
        CAPTURE_PNG | SCREENSHOT => {
            let img = image::open(&path).map_err(|e| format!("{shown}: {e}"))?.into_rgba8();
            let first = img.pixels().next().map(|p| p.0).ok_or(format!("{shown}: empty"))?;
            if img.dimensions() != (SIZE, SIZE) || img.pixels().any(|p| p.0 != first) || first[3] != 255 {
                return Err(format!("{shown}: not one generation's image"));
            }
            u64::from(first[0]) | u64::from(first[1]) << 8 | u64::from(first[2]) << 16
        }
        CAPTURE_EXR => {
            let img = image_io::load_float_image(&path).map_err(|e| format!("{shown}: {e}"))?;
            let first = img.data.first().copied().ok_or(format!("{shown}: empty"))?;
            let whole = (img.width, img.height) == (SIZE, SIZE) && img.data.iter().all(|p| *p == first);
            if !whole || first[1..] != [0.5, 2.0, 1.0] || first[0].fract() != 0.0 || first[0] < 0.0 {
                return Err(format!("{shown}: not one generation's image"));
            }
            first[0] as u64
        }
        _ => return Err(format!("{shown}: not a file of the loop")),
    };
    Ok(Some(g))
}

fn same_text(path: &Path, expected: &str) -> Result<(), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    if text != expected {
        return Err(format!("{}: parses but is not the complete version it names", path.display()));
    }
    Ok(())
}

/// The generation to start from in `dir`: one past the newest file there (0 for none).
pub fn next_generation(dir: &Path) -> Result<u64, String> {
    let mut next = 0;
    for name in file_names() {
        if let Some(g) = generation(dir, &name)? {
            next = next.max(g + 1);
        }
    }
    Ok(next)
}

/// Entries of `dir` that are not the loop's files: the temporary files a kill left behind
/// (hidden, ending in `.tmp`) in the first list, anything else in the second.
pub fn strays(dir: &Path) -> Result<(Vec<PathBuf>, Vec<PathBuf>), String> {
    let known = file_names();
    let mut temps = Vec::new();
    let mut others = Vec::new();
    for e in std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))? {
        let e = e.map_err(|e| e.to_string())?;
        let name = e.file_name().to_string_lossy().into_owned();
        if known.contains(&name) {
            continue;
        }
        if name.starts_with('.') && name.ends_with(".tmp") { &mut temps } else { &mut others }.push(e.path());
    }
    Ok((temps, others))
}
