//! Captures: the viewport saved as PNG and EXR, recorded frame sequences, and the
//! `--screenshot` of the window. Each image is written atomically (encoded in memory, then a
//! temporary file renamed over it), so a crash never leaves a truncated image.

use std::path::{Path, PathBuf};

use crate::ui::app::GiLabApp;
use crate::ui::state::State;

/// A recording of N frames to a folder (File → Record).
pub struct Recording {
    pub dir: PathBuf,
    pub remaining: u32,
    pub index: u32,
}

/// A file-name-safe UTC time stamp for captures (`2026-11-22T17-03-46Z`).
pub fn capture_stamp() -> String {
    gi_render::preset::utc_now().replace(':', "-")
}

/// Writes a window screenshot in the format its extension names (PNG when it names none),
/// atomically (`gi_render::image_io::save_atomic`: a kill mid-save leaves the old file or
/// the new complete one).
pub fn save_color_image(path: &Path, img: &egui::ColorImage) -> Result<(), String> {
    let [w, h] = img.size;
    let bytes: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
    let i = image::RgbaImage::from_raw(w as u32, h as u32, bytes).ok_or("screenshot has inconsistent size")?;
    let format = image::ImageFormat::from_path(path).unwrap_or(image::ImageFormat::Png);
    gi_render::image_io::save_atomic(path, &image::DynamicImage::ImageRgba8(i), format)
        .map_err(|e| format!("cannot write screenshot {}: {e}", path.display()))
}

impl State {
    /// Saves the viewport's image (final.ldr as PNG, final.hdr as EXR) into `captures/`.
    pub fn capture_viewport(&mut self) {
        let Ok(l) = &self.lab else { return };
        let stamp = crate::ui::capture::capture_stamp();
        let dir = PathBuf::from("captures");
        let r = (|| -> Result<String, String> {
            std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            let ldr = l.renderer.readback("final.ldr").map_err(|e| e.to_string())?;
            let hdr = l.renderer.readback("final.hdr").map_err(|e| e.to_string())?;
            let png = dir.join(format!("viewport-{stamp}.png"));
            let exr = dir.join(format!("viewport-{stamp}.exr"));
            gi_render::image_io::save_png(&png, &ldr, gi_render::BufferKind::Ldr).map_err(|e| e.to_string())?;
            gi_render::image_io::save_exr(&exr, &hdr).map_err(|e| e.to_string())?;
            Ok(format!("saved {} and {}", png.display(), exr.display()))
        })();
        self.set_status(r.unwrap_or_else(|e| format!("capture failed: {e}")));
    }

    /// File → Record: the next `frames` frames as numbered PNGs in a new folder.
    pub fn start_recording(&mut self, frames: u32) {
        let stamp = crate::ui::capture::capture_stamp();
        let dir = PathBuf::from("captures").join(format!("sequence-{stamp}"));
        match std::fs::create_dir_all(&dir) {
            Ok(()) => {
                self.set_status(format!("recording {frames} frames to {}", dir.display()));
                self.recording = Some(Recording { dir, remaining: frames, index: 0 });
            }
            Err(e) => self.set_status(format!("cannot record to {}: {e}", dir.display())),
        }
    }

    pub(super) fn record_step(&mut self) {
        let (Some(rec), Ok(l)) = (&mut self.recording, &self.lab) else { return };
        let path = rec.dir.join(format!("frame-{:05}.png", rec.index));
        let r = l.renderer.readback("final.ldr").map_err(|e| e.to_string()).and_then(|img| {
            gi_render::image_io::save_png(&path, &img, gi_render::BufferKind::Ldr).map_err(|e| e.to_string())
        });
        rec.index += 1;
        rec.remaining = rec.remaining.saturating_sub(1);
        let done = rec.remaining == 0;
        let dir = rec.dir.clone();
        let count = rec.index;
        if let Err(e) = r {
            self.recording = None;
            self.set_status(format!("recording stopped: {e}"));
        } else if done {
            self.recording = None;
            self.set_status(format!("recorded {count} frames to {}", dir.display()));
        }
    }
}

impl GiLabApp {
    pub(super) fn screenshot_step(&mut self, ctx: &egui::Context) {
        let st = &mut self.state;
        let Some(path) = st.args.screenshot.clone() else { return };
        if !st.screenshot_requested && st.frames >= st.args.screenshot_frames {
            let slot = st.screenshot.clone();
            ctx.request_screenshot(move |img| {
                if let Ok(mut s) = slot.lock() {
                    *s = Some(img);
                }
            });
            st.screenshot_requested = true;
        }
        let taken = st.screenshot.lock().ok().and_then(|mut s| s.take());
        if let Some(img) = taken {
            match save_color_image(&path, &img) {
                Ok(()) => println!("wrote screenshot {}", path.display()),
                Err(e) => eprintln!("gi-lab: {e}"),
            }
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }
}
