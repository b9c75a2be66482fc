//! Every WGSL file resolves its imports and validates with naga; the Rust uniform structs
//! have the sizes of their WGSL twins (docs/principles.md principle 8).

use gi_render::gpu::bindings::Kind;
use gi_render::shaders::{ENTRY_MODULES, SOURCES, resolve};

fn parse(path: &str) -> naga::Module {
    parse_with_info(path).0
}

/// The module and its validation info (which globals each entry point uses).
fn parse_with_info(path: &str) -> (naga::Module, naga::valid::ModuleInfo) {
    let src = resolve(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{path}: {}", e.emit_to_string(&src)));
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{path}: {}", e.emit_to_string(&src)));
    (module, info)
}

fn struct_size(module: &naga::Module, name: &str) -> u32 {
    module
        .types
        .iter()
        .find_map(|(_, t)| match (&t.name, &t.inner) {
            (Some(n), naga::TypeInner::Struct { span, .. }) if n == name => Some(*span),
            _ => None,
        })
        .unwrap_or_else(|| panic!("struct {name} not found"))
}

#[test]
fn every_entry_module_validates() {
    for path in ENTRY_MODULES {
        parse(path);
    }
}

#[test]
fn every_shader_file_is_used_and_every_entry_is_listed() {
    // Each file in shaders/ on disk is in the embedded table (a new file cannot be forgotten).
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shaders");
    let mut on_disk = Vec::new();
    for dir in std::fs::read_dir(&root).expect("shaders/ exists") {
        let dir = dir.expect("entry").path();
        for f in std::fs::read_dir(&dir).expect("folder") {
            let f = f.expect("file").path();
            if f.extension().is_some_and(|e| e == "wgsl") {
                let rel = f.strip_prefix(&root).expect("prefix").to_string_lossy().replace('\\', "/");
                on_disk.push(rel);
            }
        }
    }
    for f in &on_disk {
        assert!(SOURCES.iter().any(|(p, _)| p == f), "shaders/{f} is not in render/src/shaders.rs SOURCES");
    }
    for (p, src) in SOURCES {
        let text = std::fs::read_to_string(root.join(p)).expect("listed file exists on disk");
        assert_eq!(&text, src, "{p}: embedded copy differs from disk");
    }
}

#[test]
fn imports_are_resolved_once_and_bad_names_fail() {
    let direct = resolve("direct/direct.wgsl").expect("resolves");
    assert_eq!(direct.matches("struct Camera").count(), 1);
    assert!(!direct.contains("#import"));
    assert!(resolve("nope/nope.wgsl").is_err());
}

#[test]
fn uniform_sizes_match_wgsl() {
    use gi_render::passes::{
        CameraUniform, InstanceUniform, compose::ToneParams, direct::DirectParams, shadow::GpuLight,
    };
    use gi_render::scene::upload::MaterialUniform;
    let g = parse("gbuffer/gbuffer.wgsl");
    assert_eq!(struct_size(&g, "Camera") as usize, std::mem::size_of::<CameraUniform>());
    assert_eq!(struct_size(&g, "Instance") as usize, std::mem::size_of::<InstanceUniform>());
    assert_eq!(struct_size(&g, "Material") as usize, std::mem::size_of::<MaterialUniform>());
    let d = parse("direct/direct.wgsl");
    assert_eq!(struct_size(&d, "Light") as usize, std::mem::size_of::<GpuLight>());
    assert_eq!(struct_size(&d, "Params") as usize, std::mem::size_of::<DirectParams>());
    let t = parse("compose/tonemap.wgsl");
    assert_eq!(struct_size(&t, "Params") as usize, std::mem::size_of::<ToneParams>());
    let s = parse("shadow/shadow.wgsl");
    assert_eq!(struct_size(&s, "Instance") as usize, std::mem::size_of::<InstanceUniform>());
    use gi_render::passes::reference::{vpl, vpl_gather, vpl_visibility};
    let vs = parse("reference/sample.wgsl");
    assert_eq!(struct_size(&vs, "Vpl") as usize, std::mem::size_of::<vpl::GpuVpl>());
    assert_eq!(struct_size(&vs, "Params") as usize, std::mem::size_of::<vpl::SampleParams>());
    let vv = parse("reference/shadow.wgsl");
    assert_eq!(struct_size(&vv, "Params") as usize, std::mem::size_of::<vpl_visibility::VisibilityParams>());
    assert_eq!(struct_size(&vv, "Instance") as usize, std::mem::size_of::<InstanceUniform>());
    let vg = parse("reference/gather.wgsl");
    assert_eq!(struct_size(&vg, "Params") as usize, std::mem::size_of::<vpl_gather::GatherParams>());
    assert_eq!(struct_size(&vg, "Camera") as usize, std::mem::size_of::<CameraUniform>());
    let v = parse("view/view.wgsl");
    assert_eq!(struct_size(&v, "ViewParams") as usize, std::mem::size_of::<gi_render::passes::view::ViewParams>());
    let p = parse("view/probe.wgsl");
    assert_eq!(struct_size(&p, "Jobs") as usize, std::mem::size_of::<gi_render::buffers::ProbeJobs>());
    // Instant radiosity (issue #5).
    use gi_render::passes::knecht::{interleave, ism, temporal, vpl_importance};
    let w = parse("knecht/vpl/warp.wgsl");
    assert_eq!(struct_size(&w, "ViewParams") as usize, std::mem::size_of::<vpl_importance::ViewParams>());
    assert_eq!(struct_size(&w, "Vpl") as usize, std::mem::size_of::<vpl::GpuVpl>());
    let sp = parse("knecht/ism/splat.wgsl");
    assert_eq!(struct_size(&sp, "IsmPoint") as usize, std::mem::size_of::<ism::GpuPoint>());
    assert_eq!(struct_size(&sp, "SplatParams") as usize, std::mem::size_of::<ism::SplatParams>());
    assert_eq!(struct_size(&sp, "Instance") as usize, std::mem::size_of::<InstanceUniform>());
    use gi_render::passes::knecht::vpl_bounce::BounceParams;
    for file in ["knecht/vpl/bounce.wgsl", "knecht/vpl/irsm.wgsl"] {
        let m = parse(file);
        assert_eq!(struct_size(&m, "BounceParams") as usize, std::mem::size_of::<BounceParams>(), "{file}");
        assert_eq!(struct_size(&m, "PointSurface") as usize, std::mem::size_of::<ism::GpuPointSurface>(), "{file}");
        assert_eq!(struct_size(&m, "IsmPoint") as usize, std::mem::size_of::<ism::GpuPoint>(), "{file}");
        assert_eq!(struct_size(&m, "Vpl") as usize, std::mem::size_of::<vpl::GpuVpl>(), "{file}");
    }
    for file in ["hcb/samples.wgsl", "hcb/splat.wgsl", "hcb/cache.wgsl", "hcb/cache_removal.wgsl"] {
        let m = parse(file);
        let want = std::mem::size_of::<gi_render::passes::hcb::GpuHcbSample>();
        assert_eq!(struct_size(&m, "HcbSample") as usize, want, "{file}");
        let want = std::mem::size_of::<gi_render::passes::hcb::cache::CacheParams>();
        assert_eq!(struct_size(&m, "CacheParams") as usize, want, "{file}");
    }
    for file in ["hcb/base.wgsl", "hcb/build.wgsl", "hcb/samples.wgsl", "hcb/splat.wgsl"] {
        let m = parse(file);
        assert_eq!(
            struct_size(&m, "HcbParams") as usize,
            std::mem::size_of::<gi_render::passes::hcb::HcbParams>(),
            "{file}"
        );
    }
    let hg = parse("hcb/gather.wgsl");
    assert_eq!(
        struct_size(&hg, "HcbGatherParams") as usize,
        std::mem::size_of::<gi_render::passes::hcb::HcbGatherParams>()
    );
    let pp = parse("knecht/ism/pull_push.wgsl");
    assert_eq!(struct_size(&pp, "LevelParams") as usize, std::mem::size_of::<ism::LevelParams>());
    let sl = parse("knecht/interleave/split.wgsl");
    assert_eq!(struct_size(&sl, "SplitParams") as usize, std::mem::size_of::<interleave::SplitParams>());
    let ig = parse("knecht/interleave/gather.wgsl");
    assert_eq!(struct_size(&ig, "GatherParams") as usize, std::mem::size_of::<interleave::GatherParams>());
    let f = parse("knecht/interleave/filter.wgsl");
    assert_eq!(struct_size(&f, "FilterParams") as usize, std::mem::size_of::<interleave::FilterParams>());
    let c = parse("knecht/temporal/confidence.wgsl");
    assert_eq!(struct_size(&c, "ConfidenceParams") as usize, std::mem::size_of::<temporal::ConfidenceParams>());
    let fm = parse("knecht/temporal/filter_merge.wgsl");
    assert_eq!(struct_size(&fm, "ConfidenceParams") as usize, std::mem::size_of::<temporal::ConfidenceParams>());
    assert_eq!(struct_size(&fm, "FilterParams") as usize, std::mem::size_of::<interleave::FilterParams>());
}

/// The hot reload's building blocks: what a file affects, validation of a candidate text
/// without installing it, and a rebuild that touches only the passes of the named modules.
#[test]
fn shader_reload_rebuilds_only_the_affected_passes() {
    use gi_render::shaders::{dependents, validate_candidate};
    let lights = dependents("common/lights.wgsl");
    assert!(lights.contains(&"direct/direct.wgsl"), "{lights:?}");
    assert!(!lights.contains(&"compose/tonemap.wgsl"), "{lights:?}");
    assert_eq!(dependents("direct/direct.wgsl"), ["direct/direct.wgsl"]);
    let good = gi_render::shaders::SOURCES.iter().find(|(p, _)| *p == "direct/direct.wgsl").expect("listed").1;
    assert!(validate_candidate("direct/direct.wgsl", Some(("direct/direct.wgsl", good))).is_ok());
    let err = validate_candidate("direct/direct.wgsl", Some(("direct/direct.wgsl", "fn broken( {")))
        .expect_err("a syntax error is caught before anything is installed");
    assert!(err.contains("direct/direct.wgsl"), "{err}");

    // Direct light only: the same frame twice gives the same image (no new VPLs).
    let mut r = gi_lab_tests::direct_only_renderer(48, 32);
    r.render_frame();
    r.render_frame();
    let before = r.readback("final.hdr").expect("readback");
    let gbuffer_before = r.buffers().get("gbuffer.normal").expect("registered").texture.clone();
    let rebuilt = r.reload_shaders(&["direct/direct.wgsl"]).expect("rebuilds");
    assert_eq!(rebuilt, ["direct"]);
    assert_eq!(
        r.buffers().get("gbuffer.normal").expect("registered").texture,
        gbuffer_before,
        "the G-buffer pass was not rebuilt"
    );
    r.render_frame();
    r.render_frame();
    assert_eq!(r.readback("final.hdr").expect("readback"), before, "same source, same image");
    let all = r.reload_shaders(gi_render::shaders::ENTRY_MODULES).expect("rebuilds all");
    assert_eq!(all, ["compose", "direct", "direct.shadow", "gbuffer"], "exact_vpl is off, the viewer is not a pass");
}

/// Whether the shader variable `v` of `module` is a binding of `kind` (what WGSL cannot say —
/// whether a float texture is filterable, a sampler's filtering — is not compared).
fn declared_as(module: &naga::Module, v: &naga::GlobalVariable, kind: Kind) -> bool {
    use naga::{AddressSpace, ImageClass, ImageDimension, ScalarKind, StorageAccess, TypeInner};
    match (kind, v.space, &module.types[v.ty].inner) {
        (Kind::Uniform | Kind::UniformDynamic, AddressSpace::Uniform, _) => true,
        (Kind::StorageDynamic, AddressSpace::Storage { access }, _) => !access.contains(StorageAccess::STORE),
        (Kind::Storage { read_only }, AddressSpace::Storage { access }, _) => {
            read_only != access.contains(StorageAccess::STORE)
        }
        (_, _, TypeInner::Image { dim: ImageDimension::D2, arrayed, class }) => match (kind, class) {
            (Kind::Texture { .. }, ImageClass::Sampled { kind: ScalarKind::Float, multi: false }) => !arrayed,
            (Kind::TextureArray { .. }, ImageClass::Sampled { kind: ScalarKind::Float, multi: false }) => *arrayed,
            (Kind::UintTexture, ImageClass::Sampled { kind: ScalarKind::Uint, multi: false }) => !arrayed,
            (Kind::UintTextureArray, ImageClass::Sampled { kind: ScalarKind::Uint, multi: false }) => *arrayed,
            (Kind::Depth, ImageClass::Depth { multi: false }) => !arrayed,
            (Kind::DepthArray, ImageClass::Depth { multi: false }) => *arrayed,
            (Kind::StorageTextureArray(format), ImageClass::Storage { format: f, .. }) => {
                *arrayed && format!("{format:?}") == format!("{f:?}")
            }
            (Kind::StorageTexture(format), ImageClass::Storage { format: f, access }) => {
                !arrayed && !access.contains(StorageAccess::LOAD) && format!("{format:?}") == format!("{f:?}")
            }
            (Kind::StorageTextureReadWrite(format), ImageClass::Storage { format: f, access }) => {
                !arrayed
                    && access.contains(StorageAccess::LOAD | StorageAccess::STORE)
                    && format!("{format:?}") == format!("{f:?}")
            }
            _ => false,
        },
        (Kind::Sampler(ty), _, TypeInner::Sampler { comparison }) => {
            *comparison == (ty == wgpu::SamplerBindingType::Comparison)
        }
        _ => false,
    }
}

/// Issue #52 point 3: every pass's bind group description (`passes::BINDINGS`) matches its
/// shader, binding by binding (number, variable name, kind), and describes every binding the
/// shader declares in that group (or, for a description naming its entry point, every binding
/// of the group that entry point uses): the layout and the group made from the description
/// are the ones the shader reads.
#[test]
fn every_bind_group_description_matches_its_shader() {
    assert!(!gi_render::passes::BINDINGS.is_empty());
    for d in gi_render::passes::BINDINGS {
        let (module, info) = parse_with_info(d.shader);
        // With entry points named (`a+b` for a raster pipeline's vertex and fragment stages):
        // the bindings of the group those entry points use.
        let used = |h: naga::Handle<naga::GlobalVariable>| match d.entry {
            None => true,
            Some(names) => names.split('+').any(|name| {
                let k = module
                    .entry_points
                    .iter()
                    .position(|e| e.name == name)
                    .unwrap_or_else(|| panic!("{}: {} has no entry point {name}", d.label, d.shader));
                !info.get_entry_point(k)[h].is_empty()
            }),
        };
        let declared: Vec<&naga::GlobalVariable> = module
            .global_variables
            .iter()
            .filter(|(h, v)| v.binding.as_ref().is_some_and(|b| b.group == d.group) && used(*h))
            .map(|(_, v)| v)
            .collect();
        for b in d.list {
            let v =
                declared.iter().find(|v| v.binding.as_ref().is_some_and(|r| r.binding == b.binding)).unwrap_or_else(
                    || panic!("{}: {} declares no binding {} in group {}", d.label, d.shader, b.binding, d.group),
                );
            assert_eq!(v.name.as_deref(), Some(b.name), "{}: binding {} of {}", d.label, b.binding, d.shader);
            assert!(
                declared_as(&module, v, b.kind),
                "{}: {} ({}) is not a {:?} in {}",
                d.label,
                b.name,
                b.binding,
                b.kind,
                d.shader
            );
        }
        for v in &declared {
            let n = v.binding.as_ref().map_or(0, |r| r.binding);
            assert!(
                d.list.iter().any(|b| b.binding == n),
                "{}: {} declares binding {n} ({:?}) in group {}, which the description lacks",
                d.label,
                d.shader,
                v.name,
                d.group
            );
        }
    }
}

/// Issue #52 point 3: no bind group layout or entry of the renderer is written by hand (only
/// `gpu::bindings` makes them), and every description in its source is listed in
/// `passes::BINDINGS`, so that the check above sees all of them.
#[test]
fn every_bind_group_of_the_renderer_comes_from_a_listed_description() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../render/src");
    let files = gi_lab_tests::rust_sources(&src);
    let listed: Vec<&str> = gi_render::passes::BINDINGS.iter().map(|d| d.label).collect();
    let mut by_hand = Vec::new();
    let mut unlisted = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).expect("source");
        let code: Vec<&str> = text.lines().filter(|l| !l.trim_start().starts_with("//")).collect();
        if !f.ends_with("gpu/bindings.rs") {
            for (n, l) in code.iter().enumerate() {
                if l.contains("BindGroupEntry {") || l.contains("create_bind_group_layout(") {
                    by_hand.push(format!("{}: {}", f.display(), n + 1));
                }
            }
        }
        for (n, l) in code.iter().enumerate() {
            if l.contains(": Bindings = Bindings {") {
                let label = code[n + 1..]
                    .iter()
                    .find_map(|l| l.trim().strip_prefix("label: \"").and_then(|r| r.strip_suffix("\",")))
                    .unwrap_or_else(|| panic!("{}: a description without a label", f.display()));
                if !listed.contains(&label) {
                    unlisted.push(label.to_string());
                }
            }
        }
    }
    assert!(by_hand.is_empty(), "bind group layouts or entries written by hand: {by_hand:?}");
    assert!(unlisted.is_empty(), "descriptions not in passes::BINDINGS: {unlisted:?}");
    let mut labels = listed.clone();
    labels.sort();
    labels.dedup();
    assert_eq!(labels.len(), listed.len(), "two descriptions share a label");
}
