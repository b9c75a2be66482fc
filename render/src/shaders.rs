//! WGSL sources and the one import mechanism (DESIGN.md principle 8).
//!
//! Shaders live in the top-level `shaders/` folder: `common/` holds shared code, and each
//! pass has its own folder. A line `#import common/name.wgsl` is replaced by that file
//! (each file is included once per module). The sources are embedded in the binary so
//! that the app and the CLI run anywhere; a test resolves and validates every file with
//! naga.

/// Every WGSL file: (path relative to `shaders/`, source).
pub const SOURCES: &[(&str, &str)] = &[
    ("common/camera.wgsl", include_str!("../../shaders/common/camera.wgsl")),
    ("common/brdf.wgsl", include_str!("../../shaders/common/brdf.wgsl")),
    ("common/lights.wgsl", include_str!("../../shaders/common/lights.wgsl")),
    ("common/fullscreen.wgsl", include_str!("../../shaders/common/fullscreen.wgsl")),
    ("gbuffer/gbuffer.wgsl", include_str!("../../shaders/gbuffer/gbuffer.wgsl")),
    ("shadow/shadow.wgsl", include_str!("../../shaders/shadow/shadow.wgsl")),
    ("direct/direct.wgsl", include_str!("../../shaders/direct/direct.wgsl")),
    ("compose/luminance.wgsl", include_str!("../../shaders/compose/luminance.wgsl")),
    ("compose/compose.wgsl", include_str!("../../shaders/compose/compose.wgsl")),
    ("compose/tonemap.wgsl", include_str!("../../shaders/compose/tonemap.wgsl")),
    ("common/vpl.wgsl", include_str!("../../shaders/common/vpl.wgsl")),
    ("vpl/sample.wgsl", include_str!("../../shaders/vpl/sample.wgsl")),
    ("vpl/shadow.wgsl", include_str!("../../shaders/vpl/shadow.wgsl")),
    ("vpl/gather.wgsl", include_str!("../../shaders/vpl/gather.wgsl")),
    ("view/view.wgsl", include_str!("../../shaders/view/view.wgsl")),
    ("view/probe.wgsl", include_str!("../../shaders/view/probe.wgsl")),
];

/// Files that are entry modules (not only imported).
pub const ENTRY_MODULES: &[&str] = &[
    "gbuffer/gbuffer.wgsl",
    "shadow/shadow.wgsl",
    "direct/direct.wgsl",
    "compose/luminance.wgsl",
    "compose/compose.wgsl",
    "compose/tonemap.wgsl",
    "vpl/sample.wgsl",
    "vpl/shadow.wgsl",
    "vpl/gather.wgsl",
    "view/view.wgsl",
    "view/probe.wgsl",
];

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ShaderError {
    #[error("shader '{0}' does not exist")]
    Missing(String),
    #[error("shader '{file}' line {line}: bad #import directive '{text}'")]
    BadImport { file: String, line: usize, text: String },
}

fn source(path: &str) -> Result<&'static str, ShaderError> {
    SOURCES.iter().find(|(p, _)| *p == path).map(|(_, s)| *s).ok_or_else(|| ShaderError::Missing(path.to_string()))
}

/// Resolves `#import` lines of the module at `path` into one WGSL source.
pub fn resolve(path: &str) -> Result<String, ShaderError> {
    let mut out = String::new();
    let mut seen = Vec::new();
    resolve_into(path, &mut out, &mut seen)?;
    Ok(out)
}

fn resolve_into(path: &str, out: &mut String, seen: &mut Vec<String>) -> Result<(), ShaderError> {
    if seen.iter().any(|s| s == path) {
        return Ok(());
    }
    seen.push(path.to_string());
    let src = source(path)?;
    for (i, line) in src.lines().enumerate() {
        let t = line.trim_start();
        if let Some(rest) = t.strip_prefix("#import") {
            let name = rest.trim();
            if name.is_empty() || name.contains(char::is_whitespace) {
                return Err(ShaderError::BadImport { file: path.into(), line: i + 1, text: line.into() });
            }
            resolve_into(name, out, seen)?;
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
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(path),
        source: wgpu::ShaderSource::Wgsl(code.into()),
    })
}
