//! `gi-lab study` as a user runs it (issue #40 points 2 and 3): at 64² on two shipped scenes
//! and three presets, the page and its files exist and every number and name on the page is
//! results.json's; the page renders in headless Chromium with its images loaded; the study
//! split in three shards by GNU parallel, and in two by a Slurm job array submitted to a real
//! one-node Slurm (issue #55, scripts/slurm-local.sh), merges into the single run's rows; a
//! failed array task, a refused job and a shard written twice say which.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::Duration;

#[path = "support/slurm.rs"]
mod support_slurm;
use support_slurm::slurm;

use serde_json::Value;

fn gi_lab() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_gi-lab"));
    c.env("WGPU_BACKEND", std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "vulkan".into()));
    c
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gi-lab-study-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn repo(p: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(p).display().to_string()
}

/// The study's arguments: two shipped scenes, three presets, a two-point sweep, 64².
fn study_args() -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for s in ["assets/cornell_box.glb", "assets/scenes/chair-on-floor/MixedLightingExample.gltf"] {
        v.extend(["--scene".into(), repo(s)]);
    }
    for p in ["presets/knecht-cornell-256.ron", "presets/soler-quarter-4-64.ron", "presets/gautron-ic-splatting.ron"] {
        v.extend(["--preset".into(), repo(p)]);
    }
    for a in
        ["--param", "direct.pcf_radius=0,2", "--size", "64x64", "--frames", "2", "--flicker-frames", "2", "--spp", "8"]
    {
        v.push(a.into());
    }
    v
}

/// The unsharded study, run once for the tests of this file.
fn single() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let out = temp_dir("single");
        let o = gi_lab().arg("study").args(study_args()).arg("--out").arg(&out).output().expect("runs");
        assert!(o.status.success(), "study failed: {}", String::from_utf8_lossy(&o.stderr));
        out
    })
}

fn json(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("results.json")).expect("results.json")).expect("JSON")
}

/// The value at a dotted path (`scenes.0.rows.2.flip`).
fn at<'a>(v: &'a Value, path: &str) -> &'a Value {
    path.split('.').fold(v, |v, k| match k.parse::<usize>() {
        Ok(i) if v.is_array() => &v[i],
        _ => &v[k],
    })
}

/// The `data-json` spans of the page: (path, text).
fn spans(html: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = html;
    while let Some(i) = rest.find("<span data-json=\"") {
        rest = &rest[i + 17..];
        let q = rest.find('"').expect("closing quote");
        let path = rest[..q].to_string();
        let gt = rest.find('>').expect("tag end");
        let end = rest.find("</span>").expect("closing span");
        out.push((path, rest[gt + 1..end].to_string()));
        rest = &rest[end..];
    }
    out
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", "\"").replace("&amp;", "&")
}

#[test]
fn the_page_and_its_files_exist_and_every_number_on_it_is_results_json() {
    let dir = single();
    let v = json(dir);
    let html = std::fs::read_to_string(dir.join("index.html")).expect("index.html");
    // Files: every image the JSON names, the plots, the CSV.
    let scenes = v["scenes"].as_array().expect("scenes");
    assert_eq!(scenes.len(), 2);
    for s in scenes {
        let rows = s["rows"].as_array().expect("rows");
        assert_eq!(rows.len(), 6, "three presets × two sweep points");
        let truth = s["truth"]["image"].as_str().expect("truth image");
        let mut files = vec![truth.to_string()];
        for r in rows {
            files.push(r["image"].as_str().expect("image").into());
            files.push(r["flip_map"].as_str().expect("flip map").into());
            assert!(html.contains(&format!("src=\"{}\"", r["image"].as_str().expect("image"))), "the page shows {r}");
        }
        let slug = s["info"]["slug"].as_str().expect("slug");
        files.push(format!("plots/{slug}-error-time.svg"));
        files.push(format!("plots/{slug}-passes.svg"));
        for f in files {
            let p = dir.join(&f);
            assert!(p.is_file() && std::fs::metadata(&p).expect("meta").len() > 0, "{f} is missing or empty");
        }
        assert!(s["front"].as_array().is_some_and(|f| !f.is_empty()), "a Pareto front");
        assert!(s["equal_time"]["row"].is_number() && s["equal_error"]["row"].is_number(), "both winners");
    }
    let svg = std::fs::read_to_string(
        dir.join("plots").join(format!("{}-error-time.svg", scenes[0]["info"]["slug"].as_str().expect("slug"))),
    )
    .expect("svg");
    assert_eq!(svg.matches("<circle cx").count(), 6 + 3, "a point per job and a legend dot per preset");
    // Every number and name on the page is results.json's value at the span's path.
    let spans = spans(&html);
    assert!(spans.len() > 100, "the page prints its numbers from the JSON ({} spans)", spans.len());
    for (path, text) in &spans {
        let value = at(&v, path);
        let text = unescape(text);
        match value {
            Value::Number(x) => {
                let x = x.as_f64().expect("f64");
                let decimals = text.split_once('.').map_or(0, |(_, d)| d.len());
                let shown: f64 = text.parse().unwrap_or_else(|_| panic!("{path}: '{text}' is not a number"));
                assert!(
                    (x - shown).abs() <= 0.5 * 10f64.powi(-(decimals as i32)) + 1e-12,
                    "{path}: page {text}, JSON {x}"
                );
            }
            Value::String(s) => assert_eq!(*s, text, "{path}"),
            other => panic!("{path}: the page shows '{text}' where the JSON has {other}"),
        }
    }
    // And no number on the page comes from anywhere else: with the spans, tags, style and
    // script removed, the text holds no digit.
    let mut text = html.clone();
    for cut in [("<style>", "</style>"), ("<script>", "</script>")] {
        if let (Some(a), Some(b)) = (text.find(cut.0), text.find(cut.1)) {
            text.replace_range(a..b + cut.1.len(), "");
        }
    }
    while let Some(a) = text.find("<span data-json=") {
        let b = a + text[a..].find("</span>").expect("closing span") + 7;
        text.replace_range(a..b, "");
    }
    let mut visible = String::new();
    let mut in_tag = false;
    for c in text.chars() {
        match c {
            '<' => in_tag = true,
            '>' => in_tag = false,
            _ if !in_tag => visible.push(c),
            _ => {}
        }
    }
    let digits: Vec<&str> = visible.lines().filter(|l| l.chars().any(|c| c.is_ascii_digit())).collect();
    assert!(digits.is_empty(), "numbers on the page that are not from results.json: {digits:?}");
    // The CSV: a row per scene × preset × point, its first two columns scene and preset, its
    // numbers the JSON's.
    let csv = std::fs::read_to_string(dir.join("results.csv")).expect("results.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    assert_eq!(&header[..3], ["scene", "preset", "point"]);
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 12);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("column {name}"));
    let mut k = 0;
    for s in scenes {
        for r in s["rows"].as_array().expect("rows") {
            assert_eq!(rows[k][col("scene")], s["info"]["name"].as_str().expect("name"));
            for c in ["flip", "rmse", "frame_ms"] {
                let x: f64 = rows[k][col(c)].parse().expect("number");
                assert_eq!(x, r[c].as_f64().expect("f64"), "row {k} {c}");
            }
            k += 1;
        }
    }
}

fn chromium() -> &'static str {
    for c in ["chromium", "chromium-browser", "google-chrome"] {
        if Command::new(c).arg("--version").output().is_ok_and(|o| o.status.success()) {
            return c;
        }
    }
    panic!(
        "no headless Chromium: install it with `sudo apt-get install -y --no-install-recommends chromium` (scripts/test.sh does so as root)"
    );
}

fn browser(extra: &[&str], page: &Path) -> std::process::Output {
    let profile = temp_dir("chromium-profile");
    Command::new(chromium())
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--virtual-time-budget=5000"])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs")
}

#[test]
fn the_page_renders_in_headless_chromium_with_every_image_loaded() {
    let dir = single();
    let page = dir.join("index.html");
    let dom = browser(&["--dump-dom"], &page);
    let dom = String::from_utf8_lossy(&dom.stdout);
    let attr = |name: &str| -> Option<usize> {
        let i = dom.find(&format!("{name}=\""))? + name.len() + 2;
        dom[i..].split('"').next()?.parse().ok()
    };
    // Per scene: the truth, two images per job, two plots.
    let expected = 2 * (1 + 2 * 6 + 2);
    assert_eq!(attr("data-images-broken"), Some(0), "broken images on the page");
    assert_eq!(attr("data-images-loaded"), Some(expected), "images loaded");
    let shot = dir.join("chromium.png");
    let o = browser(&["--window-size=1300,1400", &format!("--screenshot={}", shot.display())], &page);
    assert!(shot.is_file(), "no screenshot: {}", String::from_utf8_lossy(&o.stderr));
    let img = image::open(&shot).expect("PNG").to_rgb8();
    // The image cells are not blank: the first scene's figures hold the rendered Cornell box,
    // whose red and green walls no page colour has, and FLIP maps.
    let (mut red, mut green, mut purple) = (0, 0, 0);
    for p in img.pixels() {
        let [r, g, b] = p.0.map(i32::from);
        // FLIP's maps in inferno: dark purple to orange.
        if b > g + 40 && r > g + 20 {
            purple += 1;
        }
        if r > g + 25 && r > b + 25 {
            red += 1;
        }
        if g > r + 25 && g > b + 25 {
            green += 1;
        }
    }
    assert!(
        red > 300 && green > 300 && purple > 300,
        "the screenshot shows no rendered images or FLIP maps (red {red}, green {green}, purple {purple} pixels)"
    );
}

/// The columns of a results.csv that do not depend on the machine's speed, row by row.
fn deterministic_rows(dir: &Path) -> Vec<Vec<String>> {
    let csv = std::fs::read_to_string(dir.join("results.csv")).expect("results.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    // Times (and what is derived from them: the front) differ from run to run.
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| !(header[i].ends_with("_ms") || header[i] == "pareto" || header[i] == "machine"))
        .collect();
    let mut rows = vec![keep.iter().map(|&i| header[i].to_string()).collect()];
    rows.extend(lines.map(|l| {
        let cells: Vec<&str> = l.split(',').collect();
        keep.iter().map(|&i| cells[i].to_string()).collect()
    }));
    rows
}

fn assert_merged_equals_single(merged: &Path) {
    let single = single();
    assert_eq!(deterministic_rows(merged), deterministic_rows(single), "the merged rows differ from the single run's");
    let (a, b) = (json(merged), json(single));
    assert_eq!(a["spec"], b["spec"]);
    assert_eq!(
        a["command"].as_str().map(|c| c.replace(&merged.display().to_string(), "DIR")),
        b["command"].as_str().map(|c| c.replace(&single.display().to_string(), "DIR"))
    );
    for (sa, sb) in a["scenes"].as_array().expect("scenes").iter().zip(b["scenes"].as_array().expect("scenes")) {
        for (ra, rb) in sa["rows"].as_array().expect("rows").iter().zip(sb["rows"].as_array().expect("rows")) {
            assert_eq!(ra["job"], rb["job"]);
            let (ia, ib) =
                (merged.join(ra["image"].as_str().expect("img")), single.join(rb["image"].as_str().expect("img")));
            assert_eq!(
                std::fs::read(&ia).expect("merged image"),
                std::fs::read(&ib).expect("single image"),
                "{}",
                ia.display()
            );
        }
    }
    assert!(merged.join("index.html").is_file());
}

#[test]
fn three_shards_run_by_gnu_parallel_merge_into_the_single_runs_rows() {
    let out = temp_dir("parallel");
    let o = gi_lab()
        .arg("study")
        .args(study_args())
        .arg("--out")
        .arg(&out)
        .args(["--emit-jobs", "parallel", "--shards", "3"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let script = out.join("study.parallel");
    let text = std::fs::read_to_string(&script).expect("study.parallel");
    assert!(text.contains("parallel ") && text.contains("--merge"), "{text}");
    if Command::new("parallel").arg("--version").output().is_err() {
        panic!(
            "GNU parallel is missing: install it with `sudo apt-get install -y parallel` (scripts/test.sh does so as root)"
        );
    }
    let o = Command::new("bash").arg(&script).output().expect("bash runs");
    assert!(
        o.status.success(),
        "the parallel study failed: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    for i in 1..=3 {
        assert!(out.join(format!("shard-{i}/shard.json")).is_file(), "shard {i}");
    }
    assert_merged_equals_single(&out);
}

/// `study` with the study's arguments (`study_args`) into `out`: a command line to extend.
fn study_into(out: &Path) -> Vec<String> {
    let mut v: Vec<String> = vec!["study".into()];
    v.extend(study_args());
    v.extend(["--out".into(), out.display().to_string()]);
    v
}

/// Runs `gi-lab ARGS` and gives its output, failing with its error when it fails.
fn run_ok(args: &[String]) -> std::process::Output {
    let o = gi_lab().args(args).output().expect("runs");
    assert!(o.status.success(), "gi-lab {}: {}", args.join(" "), String::from_utf8_lossy(&o.stderr));
    o
}

/// `study.slurm` submitted with the real `sbatch` to a one-node Slurm (issue #55): the array's
/// tasks and the merge complete, with the partition, time limit and account asked for, each
/// task's output in OUT/logs/, and the merged report equals the single run.
#[test]
fn a_slurm_job_array_on_a_real_slurm_merges_into_the_single_runs_rows() {
    let cluster = slurm();
    let out = temp_dir("slurm");
    let mut args = study_into(&out);
    for a in ["--emit-jobs", "slurm", "--shards", "2", "--slurm-gpus", "0", "--slurm-partition", "lab"] {
        args.push(a.into());
    }
    args.extend(["--slurm-time", "20", "--slurm-account", "gi_lab_tests"].map(String::from));
    run_ok(&args);
    let text = std::fs::read_to_string(out.join("study.slurm")).expect("study.slurm");
    assert!(!text.contains("gpus-per-task"), "--slurm-gpus 0 asks for no GPU:\n{text}");
    let (array, merge) = cluster.submit(&out.join("study.slurm"));
    // A merge by hand before the array has ended writes nothing and says which shards lack.
    let o = gi_lab().arg("study").arg("--merge").arg(&out).output().expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("shards are not there, so nothing was written") && err.contains("shard 2/2"), "{err}");
    assert!(!out.join("index.html").exists(), "no partial report");
    let took = cluster.wait(&[&array, &merge], Duration::from_secs(400), &out.join("logs"));
    let tasks = cluster.jobs(&array);
    assert_eq!(tasks.len(), 2, "two array tasks");
    for t in tasks.iter().chain(&cluster.jobs(&merge)) {
        let what = format!("job {} (task {})", t.get("JobId"), t.get("ArrayTaskId"));
        assert_eq!(t.get("JobState"), "COMPLETED", "{what}");
        assert_eq!(t.get("Partition"), "lab", "{what}");
        assert_eq!(t.get("TimeLimit"), "00:20:00", "{what}");
        assert_eq!(t.get("Account"), "gi_lab_tests", "{what}");
        assert_eq!(t.get("WorkDir"), out.display().to_string(), "{what}");
    }
    for log in ["shard-1.log", "shard-2.log", "merge.log"] {
        assert!(out.join("logs").join(log).is_file(), "logs/{log}");
    }
    let merge_log = std::fs::read_to_string(out.join("logs/merge.log")).expect("merge.log");
    assert!(merge_log.contains("wrote") && merge_log.contains("index.html"), "{merge_log}");
    eprintln!("Slurm: array {array} (2 tasks) and merge {merge} done in {took:.1?}");
    assert_merged_equals_single(&out);
}

/// A task of the array fails (its scene removed after the script was written): the merge job
/// never runs, and `--merge` by hand names the failed shard, its job and why.
#[test]
fn a_failed_array_task_cancels_the_merge_and_the_merge_by_hand_names_it() {
    let cluster = slurm();
    let out = temp_dir("slurm-fail");
    let scenes = temp_dir("slurm-fail-scenes");
    let mut args: Vec<String> = vec!["study".into()];
    for s in ["a.glb", "b.glb"] {
        std::fs::copy(repo("assets/cornell_box.glb"), scenes.join(s)).expect("copy the scene");
        args.extend(["--scene".into(), scenes.join(s).display().to_string()]);
    }
    args.extend(["--preset".into(), repo("presets/soler-quarter-4-64.ron")]);
    for a in ["--size", "32x32", "--frames", "1", "--flicker-frames", "0", "--spp", "2"] {
        args.push(a.into());
    }
    args.extend(["--out".into(), out.display().to_string()]);
    args.extend(["--emit-jobs", "slurm", "--shards", "2", "--slurm-gpus", "0"].map(String::from));
    run_ok(&args);
    std::fs::remove_file(scenes.join("b.glb")).expect("remove b.glb");
    let (array, merge) = cluster.submit(&out.join("study.slurm"));
    cluster.wait(&[&array, &merge], Duration::from_secs(300), &out.join("logs"));
    let state = |task: &str| {
        cluster.jobs(&array).iter().find(|t| t.get("ArrayTaskId") == task).map(|t| t.get("JobState").to_string())
    };
    assert_eq!(state("1").as_deref(), Some("COMPLETED"));
    assert_eq!(state("2").as_deref(), Some("FAILED"));
    // --kill-on-invalid-dep: the merge is cancelled, not left pending forever.
    let m = cluster.jobs(&merge);
    assert_eq!((m[0].get("JobState"), m[0].get("Reason")), ("CANCELLED", "DependencyNeverSatisfied"));
    assert!(!out.join("logs/merge.log").exists() && !out.join("index.html").exists(), "no merge, no report");
    let o = gi_lab().arg("study").arg("--merge").arg(&out).output().expect("runs");
    assert_eq!(o.status.code(), Some(2), "a missing shard is the user's input");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("shard 2/2 failed (Slurm job {array}_2 on host")), "{err}");
    assert!(err.contains("b.glb") && err.contains("logs/shard-2.log"), "{err}");
    assert!(!out.join("index.html").exists() && !out.join("results.csv").exists(), "no partial report");
}

/// A Slurm that refuses the job (a partition it lacks), no `sbatch` on the PATH, a shard
/// another live run writes: each a clear message naming the job and shard, nothing submitted.
#[test]
fn slurm_refusals_and_a_shard_written_twice_say_which() {
    let cluster = slurm();
    let out = temp_dir("slurm-refused");
    let args = study_into(&out);
    let script = out.join("study.slurm");
    // A GPU per task (the default) where the node has no GPU resource, then a partition the
    // cluster lacks: Slurm refuses both, the script says so with Slurm's reason.
    for (extra, reason) in
        [(&[][..], "gres"), (&["--slurm-gpus", "0", "--slurm-partition", "nowhere"][..], "partition")]
    {
        let mut a = args.clone();
        a.extend(["--emit-jobs", "slurm", "--shards", "2"].map(String::from));
        a.extend(extra.iter().map(|s| s.to_string()));
        run_ok(&a);
        let o = cluster.command("bash").arg(&script).output().expect("bash runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "Slurm must refuse ({reason})");
        assert!(err.contains("Slurm refused the job array gi-lab-study (2 shards of the study into"), "{err}");
        assert!(err.to_lowercase().contains(reason), "Slurm's reason: {err}");
        if reason == "gres" {
            assert!(err.contains("write the script again with --slurm-gpus 0"), "{err}");
        }
        assert!(!String::from_utf8_lossy(&o.stdout).contains("submitted"), "nothing submitted");
    }
    let o = Command::new("/bin/bash").arg(&script).env("PATH", "/nonexistent").output().expect("bash runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("no sbatch on the PATH: submit the job array gi-lab-study"), "{err}");
    // Shard 1 written by a live Slurm job of this host: a second run of it is refused.
    let mut holder = Command::new("sleep").arg("60").spawn().expect("sleep");
    let shard = out.join("shard-1");
    std::fs::create_dir_all(&shard).expect("shard-1");
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").expect("hostname").trim().to_string();
    let status = serde_json::json!({
        "state": "running", "shard": { "index": 1, "count": 2 },
        "writer": { "job": "77_1", "host": host, "pid": holder.id() },
        "started": 0, "ended": null, "error": null
    });
    std::fs::write(shard.join("status.json"), status.to_string()).expect("status.json");
    let mut again = study_into(&out);
    again.extend(["--shard".into(), "1/2".into()]);
    let o = gi_lab().args(&again).output().expect("runs");
    let _ = holder.kill();
    let _ = holder.wait();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("shard 1/2 of") && err.contains("already being written by Slurm job 77_1"), "{err}");
    assert!(!shard.join("shard.json").exists());
}

#[test]
fn a_merge_with_a_missing_shard_says_which_and_writes_nothing() {
    let out = temp_dir("missing");
    let o = gi_lab()
        .arg("study")
        .args(study_args())
        .arg("--out")
        .arg(&out)
        .args(["--shard", "2/3"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = gi_lab().arg("study").arg("--merge").arg(&out).output().expect("runs");
    assert_eq!(o.status.code(), Some(2), "a missing shard is the user's input");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("2 of 3 shards are not there, so nothing was written"), "{err}");
    assert!(err.contains("shard 1/3 has not run") && err.contains("shard 3/3 has not run"), "{err}");
    assert!(!out.join("index.html").exists() && !out.join("results.csv").exists());
}

/// The columns of a sweep.csv that do not depend on the machine's speed, row by row.
fn sweep_rows(dir: &Path) -> Vec<Vec<String>> {
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).expect("sweep.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let keep: Vec<usize> =
        (0..header.len()).filter(|&i| !header[i].ends_with("_ms") && header[i] != "pareto").collect();
    lines
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            keep.iter().map(|&i| c[i].to_string()).collect()
        })
        .collect()
}

/// `sweep … --emit-jobs slurm` takes the same path as the study (issues #40 point 3 and #55):
/// its three shards as a job array on the one-node Slurm, the merge as the dependent job, the
/// merged CSV the unsharded run's points (settings, FLIP, RMSE and flicker; times differ); a
/// merge that lacks a shard's results names it.
#[test]
fn a_sweep_as_a_slurm_job_array_merges_into_the_unsharded_points() {
    let cluster = slurm();
    let args: Vec<String> = [
        "sweep",
        "--size",
        "32x24",
        "--frames",
        "1",
        "--flicker-frames",
        "2",
        "--reference-spp",
        "2",
        "--param",
        "direct.pcf_radius=0..2:3",
        "--param",
        "direct.shadows=true,false",
    ]
    .map(String::from)
    .to_vec();
    let single = temp_dir("sweep-single");
    let mut a = args.clone();
    a.extend(["--out".into(), single.display().to_string()]);
    run_ok(&a);
    let sharded = temp_dir("sweep-slurm");
    let mut a = args.clone();
    a.extend(["--out".into(), sharded.display().to_string()]);
    a.extend(["--emit-jobs", "slurm", "--shards", "3", "--slurm-gpus", "0"].map(String::from));
    run_ok(&a);
    let (array, merge) = cluster.submit(&sharded.join("sweep.slurm"));
    cluster.wait(&[&array, &merge], Duration::from_secs(300), &sharded.join("logs"));
    for t in cluster.jobs(&array).iter().chain(&cluster.jobs(&merge)) {
        assert_eq!(t.get("JobState"), "COMPLETED", "job {} (task {})", t.get("JobId"), t.get("ArrayTaskId"));
    }
    assert!(sharded.join("pareto.png").is_file());
    let (a, b) = (sweep_rows(&sharded), sweep_rows(&single));
    assert_eq!(a.len(), 6);
    assert_eq!(a, b, "the merged points differ from the unsharded run's");
    std::fs::remove_file(sharded.join("shard-2/sweep.json")).expect("shard 2's results");
    let o = gi_lab().args(["sweep", "--merge"]).arg(&sharded).output().expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("shard 2/3 ended (Slurm job {array}_2 on host")), "{err}");
}
