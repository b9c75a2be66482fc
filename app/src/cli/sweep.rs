//! `gi-lab sweep`: renders every point of a grid of settings and measures each — per-pass
//! GPU time, FLIP and RMSE against a ground-truth image, temporal flicker — then writes
//! `sweep.csv` and a Pareto plot of quality against time (`pareto.png`).

use std::path::PathBuf;

use clap::Args;
use gi_render::LabSettings;
use gi_render::settings::{FieldKind, Value};

use crate::plot::{Anchor, Canvas, tick_label, ticks};
use crate::scene_args::SceneArgs;

#[derive(Args, Debug, Clone)]
pub struct SweepArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// A swept setting: `GROUP.FIELD=FROM..TO:STEPS` (numbers, evenly spaced, STEPS ≥ 1;
    /// whole numbers for integer fields) or `GROUP.FIELD=A,B,C` (any values). Repeatable:
    /// every combination is rendered.
    #[arg(long = "param", value_name = "GROUP.FIELD=FROM..TO:STEPS", required_unless_present = "merge")]
    pub params: Vec<String>,
    #[arg(long, default_value = "256x256", value_parser = super::parse_size)]
    pub size: (u32, u32),
    /// Timed frames per point (after 3 warm-up frames); the scene is paused at time 0.
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
    /// Frames over which flicker is measured per point (0: skip).
    #[arg(long, default_value_t = 4)]
    pub flicker_frames: u32,
    /// Ground truth (EXR of the same scene, camera and size at time 0, e.g. from `gi-lab
    /// reference`). When omitted, one is path-traced first: direct light only when the
    /// preset has no indirect technique, else as many bounces as the preset's `vpl.bounces`
    /// for instant radiosity and one for the others.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the path-traced reference when --reference is omitted.
    #[arg(long, default_value_t = 64)]
    pub reference_spp: u32,
    /// Output folder (created): sweep.csv, pareto.png and, when path-traced, reference.exr.
    #[arg(long, required_unless_present = "merge")]
    pub out: Option<PathBuf>,
    /// Render only share I of N of the points (a deterministic, contiguous split) into
    /// OUT/shard-I/; `--merge OUT` joins the shards.
    #[arg(long, value_parser = super::shard::parse_shard, value_name = "I/N")]
    pub shard: Option<super::shard::Shard>,
    /// Join OUT/shard-*/ into OUT's sweep.csv and pareto.png (as an unsharded run writes them).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["shard", "emit_jobs"])]
    pub merge: Option<PathBuf>,
    #[command(flatten)]
    pub emit: super::emit::EmitArgs,
}

/// One swept setting and its values.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    pub path: String,
    pub values: Vec<Value>,
}

/// Parses `GROUP.FIELD=FROM..TO:STEPS` or `GROUP.FIELD=A,B,C`, checking every value
/// against the field's kind and range.
pub fn parse_param(spec: &str) -> Result<Param, String> {
    let (path, rhs) =
        spec.split_once('=').ok_or_else(|| format!("--param '{spec}': expected GROUP.FIELD=FROM..TO:STEPS"))?;
    let path = path.trim().to_string();
    let meta = LabSettings::field(&path).ok_or_else(|| {
        format!("--param '{spec}': no setting named '{path}'; known: {}", LabSettings::all_paths().join(", "))
    })?;
    let rhs = rhs.trim();
    let values: Vec<Value> = if let Some((range, steps)) = rhs.split_once(':').filter(|_| rhs.contains("..")) {
        let (from, to) = range.split_once("..").ok_or_else(|| format!("--param '{spec}': expected FROM..TO"))?;
        let num = |t: &str| t.trim().parse::<f64>().map_err(|_| format!("--param '{spec}': '{t}' is not a number"));
        let (from, to) = (num(from)?, num(to)?);
        let steps: u32 = steps
            .trim()
            .parse()
            .ok()
            .filter(|s| *s >= 1)
            .ok_or_else(|| format!("--param '{spec}': STEPS must be a whole number ≥ 1"))?;
        let at = |i: u32| if steps == 1 { from } else { from + (to - from) * i as f64 / (steps - 1) as f64 };
        let mut v: Vec<Value> = Vec::new();
        for i in 0..steps {
            let x = at(i);
            let value = match meta.kind {
                FieldKind::F32 => Value::F32(x as f32),
                FieldKind::U32 if x >= 0.0 => Value::U32(x.round() as u32),
                FieldKind::U32 => return Err(format!("--param '{spec}': {x} is negative")),
                _ => return Err(format!("--param '{spec}': {path} is not a number; list its values: {path}=A,B")),
            };
            if !v.contains(&value) {
                v.push(value);
            }
        }
        v
    } else {
        rhs.split(',')
            .map(|t| {
                gi_render::settings::parse_value(meta.kind, t.trim()).map_err(|e| format!("--param '{spec}': {e}"))
            })
            .collect::<Result<_, _>>()?
    };
    for v in &values {
        gi_render::settings::check_range(meta, v).map_err(|e| format!("--param '{spec}': {e}"))?;
    }
    Ok(Param { path, values })
}

/// Every combination of the parameters' values, the first parameter varying slowest.
pub fn grid(params: &[Param]) -> Vec<Vec<(String, Value)>> {
    let mut points: Vec<Vec<(String, Value)>> = vec![Vec::new()];
    for p in params {
        points = points
            .into_iter()
            .flat_map(|pt| {
                p.values.iter().map(move |v| {
                    let mut q = pt.clone();
                    q.push((p.path.clone(), v.clone()));
                    q
                })
            })
            .collect();
    }
    points
}

/// `base` with each point's settings, every one checked (the first invalid point is the error).
pub fn settings_at(base: &LabSettings, points: &[Vec<(String, Value)>]) -> Result<Vec<LabSettings>, String> {
    points
        .iter()
        .map(|pt| {
            let mut s = base.clone();
            for (path, v) in pt {
                s.set(path, v)?;
            }
            let errors = s.validate();
            if !errors.is_empty() {
                let list: Vec<String> = errors.iter().map(|e| e.to_string()).collect();
                return Err(format!("point {pt:?} is invalid: {}", list.join("; ")));
            }
            Ok(s)
        })
        .collect()
}

/// The measurements of one point.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointResult {
    /// The point's place in the grid (the CSV's `point`).
    pub index: usize,
    /// The swept settings' values, as the CSV prints them.
    pub assignments: Vec<(String, String)>,
    pub passes: Vec<(String, f64)>,
    pub total_ms: f64,
    pub flip: f64,
    pub rmse: f64,
    pub flicker: Option<f64>,
    pub pareto: bool,
}

/// Marks the points no other point beats in both time and FLIP.
pub fn mark_pareto(points: &mut [PointResult]) {
    let flags = pareto_flags(&points.iter().map(|p| (p.total_ms, p.flip)).collect::<Vec<_>>());
    for (p, f) in points.iter_mut().zip(flags) {
        p.pareto = f;
    }
}

/// For each (time, error) point, whether no other point is at least as good in both and
/// better in one (the Pareto front; equal points are all on it).
pub fn pareto_flags(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .enumerate()
        .map(|(i, &(ti, fi))| {
            !points.iter().enumerate().any(|(j, &(t, f))| j != i && t <= ti && f <= fi && (t < ti || f < fi))
        })
        .collect()
}

pub fn csv(params: &[String], points: &[PointResult]) -> String {
    let mut passes: Vec<String> = Vec::new();
    for p in points {
        for (name, _) in &p.passes {
            if !passes.contains(name) {
                passes.push(name.clone());
            }
        }
    }
    let mut s = String::from("point");
    for p in params {
        s += &format!(",{p}");
    }
    for name in &passes {
        s += &format!(",{name}_ms");
    }
    s += ",total_ms,flip,rmse,flicker,pareto\n";
    for p in points {
        s += &p.index.to_string();
        for (_, v) in &p.assignments {
            s += &format!(",{v}");
        }
        for name in &passes {
            match p.passes.iter().find(|(n, _)| n == name) {
                Some((_, ms)) => s += &format!(",{ms:.4}"),
                None => s += ",",
            }
        }
        let flicker = p.flicker.map(|f| format!("{f:.6}")).unwrap_or_default();
        s += &format!(",{:.4},{:.5},{:.6},{flicker},{}\n", p.total_ms, p.flip, p.rmse, p.pareto);
    }
    s
}

/// Draws FLIP against frame time: every point numbered as in the CSV, the Pareto front as a
/// staircase, and below the plot the settings of the front's points.
pub fn pareto_plot(title: &str, points: &[PointResult]) -> image::RgbaImage {
    let front: Vec<usize> = {
        let mut f: Vec<usize> = (0..points.len()).filter(|&i| points[i].pareto).collect();
        f.sort_by(|&a, &b| points[a].total_ms.total_cmp(&points[b].total_ms));
        f
    };
    let legend_lines = front.len().min(12);
    let (w, h) = (1000u32, 640 + 22 * legend_lines as u32);
    let mut c = Canvas::new(w, h);
    let (left, right, top, bottom) = (90.0f32, 960.0f32, 60.0f32, 560.0f32);
    let (ink, grid, dot, hi) = ([20, 20, 20], [225, 225, 225], [120, 140, 170], [214, 80, 40]);
    let span = |vals: Vec<f64>| {
        let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let pad = ((hi - lo) * 0.08).max(hi.abs() * 0.02).max(1e-6);
        ((lo - pad).max(0.0), hi + pad)
    };
    let (t0, t1) = span(points.iter().map(|p| p.total_ms).collect());
    let (f0, f1) = span(points.iter().map(|p| p.flip).collect());
    let x = |t: f64| left + ((t - t0) / (t1 - t0)) as f32 * (right - left);
    let y = |f: f64| bottom - ((f - f0) / (f1 - f0)) as f32 * (bottom - top);
    c.text((w as f32 / 2.0, 14.0), title, 18.0, ink, Anchor::CenterTop);
    let xt = ticks(t0, t1, 8);
    let xstep = if xt.len() > 1 { xt[1] - xt[0] } else { 1.0 };
    for t in &xt {
        c.line((x(*t), top), (x(*t), bottom), 1.0, grid);
        c.text((x(*t), bottom + 6.0), &tick_label(*t, xstep), 13.0, ink, Anchor::CenterTop);
    }
    let yt = ticks(f0, f1, 6);
    let ystep = if yt.len() > 1 { yt[1] - yt[0] } else { 1.0 };
    for f in &yt {
        c.line((left, y(*f)), (right, y(*f)), 1.0, grid);
        c.text((left - 8.0, y(*f)), &tick_label(*f, ystep), 13.0, ink, Anchor::RightCenter);
    }
    c.line((left, bottom), (right, bottom), 1.5, ink);
    c.line((left, top), (left, bottom), 1.5, ink);
    c.text(
        ((left + right) / 2.0, bottom + 28.0),
        "GPU time per frame (ms), lower is faster",
        15.0,
        ink,
        Anchor::CenterTop,
    );
    c.text((left, top - 8.0), "mean FLIP vs ground truth (lower is closer)", 15.0, ink, Anchor::LeftCenter);
    for win in front.windows(2) {
        let (a, b) = (&points[win[0]], &points[win[1]]);
        c.line((x(a.total_ms), y(a.flip)), (x(b.total_ms), y(a.flip)), 2.0, hi);
        c.line((x(b.total_ms), y(a.flip)), (x(b.total_ms), y(b.flip)), 2.0, hi);
    }
    for (i, p) in points.iter().enumerate() {
        let at = (x(p.total_ms), y(p.flip));
        if p.pareto {
            c.disc(at, 5.5, hi);
        } else {
            c.disc(at, 4.5, dot);
        }
        c.text((at.0 + 8.0, at.1 - 2.0), &i.to_string(), 12.0, ink, Anchor::LeftCenter);
    }
    c.ring((left + 10.0, bottom + 62.0), 5.0, 1.5, hi);
    c.text(
        (left + 22.0, bottom + 62.0),
        "Pareto front (no other point is both faster and closer):",
        14.0,
        ink,
        Anchor::LeftCenter,
    );
    for (k, &i) in front.iter().take(legend_lines).enumerate() {
        let p = &points[i];
        let settings: Vec<String> = p.assignments.iter().map(|(n, v)| format!("{n}={v}")).collect();
        let line =
            format!("#{i}: {:.2} ms, FLIP {:.4}, RMSE {:.4} — {}", p.total_ms, p.flip, p.rmse, settings.join(", "));
        c.text((left + 22.0, bottom + 84.0 + 22.0 * k as f32), &line, 13.0, ink, Anchor::LeftCenter);
    }
    c.img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_lists_parse_with_kinds_and_ranges_checked() {
        let p = parse_param("direct.shadow_map_size=64..1024:3").expect("valid");
        assert_eq!(p.values, [Value::U32(64), Value::U32(544), Value::U32(1024)]);
        let p = parse_param("direct.depth_bias=0..1:5").expect("valid");
        assert_eq!(p.values.len(), 5);
        assert_eq!(p.values[1], Value::F32(0.25));
        // Integer fields round and drop repeats.
        let p = parse_param("direct.pcf_radius=0..1:4").expect("valid");
        assert_eq!(p.values, [Value::U32(0), Value::U32(1)]);
        let p = parse_param("direct.shadows=true,false").expect("valid");
        assert_eq!(p.values, [Value::Bool(true), Value::Bool(false)]);
        assert_eq!(parse_param("direct.depth_bias=2..2:1").expect("one step").values, [Value::F32(2.0)]);
        for bad in ["direct.pcf_radius=0..5:2", "nope.x=1..2:2", "direct.pcf_radius", "direct.depth_bias=a..b:2"] {
            assert!(parse_param(bad).is_err(), "{bad} must be refused");
        }
    }

    #[test]
    fn the_grid_is_the_cartesian_product_first_parameter_slowest() {
        let a = Param { path: "a.x".into(), values: vec![Value::U32(1), Value::U32(2)] };
        let b = Param { path: "b.y".into(), values: vec![Value::Bool(true), Value::Bool(false), Value::Bool(true)] };
        let g = grid(&[a, b]);
        assert_eq!(g.len(), 6);
        assert_eq!(g[0], [("a.x".to_string(), Value::U32(1)), ("b.y".to_string(), Value::Bool(true))]);
        assert_eq!(g[3], [("a.x".to_string(), Value::U32(2)), ("b.y".to_string(), Value::Bool(true))]);
    }

    #[test]
    fn pareto_front_keeps_exactly_the_undominated_points() {
        let pt = |t: f64, f: f64| PointResult {
            index: 0,
            assignments: Vec::new(),
            passes: Vec::new(),
            total_ms: t,
            flip: f,
            rmse: 0.0,
            flicker: None,
            pareto: false,
        };
        let mut pts = vec![pt(1.0, 0.5), pt(2.0, 0.3), pt(2.5, 0.4), pt(3.0, 0.1), pt(3.0, 0.1), pt(4.0, 0.2)];
        mark_pareto(&mut pts);
        let front: Vec<bool> = pts.iter().map(|p| p.pareto).collect();
        assert_eq!(front, [true, true, false, true, true, false]);
    }
}
