//! Explain a pixel (issue #42), the recording side: the replay steps that follow the steps
//! that lit the pinned pixel (the VPL gather at tiles or pixels with its filter and merge, the
//! exact reference around its gather, the HCB's splatting, Gautron's splat of records; Soler's
//! stage replays inside its run, bounce by bounce). `renderer::explain` reads and decodes them.

use super::{Flow, Recorder, StagePasses};
use crate::passes::gautron::explain::{GautronExplainPass, GautronInfo};
use crate::passes::knecht::explain::{ChainInfo, ExplainInputs, VplExplainPass};
use crate::passes::knecht::temporal::MergeOrder;
use crate::passes::stages::FrameInputs;
use crate::settings::pipeline::{Gather, NearField, Reconstruction, ShadingPoints, Temporal};

/// The pinned pixel, when it lies in the G-buffer.
fn pinned(f: &FrameInputs, x: &StagePasses) -> Option<(u32, u32)> {
    let (w, h) = f.gbuffer_size;
    x.explain_pixel.filter(|p| p.0 < w && p.1 < h)
}

/// The replay of the pinned pixel's VPL gather at tiles or pixels, with its filter and
/// confidence merge (`passes::knecht::explain`), after the frame's chain wrote `last`.
pub(super) fn vpl_gather(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let p = &f.settings.pipeline;
    let (Some(pixel), Some((vpls, vis)), Some(last)) = (pinned(f, x), flow.vpl_light(), flow.light.as_ref()) else {
        return Some(());
    };
    if !matches!(p.shading_points, ShadingPoints::EveryPixel | ShadingPoints::InterleavedTiles) {
        return Some(());
    }
    let Some(interleave) = x.interleave.as_ref() else { return Some(()) };
    let filter = p.reconstruction == Reconstruction::GeometryAwareFilter;
    let temporal = (p.temporal == Temporal::ConfidenceMerge).then_some(f.settings.temporal.order);
    let merge_first = super::merges_first(f.settings);
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
    let pass = x.explain_vpl.get_or_insert_with(|| VplExplainPass::new(f.ctx));
    pass.run(f.ctx, r.enc, &inputs, info);
    Some(())
}

/// The replay of the pinned pixel's splat of Gautron's irradiance records (lit by
/// their hemispheres or, GI Lab's mix, by the VPLs; `passes::gautron::explain`), after the
/// stage's last splat and its resolve wrote `indirect` (`gautron.indirect`).
pub(super) fn gautron(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let (Some(pixel), Some(indirect)) = (pinned(f, x), flow.light.as_ref()) else { return Some(()) };
    if f.settings.pipeline.shading_points != ShadingPoints::IrradianceRecords {
        return Some(());
    }
    // From the next frame on, the stage keeps the cache as each of its splats read it.
    if let Some(g) = x.gautron.as_mut() {
        let slots = f.settings.gautron.rounds + 1;
        let size = g.records.size();
        if !g.snapshots.as_ref().is_some_and(|s| s.capacity == size && s.slots >= slots) {
            g.snapshots = Some(crate::passes::gautron::explain::Snapshots::new(f.ctx, size, slots));
        }
    }
    let Some(stage) = x.gautron.as_ref() else { return Some(()) };
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
    pass.run(f, r.enc, stage.explain_parts(), indirect, info);
    Some(())
}

/// The replay of the pinned pixel's coherence splatting of the HCB's samples (Nguyen
/// et al. §4.2–4.3, Eq. 8–11; `passes::hcb::explain`), lit by the VPL gather at the samples
/// or, GI Lab's mixes, by Soler's ring gather or Gautron's hemispheres there, after the chain
/// wrote `last`: `hcb.indirect`, or `temporal.history` when the confidence merge follows (the
/// sample cache, stage 7's other choice, acts in stages 5–6, before the splat's sums).
pub(super) fn hcb(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let p = &f.settings.pipeline;
    let (Some(pixel), Some(last)) = (pinned(f, x), flow.light.as_ref()) else { return Some(()) };
    if p.shading_points != ShadingPoints::HcbSamples {
        return Some(());
    }
    let Some(stage) = x.hcb.as_ref() else { return Some(()) };
    let merge = p.temporal == Temporal::ConfidenceMerge;
    let temporal = match (merge, x.temporal.as_ref()) {
        (false, _) => None,
        (true, Some(t)) => Some(t),
        (true, None) => return Some(()),
    };
    let info = crate::passes::hcb::explain::HcbInfo {
        pixel,
        cache: p.temporal == Temporal::HcbSampleCache,
        merge,
        buffer: if merge { "temporal.history" } else { "hcb.indirect" }.into(),
        technique: hcb_words(f),
    };
    let pass = x.explain_hcb.get_or_insert_with(|| crate::passes::hcb::explain::HcbExplainPass::new(f.ctx));
    pass.run(f, r.enc, stage, temporal, last, info);
    Some(())
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

/// The exact-VPL reference's replay before its gather: the average the batch folds into.
pub(super) fn reference_before(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    reference(f, x, r, flow, true)
}

/// The exact-VPL reference's replay after its gather: the batch's terms and what it wrote.
pub(super) fn reference_after(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    reference(f, x, r, flow, false)
}

/// The exact-VPL reference's replay (`passes::reference::explain`): `before` the gather, the
/// average it folds into; after it, the batch's terms and what it wrote.
fn reference(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &Flow, before: bool) -> Option<()> {
    use crate::passes::reference::explain::{ReferenceExplainPass, ReferenceInputs, ReferenceRun};
    let (Some(pixel), Some(vpls), Some(reference)) = (pinned(f, x), flow.vpls.as_ref(), x.reference.as_ref()) else {
        return Some(());
    };
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
        pass.run_before(f.ctx, r.enc, &inputs, run);
    } else {
        pass.run_after(f.ctx, r.enc, &inputs);
    }
    Some(())
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

/// The replay of the pinned pixel's eight probes (`passes::ddgi::explain`), after the probes
/// lit it.
pub(super) fn ddgi(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, _: &mut Flow) -> Option<()> {
    let Some(pixel) = pinned(f, x) else { return Some(()) };
    let (Some(stage), slot) = (x.ddgi.as_ref(), &mut x.explain_ddgi) else { return Some(()) };
    let Some((probes, indirect)) = stage.explain_parts() else { return Some(()) };
    let pass = slot.get_or_insert_with(|| crate::passes::ddgi::explain::DdgiExplainPass::new(f.ctx));
    let inputs = crate::passes::ddgi::explain::ExplainInputs {
        probes,
        g: f.gbuffer,
        camera: f.camera_buffer,
        indirect: &indirect,
    };
    pass.record(f.ctx, r.enc, &inputs, pixel);
    Some(())
}
