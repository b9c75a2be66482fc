//! Explain a pixel in the window (issue #42): the pinned pixel, its latest explanation (read
//! without waiting, `Renderer::explanation_later`), and the Explain pane's and the overlay's
//! choices. The pane and the overlay draw it (`panes::explain`).

use gi_render::Renderer;
use gi_render::explain::Explanation;

/// The pixel being explained and what the pane shows of it.
pub struct ExplainView {
    /// In frame pixels (the render's size, not the viewport's points).
    pub pixel: (u32, u32),
    /// The newest explanation that arrived (a frame or two late), or why there is none.
    pub latest: Option<Result<Explanation, String>>,
    /// The pane lists the rejected contributors too (they are dimmed in the overlay).
    pub show_rejected: bool,
    /// The viewport draws the contributors.
    pub overlay: bool,
    /// The contributor whose row the pointer is over (the overlay rings it).
    pub hovered: Option<String>,
}

impl ExplainView {
    pub fn new(pixel: (u32, u32)) -> Self {
        Self { pixel, latest: None, show_rejected: false, overlay: true, hovered: None }
    }

    /// The explanation, when one arrived for this pixel.
    pub fn explanation(&self) -> Option<&Explanation> {
        match &self.latest {
            Some(Ok(e)) if e.pixel == self.pixel => Some(e),
            _ => None,
        }
    }
}

/// Before the frame: the renderer replays the pinned pixel's gather (or none).
pub fn before_frame(view: &mut Option<ExplainView>, r: &mut Renderer) {
    match view {
        Some(v) => {
            let (w, h) = r.size();
            v.pixel = (v.pixel.0.min(w.saturating_sub(1)), v.pixel.1.min(h.saturating_sub(1)));
            if r.explain_pixel() != Some(v.pixel) {
                r.set_explain(Some(v.pixel));
            }
        }
        None => {
            if r.explain_pixel().is_some() {
                r.set_explain(None);
            }
        }
    }
}

/// After the frame: takes in the newest explanation that arrived.
pub fn after_frame(view: &mut Option<ExplainView>, r: &Renderer) {
    if let Some(v) = view
        && let Some(e) = r.explanation_later()
    {
        v.latest = Some(e);
    }
}
