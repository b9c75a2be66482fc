//! Knecht 002's multiple bounces (§3.6.1, issue #5): the bounce selection and the IRSM
//! baseline on the GPU against their CPU twins in `gi_render::cpu::knecht`.

use gi_lab_tests::knecht_support::{Rng, knecht_settings, read, read_buffer};
use gi_lab_tests::{default_scene, gpu};
use gi_render::cpu::knecht::{self, ISM_EMPTY};
use gi_render::cpu::knecht_bounce;
use gi_render::passes::knecht::ism::{IsmPass, IsmSettings};
use gi_render::scene::upload::GpuScene;
use gi_render::{GpuContext, Renderer};
use glam::Vec3;

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

    fn sample(&self, j: usize) -> knecht_bounce::BounceSample {
        let (position, normal) = self.world(j);
        let surf = self.ism.cloud.surfaces[j];
        knecht_bounce::BounceSample {
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

/// The bounce selection of Knecht 002 §3.6.1 on the GPU (`knecht/vpl/bounce.wgsl`) against its CPU
/// twin: seven VPLs on the default scene's surfaces (one slot empty, some glossy), the point
/// cloud splatted into their ISMs, then bounce 2's VPLs read back. For every source VPL the
/// CPU lights its samples (Eq. 4.7–4.8 times the test against the GPU's splatted map, or the
/// gather's test on its pulled map, `cpu::knecht::ism_visible`), picks
/// the arg-max (strongest) or the exponential race's winner (proportional), and builds the
/// new VPL; the GPU's must be the same sample with the same flux.
#[test]
fn bounce_selection_on_the_gpu_picks_the_cpu_arg_max() {
    use gi_render::cpu::knecht_bounce::Selection;
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
                        &knecht::IsmTest {
                            size: l.size,
                            eye_offset,
                            bias: s.depth_bias,
                            normal_offset: s.normal_offset,
                        },
                        (src.position, src.normal),
                        (bs.surface.position, bs.surface.normal),
                    ),
                };
                let (flux, c) = knecht_bounce::bounce_incident(&src, &bs, per_vpl, d_min, visible);
                let (_, c_unseen) = knecht_bounce::bounce_incident(&src, &bs, per_vpl, d_min, true);
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
            let Some((j, sum)) = knecht_bounce::select_bounce(&contributions, sel) else {
                assert_eq!(got.position.w, 0.0, "{selection:?}: VPL {i} lights no sample");
                continue;
            };
            lit += 1;
            let (bs, flux, c) = samples[((j - i as u32) / n) as usize];
            let want = knecht_bounce::bounce_vpl(&src, &bs, flux, c, sum);
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
/// texels, and each new VPL is the texel `cpu::knecht_bounce::irsm_pick` draws from those CDFs,
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
                knecht_bounce::bounce_incident(&src, &fx.sample(o as usize - 1), fx.per_vpl(i), d_min, true).1
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
        let (i, t) = knecht_bounce::irsm_pick(&totals, &cdfs, k, seed_gpu).expect("the IRSMs are lit");
        sources.insert(i);
        let j = owner_of(i, t) as usize - 1;
        let (src, bs) = (fx.source(i), fx.sample(j));
        let (flux, c) = knecht_bounce::bounce_incident(&src, &bs, fx.per_vpl(i), d_min, true);
        let want = knecht_bounce::bounce_vpl(&src, &bs, flux, c, grand / (n as f32 * coverage[j] as f32));
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
    scene.textures.push(gi_lab_tests::checker_texture(64, 1, 0));
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
