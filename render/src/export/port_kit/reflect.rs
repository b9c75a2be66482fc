//! What a shader module declares, read with naga (issue #54 point 1): its entry points, and
//! per binding its group, number, name, kind, access and, for uniform and storage blocks,
//! the byte layout of every member (WGSL's layout rules, naga's `Layouter`). The port kit's
//! manifest names each binding and says whether a pass reads or writes it from this, not
//! from a hand-kept table.

use naga::{AddressSpace, ImageClass, StorageAccess, TypeInner};
use serde::Serialize;

/// A member of a uniform or storage block, at its byte offset.
#[derive(Clone, Debug, Serialize)]
pub struct Member {
    pub name: String,
    pub offset: u32,
    pub size: u32,
    #[serde(rename = "type")]
    pub ty: String,
}

/// One resource binding of a module.
#[derive(Clone, Debug, Serialize)]
pub struct BindingDecl {
    pub group: u32,
    pub binding: u32,
    /// The variable's name in the shader.
    pub name: String,
    /// `uniform`, `storage`, `texture`, `depth_texture`, `storage_texture` or `sampler`.
    pub kind: &'static str,
    /// `read`, `write` or `read_write`.
    pub access: &'static str,
    #[serde(rename = "type")]
    pub ty: String,
    /// Textures: the view dimension (`1d`, `2d`, `2d_array`, `cube`, `cube_array`, `3d`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dimension: Option<String>,
    /// Sampled textures: `float`, `uint`, `sint` or `depth`; storage textures: the texel
    /// format as WGSL spells it; samplers: `filtering` or `comparison`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sample: Option<String>,
    /// The block's size in bytes (uniform and storage; for a runtime-sized array, the size of
    /// everything before it plus one element).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub size: Option<u32>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub members: Vec<Member>,
}

/// A module's entry points (name, stage, workgroup size) and bindings.
#[derive(Clone, Debug, Serialize)]
pub struct ModuleDecl {
    pub entry_points: Vec<EntryPoint>,
    pub bindings: Vec<BindingDecl>,
    /// The module's pipeline-overridable constants by name, with their defaults where given.
    pub overrides: Vec<(String, Option<String>)>,
}

#[derive(Clone, Debug, Serialize)]
pub struct EntryPoint {
    pub name: String,
    pub stage: String,
    /// Compute entry points: @workgroup_size.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub workgroup_size: Option<[u32; 3]>,
}

/// The declarations of the WGSL `source`.
pub fn reflect(source: &str) -> Result<ModuleDecl, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).map_err(|e| e.to_string())?;
    let mut bindings = Vec::new();
    for (_, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let ty = &module.types[var.ty];
        let (kind, access) = match (var.space, &ty.inner) {
            (AddressSpace::Uniform, _) => ("uniform", "read"),
            (AddressSpace::Storage { access }, _) => ("storage", access_name(access)),
            (_, TypeInner::Image { class: ImageClass::Storage { access, .. }, .. }) => {
                ("storage_texture", access_name(*access))
            }
            (_, TypeInner::Image { class: ImageClass::Depth { .. }, .. }) => ("depth_texture", "read"),
            (_, TypeInner::Image { .. }) => ("texture", "read"),
            (_, TypeInner::Sampler { .. }) => ("sampler", "read"),
            _ => ("other", "read"),
        };
        let block = matches!(kind, "uniform" | "storage");
        let members = match (&ty.inner, block) {
            (TypeInner::Struct { members, .. }, true) => members
                .iter()
                .map(|m| Member {
                    name: m.name.clone().unwrap_or_default(),
                    offset: m.offset,
                    size: layouter[m.ty].size,
                    ty: type_name(&module, m.ty),
                })
                .collect(),
            _ => Vec::new(),
        };
        let (dimension, sample) = match &ty.inner {
            TypeInner::Image { dim, arrayed, class } => (Some(dim_name(*dim, *arrayed)), Some(image_sample(class))),
            TypeInner::Sampler { comparison } => {
                (None, Some(if *comparison { "comparison" } else { "filtering" }.to_string()))
            }
            _ => (None, None),
        };
        bindings.push(BindingDecl {
            group: rb.group,
            binding: rb.binding,
            name: var.name.clone().unwrap_or_default(),
            kind,
            access,
            ty: type_name(&module, var.ty),
            dimension,
            sample,
            size: block.then(|| layouter[var.ty].size),
            members,
        });
    }
    bindings.sort_by_key(|b| (b.group, b.binding));
    let entry_points = module
        .entry_points
        .iter()
        .map(|e| EntryPoint {
            name: e.name.clone(),
            stage: format!("{:?}", e.stage).to_lowercase(),
            workgroup_size: (e.stage == naga::ShaderStage::Compute).then_some(e.workgroup_size),
        })
        .collect();
    let overrides = module
        .overrides
        .iter()
        .map(|(_, o)| {
            let default = o.init.map(|h| format!("{:?}", module.global_expressions[h]));
            (o.name.clone().unwrap_or_default(), default)
        })
        .collect();
    Ok(ModuleDecl { entry_points, bindings, overrides })
}

/// A texture's view dimension as the manifest writes it.
fn dim_name(dim: naga::ImageDimension, arrayed: bool) -> String {
    let d = match dim {
        naga::ImageDimension::D1 => "1d",
        naga::ImageDimension::D2 => "2d",
        naga::ImageDimension::D3 => "3d",
        naga::ImageDimension::Cube => "cube",
    };
    if arrayed { format!("{d}_array") } else { d.into() }
}

/// A sampled texture's scalar kind, or a storage texture's format as WGSL spells it.
fn image_sample(class: &ImageClass) -> String {
    match class {
        ImageClass::Sampled { kind, .. } => match kind {
            naga::ScalarKind::Uint => "uint".into(),
            naga::ScalarKind::Sint => "sint".into(),
            _ => "float".into(),
        },
        ImageClass::Depth { .. } => "depth".into(),
        ImageClass::Storage { format, .. } => storage_format_name(*format),
        ImageClass::External => "external".into(),
    }
}

/// naga's storage format in WGSL's spelling (`rgba16float`, `r32uint`).
fn storage_format_name(f: naga::StorageFormat) -> String {
    format!("{f:?}").to_lowercase()
}

fn access_name(a: StorageAccess) -> &'static str {
    match (a.contains(StorageAccess::LOAD), a.contains(StorageAccess::STORE) || a.contains(StorageAccess::ATOMIC)) {
        (true, true) => "read_write",
        (false, true) => "write",
        _ => "read",
    }
}

/// A WGSL-like name of a type (`vec4<f32>`, `array<Vpl>`, the struct's name).
fn type_name(module: &naga::Module, ty: naga::Handle<naga::Type>) -> String {
    let t = &module.types[ty];
    if let Some(name) = &t.name {
        return name.clone();
    }
    let scalar = |s: &naga::Scalar| match (s.kind, s.width) {
        (naga::ScalarKind::Float, 2) => "f16".to_string(),
        (naga::ScalarKind::Float, _) => "f32".to_string(),
        (naga::ScalarKind::Uint, _) => "u32".to_string(),
        (naga::ScalarKind::Sint, _) => "i32".to_string(),
        (naga::ScalarKind::Bool, _) => "bool".to_string(),
        (k, w) => format!("{k:?}{w}"),
    };
    match &t.inner {
        TypeInner::Scalar(s) => scalar(s),
        TypeInner::Atomic(s) => format!("atomic<{}>", scalar(s)),
        TypeInner::Vector { size, scalar: s } => format!("vec{}<{}>", *size as u8, scalar(s)),
        TypeInner::Matrix { columns, rows, scalar: s } => {
            format!("mat{}x{}<{}>", *columns as u8, *rows as u8, scalar(s))
        }
        TypeInner::Array { base, size, .. } => match size {
            naga::ArraySize::Constant(n) => format!("array<{}, {n}>", type_name(module, *base)),
            _ => format!("array<{}>", type_name(module, *base)),
        },
        TypeInner::Image { dim, arrayed, class } => {
            let d = dim_name(*dim, *arrayed);
            match class {
                ImageClass::Storage { format, access } => {
                    let a = access_name(*access);
                    format!("texture_storage_{d}<{}, {a}>", storage_format_name(*format))
                }
                ImageClass::Depth { multi: false } => format!("texture_depth_{d}"),
                ImageClass::Depth { multi: true } => format!("texture_depth_multisampled_{d}"),
                ImageClass::Sampled { kind, multi } => {
                    let k = match kind {
                        naga::ScalarKind::Uint => "u32",
                        naga::ScalarKind::Sint => "i32",
                        _ => "f32",
                    };
                    let m = if *multi { "multisampled_" } else { "" };
                    format!("texture_{m}{d}<{k}>")
                }
                ImageClass::External => "texture_external".into(),
            }
        }
        TypeInner::Sampler { comparison } => if *comparison { "sampler_comparison" } else { "sampler" }.into(),
        other => format!("{other:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_blocks_follow_wgsl_layout_rules_and_accesses_are_read_from_the_declarations() {
        let src = "
            struct P { a: vec3<f32>, b: f32, c: vec2<f32>, d: mat4x4<f32> }
            @group(0) @binding(0) var<uniform> p: P;
            @group(0) @binding(1) var<storage, read_write> out_v: array<vec4<f32>>;
            @group(1) @binding(0) var t: texture_2d<f32>;
            @group(1) @binding(1) var o: texture_storage_2d<rgba16float, write>;
            @group(1) @binding(2) var s: sampler;
            override K: u32 = 4u;
            @compute @workgroup_size(8, 4, 1) fn cs(@builtin(global_invocation_id) id: vec3<u32>) {
                out_v[id.x] = vec4<f32>(p.a, p.b) + textureSampleLevel(t, s, vec2<f32>(0.0), 0.0) * f32(K);
                textureStore(o, id.xy, vec4<f32>(p.c, 0.0, 1.0));
            }";
        let m = reflect(src).expect("parses");
        let p = &m.bindings[0];
        assert_eq!((p.name.as_str(), p.kind, p.access, p.size), ("p", "uniform", "read", Some(96)));
        let offsets: Vec<(&str, u32, u32)> = p.members.iter().map(|m| (m.name.as_str(), m.offset, m.size)).collect();
        // vec3 is 16-aligned and 12 bytes: b packs after it; mat4x4 aligns to 16.
        assert_eq!(offsets, [("a", 0, 12), ("b", 12, 4), ("c", 16, 8), ("d", 32, 64)]);
        let kinds: Vec<(&str, &str, &str)> = m.bindings.iter().map(|b| (b.name.as_str(), b.kind, b.access)).collect();
        assert_eq!(
            kinds,
            [
                ("p", "uniform", "read"),
                ("out_v", "storage", "read_write"),
                ("t", "texture", "read"),
                ("o", "storage_texture", "write"),
                ("s", "sampler", "read")
            ]
        );
        let textures: Vec<(&str, Option<&str>, Option<&str>)> =
            m.bindings[2..].iter().map(|b| (b.ty.as_str(), b.dimension.as_deref(), b.sample.as_deref())).collect();
        assert_eq!(
            textures,
            [
                ("texture_2d<f32>", Some("2d"), Some("float")),
                ("texture_storage_2d<rgba16float, write>", Some("2d"), Some("rgba16float")),
                ("sampler", None, Some("filtering"))
            ]
        );
        assert_eq!(m.entry_points.len(), 1);
        assert_eq!(m.entry_points[0].workgroup_size, Some([8, 4, 1]));
        assert_eq!(m.overrides.len(), 1);
        assert_eq!(m.overrides[0].0, "K");
    }
}
