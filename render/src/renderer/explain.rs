//! Explain a pixel (issue #42): the renderer's side. `set_explain` pins a pixel; every frame
//! then replays its gather after the passes that lit it (`explain_vpl_gather`,
//! `explain_reference`, `explain_hcb`, `explain_gautron`, called by `frame.rs` after their
//! stages; Soler's stage replays inside its run, bounce by bounce), and `explanation` (blocking: the command line, tests) or
//! `explanation_later` (the window, without waiting) decode it (`crate::explain`); the
//! near/far mix joins the far field's replay with Soler's (`NearFar`). Tests:
//! `tests/tests/explain/`.

use crate::explain::{Explanation, Replay};
use crate::passes::gautron::explain::{GautronExplainPass, GautronInfo};
use crate::passes::knecht::explain::{ChainInfo, ExplainInputs, VplExplainPass};
use crate::passes::knecht::temporal::MergeOrder;
use crate::pipeline::{Gather, NearField, Reconstruction, ShadingPoints, Temporal, VplSource};
use crate::readback::{Readback, Readout};
use crate::renderer::{Renderer, StagePasses};
use crate::stages::{FrameInputs, Visibility, VplSet};

/// The read-back key of the explanation: one per stage choices, so that a copy made before
/// the choices changed is never decoded by another technique's replay.
fn key(p: &crate::pipeline::PipelineSettings) -> String {
    format!("explain.{:?}.{:?}.{:?}.{:?}", p.vpl_source, p.shading_points, p.gather, p.near_field)
}

/// Records the replay of the pinned pixel's VPL gather at tiles or pixels, with its filter and
/// confidence merge (`passes::knecht::explain`), after the frame's chain wrote `last`.
pub(crate) fn explain_vpl_gather(
    f: &FrameInputs,
    x: &mut StagePasses,
    enc: &mut wgpu::CommandEncoder,
    vpls: &VplSet,
    vis: &Visibility,
    last: &wgpu::TextureView,
) {
    let p = &f.settings.pipeline;
    let Some(pixel) = x.explain_pixel else { return };
    if !matches!(p.shading_points, ShadingPoints::EveryPixel | ShadingPoints::InterleavedTiles) {
        return;
    }
    let Some(interleave) = x.interleave.as_ref() else { return };
    let (w, h) = f.gbuffer_size;
    if pixel.0 >= w || pixel.1 >= h {
        return;
    }
    let filter = p.reconstruction == Reconstruction::GeometryAwareFilter;
    let temporal = (p.temporal == Temporal::ConfidenceMerge).then_some(f.settings.temporal.order);
    let merge_first = crate::frame::merges_first(f.settings);
    let buffer = if merge_first || (filter && temporal.is_none()) {
        "indirect.filtered"
    } else if temporal.is_some() {
        "temporal.history"
    } else {
        "indirect.merged"
    };
    // The demodulated filter (issue #51) when it ran on this frame's gather.
    let demodulated = filter && !merge_first && f.settings.interleave.demodulate;
    let info = ChainInfo {
        pixel,
        count: vpls.count,
        filter,
        demodulated,
        temporal,
        buffer: buffer.into(),
        sources: vpls.sources.clone(),
        technique: chain_words(f),
    };
    let s = &f.settings;
    let inputs = ExplainInputs {
        pixel,
        camera: f.camera_buffer,
        g: f.gbuffer,
        interleave,
        vpls: &vpls.list,
        vis,
        filter: filter.then(|| (s.interleave.alpha * f.depth_range(), s.interleave.beta)),
        demodulated,
        temporal: temporal.and(x.temporal.as_ref()),
        last,
    };
    let camera = crate::gpu::bgl::uniform(0, wgpu::ShaderStages::COMPUTE);
    let pass = x.explain_vpl.get_or_insert_with(|| VplExplainPass::new(f.ctx, camera));
    pass.run(f.ctx, enc, &inputs, info);
}

/// Records the replay of the pinned pixel's splat of Gautron's irradiance records (lit by
/// their hemispheres or, GI Lab's mix, by the VPLs; `passes::gautron::explain`), after the
/// stage's last splat and its resolve wrote `indirect` (`gautron.indirect`).
pub(crate) fn explain_gautron(
    f: &FrameInputs,
    x: &mut StagePasses,
    enc: &mut wgpu::CommandEncoder,
    indirect: &wgpu::TextureView,
) {
    let Some(pixel) = x.explain_pixel else { return };
    if f.settings.pipeline.shading_points != ShadingPoints::IrradianceRecords {
        return;
    }
    let (w, h) = f.gbuffer_size;
    if pixel.0 >= w || pixel.1 >= h {
        return;
    }
    // From the next frame on, the stage keeps the cache as each of its splats read it.
    if let Some(g) = x.gautron.as_mut() {
        let slots = f.settings.gautron.rounds + 1;
        let size = g.records.size();
        if !g.snapshots.as_ref().is_some_and(|s| s.capacity == size && s.slots >= slots) {
            g.snapshots = Some(crate::passes::gautron::explain::Snapshots::new(f.ctx, size, slots));
        }
    }
    let Some(stage) = x.gautron.as_ref() else { return };
    let s = &f.settings.gautron;
    let info = GautronInfo {
        pixel,
        accuracy: s.accuracy,
        weight_clamp: s.weight_clamp,
        rotational: s.rotational_gradient,
        translational: s.translational_gradient,
        neighbour_clamping: s.neighbour_clamping,
        frame: f.frame,
        snapshots: false,
        technique: gautron_words(f),
    };
    let pass = x.explain_gautron.get_or_insert_with(|| GautronExplainPass::new(f.ctx));
    pass.run(f, enc, stage.explain_parts(), indirect, info);
}

/// Records the replay of the pinned pixel's coherence splatting of the HCB's samples (Nguyen
/// et al. §4.2–4.3, Eq. 8–11; `passes::hcb::explain`), lit by the VPL gather at the samples
/// or, GI Lab's mixes, by Soler's ring gather or Gautron's hemispheres there, after the chain
/// wrote `last`: `hcb.indirect`, or `temporal.history` when the confidence merge follows (the
/// sample cache, stage 7's other choice, acts in stages 5–6, before the splat's sums).
pub(crate) fn explain_hcb(
    f: &FrameInputs,
    x: &mut StagePasses,
    enc: &mut wgpu::CommandEncoder,
    last: &wgpu::TextureView,
) {
    let p = &f.settings.pipeline;
    let Some(pixel) = x.explain_pixel else { return };
    if p.shading_points != ShadingPoints::HcbSamples {
        return;
    }
    let (w, h) = f.gbuffer_size;
    if pixel.0 >= w || pixel.1 >= h {
        return;
    }
    let Some(stage) = x.hcb.as_ref() else { return };
    let merge = p.temporal == Temporal::ConfidenceMerge;
    let temporal = match (merge, x.temporal.as_ref()) {
        (false, _) => None,
        (true, Some(t)) => Some(t),
        (true, None) => return,
    };
    let info = crate::passes::hcb::explain::HcbInfo {
        pixel,
        cache: p.temporal == Temporal::HcbSampleCache,
        merge,
        buffer: if merge { "temporal.history" } else { "hcb.indirect" }.into(),
        technique: hcb_words(f),
    };
    let pass = x.explain_hcb.get_or_insert_with(|| crate::passes::hcb::explain::HcbExplainPass::new(f.ctx));
    pass.run(f, enc, stage, temporal, last, info);
}

/// The HCB's stage choices, in words.
fn hcb_words(f: &FrameInputs) -> String {
    let p = &f.settings.pipeline;
    let s = &f.settings.hcb;
    let light = match p.gather {
        Gather::ScreenSpace => "Soler's ring gather at the samples (GI Lab's mix)".to_string(),
        Gather::Hemispheres => "Gautron's hemispheres at the samples (GI Lab's mix)".to_string(),
        _ => format!("{:?} VPLs with {:?} visibility", p.vpl_source, p.vpl_visibility),
    };
    let temporal = match p.temporal {
        Temporal::HcbSampleCache => "sample cache (§5)",
        Temporal::ConfidenceMerge => "confidence merge",
        _ => "no cache",
    };
    let near = if p.gather == Gather::Vpl && p.near_field == NearField::ScreenSpace {
        ", far field (the near field's below)"
    } else {
        ""
    };
    format!(
        "HCB samples (Nguyen) lit by {light}, coherence splatting (θ_max = {}°, γ_max = {}°, {:?} splat), \
         {temporal}{near}",
        s.theta_max_deg, s.gamma_max_deg, s.splat
    )
}

/// The exact-VPL reference's replay (`passes::reference::explain`): `before` the gather, the
/// average it folds into; after it, the batch's terms and what it wrote.
pub(crate) fn explain_reference(
    f: &FrameInputs,
    x: &mut StagePasses,
    enc: &mut wgpu::CommandEncoder,
    vpls: &VplSet,
    before: bool,
) {
    use crate::passes::reference::explain::{ReferenceExplainPass, ReferenceInputs, ReferenceRun};
    let Some(pixel) = x.explain_pixel else { return };
    let (w, h) = f.gbuffer_size;
    let Some(reference) = x.reference.as_ref() else { return };
    if pixel.0 >= w || pixel.1 >= h {
        return;
    }
    let inputs = ReferenceInputs {
        camera: f.camera_buffer,
        g: f.gbuffer,
        gather: &reference.gather,
        vpls: &vpls.list,
        atlas: &reference.visibility.atlas_view,
    };
    let pass = x.explain_reference.get_or_insert_with(|| ReferenceExplainPass::new(f.ctx));
    if before {
        let rs = &f.settings.reference;
        let run = ReferenceRun {
            pixel,
            count: vpls.count,
            batch: reference.batches,
            technique: format!(
                "exact-VPL reference: batches of {} VPLs with {:?} visibility, averaged (batch k weighs 1/(k+1))",
                rs.vpls_per_frame, f.settings.pipeline.vpl_visibility
            ),
        };
        pass.run_before(f.ctx, enc, &inputs, run);
    } else {
        pass.run_after(f.ctx, enc, &inputs);
    }
}

/// Gautron's stage choices, in words.
fn gautron_words(f: &FrameInputs) -> String {
    let p = &f.settings.pipeline;
    let s = &f.settings.gautron;
    let light = match p.gather {
        Gather::Vpl => format!(
            "irradiance records lit by {:?} VPLs with {:?} visibility (GI Lab's mix)",
            p.vpl_source, p.vpl_visibility
        ),
        _ => "irradiance records lit by their hemispheres".into(),
    };
    let cache = match p.temporal {
        Temporal::RecordCache => "record cache",
        _ => "no cache",
    };
    format!(
        "{light}, Ward-weight splatting (a = {}, w_max = {}, {:?} splat), {cache}",
        s.accuracy, s.weight_clamp, s.splat
    )
}

/// The stage choices of a VPL gather chain, in words.
fn chain_words(f: &FrameInputs) -> String {
    let p = &f.settings.pipeline;
    let mut words = vec![format!("{:?} VPLs, {:?} visibility", p.vpl_source, p.vpl_visibility)];
    words.push(match p.shading_points {
        ShadingPoints::InterleavedTiles => format!("gather at interleaved tiles (n = {})", f.settings.interleave.n),
        _ => "gather at every pixel".into(),
    });
    if p.reconstruction == Reconstruction::GeometryAwareFilter {
        words.push("geometry-aware filter".into());
    }
    if p.temporal == Temporal::ConfidenceMerge {
        words.push(format!(
            "confidence merge ({})",
            match f.settings.temporal.order {
                MergeOrder::FilterThenMerge => "filter, then merge",
                MergeOrder::MergeThenFilter => "merge, then filter",
            }
        ));
    }
    if p.near_field == NearField::ScreenSpace {
        words.push("far field (the near field's below)".into());
    }
    words.join(", ")
}

/// GI Lab's near/far mix (`pipeline.near_field = ScreenSpace`): the VPL gather's far field and
/// Soler's near field, added by the compose; one explanation of both, checked against the sum
/// of the two buffers.
struct NearFar<'a> {
    far: &'a dyn Replay,
    near: &'a dyn Replay,
}

impl<T: Replay + ?Sized> Replay for &T {
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>> {
        (**self).parts()
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        (**self).decode(parts)
    }
}

impl Replay for NearFar<'_> {
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>> {
        let mut parts = self.far.parts()?;
        parts.extend(self.near.parts()?);
        Some(parts)
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        let n = self.far.parts()?.len();
        let mut far = self.far.decode(parts.get(..n)?)?;
        let near = self.near.decode(parts.get(n..)?)?;
        far.checks.push(near.total_check());
        far.checks.extend(near.checks);
        far.contributions.extend(near.contributions.into_iter().map(|mut c| {
            c.name = format!("near: {}", c.name);
            c
        }));
        far.notes.extend(near.notes);
        far.technique = format!("{}; {}", far.technique, near.technique);
        far.buffer = format!("{} + {}", far.buffer, near.buffer);
        far.value += near.value;
        far.sort();
        Some(far)
    }
}

impl Renderer {
    /// Pins `pixel` for explaining (None: none); from the next frame on, each frame replays
    /// its gather.
    pub fn set_explain(&mut self, pixel: Option<(u32, u32)>) {
        if pixel.is_none() {
            if let Some(g) = self.stages.gautron.as_mut() {
                g.snapshots = None;
            }
            self.read_forget(&key(&self.settings.pipeline));
        }
        self.stages.explain_pixel = pixel;
    }

    pub fn explain_pixel(&self) -> Option<(u32, u32)> {
        self.stages.explain_pixel
    }

    /// Why the current stage choices cannot be explained yet (None: they can).
    pub fn explain_unsupported(&self) -> Option<String> {
        let p = &self.settings.pipeline;
        if p.gather == Gather::None {
            return Some("direct light only (gather: none): the pixel has no indirect light to explain".into());
        }
        let vpl_gather = p.gather == Gather::Vpl
            && p.vpl_source == VplSource::ImportanceWarping
            && matches!(p.shading_points, ShadingPoints::EveryPixel | ShadingPoints::InterleavedTiles);
        // Gautron's irradiance records, lit by their hemispheres or by the VPLs (GI Lab's mix).
        let gautron = p.shading_points == ShadingPoints::IrradianceRecords
            && p.reconstruction == Reconstruction::WeightSplatting
            && (p.gather == Gather::Hemispheres
                || (p.gather == Gather::Vpl && p.vpl_source == VplSource::ImportanceWarping));
        // The exact-VPL reference, while it still gathers batches.
        let reference = p.vpl_source == VplSource::UniformBatches;
        if reference && self.stages.reference.as_ref().is_some_and(|r| r.complete(&self.settings.reference)) {
            return Some(
                "the exact-VPL reference's average is complete: it gathers no more batches to replay \
                 (H restarts it)"
                    .into(),
            );
        }
        // Soler et al.'s levels, every bounce.
        let soler = p.gather == Gather::ScreenSpace && p.shading_points == ShadingPoints::MipLevels;
        // The HCB's coherence splatting, whatever lit its samples (the VPL gather at the
        // samples, Soler's ring gather or Gautron's hemispheres there: GI Lab's mixes).
        let hcb = p.shading_points == ShadingPoints::HcbSamples
            && p.reconstruction == Reconstruction::CoherenceSplatting
            && p.gather != Gather::None;
        (!vpl_gather && !gautron && !soler && !hcb && !reference).then(|| {
            format!(
                "explaining a pixel is written for the VPL gather at every pixel or interleaved tiles, \
                 the exact-VPL reference, the HCB's samples, Gautron's records and Soler's levels (and \
                 their mixes); not for {:?} VPLs gathered by {:?} at {:?} ({:?}, {:?})",
                p.vpl_source, p.gather, p.shading_points, p.reconstruction, p.temporal
            )
        })
    }

    /// The replay of the current stage choices, once a frame ran with a pinned pixel.
    fn replay(&self) -> Result<Box<dyn Replay + '_>, String> {
        let far = self.far_replay()?;
        let p = &self.settings.pipeline;
        if p.gather == Gather::Vpl && p.near_field == NearField::ScreenSpace {
            let near = self.soler_replay().ok_or("the near field was not replayed yet")?;
            return Ok(Box::new(NearFar { far, near }));
        }
        Ok(Box::new(far))
    }

    /// Soler's replay, which the stage runs bounce by bounce (`SolerStage::explain`).
    fn soler_replay(&self) -> Option<&crate::passes::soler::explain::SolerExplainPass> {
        self.stages.soler.as_ref()?.explain.as_ref()
    }

    /// The replay of the stage choices' (far-field) light.
    fn far_replay(&self) -> Result<&dyn Replay, String> {
        let none = || "no frame was rendered with a pinned pixel".to_string();
        if self.settings.pipeline.shading_points == ShadingPoints::IrradianceRecords {
            return Ok(self.stages.explain_gautron.as_ref().ok_or_else(none)?);
        }
        if self.settings.pipeline.shading_points == ShadingPoints::HcbSamples {
            return Ok(self.stages.explain_hcb.as_ref().ok_or_else(none)?);
        }
        if self.settings.pipeline.vpl_source == VplSource::UniformBatches {
            return Ok(self.stages.explain_reference.as_ref().ok_or_else(none)?);
        }
        if self.settings.pipeline.shading_points == ShadingPoints::MipLevels {
            return Ok(self.soler_replay().ok_or_else(none)?);
        }
        Ok(self.stages.explain_vpl.as_ref().ok_or_else(none)?)
    }

    /// The pinned pixel's explanation from the last frame; blocks until it is on the CPU.
    pub fn explanation(&self) -> Result<Explanation, String> {
        if let Some(why) = self.explain_unsupported() {
            return Err(why);
        }
        let replay = self.replay()?;
        let parts = replay.parts().ok_or("no frame was rendered with a pinned pixel")?;
        let bytes =
            parts.iter().map(|(b, n)| crate::buffers::read_storage(&self.ctx, b, *n)).collect::<Result<Vec<_>, _>>()?;
        replay.decode(&bytes).ok_or_else(|| "the replay's output did not match its frame".into())
    }

    /// [`Self::explanation`] of a frame or two ago, without waiting (the window): None until
    /// it arrives.
    pub fn explanation_later(&self) -> Option<Result<Explanation, String>> {
        if let Some(why) = self.explain_unsupported() {
            return Some(Err(why));
        }
        let replay = match self.replay() {
            Ok(r) => r,
            Err(e) => return Some(Err(e)),
        };
        let a = self.read_later(&key(&self.settings.pipeline), Readback::Storage(replay.parts()?), 0)?;
        match &a.data {
            // A copy made before the pixel or the choices changed does not decode: wait for the
            // next.
            Ok(Readout::Bytes(parts)) => replay.decode(parts).map(Ok),
            Ok(_) => None,
            Err(e) => Some(Err(e.clone())),
        }
    }
}
