//! The `gi-lab` binary as a user runs it. These tests live in the app package (not in
//! tests/) because Cargo builds a package's binary only for that package's own integration
//! tests (`CARGO_BIN_EXE_gi-lab`).

use std::path::PathBuf;
use std::process::Command;

fn gi_lab() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_gi-lab"));
    c.env("WGPU_BACKEND", std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "vulkan".into()));
    c
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gi-lab-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

#[test]
fn render_writes_final_png_and_buffers() {
    let out = temp_dir("render");
    let o = gi_lab()
        .args(["render", "--size", "64x48", "--frames", "2", "--buffer", "gbuffer.normal", "--buffer", "final.hdr"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "render failed: {}", String::from_utf8_lossy(&o.stderr));
    // The default preset's stages 3–7 as the frame runs them (Knecht's chain).
    let stdout = String::from_utf8_lossy(&o.stdout);
    let steps = stdout.lines().find_map(|l| l.strip_prefix("steps: ")).expect("a steps line");
    assert!(steps.starts_with("3 knecht.vpls → 4 knecht.visibility → 6 knecht.gather"), "{steps}");
    let img = image::open(out.join("final.png")).expect("final.png is a PNG").to_rgba8();
    assert_eq!(img.dimensions(), (64, 48));
    assert!(img.pixels().any(|p| p.0[0] > 20), "final.png is black");
    assert!(out.join("gbuffer.normal.png").exists());
    assert!(out.join("gbuffer.normal.exr").exists(), "float buffers are also written as EXR");
    let hdr = image::open(out.join("final.hdr.exr")).expect("EXR reads back").to_rgba32f();
    assert_eq!(hdr.dimensions(), (64, 48));
    assert!(hdr.pixels().any(|p| p.0[0] > 0.0));
}

#[test]
fn compare_reports_metrics_and_writes_the_flip_map() {
    let out = temp_dir("compare");
    let render = |name: &str, ev: &str| {
        let o = gi_lab()
            .args(["render", "--size", "48x48", "--buffer", "final.hdr", "--set"])
            .arg(format!("tonemap.exposure_ev={ev}"))
            .arg("--out")
            .arg(out.join(name))
            .output()
            .expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    render("a", "0");
    render("b", "2");
    let compare = |t: &str, r: &str, extra: &[&str]| {
        let o =
            gi_lab().arg("compare").arg(out.join(t)).arg(out.join(r)).args(extra).arg("--json").output().expect("runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice::<serde_json::Value>(&o.stdout).expect("JSON")
    };
    let same = compare("a/final.png", "a/final.png", &[]);
    assert_eq!(same["rmse"], 0.0);
    assert_eq!(same["flip"], 0.0);
    let map = out.join("flip.png");
    let diff = compare("b/final.png", "a/final.png", &["--flip-map", &map.to_string_lossy()]);
    assert!(diff["flip"].as_f64().expect("flip") > 0.0 && diff["rmse"].as_f64().expect("rmse") > 0.0);
    assert_eq!(image::open(&map).expect("FLIP map PNG").width(), 48);
    // The HDR buffers do not depend on the exposure: identical radiance.
    let hdr = compare("b/final.hdr.exr", "a/final.hdr.exr", &[]);
    assert_eq!(hdr["hdr"], true);
    assert_eq!(hdr["rmse"], 0.0);
}

#[test]
fn reference_path_traces_three_exr_files() {
    let out = temp_dir("reference");
    let full = out.join("ref.exr");
    let o = gi_lab()
        .args(["reference", "--size", "24x16", "--spp", "2", "--bounces", "1", "--out"])
        .arg(&full)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["ref.exr", "ref.direct.exr", "ref.indirect.exr"] {
        let img = image::open(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}")).to_rgba32f();
        assert_eq!(img.dimensions(), (24, 16));
        assert!(img.pixels().any(|p| p.0[0] > 0.0), "{f} is black");
    }
    // The same truth on the GPU (issue #56): punctual light is exact in both tracers, so their
    // direct images are the same but for a few pixels on the box's edges.
    let gpu = out.join("gpu.exr");
    let o = gi_lab()
        .args(["reference", "--gpu", "--size", "24x16", "--spp", "2", "--bounces", "1", "--out"])
        .arg(&gpu)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("on the GPU"), "{}", String::from_utf8_lossy(&o.stdout));
    let read = |f: &str| image::open(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}")).to_rgba32f();
    let (a, b) = (read("ref.direct.exr"), read("gpu.direct.exr"));
    let off = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| (0..3).any(|k| (p.0[k] - q.0[k]).abs() > 1e-3 * p.0[k].max(0.05)))
        .count();
    assert!(off <= 8, "{off} of 384 direct pixels differ between the CPU and the GPU truth");
    // bench measures the renderer against it (same scene, camera and size).
    let o = gi_lab()
        .args(["bench", "--size", "24x16", "--frames", "1", "--json", "--set", "pipeline.gather=None", "--reference"])
        .arg(out.join("ref.direct.exr"))
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let (flip, rmse) = (v["flip"].as_f64().expect("flip"), v["rmse"].as_f64().expect("rmse"));
    // The GPU direct pass against path-traced direct light: close, but PCF and
    // rasterisation are not exact.
    assert!(flip > 0.0 && flip < 0.05, "FLIP vs path-traced direct light {flip}");
    assert!(rmse > 0.0 && rmse < 0.05, "RMSE vs path-traced direct light {rmse}");
}

#[test]
fn a_2x2_sweep_writes_its_csv_and_pareto_plot() {
    let out = temp_dir("sweep");
    let o = gi_lab()
        .args(["sweep", "--size", "32x24", "--frames", "1", "--flicker-frames", "2", "--reference-spp", "2"])
        .args(["--param", "direct.shadow_map_size=64..256:2", "--param", "direct.shadows=true,false", "--out"])
        .arg(&out)
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5, "a header and four points:\n{csv}");
    let header: Vec<&str> = lines[0].split(',').collect();
    for col in [
        "direct.shadow_map_size",
        "direct.shadows",
        "gbuffer_ms",
        "direct_ms",
        "total_ms",
        "flip",
        "rmse",
        "flicker",
        "pareto",
    ] {
        assert!(header.contains(&col), "column {col} missing: {}", lines[0]);
    }
    let col = |name: &str| header.iter().position(|h| *h == name).expect("column");
    let rows: Vec<Vec<&str>> = lines[1..].iter().map(|l| l.split(',').collect()).collect();
    let settings: Vec<(&str, &str)> =
        rows.iter().map(|r| (r[col("direct.shadow_map_size")], r[col("direct.shadows")])).collect();
    assert_eq!(settings, [("64", "true"), ("64", "false"), ("256", "true"), ("256", "false")]);
    for r in &rows {
        let flip: f64 = r[col("flip")].parse().expect("flip is a number");
        assert!((0.0..1.0).contains(&flip) && flip > 0.0, "FLIP {flip}");
        assert!(r[col("total_ms")].parse::<f64>().expect("ms") > 0.0);
    }
    assert!(rows.iter().any(|r| r[col("pareto")] == "true"), "some point is on the Pareto front");
    // Without shadows the image is further from the path-traced direct light.
    let flip_of = |i: usize| rows[i][col("flip")].parse::<f64>().expect("flip");
    assert!(flip_of(1) > flip_of(0) && flip_of(3) > flip_of(2), "shadows off must score worse: {csv}");
    let plot = image::open(out.join("pareto.png")).expect("pareto.png").to_rgb8();
    assert!(plot.width() >= 800 && plot.height() >= 600);
    assert!(out.join("reference.exr").exists(), "the path-traced reference is kept");
}

#[test]
fn bad_arguments_exit_2_with_a_message() {
    let cases: &[(&[&str], &str)] = &[
        (&["render", "--size", "0x10", "--out", "OUT"], "at least 1"),
        (&["render", "--size", "banana", "--out", "OUT"], "WIDTHxHEIGHT"),
        (&["render", "--out", "OUT", "--scene", "/nonexistent/scene.gltf"], "nonexistent"),
        (&["render", "--out", "OUT", "--buffer", "no.such"], "no buffer named 'no.such'"),
        (&["render", "--out", "OUT", "--buffer", "direct.shadow_map@x"], "not a layer number"),
        (&["render", "--out", "OUT", "--size", "8x8", "--buffer", "direct.shadow_map@7"], "layer"),
        (&["render", "--out", "OUT", "--set", "direct.pcf_radius=99"], "direct.pcf_radius"),
        (&["render", "--out", "OUT", "--preset", "/nonexistent.ron"], "nonexistent.ron"),
        (&["bench", "--frames", "0"], "--frames"),
        (&["frobnicate"], "frobnicate"),
        (&["compare", "/nonexistent/a.png", "/nonexistent/b.png"], "a.png"),
        (&["reference", "--spp", "0", "--out", "OUT/r.exr"], "--spp"),
        (&["reference", "--gpu", "--screen-visible-senders", "--out", "OUT/r.exr"], "CPU tracer's alone"),
        (&["render"], "--out"),
        (&["sweep", "--out", "OUT", "--param", "direct.nope=1..2:2"], "no setting named 'direct.nope'"),
        (&["sweep", "--out", "OUT", "--param", "direct.pcf_radius=0..9:2"], "direct.pcf_radius"),
        (&["sweep", "--out", "OUT", "--param", "direct.pcf_radius=0..2:zero"], "STEPS"),
        (&["sweep", "--out", "OUT", "--param", "direct.shadows=0..1:2"], "list its values"),
        (&["sweep", "--out", "OUT"], "--param"),
        (&["render", "--out", "OUT", "--sky", "blue"], "not three numbers"),
        (&["render", "--out", "OUT", "--sky", "1,1,-1"], "non-negative"),
        (&["render", "--out", "OUT", "--sky", "Cargo.toml"], "Cargo.toml"),
    ];
    let out = temp_dir("bad-args");
    let out = out.to_string_lossy();
    for (args, needle) in cases {
        let args: Vec<&str> = args.iter().map(|a| if *a == "OUT" { &*out } else { *a }).collect();
        let o = gi_lab().args(&args).output().expect("runs");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?} should exit 2; stderr: {err}");
        assert!(err.contains(needle), "{args:?}: stderr does not mention '{needle}': {err}");
    }
}

#[test]
fn buffers_lists_registered_names_and_bench_prints_every_pass() {
    let o = gi_lab().arg("buffers").output().expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    for name in ["gbuffer.motion", "direct.shadow_map", "final.ldr"] {
        assert!(text.contains(name), "buffers output lacks {name}: {text}");
    }
    // The default is instant radiosity (Knecht): its passes are timed.
    // (No flicker or afterglow measurement here: the last two runs below test those.)
    let quick = ["--flicker-frames", "0", "--afterglow-frames", "0"];
    let o = gi_lab().args(["bench", "--size", "32x32", "--frames", "1", "--json"]).args(quick).output().expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("bench --json prints JSON");
    let passes: Vec<&str> = v["passes"].as_array().expect("passes").iter().filter_map(|p| p["pass"].as_str()).collect();
    for p in ["vpl.sample", "ism.splat", "interleave.gather", "temporal.filter_merge"] {
        assert!(passes.contains(&p), "the default technique's pass {p} is missing from {passes:?}");
    }
    // Issue #38's per-frame counters, and the window's frame: one submit, no GPU object made
    // in a steady frame, bytes bound, and a frame time.
    let number = |k: &str| v[k].as_f64().unwrap_or_else(|| panic!("bench --json lacks {k}: {v}"));
    assert!(number("blocking_waits_per_frame") >= 1.0, "the command line waits for each frame's timings");
    assert!(number("submits_per_frame") >= 1.0);
    assert_eq!(number("objects_created_per_frame"), 0.0);
    assert!(number("traffic_bytes_per_frame") > 32.0 * 32.0 * 16.0);
    assert!(number("window_frame_ms") > 0.0);
    // The default technique has no device-dependent pass.
    assert_eq!(v["device_choices"], serde_json::json!([]), "device choices of the default");
    // The HCB's splat and gather are chosen by the device (binned and a workgroup per
    // sample on a GPU, the quads and an invocation per sample on a CPU renderer).
    let o = gi_lab()
        .args(["bench", "--size", "32x32", "--frames", "1", "--json"])
        .args(quick)
        .arg("--preset")
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/../presets/nguyen-hcb.ron"))
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("bench --json prints JSON");
    let choices: Vec<&str> =
        v["device_choices"].as_array().expect("device_choices").iter().filter_map(|c| c.as_str()).collect();
    let cpu = v["adapter"].as_str().is_some_and(|a| a.contains("llvmpipe") || a.contains("SwiftShader"));
    let want = if cpu {
        ["hcb.splat Auto → Blend", "HCB gather: an invocation per sample"]
    } else {
        ["hcb.splat Auto → Binned", "HCB gather: a workgroup per sample"]
    };
    assert_eq!(choices, want, "{v}");
    let o = gi_lab()
        .args(["bench", "--size", "64x64", "--frames", "2", "--json", "--set", "pipeline.gather=None"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("bench --json prints JSON");
    // Direct light alone has nothing stochastic: a paused scene does not flicker at all.
    assert_eq!(v["flicker"], 0.0, "flicker of a static scene");
    let passes: Vec<&str> = v["passes"].as_array().expect("passes").iter().filter_map(|p| p["pass"].as_str()).collect();
    // The compose tone maps (with the previous frame's exposure) after the first frame.
    assert_eq!(passes, ["gbuffer", "direct.shadow", "direct", "compose", "compose.luminance"]);
    // Without temporal history, a light change shows at once.
    assert_eq!(v["afterglow_frames"], 0, "afterglow without history");
    // The default box's animation moves an object: its shadow maps are redone every frame.
    assert_eq!(
        (v["light_space_runs_per_frame"].as_f64(), v["light_space_skips_per_frame"].as_f64()),
        (Some(1.0), Some(0.0))
    );
    // Paused, they are kept (issue #53) with the G-buffer and the direct light: not timed, and
    // the counters say so.
    let o = gi_lab()
        .args(["bench", "--size", "64x64", "--frames", "2", "--json", "--paused", "--set", "pipeline.gather=None"])
        .args(["--flicker-frames", "0", "--afterglow-frames", "0"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("bench --json prints JSON");
    let passes: Vec<&str> = v["passes"].as_array().expect("passes").iter().filter_map(|p| p["pass"].as_str()).collect();
    assert_eq!(passes, ["compose", "compose.luminance"]);
    assert_eq!(
        (v["light_space_runs_per_frame"].as_f64(), v["light_space_skips_per_frame"].as_f64()),
        (Some(0.0), Some(1.0))
    );
    assert_eq!(
        (v["screen_space_runs_per_frame"].as_f64(), v["screen_space_skips_per_frame"].as_f64()),
        (Some(0.0), Some(2.0))
    );

    // The exact-VPL reference accumulates over frames: its passes are timed, it changes from
    // frame to frame while it converges, and after a light change it needs frames to settle.
    let o = gi_lab()
        .args(["bench", "--size", "32x32", "--frames", "2", "--afterglow-frames", "8", "--json"])
        .args(["--set", "indirect.technique=ExactVpl", "--set", "reference.vpls_per_frame=16"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("bench --json prints JSON");
    let passes: Vec<&str> = v["passes"].as_array().expect("passes").iter().filter_map(|p| p["pass"].as_str()).collect();
    for p in ["vpl.light_gbuffer", "vpl.sample", "vpl.shadow", "indirect.gather"] {
        assert!(passes.contains(&p), "pass {p} missing from {passes:?}");
    }
    assert!(v["flicker"].as_f64().expect("flicker") > 0.0, "a converging accumulation changes between frames");
    let afterglow = v["afterglow_frames"].as_u64().expect("afterglow settles");
    assert!((1..8).contains(&afterglow), "afterglow of the progressive reference: {afterglow}");
}

#[test]
fn export_writes_json_and_ron_that_import_to_the_preset() {
    let out = temp_dir("export");
    let preset = out.join("p.ron");
    let mut s = gi_render::LabSettings::default();
    s.direct.pcf_radius = 3;
    s.tonemap.exposure_ev = 0.1 + 0.2;
    s.save(&preset).expect("preset written");
    for format in ["json", "ron"] {
        let file = out.join(format!("p.{format}"));
        let o = gi_lab()
            .args(["export", "--format", format, "--size", "640x360", "--set", "tonemap.key=0.3", "--preset"])
            .arg(&preset)
            .arg("--out")
            .arg(&file)
            .output()
            .expect("runs");
        assert!(o.status.success(), "export {format} failed: {}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(&file).expect("export written");
        let e = gi_render::preset::Export::parse(&text, "export").unwrap_or_else(|e| panic!("{format}: {e}"));
        let mut want = s.clone();
        want.tonemap.key = 0.3;
        assert_eq!(e.settings, want, "{format}: the export carries the preset with its overrides exactly");
        assert_eq!(e.schema, "gi-lab-preset");
        assert_eq!(e.provenance.gi_lab_version, env!("CARGO_PKG_VERSION"));
        assert!(e.provenance.date.ends_with('Z') && e.provenance.date.starts_with("20"), "{}", e.provenance.date);
        // Where it was tuned (issue #54 point 4): the image, the unit, the bounds, the scale.
        assert_eq!((e.provenance.resolution, e.provenance.unit.as_str()), ([640, 360], "m"));
        let b = e.provenance.bounds.as_ref().expect("bounds");
        assert!(b.radius > 0.5 && (0..3).all(|k| b.min[k] < b.max[k]), "{b:?}");
        assert!(e.provenance.scale.as_ref().is_some_and(|s| s.length > 0.0), "{:?}", e.provenance.scale);
    }
    let o = gi_lab().args(["export", "--format", "xml"]).output().expect("runs");
    assert_eq!(o.status.code(), Some(2), "an unknown format is a usage error");
    let o = gi_lab().args(["export", "--size", "0x5"]).output().expect("runs");
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--size"), "a bad size is refused");
}

#[test]
fn export_writes_a_port_kit_and_refuses_an_existing_folder() {
    let out = temp_dir("port-kit");
    let kit = out.join("kit");
    let run = |extra: &[&str]| {
        gi_lab()
            .args(["export", "--preset"])
            .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/../presets/nguyen-hcb.ron"))
            .args(["--size", "32x18", "--frames", "2", "--port-kit"])
            .arg(&kit)
            .args(extra)
            // Expressions have their own test (tests/tests/port_kit.rs); the probes would triple
            // this one's time.
            .arg("--no-expressions")
            .output()
            .expect("runs")
    };
    let o = run(&[]);
    assert!(o.status.success(), "port kit failed: {}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("passes"), "{}", String::from_utf8_lossy(&o.stdout));
    for f in [
        "manifest.json",
        "preset.json",
        "README.md",
        "shaders/hcb/gather.wgsl",
        "golden/frame-0/inputs/frame.camera.bin",
    ] {
        assert!(kit.join(f).is_file(), "{f} missing from the kit");
    }
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(kit.join("manifest.json")).expect("manifest")).expect("json");
    assert_eq!((m["schema"].as_str(), m["preset"].as_str()), (Some("gi-lab-port-kit"), Some("nguyen-hcb")));
    assert_eq!(m["size"], serde_json::json!([32, 18]));
    assert!(m.get("expressions").is_none(), "--no-expressions leaves them out");
    let before = std::fs::read_to_string(kit.join("manifest.json")).expect("manifest");
    let o = run(&[]);
    assert!(!o.status.success(), "an existing folder is refused");
    assert!(String::from_utf8_lossy(&o.stderr).contains("--force"), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_to_string(kit.join("manifest.json")).expect("kept"), before, "nothing was touched");
    let o = run(&["--force"]);
    assert!(o.status.success(), "--force replaces it: {}", String::from_utf8_lossy(&o.stderr));
    // `gi-lab verify` on a port that wrote nothing names the first output it misses.
    let o = gi_lab()
        .args(["verify", "--port-kit"])
        .arg(&kit)
        .arg("--outputs")
        .arg(out.join("no-port"))
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("frame 0, pass 00 gbuffer") && err.contains("the port's output"), "{err}");
}

#[test]
fn the_knecht_bench_suite_prints_every_table_as_json() {
    let o = gi_lab()
        .args(["bench", "--suite", "knecht", "--size", "48x32", "--frames", "1", "--json", "--preset"])
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/../presets/knecht-cornell-256.ron"))
        // A small base (the tables' rows are the same; the ISM-size rows at 512² × 16 maps,
        // not × 256: 47 → 9 s on lavapipe).
        .args(["--set", "vpl.count=16", "--set", "ism.points=16384"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "bench --suite failed: {}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let rows = v["rows"].as_array().expect("rows");
    let in_table = |t: &str| rows.iter().filter(|r| r["table"] == t).count();
    assert_eq!((in_table("VPL count"), in_table("ISM size"), in_table("temporal coherence")), (5, 4, 2), "{text}");
    assert_eq!(in_table("bounces (focus: bounce passes only)"), 10, "{text}");
    for r in rows {
        // Every row is measured or refused with a reason, never silently empty.
        assert!(r["total_ms"].as_f64().is_some_and(|t| t > 0.0) || r["refused"].is_string(), "{r}");
    }
    assert!(v["temporal_overhead"].is_number(), "{text}");
    // Table 5.3: IRSM and point-cloud bounce times and their ratio for 2…6 bounces.
    let speedup = v["bounce_speedup"].as_array().expect("bounce_speedup");
    assert_eq!(speedup.len(), 5, "{text}");
    for row in speedup {
        let r = row.as_array().expect("a row");
        assert!(r[1].as_f64().is_some_and(|t| t > 0.0) && r[2].as_f64().is_some_and(|t| t > 0.0), "{row}");
    }
}

#[test]
fn hcb_stats_prints_the_samples_per_level_as_table_1() {
    let o = gi_lab().args(["hcb-stats", "--size", "128x96"]).output().expect("runs");
    assert!(o.status.success(), "hcb-stats failed: {}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("Table 1") && text.contains("% of G-buffer"), "{text}");
    // One row per level of the default 7, and a total that is the sum of the rows.
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(rows.len(), 7, "{text}");
    let sum: u64 = rows.iter().map(|r| r[2].parse::<u64>().expect("a count")).sum();
    let total = text.lines().find(|l| l.starts_with("total")).expect("a total row");
    assert_eq!(total.split_whitespace().nth(1).and_then(|v| v.parse::<u64>().ok()), Some(sum), "{text}");
    assert!(sum > 0 && sum < 128 * 96, "{text}");
}

#[test]
fn hcb_stats_with_the_cache_prints_a_line_per_frame() {
    let o = gi_lab()
        .args(["hcb-stats", "--size", "96x96", "--frames", "3", "--preset"])
        .arg(concat!(env!("CARGO_MANIFEST_DIR"), "/../presets/nguyen-hcb-cached.ron"))
        .output()
        .expect("runs");
    assert!(o.status.success(), "hcb-stats failed: {}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let frames: Vec<&str> = text.lines().filter(|l| l.starts_with("frame")).collect();
    assert_eq!(frames.len(), 3, "{text}");
    // The first frame has nothing cached; the still view then reuses its samples.
    assert!(frames[0].contains(" 0 cached"), "{text}");
    assert!(!frames[2].contains(" 0 cached"), "{text}");
    assert!(text.contains("d_max in use"), "{text}");
    let bad = gi_lab().args(["hcb-stats", "--frames", "0"]).output().expect("runs");
    assert_eq!(bad.status.code(), Some(2), "--frames 0 is refused");
}

#[test]
fn the_nguyen_bench_suite_compares_the_hcb_with_the_per_pixel_gather() {
    let o = gi_lab()
        .args(["bench", "--suite", "nguyen", "--size", "64x48", "--frames", "1", "--json"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "bench --suite nguyen failed: {}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(v["vpls"], 1024, "{text}");
    for k in ["hcb_ms", "per_pixel_ms", "hcb_gather_ms", "per_pixel_gather_ms"] {
        assert!(v[k].as_f64().is_some_and(|t| t > 0.0), "{k}: {text}");
    }
    let samples = v["samples"].as_u64().expect("samples");
    let per_level: u64 =
        v["samples_per_level"].as_array().expect("levels").iter().map(|n| n.as_u64().expect("n")).sum();
    assert!(samples > 0 && samples == per_level && samples < 64 * 48, "{text}");
    for run in ["cached_still", "cached_moving"] {
        let c = &v[run];
        assert!(c["hcb_passes_ms"].as_f64().is_some_and(|t| t > 0.0), "{run}: {text}");
        let n = |k: &str| c["counts"][k].as_u64().expect("count");
        assert_eq!(n("total"), n("cached") + n("new"), "{run}: {text}");
        assert!(n("cached") > 0, "{run}: the cache is reused after the warm-up: {text}");
    }
}

#[test]
fn the_soler_bench_suite_prints_fig_9_with_every_part() {
    let o = gi_lab()
        .args(["bench", "--suite", "soler", "--size", "96x64", "--frames", "1", "--json"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "bench --suite soler failed: {}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let rows = v["rows"].as_array().expect("rows");
    // Fig. 9: quarter/4/64, quarter/4/256, half/4/64, half/5/64, each without and with visibility.
    assert_eq!(rows.len(), 8, "{text}");
    for r in rows {
        let levels = r["levels"].as_u64().expect("levels");
        let per_level = r["levels_ms"].as_array().expect("levels_ms");
        assert_eq!(per_level.len() as u64, levels, "{r}");
        assert!(per_level.iter().all(|t| t.as_f64().is_some_and(|t| t > 0.0)), "every level is timed: {r}");
        let vis = r["visibility"].as_bool().expect("visibility");
        assert_eq!(
            r["voxels_ms"].as_f64().is_some_and(|t| t > 0.0),
            vis,
            "the voxel grid runs with visibility only: {r}"
        );
        assert!(r["upsampling_tc_ms"].as_f64().is_some_and(|t| t > 0.0), "{r}");
        let parts: f64 =
            ["voxels_ms", "pyramid_ms", "upsampling_tc_ms"].iter().map(|k| r[*k].as_f64().unwrap_or(0.0)).sum::<f64>()
                + per_level.iter().filter_map(|t| t.as_f64()).sum::<f64>();
        let total = r["total_ms"].as_f64().expect("total");
        assert!((total - parts).abs() <= 1e-6 * total.max(1.0), "the parts make the total: {r}");
    }
    let table =
        gi_lab().args(["bench", "--suite", "soler", "--size", "96x64", "--frames", "1"]).output().expect("runs");
    let text = String::from_utf8_lossy(&table.stdout);
    for line in ["voxel grid", "SSIL level 5", "total SSIL (1 bounce)", "upsampling + TC", "ratio to column 1", "goals"]
    {
        assert!(text.contains(line), "{line}: {text}");
    }
}

/// A newcomer's first run prints no driver noise: without `XDG_RUNTIME_DIR` (as in a bare
/// container or a CI job) Mesa would complain on stderr; `gi-lab` sets a private one.
#[cfg(target_os = "linux")]
#[test]
fn no_runtime_dir_complaint_without_xdg_runtime_dir() {
    let out = temp_dir("xdg");
    let o = gi_lab()
        .env_remove("XDG_RUNTIME_DIR")
        .args(["render", "--size", "32x32"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "render failed: {stderr}");
    assert!(!stderr.contains("XDG_RUNTIME_DIR"), "driver noise on stderr: {stderr}");
    let dir = gi_lab::runtime_dir::private_runtime_dir().expect("a private runtime dir");
    use std::os::unix::fs::PermissionsExt;
    assert_eq!(std::fs::metadata(&dir).expect("exists").permissions().mode() & 0o777, 0o700);
}

/// `bench --suite scenes` lists the project's scene and every real scene with a frame time
/// for each technique preset (issue #18).
#[test]
fn bench_scenes_lists_every_scene_with_each_technique() {
    let o = gi_lab()
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .args(["bench", "--suite", "scenes", "--size", "32x32", "--frames", "1", "--json"])
        // Every technique from few VPLs and points: the suite's rows, not its figures, are tested.
        .args(["--set", "vpl.count=16", "--set", "ism.points=16384", "--set", "direct.shadow_map_size=256"])
        .args(["--set", "ddgi.probes_x=4", "--set", "ddgi.probes_y=2", "--set", "ddgi.probes_z=4"])
        .args(["--set", "ddgi.rays_per_probe=32"])
        .output()
        .expect("runs");
    assert!(o.status.success(), "bench failed: {}", String::from_utf8_lossy(&o.stderr));
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let rows = rows.as_array().expect("rows");
    let names: Vec<&str> = rows.iter().filter_map(|r| r["scene"].as_str()).collect();
    for want in ["assets/cornell_box.glb", "CornellBox-Original.gltf", "hotel-room.glb", "MixedLightingExample.gltf"] {
        assert!(names.iter().any(|n| n.ends_with(want)), "{want} missing from {names:?}");
    }
    for r in rows {
        let times = r["frame_ms"].as_array().expect("frame times");
        // The four papers' presets and DDGI's.
        assert_eq!(times.len(), 5, "{r}");
        for t in times {
            let ms = t[1]["Ok"].as_f64().unwrap_or_else(|| panic!("{}: {}", r["scene"], t));
            assert!(ms > 0.0, "{r}");
        }
    }
    // The real Cornell box has an emissive quad and no punctual light: the quad lights it,
    // no default light is added.
    let cornell = rows
        .iter()
        .find(|r| r["scene"].as_str().is_some_and(|n| n.ends_with("CornellBox-Original.gltf")))
        .expect("row");
    assert_eq!(cornell["default_light"], false);
    assert_eq!(cornell["lights"], 0);
    assert!(cornell["emissive_triangles"].as_u64().unwrap_or(0) > 0);
    // The glowing spheres: many emissive triangles, every technique renders them.
    let spheres: Vec<u64> = rows
        .iter()
        .filter(|r| r["scene"].as_str().is_some_and(|n| n.contains("glowing sphere")))
        .map(|r| r["emissive_triangles"].as_u64().unwrap_or(0))
        .collect();
    assert_eq!(spheres.len(), 3, "{names:?}");
    assert!(spheres.iter().any(|&t| t > 5000), "{spheres:?}");
}

/// `--sky` (issue #18 point 2): a constant sky lights the default box through its open side
/// and shows behind it; `--sky off` leaves the image as without the flag.
#[test]
fn render_with_a_sky_from_the_command_line() {
    let out = temp_dir("sky");
    let render = |name: &str, sky: &[&str]| {
        let o = gi_lab()
            .args(["render", "--size", "48x48", "--frames", "1", "--buffer", "final.hdr", "--paused"])
            .args(sky)
            .arg("--out")
            .arg(out.join(name))
            .output()
            .expect("runs");
        assert!(o.status.success(), "{sky:?}: {}", String::from_utf8_lossy(&o.stderr));
        let img = image::open(out.join(name).join("final.hdr.exr")).expect("EXR").to_rgba32f();
        img.pixels().map(|p| p.0[2] as f64).sum::<f64>()
    };
    let plain = render("plain", &[]);
    let sky = render("sky", &["--sky", "0.6,0.75,1.0", "--sky-intensity", "2"]);
    let off = render("off", &["--sky", "off"]);
    assert!(sky > plain * 1.05, "the sky adds light: {plain} -> {sky}");
    assert_eq!(off, plain, "--sky off: as without a sky");
}

#[test]
fn a_device_lost_while_rendering_ends_the_run_with_a_clear_error() {
    let out = temp_dir("lost");
    // The render command destroys its device before frame 1 when told to, as a driver reset.
    let o = gi_lab()
        .args(["render", "--size", "32x32", "--frames", "3"])
        .arg("--out")
        .arg(&out)
        .env("GI_LAB_TEST_LOSE_DEVICE_AT", "1")
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "exit 1 for a lost device: {err}");
    assert!(err.contains("gi-lab: error: the GPU device was lost"), "{err}");
    assert!(!err.contains("panicked"), "no panic: {err}");
    assert!(!out.join("final.png").exists(), "no image from a lost device");
}

/// Issue #37 point 5: `bench --suite quality` runs on a real scene without a reference (it
/// traces one), and gives every technique row a frame time and its FLIP at equal time.
#[test]
fn the_quality_suite_runs_on_a_real_scene_and_traces_its_own_truth() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/scenes/cornell-box/CornellBox-Original.gltf");
    let o = gi_lab()
        .args(["bench", "--suite", "quality", "--scene", scene, "--size", "24x24", "--spp", "4", "--json"])
        // Few VPLs, points and reference batches: the suite's rows on a real scene, not its figures, are tested.
        .args(["--set", "vpl.count=16", "--set", "ism.points=16384", "--set", "direct.shadow_map_size=256"])
        .args(["--set", "reference.total_vpls=256", "--set", "reference.light_gbuffer_size=64"])
        // A small probe grid with few rays for DDGI's row (issue #56).
        .args(["--set", "ddgi.probes_x=4", "--set", "ddgi.probes_y=2", "--set", "ddgi.probes_z=4"])
        .args(["--set", "ddgi.rays_per_probe=32"])
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "bench failed: {stderr}");
    assert!(stderr.contains("path-tracing the one-bounce ground truth at 24x24, 4 spp"), "{stderr}");
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let rows = rows.as_array().expect("rows");
    let truth_rows: Vec<_> = rows.iter().filter(|r| r["against"] == "ground truth").collect();
    assert_eq!(truth_rows.len(), 7, "{rows:?}");
    // `--set` reached every row: the exact reference names the VPLs it was given.
    assert!(rows.iter().any(|r| r["configuration"] == "exact-vpl-reference (256 VPLs)"), "{rows:?}");
    for r in truth_rows {
        let flip = r["flip"].as_f64().expect("FLIP");
        assert!(flip > 0.0 && flip < 1.0, "{r}");
        assert!(r["frame_ms"].as_f64().is_some_and(|ms| ms > 0.0), "{r}");
        let eq = r["equal_time"].as_array().expect("equal time");
        let frames = eq[0].as_u64().expect("frames");
        assert!((1..=64).contains(&frames), "{r}");
        assert!(eq[1].as_f64().is_some_and(|f| f > 0.0 && f < 1.0), "{r}");
    }
}

/// Shadow maps the device cannot hold (four point lights at 8192²: 24 layers, 6 GiB) render
/// smaller instead of failing, and the renderer says so; the random walk through the window
/// found the GPU validation error this gave before.
#[test]
fn shadow_maps_too_large_for_the_device_render_smaller_and_say_so() {
    let scene = gi_render::scene::cornell::default_scene().expect("scene");
    let mut settings = gi_render::LabSettings::default();
    settings.direct.shadow_map_size = 8192;
    let ctx = gi_render::GpuContext::headless().expect(
        "no GPU adapter: install Mesa's software Vulkan driver with `sudo apt-get install -y mesa-vulkan-drivers libvulkan1`",
    );
    let mut r = gi_render::Renderer::new(ctx, scene, settings, 64, 48).expect("renderer");
    r.render_frame();
    assert_eq!(r.shadow_note(), None, "one light at 8192² fits");
    let radius = r.bounds().radius();
    for _ in 0..4 {
        let c = r.camera;
        gi_lab::scene_lights::add_light(
            r.scene_mut(),
            gi_lab::scene_lights::NewLight::Point,
            c.position,
            c.forward(),
            radius,
        );
    }
    r.render_frame();
    let note = r.shadow_note().expect("the atlas did not fit: a note says so").to_string();
    assert!(note.contains("8192²") && note.contains("do not fit this device"), "{note}");
    let hdr = r.readback("final.hdr").expect("final.hdr");
    assert!(hdr.data.iter().all(|p| p.iter().all(|c| c.is_finite())), "the frame renders");
    assert!(hdr.data.iter().any(|p| p[0] > 0.0), "and is lit");
}
