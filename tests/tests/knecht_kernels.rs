//! Knecht 002's shading, filter and confidence kernels (issue #5) against their CPU twins in
//! `gi_render::cpu::knecht` on synthetic G-buffers, and the VPL list on the default scene.

use gi_lab_tests::knecht_support::{Rng, knecht_settings, read};
use gi_lab_tests::{default_scene, gpu};
use gi_render::cpu::knecht::{self};
use gi_render::settings::pipeline::Technique;
use gi_render::{GpuContext, Renderer};
use glam::{Vec2, Vec3};

// ---------------------------------------------------------------------------------------
// Shading, filter and confidence kernels against their CPU twins on synthetic G-buffers.

/// The value an Rgba16Float texture stores for `x`.
fn f16(x: f32) -> f32 {
    gi_render::buffers::round_to_half(x)
}

/// A sampled (and copyable) texture with the given texels: Rgba32Float, or Rgba16Float
/// when `half` (the G-buffer's normal format, which the temporal pass copies).
fn texture(ctx: &GpuContext, label: &str, w: u32, h: u32, data: &[[f32; 4]], half: bool) -> wgpu::Texture {
    let format = if half { wgpu::TextureFormat::Rgba16Float } else { wgpu::TextureFormat::Rgba32Float };
    let bytes: Vec<u8> = if half {
        data.iter().flatten().flat_map(|&v| gi_render::buffers::f32_to_half(v).to_le_bytes()).collect()
    } else {
        bytemuck::cast_slice(data).to_vec()
    };
    gi_lab_tests::texture_from_bytes(ctx, label, format, (w, h), &bytes)
}

/// The normal the passes shade with where the G-buffer's normal is `n` (issue #53): its packed
/// word unpacked and rounded to half floats (`knecht::gbuffer_normal`).
fn shaded(n: Vec3) -> Vec3 {
    knecht::gbuffer_normal(knecht::pack_normal(Some(n))).expect("a normal")
}

/// Views of a synthetic G-buffer (emission and depth are not read by the passes tested). The
/// linear depth the passes read (issue #53) is the positions' w; the packed normals the
/// normals' words (`knecht::pack_normal`, none where w is 0).
struct SyntheticGBuffer {
    position: wgpu::Texture,
    linear_depth: wgpu::Texture,
    normal: wgpu::Texture,
    packed_normal: wgpu::Texture,
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
            linear_depth: {
                let depth: Vec<[f32; 4]> = position.iter().map(|p| [p[3], 0.0, 0.0, 0.0]).collect();
                texture(ctx, "test.linear_depth", w, h, &depth, false)
            },
            normal: texture(ctx, "test.normal", w, h, normal, true),
            packed_normal: {
                let words: Vec<u8> = normal
                    .iter()
                    .map(|n| knecht::pack_normal((n[3] > 0.5).then(|| Vec3::new(n[0], n[1], n[2]))))
                    .flat_map(u32::to_le_bytes)
                    .collect();
                let format = gi_render::passes::gbuffer::PACKED_NORMAL_FORMAT;
                gi_lab_tests::texture_from_bytes(ctx, "test.packed_normal", format, (w, h), &words)
            },
            albedo: texture(ctx, "test.albedo", w, h, albedo, false),
            material: texture(ctx, "test.material", w, h, material, false),
            motion: texture(ctx, "test.motion", w, h, motion, false),
        }
    }

    fn views(&self) -> gi_render::passes::gbuffer::GBufferViews {
        let v = |t: &wgpu::Texture| t.create_view(&Default::default());
        gi_render::passes::gbuffer::GBufferViews {
            position: v(&self.position),
            linear_depth: v(&self.linear_depth),
            normal: v(&self.normal),
            packed_normal: v(&self.packed_normal),
            albedo: v(&self.albedo),
            material: v(&self.material),
            motion: v(&self.motion),
            emission: v(&self.albedo),
            depth: v(&self.position),
        }
    }
}

/// The camera G-buffer's packed normals unpacked on the GPU (`gbuffer.normal`'s fill, the
/// `gbuffer_normal` every pass that reads the word shades with: common/normal.wgsl, issue #53)
/// against the CPU twin `knecht::gbuffer_normal`: every 32-bit word is some normal's octahedral
/// coordinates, so random words cover the whole sphere, the folded half and components far
/// below half floats' normal range; the no-surface word gives 0. The rounding to half floats is
/// the twin's (ties to even), bit for bit, unless the two normalisations differ in the last f32
/// bit right at a rounding tie of the half float: then by one half-float step.
#[test]
fn packed_normals_unpack_on_the_gpu_as_the_cpu_twin() {
    use gi_render::passes::gbuffer::{NO_NORMAL, NORMAL_FORMAT, PACKED_NORMAL_FORMAT};
    let ctx = gpu();
    let (w, h) = (64u32, 64u32);
    let mut rng = Rng(53);
    let mut words: Vec<u32> =
        (0..w * h).map(|_| (rng.next_f32() * 65536.0) as u32 | ((rng.next_f32() * 65536.0) as u32) << 16).collect();
    // The axes, the octahedron's edges and tiny components (2^-20 of the square's side).
    words[..6].copy_from_slice(&[0, 0x7fff, 0x8001, 0x7fff_0000, 0x8001_0000, 0x0001_7ffe]);
    words[6] = NO_NORMAL;
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let packed = gi_lab_tests::texture_from_bytes(&ctx, "test.packed_normal", PACKED_NORMAL_FORMAT, (w, h), &bytes);
    let out = gi_render::passes::create_target(
        &ctx.device,
        "test.normal",
        w,
        h,
        NORMAL_FORMAT,
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    let v = |t: &wgpu::Texture| t.create_view(&Default::default());
    let fill = gi_render::passes::gbuffer_position::normal_pass(&ctx, &v(&packed), &v(&out), (w, h));
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.unpack") });
    fill.record(&mut enc, None);
    ctx.queue.submit([enc.finish()]);
    let got = read(&ctx, &out);
    let (mut equal, mut tiny) = (0, 0);
    for (i, (&word, g)) in words.iter().zip(&got.data).enumerate() {
        let Some(n) = knecht::gbuffer_normal(word) else {
            assert_eq!(*g, [0.0; 4], "texel {i}: the no-surface word");
            continue;
        };
        assert_eq!(g[3], 1.0, "texel {i}: coverage");
        let bits_equal = (0..3).all(|c| g[c].to_bits() == n[c].to_bits());
        equal += bits_equal as usize;
        for c in 0..3 {
            let step = gi_render::buffers::half_step(n[c]);
            assert!((g[c] - n[c]).abs() <= step, "texel {i}: word {word:#010x} unpacked as {g:?}, the twin {n}");
            tiny += (n[c] != 0.0 && n[c].abs() < 6.1e-5) as usize;
        }
    }
    let covered = words.len() - 1;
    println!("{equal} of {covered} normals bit for bit the twin's; {tiny} components below 2^-14");
    assert!(equal * 1000 >= covered * 999, "{equal} of {covered} normals equal the twin's");
    assert!(tiny > 0, "no component in the half floats' subnormal range");
}

#[test]
fn interleaved_vpl_shading_on_the_gpu_equals_eq_4_7_to_4_9_on_the_cpu() {
    use gi_render::passes::knecht::interleave::InterleavePass;
    use gi_render::passes::reference::vpl_visibility::GatherVisibility;
    let ctx = gpu();
    // An odd size, so that the last row and column of tiles are partial; n = 2 and 7 VPLs,
    // so that the tiles hold 2, 2, 2 and 1 VPLs and the N / N_t scaling differs per tile.
    let (w, h, n) = (30u32, 26u32, 2u32);
    let mut rng = Rng(7);
    let len = (w * h) as usize;
    let (mut pos, mut nrm, mut alb, mut mat) =
        (vec![[0.0; 4]; len], vec![[0.0; 4]; len], vec![[0.0; 4]; len], vec![[0.0; 4]; len]);
    let mut receivers = vec![None; len];
    // A camera at `eye` looking at the origin: the gather rebuilds each receiver from its
    // linear depth (issue #53), as the CPU twin below does. A 30° field and depths 2.5–4 put
    // the receivers in about [−1, 1]² × [−1, 0.5], under the VPLs.
    let eye = Vec3::new(0.2, 0.1, 3.0);
    let view = glam::camera::rh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y);
    let view_proj =
        glam::camera::rh::proj::directx::perspective(30f32.to_radians(), w as f32 / h as f32, 0.1, 10.0) * view;
    for i in 0..len {
        if rng.next_f32() < 0.1 {
            continue; // background
        }
        let (x, y) = (i as u32 % w, i as u32 / w);
        let depth = rng.range(2.5, 4.0);
        let p =
            gi_render::passes::gbuffer_position::world_from_linear_depth(view_proj, view, eye, (w, h), (x, y), depth);
        let nq = {
            let u = rng.unit();
            Vec3::new(f16(u.x), f16(u.y), f16(u.z))
        };
        let c = Vec3::new(rng.unorm8(), rng.unorm8(), rng.unorm8());
        let di = rng.unorm8();
        // SI in eighths and SP a small integer: exact in the split's half-float target.
        let si = (rng.next_f32() * 8.0).floor() / 8.0;
        let sp = [1.0, 8.0, 32.0, 200.0][(rng.next_f32() * 4.0) as usize % 4];
        pos[i] = [p.x, p.y, p.z, depth];
        nrm[i] = [nq.x, nq.y, nq.z, 1.0];
        alb[i] = [c.x, c.y, c.z, di];
        mat[i] = [si, sp, 0.0, 0.0];
        receivers[i] = Some(knecht::Receiver { position: p, normal: shaded(nq).normalize(), albedo: c, di, si, sp });
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
            albedo: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
            di: rng.next_f32(),
            si: rng.next_f32(),
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
    let d_min = 0.1;
    let camera = gi_render::passes::CameraUniform {
        view_proj,
        prev_view_proj: view_proj,
        inv_view_proj: view_proj.inverse(),
        view,
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
    let mut pass = InterleavePass::new(&ctx, w, h, n, false);
    let mut timer = gi_render::timing::GpuTimer::new(&ctx);
    // Frame 0 with the full BRDF at the receiver, frame 1 (another slot→tile map) diffuse only.
    let (mut lit, mut dark) = (0, 0);
    for (frame, diffuse) in [(0u32, false), (1, true)] {
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.shade") });
        let inputs = gi_render::passes::knecht::interleave::ShadeInputs {
            camera: &camera_buf,
            g: &g.views(),
            vpls: &vpl_buf,
            count: vpl_count,
            min_distance: d_min,
            near_cut: 0.0,
            vis: &GatherVisibility::None,
            diffuse_only: diffuse,
        };
        pass.shade(&ctx, &mut enc, &mut timer, &inputs);
        ctx.queue.submit([enc.finish()]);
        let got = read(&ctx, &pass.merged);
        let got_irradiance = read(&ctx, &pass.irradiance);
        let offsets = gi_render::maths::tile_offsets(vpl_count, n, frame);
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let tile = (x % n) + (y % n) * n;
                let (mut expected, mut irradiance) = (Vec3::ZERO, Vec3::ZERO);
                if let Some(r) = &receivers[i] {
                    // Diffuse only: the receiver's SI is 0 (c·DI/π, as the HCB reflects).
                    let r = knecht::Receiver { si: if diffuse { 0.0 } else { r.si }, ..*r };
                    let slots: Vec<u32> = gi_render::maths::tile_slots(tile, vpl_count, n, &offsets).collect();
                    let per_tile = slots.len() as u32;
                    for k in slots {
                        if let Some(v) = &cpu_vpls[k as usize] {
                            expected += knecht::vpl_radiance(v, &r, eye, d_min);
                            irradiance += knecht::vpl_irradiance(v, &r, d_min);
                        }
                    }
                    expected *= vpl_count as f32 / per_tile as f32;
                    irradiance *= vpl_count as f32 / per_tile as f32;
                }
                // The irradiance beside the light (indirect.irradiance, the demodulated
                // filter's input), with the same tolerance.
                let e = got_irradiance.at(x, y);
                let e3 = Vec3::new(e[0], e[1], e[2]);
                let step = gi_render::buffers::half_step(irradiance.abs().max_element());
                assert!(
                    (e3 - irradiance).abs().max_element() <= 1e-5 + 2e-4 * irradiance.abs().max_element() + step,
                    "frame {frame}: irradiance at pixel ({x}, {y}): GPU {e3}, CPU {irradiance}"
                );
                let p = got.at(x, y);
                let g3 = Vec3::new(p[0], p[1], p[2]);
                let err = (g3 - expected).abs().max_element();
                // indirect.merged holds half floats, stored rounding to nearest or toward
                // zero (the device's choice): one step of that format besides the kernel's
                // own tolerance.
                let step = gi_render::buffers::half_step(expected.abs().max_element());
                assert!(
                    err <= 1e-5 + 2e-4 * expected.abs().max_element() + step,
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
    // Each pixel has an irradiance E and a textured diffuse colour (c, DI), its light is
    // k·E + S with k = c·DI/π and a specular part S: the demodulated filter must keep the
    // colour's texture (issue #51).
    let mut texels = Vec::with_capacity(len);
    let mut albedo = Vec::with_capacity(len);
    // The G-buffer's normals; the twin filters with those the pass shades with (`shaded`).
    let mut normals = Vec::with_capacity(len);
    for y in 0..h {
        for x in 0..w {
            if rng.next_f32() < 0.08 {
                let zero = Vec3::ZERO;
                texels.push(knecht::FilterTexel {
                    value: zero,
                    depth: 0.0,
                    normal: Vec3::Z,
                    irradiance: zero,
                    reflectance: zero,
                });
                albedo.push([0.0; 4]);
                normals.push([0.0; 4]);
                continue;
            }
            let floor = x + y < 24;
            let base = if floor { 2.0 + 0.01 * x as f32 } else { 2.3 };
            let depth = base + rng.range(-0.08, 0.08);
            let axis = if floor { Vec3::Y } else { Vec3::Z };
            let normal = (axis + 0.5 * rng.range(0.0, 1.0) * rng.unit()).normalize();
            let normal = Vec3::new(f16(normal.x), f16(normal.y), f16(normal.z));
            let e = Vec3::new(rng.range(0.0, 4.0), rng.range(0.0, 4.0), rng.range(0.0, 4.0));
            let irradiance = Vec3::new(f16(e.x), f16(e.y), f16(e.z));
            let (c, di) = (Vec3::new(rng.unorm8(), rng.unorm8(), rng.unorm8()), rng.unorm8());
            let reflectance = c * di / std::f32::consts::PI;
            let specular = Vec3::splat(rng.range(0.0, 0.5));
            let v = reflectance * irradiance + specular;
            let value = Vec3::new(f16(v.x), f16(v.y), f16(v.z));
            texels.push(knecht::FilterTexel { value, depth, normal: shaded(normal), irradiance, reflectance });
            albedo.push([c.x, c.y, c.z, di]);
            normals.push([normal.x, normal.y, normal.z, 1.0]);
        }
    }
    let pos: Vec<[f32; 4]> = texels.iter().map(|t| [0.0, 0.0, 0.0, t.depth]).collect();
    let nrm = normals;
    let src: Vec<[f32; 4]> = texels.iter().map(|t| [t.value.x, t.value.y, t.value.z, 1.0]).collect();
    let irr: Vec<[f32; 4]> = texels.iter().map(|t| t.irradiance.extend(1.0).to_array()).collect();
    let zero = vec![[0.0; 4]; len];
    let g = SyntheticGBuffer::new(&ctx, w, h, &pos, &nrm, &albedo, &zero, &zero);
    let src_tex = texture(&ctx, "test.src", w, h, &src, false);
    let pass = InterleavePass::new(&ctx, w, h, n, false);
    // E in half floats, as the gather writes it.
    let irr_tex = texture(&ctx, "test.irradiance", w, h, &irr, true);
    let s = InterleaveSettings { n, ..Default::default() };
    let filter = |demodulated: bool| {
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.filter") });
        let (src, irr) = (src_tex.create_view(&Default::default()), irr_tex.create_view(&Default::default()));
        pass.filter(
            gi_render::timing::PassRec { ctx: &ctx, enc: &mut enc, slot: None },
            &s,
            depth_range,
            &src,
            &g.views(),
            demodulated.then_some(&irr),
        );
        ctx.queue.submit([enc.finish()]);
        (read(&ctx, &pass.filtered), read(&ctx, &pass.filtered_irradiance))
    };
    // The thesis' filter of L: the CPU twin with E = k = 0.
    let plain: Vec<knecht::FilterTexel> =
        texels.iter().map(|t| knecht::FilterTexel { irradiance: Vec3::ZERO, reflectance: Vec3::ZERO, ..*t }).collect();
    let (got_plain, _) = filter(false);
    let cpu_plain = knecht::geometry_aware_filter(&plain, w, h, n, s.alpha, s.beta, depth_range);
    let mut worst_plain = 0.0f32;
    for (i, c) in cpu_plain.iter().enumerate() {
        let p = got_plain.at(i as u32 % w, i as u32 / w);
        let err = (Vec3::new(p[0], p[1], p[2]) - *c).abs().max_element();
        worst_plain = worst_plain.max(err - gi_render::buffers::half_step(c.abs().max_element()));
    }
    assert!(worst_plain <= 1e-5, "the filter of L: worst error beyond a half step {worst_plain}");
    let (got, got_irradiance) = filter(true);
    let cpu = knecht::geometry_aware_filter(&texels, w, h, n, s.alpha, s.beta, depth_range);
    // The window's mean irradiance beside it (indirect.filtered_irradiance, the demodulated
    // merge's E), also half floats.
    let cpu_irradiance = knecht::filter_with_irradiance(&texels, w, h, n, s.alpha, s.beta, depth_range);
    for (i, (l, e)) in cpu_irradiance.iter().enumerate() {
        assert_eq!(*l, cpu[i], "the two CPU filters disagree at {i}");
        let p = got_irradiance.at(i as u32 % w, i as u32 / w);
        let err = (Vec3::new(p[0], p[1], p[2]) - *e).abs().max_element();
        let step = gi_render::buffers::half_step(e.abs().max_element());
        assert!(err <= 1e-5 + 1e-6 * e.abs().max_element() + step, "mean irradiance at {i}: GPU {p:?}, CPU {e}");
    }
    // Demodulated, a pixel's colour shows in its filtered light: k_p·mean(E) differs from the
    // mean of k·E wherever the window's colours differ.
    let sharper = cpu.iter().zip(&cpu_plain).filter(|(a, b)| (**a - **b).abs().max_element() > 1e-2).count();
    assert!(sharper > len / 2, "the demodulated filter differs from the filter of L at only {sharper} pixels");
    let mut partial = 0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let p = got.at(x, y);
            let g3 = Vec3::new(p[0], p[1], p[2]);
            // indirect.filtered holds half floats: one step of that format besides 1e-5 (k is
            // the albedo's 8-bit value times DI / π in both).
            let step = gi_render::buffers::half_step(cpu[i].abs().max_element());
            let err = (g3 - cpu[i]).abs().max_element();
            assert!(
                err <= 1e-5 + 1e-6 * cpu[i].abs().max_element() + step,
                "pixel ({x}, {y}): GPU {g3}, CPU {}",
                cpu[i]
            );
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
    confidence_and_merge_case(false);
}

/// The demodulated merge (issue #51): E and S merged apart with Eq. 3.6 and reflected with
/// each pixel's own colour, against `cpu::knecht::merge_demodulated`.
#[test]
fn the_demodulated_merge_on_the_gpu_equals_the_cpu() {
    confidence_and_merge_case(true);
}

/// Two frames through the confidence pass against Eq. 3.1–3.6 on the CPU; `demodulated`: each
/// pixel also has a textured colour and an irradiance E, its light is k·E + S, and the pass
/// merges E and S apart (`cpu::knecht::merge_demodulated`).
fn confidence_and_merge_case(demodulated: bool) {
    use gi_render::passes::knecht::temporal::{TemporalPass, TemporalSettings};
    let ctx = gpu();
    let (w, h) = (24u32, 20u32);
    let depth_range = 9.9;
    let mut rng = Rng(if demodulated { 29 } else { 23 });
    let len = (w * h) as usize;
    // Frame 0: depth, normal, colour, irradiance and light per pixel (some background).
    struct Px {
        depth: f32,
        normal: Vec3,
        light: Vec3,
        /// (c, DI) and E; light = k·E + S with k = c·DI/π (zero colour without demodulation).
        albedo: [f32; 4],
        irradiance: Vec3,
    }
    let half3 = |v: Vec3| Vec3::new(f16(v.x), f16(v.y), f16(v.z));
    let lit = |rng: &mut Rng, depth: f32, normal: Vec3| {
        let (c, di) = (Vec3::new(rng.unorm8(), rng.unorm8(), rng.unorm8()), rng.unorm8());
        let e = half3(Vec3::new(rng.range(0.1, 4.0), rng.range(0.1, 4.0), rng.range(0.1, 4.0)));
        let light = if demodulated {
            half3(c * di / std::f32::consts::PI * e + Vec3::splat(rng.range(0.0, 0.5)))
        } else {
            half3(Vec3::new(rng.range(0.1, 2.0), rng.range(0.1, 2.0), rng.range(0.1, 2.0)))
        };
        Px { depth, normal, light, albedo: [c.x, c.y, c.z, di], irradiance: e }
    };
    let frame = |rng: &mut Rng| -> Vec<Option<Px>> {
        (0..len)
            .map(|_| {
                (rng.next_f32() > 0.1).then(|| {
                    let n = (Vec3::Z + 0.4 * rng.unit()).normalize();
                    let depth = f16(rng.range(1.0, 5.0));
                    lit(rng, depth, half3(n))
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
            let keep = rng.next_f32();
            if rng.next_f32() < 0.1 {
                return None;
            }
            Some(match p {
                Some(p) if keep < 0.8 => {
                    let n = (p.normal + rng.range(0.0, 0.3) * rng.unit()).normalize();
                    let depth = f16(p.depth + rng.range(-0.2, 0.2));
                    let mut q = lit(&mut rng, depth, half3(n));
                    if !demodulated {
                        q.light = half3(p.light * rng.range(0.7, 1.3));
                    }
                    q
                }
                _ => {
                    let depth = f16(rng.range(1.0, 5.0));
                    lit(&mut rng, depth, Vec3::Z)
                }
            })
        })
        .collect();
    let motion: Vec<Vec2> = (0..len)
        .map(|_| if rng.next_f32() < 0.5 { Vec2::ZERO } else { Vec2::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0)) })
        .collect();
    let upload = |f: &[Option<Px>], motion: &[Vec2]| {
        let pos: Vec<[f32; 4]> = f.iter().map(|p| [0.0, 0.0, 0.0, p.as_ref().map_or(0.0, |p| p.depth)]).collect();
        let nrm: Vec<[f32; 4]> =
            f.iter().map(|p| p.as_ref().map_or([0.0; 4], |p| [p.normal.x, p.normal.y, p.normal.z, 1.0])).collect();
        let light: Vec<[f32; 4]> =
            f.iter().map(|p| p.as_ref().map_or([0.0; 4], |p| [p.light.x, p.light.y, p.light.z, 1.0])).collect();
        let albedo: Vec<[f32; 4]> = f.iter().map(|p| p.as_ref().map_or([0.0; 4], |p| p.albedo)).collect();
        let irr: Vec<[f32; 4]> =
            f.iter().map(|p| p.as_ref().map_or([0.0; 4], |p| p.irradiance.extend(1.0).to_array())).collect();
        let mv: Vec<[f32; 4]> = motion.iter().map(|m| [m.x, m.y, 0.0, 0.0]).collect();
        let zero = vec![[0.0; 4]; len];
        (
            SyntheticGBuffer::new(&ctx, w, h, &pos, &nrm, &albedo, &zero, &mv),
            texture(&ctx, "test.light", w, h, &light, false),
            texture(&ctx, "test.irradiance", w, h, &irr, true),
        )
    };
    let s = TemporalSettings { w_pos: 10.0, ..Default::default() };
    let mut pass = TemporalPass::new(&ctx, w, h);
    for (f, m) in [(&f0, vec![Vec2::ZERO; len]), (&f1, motion.clone())] {
        let (g, light, irr) = upload(f, &m);
        let mut enc =
            ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.temporal") });
        let irr = irr.create_view(&Default::default());
        let irr = demodulated.then_some(&irr);
        pass.run(
            gi_render::timing::PassRec { ctx: &ctx, enc: &mut enc, slot: None },
            &s,
            depth_range,
            &light.create_view(&Default::default()),
            &g.views(),
            irr,
        );
        ctx.queue.submit([enc.finish()]);
    }
    assert_eq!(pass.split_prev().is_some(), demodulated, "the second frame read a split history");
    let conf = read(&ctx, &pass.confidence);
    let hist = read(&ctx, pass.history());
    let weights = knecht::ConfidenceWeights {
        c_base: s.c_base,
        w_pos: s.w_pos,
        w_normal: s.w_normal,
        w_illumination: s.w_illumination,
    };
    let k = |p: &Px| Vec3::new(p.albedo[0], p.albedo[1], p.albedo[2]) * p.albedo[3] / std::f32::consts::PI;
    let (mut zero, mut middle, mut merged) = (0, 0, 0);
    for y in 0..h as i32 {
        for x in 0..w as i32 {
            let i = (y * w as i32 + x) as usize;
            let (mut c, mut out) = (0.0, f1[i].as_ref().map_or(Vec3::ZERO, |p| p.light));
            // The half-float rounding of the split history (E_prev, S_prev) that the merge read,
            // as one half step of each, times its share: 0 without demodulation.
            let mut split_step = 0.0;
            if let Some(p) = &f1[i] {
                // The shader's lookup: the previous position rounded to a pixel.
                let m = motion[i];
                let q = (Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + m).floor();
                let inside = q.x >= 0.0 && q.y >= 0.0 && q.x < w as f32 && q.y < h as f32;
                if inside && let Some(prev) = &f0[(q.y as u32 * w + q.x as u32) as usize] {
                    // Without demodulation the history is the light itself; demodulated it is
                    // frame 0's split, stored as half floats, reflected with this pixel's k.
                    let split_prev = knecht::SplitLight::of(prev.light, k(prev), prev.irradiance);
                    let split_prev = knecht::SplitLight {
                        irradiance: half3(split_prev.irradiance),
                        specular: half3(split_prev.specular),
                    };
                    let i_prev = if demodulated { split_prev.reflect(k(p)) } else { prev.light };
                    // Demodulated, n_prev comes from the split history's normal word (issue #53),
                    // octahedral snorm16: the twin rounds as the shader stores it.
                    // Not demodulated, the thesis' normals texture keeps the normal the merge
                    // shaded with (`shaded`, issue #53).
                    let normal_prev = if demodulated {
                        knecht::unpack_normal(knecht::pack_normal(Some(prev.normal))).expect("a covered pixel")
                    } else {
                        shaded(prev.normal)
                    };
                    let input = knecht::ConfidenceInput {
                        motion_px: m,
                        size: Vec2::new(w as f32, h as f32),
                        depth: p.depth,
                        depth_prev: prev.depth,
                        depth_range,
                        normal: shaded(p.normal),
                        normal_prev,
                        illumination: p.light,
                        illumination_prev: i_prev,
                    };
                    c = knecht::confidence(&input, &weights);
                    out = if demodulated {
                        let new = knecht::SplitLight::of(p.light, k(p), p.irradiance);
                        let step = |v: Vec3| gi_render::buffers::half_step(v.abs().max_element());
                        split_step = c * (k(p).max_element() * step(split_prev.irradiance) + step(split_prev.specular));
                        knecht::merge_demodulated(k(p), new, split_prev, c).0
                    } else {
                        knecht::merge(p.light, prev.light, c)
                    };
                    merged += 1;
                }
            }
            let g = conf.at(x as u32, y as u32)[0];
            assert!((g - c).abs() <= 2e-5, "confidence at ({x}, {y}): GPU {g}, CPU {c}");
            let hp = hist.at(x as u32, y as u32);
            let h3 = Vec3::new(hp[0], hp[1], hp[2]);
            // The history is stored as half floats (issue #53): one half step of the merged
            // light more (the inputs are exact halves, so the depth and frame 0's light read
            // back unrounded).
            let store_step = gi_render::buffers::half_step(out.max_element());
            assert!(
                (h3 - out).abs().max_element() <= 1e-4 * out.max_element().max(1.0) + split_step + store_step,
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
