//! The study's page, `index.html`: opens from the file system, loads nothing from a network.
//! Every number and name on it is printed from `results.json`'s values and carries that
//! value's path (`data-json="scenes.0.rows.2.flip"`), so a test can check the page against the
//! file; the prose around them holds no number of its own.

use super::results::{Row, SceneReport, Study, Winner};
use super::svg::escape;

pub fn error_plot_file(s: &SceneReport) -> String {
    format!("plots/{}-error-time.svg", s.info.slug)
}

pub fn passes_plot_file(s: &SceneReport) -> String {
    format!("plots/{}-passes.svg", s.info.slug)
}

/// A number printed from results.json at `path` with `decimals` decimals.
fn n(path: &str, v: f64, decimals: usize) -> String {
    format!("<span data-json=\"{path}\">{v:.decimals$}</span>")
}

/// A string printed from results.json at `path`.
fn t(path: &str, s: &str) -> String {
    format!("<span data-json=\"{path}\">{}</span>", escape(s))
}

const STYLE: &str = "
body { font-family: sans-serif; margin: 24px auto; max-width: 1280px; color: #222; }
h1 { margin-bottom: 4px; }
nav a { margin-right: 12px; }
section { border-top: 1px solid #ccc; margin-top: 28px; }
.answer { background: #f4f7fb; border-left: 4px solid #0072b2; padding: 6px 14px; }
.grid { display: flex; flex-wrap: wrap; gap: 14px; }
figure { margin: 0; background: #fafafa; border: 1px solid #ddd; padding: 6px; }
figure img { width: 160px; height: auto; image-rendering: pixelated; display: block; }
.pair { display: flex; gap: 4px; }
figcaption { font-size: 12px; max-width: 330px; margin-top: 4px; }
figure.truth { border-color: #333; }
table { border-collapse: collapse; font-size: 13px; margin: 10px 0; }
td, th { border: 1px solid #ccc; padding: 3px 8px; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.front td:first-child { font-weight: bold; }
.plots img { max-width: 100%; }
code, pre { font-size: 12px; white-space: pre-wrap; word-break: break-all; }
.diff li { font-family: monospace; font-size: 12px; }
";

/// After every image has loaded or failed, the body says how many did which (read by the
/// headless-browser test): `data-images-loaded` and `data-images-broken`.
const CHECK_IMAGES: &str = "
window.addEventListener('load', function () {
  var imgs = Array.prototype.slice.call(document.images);
  var broken = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); });
  document.body.setAttribute('data-images-loaded', String(imgs.length - broken.length));
  document.body.setAttribute('data-images-broken', String(broken.length));
});
";

fn row_label(study: &Study, si: usize, ri: usize, r: &Row) -> String {
    let mut s = t(&format!("presets.{}.name", r.preset), &study.presets[r.preset].name);
    if !study.params.is_empty() {
        let a: Vec<String> = r
            .assignments
            .iter()
            .enumerate()
            .map(|(k, (p, v))| {
                format!(
                    "{}={}",
                    t(&format!("scenes.{si}.rows.{ri}.assignments.{k}.0"), p),
                    t(&format!("scenes.{si}.rows.{ri}.assignments.{k}.1"), v)
                )
            })
            .collect();
        s += &format!(" ({})", a.join(", "));
    }
    s
}

fn winner_line(study: &Study, si: usize, which: &str, w: &Winner) -> String {
    let s = &study.scenes[si];
    let base = format!("scenes.{si}.{which}");
    let limit = if which == "equal_time" {
        format!("within a frame budget of {} ms", n(&format!("{base}.limit"), w.limit, 3))
    } else {
        format!("reaching a mean FLIP of {}", n(&format!("{base}.limit"), w.limit, 4))
    };
    let from = t(&format!("{base}.limit_from"), &w.limit_from);
    let title = if which == "equal_time" { "Equal time" } else { "Equal error" };
    match w.row {
        Some(ri) => {
            let r = &s.rows[ri];
            format!(
                "<p><b>{title}</b> — {limit} (from {from}): <b>{}</b>, {} ms, FLIP {}.</p>\n",
                row_label(study, si, ri, r),
                n(&format!("scenes.{si}.rows.{ri}.frame_ms"), r.frame_ms, 3),
                n(&format!("scenes.{si}.rows.{ri}.flip"), r.flip, 4)
            )
        }
        None => format!("<p><b>{title}</b> — {limit} (from {from}): no job qualifies.</p>\n"),
    }
}

fn scene_section(study: &Study, si: usize) -> String {
    let s = &study.scenes[si];
    let mut o =
        format!("<section id=\"{}\">\n<h2>{}</h2>\n", s.info.slug, t(&format!("scenes.{si}.info.name"), &s.info.name));
    if let Some(f) = &s.info.file {
        o += &format!("<p>File: <code>{}</code></p>\n", t(&format!("scenes.{si}.info.file"), f));
    }
    o += "<div class=\"answer\">\n";
    o += &winner_line(study, si, "equal_time", &s.equal_time);
    o += &winner_line(study, si, "equal_error", &s.equal_error);
    let front: Vec<String> = s
        .front
        .iter()
        .map(|&ri| {
            let r = &s.rows[ri];
            format!(
                "{} ({} ms, FLIP {})",
                row_label(study, si, ri, r),
                n(&format!("scenes.{si}.rows.{ri}.frame_ms"), r.frame_ms, 3),
                n(&format!("scenes.{si}.rows.{ri}.flip"), r.flip, 4)
            )
        })
        .collect();
    o += &format!(
        "<p><b>Pareto front</b>, fastest first (no other job is both faster and closer): {}.</p>\n</div>\n",
        front.join(" → ")
    );
    // The images.
    let truth_note = if s.truth.cached {
        "from the cache".to_string()
    } else if s.truth.tracer.is_empty() {
        format!("traced in {} s", n(&format!("scenes.{si}.truth.seconds"), s.truth.seconds, 1))
    } else {
        format!(
            "traced by {} in {} s",
            t(&format!("scenes.{si}.truth.tracer"), &s.truth.tracer),
            n(&format!("scenes.{si}.truth.seconds"), s.truth.seconds, 1)
        )
    };
    o += "<h3>Images and FLIP maps</h3>\n<div class=\"grid\">\n";
    o += &format!(
        "<figure class=\"truth\"><img src=\"{}\" alt=\"truth\"><figcaption><b>Truth</b>: path traced, {} bounce(s), {} spp, {truth_note}</figcaption></figure>\n",
        escape(&s.truth.image),
        n("spec.bounces", study.spec.bounces as f64, 0),
        n("spec.spp", study.spec.spp as f64, 0),
    );
    for (ri, r) in s.rows.iter().enumerate() {
        o += &format!(
            "<figure><div class=\"pair\"><img src=\"{}\" alt=\"image\"><img src=\"{}\" alt=\"FLIP map\"></div><figcaption><b>{}</b> — {}<br>FLIP {} · {} ms</figcaption></figure>\n",
            escape(&r.image),
            escape(&r.flip_map),
            row_label(study, si, ri, r),
            t(&format!("scenes.{si}.rows.{ri}.technique"), &r.technique),
            n(&format!("scenes.{si}.rows.{ri}.flip"), r.flip, 4),
            n(&format!("scenes.{si}.rows.{ri}.frame_ms"), r.frame_ms, 3),
        );
    }
    o += "</div>\n<p>Each job: its image (left) and its FLIP map against the truth (right; black: no visible difference, yellow: large).</p>\n";
    // The table.
    let many_machines = study.machines.len() > 1;
    o += "<h3>Measurements</h3>\n<table>\n<tr><th>preset</th><th>technique</th><th>mean FLIP</th><th>RMSE</th><th>flicker</th><th>frame ms (GPU)</th><th>wall ms</th>";
    if many_machines {
        o += "<th>machine</th>";
    }
    o += "</tr>\n";
    for (ri, r) in s.rows.iter().enumerate() {
        let p = format!("scenes.{si}.rows.{ri}");
        let flicker = match r.flicker {
            Some(f) => n(&format!("{p}.flicker"), f, 6),
            None => "—".into(),
        };
        o += &format!(
            "<tr{}><td>{}</td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{flicker}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>",
            if r.pareto { " class=\"front\"" } else { "" },
            row_label(study, si, ri, r),
            t(&format!("{p}.technique"), &r.technique),
            n(&format!("{p}.flip"), r.flip, 4),
            n(&format!("{p}.rmse"), r.rmse, 5),
            n(&format!("{p}.frame_ms"), r.frame_ms, 3),
            n(&format!("{p}.wall_ms"), r.wall_ms, 3),
        );
        if many_machines {
            o += &format!("<td>{}</td>", t(&format!("machines.{}.host", r.machine), &study.machines[r.machine].host));
        }
        o += "</tr>\n";
    }
    o += "</table>\n<p>Bold: on the Pareto front. Frame ms: the passes' mean times summed; wall ms: one frame's call, waits included.</p>\n";
    o += &format!(
        "<div class=\"plots\"><h3>Time per pass</h3><img src=\"{}\" alt=\"time per pass\">\n<h3>Error against time</h3><img src=\"{}\" alt=\"error against time\"></div>\n</section>\n",
        passes_plot_file(s),
        error_plot_file(s)
    );
    o
}

/// The whole page.
pub fn html(study: &Study) -> String {
    let mut o = format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>GI Lab study</title><style>{STYLE}</style></head>\n<body>\n<h1>GI Lab study</h1>\n"
    );
    let sweep = if study.params.is_empty() {
        String::new()
    } else {
        let p: Vec<String> = study.params.iter().enumerate().map(|(k, p)| t(&format!("params.{k}"), p)).collect();
        format!(", sweeping {}", p.join(", "))
    };
    o += &format!(
        "<p>{} jobs: every scene × every preset{sweep}, at {}×{}, {} timed frames per job with the scene paused at the start of its animation. Truth: the path tracer, {} bounce(s), {} spp.</p>\n",
        n("jobs", study.jobs as f64, 0),
        n("spec.size.0", study.spec.size.0 as f64, 0),
        n("spec.size.1", study.spec.size.1 as f64, 0),
        n("spec.frames", study.spec.frames as f64, 0),
        n("spec.bounces", study.spec.bounces as f64, 0),
        n("spec.spp", study.spec.spp as f64, 0),
    );
    let links: Vec<String> = study
        .scenes
        .iter()
        .enumerate()
        .map(|(si, s)| {
            format!("<a href=\"#{}\">{}</a>", s.info.slug, t(&format!("scenes.{si}.info.name"), &s.info.name))
        })
        .collect();
    o += &format!(
        "<nav>Scenes: {} · <a href=\"#presets\">presets</a> · <a href=\"#machine\">machine</a> · <a href=\"results.csv\">results.csv</a> · <a href=\"results.json\">results.json</a></nav>\n",
        links.join(" ")
    );
    for si in 0..study.scenes.len() {
        o += &scene_section(study, si);
    }
    o += "<section id=\"presets\"><h2>Presets</h2>\n<p>Each preset's settings that differ from the defaults (the study's overrides included).</p>\n";
    for (pi, p) in study.presets.iter().enumerate() {
        o += &format!(
            "<h3>{}</h3>\n<p>{}{}</p>\n<ul class=\"diff\">\n",
            t(&format!("presets.{pi}.name"), &p.name),
            t(&format!("presets.{pi}.technique"), &p.technique),
            match &p.file {
                Some(f) => format!(" — <code>{}</code>", t(&format!("presets.{pi}.file"), f)),
                None => " — shipped with GI Lab".into(),
            }
        );
        if p.diff.is_empty() {
            o += "<li>the defaults</li>\n";
        }
        for (k, d) in p.diff.iter().enumerate() {
            o += &format!("<li>{}</li>\n", t(&format!("presets.{pi}.diff.{k}"), d));
        }
        o += "</ul>\n";
    }
    o += "</section>\n<section id=\"machine\"><h2>Machine and version</h2>\n<table><tr><th>host</th><th>system</th><th>processor</th><th>cores</th><th>adapter</th><th>timing</th></tr>\n";
    for (mi, m) in study.machines.iter().enumerate() {
        let p = format!("machines.{mi}");
        o += &format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td class=\"num\">{}</td><td>{}</td><td>{}</td></tr>\n",
            t(&format!("{p}.host"), &m.host),
            t(&format!("{p}.os"), &m.os),
            t(&format!("{p}.cpu"), &m.cpu),
            n(&format!("{p}.cores"), m.cores as f64, 0),
            t(&format!("{p}.adapter"), &m.adapter),
            t(&format!("{p}.timing_source"), &m.timing_source),
        );
    }
    o += &format!(
        "</table>\n<p>GI Lab {}. The command that reproduces this report:</p>\n<pre><code>{}</code></pre>\n</section>\n",
        t("gi_lab_version", &study.gi_lab_version),
        t("command", &study.command)
    );
    o += &format!("<script>{CHECK_IMAGES}</script>\n</body></html>\n");
    o
}
