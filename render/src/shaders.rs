//! WGSL sources and the one import mechanism (docs/principles.md principle 8).
//!
//! Shaders live in the top-level `shaders/` folder: `common/` holds shared code, and each
//! pass has its own folder. A line `#import common/name.wgsl` is replaced by that file
//! (each file is included once per module). The sources are embedded in the binary so
//! that the app and the CLI run anywhere; a test resolves and validates every file with
//! naga.

/// Every WGSL file: (path relative to `shaders/`, source).
pub const SOURCES: &[(&str, &str)] = &[
    ("common/camera.wgsl", include_str!("../../shaders/common/camera.wgsl")),
    ("common/material.wgsl", include_str!("../../shaders/common/material.wgsl")),
    ("common/brdf.wgsl", include_str!("../../shaders/common/brdf.wgsl")),
    ("common/split_light.wgsl", include_str!("../../shaders/common/split_light.wgsl")),
    ("common/normal.wgsl", include_str!("../../shaders/common/normal.wgsl")),
    ("common/receiver.wgsl", include_str!("../../shaders/common/receiver.wgsl")),
    ("common/lights.wgsl", include_str!("../../shaders/common/lights.wgsl")),
    ("common/fullscreen.wgsl", include_str!("../../shaders/common/fullscreen.wgsl")),
    ("gbuffer/gbuffer.wgsl", include_str!("../../shaders/gbuffer/gbuffer.wgsl")),
    ("gbuffer/position.wgsl", include_str!("../../shaders/gbuffer/position.wgsl")),
    ("gbuffer/normal.wgsl", include_str!("../../shaders/gbuffer/normal.wgsl")),
    ("gbuffer/no_emission.wgsl", include_str!("../../shaders/gbuffer/no_emission.wgsl")),
    ("gbuffer/material.wgsl", include_str!("../../shaders/gbuffer/material.wgsl")),
    ("shadow/shadow.wgsl", include_str!("../../shaders/shadow/shadow.wgsl")),
    ("direct/direct.wgsl", include_str!("../../shaders/direct/direct.wgsl")),
    ("direct/sky_history.wgsl", include_str!("../../shaders/direct/sky_history.wgsl")),
    ("compose/luminance.wgsl", include_str!("../../shaders/compose/luminance.wgsl")),
    ("compose/compose.wgsl", include_str!("../../shaders/compose/compose.wgsl")),
    ("compose/tonemap.wgsl", include_str!("../../shaders/compose/tonemap.wgsl")),
    ("compose/reinhard.wgsl", include_str!("../../shaders/compose/reinhard.wgsl")),
    ("common/random.wgsl", include_str!("../../shaders/common/random.wgsl")),
    ("common/vpl.wgsl", include_str!("../../shaders/common/vpl.wgsl")),
    ("reference/sample.wgsl", include_str!("../../shaders/reference/sample.wgsl")),
    ("reference/shadow.wgsl", include_str!("../../shaders/reference/shadow.wgsl")),
    ("reference/gather.wgsl", include_str!("../../shaders/reference/gather.wgsl")),
    ("reference/explain.wgsl", include_str!("../../shaders/reference/explain.wgsl")),
    ("reference/gather_params.wgsl", include_str!("../../shaders/reference/gather_params.wgsl")),
    ("common/vpl_explain.wgsl", include_str!("../../shaders/common/vpl_explain.wgsl")),
    ("common/light_view.wgsl", include_str!("../../shaders/common/light_view.wgsl")),
    ("common/ism.wgsl", include_str!("../../shaders/common/ism.wgsl")),
    ("common/bounce.wgsl", include_str!("../../shaders/common/bounce.wgsl")),
    ("common/reproject.wgsl", include_str!("../../shaders/common/reproject.wgsl")),
    ("common/bins.wgsl", include_str!("../../shaders/common/bins.wgsl")),
    ("knecht/vpl/importance.wgsl", include_str!("../../shaders/knecht/vpl/importance.wgsl")),
    ("knecht/vpl/reduce.wgsl", include_str!("../../shaders/knecht/vpl/reduce.wgsl")),
    ("knecht/vpl/warp.wgsl", include_str!("../../shaders/knecht/vpl/warp.wgsl")),
    ("knecht/vpl/bounce.wgsl", include_str!("../../shaders/knecht/vpl/bounce.wgsl")),
    ("knecht/vpl/irsm.wgsl", include_str!("../../shaders/knecht/vpl/irsm.wgsl")),
    ("knecht/ism/splat.wgsl", include_str!("../../shaders/knecht/ism/splat.wgsl")),
    ("knecht/ism/resolve.wgsl", include_str!("../../shaders/knecht/ism/resolve.wgsl")),
    ("knecht/ism/pull_push.wgsl", include_str!("../../shaders/knecht/ism/pull_push.wgsl")),
    ("knecht/interleave/split.wgsl", include_str!("../../shaders/knecht/interleave/split.wgsl")),
    ("knecht/interleave/gather.wgsl", include_str!("../../shaders/knecht/interleave/gather.wgsl")),
    ("knecht/interleave/merge.wgsl", include_str!("../../shaders/knecht/interleave/merge.wgsl")),
    ("knecht/interleave/filter.wgsl", include_str!("../../shaders/knecht/interleave/filter.wgsl")),
    ("knecht/interleave/filter_window.wgsl", include_str!("../../shaders/knecht/interleave/filter_window.wgsl")),
    ("knecht/interleave/explain.wgsl", include_str!("../../shaders/knecht/interleave/explain.wgsl")),
    ("knecht/interleave/params.wgsl", include_str!("../../shaders/knecht/interleave/params.wgsl")),
    ("knecht/temporal/confidence.wgsl", include_str!("../../shaders/knecht/temporal/confidence.wgsl")),
    ("knecht/temporal/merge.wgsl", include_str!("../../shaders/knecht/temporal/merge.wgsl")),
    ("knecht/temporal/filter_merge.wgsl", include_str!("../../shaders/knecht/temporal/filter_merge.wgsl")),
    ("hcb/common.wgsl", include_str!("../../shaders/hcb/common.wgsl")),
    ("hcb/base.wgsl", include_str!("../../shaders/hcb/base.wgsl")),
    ("hcb/build.wgsl", include_str!("../../shaders/hcb/build.wgsl")),
    ("hcb/samples.wgsl", include_str!("../../shaders/hcb/samples.wgsl")),
    ("hcb/splat.wgsl", include_str!("../../shaders/hcb/splat.wgsl")),
    ("hcb/gather.wgsl", include_str!("../../shaders/hcb/gather.wgsl")),
    ("hcb/normalize.wgsl", include_str!("../../shaders/hcb/normalize.wgsl")),
    ("hcb/cache.wgsl", include_str!("../../shaders/hcb/cache.wgsl")),
    ("hcb/cache_removal.wgsl", include_str!("../../shaders/hcb/cache_removal.wgsl")),
    ("hcb/explain.wgsl", include_str!("../../shaders/hcb/explain.wgsl")),
    ("soler/common.wgsl", include_str!("../../shaders/soler/common.wgsl")),
    ("soler/vote.wgsl", include_str!("../../shaders/soler/vote.wgsl")),
    ("soler/gather.wgsl", include_str!("../../shaders/soler/gather.wgsl")),
    ("soler/upsample.wgsl", include_str!("../../shaders/soler/upsample.wgsl")),
    ("soler/jbu.wgsl", include_str!("../../shaders/soler/jbu.wgsl")),
    ("soler/explain.wgsl", include_str!("../../shaders/soler/explain.wgsl")),
    ("soler/explain_ring.wgsl", include_str!("../../shaders/soler/explain_ring.wgsl")),
    ("soler/resolve.wgsl", include_str!("../../shaders/soler/resolve.wgsl")),
    ("soler/voxel_common.wgsl", include_str!("../../shaders/soler/voxel_common.wgsl")),
    ("soler/voxelize.wgsl", include_str!("../../shaders/soler/voxelize.wgsl")),
    ("soler/voxel_down.wgsl", include_str!("../../shaders/soler/voxel_down.wgsl")),
    ("soler/voxel_view.wgsl", include_str!("../../shaders/soler/voxel_view.wgsl")),
    ("soler/temporal.wgsl", include_str!("../../shaders/soler/temporal.wgsl")),
    ("soler/bounces.wgsl", include_str!("../../shaders/soler/bounces.wgsl")),
    ("soler/glossy.wgsl", include_str!("../../shaders/soler/glossy.wgsl")),
    ("soler/ring.wgsl", include_str!("../../shaders/soler/ring.wgsl")),
    ("soler/ring_texel.wgsl", include_str!("../../shaders/soler/ring_texel.wgsl")),
    ("soler/hcb_gather.wgsl", include_str!("../../shaders/soler/hcb_gather.wgsl")),
    ("gautron/common.wgsl", include_str!("../../shaders/gautron/common.wgsl")),
    ("gautron/create.wgsl", include_str!("../../shaders/gautron/create.wgsl")),
    ("gautron/hemisphere.wgsl", include_str!("../../shaders/gautron/hemisphere.wgsl")),
    ("gautron/reduce.wgsl", include_str!("../../shaders/gautron/reduce.wgsl")),
    ("gautron/splat.wgsl", include_str!("../../shaders/gautron/splat.wgsl")),
    ("gautron/resolve.wgsl", include_str!("../../shaders/gautron/resolve.wgsl")),
    ("gautron/vpl_records.wgsl", include_str!("../../shaders/gautron/vpl_records.wgsl")),
    ("gautron/at_samples.wgsl", include_str!("../../shaders/gautron/at_samples.wgsl")),
    ("gautron/explain.wgsl", include_str!("../../shaders/gautron/explain.wgsl")),
    ("view/view.wgsl", include_str!("../../shaders/view/view.wgsl")),
    ("view/probe.wgsl", include_str!("../../shaders/view/probe.wgsl")),
    ("rays/scene.wgsl", include_str!("../../shaders/rays/scene.wgsl")),
    ("rays/cast.wgsl", include_str!("../../shaders/rays/cast.wgsl")),
    ("rays/lights.wgsl", include_str!("../../shaders/rays/lights.wgsl")),
    ("rays/shade.wgsl", include_str!("../../shaders/rays/shade.wgsl")),
    ("rays/pathtrace.wgsl", include_str!("../../shaders/rays/pathtrace.wgsl")),
    ("ddgi/probes.wgsl", include_str!("../../shaders/ddgi/probes.wgsl")),
    ("ddgi/blend.wgsl", include_str!("../../shaders/ddgi/blend.wgsl")),
    ("ddgi/lookup.wgsl", include_str!("../../shaders/ddgi/lookup.wgsl")),
    ("ddgi/trace.wgsl", include_str!("../../shaders/ddgi/trace.wgsl")),
    ("ddgi/apply.wgsl", include_str!("../../shaders/ddgi/apply.wgsl")),
    ("ddgi/view.wgsl", include_str!("../../shaders/ddgi/view.wgsl")),
    ("ddgi/explain.wgsl", include_str!("../../shaders/ddgi/explain.wgsl")),
];

/// Files that are entry modules (not only imported).
pub const ENTRY_MODULES: &[&str] = &[
    "gbuffer/gbuffer.wgsl",
    "gbuffer/position.wgsl",
    "gbuffer/normal.wgsl",
    "gbuffer/no_emission.wgsl",
    "gbuffer/material.wgsl",
    "shadow/shadow.wgsl",
    "direct/direct.wgsl",
    "direct/sky_history.wgsl",
    "compose/luminance.wgsl",
    "compose/compose.wgsl",
    "compose/tonemap.wgsl",
    "reference/sample.wgsl",
    "reference/shadow.wgsl",
    "reference/gather.wgsl",
    "reference/explain.wgsl",
    "knecht/vpl/importance.wgsl",
    "knecht/vpl/reduce.wgsl",
    "knecht/vpl/warp.wgsl",
    "knecht/vpl/bounce.wgsl",
    "knecht/vpl/irsm.wgsl",
    "knecht/ism/splat.wgsl",
    "knecht/ism/resolve.wgsl",
    "knecht/ism/pull_push.wgsl",
    "knecht/interleave/split.wgsl",
    "knecht/interleave/gather.wgsl",
    "knecht/interleave/merge.wgsl",
    "knecht/interleave/filter.wgsl",
    "knecht/interleave/explain.wgsl",
    "knecht/temporal/confidence.wgsl",
    "knecht/temporal/filter_merge.wgsl",
    "hcb/base.wgsl",
    "hcb/build.wgsl",
    "hcb/samples.wgsl",
    "hcb/splat.wgsl",
    "hcb/gather.wgsl",
    "hcb/normalize.wgsl",
    "hcb/cache.wgsl",
    "hcb/cache_removal.wgsl",
    "hcb/explain.wgsl",
    "gautron/create.wgsl",
    "gautron/hemisphere.wgsl",
    "gautron/reduce.wgsl",
    "gautron/splat.wgsl",
    "gautron/resolve.wgsl",
    "gautron/vpl_records.wgsl",
    "gautron/at_samples.wgsl",
    "gautron/explain.wgsl",
    "soler/vote.wgsl",
    "soler/gather.wgsl",
    "soler/upsample.wgsl",
    "soler/explain.wgsl",
    "soler/explain_ring.wgsl",
    "soler/resolve.wgsl",
    "soler/voxelize.wgsl",
    "soler/voxel_down.wgsl",
    "soler/voxel_view.wgsl",
    "soler/temporal.wgsl",
    "soler/bounces.wgsl",
    "soler/hcb_gather.wgsl",
    "view/view.wgsl",
    "view/probe.wgsl",
    "rays/cast.wgsl",
    "rays/pathtrace.wgsl",
    "ddgi/blend.wgsl",
    "ddgi/trace.wgsl",
    "ddgi/apply.wgsl",
    "ddgi/view.wgsl",
    "ddgi/explain.wgsl",
];

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ShaderError {
    #[error("shader '{0}' does not exist")]
    Missing(String),
    #[error("shader '{file}' line {line}: bad #import directive '{text}'")]
    BadImport { file: String, line: usize, text: String },
}

/// Sources that replace the embedded ones (the app's shader hot reload sets them from the
/// files on disk; everything else uses the embedded table).
static OVERRIDES: std::sync::RwLock<Vec<(String, String)>> = std::sync::RwLock::new(Vec::new());

/// Replaces the source of `path` (a file of [`SOURCES`]) for every module created from now on.
pub fn set_override(path: &str, source: &str) -> Result<(), ShaderError> {
    if !SOURCES.iter().any(|(p, _)| *p == path) {
        return Err(ShaderError::Missing(path.to_string()));
    }
    let mut o = OVERRIDES.write().unwrap_or_else(|e| e.into_inner());
    o.retain(|(p, _)| p != path);
    o.push((path.to_string(), source.to_string()));
    Ok(())
}

/// Drops the override of `path` (back to the embedded source).
pub fn clear_override(path: &str) {
    OVERRIDES.write().unwrap_or_else(|e| e.into_inner()).retain(|(p, _)| p != path);
}

/// The override of `path`, if any.
pub fn override_of(path: &str) -> Option<String> {
    OVERRIDES.read().unwrap_or_else(|e| e.into_inner()).iter().find(|(p, _)| p == path).map(|(_, s)| s.clone())
}

fn source(path: &str) -> Result<String, ShaderError> {
    if let Some(s) = override_of(path) {
        return Ok(s);
    }
    SOURCES
        .iter()
        .find(|(p, _)| *p == path)
        .map(|(_, s)| s.to_string())
        .ok_or_else(|| ShaderError::Missing(path.to_string()))
}

/// Every file `path` includes, itself first (its `#import` closure).
pub fn closure(path: &str) -> Result<Vec<String>, ShaderError> {
    let mut seen = Vec::new();
    let mut out = String::new();
    resolve_into(path, &mut out, &mut seen, None)?;
    Ok(seen)
}

/// The entry modules that include `file` (directly or through imports): what a change of
/// `file` affects.
pub fn dependents(file: &str) -> Vec<&'static str> {
    ENTRY_MODULES.iter().copied().filter(|e| closure(e).is_ok_and(|c| c.iter().any(|f| f == file))).collect()
}

/// Resolves and validates an entry module with naga (WGSL front end + validator), as the
/// hot reload does before it touches any pipeline. The error names the file and line.
pub fn validate(path: &str) -> Result<(), String> {
    validate_candidate(path, None)
}

/// [`validate`] as if `candidate` = (file, source) replaced that file, without installing
/// it (other threads keep creating modules from the current sources meanwhile).
pub fn validate_candidate(path: &str, candidate: Option<(&str, &str)>) -> Result<(), String> {
    let mut code = String::new();
    let mut seen = Vec::new();
    resolve_into(path, &mut code, &mut seen, candidate).map_err(|e| e.to_string())?;
    let module = naga::front::wgsl::parse_str(&code).map_err(|e| format!("{path}: {}", e.emit_to_string(&code)))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| format!("{path}: {}", e.emit_to_string(&code)))?;
    Ok(())
}

/// Resolves `#import` lines of the module at `path` into one WGSL source.
pub fn resolve(path: &str) -> Result<String, ShaderError> {
    let mut out = String::new();
    let mut seen = Vec::new();
    resolve_into(path, &mut out, &mut seen, None)?;
    Ok(out)
}

fn resolve_into(
    path: &str,
    out: &mut String,
    seen: &mut Vec<String>,
    candidate: Option<(&str, &str)>,
) -> Result<(), ShaderError> {
    if seen.iter().any(|s| s == path) {
        return Ok(());
    }
    seen.push(path.to_string());
    let src = match candidate {
        Some((file, text)) if file == path => text.to_string(),
        _ => source(path)?,
    };
    for (i, line) in src.lines().enumerate() {
        let t = line.trim_start();
        if let Some(rest) = t.strip_prefix("#import") {
            let name = rest.trim();
            if name.is_empty() || name.contains(char::is_whitespace) {
                return Err(ShaderError::BadImport { file: path.into(), line: i + 1, text: line.into() });
            }
            resolve_into(name, out, seen, candidate)?;
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    Ok(())
}

/// Creates a shader module from a resolved entry file; the label is `<pass>.shader`.
pub fn create_module(device: &wgpu::Device, path: &str) -> wgpu::ShaderModule {
    let code = resolve(path).unwrap_or_else(|e| panic!("embedded shader table is inconsistent: {e}"));
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(path),
        source: wgpu::ShaderSource::Wgsl(code.into()),
    });
    crate::counters::capture::remember_module(&module, path);
    module
}
