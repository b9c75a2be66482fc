//! DDGI (issue #56 point 3) on the GPU against its CPU twin (`cpu::ddgi`): so far the probe
//! update's blend — every texel of both atlases, borders included, after one update from
//! empty and after one that keeps the old values by the hysteresis, from the same rays.

use gi_lab_tests::gpu;
use gi_render::counters::prelude::*;
use gi_render::cpu::ddgi::{Atlas, ProbeRay, random_rotation, spherical_fibonacci, update_distance, update_irradiance};
use gi_render::passes::ddgi::blend::{BLEND_BINDINGS, DdgiBlendPass, DdgiUpdateParams};
use glam::{Vec3, Vec4};

fn storage(ctx: &gi_render::GpuContext, label: &str, data: &[u8]) -> wgpu::Buffer {
    ctx.device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: data,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
    })
}

#[test]
fn the_blend_matches_its_cpu_twin_texel_for_texel() {
    let ctx = gpu();
    let pass = DdgiBlendPass::new(&ctx);
    let (probes, rays_per_probe) = (5usize, 96u32);
    let rotation = random_rotation([0.31, 0.72, 0.13]);
    let mut s = 17u32;
    let mut f = move || {
        s = s.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        ((s >> 8) as f32) / 16_777_216.0
    };
    // Each probe's rays: radiance, a hit distance (some misses, some back faces).
    let rays: Vec<Vec<ProbeRay>> = (0..probes)
        .map(|_| {
            (0..rays_per_probe)
                .map(|r| {
                    let kind = f();
                    ProbeRay {
                        dir: (rotation * spherical_fibonacci(r, rays_per_probe)).normalize(),
                        radiance: Vec3::new(f(), f(), f()) * 2.0,
                        distance: if kind < 0.15 { f32::INFINITY } else { 0.1 + 2.0 * f() },
                        backface: (0.15..0.3).contains(&kind),
                    }
                })
                .collect()
        })
        .collect();
    let packed: Vec<Vec4> = rays
        .iter()
        .flatten()
        .map(|r| {
            let d = if r.distance.is_finite() { r.distance } else { 1e30 };
            r.radiance.extend(if r.backface { -d } else { d })
        })
        .collect();
    for keep_old in [false, true] {
        let (alpha, sharpness, max_distance) = (if keep_old { 0.85 } else { 0.0 }, 50.0, 1.8);
        // Old values: anything (the first update ignores them).
        let mut irr = Atlas::new(6, probes, Vec3::ZERO);
        let mut dist = Atlas::new(14, probes, Vec3::ZERO);
        for t in irr.texels.iter_mut() {
            *t = Vec3::new(f(), f(), f());
        }
        for t in dist.texels.iter_mut() {
            *t = Vec3::new(f(), f() * 2.0, 0.0);
        }
        let upload = |a: &Atlas, z: f32| -> Vec<Vec4> {
            a.texels.iter().map(|t| Vec3::new(t.x, t.y, if z > 0.0 { t.z } else { 0.0 }).extend(1.0)).collect()
        };
        let irr_buf = storage(&ctx, "test.ddgi.irradiance", bytemuck::cast_slice(&upload(&irr, 1.0)));
        let dist_buf = storage(&ctx, "test.ddgi.distance", bytemuck::cast_slice(&upload(&dist, 0.0)));
        let params = DdgiUpdateParams::new(
            rotation,
            (probes as u32, rays_per_probe),
            (&irr, &dist),
            keep_old,
            alpha,
            sharpness,
            max_distance,
        );
        let params_buf = storage(&ctx, "test.ddgi.params", bytemuck::bytes_of(&params));
        let rays_buf = storage(&ctx, "test.ddgi.rays", bytemuck::cast_slice(&packed));
        let group = BLEND_BINDINGS.group(
            &ctx.device,
            &pass.layout,
            [
                params_buf.as_entire_binding(),
                rays_buf.as_entire_binding(),
                irr_buf.as_entire_binding(),
                dist_buf.as_entire_binding(),
            ],
        );
        let mut enc =
            ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.ddgi.blend") });
        pass.record(&mut enc, &group, (irr.width(), irr.height()), (dist.width(), dist.height()));
        ctx.submit([enc.finish()]);
        let read = |b: &wgpu::Buffer| -> Vec<Vec4> {
            bytemuck::pod_collect_to_vec(&gi_render::buffers::read_storage(&ctx, b, b.size()).expect("read back"))
        };
        let (gpu_irr, gpu_dist) = (read(&irr_buf), read(&dist_buf));
        for (p, r) in rays.iter().enumerate() {
            update_irradiance(&mut irr, p, r, alpha);
            update_distance(&mut dist, p, r, alpha, sharpness, max_distance);
        }
        for (name, cpu, gpu) in [("irradiance", &irr, &gpu_irr), ("distance", &dist, &gpu_dist)] {
            let mut worst = 0f32;
            for p in 0..probes {
                for ty in 0..cpu.tile() {
                    for tx in 0..cpu.tile() {
                        let (x, y) = cpu.texel(p, tx, ty);
                        let g = gpu[(y * cpu.width() + x) as usize].truncate();
                        let c = cpu.get(p, tx, ty);
                        let c = if name == "distance" { Vec3::new(c.x, c.y, 0.0) } else { c };
                        worst = worst.max(((g - c).abs() / c.abs().max(Vec3::splat(0.05))).max_element());
                    }
                }
            }
            eprintln!("{name}, keeping the old values {keep_old}: worst relative difference {worst:e}");
            assert!(worst < 1e-3, "{name}: the GPU's blend is {worst} from the CPU's");
        }
    }
}
