//! Every pass of every shipped preset under the Vulkan validation layers (issue #52 point 6):
//! lavapipe forgives what a real driver may not (a texture in the wrong layout, a missing
//! barrier), the layers do not. Each preset renders three frames of the default scene at 64²
//! (the first frame, a frame with history, and one that explains a pixel), then every buffer
//! it registered is read back; any validation message but the allow-listed ones
//! (`gi_lab_tests::validation::ALLOWED`, each with why) fails the test and names the preset.
//!
//! `bash scripts/test.sh` installs the layers (Debian's `vulkan-validationlayers`) and runs this
//! binary with validation on, the others with `WGPU_VALIDATION=0` (the layers slow every Vulkan
//! call). Without the layers this test fails and says how to install them.

use gi_lab_tests::{default_scene, gpu, validation};
use gi_render::{GpuContext, Renderer};

#[test]
fn every_shipped_preset_runs_without_a_validation_message() {
    assert!(
        validation::layer_installed(),
        "the Vulkan validation layer is not installed: `sudo apt-get install -y vulkan-validationlayers` \
         (bash scripts/test.sh installs it)"
    );
    assert_ne!(
        std::env::var("WGPU_VALIDATION").as_deref(),
        Ok("0"),
        "WGPU_VALIDATION=0 turns the validation layer off; this test needs it on"
    );
    validation::install();
    wgpus_mip_tracking_still_needs_the_ism_workaround();
    let presets = gi_lab_tests::shipped_presets();
    let mut failures = Vec::new();
    for p in &presets {
        let name = p.file_stem().and_then(|s| s.to_str()).unwrap_or("?").to_string();
        let loaded = gi_render::preset::load_file(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let mut r = Renderer::new(gpu(), default_scene(), loaded.settings, 64, 64)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        r.clock.playing = false;
        r.render_frame();
        r.render_frame();
        r.set_explain(Some((32, 40)));
        r.render_frame();
        // Explaining may legitimately find nothing to explain (direct light only).
        let _ = r.explanation();
        for buffer in r.buffers().names() {
            // Depth and array buffers read back through their own paths; a refusal is fine,
            // a validation message is not.
            let _ = r.readback(&buffer);
        }
        drop(r);
        let messages = validation::take();
        if !messages.is_empty() {
            failures.push(format!("{name}: {} message(s), the first: {}", messages.len(), messages[0]));
        }
        println!("{name}: {} validation message(s)", messages.len());
    }
    assert!(
        validation::active(),
        "the loader never reported VK_LAYER_KHRONOS_validation: the layer did not load, so nothing was checked"
    );
    assert!(failures.is_empty(), "validation messages:\n{}", failures.join("\n"));
}

/// gfx-rs/wgpu#10199 in miniature: an encoder that already knows a texture (mip 0 written in an
/// earlier pass) runs one compute pass that writes mip 1 as storage, then reads it as a sampled
/// texture. wgpu 30 records the pass's last use of the mip it did not know (sampled) as the
/// command buffer's start state, so submission leaves mip 1 in SHADER_READ_ONLY while the first
/// dispatch writes it (the layer: InvalidImageLayout, "expects … GENERAL"). Telling the encoder
/// the first use before the pass (`transition_resources`, what `passes/knecht/ism.rs` does
/// before pull-push) avoids it. When a wgpu upgrade fixes the bug, the first assertion fails:
/// then the workaround in the ISM pass can go.
fn wgpus_mip_tracking_still_needs_the_ism_workaround() {
    let ctx = gpu();
    let run = |transition: bool| {
        mip_chain_in_one_pass(&ctx, transition);
        validation::take()
    };
    let without = run(false);
    assert!(
        without.iter().any(|m| m.contains("InvalidImageLayout") || m.contains("09600")),
        "wgpu no longer mistracks a mip written then read in one compute pass (gfx-rs/wgpu#10199 fixed?): \
         remove the transition before pull-push in render/src/passes/knecht/ism.rs; messages: {without:?}"
    );
    let with = run(true);
    assert!(with.is_empty(), "the transition before the pass did not avoid the layout error: {with:?}");
}

const MIP_CHAIN: &str = r"
@group(0) @binding(0) var dst: texture_storage_2d<rgba8unorm, write>;
@compute @workgroup_size(1) fn write_mip() { textureStore(dst, vec2<i32>(0, 0), vec4<f32>(1.0)); }
@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var dst2: texture_storage_2d<rgba8unorm, write>;
@compute @workgroup_size(1) fn copy_down() { textureStore(dst2, vec2<i32>(0, 0), textureLoad(src, vec2<i32>(0, 0), 0)); }
";

/// Writes mip 1 of a 3-mip texture, then copies it into mip 0, in one compute pass, and
/// submits, twice; with `transition`, each encoder first learns that mip 1's first use is
/// storage.
fn mip_chain_in_one_pass(ctx: &GpuContext, transition: bool) {
    let d = &ctx.device;
    let texture = d.create_texture(&wgpu::TextureDescriptor {
        label: Some("test.mip_chain"),
        size: wgpu::Extent3d { width: 4, height: 4, depth_or_array_layers: 1 },
        mip_level_count: 3,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    });
    let mip = |level| {
        texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("test.mip_chain.level"),
            base_mip_level: level,
            mip_level_count: Some(1),
            ..Default::default()
        })
    };
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("test.mip_chain"),
        source: wgpu::ShaderSource::Wgsl(MIP_CHAIN.into()),
    });
    let pipeline = |entry| {
        d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    };
    let (write, copy) = (pipeline("write_mip"), pipeline("copy_down"));
    let (m0, m1) = (mip(0), mip(1));
    let write_group = |view| {
        d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("test.mip_chain.write"),
            layout: &write.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(view) }],
        })
    };
    let (write_0, write_1) = (write_group(&m0), write_group(&m1));
    let copy_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("test.mip_chain.copy"),
        layout: &copy.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&m1) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&m0) },
        ],
    });
    // Twice: the first submission also zero-initialises the texture, and those clears tell the
    // command buffer the mips' state before the pass; the second finds them initialised.
    for _ in 0..2 {
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("test.mip_chain") });
        {
            // Mip 0 first, in a pass of its own: the encoder then knows the texture but not
            // mips 1 and 2 (as the ISM's copy into level 0 does before pull-push).
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("test.mip_chain.0"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&write);
            pass.set_bind_group(0, &write_0, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        if transition {
            enc.transition_resources(
                std::iter::empty(),
                std::iter::once(wgpu::TextureTransition {
                    texture: &texture,
                    selector: Some(wgpu::wgt::TextureSelector { mips: 1..2, layers: 0..1 }),
                    state: wgpu::TextureUses::STORAGE_WRITE_ONLY,
                }),
            );
        }
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("test.mip_chain"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&write);
            pass.set_bind_group(0, &write_1, &[]);
            pass.dispatch_workgroups(1, 1, 1);
            pass.set_pipeline(&copy);
            pass.set_bind_group(0, &copy_group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        ctx.queue.submit([enc.finish()]);
    }
    let _ = d.poll(wgpu::PollType::wait_indefinitely());
}
