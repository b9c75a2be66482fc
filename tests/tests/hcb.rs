//! The hierarchical coherence buffer (Nguyen et al., issue #6): the GPU levels, masks and
//! samples against the CPU reference `gi_render::cpu::hcb` on synthetic G-buffers — a plane
//! facing the camera, a 90° corner, a step between parallel planes (the pose test), random
//! normals — and on the default scene's G-buffer at 128²; the gather at the samples and the
//! splatted light in the renderer (the splat's weights: `tests/hcb_splat.rs`).

use gi_lab_tests::{default_renderer, gpu, hcb_gbuffer as gbuffer, upload_rgba32f as upload};
use gi_render::GpuContext;
use gi_render::cpu::hcb::{self, Level, Sample, Thresholds};
use gi_render::passes::hcb::{GpuHcbSample, HcbFrame, HcbPass};
use glam::Vec3;

const EYE: Vec3 = Vec3::ZERO;
const PIXEL_SCALE: f32 = 0.01;

/// One G-buffer to build an HCB from.
struct Case<'a> {
    w: u32,
    h: u32,
    pos: &'a [[f32; 4]],
    nrm: &'a [[f32; 4]],
    levels: u32,
    frame: HcbFrame,
    /// The cache's incomplete texels (§5.2): the base is then the supplementary G-buffer.
    incomplete: Option<Vec<bool>>,
}

/// Runs the GPU HCB on a G-buffer; returns its levels, masks, sample list (sorted) and the
/// sample buffer.
fn gpu_hcb(ctx: &GpuContext, c: &Case) -> (Vec<Level>, Vec<Vec<bool>>, Vec<Sample>, Vec<f32>) {
    let (w, h) = (c.w, c.h);
    let (p, n) = (upload(ctx, "test.position", w, h, c.pos), upload(ctx, "test.normal", w, h, c.nrm));
    let pass = HcbPass::new(ctx, w, h, c.levels);
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.hcb") });
    let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
    match &c.incomplete {
        None => {
            pass.run(gi_render::timing::PassRec { ctx, enc: &mut enc, slot: None }, &view(&p), &view(&n), c.frame, None)
        }
        Some(inc) => {
            // The cached samples' splat: Σw 0 on the incomplete texels, 1 elsewhere.
            let weights: Vec<[f32; 4]> = inc.iter().map(|&i| [0.0, 0.0, 0.0, if i { 0.0 } else { 1.0 }]).collect();
            let ws = upload(ctx, "test.weight_sum", w, h, &weights);
            let mark = |label| {
                gi_render::passes::create_target(
                    &ctx.device,
                    label,
                    w,
                    h,
                    wgpu::TextureFormat::R32Float,
                    wgpu::TextureUsages::STORAGE_BINDING,
                )
            };
            let (i, m, g) = (mark("test.incomplete"), mark("test.cache"), mark("test.group"));
            let (wv, iv, mv, gv) = (view(&ws), view(&i), view(&m), view(&g));
            let io = gi_render::passes::hcb::CacheViews {
                weight_sum: &wv,
                incomplete: &iv,
                cache: &mv,
                recompute_group: &gv,
            };
            pass.run(
                gi_render::timing::PassRec { ctx, enc: &mut enc, slot: None },
                &view(&p),
                &view(&n),
                c.frame,
                Some(io),
            );
            ctx.queue.submit([enc.finish()]);
            enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.hcb") });
            let got = gi_render::buffers::read_texture(ctx, "hcb", &i, 0, 0).expect("read");
            let want: Vec<f32> = inc.iter().zip(c.nrm).map(|(&i, n)| if i && n[3] > 0.5 { 1.0 } else { 0.0 }).collect();
            assert_eq!(got.data.iter().map(|v| v[0]).collect::<Vec<_>>(), want, "hcb.incomplete");
        }
    }
    ctx.queue.submit([enc.finish()]);
    let read = |t: &wgpu::Texture| gi_render::buffers::read_texture(ctx, "hcb", t, 0, 0).expect("read");
    let mut out = Vec::new();
    let mut masks = Vec::new();
    for l in &pass.levels {
        let (pp, nn, mm) = (read(&l.position), read(&l.normal), read(&l.mask));
        let texels = pp
            .data
            .iter()
            .zip(&nn.data)
            .map(|(p, n)| hcb::HcbTexel {
                position: Vec3::new(p[0], p[1], p[2]),
                distance: p[3],
                normal: Vec3::new(n[0], n[1], n[2]),
                coherence: n[3],
            })
            .collect();
        out.push(Level { width: l.width, height: l.height, texels });
        masks.push(mm.data.iter().map(|m| m[0] > 0.5).collect());
    }
    let count: Vec<u32> = bytemuck::pod_collect_to_vec(
        &gi_render::buffers::read_storage(ctx, &pass.counter, gi_render::passes::hcb::COUNTER_BYTES).expect("count"),
    );
    let size = std::mem::size_of::<GpuHcbSample>() as u64;
    let list: Vec<GpuHcbSample> = bytemuck::pod_collect_to_vec(
        &gi_render::buffers::read_storage(ctx, &pass.list, size * count[0] as u64).expect("list"),
    );
    // Each listed sample carries its level texel's position, radius and normal.
    for s in &list {
        let l = &out[s.level() as usize];
        let t = l.at(s.texel[0] as i64, s.texel[1] as i64).expect("the sample's texel");
        let got = (s.position.truncate(), s.position.w, s.normal.truncate(), s.normal.w);
        assert_eq!(got, (t.position, t.distance, t.normal, t.coherence), "{s:?}");
    }
    let mut samples: Vec<Sample> =
        list.iter().map(|s| Sample { level: s.level(), x: s.texel[0], y: s.texel[1] }).collect();
    samples.sort();
    let buffer = read(&pass.samples).data.iter().map(|v| v[0]).collect();
    (out, masks, samples, buffer)
}

/// GPU against CPU for one G-buffer; returns the CPU's levels and samples for further checks.
fn check(name: &str, c: Case) -> (Vec<Level>, Vec<Sample>) {
    let (w, h, f) = (c.w, c.h, c.frame);
    let ctx = gpu();
    let mut base = hcb::base_level(c.pos, c.nrm, w, h, f.eye, f.pixel_scale, f.footprint_min_cos);
    if let Some(inc) = &c.incomplete {
        base = hcb::supplementary_base(base, inc);
    }
    let cpu = hcb::build(base, c.levels, f.thresholds);
    let cpu_masks = hcb::masks(&cpu);
    let mut cpu_samples = hcb::samples(&cpu, &cpu_masks);
    cpu_samples.sort();
    let (got, got_masks, got_samples, buffer) = gpu_hcb(&ctx, &c);
    for (k, (g, c)) in got.iter().zip(&cpu).enumerate() {
        assert_eq!((g.width, g.height), (c.width, c.height), "{name}: level {k} size");
        for (i, (a, b)) in g.texels.iter().zip(&c.texels).enumerate() {
            let at = (i as u32 % c.width, i as u32 / c.width);
            assert!(
                (a.coherence - b.coherence).abs() <= 1e-5,
                "{name}: level {k} {at:?} n^w GPU {} CPU {}",
                a.coherence,
                b.coherence
            );
            assert!(
                (a.distance - b.distance).abs() <= 1e-5 * b.distance.abs().max(1.0),
                "{name}: level {k} {at:?} a^w GPU {} CPU {}",
                a.distance,
                b.distance
            );
            if b.coherence != 0.0 {
                assert!(
                    (a.position - b.position).length() <= 1e-5 && (a.normal - b.normal).length() <= 1e-5,
                    "{name}: level {k} {at:?}"
                );
            }
        }
    }
    assert_eq!(got_masks[..cpu.len() - 1], cpu_masks[..cpu.len() - 1], "{name}: masks");
    assert_eq!(got_samples, cpu_samples, "{name}: samples");
    // The sample buffer marks exactly the samples' pixels with their level + 1.
    let mut expect = vec![0.0f32; (w * h) as usize];
    for s in &cpu_samples {
        expect[((s.y << s.level) * w + (s.x << s.level)) as usize] = (s.level + 1) as f32;
    }
    assert_eq!(buffer, expect, "{name}: sample buffer");
    (cpu, cpu_samples)
}

const T: Thresholds = Thresholds { cos_theta_max: 0.9, cos_gamma_max: 0.3, d_max: 10.0, spread_incomplete: false };

/// A synthetic case seen from the origin with thresholds `T`.
fn case<'a>(w: u32, h: u32, pos: &'a [[f32; 4]], nrm: &'a [[f32; 4]], levels: u32) -> Case<'a> {
    Case { w, h, pos, nrm, levels, frame: HcbFrame::new(T, EYE, PIXEL_SCALE), incomplete: None }
}

/// The point the pixel's ray (pinhole at the origin looking down −z) hits on the plane
/// through `q` with normal `n`.
fn on_plane(x: u32, y: u32, w: u32, h: u32, q: Vec3, n: Vec3) -> Vec3 {
    let d = Vec3::new(
        (x as f32 + 0.5 - w as f32 / 2.0) * PIXEL_SCALE,
        (h as f32 / 2.0 - y as f32 - 0.5) * PIXEL_SCALE,
        -1.0,
    );
    d * (q.dot(n) / d.dot(n))
}

#[test]
fn a_plane_facing_the_camera_is_coherent_up_to_the_top() {
    let (w, h) = (37, 29);
    let (pos, nrm) = gbuffer(w, h, |x, y| Some((on_plane(x, y, w, h, Vec3::new(0.0, 0.0, -3.0), Vec3::Z), Vec3::Z)));
    let (levels, samples) = check("plane", case(w, h, &pos, &nrm, 4));
    let top = levels.last().expect("top");
    assert!(top.texels.iter().any(|t| t.coherence == 1.0), "the top level has coherent texels");
    // Only the one-pixel ring at the image border (whose blocks reach outside) needs level-0
    // samples; a few samples of levels 2–3 stand for the whole inside.
    for s in samples.iter().filter(|s| s.level == 0) {
        assert!(s.x == 0 || s.y == 0 || s.x == w - 1 || s.y == h - 1, "level-0 sample inside the plane: {s:?}");
    }
    let above = samples.iter().filter(|s| s.level > 0).count();
    assert!(above > 0 && above <= 20, "{above} samples above level 0: {samples:?}");
}

#[test]
fn a_90_degree_corner_is_incoherent_across_the_crease() {
    let (w, h) = (37, 29);
    // A side wall (x = −0.015, normal +x) meets the back wall (z = −3, normal +z) at the
    // line that projects between columns 17 and 18.
    let crease = 18;
    let corner = Vec3::new(-0.015, 0.0, -3.0);
    let (pos, nrm) = gbuffer(w, h, |x, y| {
        Some(if x < crease {
            (on_plane(x, y, w, h, corner, Vec3::X), Vec3::X)
        } else {
            (on_plane(x, y, w, h, corner, Vec3::Z), Vec3::Z)
        })
    });
    let (levels, _) = check("corner", case(w, h, &pos, &nrm, 4));
    // No level-1 block straddling the crease is coherent.
    let l1 = &levels[1];
    for y in 0..l1.height {
        for x in 0..l1.width {
            let straddles = (2 * x).saturating_sub(1) < crease && 2 * x + 1 >= crease;
            if straddles {
                assert_eq!(l1.at(x as i64, y as i64).expect("t").coherence, 0.0, "({x}, {y})");
            }
        }
    }
}

#[test]
fn a_step_between_parallel_planes_is_rejected_by_the_pose_test() {
    let (w, h) = (37, 29);
    let step = 19;
    let (pos, nrm) = gbuffer(w, h, |x, y| {
        let z = if x < step { -3.0 } else { -3.6 };
        Some((on_plane(x, y, w, h, Vec3::new(0.0, 0.0, z), Vec3::Z), Vec3::Z))
    });
    let (levels, _) = check("step", case(w, h, &pos, &nrm, 4));
    let l1 = &levels[1];
    let (mut across, mut beside) = (0, 0);
    for y in 1..l1.height - 1 {
        for x in 1..l1.width - 1 {
            let c = l1.at(x as i64, y as i64).expect("t").coherence;
            if 2 * x - 1 < step && 2 * x + 1 >= step {
                assert_eq!(c, 0.0, "a block across the step at ({x}, {y}) is coherent");
                across += 1;
            } else if c > 0.0 {
                beside += 1;
            }
        }
    }
    assert!(across > 0 && beside > 0, "across {across}, coherent beside {beside}");
}

#[test]
fn random_normals_are_not_coherent() {
    let (w, h) = (33, 33);
    let mut s = 12345u32;
    let mut next = move || {
        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (s >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
    };
    let normals: Vec<Vec3> = (0..w * h).map(|_| Vec3::new(next(), next(), next().abs() + 0.2).normalize()).collect();
    let (pos, nrm) = gbuffer(w, h, |x, y| {
        Some((on_plane(x, y, w, h, Vec3::new(0.0, 0.0, -3.0), Vec3::Z), normals[(y * w + x) as usize]))
    });
    let (levels, samples) = check("random normals", case(w, h, &pos, &nrm, 3));
    assert!(levels[1].texels.iter().all(|t| t.coherence == 0.0));
    assert_eq!(samples.len(), (w * h) as usize, "every pixel is its own sample");
}

#[test]
fn the_default_scene_at_128_matches_the_cpu() {
    let mut r = default_renderer(128, 128);
    r.render_frame();
    let pos = r.readback("gbuffer.position").expect("position").data;
    let nrm = r.readback("gbuffer.normal").expect("normal").data;
    let pixel_scale = 2.0 * (r.camera.yfov * 0.5).tan() / 128.0;
    let t = Thresholds {
        cos_theta_max: 20f32.to_radians().cos(),
        cos_gamma_max: 70f32.to_radians().cos(),
        d_max: 0.5,
        spread_incomplete: false,
    };
    let frame = HcbFrame::new(t, r.camera.position, pixel_scale);
    let (levels, samples) =
        check("default scene", Case { w: 128, h: 128, pos: &pos, nrm: &nrm, levels: 6, frame, incomplete: None });
    let per_level: Vec<usize> =
        (0..levels.len()).map(|k| samples.iter().filter(|s| s.level == k as u32).count()).collect();
    println!(
        "default scene 128², θmax 20°, γmax 70°, dmax 0.5: samples per level {per_level:?}, {} of {} pixels",
        samples.len(),
        128 * 128
    );
    assert!(per_level[1..].iter().sum::<usize>() > 0, "samples above level 0: {per_level:?}");
}

/// §5.2 on the GPU against the CPU: the supplementary G-buffer of the default scene at 128²
/// with a blob of incomplete texels (a disc, and a band along the sphere), built with both
/// sign rules — Fig. 7c keeps new samples on the incomplete texels, Fig. 7d lets them out.
#[test]
fn the_supplementary_g_buffer_matches_the_cpu_in_both_variants() {
    let mut r = default_renderer(128, 128);
    r.render_frame();
    let pos = r.readback("gbuffer.position").expect("position").data;
    let nrm = r.readback("gbuffer.normal").expect("normal").data;
    let pixel_scale = 2.0 * (r.camera.yfov * 0.5).tan() / 128.0;
    let incomplete: Vec<bool> = (0..128 * 128)
        .map(|i| {
            let (x, y) = ((i % 128) as f32, (i / 128) as f32);
            (x - 40.0).hypot(y - 70.0) < 14.0 || (90.0..100.0).contains(&x)
        })
        .collect();
    let mut counts = Vec::new();
    for spread in [false, true] {
        let t = Thresholds {
            cos_theta_max: 20f32.to_radians().cos(),
            cos_gamma_max: 70f32.to_radians().cos(),
            d_max: 0.5,
            spread_incomplete: spread,
        };
        let frame = HcbFrame { incomplete_weight: 0.5, ..HcbFrame::new(t, r.camera.position, pixel_scale) };
        let c = Case { w: 128, h: 128, pos: &pos, nrm: &nrm, levels: 6, frame, incomplete: Some(incomplete.clone()) };
        let (_, samples) = check(if spread { "Fig. 7d" } else { "Fig. 7c" }, c);
        assert!(!samples.is_empty());
        let outside =
            samples.iter().filter(|s| !incomplete[((s.y << s.level) * 128 + (s.x << s.level)) as usize]).count();
        if spread {
            assert!(outside > 0, "Fig. 7d places some samples beside the incomplete texels");
        } else {
            assert_eq!(outside, 0, "Fig. 7c places samples on incomplete texels only");
        }
        counts.push(samples.len());
    }
    println!("new samples on the supplementary G-buffer: Fig. 7c {}, Fig. 7d {}", counts[0], counts[1]);
}

/// The gather at the samples runs a workgroup per sample on a GPU (its 64 invocations over
/// every 64th VPL, summed in shared memory) and an invocation per sample on a CPU renderer:
/// both give the same light to float rounding, per frame and with the cache.
#[test]
fn the_gather_per_workgroup_equals_the_gather_per_invocation() {
    for cached in [false, true] {
        let run = |wide: bool| {
            let mut r = hcb_renderer(96, |s| {
                s.vpl.count = 256;
                if cached {
                    s.pipeline.temporal = gi_render::settings::pipeline::Temporal::HcbSampleCache;
                }
            });
            r.hcb_mut().expect("the HCB runs").gather.wide = wide;
            for _ in 0..3 {
                r.render_frame();
            }
            gi_lab_tests::read(&r, "hcb.indirect").data
        };
        let (serial, wide) = (run(false), run(true));
        let lit = serial.iter().filter(|p| p[0] + p[1] + p[2] > 1e-4).count();
        assert!(lit > 4000, "{lit} pixels lit");
        let worst = gi_lab_tests::max_relative_difference(&serial, &wide);
        assert!(worst <= 1e-4, "cache {cached}: relative difference {worst}");
    }
}

/// The `nguyen-hcb` preset on the default scene at `size`², paused, with `edit`.
fn hcb_renderer(size: u32, edit: impl FnOnce(&mut gi_render::LabSettings)) -> gi_render::Renderer {
    let loaded =
        gi_render::preset::load_lenient(include_str!("../../presets/nguyen-hcb.ron"), "nguyen-hcb").expect("loads");
    let mut s = loaded.settings;
    edit(&mut s);
    let mut r = gi_render::Renderer::new(gpu(), gi_lab_tests::default_scene(), s, size, size).expect("renderer");
    r.clock.playing = false;
    r
}

#[test]
fn hcb_splatting_stays_close_to_gathering_at_every_pixel_with_few_samples() {
    use gi_render::image_io::hdr_display;
    let image = |levels: u32| {
        let mut r = hcb_renderer(256, |s| s.hcb.levels = levels);
        r.render_frame();
        let stats = r.hcb_stats().expect("HCB statistics");
        (r.readback("final.hdr").expect("final"), stats)
    };
    let (hcb, stats) = image(gi_render::LabSettings::default().hcb.levels);
    let (per_pixel, per_pixel_stats) = image(1);
    let covered = per_pixel_stats.samples();
    let flip = gi_render::metrics::flip(&hdr_display(&hcb), &hdr_display(&per_pixel)).expect("flip").0;
    println!(
        "HCB vs per-pixel gather, same 1024 VPLs, 256²: FLIP {flip:.4}; samples {} of {covered} covered pixels ({:.2} %), per level {:?}, uncovered {}",
        stats.samples(),
        100.0 * stats.samples() as f64 / covered as f64,
        stats.samples_per_level,
        stats.uncovered
    );
    // Levels = 1 makes every covered pixel a sample: the per-pixel gather.
    assert_eq!(per_pixel_stats.samples_per_level.len(), 1);
    assert_eq!(per_pixel_stats.uncovered, 0);
    // Measured on lavapipe with the scene-relative d_max (0.17 here, 0.1 × the bounding
    // radius): FLIP 0.022 with 10.0 % of the pixels as samples at 256² (the crease and
    // silhouette pixels are level-0 samples, a larger share at low resolution; 4.1 % at 512²).
    // 0.03 is issue #15's goal for this comparison.
    assert!(flip <= 0.03, "HCB vs per-pixel gather: FLIP {flip}");
    assert!(stats.samples() * 100 <= 11 * covered, "{} samples of {covered}", stats.samples());
    assert!(stats.uncovered * 1000 <= covered, "{} covered pixels no sample reached", stats.uncovered);
}

/// The GPU lists the covered pixels no sample reached: exactly the pixels with geometry whose
/// `hcb.irradiance` has a = 0 (what the overlay draws instead of reading two whole images).
#[test]
fn the_uncovered_pixels_are_listed_on_the_gpu() {
    // At 256² the default box has a pixel no sample reaches (`gi-lab hcb-stats`).
    let mut r = hcb_renderer(256, |_| {});
    r.render_frame();
    let stats = r.hcb_stats().expect("HCB statistics");
    let (light, normal) = (r.readback("hcb.irradiance").expect("light"), r.readback("gbuffer.normal").expect("normal"));
    let mut want: Vec<[u32; 2]> = (0..light.data.len())
        .filter(|&i| light.data[i][3] == 0.0 && normal.data[i][3] > 0.5)
        .map(|i| [i as u32 % light.width, i as u32 / light.width])
        .collect();
    let mut got = stats.uncovered_pixels.clone();
    want.sort();
    got.sort();
    assert!(stats.uncovered > 0, "no uncovered pixel to list");
    assert_eq!(stats.uncovered as usize, want.len());
    assert_eq!(got, want);
}

#[test]
fn hcb_samples_are_at_most_five_percent_of_the_pixels_at_512() {
    let mut r = hcb_renderer(512, |_| {});
    r.render_frame();
    let stats = r.hcb_stats().expect("HCB statistics");
    let pixels = 512 * 512;
    let share = 100.0 * stats.samples() as f64 / pixels as f64;
    println!(
        "default scene 512², nguyen-hcb: {} samples ({share:.2} % of the pixels), per level {:?}",
        stats.samples(),
        stats.samples_per_level
    );
    // The overlay's dots: every listed sample sits on its pixel of the sample buffer.
    let buffer = r.readback("hcb.samples").expect("hcb.samples");
    assert_eq!(stats.samples.len() as u32, stats.samples());
    for &[x, y, level] in &stats.samples {
        assert_eq!(buffer.data[(y * 512 + x) as usize][0], (level + 1) as f32, "sample at ({x}, {y})");
    }
    assert_eq!(buffer.data.iter().filter(|p| p[0] > 0.0).count() as u32, stats.samples());
    assert!(
        stats.summary(pixels).starts_with(&format!("{} HCB samples ({share:.2} %", stats.samples())),
        "{}",
        stats.summary(pixels)
    );
    // Measured 4.09 %; the paper reports 1.9–4.4 % on its scenes.
    assert!(share <= 5.0, "{share} % of the pixels are samples");
    assert!(
        stats.samples_per_level.iter().skip(2).sum::<u32>() > 0,
        "samples above level 1: {:?}",
        stats.samples_per_level
    );
}

#[test]
fn hcb_on_the_hotel_room_stays_close_to_the_per_pixel_gather() {
    use gi_render::image_io::hdr_display;
    let opts = gi_render::scene::LoadOptions { unit_scale: 0.001, ..Default::default() };
    let path = gi_lab_tests::real_scene("hotel-room/hotel-room.glb");
    let scene = gi_render::scene::load_gltf_file(&path, &opts).expect("the hotel room loads");
    let loaded =
        gi_render::preset::load_lenient(include_str!("../../presets/nguyen-hcb.ron"), "nguyen-hcb").expect("loads");
    let size = 512;
    let image = |levels: u32, size: u32| {
        let mut s = loaded.settings.clone();
        s.hcb.levels = levels;
        let mut r = gi_render::Renderer::new(gpu(), scene.clone(), s, size, size).expect("renderer");
        r.clock.playing = false;
        // Inside the closed room (the default camera frames it from outside): from near one
        // corner at eye height toward the opposite one.
        let b = r.bounds();
        let e = b.extent();
        let eye = b.min + Vec3::new(0.2 * e.x, 0.45 * e.y, 0.2 * e.z);
        let target = b.min + Vec3::new(0.8 * e.x, 0.35 * e.y, 0.8 * e.z);
        r.camera = gi_render::camera::Camera::look_at(eye, target, 60f32.to_radians(), b);
        r.render_frame();
        (r.readback("final.hdr").expect("final"), r.hcb_stats().expect("stats"))
    };
    let (hcb, stats) = image(loaded.settings.hcb.levels, size);
    let (per_pixel, all) = image(1, size);
    let covered = all.samples();
    let flip = gi_render::metrics::flip(&hdr_display(&hcb), &hdr_display(&per_pixel)).expect("flip").0;
    let share = 100.0 * stats.samples() as f64 / (size * size) as f64;
    println!(
        "hotel room {size}²: FLIP HCB vs per-pixel {flip:.4}; samples {} ({share:.2} % of the pixels, {covered} covered), per level {:?}, uncovered {}",
        stats.samples(),
        stats.samples_per_level,
        stats.uncovered
    );
    assert!(covered > size * size / 2, "the room fills the view: {covered}");
    // Measured on lavapipe at 512² with the scene-relative d_max (0.61 m here) and 1024 VPLs:
    // FLIP 0.0268 with 6.00 % of the pixels as samples (3.24 % at 1024²). The room's
    // furniture has many creases, whose pixels are level-0 samples: the share falls with the
    // resolution, and the 5 % is met at the paper's 1024² below.
    assert!(flip <= 0.04, "HCB vs per-pixel gather on the hotel room: FLIP {flip}");
    assert!(share <= 6.5, "{share} % of the pixels are samples");
    // At the paper's resolution (Table 1: 1024²) the crease bands are half as wide
    // relative to the image.
    let (_, big) = image(loaded.settings.hcb.levels, 1024);
    let big_share = 100.0 * big.samples() as f64 / (1024.0 * 1024.0);
    println!(
        "hotel room 1024²: {} samples ({big_share:.2} % of the pixels), per level {:?}",
        big.samples(),
        big.samples_per_level
    );
    assert!(big_share <= 5.0, "{big_share} % of the pixels are samples at 1024²");
}

/// §6, Fig. 9: the samples depend on the geometry alone, so a second light changes none of
/// them, and the splatted light of both stays as close to the per-pixel gather as one.
#[test]
fn a_second_light_leaves_the_samples_unchanged_and_the_splatting_close_to_the_per_pixel_gather() {
    use gi_render::image_io::hdr_display;
    use gi_render::scene::{Light, LightKind, Node, Transform};
    let two_lights = || {
        let mut scene = gi_lab_tests::default_scene();
        scene.lights.push(Light {
            name: "warm point".into(),
            kind: LightKind::Point,
            color: Vec3::new(1.0, 0.7, 0.4),
            intensity: 1.5,
            range: None,
        });
        scene.nodes.push(Node {
            name: "warm point".into(),
            transform: Transform { translation: Vec3::new(0.55, 0.5, 0.4), ..Transform::default() },
            children: vec![],
            mesh: None,
            light: Some(scene.lights.len() - 1),
            camera: None,
        });
        scene.roots.push(scene.nodes.len() - 1);
        scene
    };
    let run = |scene: gi_render::scene::Scene, levels: u32| {
        let loaded =
            gi_render::preset::load_lenient(include_str!("../../presets/nguyen-hcb.ron"), "nguyen-hcb").expect("loads");
        let mut s = loaded.settings;
        s.hcb.levels = levels;
        let mut r = gi_render::Renderer::new(gpu(), scene, s, 192, 192).expect("renderer");
        r.clock.playing = false;
        r.render_frame();
        let stats = r.hcb_stats().expect("HCB statistics");
        let indirect = r.readback("hcb.indirect").expect("indirect").data;
        let mean = indirect.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / indirect.len() as f32;
        (r.readback("final.hdr").expect("final"), stats, mean)
    };
    let levels = gi_render::LabSettings::default().hcb.levels;
    let (_, one, one_mean) = run(gi_lab_tests::default_scene(), levels);
    let (hcb, two, two_mean) = run(two_lights(), levels);
    let (per_pixel, _, _) = run(two_lights(), 1);
    let flip = gi_render::metrics::flip(&hdr_display(&hcb), &hdr_display(&per_pixel)).expect("flip").0;
    println!(
        "two lights, 192²: {} samples (one light: {}), indirect mean {two_mean:.4} (one light {one_mean:.4}), FLIP HCB vs per-pixel {flip:.4}",
        two.samples(),
        one.samples()
    );
    let mut a = one.samples.clone();
    let mut b = two.samples.clone();
    a.sort();
    b.sort();
    assert_eq!(a, b, "the samples depend on the geometry alone");
    assert!(two_mean > 1.1 * one_mean, "the second light adds indirect light: {one_mean} -> {two_mean}");
    // Measured 0.037 (one light at 256²: 0.040).
    assert!(flip <= 0.05, "two lights, HCB vs per-pixel gather: FLIP {flip}");
}

/// Issue #51: Eq. 11's pixels reflect the splatted irradiance with the glossy receiver — the
/// GPU's `hcb.indirect` equals the CPU twin on the chair (whose wood and metal are glossy),
/// and the paper's diffuse receiver is c·DI/π·E.
#[test]
fn the_glossy_receiver_of_the_hcb_matches_the_cpu_twin_on_the_chair() {
    let settings = |receiver| {
        let mut s = gi_render::preset::load_lenient(include_str!("../../presets/nguyen-hcb.ron"), "nguyen-hcb")
            .expect("loads")
            .settings;
        s.hcb.receiver = receiver;
        s
    };
    use gi_render::settings::splat::IrradianceReceiver;
    let scene = gi_lab_tests::test_scene("chair-behind.glb");
    let mut r = gi_render::Renderer::new(gpu(), scene, settings(IrradianceReceiver::Glossy), 64, 64).expect("renderer");
    r.clock.playing = false;
    r.render_frame();
    let (compared, glossy) = gi_lab_tests::assert_glossy_receiver_matches_the_cpu(
        &r,
        "hcb.indirect",
        "hcb.irradiance",
        "hcb.weight_sum",
        "hcb.weight_sum.direction",
    );
    assert!(compared > 1500 && glossy > 100, "{compared} pixels compared, {glossy} with specular light");
    // The samples' directions are at most as long as their irradiance's luminance.
    let stats = r.hcb_stats().expect("stats");
    for s in &stats.list {
        let lum = Vec3::new(s.light.x, s.light.y, s.light.z).dot(Vec3::new(0.2126, 0.7152, 0.0722));
        assert!(s.dir.truncate().length() <= lum * 1.0001 + 1e-9, "{s:?}");
    }
    r.set_settings(settings(IrradianceReceiver::DiffuseOnly)).expect("valid");
    r.render_frame();
    let (ind, irr, alb) = (
        gi_lab_tests::read(&r, "hcb.indirect"),
        gi_lab_tests::read(&r, "hcb.irradiance"),
        gi_lab_tests::read(&r, "gbuffer.albedo"),
    );
    for ((i, e), c) in ind.data.iter().zip(&irr.data).zip(&alb.data) {
        for k in 0..3 {
            let want = c[k] * c[3] / std::f32::consts::PI * e[k];
            assert!((i[k] - want).abs() <= 1e-5 * want.abs().max(1e-3), "{i:?} vs c·DI/π·E {want}");
        }
    }
}

/// A 1920×1080 frame of the HCB's cached preset fits the device's storage bindings: a list of
/// every pixel's sample (2.07 M × 80 bytes) is more than lavapipe binds (128 MiB), and the
/// lists made for it panicked at this size there. The lists hold what the device allows
/// (`hcb::list_capacity`), and the frame lights the image.
#[test]
fn an_hcb_frame_at_1080p_fits_the_devices_storage_bindings() {
    let (w, h) = (1920u32, 1080u32);
    let ctx = gpu();
    let limits = ctx.device.limits();
    let capacity = gi_render::passes::hcb::list_capacity(&ctx.device, w, h) as u64;
    let bytes = capacity * std::mem::size_of::<GpuHcbSample>() as u64;
    assert!(bytes <= limits.max_storage_buffer_binding_size, "{bytes} bytes for {capacity} samples");
    assert!(capacity >= (w * h) as u64 / 2, "{capacity} samples");
    let mut s = gi_render::LabSettings::default();
    gi_render::settings::pipeline::Technique::NguyenCached.apply(&mut s);
    let mut r = gi_render::Renderer::new(ctx, gi_lab_tests::default_scene(), s, w, h).expect("renderer");
    r.clock.playing = false;
    r.render_frame();
    let indirect = r.readback("hcb.indirect").expect("hcb.indirect");
    let lit = indirect.data.iter().filter(|p| p[0] > 0.0).count();
    assert!(lit > indirect.data.len() / 2, "{lit} of {} pixels lit", indirect.data.len());
}
