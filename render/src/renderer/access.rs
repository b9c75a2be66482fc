//! Reading the renderer's results back (timings, buffers, statistics, probes) and the
//! shader hot reload.

use std::sync::Arc;

use crate::readback::{Arrived, Readback, Readout};

use glam::Mat4;

use super::Renderer;
use crate::buffers::{BufferError, BufferRegistry, ImageF32};
use crate::camera::Camera;
use crate::passes::compose::ComposePass;
use crate::passes::direct::DirectPass;
use crate::passes::gbuffer::GBufferPass;
use crate::passes::hcb::stage::HcbStats;
use crate::passes::knecht::ism::MAX_BOUNCES;
use crate::passes::shadow::ShadowPass;
use crate::scene::{Aabb, Scene};
use crate::timing::{GpuTimer, PassTiming};

/// A voxel grid read back: width, height, 32-bit words per column, the columns row-major.
pub type VoxelBits = (u32, u32, u32, Vec<u32>);

impl Renderer {
    /// The bits of Soler's voxel grid of the i-th gathered level, read back for tests; None
    /// without visibility.
    pub fn soler_voxel_bits(&self, i: usize) -> Option<Result<VoxelBits, String>> {
        let v = &self.stages.soler.as_ref()?.voxels;
        self.soler_voxel_level_bits(v.gathered().get(i)?.level)
    }

    /// The bits of Soler's voxel grid of pyramid level `level` (0: the screen's, with
    /// `soler.voxel_resolution = Screen`), read back for tests; None without that grid.
    pub fn soler_voxel_level_bits(&self, level: u32) -> Option<Result<VoxelBits, String>> {
        let v = &self.stages.soler.as_ref()?.voxels;
        let g = v.grids.iter().find(|g| g.level == level)?;
        let bytes = (g.width * g.height * v.words) as u64 * 4;
        Some(crate::buffers::read_storage(&self.ctx, &g.buffer, bytes).map(|b| {
            let bits = b.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect();
            (g.width, g.height, v.words, bits)
        }))
    }

    /// Rebuilds the passes whose shaders are among `entries` (entry modules, as listed in
    /// `shaders::ENTRY_MODULES`) from the current shader sources — the shader hot reload.
    /// Only those passes are recreated; their history restarts. If any new pipeline fails
    /// to build, every old pass is kept and the error is returned. Returns the passes
    /// rebuilt.
    pub fn reload_shaders(&mut self, entries: &[&str]) -> Result<Vec<&'static str>, String> {
        let mut passes: Vec<&'static str> = entries.iter().filter_map(|e| pass_of_shader(e)).collect();
        if let Some(i) = passes.iter().position(|p| *p == "vpl_shadow") {
            passes.swap_remove(i);
            passes.extend(["exact_vpl", "instant_radiosity"]);
        }
        passes.sort();
        passes.dedup();
        // The exact-VPL passes exist only while that technique is on.
        passes.retain(|p| *p != "exact_vpl" || self.stages.reference.is_some());
        passes.retain(|p| *p != "instant_radiosity" || self.stages.knecht.is_some());
        passes.retain(|p| *p != "soler" || self.stages.soler.is_some());
        passes.retain(|p| *p != "gautron" || self.stages.gautron.is_some());
        passes.retain(|p| *p != "ddgi" || self.stages.ddgi.is_some());
        // The replays of a pinned pixel exist once a pixel was explained.
        let x = &self.stages;
        let replays = x.explain_vpl.is_some()
            || x.explain_gautron.is_some()
            || x.explain_hcb.is_some()
            || x.soler.as_ref().is_some_and(|s| s.explain.is_some())
            || x.explain_reference.is_some()
            || x.explain_ddgi.is_some();
        passes.retain(|p| *p != "explain" || replays);
        if passes.is_empty() {
            return Ok(passes);
        }
        let ctx = self.ctx.clone();
        let (w, h) = (self.width, self.height);
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let gbuffer = passes.contains(&"gbuffer").then(|| GBufferPass::new(&ctx, &self.gpu_scene, w, h));
        let shadow = passes.contains(&"direct.shadow").then(|| ShadowPass::new(&ctx, &self.gpu_scene));
        let direct = passes.contains(&"direct").then(|| DirectPass::new(&ctx, w, h));
        let compose = passes.contains(&"compose").then(|| ComposePass::new(&ctx, w, h));
        let explain = (passes.contains(&"explain") && self.stages.explain_vpl.is_some())
            .then(|| crate::passes::knecht::explain::VplExplainPass::new(&ctx));
        let explain_gautron = (passes.contains(&"explain") && self.stages.explain_gautron.is_some())
            .then(|| crate::passes::gautron::explain::GautronExplainPass::new(&ctx));
        let explain_soler = (passes.contains(&"explain")
            && self.stages.soler.as_ref().is_some_and(|s| s.explain.is_some()))
        .then(|| crate::passes::soler::explain::SolerExplainPass::new(&ctx));
        let explain_reference = (passes.contains(&"explain") && self.stages.explain_reference.is_some())
            .then(|| crate::passes::reference::explain::ReferenceExplainPass::new(&ctx));
        let explain_hcb = (passes.contains(&"explain") && self.stages.explain_hcb.is_some())
            .then(|| crate::passes::hcb::explain::HcbExplainPass::new(&ctx));
        let explain_ddgi = (passes.contains(&"explain") && self.stages.explain_ddgi.is_some())
            .then(|| crate::passes::ddgi::explain::DdgiExplainPass::new(&ctx));
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(e.to_string());
        }
        if let Some(g) = gbuffer {
            self.gbuffer = g;
            self.camera_group = crate::passes::gbuffer::CAMERA_BINDINGS.group_labelled(
                &ctx.device,
                "frame.camera",
                &self.gbuffer.camera_layout,
                [self.camera_buffer.as_entire_binding()],
            );
        }
        if let Some(p) = shadow {
            self.shadow = p;
        }
        if let Some(p) = direct {
            self.direct = p;
        }
        if let Some(p) = compose {
            self.compose = p;
        }
        if let Some(p) = explain {
            self.stages.explain_vpl = Some(p);
        }
        if let (Some(p), Some(st)) = (explain_soler, self.stages.soler.as_mut()) {
            st.explain = Some(p);
        }
        if let Some(p) = explain_reference {
            self.stages.explain_reference = Some(p);
        }
        if let Some(p) = explain_gautron {
            self.stages.explain_gautron = Some(p);
        }
        if let Some(p) = explain_hcb {
            self.stages.explain_hcb = Some(p);
        }
        if let Some(p) = explain_ddgi {
            self.stages.explain_ddgi = Some(p);
        }
        if passes.contains(&"exact_vpl") {
            let old = self.stages.reference.take();
            let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
            self.ensure_passes();
            if let Some(e) = pollster::block_on(scope.pop()) {
                self.stages.reference = old;
                return Err(e.to_string());
            }
        }
        if passes.contains(&"instant_radiosity") {
            let x = &mut self.stages;
            let old = (x.knecht.take(), x.interleave.take(), x.hcb.take(), x.temporal.take());
            let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
            self.ensure_passes();
            if let Some(e) = pollster::block_on(scope.pop()) {
                let x = &mut self.stages;
                (x.knecht, x.interleave, x.hcb, x.temporal) = old;
                return Err(e.to_string());
            }
        }
        if passes.contains(&"soler") {
            let old = self.stages.soler.take();
            let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
            self.ensure_passes();
            if let Some(e) = pollster::block_on(scope.pop()) {
                self.stages.soler = old;
                return Err(e.to_string());
            }
        }
        if passes.contains(&"gautron") {
            let old = self.stages.gautron.take();
            let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
            self.ensure_passes();
            if let Some(e) = pollster::block_on(scope.pop()) {
                self.stages.gautron = old;
                return Err(e.to_string());
            }
        }
        if passes.contains(&"ddgi") {
            let old = self.stages.ddgi.take();
            let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
            self.ensure_passes();
            if let Some(e) = pollster::block_on(scope.pop()) {
                self.stages.ddgi = old;
                return Err(e.to_string());
            }
        }
        self.register_all();
        self.reset_history();
        Ok(passes)
    }

    /// DDGI's probes of a frame or two ago for the probe overlay, with every probe's rays when
    /// `rays`; never waits (None until they arrive, or while DDGI is not the gather).
    pub fn ddgi_overlay_later(&self, rays: bool) -> Option<crate::passes::ddgi::stage::ProbeOverlay> {
        let st = self.stages.ddgi.as_ref()?;
        let key = if rays { "ddgi.overlay.rays" } else { "ddgi.overlay" };
        let a = self.read_later(key, Readback::Storage(st.overlay_sources(rays)?), 0)?;
        match &a.data {
            Ok(Readout::Bytes(parts)) => st.overlay_from(parts),
            _ => None,
        }
    }

    /// Why DDGI's stage could not be made on this scene (the ray caster's message), if so.
    pub fn ddgi_error(&self) -> Option<&str> {
        self.stages.ddgi_error.as_deref()
    }

    /// DDGI's probes, when they are the gather (tests read their buffers back).
    pub fn ddgi(&self) -> Option<&crate::passes::ddgi::stage::DdgiStage> {
        self.stages.ddgi.as_ref()
    }

    /// Gautron et al.'s passes, when the hemisphere gather is on (tests and the bench read its
    /// records and counters).
    pub fn gautron(&self) -> Option<&crate::passes::gautron::stage::GautronStage> {
        self.stages.gautron.as_ref()
    }

    /// Gautron et al.'s passes, to change (tests choose how the VPL-lit records are lit,
    /// `VplRecordPass::wide`).
    pub fn gautron_mut(&mut self) -> Option<&mut crate::passes::gautron::stage::GautronStage> {
        self.stages.gautron.as_mut()
    }

    /// The HCB's passes, when its samples are the shading points (tests choose the gather's
    /// shape, `HcbGatherPass::wide`).
    pub fn hcb_mut(&mut self) -> Option<&mut crate::passes::hcb::stage::HcbStage> {
        self.stages.hcb.as_mut()
    }

    /// Timings of the last frame.
    /// Stages 3–7 of this frame as the list of steps the stage choices compose (`chain`):
    /// (stage, step) in frame order, the near field's last.
    pub fn frame_steps(&self) -> Vec<(u8, &'static str)> {
        self.steps.names()
    }

    /// The step of the last frame that found no pass to run (None: every step ran).
    pub fn failed_step(&self) -> Option<&'static str> {
        self.steps.failed
    }

    pub fn timings(&self) -> &[PassTiming] {
        self.timer.last()
    }

    pub fn timing_source(&self) -> crate::timing::TimingSource {
        self.timer.source()
    }

    /// Measures the passes with `source` from the next frame on (GPU timestamps fall back to
    /// the wall clock where the device has none).
    pub fn set_timing_source(&mut self, source: crate::timing::TimingSource) {
        self.timer = GpuTimer::with_source(&self.ctx, source);
        self.timer.set_no_wait(self.interactive);
    }

    pub fn buffers(&self) -> &BufferRegistry {
        &self.registry
    }

    /// Reads a registered buffer back (layer 0, level 0).
    /// The HCB's samples of the last frame (Nguyen §3.6, Table 1's statistics): the count
    /// per level, the texels per level and the covered pixels that no sample reached. None
    /// when the technique is not the HCB or no frame was rendered with it. Blocks until the
    pub fn hcb_stats(&self) -> Option<HcbStats> {
        self.stages.hcb.as_ref()?.stats(&self.ctx, self.settings.hcb.d_max(self.scale_radius()))
    }

    /// Why the shadow maps render at a smaller size than `direct.shadow_map_size` asks: the
    /// atlas at that size did not fit the device (None when they render as asked).
    pub fn shadow_note(&self) -> Option<&str> {
        self.shadow.fitted.as_deref()
    }

    /// The emitters of the last frame (issue #18): emissive triangles, their power, the VPLs on
    /// them and stage 3's share for their first bounce. None while emitters are off or the
    /// scene has none.
    pub fn emitter_stats(&self) -> Option<crate::passes::emitters::EmitterStats> {
        Some(self.stages.emitters.as_ref()?.stats)
    }

    /// The VPLs of the last frame (`vpl.list`): instant radiosity's (Knecht §3.3), or the
    /// exact-VPL reference's last batch, in slot order; position and incident flux of every
    /// filled slot. None when no VPL source runs or no frame was rendered with it. Blocks
    /// until the list is on the CPU.
    pub fn vpl_list(&self) -> Option<Vec<crate::passes::reference::vpl::GpuVpl>> {
        let (buffer, bytes) = self.vpl_source()?;
        Some(decode_vpls(&crate::buffers::read_storage(&self.ctx, &buffer, bytes).ok()?))
    }

    /// Every slot of the last frame's VPL list, empty ones included (slot k at index k, as the
    /// gather and the explanations number them). Blocks.
    pub fn vpl_slots(&self) -> Option<Vec<crate::passes::reference::vpl::GpuVpl>> {
        let (buffer, bytes) = self.vpl_source()?;
        let raw = crate::buffers::read_storage(&self.ctx, &buffer, bytes).ok()?;
        Some(bytemuck::pod_collect_to_vec(&raw))
    }

    /// [`Self::vpl_list`] of a frame or two ago, without waiting (the window's overlay).
    pub fn vpl_list_later(&self) -> Option<Vec<crate::passes::reference::vpl::GpuVpl>> {
        let source = self.vpl_source()?;
        let a = self.read_later("vpl.list", Readback::Storage(vec![source]), 0)?;
        match &a.data {
            Ok(Readout::Bytes(parts)) => Some(decode_vpls(parts.first()?)),
            _ => None,
        }
    }

    /// The buffer of the last frame's VPLs and its filled bytes.
    fn vpl_source(&self) -> Option<(wgpu::Buffer, u64)> {
        let (buffer, count) = if self.settings.pipeline.uses_knecht_vpls() {
            let k = self.stages.knecht.as_ref()?;
            if k.frames == 0 {
                return None;
            }
            let count = (self.settings.vpl.count * self.settings.vpl.bounces.clamp(1, MAX_BOUNCES)).min(k.vpl.capacity);
            (&k.vpl.vpls, count)
        } else if self.settings.pipeline.is_reference() {
            let x = self.stages.reference.as_ref()?;
            if x.batches == 0 {
                return None;
            }
            (&x.sample.vpls, self.settings.reference.vpls_per_frame.min(x.sample.capacity))
        } else {
            return None;
        };
        let size = std::mem::size_of::<crate::passes::reference::vpl::GpuVpl>() as u64;
        Some((buffer.clone(), count as u64 * size))
    }

    pub fn readback(&self, name: &str) -> Result<ImageF32, BufferError> {
        self.registry.readback(&self.ctx, name, 0, 0)
    }

    /// The tone-mapped image (Rgba8Unorm with an Rgba8UnormSrgb view format).
    /// The raw value of every registered buffer at each pixel (see
    /// [`BufferRegistry::probe`]); blocks until the values are on the CPU.
    pub fn probe(&self, pixels: &[(u32, u32)]) -> Result<Vec<Vec<crate::buffers::ProbeValue>>, BufferError> {
        let probe = self.depth_probe.get_or_init(|| crate::buffers::DepthProbe::new(&self.ctx));
        self.registry.probe(&self.ctx, probe, self.size(), pixels)
    }

    /// The last frame's memory traffic per pass, in bytes, in pass order
    /// (`counters::traffic`: what each pass binds, from the formats and sizes).
    pub fn traffic(&self) -> &[(String, u64)] {
        &self.traffic
    }

    /// Asks for `what` under `key` (with the caller's `tag`), copied at the end of the next
    /// frame, and returns the newest copy of `key` that has arrived; never waits
    /// (`crate::readback`).
    pub fn read_later(&self, key: &str, what: Readback, tag: u64) -> Option<Arc<Arrived>> {
        self.readbacks.lock().ok()?.request(key, what, tag)
    }

    /// The newest arrived copy of `key`, without asking for another.
    pub fn read_latest(&self, key: &str) -> Option<Arc<Arrived>> {
        self.readbacks.lock().ok()?.latest(key)
    }

    /// Drops `key`'s read-backs (its pane or overlay closed).
    pub fn read_forget(&self, key: &str) {
        if let Ok(mut r) = self.readbacks.lock() {
            r.forget(key);
        }
    }

    /// [`Self::hcb_stats`] without waiting: the statistics of a frame or two ago, None
    /// until they arrive (the window's panes and overlay).
    pub fn hcb_stats_later(&self) -> Option<HcbStats> {
        let h = self.stages.hcb.as_ref()?;
        let a = self.read_later("hcb.stats", Readback::Storage(h.stats_sources()), 0)?;
        match &a.data {
            Ok(Readout::Bytes(parts)) => h.stats_from(parts, self.settings.hcb.d_max(self.scale_radius())),
            _ => None,
        }
    }

    /// Gautron's cache counters (and with `records` its records) of a frame or two ago,
    /// without waiting; None until they arrive or without a Gautron stage.
    pub fn gautron_state_later(
        &self,
        records: bool,
    ) -> Option<(crate::passes::gautron::CacheState, Option<Vec<crate::passes::gautron::GpuRecord>>)> {
        let g = self.stages.gautron.as_ref()?;
        let key = if records { "gautron.records" } else { "gautron.state" };
        let a = self.read_later(key, Readback::Storage(g.state_sources(records)), 0)?;
        match &a.data {
            Ok(Readout::Bytes(parts)) => crate::passes::gautron::stage::GautronStage::state_from(parts),
            _ => None,
        }
    }

    pub fn final_ldr(&self) -> &wgpu::Texture {
        &self.compose.ldr
    }

    /// The camera uniform's view-projection for the current size (for CPU references).
    /// The meshes Soler's voxel visibility treats wrongly (not closed), while it is on.
    pub fn voxel_visibility_open_meshes(&self) -> &[(String, usize)] {
        match &self.stages.soler {
            Some(st) if self.settings.soler.visibility => &st.open_meshes,
            _ => &[],
        }
    }

    pub fn view_proj(&self) -> Mat4 {
        self.camera.view_proj(self.width as f32 / self.height as f32)
    }
}

/// The pass (as `Renderer::reload_shaders` names it) that an entry module's pipelines
/// belong to; None for shaders outside the frame (the viewer's).
pub fn pass_of_shader(entry: &str) -> Option<&'static str> {
    Some(match entry {
        "gbuffer/gbuffer.wgsl" | "gbuffer/position.wgsl" | "gbuffer/no_emission.wgsl" | "gbuffer/material.wgsl" => {
            "gbuffer"
        }
        "shadow/shadow.wgsl" => "direct.shadow",
        "direct/direct.wgsl" => "direct",
        "compose/compose.wgsl" | "compose/tonemap.wgsl" | "compose/luminance.wgsl" => "compose",
        "reference/sample.wgsl" | "reference/gather.wgsl" => "exact_vpl",
        // The exact cube-face maps serve both VPL techniques.
        "reference/shadow.wgsl" => "vpl_shadow",
        "knecht/vpl/importance.wgsl"
        | "knecht/vpl/reduce.wgsl"
        | "knecht/vpl/warp.wgsl"
        | "knecht/vpl/bounce.wgsl"
        | "knecht/vpl/irsm.wgsl"
        | "knecht/ism/splat.wgsl"
        | "knecht/ism/resolve.wgsl"
        | "knecht/ism/pull_push.wgsl"
        | "knecht/interleave/split.wgsl"
        | "knecht/interleave/gather.wgsl"
        | "knecht/interleave/merge.wgsl"
        | "knecht/interleave/filter.wgsl"
        | "knecht/temporal/confidence.wgsl"
        | "knecht/temporal/filter_merge.wgsl"
        | "hcb/base.wgsl"
        | "hcb/build.wgsl"
        | "hcb/samples.wgsl"
        | "hcb/gather.wgsl"
        | "hcb/splat.wgsl"
        | "hcb/normalize.wgsl"
        | "hcb/cache.wgsl"
        | "hcb/cache_removal.wgsl" => "instant_radiosity",
        "soler/vote.wgsl"
        | "soler/gather.wgsl"
        | "soler/upsample.wgsl"
        | "soler/jbu.wgsl"
        | "soler/resolve.wgsl"
        | "soler/voxelize.wgsl"
        | "soler/voxel_down.wgsl"
        | "soler/voxel_view.wgsl"
        | "soler/temporal.wgsl"
        | "soler/bounces.wgsl"
        | "soler/glossy.wgsl"
        | "soler/ring.wgsl"
        | "soler/ring_texel.wgsl"
        | "soler/hcb_gather.wgsl"
        | "soler/voxel_common.wgsl" => "soler",
        "knecht/interleave/explain.wgsl"
        | "gautron/explain.wgsl"
        | "soler/explain.wgsl"
        | "soler/explain_ring.wgsl"
        | "hcb/explain.wgsl"
        | "reference/explain.wgsl"
        | "ddgi/explain.wgsl" => "explain",
        "gautron/create.wgsl"
        | "gautron/hemisphere.wgsl"
        | "gautron/reduce.wgsl"
        | "gautron/splat.wgsl"
        | "gautron/resolve.wgsl"
        | "gautron/vpl_records.wgsl"
        | "gautron/at_samples.wgsl"
        | "gautron/common.wgsl" => "gautron",
        // DDGI's probes trace through the GPU ray caster and light their hits with the truth's
        // shading.
        "ddgi/probes.wgsl" | "ddgi/lookup.wgsl" | "ddgi/trace.wgsl" | "ddgi/blend.wgsl" | "ddgi/apply.wgsl"
        | "ddgi/view.wgsl" | "rays/scene.wgsl" | "rays/lights.wgsl" | "rays/shade.wgsl" => "ddgi",
        _ => return None,
    })
}

/// The buffer that shows what a timing scope produced (the lab's "hover a pass to see its
/// output"). Every scope of `render_frame` is listed; a test checks it.
pub fn scope_output(scope: &str) -> Option<&'static str> {
    Some(match scope {
        "gbuffer" => "gbuffer.albedo",
        // The camera G-buffer's fills (issue #53), when the frame runs them.
        "gbuffer.position" => "gbuffer.position",
        "gbuffer.no_emission" => "gbuffer.emission",
        "gbuffer.material" => "gbuffer.material",
        "direct.shadow" => "direct.shadow_map",
        "direct" => "direct.radiance",
        "compose" | "compose.luminance" => "final.hdr",
        "compose.tonemap" => "final.ldr",
        "vpl.light_gbuffer" => "vpl.light_gbuffer.albedo",
        "vpl.sample" => "vpl.light_gbuffer.position",
        "vpl.shadow" => "vpl.shadow_atlas",
        "indirect.gather" => "indirect.raw",
        "vpl.importance" => "vpl.importance",
        "ism.splat" => "ism.atlas",
        s if s.starts_with("ism.splat.") || s.starts_with("vpl.bounce.") => "ism.atlas",
        "ism.pull_push" => "ism.atlas_pulled",
        "interleave.split" => "interleave.split.albedo",
        // The fused gather (default) writes the merged light; with `interleave.split_passes`
        // its output is `indirect.accum`, which the merge turns into this.
        "interleave.gather" => "indirect.merged",
        "interleave.merge" => "indirect.merged",
        "temporal" | "temporal.filter_merge" => "temporal.confidence",
        "interleave.filter" => "indirect.filtered",
        "hcb.build" => "hcb.samples",
        "hcb.gather" => "hcb.samples",
        "soler.hcb_gather" => "hcb.samples",
        "hcb.splat" => "hcb.indirect",
        "hcb.cache.update" => "hcb.cache",
        "hcb.cache.recompute" => "hcb.recompute_group",
        "hcb.cache.splat" => "hcb.weight_sum",
        "soler.pyramid" => "soler.level.1.normal",
        "soler.upsample" => "soler.indirect",
        "soler.bounces" => "soler.indirect",
        // One scope per gathered level k (`soler.gather.k`), per bounce b ≥ 2
        // (`soler.bounceb.{pyramid,gather.k,upsample}`).
        s if s.starts_with("soler.gather.") => level_indirect(s.rsplit('.').next()?)?,
        s if s.starts_with("soler.bounce") && s.contains(".gather.") => level_indirect(s.rsplit('.').next()?)?,
        s if s.starts_with("soler.bounce") && s.ends_with(".pyramid") => "soler.level.1.radiance",
        s if s.starts_with("soler.bounce") && s.ends_with(".upsample") => "soler.indirect",
        "soler.voxels" => "soler.voxels.2",
        "soler.temporal" => "soler.temporal",
        "gautron.splat" => "gautron.accum",
        "gautron.create" => "gautron.candidates",
        "gautron.hemispheres" => "gautron.hemisphere.radiance",
        "gautron.resolve" => "gautron.irradiance",
        "ddgi.trace" => "ddgi.rays",
        "ddgi.update" => "ddgi.atlas.irradiance",
        "ddgi.apply" => "ddgi.indirect",
        _ => return None,
    })
}

/// `soler.level.k.indirect` for the level number `k` of a timing scope.
fn level_indirect(k: &str) -> Option<&'static str> {
    const NAMES: [&str; 10] = [
        "soler.level.0.indirect",
        "soler.level.1.indirect",
        "soler.level.2.indirect",
        "soler.level.3.indirect",
        "soler.level.4.indirect",
        "soler.level.5.indirect",
        "soler.level.6.indirect",
        "soler.level.7.indirect",
        "soler.level.8.indirect",
        "soler.level.9.indirect",
    ];
    NAMES.get(k.parse::<usize>().ok()?).copied()
}

/// The camera a scene opens on: its first glTF camera, else the view of
/// [`crate::scene::framing`] (inside its largest room, or a three-quarter view fitted to its
/// geometry), fitted to `aspect`.
impl Renderer {
    /// The length scene-relative settings are fractions of now (`scale.reference`: the room
    /// the camera stands in, else the scene's bounding radius; [`crate::scale`]).
    pub fn scale_radius(&self) -> f32 {
        self.scale().0
    }

    /// [`Self::scale_radius`] and where it comes from (the settings pane says it).
    pub fn scale(&self) -> (f32, crate::scale::ScaleSource) {
        let room = self.scene.view.as_ref().and_then(|v| v.room.as_ref());
        crate::scale::scale_radius(self.settings.scale.reference, room, self.camera.position, self.bounds)
    }
}

pub fn default_camera(scene: &Scene, bounds: Aabb, aspect: f32) -> Camera {
    scene_view(scene, bounds, aspect).camera
}

/// The view a scene opens on and why (the status bar says it): the one the loader stored,
/// else chosen now; an exterior view is fitted again to `aspect`.
pub fn scene_view(scene: &Scene, bounds: Aabb, aspect: f32) -> crate::scene::framing::Framing {
    match &scene.view {
        Some(v) => v.for_aspect(aspect, bounds),
        None => crate::scene::framing::choose_view(scene, aspect, Default::default()),
    }
}

/// The filled VPL slots of a `vpl.list` read-back.
fn decode_vpls(bytes: &[u8]) -> Vec<crate::passes::reference::vpl::GpuVpl> {
    let size = std::mem::size_of::<crate::passes::reference::vpl::GpuVpl>();
    bytemuck::pod_collect_to_vec::<u8, crate::passes::reference::vpl::GpuVpl>(&bytes[..bytes.len() / size * size])
        .into_iter()
        .filter(|v| v.position.w > 0.5)
        .collect()
}
