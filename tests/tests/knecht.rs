//! Instant radiosity with imperfect shadow maps and temporal coherence (Knecht 002, issue
//! #5): GPU kernels against their CPU twins in `gi_render::cpu::knecht`, and the whole
//! technique on the default scene.

use gi_lab_tests::{default_scene, gpu};
use gi_render::cpu::knecht::{self, ISM_EMPTY, Pyramid, halton};
use gi_render::passes::knecht::ism::{IsmPass, IsmSettings, PushBehind};
use gi_render::passes::knecht::vpl_importance::{ViewJob, VplImportancePass};
use gi_render::passes::shadow::LightView;
use gi_render::pipeline::{Technique, VplVisibility};
use gi_render::scene::upload::GpuScene;
use gi_render::{GpuContext, LabSettings, RenderError, Renderer};
use glam::{Mat4, Vec2, Vec3};

fn read_buffer(ctx: &GpuContext, src: &wgpu::Buffer, bytes: u64) -> Vec<u8> {
    gi_render::buffers::read_storage(ctx, src, bytes).expect("map")
}

fn dummy_view() -> LightView {
    LightView {
        view: Mat4::IDENTITY,
        proj: Mat4::IDENTITY,
        eye: Vec3::ZERO,
        forward: Vec3::NEG_Z,
        pixel_extent: 2.0,
        orthographic: false,
    }
}

/// Warps `count` Halton samples from index `first` over a synthetic `size`² importance map
/// on the GPU; returns (uv, pdf, texel index) per sample.
fn gpu_warp(ctx: &GpuContext, map: &[f32], size: u32, first: u32, count: u32) -> Vec<[f32; 4]> {
    let scene = default_scene();
    let gs = GpuScene::new(ctx, &scene);
    let mut pass = VplImportancePass::new(ctx, size);
    pass.ensure(ctx, &gs, size, 1, count);
    pass.upload_importance(ctx, 0, map);
    let jobs = [ViewJob { light_index: 0, view: dummy_view(), first: 0, count }];
    pass.write_params(ctx, &[], &jobs, first, 1.0);
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.warp") });
    pass.pyramid(ctx, &mut enc, None, 1, false);
    pass.warp(ctx, &mut enc, None, &jobs);
    ctx.queue.submit([enc.finish()]);
    let bytes = read_buffer(ctx, &pass.warped, 16 * count as u64);
    bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec()
}

#[test]
fn halton_and_warping_of_a_uniform_map_are_the_identity_on_the_gpu() {
    let ctx = gpu();
    let out = gpu_warp(&ctx, &vec![1.0; 16 * 16], 16, 1, 256);
    for (i, w) in out.iter().enumerate() {
        let k = 1 + i as u32;
        let u = Vec2::new(halton(k, 2), halton(k, 3));
        assert!((Vec2::new(w[0], w[1]) - u).length() < 1e-5, "sample {i}: GPU {w:?}, Halton {u}");
        assert!((w[2] - 1.0).abs() < 1e-5);
    }
}

#[test]
fn hierarchical_warping_matches_the_cpu_and_follows_the_importance_map() {
    let ctx = gpu();
    let size = 64u32;
    // A smooth gradient, a bright square and a region of zero importance.
    let map: Vec<f32> = (0..size * size)
        .map(|i| {
            let (x, y) = ((i % size) as f32, (i / size) as f32);
            if x < 8.0 {
                0.0
            } else if (40.0..48.0).contains(&x) && (10.0..18.0).contains(&y) {
                20.0
            } else {
                0.2 + x / 64.0 + 0.5 * (y / 64.0)
            }
        })
        .collect();
    let n = 4096u32;
    let out = gpu_warp(&ctx, &map, size, 1, n);
    let pyr = Pyramid::new(size, map.clone());
    let mut same = 0;
    let mut hist = vec![0u32; 64];
    for (i, w) in out.iter().enumerate() {
        let k = 1 + i as u32;
        let (texel, uv, pdf) = pyr.warp(Vec2::new(halton(k, 2), halton(k, 3))).expect("non-zero map");
        let t = w[3] as u32;
        assert!(map[t as usize] > 0.0, "sample {i} landed on zero importance");
        if t == texel.y * size + texel.x {
            same += 1;
            assert!((Vec2::new(w[0], w[1]) - uv).length() < 1e-4, "sample {i}: GPU {w:?}, CPU {uv}");
            assert!((w[2] - pdf).abs() <= 1e-4 * pdf, "sample {i}: pdf GPU {} CPU {pdf}", w[2]);
        }
        let (bx, by) = ((t % size) / 8, (t / size) / 8);
        hist[(by * 8 + bx) as usize] += 1;
    }
    // Rounding may move a sample that sits on a split across it; nearly all must agree.
    assert!(same as f32 >= 0.995 * n as f32, "only {same} of {n} samples in the CPU's texel");
    // χ² of the 8×8 block histogram against the map: 63 degrees of freedom (minus the empty
    // blocks), critical value 103.4 at p = 0.001. Halton samples are far more even than
    // random ones, so the statistic is well below it.
    let total: f32 = map.iter().sum();
    let mut chi2 = 0.0f32;
    for by in 0..8 {
        for bx in 0..8 {
            let mut e = 0.0;
            for y in by * 8..by * 8 + 8 {
                for x in bx * 8..bx * 8 + 8 {
                    e += map[(y * size + x) as usize];
                }
            }
            let expected = e / total * n as f32;
            let observed = hist[(by * 8 + bx) as usize] as f32;
            if expected > 0.0 {
                chi2 += (observed - expected).powi(2) / expected;
            } else {
                assert_eq!(observed, 0.0, "samples in a block of zero importance");
            }
        }
    }
    assert!(chi2 < 103.4, "χ² = {chi2}");
}

#[test]
fn pull_push_on_the_gpu_equals_the_cpu_reference() {
    let ctx = gpu();
    let scene = default_scene();
    let state = scene.evaluate(0.0);
    let s = IsmSettings { points: 1024, map_size: 32, pull_push_levels: 3, ..Default::default() };
    let mut pass = IsmPass::new(&ctx);
    pass.ensure(&ctx, &scene, &state, &s, 6, false);
    let l = pass.layout_info;
    let (w, h) = (l.width() as u32, l.height() as u32);
    assert_eq!((l.cols, l.rows), (3, 2));
    // Two depth layers (a near occluder over a far wall) with holes of every size.
    let atlas: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let hash = (x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663)) % 100;
            if hash < 35 || ((x % 32) > 20 && (y % 32) < 6) {
                ISM_EMPTY
            } else if (x % 32) < 12 {
                1.0 + 0.01 * (y % 32) as f32
            } else {
                3.0 + 0.02 * (x % 7) as f32
            }
        })
        .collect();
    ctx.queue.write_texture(
        pass.atlas.as_image_copy(),
        bytemuck::cast_slice(&atlas),
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * w), rows_per_image: None },
        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    );
    let extent = 4.0;
    let mut cpu = Vec::new();
    let mut finest = Vec::new();
    // Both push rules (`ism.push_behind`): the thesis' and inside-surfaces-only.
    for rule in [PushBehind::Everywhere, PushBehind::InsideSurfaces] {
        let s = IsmSettings { push_behind: rule, ..s.clone() };
        let mut enc =
            ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.pull_push") });
        pass.pull_push(&ctx, &mut enc, None, &s, extent);
        ctx.queue.submit([enc.finish()]);
        let thresholds = [s.pull_threshold * extent, s.push_threshold * extent];
        cpu = knecht::pull_push(&atlas, w, h, 32, 3, thresholds, rule == PushBehind::InsideSurfaces);
        for (level, expected) in cpu.iter().enumerate() {
            let got = gi_render::buffers::read_texture(&ctx, "ism.atlas_pulled", &pass.pulled, 0, level as u32)
                .expect("read");
            let mut bad = 0;
            for (i, e) in expected.iter().enumerate() {
                let g = got.data[i][0];
                let ok = if *e >= ISM_EMPTY { g >= ISM_EMPTY } else { (g - e).abs() <= 1e-5 * e.abs().max(1.0) };
                if !ok {
                    bad += 1;
                }
            }
            assert_eq!(bad, 0, "{rule:?}, level {level}: {bad} texels differ from the CPU reference");
        }
        finest.push(cpu[0].clone());
    }
    assert_ne!(finest[0], finest[1], "the atlas has silhouettes where the two rules differ");
    // Pull-push filled holes: fewer holes at level 0 than splatted.
    let holes = |v: &[f32]| v.iter().filter(|&&d| d >= ISM_EMPTY).count();
    assert!(holes(&cpu[0]) * 4 < holes(&atlas), "{} holes left of {}", holes(&cpu[0]), holes(&atlas));
}

fn knecht_settings() -> LabSettings {
    let mut s = LabSettings::default();
    Technique::Knecht.apply(&mut s);
    s
}

/// Mean indirect light (rgb) of the left and right thirds of `temporal.history`.
fn thirds(r: &Renderer) -> (Vec3, Vec3) {
    let img = r.readback("temporal.history").expect("temporal.history");
    let (mut left, mut right) = (Vec3::ZERO, Vec3::ZERO);
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.at(x, y);
            let v = Vec3::new(p[0], p[1], p[2]);
            assert!(v.is_finite() && v.min_element() >= 0.0, "indirect light {v} at ({x}, {y})");
            if x < img.width / 3 {
                left += v;
            } else if x >= 2 * img.width / 3 {
                right += v;
            }
        }
    }
    (left, right)
}

#[test]
fn instant_radiosity_bleeds_the_walls_colours() {
    let mut r = Renderer::new(gpu(), default_scene(), knecht_settings(), 128, 128).expect("renderer");
    r.clock.playing = false;
    for _ in 0..4 {
        r.render_frame();
    }
    let (left, right) = thirds(&r);
    // The red wall is on the left, the green one on the right (Knecht's Cornell box).
    assert!(left.x > 1.2 * left.y, "left third: {left}");
    assert!(right.y > 1.2 * right.x, "right third: {right}");
    for name in [
        "vpl.importance",
        "vpl.light_gbuffer.albedo",
        "ism.atlas",
        "ism.atlas_pulled",
        "interleave.split.albedo",
        "indirect.accum",
        "indirect.merged",
        "indirect.filtered",
        "temporal.confidence",
        "temporal.history",
    ] {
        r.readback(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

#[test]
fn an_ism_atlas_larger_than_the_device_is_refused_with_the_largest_valid_combination() {
    let mut r = Renderer::new(gpu(), default_scene(), LabSettings::default(), 64, 64).expect("renderer");
    let before = r.settings().clone();
    let mut s = knecht_settings();
    s.vpl.count = 4096;
    s.ism.map_size = 512;
    s.ism.points = 262144;
    match r.set_settings(s) {
        Err(e @ RenderError::IsmAtlasTooLarge { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains("at most") && msg.contains("VPLs fit"), "{msg}");
        }
        other => panic!("expected IsmAtlasTooLarge, got {other:?}"),
    }
    assert_eq!(r.settings(), &before, "a refused change must change nothing");
}

#[test]
fn combinations_that_cannot_work_are_refused_with_a_reason() {
    let mut s = knecht_settings();
    s.vpl.count = 8;
    s.interleave.n = 4;
    s.ism.map_size = 100;
    let errors = s.validate();
    let fields: Vec<&str> = errors.iter().map(|e| e.field.as_str()).collect();
    assert!(fields.contains(&"vpl.count"), "{errors:?}");
    assert!(fields.contains(&"ism.map_size"), "{errors:?}");
    assert!(errors.iter().any(|e| e.message.contains("64 or 128")), "{errors:?}");
    s.ism.map_size = 128;
    s.vpl.count = 16;
    assert!(s.validate().is_empty(), "{:?}", s.validate());
    s.pipeline.vpl_visibility = VplVisibility::None;
    assert!(s.validate().is_empty());
}

#[test]
fn every_shipped_preset_loads_cleanly_and_validates() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("presets/ exists") {
        let path = entry.expect("entry").path();
        if path.extension().is_none_or(|e| e != "ron") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("readable");
        let l = gi_render::preset::load_lenient(&text, &path.display().to_string()).expect("parses");
        assert!(l.problems.is_empty(), "{}: {:?}", path.display(), l.problems);
        assert!(l.settings.validate().is_empty(), "{}: {:?}", path.display(), l.settings.validate());
        names.push(path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default());
    }
    for want in [
        "default",
        "knecht-cornell-256",
        "knecht-multibounce",
        "ritschel-ism",
        "exact-vpl-reference",
        "nguyen-hcb",
        "nguyen-hcb-cached",
        "soler-quarter-4-64",
        "soler-near-knecht-far",
        "soler-quarter-4-64-visibility",
        "soler-at-hcb-samples",
        "gautron-ic-splatting",
        "gautron-vpl-records",
        "gautron-at-hcb-samples",
    ] {
        assert!(names.iter().any(|n| n == want), "presets/{want}.ron is missing");
    }
    let k = gi_render::preset::load_lenient(include_str!("../../presets/knecht-cornell-256.ron"), "k").expect("loads");
    let s = &k.settings;
    assert_eq!(Technique::of(&s.pipeline), Some(Technique::Knecht));
    assert_eq!((s.vpl.count, s.ism.map_size, s.interleave.n), (256, 128, 4));
    assert_eq!((s.temporal.c_base, s.interleave.alpha, s.interleave.beta), (0.9, 0.01, 0.8));
    assert_eq!(s.vpl.bounces, 1);
    let m = gi_render::preset::load_lenient(include_str!("../../presets/knecht-multibounce.ron"), "m").expect("loads");
    assert_eq!(m.settings.vpl.bounces, 2);
    assert_eq!((m.settings.vpl.count, m.settings.ism.map_size), (256, 128));
    let sol =
        gi_render::preset::load_lenient(include_str!("../../presets/soler-quarter-4-64.ron"), "s").expect("loads");
    assert_eq!(Technique::of(&sol.settings.pipeline), Some(Technique::Soler));
    let ss = &sol.settings.soler;
    assert_eq!((ss.levels, ss.samples, ss.radius_px), (4, 64, 40.0));
    let mix =
        gi_render::preset::load_lenient(include_str!("../../presets/soler-near-knecht-far.ron"), "h").expect("loads");
    assert_eq!(Technique::of(&mix.settings.pipeline), Some(Technique::SolerNearKnechtFar));
    // The far field is knecht-cornell-256's instant radiosity.
    assert_eq!((mix.settings.vpl.count, mix.settings.ism.map_size, mix.settings.interleave.n), (256, 128, 4));
    assert_eq!(mix.settings.soler.near_field_distance, 0.1);
    let vis = gi_render::preset::load_lenient(include_str!("../../presets/soler-quarter-4-64-visibility.ron"), "v")
        .expect("loads");
    assert_eq!(Technique::of(&vis.settings.pipeline), Some(Technique::Soler));
    assert!(vis.settings.soler.visibility && vis.settings.soler.voxel_slices == 128);
}

// ---------------------------------------------------------------------------------------
// Shading, filter and confidence kernels against their CPU twins on synthetic G-buffers.

/// A small deterministic generator (PCG-style hash), so that the synthetic inputs are
/// random-looking but identical on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            if (0.05..1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }
    /// A multiple of 1/255, stored exactly by an 8-bit unorm target.
    fn unorm8(&mut self) -> f32 {
        (self.next() * 255.0).round() / 255.0
    }
}

/// f32 → IEEE 754 half bits, round to nearest (normal range and zero only: the tests'
/// values are unit vectors and small integers).
fn f16_bits(x: f32) -> u16 {
    if x.abs() < 6.2e-5 {
        return if x.is_sign_negative() { 0x8000 } else { 0 };
    }
    let b = x.to_bits();
    let sign = ((b >> 16) & 0x8000) as u16;
    let exp = ((b >> 23) & 0xff) as i32 - 127 + 15;
    let man = b & 0x7f_ffff;
    let mut h = ((exp as u32) << 10) | (man >> 13);
    if man & 0x1fff > 0x1000 || (man & 0x1fff == 0x1000 && h & 1 == 1) {
        h += 1;
    }
    sign | h as u16
}

/// The value an Rgba16Float texture stores for `x`.
fn f16(x: f32) -> f32 {
    gi_render::buffers::half_to_f32(f16_bits(x))
}

/// A sampled (and copyable) texture with the given texels: Rgba32Float, or Rgba16Float
/// when `half` (the G-buffer's normal format, which the temporal pass copies).
fn texture(ctx: &GpuContext, label: &str, w: u32, h: u32, data: &[[f32; 4]], half: bool) -> wgpu::Texture {
    let format = if half { wgpu::TextureFormat::Rgba16Float } else { wgpu::TextureFormat::Rgba32Float };
    let bytes: Vec<u8> = if half {
        data.iter().flatten().flat_map(|&v| f16_bits(v).to_le_bytes()).collect()
    } else {
        bytemuck::cast_slice(data).to_vec()
    };
    gi_lab_tests::texture_from_bytes(ctx, label, format, (w, h), &bytes)
}

/// Views of a synthetic G-buffer (emission and depth are not read by the passes tested).
struct SyntheticGBuffer {
    position: wgpu::Texture,
    normal: wgpu::Texture,
    albedo: wgpu::Texture,
    material: wgpu::Texture,
    motion: wgpu::Texture,
}

impl SyntheticGBuffer {
    #[allow(clippy::too_many_arguments)]
    fn new(
        ctx: &GpuContext,
        w: u32,
        h: u32,
        position: &[[f32; 4]],
        normal: &[[f32; 4]],
        albedo: &[[f32; 4]],
        material: &[[f32; 4]],
        motion: &[[f32; 4]],
    ) -> Self {
        Self {
            position: texture(ctx, "test.position", w, h, position, false),
            normal: texture(ctx, "test.normal", w, h, normal, true),
            albedo: texture(ctx, "test.albedo", w, h, albedo, false),
            material: texture(ctx, "test.material", w, h, material, false),
            motion: texture(ctx, "test.motion", w, h, motion, false),
        }
    }

    fn views(&self) -> gi_render::passes::gbuffer::GBufferViews {
        let v = |t: &wgpu::Texture| t.create_view(&Default::default());
        gi_render::passes::gbuffer::GBufferViews {
            position: v(&self.position),
            normal: v(&self.normal),
            albedo: v(&self.albedo),
            material: v(&self.material),
            motion: v(&self.motion),
            emission: v(&self.albedo),
            depth: v(&self.position),
        }
    }
}

fn read(ctx: &GpuContext, t: &wgpu::Texture) -> gi_render::buffers::ImageF32 {
    gi_render::buffers::read_texture(ctx, "test", t, 0, 0).expect("readback")
}

#[test]
fn interleaved_vpl_shading_on_the_gpu_equals_eq_4_7_to_4_9_on_the_cpu() {
    use gi_render::passes::knecht::interleave::{GatherVisibility, InterleavePass};
    let ctx = gpu();
    // An odd size, so that the last row and column of tiles are partial; n = 2 and 7 VPLs,
    // so that the tiles hold 2, 2, 2 and 1 VPLs and the N / N_t scaling differs per tile.
    let (w, h, n) = (30u32, 26u32, 2u32);
    let mut rng = Rng(7);
    let len = (w * h) as usize;
    let (mut pos, mut nrm, mut alb, mut mat) =
        (vec![[0.0; 4]; len], vec![[0.0; 4]; len], vec![[0.0; 4]; len], vec![[0.0; 4]; len]);
    let mut receivers = vec![None; len];
    for i in 0..len {
        if rng.next() < 0.1 {
            continue; // background
        }
        let p = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 0.5));
        let nq = {
            let u = rng.unit();
            Vec3::new(f16(u.x), f16(u.y), f16(u.z))
        };
        let c = Vec3::new(rng.unorm8(), rng.unorm8(), rng.unorm8());
        let di = rng.unorm8();
        // SI in eighths and SP a small integer: exact in the split's half-float target.
        let si = (rng.next() * 8.0).floor() / 8.0;
        let sp = [1.0, 8.0, 32.0, 200.0][(rng.next() * 4.0) as usize % 4];
        pos[i] = [p.x, p.y, p.z, 1.0];
        nrm[i] = [nq.x, nq.y, nq.z, 1.0];
        alb[i] = [c.x, c.y, c.z, di];
        mat[i] = [si, sp, 0.0, 0.0];
        receivers[i] = Some(knecht::Receiver { position: p, normal: nq.normalize(), albedo: c, di, si, sp });
    }
    let vpl_count = 7u32;
    let mut cpu_vpls = Vec::new();
    let mut gpu_vpls = Vec::new();
    for k in 0..vpl_count {
        let v = knecht::Vpl {
            position: Vec3::new(rng.range(-1.5, 1.5), rng.range(-1.5, 1.5), rng.range(0.0, 1.5)),
            normal: rng.unit(),
            flux: Vec3::new(rng.range(0.5, 4.0), rng.range(0.5, 4.0), rng.range(0.5, 4.0)),
            incident: rng.unit(),
            albedo: Vec3::new(rng.next(), rng.next(), rng.next()),
            di: rng.next(),
            si: rng.next(),
            sp: [2.0, 16.0, 64.0][k as usize % 3],
        };
        // VPL 5 is an empty slot (position.w = 0): it is skipped but still counted in N_t.
        let enabled = k != 5;
        gpu_vpls.push(gi_render::passes::reference::vpl::GpuVpl {
            position: v.position.extend(enabled as u32 as f32),
            normal: v.normal.extend(v.di),
            flux: v.flux.extend(v.si),
            incident: v.incident.extend(v.sp),
            albedo: v.albedo.extend(0.0),
        });
        cpu_vpls.push(enabled.then_some(v));
    }
    let eye = Vec3::new(0.2, 0.1, 3.0);
    let d_min = 0.1;
    let camera = gi_render::passes::CameraUniform {
        view_proj: Mat4::IDENTITY,
        prev_view_proj: Mat4::IDENTITY,
        inv_view_proj: Mat4::IDENTITY,
        view: Mat4::IDENTITY,
        position: eye.extend(1.0),
        viewport: glam::Vec4::new(w as f32, h as f32, 1.0 / w as f32, 1.0 / h as f32),
        params: glam::Vec4::new(0.1, 10.0, 0.0, 0.0),
        lod: glam::Vec4::new(-1.0, 0.0, 0.0, 0.0),
    };
    let buffer = |label, bytes: &[u8], usage| {
        let b = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes.len() as u64,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue.write_buffer(&b, 0, bytes);
        b
    };
    let camera_buf = buffer("test.camera", bytemuck::bytes_of(&camera), wgpu::BufferUsages::UNIFORM);
    let vpl_buf = buffer("test.vpls", bytemuck::cast_slice(&gpu_vpls), wgpu::BufferUsages::STORAGE);
    let g = SyntheticGBuffer::new(&ctx, w, h, &pos, &nrm, &alb, &mat, &vec![[0.0; 4]; len]);
    let mut pass = InterleavePass::new(&ctx, gi_render::passes::bgl::uniform(0, wgpu::ShaderStages::COMPUTE), w, h, n);
    let mut timer = gi_render::timing::GpuTimer::new(&ctx);
    // Frame 0 with the full BRDF at the receiver, frame 1 (another slot→tile map) diffuse only.
    let (mut lit, mut dark) = (0, 0);
    for (frame, diffuse) in [(0u32, false), (1, true)] {
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.shade") });
        pass.shade(
            &ctx,
            &mut enc,
            &mut timer,
            &camera_buf,
            &g.views(),
            &vpl_buf,
            vpl_count,
            d_min,
            0.0,
            &GatherVisibility::None,
            diffuse,
        );
        ctx.queue.submit([enc.finish()]);
        let got = read(&ctx, &pass.merged);
        let offsets = knecht::tile_offsets(vpl_count, n, frame);
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let tile = (x % n) + (y % n) * n;
                let mut expected = Vec3::ZERO;
                if let Some(r) = &receivers[i] {
                    // Diffuse only: the receiver's SI is 0 (c·DI/π, as the HCB reflects).
                    let r = knecht::Receiver { si: if diffuse { 0.0 } else { r.si }, ..*r };
                    let slots: Vec<u32> = knecht::tile_slots(tile, vpl_count, n, &offsets).collect();
                    let per_tile = slots.len() as u32;
                    for k in slots {
                        if let Some(v) = &cpu_vpls[k as usize] {
                            expected += knecht::vpl_radiance(v, &r, eye, d_min);
                        }
                    }
                    expected *= vpl_count as f32 / per_tile as f32;
                }
                let p = got.at(x, y);
                let g3 = Vec3::new(p[0], p[1], p[2]);
                let err = (g3 - expected).abs().max_element();
                assert!(
                    err <= 1e-5 + 2e-4 * expected.abs().max_element(),
                    "frame {frame}, diffuse {diffuse}: pixel ({x}, {y}), tile {tile}: GPU {g3}, CPU {expected}"
                );
                if expected.max_element() > 1e-3 {
                    lit += 1;
                } else if receivers[i].is_some() {
                    dark += 1;
                }
            }
        }
    }
    let len = 2 * len;
    // The inputs exercise both sides of the cosine tests.
    assert!(lit > len / 4 && dark > len / 20, "{lit} lit and {dark} unlit foreground pixels of {len}");
}

#[test]
fn geometry_aware_filter_on_the_gpu_equals_the_cpu() {
    use gi_render::passes::knecht::interleave::{InterleavePass, InterleaveSettings};
    let ctx = gpu();
    let (w, h, n) = (27u32, 21u32, 4u32);
    let depth_range = 10.0;
    let mut rng = Rng(11);
    let len = (w * h) as usize;
    // Two surfaces meeting along a diagonal — a floor (depth 2 + a slope, normal +y) and a
    // wall 0.3 behind it (normal +z) — with per-pixel depth jitter around α·range = 0.1,
    // tilted normals around β, and background pixels.
    let mut texels = Vec::with_capacity(len);
    for y in 0..h {
        for x in 0..w {
            if rng.next() < 0.08 {
                texels.push(knecht::FilterTexel { value: Vec3::ZERO, depth: 0.0, normal: Vec3::Z });
                continue;
            }
            let floor = x + y < 24;
            let base = if floor { 2.0 + 0.01 * x as f32 } else { 2.3 };
            let depth = base + rng.range(-0.08, 0.08);
            let axis = if floor { Vec3::Y } else { Vec3::Z };
            let normal = (axis + 0.5 * rng.range(0.0, 1.0) * rng.unit()).normalize();
            let normal = Vec3::new(f16(normal.x), f16(normal.y), f16(normal.z));
            let value = Vec3::new(rng.range(0.0, 2.0), rng.range(0.0, 2.0), rng.range(0.0, 2.0));
            texels.push(knecht::FilterTexel { value, depth, normal });
        }
    }
    let pos: Vec<[f32; 4]> = texels.iter().map(|t| [0.0, 0.0, 0.0, t.depth]).collect();
    let nrm: Vec<[f32; 4]> = texels
        .iter()
        .map(|t| if t.depth > 0.0 { [t.normal.x, t.normal.y, t.normal.z, 1.0] } else { [0.0; 4] })
        .collect();
    let src: Vec<[f32; 4]> = texels.iter().map(|t| [t.value.x, t.value.y, t.value.z, 1.0]).collect();
    let zero = vec![[0.0; 4]; len];
    let g = SyntheticGBuffer::new(&ctx, w, h, &pos, &nrm, &zero, &zero, &zero);
    let src_tex = texture(&ctx, "test.src", w, h, &src, false);
    let pass = InterleavePass::new(&ctx, gi_render::passes::bgl::uniform(0, wgpu::ShaderStages::COMPUTE), w, h, n);
    let s = InterleaveSettings { n, ..Default::default() };
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.filter") });
    pass.filter(&ctx, &mut enc, None, &s, depth_range, &src_tex.create_view(&Default::default()), &g.views());
    ctx.queue.submit([enc.finish()]);
    let got = read(&ctx, &pass.filtered);
    let cpu = knecht::geometry_aware_filter(&texels, w, h, n, s.alpha, s.beta, depth_range);
    let mut partial = 0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let p = got.at(x, y);
            let g3 = Vec3::new(p[0], p[1], p[2]);
            assert!((g3 - cpu[i]).abs().max_element() <= 1e-5, "pixel ({x}, {y}): GPU {g3}, CPU {}", cpu[i]);
            // Count pixels where the thresholds rejected some neighbours but not all.
            if texels[i].depth > 0.0 && (cpu[i] - texels[i].value).abs().max_element() > 1e-3 {
                partial += 1;
            }
        }
    }
    assert!(partial > len / 2, "only {partial} pixels were averaged");
    // The thresholds matter: with α and β open the result differs near the crease.
    let open = knecht::geometry_aware_filter(&texels, w, h, n, 1.0, -1.0, depth_range);
    let differ = cpu.iter().zip(&open).filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3).count();
    assert!(differ > len / 4, "the thresholds rejected neighbours at only {differ} pixels");
}

#[test]
fn confidence_and_merge_on_the_gpu_equal_eq_3_1_to_3_6_on_the_cpu() {
    use gi_render::passes::knecht::temporal::{TemporalPass, TemporalSettings};
    let ctx = gpu();
    let (w, h) = (24u32, 20u32);
    let depth_range = 9.9;
    let mut rng = Rng(23);
    let len = (w * h) as usize;
    // Frame 0: depth, normal and light per pixel (some background).
    struct Px {
        depth: f32,
        normal: Vec3,
        light: Vec3,
    }
    let frame = |rng: &mut Rng| -> Vec<Option<Px>> {
        (0..len)
            .map(|_| {
                (rng.next() > 0.1).then(|| {
                    let n = (Vec3::Z + 0.4 * rng.unit()).normalize();
                    Px {
                        depth: rng.range(1.0, 5.0),
                        normal: Vec3::new(f16(n.x), f16(n.y), f16(n.z)),
                        light: Vec3::new(rng.range(0.1, 2.0), rng.range(0.1, 2.0), rng.range(0.1, 2.0)),
                    }
                })
            })
            .collect()
    };
    let f0 = frame(&mut rng);
    // Frame 1: each pixel moved a little from its frame-0 self (or is new); motion in
    // pixels, some reaching off screen.
    let f1: Vec<Option<Px>> = f0
        .iter()
        .map(|p| {
            let keep = rng.next();
            if rng.next() < 0.1 {
                return None;
            }
            Some(match p {
                Some(p) if keep < 0.8 => {
                    let n = (p.normal + rng.range(0.0, 0.3) * rng.unit()).normalize();
                    Px {
                        depth: p.depth + rng.range(-0.2, 0.2),
                        normal: Vec3::new(f16(n.x), f16(n.y), f16(n.z)),
                        light: p.light * rng.range(0.7, 1.3),
                    }
                }
                _ => Px {
                    depth: rng.range(1.0, 5.0),
                    normal: Vec3::Z,
                    light: Vec3::new(rng.range(0.1, 2.0), rng.range(0.1, 2.0), rng.range(0.1, 2.0)),
                },
            })
        })
        .collect();
    let motion: Vec<Vec2> = (0..len)
        .map(|_| if rng.next() < 0.5 { Vec2::ZERO } else { Vec2::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)) })
        .collect();
    let upload = |f: &[Option<Px>], motion: &[Vec2]| {
        let pos: Vec<[f32; 4]> = f.iter().map(|p| [0.0, 0.0, 0.0, p.as_ref().map_or(0.0, |p| p.depth)]).collect();
        let nrm: Vec<[f32; 4]> =
            f.iter().map(|p| p.as_ref().map_or([0.0; 4], |p| [p.normal.x, p.normal.y, p.normal.z, 1.0])).collect();
        let light: Vec<[f32; 4]> =
            f.iter().map(|p| p.as_ref().map_or([0.0; 4], |p| [p.light.x, p.light.y, p.light.z, 1.0])).collect();
        let mv: Vec<[f32; 4]> = motion.iter().map(|m| [m.x, m.y, 0.0, 0.0]).collect();
        let zero = vec![[0.0; 4]; len];
        (
            SyntheticGBuffer::new(&ctx, w, h, &pos, &nrm, &zero, &zero, &mv),
            texture(&ctx, "test.light", w, h, &light, false),
        )
    };
    let s = TemporalSettings { w_pos: 10.0, ..Default::default() };
    let mut pass = TemporalPass::new(&ctx, w, h);
    for (f, m) in [(&f0, vec![Vec2::ZERO; len]), (&f1, motion.clone())] {
        let (g, light) = upload(f, &m);
        let mut enc =
            ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.temporal") });
        pass.run(&ctx, &mut enc, None, &s, depth_range, &light.create_view(&Default::default()), &g.views(), &g.normal);
        ctx.queue.submit([enc.finish()]);
    }
    let conf = read(&ctx, &pass.confidence);
    let hist = read(&ctx, &pass.history);
    let weights = knecht::ConfidenceWeights {
        c_base: s.c_base,
        w_pos: s.w_pos,
        w_normal: s.w_normal,
        w_illumination: s.w_illumination,
    };
    let (mut zero, mut middle, mut merged) = (0, 0, 0);
    for y in 0..h as i32 {
        for x in 0..w as i32 {
            let i = (y * w as i32 + x) as usize;
            let (mut c, mut out) = (0.0, f1[i].as_ref().map_or(Vec3::ZERO, |p| p.light));
            if let Some(p) = &f1[i] {
                // The shader's lookup: the previous position rounded to a pixel.
                let m = motion[i];
                let q = (Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + m).floor();
                let inside = q.x >= 0.0 && q.y >= 0.0 && q.x < w as f32 && q.y < h as f32;
                if inside && let Some(prev) = &f0[(q.y as u32 * w + q.x as u32) as usize] {
                    let input = knecht::ConfidenceInput {
                        motion_px: m,
                        size: Vec2::new(w as f32, h as f32),
                        depth: p.depth,
                        depth_prev: prev.depth,
                        depth_range,
                        normal: p.normal,
                        normal_prev: prev.normal,
                        illumination: p.light,
                        illumination_prev: prev.light,
                    };
                    c = knecht::confidence(&input, &weights);
                    out = knecht::merge(p.light, prev.light, c);
                    merged += 1;
                }
            }
            let g = conf.at(x as u32, y as u32)[0];
            assert!((g - c).abs() <= 2e-5, "confidence at ({x}, {y}): GPU {g}, CPU {c}");
            let hp = hist.at(x as u32, y as u32);
            let h3 = Vec3::new(hp[0], hp[1], hp[2]);
            assert!(
                (h3 - out).abs().max_element() <= 1e-4 * out.max_element().max(1.0),
                "merge at ({x}, {y}): GPU {h3}, CPU {out}"
            );
            let depth = f1[i].as_ref().map_or(0.0, |p| p.depth);
            assert_eq!(hp[3], depth, "history depth at ({x}, {y})");
            if c == 0.0 {
                zero += 1;
            } else if c > 0.05 && c < 0.85 {
                middle += 1;
            }
        }
    }
    // Every branch is exercised: rejected, partial and merged pixels.
    assert!(merged > len / 2 && zero > len / 20 && middle > len / 10, "{merged} merged, {zero} zero, {middle} between");
}

#[test]
fn the_vpl_list_holds_every_vpl_on_the_scene_surfaces() {
    let mut r = Renderer::new(gpu(), default_scene(), knecht_settings(), 64, 64).expect("renderer");
    r.clock.playing = false;
    assert!(r.vpl_list().is_none(), "no list before a frame");
    r.render_frame();
    let vpls = r.vpl_list().expect("instant radiosity has a VPL list");
    assert_eq!(vpls.len(), r.settings().vpl.count as usize);
    let b = r.bounds();
    let slack = 1e-3 * b.radius();
    for v in &vpls {
        let p = v.position.truncate();
        assert!(p.cmpge(b.min - slack).all() && p.cmple(b.max + slack).all(), "VPL at {p} outside the scene");
        assert!((v.normal.truncate().length() - 1.0).abs() < 1e-3, "normal {:?}", v.normal);
        assert!(v.flux.truncate().is_finite() && v.flux.truncate().min_element() >= 0.0, "flux {:?}", v.flux);
    }
    // The red and green walls hold VPLs whose reflected flux is red and green.
    let reflected: Vec<Vec3> = vpls.iter().map(|v| (v.flux * v.albedo).truncate()).collect();
    assert!(reflected.iter().any(|c| c.x > 2.0 * c.y) && reflected.iter().any(|c| c.y > 2.0 * c.x));
    let mut s = r.settings().clone();
    Technique::DirectOnly.apply(&mut s);
    r.set_settings(s).expect("valid");
    assert!(r.vpl_list().is_none(), "no list without instant radiosity");
}

/// Seven VPLs on the default scene's surfaces (slot 4 empty, every third glossy) in a list of
/// 14 slots, and the ISM pass with a 4096-point cloud, for the bounce tests.
struct BounceFixture {
    ctx: GpuContext,
    state: gi_render::scene::SceneState,
    gs: GpuScene,
    ism: IsmPass,
    s: IsmSettings,
    vpls: Vec<gi_render::passes::reference::vpl::GpuVpl>,
    vpl_buf: wgpu::Buffer,
    n: u32,
}

impl BounceFixture {
    fn new() -> Self {
        use gi_render::passes::reference::vpl::GpuVpl;
        use glam::Vec4;
        let ctx = gpu();
        let scene = default_scene();
        let state = scene.evaluate(0.0);
        let gs = GpuScene::new(&ctx, &scene);
        gs.update_instances(&ctx, &state, None);
        let n = 7u32;
        let s = IsmSettings { points: 4096, map_size: 32, ..Default::default() };
        let mut ism = IsmPass::new(&ctx);
        ism.ensure(&ctx, &scene, &state, &s, 2 * n, false);
        let mut f = Self { ctx, state, gs, ism, s, vpls: Vec::new(), vpl_buf: dummy_buffer(), n };
        let mut rng = Rng(11);
        let empty =
            GpuVpl { position: Vec4::ZERO, normal: Vec4::Z, flux: Vec4::ZERO, incident: Vec4::Z, albedo: Vec4::ZERO };
        let mut vpls = vec![empty; 2 * n as usize];
        for (i, v) in vpls.iter_mut().take(n as usize).enumerate() {
            if i == 4 {
                continue; // an empty slot gives an empty bounce VPL
            }
            let (p, nrm) = f.world(97 * i + 5);
            let incident = (nrm + 0.6 * rng.unit()).normalize();
            let si = if i % 3 == 0 { 0.6 } else { 0.0 };
            *v = GpuVpl {
                position: (p + nrm * 0.01).extend(1.0),
                normal: nrm.extend(rng.range(0.3, 1.0)),
                flux: Vec3::new(rng.range(0.5, 3.0), rng.range(0.5, 3.0), rng.range(0.5, 3.0)).extend(si),
                incident: incident.extend(rng.range(4.0, 40.0)),
                albedo: Vec3::new(rng.range(0.1, 0.9), rng.range(0.1, 0.9), rng.range(0.1, 0.9)).extend(0.0),
            };
        }
        use wgpu::util::DeviceExt;
        f.vpl_buf = f.ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("test.vpls"),
            contents: bytemuck::cast_slice(&vpls),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        });
        f.vpls = vpls;
        f
    }

    /// World position and normal of cloud point j.
    fn world(&self, j: usize) -> (Vec3, Vec3) {
        let p = self.ism.cloud.gpu[j];
        let m = self.state.draws[p.draw as usize].world;
        let nm = m.inverse().transpose();
        (m.transform_point3(Vec3::from(p.position)), nm.transform_vector3(Vec3::from(p.normal)).normalize())
    }

    fn sample(&self, j: usize) -> knecht::BounceSample {
        let (position, normal) = self.world(j);
        let surf = self.ism.cloud.surfaces[j];
        knecht::BounceSample {
            surface: knecht::Receiver {
                position,
                normal,
                albedo: glam::Vec4::from(surf.albedo).truncate(),
                di: surf.material[0],
                si: surf.material[1],
                sp: surf.material[2],
            },
            weighted_area: surf.albedo[3],
        }
    }

    fn source(&self, i: usize) -> knecht::Vpl {
        let g = self.vpls[i];
        knecht::Vpl {
            position: g.position.truncate(),
            normal: g.normal.truncate(),
            flux: g.flux.truncate(),
            incident: g.incident.truncate(),
            albedo: g.albedo.truncate(),
            di: g.normal.w,
            si: g.flux.w,
            sp: g.incident.w,
        }
    }

    fn per_vpl(&self, i: usize) -> u32 {
        (self.ism.cloud.gpu.len() as u32 - i as u32).div_ceil(self.n)
    }

    fn read_vpls(&self) -> Vec<gi_render::passes::reference::vpl::GpuVpl> {
        let size = std::mem::size_of::<gi_render::passes::reference::vpl::GpuVpl>() as u64;
        bytemuck::pod_collect_to_vec(&read_buffer(&self.ctx, &self.vpl_buf, (2 * self.n) as u64 * size))
    }
}

fn dummy_buffer() -> wgpu::Buffer {
    gpu().device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test.dummy"),
        size: 4,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).length() <= tol * b.length().max(1e-6)
}

/// The bounce selection of Knecht 002 §3.6.1 on the GPU (`vpl/bounce.wgsl`) against its CPU
/// twin: seven VPLs on the default scene's surfaces (one slot empty, some glossy), the point
/// cloud splatted into their ISMs, then bounce 2's VPLs read back. For every source VPL the
/// CPU lights its samples (Eq. 4.7–4.8 times the test against the GPU's splatted map, or the
/// gather's test on its pulled map, `cpu::knecht::ism_visible`), picks
/// the arg-max (strongest) or the exponential race's winner (proportional), and builds the
/// new VPL; the GPU's must be the same sample with the same flux.
#[test]
fn bounce_selection_on_the_gpu_picks_the_cpu_arg_max() {
    use gi_render::cpu::knecht::Selection;
    use gi_render::passes::knecht::ism::BounceShadowTest;
    use gi_render::passes::knecht::ism::IsmFrame;
    use gi_render::passes::knecht::vpl_bounce::{BounceFrame, BounceSelection, VplBouncePass};
    use gi_render::passes::reference::vpl::GpuVpl;
    let fx = BounceFixture::new();
    let (ctx, s, ism, gs, n, vpl_buf) = (&fx.ctx, &fx.s, &fx.ism, &fx.gs, fx.n, &fx.vpl_buf);
    let bounce = VplBouncePass::new(ctx);
    let (eye_offset, d_min, extent) = (0.01, 0.1, 4.0);
    let l = ism.layout_info;
    for (selection, seed, test) in [
        (BounceSelection::Strongest, 0u32, BounceShadowTest::RawSplats),
        (BounceSelection::Proportional, 5, BounceShadowTest::RawSplats),
        (BounceSelection::Strongest, 0, BounceShadowTest::PulledMaps),
    ] {
        let job = ism.begin(ctx, &gs.instances, vpl_buf, s, IsmFrame { vpls: n, bounces: 2, eye_offset, extent });
        let f = BounceFrame {
            vpls: n,
            selection,
            visibility: Some(test),
            eye_offset,
            depth_bias: s.depth_bias,
            normal_offset: s.normal_offset,
            min_distance: d_min,
            seed,
        };
        let group = bounce.begin(ctx, ism, &gs.instances, vpl_buf, 2, f);
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.bounce") });
        ism.splat(&mut enc, None, &job, 0);
        if test == BounceShadowTest::PulledMaps {
            ism.finish(ctx, &mut enc, None, &job, s, extent);
        }
        bounce.run(&mut enc, None, &group, 1, n);
        ctx.queue.submit([enc.finish()]);
        let out: Vec<GpuVpl> = fx.read_vpls();
        let depth: Vec<u32> = bytemuck::pod_collect_to_vec(&read_buffer(ctx, &ism.depth, l.width() * l.height() * 4));
        let pulled = read(ctx, &ism.pulled);
        let seed_gpu = gi_render::passes::knecht::vpl_bounce::bounce_seed(seed, 1);
        let sel = match selection {
            BounceSelection::Strongest => Selection::Strongest,
            BounceSelection::Proportional => Selection::Proportional { seed: seed_gpu },
        };
        let (mut hidden, mut lit) = (0, 0);
        for i in 0..n as usize {
            let src = fx.source(i);
            let per_vpl = fx.per_vpl(i);
            let mut contributions = Vec::new();
            let mut samples = Vec::new();
            let (ox, oy) = ((i as u32 % l.cols) * l.size, (i as u32 / l.cols) * l.size);
            for m in 0..per_vpl {
                let j = i as u32 + m * n;
                let bs = fx.sample(j as usize);
                let visible = match test {
                    // The splat test of `splat_visible`.
                    BounceShadowTest::RawSplats => {
                        let w = bs.surface.position - (src.position + src.normal * eye_offset);
                        let d = w.length();
                        let (t, b, nn) = knecht::basis(src.normal);
                        knecht::paraboloid_project(Vec3::new(w.dot(t), w.dot(b), w.dot(nn)) / d).is_some_and(|uv| {
                            let tx = ((uv.x * l.size as f32) as u32).min(l.size - 1);
                            let ty = ((uv.y * l.size as f32) as u32).min(l.size - 1);
                            let bits = depth[((oy + ty) * l.cols * l.size + ox + tx) as usize];
                            let stored = if bits == 0 { ISM_EMPTY } else { f32::from_bits(!bits) };
                            d * (1.0 - s.depth_bias) <= stored
                        })
                    }
                    // The gather's test on the pulled maps.
                    BounceShadowTest::PulledMaps => knecht::ism_visible(
                        |tx, ty| pulled.at(ox + tx, oy + ty)[0],
                        src.position,
                        src.normal,
                        bs.surface.position,
                        bs.surface.normal,
                        eye_offset,
                        l.size,
                        s.depth_bias,
                        s.normal_offset,
                    ),
                };
                let (flux, c) = knecht::bounce_incident(&src, &bs, per_vpl, d_min, visible);
                let (_, c_unseen) = knecht::bounce_incident(&src, &bs, per_vpl, d_min, true);
                if c_unseen > 0.0 && !visible {
                    hidden += 1;
                }
                contributions.push((j, c));
                samples.push((bs, flux, c));
            }
            let got = out[n as usize + i];
            if fx.vpls[i].position.w < 0.5 {
                assert_eq!(got.position.w, 0.0, "{selection:?}: empty source slot {i} gives an empty VPL");
                continue;
            }
            let Some((j, sum)) = knecht::select_bounce(&contributions, sel) else {
                assert_eq!(got.position.w, 0.0, "{selection:?}: VPL {i} lights no sample");
                continue;
            };
            lit += 1;
            let (bs, flux, c) = samples[((j - i as u32) / n) as usize];
            let want = knecht::bounce_vpl(&src, &bs, flux, c, sum);
            assert_vpl_eq(&got, &want, &format!("{selection:?}, {test:?}: VPL {i} (CPU sample {j})"));
        }
        assert!(lit >= 5, "{selection:?}: only {lit} VPLs found a lit sample");
        assert!(hidden > 0, "{selection:?}: the ISM test hid no sample, so it was not exercised");
    }
}

fn assert_vpl_eq(got: &gi_render::passes::reference::vpl::GpuVpl, want: &knecht::Vpl, what: &str) {
    assert!(
        close(got.position.truncate(), want.position, 1e-5),
        "{what}: GPU at {:?}, CPU at {:?}",
        got.position,
        want.position
    );
    assert!(close(got.flux.truncate(), want.flux, 1e-3), "{what}: flux {:?} vs {:?}", got.flux, want.flux);
    assert!(close(got.normal.truncate(), want.normal, 1e-5) && (got.normal.w - want.di).abs() < 1e-6, "{what}: normal");
    assert!(
        close(got.incident.truncate(), want.incident, 1e-4) && (got.incident.w - want.sp).abs() < 1e-4,
        "{what}: ω_in"
    );
    assert!(
        (got.flux.w - want.si).abs() < 1e-6 && close(got.albedo.truncate(), want.albedo, 1e-6),
        "{what}: SI, colour"
    );
}

/// The IRSM baseline (Knecht 002 §3.6 after Ritschel et al.) on the GPU against the CPU: the
/// same seven VPLs' IRSMs of 16²; every texel's CDF step equals the contribution of the
/// sample that owns it (the nearest that covers it), the coverage counts equal the owned
/// texels, and each new VPL is the texel `cpu::knecht::irsm_pick` draws from those CDFs,
/// with flux Φ_s · ΣC / (N n_s C_s).
#[test]
fn irsm_bounce_on_the_gpu_samples_the_texels_the_cpu_picks() {
    use gi_render::passes::knecht::irsm::{IrsmFrame, IrsmPass};
    let fx = BounceFixture::new();
    let (ctx, ism, n) = (&fx.ctx, &fx.ism, fx.n);
    let mut irsm = IrsmPass::new(ctx);
    irsm.ensure(ctx, n, 16, ism.cloud.gpu.len());
    let d_min = 0.1;
    let seed = 3;
    let f = IrsmFrame { vpls: n, bounces: 2, eye_offset: 0.01, min_distance: d_min, seed };
    let job = irsm.begin(ctx, ism, &fx.s, &fx.gs.instances, &fx.vpl_buf, f);
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.irsm") });
    irsm.run(&mut enc, None, &job, 1, n, ism.cloud.gpu.len() as u32);
    ctx.queue.submit([enc.finish()]);
    let out = fx.read_vpls();
    let l = irsm.layout_info;
    let texels = (l.size * l.size) as usize;
    let u32s = |b: &wgpu::Buffer, len: u64| -> Vec<u32> { bytemuck::pod_collect_to_vec(&read_buffer(ctx, b, 4 * len)) };
    let owner = u32s(&irsm.owner, l.width() * l.height());
    let coverage = u32s(&irsm.coverage, ism.cloud.gpu.len() as u64);
    let cdf_all: Vec<f32> = bytemuck::pod_collect_to_vec(&read_buffer(ctx, &irsm.cdf, 4 * (n as u64 * texels as u64)));
    let totals: Vec<f32> = bytemuck::pod_collect_to_vec(&read_buffer(ctx, &irsm.totals, 4 * n as u64));
    let atlas_index = |i: usize, t: usize| {
        let (x, y) =
            ((i as u32 % l.cols) * l.size + t as u32 % l.size, (i as u32 / l.cols) * l.size + t as u32 / l.size);
        (y * l.cols * l.size + x) as usize
    };
    let owner_of = |i: usize, t: usize| owner[atlas_index(i, t)];
    let illumination =
        gi_render::buffers::read_texture(ctx, "irsm.illumination", &irsm.illumination, 0, 0).expect("read");
    // CDF steps, the illumination map and coverage.
    let mut owned = vec![0u32; ism.cloud.gpu.len()];
    let mut cdfs = Vec::new();
    let mut covered = 0;
    for i in 0..n as usize {
        let cdf = cdf_all[i * texels..(i + 1) * texels].to_vec();
        let src = fx.source(i);
        let mut prev = 0.0;
        for (t, &c_gpu) in cdf.iter().enumerate() {
            let o = owner_of(i, t);
            let want = if o == 0 || fx.vpls[i].position.w < 0.5 {
                0.0
            } else {
                knecht::bounce_incident(&src, &fx.sample(o as usize - 1), fx.per_vpl(i), d_min, true).1
            };
            if want > 0.0 {
                owned[o as usize - 1] += 1;
                covered += 1;
            }
            let shown = illumination.data[atlas_index(i, t)][0];
            assert!(
                (shown - want).abs() <= 1e-5 * want.abs().max(1e-9),
                "irsm.illumination of IRSM {i} texel {t}: {shown} vs {want}"
            );
            assert!(
                ((c_gpu - prev) - want).abs() <= 1e-4 * totals[i].max(1e-6),
                "IRSM {i} texel {t}: CDF step {} vs contribution {want}",
                c_gpu - prev
            );
            prev = c_gpu;
        }
        assert!((prev - totals[i]).abs() <= 1e-5 * totals[i].max(1e-6), "IRSM {i}: total {} vs {prev}", totals[i]);
        cdfs.push(cdf);
    }
    assert!(covered > texels, "the IRSMs hold only {covered} lit texels");
    assert_eq!(coverage, owned, "texels owned per sample");
    // The picks.
    let seed_gpu = gi_render::passes::knecht::vpl_bounce::bounce_seed(seed, 1);
    let grand: f32 = totals.iter().sum();
    let mut sources = std::collections::BTreeSet::new();
    for k in 0..n {
        let got = out[(n + k) as usize];
        let (i, t) = knecht::irsm_pick(&totals, &cdfs, k, seed_gpu).expect("the IRSMs are lit");
        sources.insert(i);
        let j = owner_of(i, t) as usize - 1;
        let (src, bs) = (fx.source(i), fx.sample(j));
        let (flux, c) = knecht::bounce_incident(&src, &bs, fx.per_vpl(i), d_min, true);
        let want = knecht::bounce_vpl(&src, &bs, flux, c, grand / (n as f32 * coverage[j] as f32));
        assert_vpl_eq(&got, &want, &format!("new VPL {k} (IRSM {i}, texel {t}, sample {j})"));
    }
    assert!(!sources.contains(&4), "the empty VPL's IRSM was sampled");
}

/// Knecht 002 §4.3, render target 0: the light G-buffer reads the surfaces' colour texture at
/// the `vpl.albedo_mip` level, so that VPLs carry a blurred colour. A one-texel checker on
/// every surface varies from pixel to pixel of the light G-buffer at level 0 and is a flat
/// average at level 6 (the 1×1 mip of the 64² texture); only the walls' edges remain.
#[test]
fn the_light_gbuffer_blurs_the_surface_colour_by_the_albedo_mip_level() {
    let mut scene = default_scene();
    let rgba8: Vec<u8> = (0..64 * 64)
        .flat_map(|i| {
            let v = if (i % 64 + i / 64) % 2 == 0 { 255 } else { 0 };
            [v, v, v, 255]
        })
        .collect();
    scene.textures.push(gi_render::scene::TextureImage {
        name: "checker".into(),
        width: 64,
        height: 64,
        rgba8: rgba8.into(),
    });
    let t = scene.textures.len() - 1;
    for m in &mut scene.materials {
        m.base_color_texture = Some(t);
    }
    let variation = |mip: f32| {
        let mut s = knecht_settings();
        s.vpl.albedo_mip = mip;
        let mut r = Renderer::new(gpu(), scene.clone(), s, 64, 64).expect("renderer");
        r.clock.playing = false;
        r.render_frame();
        let a = r.readback("vpl.light_gbuffer.albedo").expect("light G-buffer albedo");
        let (mut sum, mut n) = (0.0f64, 0usize);
        for y in 0..a.height as usize {
            for x in 1..a.width as usize {
                let (p, q) = (a.data[y * a.width as usize + x - 1], a.data[y * a.width as usize + x]);
                if p[3] > 0.0 && q[3] > 0.0 {
                    sum += (0..3).map(|c| (p[c] - q[c]).abs() as f64).sum::<f64>();
                    n += 1;
                }
            }
        }
        assert!(n > 1000, "the light G-buffer sees only {n} surface pixel pairs");
        sum / n as f64
    };
    let (sharp, blurred) = (variation(0.0), variation(6.0));
    println!("mean neighbour difference in vpl.light_gbuffer.albedo: mip 0 {sharp:.4}, mip 6 {blurred:.4}");
    assert!(sharp > 0.1, "the checker must show at mip 0: {sharp}");
    assert!(blurred < 0.2 * sharp, "mip 6 must average the checker away: {blurred} vs {sharp}");
}
