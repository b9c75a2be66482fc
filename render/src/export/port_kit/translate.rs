//! Each entry point the frame runs, translated by naga into the engines' shading languages
//! (issue #54 point 1; docs/port-kit.md, "Shaders"): SPIR-V 1.3, GLSL 4.50, HLSL shader model
//! 6.0 and MSL 2.4, one file per entry point and set of constants. The pipeline's overridable
//! constants are baked in (naga's `process_overrides`, what wgpu does when it makes the
//! pipeline), so each file is the program the frame ran. A translation that fails is kept
//! with naga's message, never dropped.

use std::path::PathBuf;

use serde::Serialize;

/// The languages of a translation, with their file extensions.
pub const LANGUAGES: [&str; 4] = ["spirv", "glsl", "hlsl", "msl"];

/// One entry point with its constants, and the file or error of each language.
#[derive(Clone, Debug, Serialize)]
pub struct Translation {
    pub module: String,
    pub entry: String,
    pub stage: String,
    pub constants: Vec<(String, f64)>,
    /// Language → the kit's file, or naga's error.
    pub files: Vec<(String, Result<String, String>)>,
}

fn stage_of(s: &str) -> Option<naga::ShaderStage> {
    Some(match s {
        "compute" => naga::ShaderStage::Compute,
        "vertex" => naga::ShaderStage::Vertex,
        "fragment" => naga::ShaderStage::Fragment,
        _ => return None,
    })
}

/// The file stem of a variant: the module's path without `.wgsl`, the entry point and the
/// constants (`knecht/interleave/gather.cs_gather_fused.VISIBILITY_MODE-1`).
fn stem(module: &str, entry: &str, constants: &[(String, f64)]) -> String {
    let mut s = format!("{}.{entry}", module.trim_end_matches(".wgsl"));
    for (k, v) in constants {
        s += &format!(".{k}-{v}");
    }
    s
}

/// The GLSL file extension glslangValidator reads the stage from.
fn glsl_extension(stage: naga::ShaderStage) -> &'static str {
    match stage {
        naga::ShaderStage::Vertex => "vert",
        naga::ShaderStage::Fragment => "frag",
        _ => "comp",
    }
}

/// Translates `entry` (of `stage`) of the WGSL `source` of `module` with `constants`: the
/// record and the files (kit-relative path, bytes).
pub fn translate(
    module: &str,
    source: &str,
    entry: &str,
    stage: &str,
    constants: &[(String, f64)],
) -> (Translation, Vec<(PathBuf, Vec<u8>)>) {
    let mut t = Translation {
        module: module.into(),
        entry: entry.into(),
        stage: stage.into(),
        constants: constants.to_vec(),
        files: Vec::new(),
    };
    let mut files = Vec::new();
    let prepared = prepare(source, entry, stage, constants);
    let stem = stem(module, entry, constants);
    for lang in LANGUAGES {
        let result = prepared.as_ref().map_err(|e| e.clone()).and_then(|(m, info, stage)| {
            let (ext, bytes) = write(lang, m, info, *stage, entry)?;
            let path = format!("shaders/{lang}/{stem}.{ext}");
            files.push((PathBuf::from(&path), bytes));
            Ok(path)
        });
        t.files.push((lang.to_string(), result));
    }
    (t, files)
}

/// The module parsed, validated and with its constants baked, and the entry point's stage.
fn prepare(
    source: &str,
    entry: &str,
    stage: &str,
    constants: &[(String, f64)],
) -> Result<(naga::Module, naga::valid::ModuleInfo, naga::ShaderStage), String> {
    let stage = stage_of(stage).ok_or_else(|| format!("stage '{stage}' is not translated"))?;
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| e.emit_to_string(source))?;
    let values: naga::back::PipelineConstants = constants.iter().cloned().collect();
    let (m, i) = naga::back::pipeline_constants::process_overrides(&module, &info, Some((stage, entry)), &values)
        .map_err(|e| format!("constants: {e}"))?;
    Ok((m.into_owned(), i.into_owned(), stage))
}

/// One language's text or binary, with its file extension.
fn write(
    lang: &str,
    m: &naga::Module,
    info: &naga::valid::ModuleInfo,
    stage: naga::ShaderStage,
    entry: &str,
) -> Result<(&'static str, Vec<u8>), String> {
    match lang {
        "spirv" => {
            let options = naga::back::spv::Options { lang_version: (1, 3), ..Default::default() };
            let pipeline = naga::back::spv::PipelineOptions { shader_stage: stage, entry_point: entry.into() };
            let words =
                naga::back::spv::write_vec(m, info, &options, Some(&pipeline)).map_err(|e| format!("SPIR-V: {e}"))?;
            Ok(("spv", words.iter().flat_map(|w| w.to_le_bytes()).collect()))
        }
        "glsl" => {
            let options =
                naga::back::glsl::Options { version: naga::back::glsl::Version::Desktop(450), ..Default::default() };
            let pipeline =
                naga::back::glsl::PipelineOptions { shader_stage: stage, entry_point: entry.into(), multiview: None };
            let mut out = String::new();
            naga::back::glsl::Writer::new(&mut out, m, info, &options, &pipeline, Default::default())
                .and_then(|mut w| w.write())
                .map_err(|e| format!("GLSL: {e}"))?;
            Ok((glsl_extension(stage), out.into_bytes()))
        }
        "hlsl" => {
            let options =
                naga::back::hlsl::Options { shader_model: naga::back::hlsl::ShaderModel::V6_0, ..Default::default() };
            let pipeline = naga::back::hlsl::PipelineOptions { entry_point: Some((stage, entry.into())) };
            let mut out = String::new();
            naga::back::hlsl::Writer::new(&mut out, &options, &pipeline)
                .write(m, info, None)
                .map_err(|e| format!("HLSL: {e}"))?;
            Ok(("hlsl", out.into_bytes()))
        }
        _ => {
            let options = naga::back::msl::Options { lang_version: (2, 4), ..Default::default() };
            let pipeline =
                naga::back::msl::PipelineOptions { entry_point: Some((stage, entry.into())), ..Default::default() };
            let (out, _) =
                naga::back::msl::write_string(m, info, &options, &pipeline).map_err(|e| format!("MSL: {e}"))?;
            Ok(("metal", out.into_bytes()))
        }
    }
}
