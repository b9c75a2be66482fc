//! The port kit (issue #54; docs/port-kit.md): everything an engine team needs to port a
//! preset, written to one folder — `manifest.json` (the frame as the ordered list of its
//! passes, with every binding, resource and shader declaration: [`manifest`]), `preset.json`
//! (the engine export with the resolved values), `shaders/` (each module with its imports
//! resolved) and a `README.md` that walks the passes in order with the papers' sections.
//!
//! The frame is captured, not described: the renderer draws `frames` frames of the kit's scene
//! at the kit's size, paused, under a [`crate::counters::capture`], and the last frame's
//! commands are the manifest. What the kit does not hold yet is listed in
//! [`manifest::NOT_YET`] and said in every kit.

use std::path::{Path, PathBuf};

use crate::counters::capture;
use crate::export::{Export, ExportFormat};
use crate::{GpuContext, LabSettings, Renderer};

pub mod expressions;
pub mod golden;
pub mod joint_fit;
pub mod loops;
pub mod manifest;
pub mod reflect;
pub mod settings_probe;
pub mod translate;
pub mod uniforms;
pub mod verify;

pub use manifest::Manifest;

/// What to export.
#[derive(Clone)]
pub struct KitRequest<'a> {
    /// The preset's name (its file stem), for the manifest and the README.
    pub preset: &'a str,
    pub settings: LabSettings,
    pub scene: crate::scene::Scene,
    /// The scene file, or the embedded scene's name (the export's provenance).
    pub scene_name: &'a str,
    pub size: (u32, u32),
    /// Frames drawn from a fresh start and recorded in the goldens (at least 2).
    pub frames: u32,
    /// Whether to read back every pass's outputs into `golden/` (the command line and the
    /// window do; a test of the manifest alone may not).
    pub goldens: bool,
    /// The camera (the window's live one); None: the scene's opening view.
    pub camera: Option<crate::camera::Camera>,
    /// Whether to fit sizes and counts as expressions of W and H (six more captures of
    /// two frames at the probe sizes, `expressions::PROBES`) and of the settings (two more per
    /// integer setting in use, `settings_probe`).
    pub expressions: bool,
    /// With `expressions`: the settings to vary (None: every integer setting in use).
    pub settings_probed: Option<&'a [&'a str]>,
}

/// A kit in memory: the manifest, the export and the files to write (relative path, bytes).
pub struct Kit {
    pub manifest: Manifest,
    pub export: Export,
    pub files: Vec<(PathBuf, Vec<u8>)>,
}

/// Draws the request's frames under a capture and builds the kit.
pub fn build(ctx: GpuContext, req: KitRequest) -> Result<Kit, String> {
    let (w, h) = req.size;
    if w == 0 || h == 0 {
        return Err(format!("the kit's size {w}×{h} has no pixels"));
    }
    if req.goldens {
        capture::start_with_goldens();
    } else {
        capture::start();
    }
    let result = draw(ctx.clone(), &req);
    let objects = capture::stop();
    let (frames, export) = result?;
    let objects = objects.ok_or("the capture was stopped by someone else")?;
    let mut built = manifest::build(req.preset, req.size, &frames, &objects)?;
    if req.expressions {
        fit_expressions(&ctx, &req, &mut built.manifest)?;
    }
    let (golden, mut files) = golden::goldens(&built, &frames, &objects);
    files.extend(built.uploads.iter().cloned());
    let mut manifest = built.manifest;
    manifest.golden = golden;
    uniforms::decode(&mut manifest, &files);
    for s in &manifest.shaders {
        let source = crate::shaders::resolve(&s.module).map_err(|e| format!("{}: {e}", s.module))?;
        files.push((PathBuf::from(&s.file), source.into_bytes()));
    }
    // Every entry point the frames run, with its constants, in each engine's language.
    let mut variants: Vec<Variant> = Vec::new();
    for pass in manifest.frame_passes.iter().flatten() {
        for step in &pass.steps {
            for (module, entry) in &step.entry_points {
                let v = (module.clone(), entry.clone(), step.constants.clone());
                if !variants.contains(&v) {
                    variants.push(v);
                }
            }
        }
    }
    for (module, entry, constants) in variants {
        let shader = manifest.shaders.iter().find(|s| s.module == module);
        let stage = shader
            .and_then(|s| s.decl.entry_points.iter().find(|e| e.name == entry))
            .map(|e| e.stage.clone())
            .unwrap_or_default();
        let source = crate::shaders::resolve(&module).map_err(|e| format!("{module}: {e}"))?;
        let (t, mut out) = translate::translate(&module, &source, &entry, &stage, &constants);
        manifest.translations.push(t);
        files.append(&mut out);
    }
    let json = serde_json::to_string_pretty(&manifest).map_err(|e| format!("manifest: {e}"))?;
    files.push((PathBuf::from("manifest.json"), json.into_bytes()));
    files.push((PathBuf::from("preset.json"), export.to_text(ExportFormat::Json).into_bytes()));
    files.push((PathBuf::from("README.md"), readme(&manifest, &export).into_bytes()));
    Ok(Kit { manifest, export, files })
}

/// An entry point with its pipeline constants: (module, entry, constants).
type Variant = (String, String, Vec<(String, f64)>);

type Frames = Vec<Vec<capture::PassCommands>>;

/// The frames of the capture (the renderer is made inside it, so that its objects are known):
/// every frame's commands with their read-backs, and the export of what was drawn.
fn draw(ctx: GpuContext, req: &KitRequest) -> Result<(Frames, Export), String> {
    let (w, h) = req.size;
    let mut r = Renderer::new(ctx, req.scene.clone(), req.settings.clone(), w, h).map_err(|e| e.to_string())?;
    r.clock.playing = false;
    if let Some(c) = req.camera {
        r.camera = c;
    }
    // Every pass every frame: a kit lists the whole frame, not what a still view could keep.
    r.reuse_unchanged = false;
    let mut frames = Vec::new();
    for _ in 0..req.frames.max(2) {
        capture::take_passes();
        r.render_frame();
        frames.push(capture::take_passes());
    }
    let view = super::ExportView::of_scene(req.scene_name, r.scene(), r.bounds(), r.camera, r.size(), r.settings());
    let export = Export::new(r.settings().clone(), super::Provenance::now(&view));
    Ok((frames, export))
}

/// The frame captured again at the probe sizes and with the settings changed, and the
/// expressions fitted to them ([`expressions`], [`settings_probe`], [`joint_fit`]).
fn fit_expressions(ctx: &GpuContext, req: &KitRequest, m: &mut Manifest) -> Result<(), String> {
    // Two frames of the request at `size` with `settings`: the manifest, or the renderer's
    // refusal (an ISM atlas over this device's limits).
    let capture_at = |settings: &LabSettings, size: (u32, u32)| -> Result<Result<Manifest, String>, String> {
        capture::start();
        let probe = KitRequest {
            settings: settings.clone(),
            size,
            frames: 2,
            goldens: false,
            expressions: false,
            ..req.clone()
        };
        let result = draw(ctx.clone(), &probe);
        let objects = capture::stop().ok_or("the capture was stopped by someone else")?;
        match result {
            Ok((frames, _)) => Ok(Ok(manifest::build(req.preset, size, &frames, &objects)?.manifest)),
            Err(e) => Ok(Err(e)),
        }
    };
    let mut images = Vec::new();
    for size in expressions::PROBES {
        images.push((size, capture_at(&req.settings, size)??));
    }
    let (fitted, left) = expressions::annotate(m, &images);
    // Each integer setting in use at two nearby values and a neighbour, at one probe size; a value
    // this device cannot draw (double the VPLs overflow the ISM atlas) is listed with the
    // renderer's reason and the next is tried.
    let variants = settings_probe::variants(&req.settings, req.settings_probed);
    let mut refused: Vec<serde_json::Value> = Vec::new();
    let mut c = settings_probe::Captured { images: &images, variants: Vec::new(), joints: Vec::new() };
    for v in &variants {
        let mut got = Vec::new();
        for (x, settings) in &v.others {
            if got.len() == 2 {
                break;
            }
            match capture_at(settings, expressions::PROBES[settings_probe::AT])? {
                Ok(mm) => got.push((*x, mm)),
                Err(e) => refused.push(serde_json::json!({"setting": v.path, "value": x, "reason": e})),
            }
        }
        let values: Vec<u32> = got.iter().map(|g| g.0).collect();
        if let (2, Some((x, settings))) = (got.len(), v.neighbour(&values)) {
            match capture_at(settings, expressions::PROBES[settings_probe::AT])? {
                Ok(mm) => got.push((*x, mm)),
                Err(e) => refused.push(serde_json::json!({"setting": v.path, "value": x, "reason": e})),
            }
        }
        if got.len() >= 2 {
            c.variants.push((v, got));
        }
    }
    // The settings a number follows together, changed together at two other sizes: each to
    // its first other value, each to its second, then the two mixed.
    for names in settings_probe::joint_sets(m, &c) {
        let values: Vec<[u32; 2]> = names
            .iter()
            .filter_map(|n| c.variants.iter().find(|(v, _)| &v.path == n).map(|(_, g)| [g[0].0, g[1].0]))
            .collect();
        let mut done = 0;
        for pick in 0..4usize {
            if done == 2 {
                break;
            }
            let chosen: Vec<(String, u32)> = names
                .iter()
                .zip(&values)
                .enumerate()
                .map(|(i, (n, o))| (n.clone(), o[(pick + i * (pick / 2)) % 2]))
                .collect();
            let mut s = req.settings.clone();
            if chosen.iter().any(|(n, x)| s.set(n, &crate::settings::Value::U32(*x)).is_err())
                || !s.validate().is_empty()
            {
                continue;
            }
            // Two sizes other than the variants': the first probe's and the last's.
            let size = expressions::PROBES[[0, 5][done]];
            match capture_at(&s, size)? {
                Ok(manifest) => {
                    c.joints.push(settings_probe::Joint { settings: chosen, size, manifest });
                    done += 1;
                }
                Err(e) => refused.push(serde_json::json!({"settings": chosen, "reason": e})),
            }
        }
    }
    let (following, in_settings) = settings_probe::annotate(m, &c);
    loops::annotate(m, &c);
    m.expressions = Some(serde_json::json!({
        "variables": {"W": "the image's width", "H": "its height", "group.field": "a setting (preset.json)"},
        "probes": expressions::PROBES,
        "fitted": fitted,
        "as_captured": left,
        "settings_varied": c.variants.iter().map(|(v, got)| serde_json::json!({
            "setting": v.path, "value": v.value, "others": got.iter().map(|o| o.0).collect::<Vec<_>>()
        })).collect::<Vec<_>>(),
        "settings_together": c.joints.iter().map(|j| serde_json::json!({
            "settings": j.settings, "size": [j.size.0, j.size.1]
        })).collect::<Vec<_>>(),
        "settings_refused": refused,
        "following_a_setting": following,
        "fitted_in_a_setting": in_settings,
    }));
    Ok(())
}

/// Writes `kit` to `dir` whole or not at all: into a new folder beside it, renamed into place.
/// An existing `dir` is refused unless `force`, and then replaced only once the new kit is
/// complete.
pub fn write(kit: &Kit, dir: &Path, force: bool) -> Result<(), String> {
    if dir.exists() && !force {
        return Err(format!("{} exists: choose another folder or pass --force to replace it", dir.display()));
    }
    let parent = dir.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let stem = dir.file_name().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| "kit".into());
    let tmp = parent.join(format!(".{stem}.writing-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let written = (|| -> std::io::Result<()> {
        for (rel, text) in &kit.files {
            let path = tmp.join(rel);
            if let Some(p) = path.parent() {
                std::fs::create_dir_all(p)?;
            }
            std::fs::write(&path, text)?;
        }
        Ok(())
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(format!("{}: {e}", tmp.display()));
    }
    if dir.exists() {
        let old = parent.join(format!(".{stem}.old-{}", std::process::id()));
        std::fs::rename(dir, &old).map_err(|e| format!("{}: {e}", dir.display()))?;
        if let Err(e) = std::fs::rename(&tmp, dir) {
            let _ = std::fs::rename(&old, dir);
            return Err(format!("{}: {e}", dir.display()));
        }
        let _ = std::fs::remove_dir_all(&old);
    } else {
        std::fs::rename(&tmp, dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    Ok(())
}

/// The first comment paragraph of a shader's own file (its header cites the paper's section
/// and equation), joined into one line.
fn header(module: &str) -> String {
    let source = crate::shaders::SOURCES.iter().find(|(p, _)| *p == module).map(|(_, s)| *s).unwrap_or("");
    source
        .lines()
        .take_while(|l| l.trim_start().starts_with("//"))
        .map(|l| l.trim_start().trim_start_matches('/').trim())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The kit's README: the passes in order with the papers' sections, the order to bring them
/// up, and what the kit does not hold yet.
/// The README's section on sizes at another size and settings, with the kit's loops.
fn loops(m: &Manifest) -> String {
    let mut s = String::from("\n## At your own size and settings\n\n");
    if m.expressions.is_none() {
        s += "This kit was exported without expressions (`--no-expressions`): its sizes and counts hold at its own \
              size and settings only.\n";
        return s;
    }
    s += "Every resource's `size_expr` and every step's `counts_expr` give its size and counts as expressions of the \
          image's W and H and of the settings (by their names in `preset.json`), where one was fitted (`docs/port-kit.md`, \
          \"Sizes as expressions\"). The frame's loops, with their counts and each iteration's workgroups as \
          expressions of the iteration `i` and the count `n`:\n\n| pass | pipeline | runs | count | each iteration \
          (x, y, z) |\n|---|---|---:|---|---|\n";
    let text = |e: &Option<String>| e.as_deref().map_or("as listed".to_string(), |e| format!("`{e}`"));
    let mut any = false;
    for pass in &m.passes {
        for r in &pass.runs {
            any = true;
            let each: Vec<String> = r.iteration_expr.iter().map(text).collect();
            s += &format!(
                "| `{}` | `{}` | {} | {} | {} |\n",
                pass.name,
                r.pipeline.as_deref().unwrap_or(""),
                r.count,
                text(&r.count_expr),
                each.join(", ")
            );
        }
    }
    if !any {
        s += "| (none) | | | | |\n";
    }
    if !m.repeated_passes.is_empty() {
        s += "\nPasses repeated per round or per level:\n\n| passes | count | first level |\n|---|---|---|\n";
        for r in &m.repeated_passes {
            let first = r.first.map_or(String::new(), |k| format!("{k}: {}", text(&r.first_expr)));
            s += &format!("| `{}` | {}: {} | {} |\n", r.name, r.count, text(&r.count_expr), first);
        }
    }
    s
}

fn readme(m: &Manifest, e: &Export) -> String {
    let mut s = format!("# Port kit: `{}`\n\n", m.preset);
    let p = &e.provenance;
    s += &format!(
        "Exported by GI Lab {} on {} from `{}` at {}×{}, paused, {} frames from a fresh start. \
         Schema `{}` version {}; the manifest's fields are documented in GI Lab's `docs/port-kit.md`.\n\n",
        p.gi_lab_version, p.date, p.scene, m.size[0], m.size[1], m.frames, m.schema, m.schema_version
    );
    s += "- `manifest.json`: the frame as the ordered list of its passes; each pass's steps (dispatches, draws, \
          copies) with the pipeline, entry points and every binding in force; the resources with formats, sizes \
          and lifetimes (`input`, `history`, `frame`); each shader's bindings and uniform layouts.\n";
    s += "- `preset.json`: the settings in use, where they were tuned, and every scene- or image-relative value \
          as set and as resolved.\n";
    s += "- `shaders/`: each module as WGSL with its imports resolved, and each entry point the frame runs in SPIR-V, \
          GLSL, HLSL and MSL (below).\n";
    s += "- `golden/`: every frame's inputs and every pass's outputs as GI Lab drew them (below).\n\n";
    s += "## Bring-up order\n\n";
    s += "1. Feed the `engine` passes' outputs from your engine (the G-buffer and direct light, in the formats the \
          manifest lists), or port them too.\n";
    s += "2. Create every `history` resource zeroed; it holds the last frame's result from the second frame on.\n";
    s += "3. Port the `technique` passes in the order below, one at a time, checking each against GI Lab.\n";
    s += "4. Compose and tone-map (`tail`) as your engine does.\n\n";
    s += "## The passes in order\n\n| # | pass | role | steps | shaders (entry points) |\n|---|---|---|---:|---|\n";
    for pass in &m.passes {
        let mut entries: Vec<String> = Vec::new();
        for st in &pass.steps {
            for (module, entry) in &st.entry_points {
                let e = format!("`{module}` `{entry}`");
                if !entries.contains(&e) {
                    entries.push(e);
                }
            }
        }
        s += &format!(
            "| {} | `{}` | {} | {} | {} |\n",
            pass.index,
            pass.name,
            pass.role,
            pass.steps.len(),
            entries.join(", ")
        );
    }
    s += &loops(m);
    s += "\n## What each shader does (its header, citing the paper)\n\n";
    for sh in &m.shaders {
        let h = header(&sh.module);
        if !h.is_empty() {
            s += &format!("- `{}`: {}\n", sh.module, h);
        }
    }
    s += "\n## Checking your port\n\n";
    s += &format!(
        "`golden/frame-K/` holds, for each of the {} frames from a fresh start, the inputs to upload (`inputs/`) and \
         every pass's outputs (`NN-pass/`), raw bytes in each resource's format (levels, then layers, rows packed), \
         with an `.exr` of float images. Write your port's outputs to the `path` each golden names in `manifest.json` \
         and run:\n\n```sh\ngi-lab verify --port-kit <this folder> --outputs <your outputs> --tolerance 0.01\n```\n\n\
         It names the first pass that diverges and by how much. GI Lab's `examples/port-kit-host` is a port of \
         this kit to plain wgpu that reads nothing but the kit (`docs/port-kit.md`, \"Bringing a kit up\"): each \
         frame uploads `golden[K].inputs`, runs `frame_passes[K]` step by step (`upload` steps are queue writes before \
         the pass's commands) and writes every pass's outputs for `gi-lab verify`.\n",
        m.frames
    );
    s += "\n## The shaders in your engine's language\n\n";
    s += "Each entry point the frame runs, with the pipeline's constants baked in, translated by naga: \
          `shaders/spirv/*.spv` (SPIR-V 1.3), `shaders/glsl/*.{comp,vert,frag}` (GLSL 4.50), `shaders/hlsl/*.hlsl` \
          (shader model 6.0), `shaders/msl/*.metal` (MSL 2.4). GI Lab checks the SPIR-V with `spirv-val` and the GLSL \
          with `glslangValidator`; the HLSL and MSL are naga's output, not compiled here (no DXC or Metal compiler on \
          GI Lab's test machines).\n\n| module | entry | constants | spirv | glsl | hlsl | msl |\n|---|---|---|---|---|---|---|\n";
    for t in &m.translations {
        let constants: Vec<String> = t.constants.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        let cells: Vec<String> = t
            .files
            .iter()
            .map(|(_, r)| match r {
                Ok(f) => format!("`{}`", f.rsplit('/').next().unwrap_or(f)),
                Err(e) => format!("**failed**: {}", e.lines().next().unwrap_or("")),
            })
            .collect();
        s += &format!("| `{}` | `{}` | {} | {} |\n", t.module, t.entry, constants.join(", "), cells.join(" | "));
    }
    s += "\n## Not yet in the kit\n\n";
    for n in &m.not_yet {
        s += &format!("- {n}\n");
    }
    s
}
