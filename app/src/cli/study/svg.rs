//! The study's plots as SVG text (no network resources, no fonts to load): error against
//! time per scene, and each job's frame as stacked bars of its passes.

use super::results::Study;
use crate::plot::{tick_label, ticks};

/// Distinct colours for presets and passes (Okabe–Ito, then Tableau's).
const PALETTE: [&str; 14] = [
    "#0072b2", "#e69f00", "#009e73", "#d55e00", "#cc79a7", "#56b4e9", "#f0e442", "#000000", "#4e79a7", "#f28e2b",
    "#59a14f", "#b07aa1", "#9c755f", "#bab0ac",
];

pub fn colour(i: usize) -> &'static str {
    PALETTE[i % PALETTE.len()]
}

/// The colour of pass `name` among `passes`: one hue per stage (the name before its first
/// dot, e.g. `ism` or `soler`), lighter for each further pass of that stage, so that a
/// frame's bars read by stage even with thirty passes.
pub fn pass_colour(passes: &[String], name: &str) -> String {
    let stage = |p: &str| p.split('.').next().unwrap_or(p).to_string();
    let mut stages: Vec<String> = Vec::new();
    for p in passes {
        if !stages.contains(&stage(p)) {
            stages.push(stage(p));
        }
    }
    let si = stages.iter().position(|s| *s == stage(name)).unwrap_or(0);
    let k = passes.iter().filter(|p| stage(p) == stage(name)).position(|p| p == name).unwrap_or(0);
    let hue = (si as f32 * 137.508) % 360.0;
    let light = 32.0 + (k % 4) as f32 * 14.0;
    format!("hsl({hue:.0},{}%,{light:.0}%)", if k % 2 == 0 { 70 } else { 55 })
}

/// Text for SVG and HTML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn text(x: f32, y: f32, size: f32, anchor: &str, s: &str) -> String {
    format!(
        "<text x=\"{x:.1}\" y=\"{y:.1}\" font-size=\"{size}\" text-anchor=\"{anchor}\" font-family=\"sans-serif\">{}</text>\n",
        escape(s)
    )
}

fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(hi.abs() * 0.05).max(1e-6);
    ((lo - pad).max(0.0), hi + pad)
}

/// Mean FLIP against frame time for scene `si`: each job a point in its preset's colour, a
/// preset's sweep points joined in order, the Pareto front as a staircase, the frame budget
/// and the error target of the winners as dashed lines.
pub fn error_against_time(study: &Study, si: usize) -> String {
    let s = &study.scenes[si];
    let (w, h) = (760.0f32, 480.0f32);
    let (left, right, top, bottom) = (70.0f32, 560.0f32, 40.0f32, 420.0f32);
    let (t0, t1) = span(s.rows.iter().map(|r| r.frame_ms).chain([s.equal_time.limit]));
    let (f0, f1) = span(s.rows.iter().map(|r| r.flip).chain([s.equal_error.limit]));
    let x = |t: f64| left + ((t - t0) / (t1 - t0)) as f32 * (right - left);
    let y = |f: f64| bottom - ((f - f0) / (f1 - f0)) as f32 * (bottom - top);
    let mut o = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    o += &text((left + right) / 2.0, 22.0, 15.0, "middle", &format!("{}: error against time", s.info.name));
    let xt = ticks(t0, t1, 7);
    let xs = if xt.len() > 1 { xt[1] - xt[0] } else { 1.0 };
    for t in &xt {
        o += &format!("<line x1=\"{0:.1}\" y1=\"{top}\" x2=\"{0:.1}\" y2=\"{bottom}\" stroke=\"#e4e4e4\"/>\n", x(*t));
        o += &text(x(*t), bottom + 16.0, 11.0, "middle", &tick_label(*t, xs));
    }
    let yt = ticks(f0, f1, 6);
    let ys = if yt.len() > 1 { yt[1] - yt[0] } else { 1.0 };
    for f in &yt {
        o += &format!("<line x1=\"{left}\" y1=\"{0:.1}\" x2=\"{right}\" y2=\"{0:.1}\" stroke=\"#e4e4e4\"/>\n", y(*f));
        o += &text(left - 6.0, y(*f) + 4.0, 11.0, "end", &tick_label(*f, ys));
    }
    o += &format!(
        "<rect x=\"{left}\" y=\"{top}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#222\"/>\n",
        right - left,
        bottom - top
    );
    o += &text((left + right) / 2.0, bottom + 36.0, 12.0, "middle", "GPU time per frame (ms), lower is faster");
    o += &format!(
        "<text x=\"16\" y=\"{:.1}\" font-size=\"12\" font-family=\"sans-serif\" text-anchor=\"middle\" transform=\"rotate(-90 16 {:.1})\">mean FLIP against the truth, lower is closer</text>\n",
        (top + bottom) / 2.0,
        (top + bottom) / 2.0
    );
    // The limits of the winners.
    o += &format!(
        "<line x1=\"{0:.1}\" y1=\"{top}\" x2=\"{0:.1}\" y2=\"{bottom}\" stroke=\"#888\" stroke-dasharray=\"5 4\"/>\n",
        x(s.equal_time.limit)
    );
    o += &format!(
        "<line x1=\"{left}\" y1=\"{0:.1}\" x2=\"{right}\" y2=\"{0:.1}\" stroke=\"#888\" stroke-dasharray=\"2 3\"/>\n",
        y(s.equal_error.limit)
    );
    // The front as a staircase.
    let mut path = String::new();
    for (k, &i) in s.front.iter().enumerate() {
        let r = &s.rows[i];
        if k == 0 {
            path += &format!("M{:.1},{:.1}", x(r.frame_ms), y(r.flip));
        } else {
            path += &format!(" H{:.1} V{:.1}", x(r.frame_ms), y(r.flip));
        }
    }
    if !path.is_empty() {
        o += &format!("<path d=\"{path}\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"2\" opacity=\"0.7\"/>\n");
    }
    // Each preset's points, its sweep joined in order.
    for (pi, preset) in study.presets.iter().enumerate() {
        let pts: Vec<&super::results::Row> = s.rows.iter().filter(|r| r.preset == pi).collect();
        if pts.len() > 1 {
            let d: Vec<String> = pts.iter().map(|r| format!("{:.1},{:.1}", x(r.frame_ms), y(r.flip))).collect();
            o += &format!(
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\"/>\n",
                d.join(" "),
                colour(pi)
            );
        }
        for r in &pts {
            let label =
                if study.params.is_empty() { preset.name.clone() } else { format!("{} p{}", preset.name, r.point) };
            o += &text(x(r.frame_ms) + 8.0, y(r.flip) - 6.0, 10.0, "start", &label);
            let ring = if r.pareto { " stroke=\"#d62728\" stroke-width=\"2\"" } else { "" };
            o += &format!(
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"5\" fill=\"{}\"{ring}><title>{}</title></circle>\n",
                x(r.frame_ms),
                y(r.flip),
                colour(pi),
                escape(&format!("{} point {}: {:.3} ms, FLIP {:.4}", preset.name, r.point, r.frame_ms, r.flip))
            );
        }
    }
    // The legend.
    let mut ly = top + 8.0;
    for (pi, preset) in study.presets.iter().enumerate() {
        o += &format!("<circle cx=\"{:.1}\" cy=\"{ly:.1}\" r=\"5\" fill=\"{}\"/>\n", right + 20.0, colour(pi));
        o += &text(right + 30.0, ly + 4.0, 12.0, "start", &preset.name);
        ly += 20.0;
    }
    ly += 8.0;
    for (stroke, label) in [
        ("stroke=\"#d62728\" stroke-width=\"2\"", "Pareto front"),
        ("stroke=\"#888\" stroke-dasharray=\"5 4\"", "frame budget"),
        ("stroke=\"#888\" stroke-dasharray=\"2 3\"", "error target"),
    ] {
        o += &format!(
            "<line x1=\"{:.1}\" y1=\"{ly:.1}\" x2=\"{:.1}\" y2=\"{ly:.1}\" {stroke}/>\n",
            right + 12.0,
            right + 28.0
        );
        o += &text(right + 30.0, ly + 4.0, 12.0, "start", label);
        ly += 20.0;
    }
    o += "</svg>\n";
    o
}

/// Each job of scene `si` as a horizontal bar of its passes' mean times, stacked in the
/// order the frame runs them, one colour per pass name.
pub fn pass_bars(study: &Study, si: usize) -> String {
    let s = &study.scenes[si];
    let bar = 18.0f32;
    let (left, right, top) = (180.0f32, 620.0f32, 40.0f32);
    let legend_rows = s.passes.len().div_ceil(3) as f32;
    let bottom = top + s.rows.len() as f32 * (bar + 8.0);
    let (w, h) = (760.0f32, bottom + 44.0 + legend_rows * 18.0);
    let max = s.rows.iter().map(|r| r.passes.iter().map(|p| p.1).sum::<f64>()).fold(1e-9, f64::max);
    let sx = |ms: f64| (ms / max) as f32 * (right - left);
    let mut o = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h:.0}\" viewBox=\"0 0 {w} {h:.0}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    );
    o += &text(w / 2.0, 22.0, 15.0, "middle", &format!("{}: time per pass (ms)", s.info.name));
    for (k, r) in s.rows.iter().enumerate() {
        let y = top + k as f32 * (bar + 8.0);
        let label = if study.params.is_empty() {
            study.presets[r.preset].name.clone()
        } else {
            format!("{} p{}", study.presets[r.preset].name, r.point)
        };
        o += &text(left - 8.0, y + bar * 0.7, 12.0, "end", &label);
        let mut at = left;
        for (name, ms) in &r.passes {
            let wd = sx(*ms);
            o += &format!(
                "<rect x=\"{at:.1}\" y=\"{y:.1}\" width=\"{wd:.2}\" height=\"{bar}\" fill=\"{}\"><title>{}</title></rect>\n",
                pass_colour(&s.passes, name),
                escape(&format!("{name}: {ms:.3} ms"))
            );
            at += wd;
        }
        o += &text(at + 6.0, y + bar * 0.7, 11.0, "start", &format!("{:.2}", r.frame_ms));
    }
    for (pi, name) in s.passes.iter().enumerate() {
        let (col, row) = (pi % 3, pi / 3);
        let (x, y) = (20.0 + col as f32 * 245.0, bottom + 24.0 + row as f32 * 18.0);
        o += &format!(
            "<rect x=\"{x:.1}\" y=\"{:.1}\" width=\"12\" height=\"12\" fill=\"{}\"/>\n",
            y - 10.0,
            pass_colour(&s.passes, name)
        );
        o += &text(x + 16.0, y, 11.0, "start", name);
    }
    o += "</svg>\n";
    o
}
