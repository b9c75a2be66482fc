//! A/B comparison (issue #4 item 6): a second renderer (B) draws the same scene, camera,
//! lights and animation time with other settings — a preset file, the live settings frozen
//! at the moment the comparison started, or the exact-VPL reference — and the viewport is
//! split by a draggable divider, or shows the absolute difference or the FLIP error map of
//! the two images (with mean FLIP and RMSE). Difference and FLIP are computed on the CPU
//! from read-back images, a few times a second, on a thread of their own: nv-flip takes about
//! 0.3 s at 1920×1080, which on the window's thread stalled every frame it landed in.

use gi_render::readback::{Arrived, Readback, Readout};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::{Duration, Instant};

use gi_render::{LabSettings, Renderer};

/// What B renders with.
#[derive(Clone, Debug, PartialEq)]
pub enum AbSource {
    /// A preset file.
    Preset(PathBuf),
    /// The live settings as they were when the comparison started.
    Frozen,
    /// The live settings with the exact-VPL reference as indirect technique.
    Reference,
}

impl AbSource {
    pub fn label(&self) -> String {
        match self {
            Self::Preset(p) => p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default(),
            Self::Frozen => "frozen settings".into(),
            Self::Reference => "exact-VPL reference".into(),
        }
    }
}

/// How the two images are shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AbView {
    Split,
    Difference,
    Flip,
}

pub struct Ab {
    pub b: Renderer,
    pub source: AbSource,
    /// Divider position as a fraction of the viewport width (A left, B right).
    pub split: f32,
    pub view: AbView,
    /// Gain of the difference view.
    pub gain: f32,
    texture_b: Option<(egui::TextureId, (u32, u32))>,
    compared: Option<egui::TextureHandle>,
    last_compare: Option<Instant>,
    /// The frames (A's, B's) of the last images compared.
    compared_frames: Option<(u64, u64)>,
    /// The comparison being computed on its own thread.
    job: Option<Receiver<Result<Comparison, String>>>,
    /// Mean FLIP and RMSE (of final.hdr) of the last comparison.
    pub metrics: Option<(f64, f64)>,
    pub error: Option<String>,
}

impl Ab {
    /// Starts a comparison of `a` with `source`.
    pub fn start(a: &Renderer, live: &LabSettings, source: AbSource) -> Result<Self, String> {
        let settings = b_settings(live, &source)?;
        let (w, h) = a.size();
        let mut b = Renderer::new(a.ctx.clone(), a.scene().clone(), settings, w, h).map_err(|e| e.to_string())?;
        b.set_interactive(true);
        Ok(Self {
            b,
            source,
            split: 0.5,
            view: AbView::Split,
            gain: 4.0,
            texture_b: None,
            compared: None,
            last_compare: None,
            compared_frames: None,
            job: None,
            metrics: None,
            error: None,
        })
    }

    /// Renders B in step with A: same size, camera, light edits and animation time. Call
    /// before A renders (the clock is copied before it ticks).
    pub fn render(&mut self, a: &Renderer) {
        match follow(a, &mut self.b) {
            Ok(()) => {
                self.b.render_frame();
            }
            Err(e) => self.error = Some(e),
        }
    }

    /// B's final image as an egui texture.
    pub fn texture_b(&mut self, rs: &egui_wgpu::RenderState) -> (egui::TextureId, (u32, u32)) {
        let t = self.b.final_ldr().clone();
        let id = crate::ui::lab::native_texture(rs, &mut self.texture_b, &t, false);
        (id, (t.width(), t.height()))
    }

    /// The difference or FLIP image of A and B (refreshed at most every 400 ms).
    pub fn compared(&mut self, ctx: &egui::Context, a: &Renderer) -> Option<egui::TextureId> {
        // Asked for at most every 400 ms; compared as soon as the pair arrives.
        let due = self.last_compare.is_none_or(|t| t.elapsed() > Duration::from_millis(400));
        if due {
            self.last_compare = Some(Instant::now());
        }
        match self.finished() {
            None => {}
            Some(Ok(c)) => {
                self.metrics = Some(c.metrics);
                let opts = egui::TextureOptions::NEAREST;
                match &mut self.compared {
                    Some(h) => h.set(c.image, opts),
                    None => self.compared = Some(ctx.load_texture("ab.compare", c.image, opts)),
                }
                self.error = None;
            }
            Some(Err(e)) => self.error = Some(e),
        }
        if self.job.is_none() {
            self.compare(a, due);
        }
        self.compared.as_ref().map(|h| h.id())
    }

    /// The comparison computed on its thread, once it is done.
    fn finished(&mut self) -> Option<Result<Comparison, String>> {
        let done = match self.job.as_ref()?.try_recv() {
            Ok(c) => c,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => Err("the comparison stopped without a result".to_string()),
        };
        self.job = None;
        Some(done)
    }

    /// Asks both renderers for their final images (copied in their next frames, read without
    /// waiting, issue #38) and starts comparing the newest pair that has arrived on a thread.
    fn compare(&mut self, a: &Renderer, ask: bool) {
        let arrived = |r: &Renderer, name: &str| {
            let (key, what) = (format!("ab.{name}"), Readback::Image { name: name.into(), layer: 0, mip: 0 });
            if ask { r.read_later(&key, what, 0) } else { r.read_latest(&key) }
        };
        let pair = (|| Some((arrived(a, "final.hdr")?, arrived(&self.b, "final.hdr")?)))();
        let ldr = (|| Some((arrived(a, "final.ldr")?, arrived(&self.b, "final.ldr")?)))();
        let (Some((ah, bh)), Some((al, bl))) = (pair, ldr) else { return };
        // Only a pair not compared yet (the images stay in their read-backs, shared).
        if self.compared_frames == Some((ah.frame, bh.frame)) {
            return;
        }
        self.compared_frames = Some((ah.frame, bh.frame));
        let (view, gain) = (self.view, self.gain);
        let (tx, rx) = std::sync::mpsc::channel();
        let spawned = std::thread::Builder::new().name("ab-compare".into()).spawn(move || {
            let _ = tx.send(compare_images([&ah, &bh, &al, &bl], view, gain));
        });
        match spawned {
            Ok(_) => self.job = Some(rx),
            Err(e) => self.error = Some(format!("cannot start the comparison: {e}")),
        }
    }

    /// Frees B's texture.
    pub fn release(&mut self, rs: &egui_wgpu::RenderState) {
        if let Some((id, _)) = self.texture_b.take() {
            rs.renderer.write().free_texture(&id);
        }
    }
}

/// Puts `b` in step with `a`: the same size, camera, animation time and lights (the lab's
/// light edits, added and removed lights); a change of lights restarts b's temporal history.
/// Used by A/B and by the comparison grid's cells.
pub fn follow(a: &Renderer, b: &mut Renderer) -> Result<(), String> {
    let (w, h) = a.size();
    b.resize(w, h).map_err(|e| e.to_string())?;
    b.camera = a.camera;
    b.clock = a.clock;
    let (src, dst) = (a.scene(), b.scene_mut());
    let mut lights_moved = false;
    // Lights added or removed in the lab (issue #18): b takes a's whole light set.
    let lit = |s: &gi_render::scene::Scene| s.nodes.iter().map(|n| n.light.is_some()).collect::<Vec<_>>();
    if src.nodes.len() != dst.nodes.len() || lit(src) != lit(dst) || src.lights.len() != dst.lights.len() {
        dst.nodes = src.nodes.clone();
        dst.roots = src.roots.clone();
        dst.lights = src.lights.clone();
        lights_moved = true;
    }
    for (i, n) in src.nodes.iter().enumerate() {
        if let (Some(li), Some(d)) = (n.light, dst.nodes.get_mut(i)) {
            if d.transform != n.transform {
                d.transform = n.transform;
                lights_moved = true;
            }
            if let (Some(sl), Some(dl)) = (src.lights.get(li), dst.lights.get_mut(li))
                && dl != sl
            {
                *dl = sl.clone();
                lights_moved = true;
            }
        }
    }
    if lights_moved {
        b.reset_history();
    }
    Ok(())
}

/// One comparison: mean FLIP and RMSE, and the image the view shows.
struct Comparison {
    metrics: (f64, f64),
    image: egui::ColorImage,
}

/// RMSE of final.hdr, FLIP of final.ldr, and the difference (× `gain`) or FLIP image of the
/// read-backs [A hdr, B hdr, A ldr, B ldr].
fn compare_images(images: [&Arc<Arrived>; 4], view: AbView, gain: f32) -> Result<Comparison, String> {
    fn image(x: &Arrived) -> Result<&gi_render::ImageF32, String> {
        match &x.data {
            Ok(Readout::Image(img)) => Ok(img),
            Ok(_) => Err("a read-back is not an image".to_string()),
            Err(e) => Err(e.clone()),
        }
    }
    let [ah, bh, al, bl] = images.map(|x| image(x));
    let (ah, bh, al, bl) = (ah?, bh?, al?, bl?);
    let rmse = gi_render::metrics::rmse(ah, bh).map_err(|e| e.to_string())?;
    let (mean, map) = gi_render::metrics::flip(al, bl).map_err(|e| e.to_string())?;
    let (w, h) = (al.width as usize, al.height as usize);
    let pixels: Vec<egui::Color32> = match view {
        AbView::Flip => map
            .data
            .iter()
            .map(|p| {
                let c = gi_render::cpu::view::colormap(gi_render::passes::view::Colormap::Inferno, p[0]);
                egui::Color32::from_rgb((c[0] * 255.0) as u8, (c[1] * 255.0) as u8, (c[2] * 255.0) as u8)
            })
            .collect(),
        _ => al
            .data
            .iter()
            .zip(&bl.data)
            .map(|(x, y)| {
                let d = |i: usize| ((x[i] - y[i]).abs() * gain).clamp(0.0, 1.0);
                egui::Color32::from_rgb((d(0) * 255.0) as u8, (d(1) * 255.0) as u8, (d(2) * 255.0) as u8)
            })
            .collect(),
    };
    Ok(Comparison { metrics: (mean, rmse), image: egui::ColorImage::new([w, h], pixels) })
}

/// B's settings for `source`, given A's live settings. The exact-VPL reference keeps A's
/// scene-facing settings; when A is the HCB with the paper's diffuse receiver
/// (`hcb.receiver = DiffuseOnly`: c·DI/π, Nguyen §4), the reference's gather is diffuse only
/// too, so that the comparison is like for like (issue #15); with GI Lab's glossy receiver
/// (issue #51) the reference reflects with the full BRDF.
pub fn b_settings(live: &LabSettings, source: &AbSource) -> Result<LabSettings, String> {
    Ok(match source {
        AbSource::Preset(p) => gi_render::preset::load_file(p).map_err(|e| e.to_string())?.settings,
        AbSource::Frozen => live.clone(),
        AbSource::Reference => {
            let mut s = live.clone();
            gi_render::settings::pipeline::Technique::ExactVpl.apply(&mut s);
            if live.pipeline.uses_hcb()
                && live.hcb.receiver == gi_render::settings::splat::IrradianceReceiver::DiffuseOnly
            {
                s.vpl.receiver_brdf = gi_render::passes::knecht::vpl_importance::ReceiverBrdf::DiffuseOnly;
            }
            s
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use gi_render::passes::knecht::vpl_importance::ReceiverBrdf;
    use gi_render::settings::pipeline::Technique;

    #[test]
    fn the_reference_of_the_hcb_reflects_diffusely_like_it() {
        let mut live = LabSettings::default();
        Technique::Nguyen.apply(&mut live);
        let b = b_settings(&live, &AbSource::Reference).expect("settings");
        assert!(b.pipeline.is_reference());
        assert_eq!(b.vpl.receiver_brdf, ReceiverBrdf::Full, "the glossy HCB against the full BRDF");
        live.hcb.receiver = gi_render::settings::splat::IrradianceReceiver::DiffuseOnly;
        let b = b_settings(&live, &AbSource::Reference).expect("settings");
        assert_eq!(b.vpl.receiver_brdf, ReceiverBrdf::DiffuseOnly);
        Technique::Knecht.apply(&mut live);
        let b = b_settings(&live, &AbSource::Reference).expect("settings");
        assert_eq!(b.vpl.receiver_brdf, ReceiverBrdf::Full, "instant radiosity gathers with the full BRDF");
    }
}
