//! The HCB's coherence-weighted splatting (Nguyen et al. §4.2–4.3, Eq. 8–11) on the GPU:
//! the weights of both splat methods (the paper's blended quads and GI Lab's binned sums)
//! against the CPU reference `gi_render::cpu::hcb::weight`, a constant light reproduced
//! wherever a sample reaches, and the two methods equal bit for bit.

use gi_lab_tests::{gpu, hcb_gbuffer as gbuffer, upload_rgba32f as upload};
use gi_render::cpu::hcb::{self, Thresholds};
use gi_render::passes::bins::SplatMethod;
use gi_render::passes::hcb::{GpuHcbSample, HcbFrame};
use glam::Vec3;

/// A perspective camera at the origin looking down −z (60° vertical field of view) and the
/// G-buffer of a bumpy surface around z = −3 with tilted normals seen through it.
fn splat_scene(w: u32, h: u32) -> (gi_render::passes::CameraUniform, Vec<[f32; 4]>, Vec<[f32; 4]>, f32) {
    use glam::{Mat4, Vec4};
    let yfov = 60f32.to_radians();
    let proj = glam::camera::rh::proj::directx::perspective(yfov, w as f32 / h as f32, 0.1, 100.0);
    let view = Mat4::IDENTITY;
    let vp = proj * view;
    let camera = gi_render::passes::CameraUniform {
        view_proj: vp,
        prev_view_proj: vp,
        inv_view_proj: vp.inverse(),
        view,
        position: Vec4::new(0.0, 0.0, 0.0, 1.0),
        viewport: Vec4::new(w as f32, h as f32, 1.0 / w as f32, 1.0 / h as f32),
        params: Vec4::new(0.1, 100.0, 0.0, 0.0),
        lod: Vec4::new(-1.0, 0.0, 0.0, 0.0),
    };
    let pixel_scale = 2.0 * (yfov * 0.5).tan() / h as f32;
    let (pos, nrm) = gbuffer(w, h, |x, y| {
        if (x * 7 + y * 3) % 23 == 0 {
            return None; // background holes
        }
        let ndc = glam::Vec2::new((x as f32 + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h as f32 * 2.0);
        let far = vp.inverse().project_point3(ndc.extend(1.0));
        let dir = far.normalize();
        let z = -3.0 - 0.3 * (x as f32 * 0.31).sin() * (y as f32 * 0.17).cos();
        let p = dir * (z / dir.z);
        let n = Vec3::new(0.25 * (x as f32 * 0.21).cos(), 0.2 * (y as f32 * 0.13).sin(), 1.0).normalize();
        Some((p, n))
    });
    (camera, pos, nrm, pixel_scale)
}

/// The splat scene at 48×36 and its frame with the thresholds θ_max, γ_max (as cosines).
fn splat_case(cos_theta_max: f32, cos_gamma_max: f32) -> (Scene, Thresholds, HcbFrame) {
    let (w, h) = (48, 36);
    let (camera, pos, nrm, pixel_scale) = splat_scene(w, h);
    let t = Thresholds { cos_theta_max, cos_gamma_max, d_max: 10.0, spread_incomplete: false };
    (Scene { w, h, camera, pos, nrm }, t, HcbFrame::new(t, Vec3::ZERO, pixel_scale))
}

/// A synthetic G-buffer and its camera.
struct Scene {
    w: u32,
    h: u32,
    camera: gi_render::passes::CameraUniform,
    pos: Vec<[f32; 4]>,
    nrm: Vec<[f32; 4]>,
}

/// What the splat wrote: `hcb.weight_sum`, `hcb.irradiance`, the uncovered count and
/// `hcb.weight_sum.direction`.
type Splatted = (Vec<[f32; 4]>, Vec<[f32; 4]>, u32, Vec<[f32; 4]>);

/// Splats `samples` over the G-buffer on the GPU by `method` (binned into at most `bins`
/// items, the rest drawn as quads); returns what it wrote.
#[allow(clippy::too_many_arguments)]
fn gpu_splat(
    w: u32,
    h: u32,
    pos: &[[f32; 4]],
    nrm: &[[f32; 4]],
    camera: &gi_render::passes::CameraUniform,
    samples: &[GpuHcbSample],
    frame: HcbFrame,
    (method, bins): (SplatMethod, u32),
) -> Splatted {
    use gi_render::passes::hcb::HcbSplatPass;
    use wgpu::util::DeviceExt;
    let ctx = gpu();
    let (p, n) = (upload(&ctx, "test.position", w, h, pos), upload(&ctx, "test.normal", w, h, nrm));
    let buf = |label, bytes: &[u8], usage| {
        ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents: bytes, usage })
    };
    let cam = buf("test.camera", bytemuck::bytes_of(camera), wgpu::BufferUsages::UNIFORM);
    let list = buf("test.samples", bytemuck::cast_slice(samples), wgpu::BufferUsages::STORAGE);
    let args = buf(
        "test.args",
        bytemuck::cast_slice(&[6u32, samples.len() as u32, 0, 0]),
        wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::STORAGE,
    );
    let counter = buf("test.counter", &[0u8; 32], wgpu::BufferUsages::STORAGE);
    let mut pass = HcbSplatPass::new(&ctx, w, h);
    pass.limit_bins(&ctx, bins);
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.splat") });
    let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
    let white = upload(&ctx, "test.albedo", w, h, &vec![[1.0; 4]; (w * h) as usize]);
    let black = upload(&ctx, "test.material", w, h, &vec![[0.0; 4]; (w * h) as usize]);
    let g = (&view(&p), &view(&n), &view(&white), &view(&black));
    pass.run(
        gi_render::timing::PassRec { ctx: &ctx, enc: &mut enc, slot: None },
        &cam,
        g,
        (&list, &counter),
        &args,
        (frame, method),
    );
    ctx.queue.submit([enc.finish()]);
    let read = |t: &wgpu::Texture| gi_render::buffers::read_texture(&ctx, "hcb", t, 0, 0).expect("read").data;
    let uncovered: Vec<u32> =
        bytemuck::pod_collect_to_vec(&gi_render::buffers::read_storage(&ctx, &pass.uncovered, 16).expect("count"));
    (read(pass.weight_sum()), read(&pass.irradiance), uncovered[0], read(pass.weight_dir()))
}

fn splat_samples(w: u32, pos: &[[f32; 4]], nrm: &[[f32; 4]], light: impl Fn(usize) -> Vec3) -> Vec<GpuHcbSample> {
    let picks = [
        (5u32, 4u32, 0.08f32),
        (20, 10, 0.35),
        (33, 25, 0.2),
        (12, 27, 0.5),
        (40, 6, 0.12),
        (26, 17, 1.2),
        (2, 30, 0.3),
    ];
    picks
        .iter()
        .enumerate()
        .filter_map(|(k, &(x, y, r))| {
            let i = (y * w + x) as usize;
            (nrm[i][3] > 0.5).then(|| GpuHcbSample {
                position: glam::Vec4::new(pos[i][0], pos[i][1], pos[i][2], r),
                normal: glam::Vec4::new(nrm[i][0], nrm[i][1], nrm[i][2], 1.0),
                texel: [x, y, 0, 0],
                light: light(k).extend(1.0),
                dir: glam::Vec4::ZERO,
            })
        })
        .collect()
}

#[test]
fn splat_weights_on_the_gpu_equal_eq_8_and_10_on_the_cpu() {
    for method in [SplatMethod::Blend, SplatMethod::Binned] {
        splat_weights_match_the_cpu(method);
    }
}

fn splat_weights_match_the_cpu(method: SplatMethod) {
    let (Scene { w, h, camera, pos, nrm }, t, frame) = splat_case(15f32.to_radians().cos(), 80f32.to_radians().cos());
    let samples = splat_samples(w, &pos, &nrm, |k| Vec3::new(1.0 + k as f32, 0.5, 2.0 - 0.2 * k as f32));
    assert!(samples.len() >= 6, "the picked pixels are covered");
    let (sum, light, uncovered, _) = gpu_splat(w, h, &pos, &nrm, &camera, &samples, frame, (method, w * h));
    let (mut reached, mut rejected) = (0, 0);
    let mut covered_unreached = 0;
    for i in 0..(w * h) as usize {
        if nrm[i][3] < 0.5 {
            assert_eq!(sum[i], [0.0; 4], "background pixel {i}");
            continue;
        }
        let (b, n_b) =
            (Vec3::new(pos[i][0], pos[i][1], pos[i][2]), Vec3::new(nrm[i][0], nrm[i][1], nrm[i][2]).normalize());
        let (mut ws, mut we) = (0.0f32, Vec3::ZERO);
        for s in &samples {
            let a = hcb::HcbTexel {
                position: s.position.truncate(),
                distance: s.position.w,
                normal: s.normal.truncate(),
                coherence: 1.0,
            };
            match hcb::weight(&a, b, n_b, t) {
                Some(wt) => {
                    ws += wt;
                    we += wt * s.light.truncate();
                    reached += 1;
                }
                None if (b - a.position).length() < a.distance => rejected += 1,
                None => {}
            }
        }
        let tol = 1e-4 * ws.max(1.0);
        assert!((sum[i][3] - ws).abs() <= tol, "pixel {i}: Σw GPU {} CPU {ws}", sum[i][3]);
        assert!((Vec3::from_slice(&sum[i][..3]) - we).length() <= 1e-4 * we.length().max(1.0), "pixel {i}: Σ w E");
        if ws > 0.0 {
            assert!(
                (Vec3::from_slice(&light[i][..3]) - we / ws).length() <= 1e-4 * (we / ws).length().max(1.0),
                "pixel {i}: Eq. 11"
            );
            assert_eq!(light[i][3], 1.0);
        } else {
            covered_unreached += 1;
            assert_eq!(light[i][3], 0.0, "pixel {i} no sample reached is flagged");
        }
    }
    assert_eq!(uncovered, covered_unreached, "uncovered pixels are counted");
    // Both outcomes of Eq. 9 occur inside the samples' spheres.
    assert!(reached > 100 && rejected > 20, "reached {reached}, rejected inside a sphere {rejected}");
}

#[test]
fn splatting_a_constant_light_gives_that_constant_wherever_a_sample_reaches() {
    let (Scene { w, h, camera, pos, nrm }, _, frame) = splat_case(0.8, 0.3);
    let e = Vec3::new(0.7, 0.25, 1.5);
    let samples = splat_samples(w, &pos, &nrm, |_| e);
    let (sum, light, _, _) = gpu_splat(w, h, &pos, &nrm, &camera, &samples, frame, (SplatMethod::Blend, w * h));
    let mut lit = 0;
    for i in 0..(w * h) as usize {
        if sum[i][3] > 0.0 {
            assert!((Vec3::from_slice(&light[i][..3]) - e).length() <= 1e-5, "pixel {i}: {:?}", light[i]);
            lit += 1;
        }
    }
    assert!(lit > 200, "{lit} pixels reached");
}

/// The splat binned in compute (GI Lab, issue #38) gives the blended quads' sums (the paper's
/// additive blending) bit for bit: the same samples added in the same order at every pixel,
/// also when the bins hold fewer samples than the splat has and the rest are drawn as quads.
#[test]
fn the_binned_splat_equals_the_blended_quads() {
    let (Scene { w, h, camera, pos, nrm }, _, frame) = splat_case(0.9, 0.2);
    // A sample every 11th covered pixel, of radii 0.05 to 0.6: overlapping splats of many sizes.
    let samples: Vec<GpuHcbSample> = (0..(w * h) as usize)
        .filter(|&i| nrm[i][3] > 0.5 && i % 11 == 0)
        .enumerate()
        .map(|(k, i)| GpuHcbSample {
            position: glam::Vec4::new(pos[i][0], pos[i][1], pos[i][2], 0.05 + 0.05 * (k % 12) as f32),
            normal: glam::Vec4::new(nrm[i][0], nrm[i][1], nrm[i][2], 1.0),
            texel: [i as u32 % w, i as u32 / w, 0, 0],
            light: Vec3::new(0.3 + 0.1 * (k % 7) as f32, 1.0 / (1.0 + k as f32), 0.01 * k as f32).extend(1.0),
            // The glossy receiver's direction sum (issue #51), summed beside the light.
            dir: glam::Vec4::new(0.1 * (k % 5) as f32, 0.2, -0.05 * (k % 3) as f32, 0.0),
        })
        .collect();
    assert!(samples.len() > 100, "{} samples", samples.len());
    let run = |method| gpu_splat(w, h, &pos, &nrm, &camera, &samples, frame, method);
    let blend = run((SplatMethod::Blend, w * h));
    let bits = |v: &[[f32; 4]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    let reached = blend.0.iter().filter(|p| p[3] > 0.0).count();
    assert!(reached > 1000, "{reached} pixels reached");
    assert!(blend.3.iter().filter(|p| p[1] > 0.0).count() == reached, "every reached pixel sums directions");
    // All samples binned, then 32 binned and the rest as quads.
    for bins in [w * h, 32] {
        let binned = run((SplatMethod::Binned, bins));
        let pairs = [
            ("weight_sum", &blend.0, &binned.0),
            ("irradiance", &blend.1, &binned.1),
            ("weight_sum.direction", &blend.3, &binned.3),
        ];
        for (name, a, b) in pairs {
            let differ = bits(a).iter().zip(bits(b)).filter(|(x, y)| **x != *y).count();
            assert_eq!(differ, 0, "hcb.{name} with {bins} binned: {differ} channels differ");
        }
        assert_eq!(blend.2, binned.2, "uncovered pixels");
    }
}
