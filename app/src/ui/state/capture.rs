//! The window's captures as the state runs them: the viewport saved as PNG and EXR, and
//! recorded frame sequences (File → Record); the image writing is `crate::ui::capture`.

use std::path::PathBuf;

use crate::ui::capture::{Recording, capture_stamp};
use crate::ui::state::State;

impl State {
    /// Saves the viewport's image (final.ldr as PNG, final.hdr as EXR) into `captures/`.
    pub fn capture_viewport(&mut self) {
        let Ok(l) = &self.lab else { return };
        let stamp = capture_stamp();
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
        let stamp = capture_stamp();
        let dir = PathBuf::from("captures").join(format!("sequence-{stamp}"));
        match std::fs::create_dir_all(&dir) {
            Ok(()) => {
                self.set_status(format!("recording {frames} frames to {}", dir.display()));
                self.capture.recording = Some(Recording { dir, remaining: frames, index: 0 });
            }
            Err(e) => self.set_status(format!("cannot record to {}: {e}", dir.display())),
        }
    }

    pub(in crate::ui) fn record_step(&mut self) {
        let (Some(rec), Ok(l)) = (&mut self.capture.recording, &self.lab) else { return };
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
            self.capture.recording = None;
            self.set_status(format!("recording stopped: {e}"));
        } else if done {
            self.capture.recording = None;
            self.set_status(format!("recorded {count} frames to {}", dir.display()));
        }
    }
}
