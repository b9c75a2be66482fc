//! The parts of the window's state that one pane or one menu reads and changes, each on its
//! own (issue #52 point 2): the probes pane takes [`Probes`], the timings pane [`Timings`], the
//! View menu and the viewport's overlays [`Overlays`]; the rest of the state stays with
//! [`super::State`].

use std::collections::{BTreeMap, VecDeque};
use std::sync::{Arc, Mutex};

use gi_render::buffers::ProbeValue;
use gi_render::passes::view::ViewPipeline;
use gi_render::readback::{Readback, Readout};
use gi_render::timing::PassTiming;

use crate::ui::capture::Recording;
use crate::ui::session::PinnedProbe;
use crate::ui::viewer::Viewer;

/// The pixel probes: the hovered pixel and every buffer's value there, the pinned probes and
/// their histories.
#[derive(Default)]
pub struct Probes {
    /// The hovered frame pixel (viewport or a viewer).
    pub hover: Option<(u32, u32)>,
    /// Every buffer's value at `hover`.
    pub values: Vec<ProbeValue>,
    pub pinned: Vec<PinnedProbe>,
    /// Per pinned probe: the chosen buffer's value over the last frames.
    pub history: Vec<VecDeque<[f32; 4]>>,
    /// The frame of the last probe values taken in (they arrive without waiting, late).
    pub frame: u64,
    /// The pixel under the pointer when the viewport's context menu opened.
    pub context_pixel: Option<(u32, u32)>,
}

impl Probes {
    /// Pins a probe at `pixel` on `buffer`; refused when the read-back holds no more points.
    pub fn pin(&mut self, pixel: (u32, u32), buffer: String) -> Result<(), String> {
        if self.pinned.len() + 1 >= gi_render::buffers::PROBE_MAX_POINTS {
            return Err("too many pinned probes".into());
        }
        self.pinned.push(PinnedProbe { pixel, buffer, channel: 0 });
        self.history.push(VecDeque::new());
        Ok(())
    }

    /// Removes pinned probe `k` and its history.
    pub fn unpin(&mut self, k: usize) {
        if k < self.pinned.len() {
            self.pinned.remove(k);
        }
        if k < self.history.len() {
            self.history.remove(k);
        }
    }

    /// Asks for this frame's values at the hovered and pinned pixels (clamped to the frame of
    /// `renderer`) and takes in those that arrived, keeping `keep` frames of each pin's
    /// history. The values arrive a frame or two late, without waiting (issue #38); a tag says
    /// which points they are, so that a pin added or removed meanwhile is not misread. Returns
    /// the read-back's error, when one arrived.
    pub fn update(&mut self, renderer: &mut gi_render::Renderer, keep: usize) -> Option<String> {
        let mut points: Vec<(u32, u32)> = self.hover.into_iter().collect();
        points.extend(self.pinned.iter().map(|p| p.pixel));
        points.truncate(gi_render::buffers::PROBE_MAX_POINTS);
        let (fw, fh) = renderer.size();
        let points: Vec<(u32, u32)> = points.into_iter().map(|(x, y)| (x.min(fw - 1), y.min(fh - 1))).collect();
        let tag = |hover: bool| probe_tag(hover, self.pinned.iter().map(|p| p.pixel));
        let arrived = if points.is_empty() {
            renderer.read_latest("probe")
        } else {
            renderer.read_later("probe", Readback::Probe(points), tag(self.hover.is_some()))
        };
        let mut error = None;
        match arrived.as_deref().map(|a| (a.frame, a.tag, &a.data)) {
            Some((frame, t, Ok(Readout::Probe(values)))) if frame != self.frame => {
                self.frame = frame;
                let had_hover = t == tag(true);
                let pins_same = had_hover || t == tag(false);
                let mut values = values.iter();
                self.values = match (had_hover, self.hover.is_some()) {
                    (true, true) => values.next().cloned().unwrap_or_default(),
                    (true, false) => {
                        values.next();
                        Vec::new()
                    }
                    _ => Vec::new(),
                };
                if pins_same {
                    self.history.resize_with(self.pinned.len(), VecDeque::new);
                    for ((p, h), vals) in self.pinned.iter().zip(&mut self.history).zip(values) {
                        let v = vals.iter().find(|v| v.name == p.buffer).map(|v| v.value).unwrap_or([f32::NAN; 4]);
                        h.push_back(v);
                        while h.len() > keep.max(2) {
                            h.pop_front();
                        }
                    }
                }
            }
            Some((frame, _, Err(e))) if frame != self.frame => {
                self.frame = frame;
                error = Some(format!("probe: {e}"));
            }
            _ => {}
        }
        if self.hover.is_none() {
            self.values.clear();
        }
        error
    }
}

/// Which points a probe read-back was asked for: whether the hovered pixel came first, and
/// the pinned pixels.
fn probe_tag(hover: bool, pins: impl Iterator<Item = (u32, u32)>) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    hover.hash(&mut h);
    for p in pins {
        p.hash(&mut h);
    }
    h.finish()
}

/// The timings pane's history and the pass the pointer is over.
#[derive(Default)]
pub struct Timings {
    /// Each frame's per-pass times, the last `session.history_frames`.
    pub history: VecDeque<Vec<PassTiming>>,
    /// The pass whose row the pointer is over in the timings panel (the viewport shows its
    /// output).
    pub hovered_pass: Option<String>,
}

impl Timings {
    /// Takes in a frame's times, keeping the last `keep` frames.
    pub fn push(&mut self, frame: Vec<PassTiming>, keep: usize) {
        self.history.push_back(frame);
        while self.history.len() > keep.max(2) {
            self.history.pop_front();
        }
    }
}

/// What the View menu draws over the viewport.
pub struct Overlays {
    /// Instant radiosity's VPLs (`vpl.list`) as dots.
    pub vpls: bool,
    /// The HCB's samples (Nguyen et al.'s white dots).
    pub hcb_samples: bool,
    /// The ring samples of the hovered pixel per level (Soler 004 Fig. 3 right).
    pub soler_samples: bool,
    /// The irradiance records as dots coloured by E_k with their influence circles a·R_k
    /// (Gautron 003, "From Octree to Splatting").
    pub gautron_records: bool,
    /// Every light, the selected one with its move and aim handles (issue #39 point 2).
    pub lights: bool,
    /// DDGI's probes coloured by state; the selected probe's rays (issue #56).
    pub ddgi_probes: bool,
    pub ddgi_selected: Option<usize>,
}

impl Default for Overlays {
    fn default() -> Self {
        Self {
            vpls: false,
            hcb_samples: false,
            soler_samples: false,
            gautron_records: false,
            lights: true,
            ddgi_probes: false,
            ddgi_selected: None,
        }
    }
}

/// The buffer viewers: the open ones by id, the pipeline they share, and the viewer the
/// viewport uses to show a hovered pass's output.
#[derive(Default)]
pub struct Viewers {
    pub open: BTreeMap<u32, Viewer>,
    pub(in crate::ui) pipeline: Option<Arc<ViewPipeline>>,
    /// A viewer used by the viewport to show a hovered pass's output.
    pub(in crate::ui) pass_view: Option<Viewer>,
    /// The viewers the tree drew last frame (those not shown are not updated).
    pub visible: Vec<u32>,
}

/// What a menu or a pane asked of the app, which owns the layout: done on the next frame.
#[derive(Default)]
pub struct Requests {
    pub new_viewer: bool,
    pub reset_layout: bool,
    /// Edit → History asked for the History pane.
    pub history: bool,
    /// An explain pin asked for the Explain pane.
    pub explain: bool,
    /// The keyboard help window is open.
    pub help: bool,
}

/// Captures under way: a recording of N frames, and the `--screenshot` of the window.
pub struct Captures {
    pub recording: Option<Recording>,
    /// Frames File → Record records.
    pub record_frames: u32,
    pub(in crate::ui) screenshot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    pub(in crate::ui) screenshot_requested: bool,
}

impl Default for Captures {
    fn default() -> Self {
        Self { recording: None, record_frames: 60, screenshot: Arc::new(Mutex::new(None)), screenshot_requested: false }
    }
}
