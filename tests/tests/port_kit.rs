//! The port kit (issue #54 point 1; docs/port-kit.md): its manifest lists the frame the
//! renderer draws — every timed pass in order, each step's shader entry point, every binding's
//! resource — and is written whole or not at all.

use gi_lab_tests::{default_scene, gpu};
use gi_render::export::port_kit::{self, Kit, KitRequest};
use gi_render::{LabSettings, Renderer};

const SIZE: (u32, u32) = (48, 27);

fn settings(preset: &str) -> LabSettings {
    let path = format!("{}/../presets/{preset}.ron", env!("CARGO_MANIFEST_DIR"));
    LabSettings::load(std::path::Path::new(&path)).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The kit of `preset` on the default scene at [`SIZE`], without expressions.
fn request(preset: &str, frames: u32, goldens: bool) -> KitRequest<'_> {
    KitRequest {
        preset,
        settings: settings(preset),
        scene: default_scene(),
        scene_name: "default",
        size: SIZE,
        frames,
        goldens,
        camera: None,
        expressions: false,
        settings_probed: None,
    }
}

fn kit(preset: &str, frames: u32, goldens: bool) -> Kit {
    port_kit::build(gpu(), request(preset, frames, goldens)).unwrap_or_else(|e| panic!("{preset}: {e}"))
}

/// Names in the order they first appear.
fn first_seen<'a>(names: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for n in names {
        if !out.iter().any(|o| o == n) {
            out.push(n.to_string());
        }
    }
    out
}

#[test]
fn the_manifest_lists_every_timed_pass_with_its_shaders_bindings_and_resources_and_every_shader_translates() {
    let (spirv_val, glslang) = (tool("spirv-val", "spirv-tools"), tool("glslangValidator", "glslang-tools"));
    let base = std::env::temp_dir().join(format!("gi-lab-port-kit-shaders-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let mut tables = format!(
        "# The port kit host against the goldens\n\nWritten by tests/tests/port_kit.rs: each kit exported at {}x{}, 4 frames, \
         on the embedded default scene; examples/port-kit-host ran it, `gi-lab verify`'s comparison per pass (the worst \
         output over the 4 frames).\n",
        SIZE.0, SIZE.1
    );
    // The four papers' presets and one mix.
    for preset in
        ["knecht-cornell-256", "nguyen-hcb", "gautron-ic-splatting", "soler-quarter-4-64", "soler-near-knecht-far"]
    {
        let k = kit(preset, 4, true);
        let m = &k.manifest;
        // The same frame drawn without a capture: its timed passes.
        let mut r = Renderer::new(gpu(), default_scene(), settings(preset), SIZE.0, SIZE.1).expect("renderer");
        r.clock.playing = false;
        r.reuse_unchanged = false;
        let mut timed = Vec::new();
        for _ in 0..4 {
            timed = r.render_frame();
        }
        let timed = first_seen(timed.iter().map(|t| t.name.as_str()));
        let listed = first_seen(m.passes.iter().map(|p| p.name.as_str()).filter(|n| *n != "(between passes)"));
        assert_eq!(listed, timed, "{preset}: the manifest's passes are the frame's timed passes, in order");
        assert_eq!(m.frame_passes.len(), 4, "{preset}: every frame's passes");
        let last = m.frame_passes.last().map(|f| f.iter().map(|p| p.name.as_str()).collect::<Vec<_>>());
        assert_eq!(
            last,
            Some(m.passes.iter().map(|p| p.name.as_str()).collect()),
            "{preset}: `passes` is the last frame"
        );

        let resource = |name: &str| m.resources.iter().find(|r| r.name == name);
        let mut dispatches = 0;
        for pass in &m.passes {
            assert!(!pass.steps.is_empty(), "{preset} {}: a pass without steps", pass.name);
            for step in &pass.steps {
                for (module, entry) in &step.entry_points {
                    let shader = m.shaders.iter().find(|s| &s.module == module);
                    let shader = shader.unwrap_or_else(|| panic!("{preset}: {module} is not among the kit's shaders"));
                    assert!(
                        shader.decl.entry_points.iter().any(|e| &e.name == entry),
                        "{preset}: {module} has no entry point {entry}"
                    );
                    assert!(
                        k.files.iter().any(|(p, text)| p.to_string_lossy() == shader.file
                            && String::from_utf8_lossy(text).contains(entry.as_str())),
                        "{preset}: {} is not written with {entry}",
                        shader.file
                    );
                    for b in &step.bindings {
                        let decl = shader.decl.bindings.iter().find(|d| d.group == b.group && d.binding == b.binding);
                        if let Some(d) = decl {
                            assert_eq!(d.name, b.name, "{preset} {}: binding {}/{}", pass.name, b.group, b.binding);
                            // The uniform block's reflected layout fits the buffer range bound.
                            if d.kind == "uniform" {
                                let (size, bound) = (d.size.unwrap_or(0) as u64, b.size.unwrap_or(0));
                                assert!(
                                    size > 0 && bound >= size,
                                    "{preset} {}: {} is {size} B, bound {bound} B",
                                    pass.name,
                                    b.name
                                );
                            }
                        }
                    }
                }
                for b in &step.bindings {
                    let r = resource(&b.resource);
                    assert!(
                        r.is_some(),
                        "{preset} {}: {} binds {}, not among the resources",
                        pass.name,
                        b.name,
                        b.resource
                    );
                }
                if step.kind == "dispatch" {
                    dispatches += 1;
                    let w = step.workgroups.expect("a dispatch's workgroups");
                    assert!(w.iter().all(|&x| x >= 1), "{preset} {}: {w:?}", pass.name);
                    assert!(!step.bindings.is_empty(), "{preset} {}: a dispatch binds nothing", pass.name);
                }
                if step.kind.starts_with("draw") {
                    assert!(
                        !step.targets.is_empty() || step.depth_target.is_some(),
                        "{preset} {}: a draw without targets",
                        pass.name
                    );
                }
            }
        }
        assert!(dispatches > 0, "{preset}: no dispatch");
        // Every pipeline a step sets is described, a raster one with its targets' state.
        for (pass, step) in m.passes.iter().flat_map(|p| p.steps.iter().map(move |s| (p, s))) {
            let Some(label) = &step.pipeline else { continue };
            let p = m.pipelines.iter().find(|p| &p.label == label);
            let p = p.unwrap_or_else(|| panic!("{preset} {}: pipeline {label} not described", pass.name));
            if step.kind.starts_with("draw") {
                assert_eq!(p.kind, "render", "{preset} {label}");
                assert!(!p.targets.is_empty() || p.depth.is_some(), "{preset} {label}: no targets");
                assert!(p.primitive.is_some(), "{preset} {label}: no primitive state");
            }
            // The HCB's coherence-weighted splats add up (Nguyen et al. §4.2): blending is part
            // of what a port must reproduce.
            if pass.name == "hcb.splat" && step.kind.starts_with("draw") {
                assert!(p.targets.iter().all(|t| t.blend.is_some()), "{preset} {label}: the splat blends");
            }
        }
        // What the engine feeds is listed as such: the G-buffer pass and the direct light.
        for name in ["gbuffer", "direct"] {
            assert!(
                m.passes.iter().any(|p| p.name == name && p.role == "engine"),
                "{preset}: {name} as an engine pass"
            );
        }
        // Temporal techniques keep histories across frames, and the kit says which.
        let histories: Vec<&str> =
            m.resources.iter().filter(|r| r.lifetime == "history").map(|r| r.name.as_str()).collect();
        let expect = match preset {
            "knecht-cornell-256" => Some("temporal.history"),
            "soler-quarter-4-64" => Some("soler.temporal"),
            _ => None,
        };
        if let Some(prefix) = expect {
            assert!(histories.iter().any(|h| h.starts_with(prefix)), "{preset}: no {prefix}* history in {histories:?}");
        }
        assert!(
            m.resources.iter().all(|r| !r.name.starts_with("timing.")),
            "{preset}: GI Lab's instrumentation listed"
        );
        let dir = base.join(preset);
        port_kit::write(&k, &dir, false).expect("written");
        check_translations(preset, &k, &dir, (&spirv_val, &glslang));
        tables += &host_reproduces(preset, &dir, &base.join(format!("{preset}-port")));
        let _ = std::fs::remove_dir_all(&dir);
    }
    let _ = std::fs::remove_dir_all(&base);
    // scripts/test.sh prints it, so that the CI log carries the verify tables.
    let _ = std::fs::write(std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("port-kit-verify.md"), tables);
}

/// The host that knows nothing but the kit (examples/port-kit-host: plain wgpu, no GI Lab
/// code) runs every frame of the kit in `dir`, and `gi-lab verify`'s comparison finds every
/// pass's outputs within 0.01 (FLIP on images, relative error on data, words on integers,
/// records as a set for atomically appended lists): the kit is complete (issue #54 point 3).
/// Returns the per-pass table (the worst output over the frames).
fn host_reproduces(preset: &str, dir: &std::path::Path, out: &std::path::Path) -> String {
    let summary = port_kit_host::run(dir, out).unwrap_or_else(|e| panic!("{preset}: the host: {e}"));
    assert_eq!(summary.frames, 4, "{preset}: the host ran every frame");
    let report = port_kit::verify::verify(dir, out, 0.01).unwrap_or_else(|e| panic!("{preset}: verify: {e}"));
    println!("{preset}: the host's {} outputs\n{}", report.rows.len(), report.table());
    assert!(report.rows.len() == summary.outputs && !report.rows.is_empty(), "{preset}: every output compared");
    if let Some(first) = report.first_divergence() {
        panic!(
            "{preset}: the host diverges first at frame {}, pass {:02} {}: {} {} {:.5}\n{}",
            first.frame,
            first.index,
            first.pass,
            first.resource,
            first.metric,
            first.value,
            report.table()
        );
    }
    let _ = std::fs::remove_dir_all(out);
    let mut worst: Vec<(u64, String, f64, String, &str, usize)> = Vec::new();
    for r in &report.rows {
        match worst.iter_mut().find(|w| w.0 == r.index) {
            Some(w) => {
                w.5 += 1;
                if r.value > w.2 {
                    (w.2, w.3, w.4) = (r.value, r.resource.clone(), r.metric);
                }
            }
            None => worst.push((r.index, r.pass.clone(), r.value, r.resource.clone(), r.metric, 1)),
        }
    }
    worst.sort_by_key(|w| w.0);
    let mut t = format!(
        "\n## {preset}\n\n{} passes run over {} frames, {} outputs compared, all within 0.01.\n\n\
         | pass | outputs (all frames) | worst | metric | resource |\n|---|---:|---:|---|---|\n",
        summary.passes, summary.frames, summary.outputs
    );
    for (index, pass, value, resource, metric, n) in worst {
        t += &format!("| {index:02} {pass} | {n} | {value:.5} | {metric} | {resource} |\n");
    }
    t
}

#[test]
fn a_kit_is_written_whole_and_an_existing_folder_is_refused_unless_forced() {
    let k = kit("knecht-cornell-256", 3, false);
    let base = std::env::temp_dir().join(format!("gi-lab-port-kit-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).expect("temp dir");
    let dir = base.join("kit");
    port_kit::write(&k, &dir, false).expect("written");
    for (rel, text) in &k.files {
        assert_eq!(&std::fs::read(dir.join(rel)).expect("a kit file"), text, "{}", rel.display());
    }
    let refused = port_kit::write(&k, &dir, false).expect_err("an existing folder is refused");
    assert!(refused.contains("exists") && refused.contains("--force"), "{refused}");
    std::fs::write(dir.join("stale.txt"), "from before").expect("write");
    port_kit::write(&k, &dir, true).expect("replaced");
    assert!(!dir.join("stale.txt").exists(), "--force replaces the folder, not merges into it");
    let left: Vec<_> = std::fs::read_dir(&base).expect("list").flatten().map(|e| e.file_name()).collect();
    assert_eq!(left, vec![std::ffi::OsString::from("kit")], "no temporary folders left");
    let _ = std::fs::remove_dir_all(&base);
}

/// `tool` on the PATH, or a failure that says how to install it.
fn tool(name: &str, package: &str) -> String {
    let found = std::process::Command::new(name).arg("--version").output().is_ok();
    assert!(
        found,
        "{name} is missing: `sudo apt-get install -y {package}` (scripts/test.sh installs it when it runs as root)"
    );
    name.to_string()
}

/// Every translation of `k` succeeded, and every SPIR-V and GLSL file written to `dir`
/// validates (HLSL and MSL cannot be compiled here: docs/port-kit.md).
fn check_translations(preset: &str, k: &Kit, dir: &std::path::Path, (spirv_val, glslang): (&str, &str)) {
    let m = &k.manifest;
    assert!(!m.translations.is_empty(), "{preset}: no translations");
    for t in &m.translations {
        for (lang, file) in &t.files {
            let file = file.as_ref().unwrap_or_else(|e| panic!("{preset}: {} {} in {lang}: {e}", t.module, t.entry));
            let path = dir.join(file);
            assert!(path.is_file(), "{preset}: {file} not written");
            let check = match lang.as_str() {
                "spirv" => {
                    Some(std::process::Command::new(spirv_val).args(["--target-env", "vulkan1.1"]).arg(&path).output())
                }
                "glsl" => Some(std::process::Command::new(glslang).arg(&path).output()),
                _ => None,
            };
            if let Some(o) = check {
                let o = o.expect("the validator runs");
                assert!(
                    o.status.success(),
                    "{preset}: {file} does not validate:\n{}{}",
                    String::from_utf8_lossy(&o.stdout),
                    String::from_utf8_lossy(&o.stderr)
                );
            }
        }
    }
}

/// Bytes a texture's levels and layers (or a buffer) hold, from the manifest's resource.
fn resource_bytes(r: &gi_render::export::port_kit::manifest::Resource) -> u64 {
    if r.kind == "buffer" {
        return r.size[0];
    }
    let bpp = match r.format.as_deref() {
        Some("Rgba32Float" | "Rgba32Uint") => 16,
        Some("Rgba16Float" | "Rg32Float") => 8,
        _ => 4,
    };
    let (w, h, layers) = (r.size[0], r.size[1], r.size[2]);
    (0..r.mips.unwrap_or(1)).map(|m| (w >> m).max(1) * (h >> m).max(1) * layers * bpp).sum()
}

#[test]
fn goldens_hold_every_pass_output_as_the_renderer_draws_it_and_verify_finds_the_first_divergence() {
    // Instant radiosity with a small VPL budget (its ISM atlas is the kit's largest file) and
    // four frames, so that the temporal merge's history is covered.
    let mut s = settings("knecht-cornell-256");
    s.vpl.count = 16;
    let req = KitRequest {
        preset: "knecht-16",
        settings: s.clone(),
        scene: default_scene(),
        scene_name: "default",
        size: SIZE,
        frames: 4,
        goldens: true,
        camera: None,
        expressions: false,
        settings_probed: None,
    };
    let k = port_kit::build(gpu(), req).expect("kit");
    let m = &k.manifest;
    assert_eq!(m.golden.len(), 4, "a golden frame per frame drawn");
    for f in &m.golden {
        assert!(!f.inputs.is_empty(), "frame {}: no inputs", f.frame);
        assert!(!f.passes.is_empty(), "frame {}: no passes", f.frame);
        for p in &f.passes {
            assert!(!p.outputs.is_empty(), "frame {} pass {}: no outputs", f.frame, p.name);
            for o in &p.outputs {
                let r = m.resources.iter().find(|r| r.name == o.resource).expect("a listed resource");
                assert_eq!(o.bytes, resource_bytes(r), "frame {} {}: {}", f.frame, p.name, o.resource);
                assert!(k.files.iter().any(|(path, _)| path.to_string_lossy() == o.file), "{} not written", o.file);
            }
        }
    }
    // Every uniform block the frame uploads is decoded for the last frame, member by member:
    // the G-buffer's first draw binds the scene's first material, whose base colour it shows.
    for p in &m.passes {
        for st in &p.steps {
            for b in st.bindings.iter().filter(|b| b.kind == "uniform") {
                let input = m.resources.iter().any(|r| r.name == b.resource && r.lifetime == "input");
                assert!(!input || !b.values.is_empty(), "{}: {} ({}) not decoded", p.name, b.name, b.resource);
            }
        }
    }
    let draw = &m.passes.iter().find(|p| p.name == "gbuffer").expect("the G-buffer").steps[0];
    let material = draw.bindings.iter().find(|b| b.name == "material").expect("its material");
    let base = &material.values.iter().find(|(n, _)| n == "base_color").expect("base_color").1;
    let want = default_scene().materials[0].base_color;
    let got: Vec<f32> =
        base.as_array().expect("a vec4").iter().map(|v| v.as_f64().unwrap_or(f64::NAN) as f32).collect();
    assert_eq!(got, want.to_array(), "the first material's base colour, decoded");
    let timed = m.passes.iter().filter(|p| p.name != "(between passes)").count();
    assert_eq!(m.golden.last().map(|f| f.passes.len()), Some(timed), "the last frame: a golden pass per timed pass");
    // The last frame's direct light, as the golden holds it, is what a renderer drawing the
    // same four frames shows.
    let mut r = Renderer::new(gpu(), default_scene(), s, SIZE.0, SIZE.1).expect("renderer");
    r.clock.playing = false;
    r.reuse_unchanged = false;
    for _ in 0..4 {
        r.render_frame();
    }
    let direct = gi_lab_tests::read(&r, "direct.radiance");
    let last = m.golden.last().expect("frames");
    let golden = last.passes.iter().flat_map(|p| &p.outputs).find(|o| o.resource == "direct.radiance").expect("direct");
    let bytes = &k.files.iter().find(|(p, _)| p.to_string_lossy() == golden.file).expect("file").1;
    let decoded =
        gi_render::buffers::decode_texels(wgpu::TextureFormat::Rgba16Float, bytes, SIZE.0, SIZE.1).expect("f16");
    assert_eq!(decoded.data, direct.data, "the golden is the renderer's own direct light");

    // A port that writes the goldens back passes; one changed output fails at its pass.
    let base = std::env::temp_dir().join(format!("gi-lab-port-kit-verify-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let (kit, port) = (base.join("kit"), base.join("port"));
    port_kit::write(&k, &kit, false).expect("written");
    for f in &m.golden {
        for o in f.passes.iter().flat_map(|p| &p.outputs) {
            let to = port.join(&o.path);
            std::fs::create_dir_all(to.parent().expect("folder")).expect("mkdir");
            std::fs::copy(kit.join(&o.file), &to).expect("copy");
        }
    }
    let report = port_kit::verify::verify(&kit, &port, 0.01).expect("verifies");
    assert!(report.first_divergence().is_none(), "{}", report.table());
    let outputs: usize = m.golden.iter().flat_map(|f| &f.passes).map(|p| p.outputs.len()).sum();
    assert_eq!(report.rows.len(), outputs);
    let f2 = &m.golden[2];
    let gather = f2.passes.iter().find(|p| p.name == "interleave.gather").expect("the gather");
    let merged = gather.outputs.iter().find(|o| o.resource == "indirect.merged").expect("its light");
    let path = port.join(&merged.path);
    let mut bytes = std::fs::read(&path).expect("read");
    for b in bytes.iter_mut().skip(1).step_by(2) {
        *b ^= 0x08; // every half float's exponent
    }
    std::fs::write(&path, bytes).expect("write");
    let report = port_kit::verify::verify(&kit, &port, 0.01).expect("verifies");
    let first = report.first_divergence().expect("a divergence");
    assert_eq!(
        (first.frame, first.pass.as_str(), first.resource.as_str()),
        (2, "interleave.gather", "indirect.merged")
    );
    std::fs::write(&path, b"short").expect("write");
    let err = port_kit::verify::verify(&kit, &port, 0.01).expect_err("a wrong size is an error");
    assert!(
        err.contains("interleave.gather") && err.contains("indirect.merged") && err.contains("wrong size"),
        "{err}"
    );
    std::fs::remove_file(&path).expect("remove");
    let err = port_kit::verify::verify(&kit, &port, 0.01).expect_err("a missing output is an error");
    assert!(err.contains("interleave.gather") && err.contains("indirect.merged"), "{err}");
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn sizes_and_counts_are_expressions_of_the_image_that_give_another_sizes_values() {
    use gi_render::export::port_kit::expressions::eval_with;
    // Soler et al.'s pyramid: its levels are halvings of the image, its dispatches tile them,
    // and its gather runs once per level, a pass each (soler.gather.k).
    let preset = "soler-quarter-4-64";
    let probed: &[&str] = &["soler.levels"];
    let req = KitRequest { expressions: true, settings_probed: Some(probed), ..request(preset, 2, false) };
    let k = port_kit::build(gpu(), req.clone()).expect("kit");
    let m = &k.manifest;
    let exprs = |e: &[Option<String>]| e.iter().map(|x| x.clone().unwrap_or_default()).collect::<Vec<_>>();
    let res = |name: &str| m.resources.iter().find(|r| r.name == name).unwrap_or_else(|| panic!("{name}"));
    assert_eq!(exprs(&res("gbuffer.linear_depth").size_expr), ["W", "H", "1"]);
    let level2 = m.resources.iter().find(|r| r.name.starts_with("soler.level.2.")).expect("level 2");
    assert!(exprs(&level2.size_expr)[0].contains("W / 4"), "{}: {:?}", level2.name, level2.size_expr);
    let normal = m.passes.iter().find(|p| p.name == "gbuffer.normal").expect("gbuffer.normal");
    assert_eq!(exprs(&normal.steps[0].counts_expr), ["ceil(W / 8)", "ceil(H / 8)", "1"]);
    // The expressions give another size's values, which no probe saw (at the preset's levels).
    let (w, h) = (70u64, 45u64);
    let at = |levels: f64| move |n: &str| (n == "soler.levels").then_some(levels);
    let other = port_kit::build(gpu(), KitRequest { size: (w as u32, h as u32), expressions: false, ..req.clone() })
        .expect("the kit at another size");
    let (mut checked, mut total) = (0, 0);
    for r in &m.resources {
        let Some(r2) = other.manifest.resources.iter().find(|x| x.name == r.name) else { continue };
        for (e, v) in r.size_expr.iter().zip(&r2.size) {
            total += 1;
            if let Some(e) = e {
                assert_eq!(eval_with(e, w, h, &at(4.0)), Some(*v), "{}: {e} at {w}x{h}", r.name);
                checked += 1;
            }
        }
    }
    for (p, p2) in m.passes.iter().zip(&other.manifest.passes) {
        for (s, s2) in p.steps.iter().zip(&p2.steps) {
            let Some(wg) = s2.workgroups else { continue };
            for (e, v) in s.counts_expr.iter().zip(wg) {
                total += 1;
                if let Some(e) = e {
                    let got = eval_with(e, w, h, &at(4.0));
                    assert_eq!(got, Some(v as u64), "{} {:?}: {e} at {w}x{h}", p.name, s.pipeline);
                    checked += 1;
                }
            }
        }
    }
    assert!(checked * 10 >= total * 9, "{checked} of {total} sizes and counts have an expression");
    // The gathers, one pass per level: how many at five levels, which no capture saw.
    let gather = m.repeated_passes.iter().find(|r| r.name == "soler.gather.{k}").expect("the gathers");
    assert_eq!(gather.depends_on, ["soler.levels"], "{gather:?}");
    assert_eq!(gather.passes.len() as u64, gather.count);
    let count = gather.count_expr.as_deref().expect("how many gathers, as an expression");
    let mut s = settings(preset);
    s.apply_override("soler.levels=5").expect("soler.levels");
    let five = port_kit::build(gpu(), KitRequest { settings: s, expressions: false, ..req })
        .expect("the kit with five levels");
    let gathers = five.manifest.passes.iter().filter(|p| p.name.starts_with("soler.gather.")).count() as u64;
    assert_eq!(eval_with(count, SIZE.0 as u64, SIZE.1 as u64, &at(5.0)), Some(gathers), "{count}");
}

#[test]
fn sizes_and_counts_that_follow_settings_are_expressions_of_them_that_give_other_values() {
    use gi_render::export::port_kit::expressions::eval_with;
    // Instant radiosity: the VPL count sets the warp's dispatch, the ISM points their buffer,
    // and the atlas holds a map of ism.map_size² per VPL and bounce, ceil(sqrt(n)) a row.
    let preset = "knecht-cornell-256";
    let probed: &[&str] =
        &["vpl.count", "vpl.bounces", "ism.map_size", "ism.points", "ism.pull_push_levels", "vpl.light_gbuffer_size"];
    let req = KitRequest { expressions: true, settings_probed: Some(probed), ..request(preset, 2, false) };
    let k = port_kit::build(gpu(), req.clone()).expect("kit");
    let m = &k.manifest;
    let points = m.resources.iter().find(|r| r.name == "ism.points").expect("the ISM points");
    assert_eq!(points.size_expr, [Some("32 * ism.points".to_string())]);
    assert_eq!(points.depends_on, ["ism.points"]);
    let warp =
        m.passes.iter().flat_map(|p| &p.steps).find(|s| s.pipeline.as_deref() == Some("vpl.warp")).expect("warp");
    assert_eq!(warp.counts_expr.first().cloned().flatten().as_deref(), Some("ceil(vpl.count / 64)"));
    let atlas = m.resources.iter().find(|r| r.name == "ism.atlas_pulled").expect("the pulled atlas");
    assert_eq!(atlas.depends_on, ["ism.map_size", "vpl.bounces", "vpl.count"]);
    assert_eq!(
        atlas.size_expr[0].as_deref(),
        Some("ceil(sqrt(vpl.bounces * vpl.count)) * ism.map_size"),
        "the atlas's width follows three settings at once"
    );
    // Other values, which no capture saw: the expressions give that kit's sizes and counts.
    let mut s = settings(preset);
    let others = [
        "vpl.count=200",
        "vpl.bounces=2",
        "ism.map_size=64",
        "ism.points=65536",
        "ism.pull_push_levels=4",
        "vpl.light_gbuffer_size=64",
    ];
    for o in others {
        s.apply_override(o).expect(o);
    }
    let other = port_kit::build(gpu(), KitRequest { settings: s.clone(), expressions: false, ..req })
        .expect("the kit with other settings");
    let value = |n: &str| match s.get(n) {
        Some(gi_render::settings::Value::U32(v)) => Some(v as f64),
        _ => None,
    };
    let (w, h) = (SIZE.0 as u64, SIZE.1 as u64);
    let (mut checked, mut several) = (0, 0);
    for r in m.resources.iter().filter(|r| !r.depends_on.is_empty()) {
        let Some(r2) = other.manifest.resources.iter().find(|x| x.name == r.name) else { continue };
        for (e, v) in r.size_expr.iter().zip(&r2.size) {
            if let Some(e) = e.as_ref().filter(|e| e.contains('.')) {
                assert_eq!(eval_with(e, w, h, &value), Some(*v), "{}: {e}", r.name);
                checked += 1;
                several += usize::from(r.depends_on.len() > 1);
            }
        }
    }
    // Steps matched as the fits match them: the pass by name, the step by its pipeline and
    // how many of that pipeline come before it (the second bounce adds steps).
    for (pi, p) in m.passes.iter().enumerate() {
        let nth_pass = m.passes[..pi].iter().filter(|x| x.name == p.name).count();
        let Some(p2) = other.manifest.passes.iter().filter(|x| x.name == p.name).nth(nth_pass) else { continue };
        for (si, st) in p.steps.iter().enumerate().filter(|(_, st)| !st.counts_depend_on.is_empty()) {
            let same =
                |x: &&gi_render::export::port_kit::manifest::Step| x.kind == st.kind && x.pipeline == st.pipeline;
            let nth = p.steps[..si].iter().filter(same).count();
            let Some(wg) = p2.steps.iter().filter(same).nth(nth).and_then(|x| x.workgroups) else { continue };
            for (e, v) in st.counts_expr.iter().zip(wg) {
                if let Some(e) = e.as_ref().filter(|e| e.contains('.')) {
                    assert_eq!(eval_with(e, w, h, &value), Some(v as u64), "{} {:?}: {e}", p.name, st.pipeline);
                    checked += 1;
                    several += usize::from(st.counts_depend_on.len() > 1);
                }
            }
        }
    }
    assert!(checked >= 8 && several >= 4, "{checked} expressions of a setting checked, {several} of several");
    // The pull-push pyramid's loops: their counts follow ism.pull_push_levels.
    let pull_push = |m: &gi_render::export::port_kit::Manifest| {
        m.passes.iter().find(|p| p.name == "ism.pull_push").map(|p| p.runs.clone()).expect("the pull-push pass")
    };
    let (runs, runs2) = (pull_push(m), pull_push(&other.manifest));
    let exprs: Vec<Option<&str>> = runs.iter().map(|r| r.count_expr.as_deref()).collect();
    assert_eq!(exprs, [Some("ism.pull_push_levels - 1"), Some("ism.pull_push_levels")], "{runs:?}");
    for r in &runs {
        let e = r.count_expr.as_deref().expect("fitted");
        let there = runs2.iter().find(|x| x.pipeline == r.pipeline).expect("the loop at the other settings");
        assert_eq!(eval_with(e, w, h, &value), Some(there.count), "{:?}: {e}", r.pipeline);
    }
    // The light view's importance pyramid, reduced level by level: the loop's count and each
    // iteration's workgroups at a light G-buffer of 64², which no capture saw.
    let reduce = |m: &gi_render::export::port_kit::Manifest| {
        let p = m.passes.iter().find(|p| p.name == "vpl.importance").expect("the importance pass");
        let r = p.runs.iter().find(|r| r.pipeline.as_deref() == Some("vpl.importance.reduce")).expect("the reduction");
        (r.clone(), p.steps[r.first..r.first + r.count as usize].to_vec())
    };
    let ((r, _), (r2, steps2)) = (reduce(m), reduce(&other.manifest));
    assert_eq!(r.count_expr.as_deref(), Some("floor(log2(vpl.light_gbuffer_size))"));
    assert_eq!(eval_with(r.count_expr.as_deref().expect("count"), w, h, &value), Some(r2.count));
    for (i, st) in steps2.iter().enumerate() {
        let at = |k: &str| match k {
            "i" => Some(i as f64),
            "n" => Some(r2.count as f64),
            _ => value(k),
        };
        for (e, v) in r.iteration_expr.iter().zip(st.workgroups.expect("a dispatch")) {
            let e = e.as_deref().expect("each iteration's workgroups fitted");
            assert_eq!(eval_with(e, w, h, &at), Some(v as u64), "iteration {i}: {e}");
        }
    }
}
