//! The DDGI probe overlay (issue #56 point 3): every probe of the grid as a dot at its
//! relocated place, green while active, red when classification turned it off (Majercik et
//! al. 2021 §5.2), with its offset from the grid drawn as a line; a click on a dot selects
//! the probe and draws its rays of the frame (2019 §3.1) to their hits, coloured by the
//! radiance they brought back (magenta: a back face; grey and short: a miss).

use super::caption;
use crate::ui::state::State;

/// How far from a dot a click selects its probe (points).
const PICK_RADIUS: f32 = 8.0;

/// World → the viewport's points (None behind the camera).
fn to_screen(vp: glam::Mat4, rect: egui::Rect, p: glam::Vec3) -> Option<egui::Pos2> {
    let clip = vp * p.extend(1.0);
    (clip.w > 0.0).then(|| {
        let ndc = clip.truncate() / clip.w;
        rect.min + egui::vec2((ndc.x * 0.5 + 0.5) * rect.width(), (0.5 - ndc.y * 0.5) * rect.height())
    })
}

/// The probe whose dot lies within [`PICK_RADIUS`] of `click`, the nearest one.
pub(super) fn pick(st: &State, rect: egui::Rect, click: egui::Pos2) -> Option<usize> {
    let l = st.lab.as_ref().ok()?;
    let o = l.renderer.ddgi_overlay_later(st.overlays.ddgi_selected.is_some())?;
    let vp = l.renderer.view_proj();
    (0..o.probes.len())
        .filter_map(|i| Some((i, to_screen(vp, rect, o.position(i))?.distance(click))))
        .filter(|(_, d)| *d <= PICK_RADIUS)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

pub(super) fn probes_overlay(st: &State, ui: &mut egui::Ui, rect: egui::Rect) {
    let Ok(l) = &st.lab else { return };
    let painter = ui.painter_at(rect);
    let text = |s: String| caption(&painter, rect, s);
    let Some(o) = l.renderer.ddgi_overlay_later(st.overlays.ddgi_selected.is_some()) else {
        text("DDGI probes: pick the DDGI technique (gather: DDGI probes) to see its probes".into());
        return;
    };
    let vp = l.renderer.view_proj();
    let active = egui::Color32::from_rgb(60, 220, 90);
    let inactive = egui::Color32::from_rgb(230, 60, 50);
    let mut off = 0;
    for i in 0..o.probes.len() {
        let (Some(at), on) = (to_screen(vp, rect, o.position(i)), o.active(i)) else { continue };
        off += !on as usize;
        if let Some(grid) = to_screen(vp, rect, o.grid.position(i))
            && grid.distance(at) > 1.0
        {
            painter.line_segment([grid, at], egui::Stroke::new(1.0, egui::Color32::from_white_alpha(90)));
        }
        painter.circle(at, 3.0, if on { active } else { inactive }, egui::Stroke::new(1.0, egui::Color32::BLACK));
    }
    let mut line = format!(
        "{} DDGI probes ({}×{}×{}), {off} inactive (red); click a probe to see its rays",
        o.probes.len(),
        o.grid.counts.x,
        o.grid.counts.y,
        o.grid.counts.z
    );
    if let Some(i) = st.overlays.ddgi_selected.filter(|i| *i < o.probes.len()) {
        let rays = o.rays_of(i);
        let p = o.position(i);
        let brightest = rays.iter().map(|r| r.1.max_element()).fold(0.0f32, f32::max).max(1e-12);
        let miss_len = o.grid.spacing.max_element() * 0.5;
        let (mut back, mut miss) = (0, 0);
        for (d, radiance, t) in &rays {
            let (end, colour) = if *t >= 1e30 {
                miss += 1;
                (p + *d * miss_len, egui::Color32::from_gray(120))
            } else if *t < 0.0 {
                back += 1;
                (p + *d * -*t, egui::Color32::from_rgb(255, 0, 255))
            } else {
                let c = (*radiance / brightest).clamp(glam::Vec3::ZERO, glam::Vec3::ONE).powf(0.5);
                (p + *d * *t, egui::Color32::from(egui::Rgba::from_rgb(c.x, c.y, c.z)))
            };
            if let (Some(a), Some(b)) = (to_screen(vp, rect, p), to_screen(vp, rect, end)) {
                painter.line_segment([a, b], egui::Stroke::new(1.0, colour));
            }
        }
        if let Some(at) = to_screen(vp, rect, p) {
            painter.circle_stroke(at, 6.0, egui::Stroke::new(2.0, egui::Color32::YELLOW));
        }
        let c = o.grid.coords(i);
        line = format!(
            "probe {i} ({}, {}, {}) {}: {} rays, {back} on back faces (magenta), {miss} misses (grey), brightest {brightest:.3e}",
            c.x,
            c.y,
            c.z,
            if o.active(i) { "active" } else { "inactive" },
            rays.len()
        );
    }
    text(line);
}
