//! Shared helpers of GI Lab's integration tests.

use gi_render::scene::Scene;
use gi_render::{GpuContext, LabSettings, Renderer};

/// Opens the headless GPU context or fails the test with instructions; tests never skip
/// silently when no adapter exists.
pub fn gpu() -> GpuContext {
    match GpuContext::headless() {
        Ok(c) => c,
        Err(e) => panic!(
            "no GPU adapter for the tests: {e}\n\
             Install Mesa's software Vulkan driver (lavapipe): `sudo apt-get install -y mesa-vulkan-drivers libvulkan1` \
             and run with WGPU_BACKEND=vulkan, or run `bash scripts/test.sh`, which does both."
        ),
    }
}

/// The embedded default scene.
pub fn default_scene() -> Scene {
    gi_render::scene::cornell::default_scene().expect("the embedded default scene loads")
}

/// The passes of a frame with the default settings (instant radiosity with ISMs and
/// temporal coherence, Knecht), in order, after the first frame (see [`first_frame`]), while
/// the scene moves (its animation plays); a still frame keeps some ([`still`]).
pub const DEFAULT_PASSES: &[&str] = &[
    "gbuffer",
    "direct.shadow",
    "direct",
    "vpl.light_gbuffer",
    "vpl.importance",
    "vpl.sample",
    "ism.splat",
    "ism.pull_push",
    "interleave.gather",
    "temporal.filter_merge",
    "compose",
    "compose.luminance",
];

/// The passes of the default settings that a frame keeps from the one before while nothing
/// they depend on moved (issue #53): the G-buffer, the shadow maps, the direct light, the
/// light G-buffer and its importance (the VPL set is new every frame,
/// `vpl.new_set_each_frame`). From the third still frame on: the second redraws the G-buffer,
/// whose movement buffer had no previous frame in the first.
pub const KEPT_WHEN_STILL: &[&str] = &["gbuffer", "direct.shadow", "direct", "vpl.light_gbuffer", "vpl.importance"];

/// The second frame of a still scene: it keeps the light space, not yet the G-buffer and
/// the direct light (see [`KEPT_WHEN_STILL`]).
pub fn second_frame(passes: &[&'static str]) -> Vec<&'static str> {
    let redone = ["gbuffer", "direct"];
    passes.iter().copied().filter(|p| !KEPT_WHEN_STILL.contains(p) || redone.contains(p)).collect()
}

/// `passes` without those a still frame keeps ([`KEPT_WHEN_STILL`]).
pub fn still(passes: &[&'static str]) -> Vec<&'static str> {
    passes.iter().copied().filter(|p| !KEPT_WHEN_STILL.contains(p)).collect()
}

/// The passes of a frame of direct light only (`pipeline.gather = None`), after the first.
pub const DIRECT_PASSES: &[&str] = &["gbuffer", "direct.shadow", "direct", "compose", "compose.luminance"];

/// The passes of the first frame (or the first after `reset_history`) with automatic
/// exposure: `passes` and a tone-mapping pass of its own, since the compose tone maps with
/// the previous frame's log-average luminance and there is none yet.
pub fn first_frame(passes: &[&'static str]) -> Vec<&'static str> {
    let mut v = passes.to_vec();
    v.push("compose.tonemap");
    v
}

/// The default renderer with direct light only (`pipeline.gather = None`): deterministic
/// from frame to frame, for tests of the direct light and the frame's machinery.
pub fn direct_only_renderer(w: u32, h: u32) -> Renderer {
    let mut s = LabSettings::default();
    s.pipeline.gather = gi_render::settings::pipeline::Gather::None;
    let mut r = Renderer::new(gpu(), default_scene(), s, w, h).expect("renderer");
    r.clock.playing = false;
    r
}

/// The default scene at `w`×`h` with the `nguyen-hcb` preset's VPLs (the same set every
/// frame) and the choices `edit` makes, validated; animation paused.
pub fn nguyen_fixed_vpls_renderer(w: u32, h: u32, edit: impl FnOnce(&mut LabSettings)) -> Renderer {
    let loaded =
        gi_render::preset::load_lenient(include_str!("../../presets/nguyen-hcb.ron"), "nguyen-hcb").expect("loads");
    let mut s = loaded.settings;
    s.vpl.new_set_each_frame = false;
    edit(&mut s);
    assert!(s.validate().is_empty(), "{:?}", s.validate());
    let mut r = Renderer::new(gpu(), default_scene(), s, w, h).expect("renderer");
    r.clock.playing = false;
    r
}

/// A renderer of the default scene at `w`×`h` with default settings, animation paused.
pub fn default_renderer(w: u32, h: u32) -> Renderer {
    let mut r = Renderer::new(gpu(), default_scene(), LabSettings::default(), w, h).expect("renderer");
    r.clock.playing = false;
    r
}

/// Every `.rs` file below `dir`, sorted (the source scans of `tests/modules.rs` and
/// `tests/shaders.rs`).
pub fn rust_sources(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut entries: Vec<_> = std::fs::read_dir(dir).expect("source folder").flatten().map(|e| e.path()).collect();
    entries.sort();
    let mut out = Vec::new();
    for p in entries {
        if p.is_dir() {
            out.extend(rust_sources(&p));
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
    out
}

/// Path of a real scene in the repository's `assets/scenes/` (each with its licence and
/// attribution), failing clearly when it is missing.
pub fn real_scene(rel: &str) -> std::path::PathBuf {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/scenes").join(rel);
    assert!(p.exists(), "real scene {} is missing from the repository's assets/scenes/", p.display());
    p
}

/// Every shipped preset (`presets/*.ron`), sorted by name; fails when fewer than ten are found.
pub fn shipped_presets() -> Vec<std::path::PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets");
    let mut presets: Vec<std::path::PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    presets.sort();
    assert!(presets.len() >= 10, "only {} presets found in presets/", presets.len());
    presets
}

/// A scene file of the tests' own in `tests/data/` (e.g. `chair-behind.glb`: the shipped
/// chair with a camera of its own, `scripts/make-chair-view.py`), loaded as the CLI loads it.
pub fn test_scene(file: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(file);
    gi_render::scene::load_gltf_file(&path, &gi_render::scene::LoadOptions::default())
        .unwrap_or_else(|e| panic!("tests/data/{file}: {e}"))
}

/// A scene of the repository's `assets/` (e.g. `scenes/hotel-room/hotel-room.glb`), loaded as
/// `gi-lab --scene` loads it.
pub fn asset_scene(file: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets").join(file);
    gi_render::scene::load_gltf_file(&path, &gi_render::scene::LoadOptions::default())
        .unwrap_or_else(|e| panic!("assets/{file}: {e}"))
}

/// The default scene under a constant white sky of radiance 1 (its lights kept), as `gi-lab …
/// --sky 1,1,1` opens it: issue #51's sky box.
pub fn white_sky_box() -> Scene {
    let mut scene = default_scene();
    scene.sky = gi_render::scene::sky::Sky::constant(glam::Vec3::ONE, 1.0);
    scene
}

/// A path-traced reference stored in `tests/data/` (see `tests/references.rs`).
pub fn stored_reference(file: &str) -> gi_render::ImageF32 {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(file);
    gi_render::image_io::load_float_image(&path).unwrap_or_else(|e| panic!("tests/data/{file}: {e}"))
}

/// The largest |a − b| / max(|a|, 10⁻³) over the channels of two images of the same size (two
/// runs that should agree to float rounding).
pub fn max_relative_difference(a: &[[f32; 4]], b: &[[f32; 4]]) -> f32 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs() / x.abs().max(1e-3)).fold(0.0, f32::max)
}

/// An `Rgba32Float` texture of `w`×`h` texels (a synthetic G-buffer target).
pub fn upload_rgba32f(ctx: &GpuContext, label: &str, w: u32, h: u32, data: &[[f32; 4]]) -> wgpu::Texture {
    texture_from_bytes(ctx, label, wgpu::TextureFormat::Rgba32Float, (w, h), bytemuck::cast_slice(data))
}

/// A synthetic G-buffer of `w`×`h` for the HCB's tests from a function of the pixel:
/// (position, normal); position.w = the view depth −z (a camera at the origin looking down
/// −z); None for the background.
pub fn hcb_gbuffer(
    w: u32,
    h: u32,
    f: impl Fn(u32, u32) -> Option<(glam::Vec3, glam::Vec3)>,
) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    (0..w * h)
        .map(|i| match f(i % w, i / w) {
            Some((p, n)) => ([p.x, p.y, p.z, -p.z], [n.x, n.y, n.z, 1.0]),
            None => ([0.0; 4], [0.0; 4]),
        })
        .unzip()
}

/// A sampled, copyable 2D texture of `format` filled with `bytes` (tightly packed rows).
pub fn texture_from_bytes(
    ctx: &GpuContext,
    label: &str,
    format: wgpu::TextureFormat,
    (width, height): (u32, u32),
    bytes: &[u8],
) -> wgpu::Texture {
    let t = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    ctx.queue.write_texture(
        t.as_image_copy(),
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(bytes.len() as u32 / height),
            rows_per_image: None,
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    t
}

/// A renderer of `technique` on the default scene at `size`², its settings edited by `edit`
/// (which must leave them valid), with the animation paused.
pub fn paused_renderer(
    size: u32,
    technique: gi_render::settings::pipeline::Technique,
    edit: impl FnOnce(&mut LabSettings),
) -> Renderer {
    let mut s = LabSettings::default();
    technique.apply(&mut s);
    edit(&mut s);
    assert!(s.validate().is_empty(), "{:?}", s.validate());
    let mut r = Renderer::new(gpu(), default_scene(), s, size, size).expect("renderer");
    r.clock.playing = false;
    r
}

/// A renderer of `scene` at `size`², its default settings edited by `edit`, with the
/// animation paused.
pub fn scene_renderer(scene: Scene, size: u32, edit: impl FnOnce(&mut LabSettings)) -> Renderer {
    let mut s = LabSettings::default();
    edit(&mut s);
    let mut r = Renderer::new(gpu(), scene, s, size, size).expect("renderer");
    r.clock.playing = false;
    r
}

/// A registered buffer read back, or the test fails naming it.
pub fn read(r: &Renderer, name: &str) -> gi_render::ImageF32 {
    r.readback(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The rgb of a texel.
pub fn v3(p: [f32; 4]) -> glam::Vec3 {
    glam::Vec3::new(p[0], p[1], p[2])
}

/// A Soler mip level as the CPU twin (`cpu::soler`) reads it from the GPU: level k ≥ 1 from
/// `soler.level.k.{position,normal,radiance,material}`, level 0 from the G-buffer with the
/// light named `radiance` (`direct.radiance`, or the bounce before's).
pub fn soler_level(r: &Renderer, k: u32, radiance: &str) -> gi_render::cpu::soler::Level {
    use gi_render::cpu::soler::{Level, Texel};
    let names: [String; 4] = if k == 0 {
        ["gbuffer.position".into(), "gbuffer.normal".into(), radiance.into(), "gbuffer.material".into()]
    } else {
        ["position", "normal", "radiance", "material"].map(|n| format!("soler.level.{k}.{n}"))
    };
    let [p, n, l, m] = names.map(|name| read(r, &name));
    let texels = (0..p.data.len())
        .map(|i| {
            if n.data[i][3] < 0.5 {
                return Texel::default();
            }
            let material = glam::Vec2::new(m.data[i][0], m.data[i][1]);
            Texel {
                position: v3(p.data[i]),
                depth: p.data[i][3],
                normal: v3(n.data[i]),
                radiance: v3(l.data[i]),
                material,
            }
        })
        .collect();
    Level { width: p.width, height: p.height, texels }
}

/// The CPU twin's screen camera and gather parameters for `level`, the `i`-th gathered level
/// (mip level `k`) of `r`'s Soler settings, at frame 0 and without a near-field cut.
pub fn soler_gather_params(
    r: &Renderer,
    i: usize,
    k: u32,
    level: &gi_render::cpu::soler::Level,
) -> (gi_render::cpu::soler::ScreenCamera, gi_render::cpu::soler::GatherParams) {
    use gi_render::passes::soler::FormFactor;
    let s = &r.settings().soler;
    let tan_v = (0.5 * r.camera.yfov).tan();
    let screen = gi_render::cpu::soler::ScreenCamera {
        eye: r.camera.position,
        tan_half: glam::Vec2::new(tan_v, tan_v),
        size: glam::Vec2::new(level.width as f32, level.height as f32),
    };
    let p = gi_render::cpu::soler::GatherParams {
        samples: s.samples,
        radius: s.radius_px,
        full_disc: i == 0,
        level: k,
        frame: 0,
        disc: s.form_factor == FormFactor::PointToDisc,
        min_cos_beta: s.min_cos_beta,
        near_cut: 0.0,
    };
    (screen, p)
}
pub mod crash_safe;
pub mod images;
pub mod knecht_support;
pub mod meshopt_copy;
pub mod ui_harness;
pub mod validation;

/// A square grey checkerboard base-colour texture of `size` texels, cells of `cell` texels,
/// white and `dark` (sRGB byte) in turn.
pub fn checker_texture(size: u32, cell: u32, dark: u8) -> gi_render::scene::TextureImage {
    let rgba8: Vec<u8> = (0..size * size)
        .flat_map(|i| {
            let v = if ((i % size) / cell + (i / size) / cell).is_multiple_of(2) { 255 } else { dark };
            [v, v, v, 255]
        })
        .collect();
    gi_render::scene::TextureImage { name: "checker".into(), width: size, height: size, rgba8: rgba8.into() }
}

/// Issue #51: at every pixel a splatting technique covers, its indirect light (`indirect`)
/// equals the CPU twin of the glossy receiver (`cpu::brdf::receive_irradiance`) fed with the
/// pass's own buffers: E from `irradiance`, the mean direction Σ w·dir / lum(Σ w·E) from the
/// direction sums `dirs` and the irradiance sums `sums`, the G-buffer's normal, albedo, DI, SI
/// and SP, the view from the camera. Returns the pixels compared and those whose specular term
/// is at least 10 % of their diffuse one (so that the comparison is not of diffuse light only).
pub fn assert_glossy_receiver_matches_the_cpu(
    r: &Renderer,
    indirect: &str,
    irradiance: &str,
    sums: &str,
    dirs: &str,
) -> (usize, usize) {
    let [ind, irr, sum, dir, pos, nrm, alb, mat] =
        [indirect, irradiance, sums, dirs, "gbuffer.position", "gbuffer.normal", "gbuffer.albedo", "gbuffer.material"]
            .map(|name| read(r, name));
    let eye = r.camera.position;
    let luma = glam::Vec3::new(0.2126, 0.7152, 0.0722);
    let (mut compared, mut glossy) = (0, 0);
    for y in 0..ind.height {
        for x in 0..ind.width {
            let (n, a) = (nrm.at(x, y), sum.at(x, y));
            if n[3] < 0.5 || a[3] <= 0.0 {
                continue;
            }
            let e = v3(irr.at(x, y));
            let lum = v3(a).dot(luma);
            let d = if lum > 0.0 { v3(dir.at(x, y)) / lum } else { glam::Vec3::ZERO };
            let p = v3(pos.at(x, y));
            let (c, m) = (alb.at(x, y), mat.at(x, y));
            let (n, v) = (v3(n).normalize(), (eye - p).normalize());
            let rx = gi_render::cpu::brdf::Receiver { n, v, albedo: v3(c), di: c[3], si: m[0], sp: m[1], glossy: true };
            let want = gi_render::cpu::brdf::receive_irradiance(e, d, &rx);
            let diffuse = rx.albedo * rx.di / std::f32::consts::PI * e;
            let got = v3(ind.at(x, y));
            let scale = want.max_element().max(1e-6);
            assert!(
                (got - want).abs().max_element() <= 2e-3 * scale + 1e-7,
                "{indirect} at ({x}, {y}): {got} vs the CPU twin's {want} (E {e}, d {d})"
            );
            compared += 1;
            glossy += ((want - diffuse).max_element() >= 0.1 * diffuse.max_element()) as usize;
        }
    }
    (compared, glossy)
}

/// A GPU irradiance record as Gautron's CPU twin holds it (`cpu::gautron::Record`), for the
/// tests that compare the two (the renderer itself never needs the conversion).
pub fn cpu_record(r: &gi_render::passes::gautron::GpuRecord) -> gi_render::cpu::gautron::Record {
    gi_render::cpu::gautron::Record {
        p: r.position.truncate(),
        n: r.normal.truncate(),
        r: r.position.w,
        e: r.irradiance.truncate(),
        rot: r.rot.map(|v| v.truncate()),
        trans: r.trans.map(|v| v.truncate()),
    }
}

/// A closed cube [−1, 1]³ whose faces look inward, all of one material of albedo `albedo`
/// emitting `emission` (the white furnaces of the path tracers and of DDGI).
pub fn furnace_scene(albedo: f32, emission: f32) -> gi_render::scene::Scene {
    use gi_render::scene::{Material, Mesh, Node, Primitive, Scene, Transform, vertex};
    use glam::{Vec2, Vec3, Vec4};
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = -Vec3::from_array({
                let mut a = [0.0; 3];
                a[axis] = sign;
                a
            });
            let (u, v) = {
                let t = n.any_orthonormal_vector();
                (t, n.cross(t))
            };
            let c = -n; // face centre
            let base = vertices.len() as u32;
            for (du, dv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                vertices.push(vertex(c + u * du + v * dv, n, Vec2::ZERO));
            }
            // Counter-clockwise seen from inside (around n).
            indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    let material = Material {
        name: "furnace".into(),
        base_color: Vec4::new(albedo, albedo, albedo, 1.0),
        emissive: Vec3::splat(emission),
        specular_override: Some(0.0),
        double_sided: true,
        ..Material::default()
    };
    Scene {
        name: "furnace".into(),
        meshes: vec![Mesh { name: "cube".into(), primitives: vec![Primitive { vertices, indices, material: 0 }] }],
        materials: vec![material],
        nodes: vec![Node {
            name: "cube".into(),
            transform: Transform::default(),
            children: vec![],
            mesh: Some(0),
            light: None,
            camera: None,
        }],
        roots: vec![0],
        ..Scene::default()
    }
}
