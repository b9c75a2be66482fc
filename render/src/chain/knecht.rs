//! Knecht's steps (docs/readings.md, "Knecht"): VPLs by importance warping (002 §3.3,
//! stage 3), their imperfect shadow maps (§3.4, stage 4), the gather at interleaved tiles or
//! every pixel (§3.5, stages 5–6), the geometry-aware filter (§3.5.2, Eq. 4.2) and the
//! confidence merge (§3.5.1, Eq. 3.3; stage 7), in the order `temporal.order` says.

use super::{Flow, Recorder, StagePasses};
use crate::lab_settings::LabSettings;
use crate::passes::knecht::interleave::ShadeInputs;
use crate::passes::knecht::stage::FirstBounceSource;
use crate::passes::knecht::temporal::{FusedFilter, MergeOrder};
use crate::passes::knecht::vpl_importance::ReceiverBrdf;
use crate::passes::stages::FrameInputs;
use crate::settings::pipeline::{Reconstruction, ShadingPoints, Temporal};
use crate::timing::PassRec;

/// Stage 3: this frame's VPLs of every light view and bounce (and the emitters' first bounce).
pub(super) fn vpls(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let emitters = x.emitters.as_mut().map(|e| e as &mut dyn FirstBounceSource);
    flow.vpls = Some(x.knecht.as_mut()?.vpls(f, r.enc, r.timer, emitters));
    Some(())
}

/// Stage 4: the imperfect shadow maps of the VPLs, pulled and pushed.
pub(super) fn visibility(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let vpls = flow.vpls.as_ref()?;
    flow.vis = Some(x.knecht.as_mut()?.visibility(f, r.enc, r.timer, vpls)?);
    Some(())
}

/// Stages 5–6: the VPL gather at interleaved tiles (n > 1) or every pixel, merged back to the
/// screen (`indirect.merged`).
pub(super) fn gather(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let (vpls, vis) = flow.vpl_light()?;
    let i = x.interleave.as_mut()?;
    let diffuse = f.settings.vpl.receiver_brdf == ReceiverBrdf::DiffuseOnly;
    let inputs = ShadeInputs {
        camera: f.camera_buffer,
        g: f.gbuffer,
        vpls: &vpls.list,
        count: vpls.count,
        min_distance: vpls.min_distance,
        near_cut: vpls.near_cut,
        vis,
        diffuse_only: diffuse,
    };
    i.shade(f.ctx, r.enc, r.timer, &inputs);
    flow.light = Some(crate::passes::view(&i.merged, "indirect.merged"));
    Some(())
}

/// Stage 6's geometry-aware filter (`indirect.filtered`).
pub(super) fn filter(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    // Knecht's thesis merges, then filters (§4 steps 11–12; `temporal.order` MergeThenFilter);
    // we filter first by default because the confidence's illumination term (Eq. 3.3) then
    // compares the filtered light, an estimate from all N VPLs, with the history instead of one
    // pixel's N/n² VPLs, whose noise alone drove the confidence down and kept flicker high
    // (measured in tests/knecht_quality.rs). The demodulated filter (issue #51) reads this
    // frame's irradiance beside the gathered light; after the thesis' merge its input is the
    // history, which has none.
    let src = flow.light.take()?;
    let i = x.interleave.as_ref()?;
    let (ctx, s, depth_range) = (f.ctx, &f.settings.interleave, f.depth_range());
    let irradiance =
        (s.demodulate && !merges_first(f.settings)).then(|| crate::passes::view(&i.irradiance, "indirect.irradiance"));
    r.timer.scope(ctx, r.enc, "interleave.filter", |e, slot| {
        i.filter(PassRec { ctx, enc: e, slot }, s, depth_range, &src, f.gbuffer, irradiance.as_ref())
    });
    flow.light = Some(crate::passes::view(&i.filtered, "indirect.filtered"));
    Some(())
}

/// Stage 7's confidence merge with the reprojected history (`temporal.history`).
pub(super) fn merge(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let src = flow.light.take()?;
    // The demodulated merge (issue #51) keeps the irradiance beside the light.
    let irradiance = merge_irradiance(f, x);
    let t = x.temporal.as_mut()?;
    (t.store_confidence, t.decode_normals) = (stores_confidence(f), f.read_back.reads("temporal.prev_normal"));
    let (ctx, s, depth_range) = (f.ctx, &f.settings.temporal, f.depth_range());
    r.timer.scope(ctx, r.enc, "temporal", |e, slot| {
        t.run(PassRec { ctx, enc: e, slot }, s, depth_range, &src, f.gbuffer, irradiance.as_ref())
    });
    flow.light = Some(crate::passes::view(t.history(), "temporal.history"));
    Some(())
}

/// Whether the frame's merge stores `temporal.confidence` (issue #53): while a pixel is
/// explained (the replays read it) or a read-back of this frame copies it; otherwise it is
/// computed when read, by the same pass storing it alone.
fn stores_confidence(f: &FrameInputs) -> bool {
    f.explain_pixel.is_some() || f.read_back.reads("temporal.confidence")
}

/// Stages 6–7 in one pass when the filter precedes the merge (issue #53): the geometry-aware
/// filter of the gathered light fused into the confidence merge
/// (`TemporalPass::run_fused`); `indirect.filtered` and its irradiance are filled from the
/// same inputs only when read. While a pixel is explained, or a read-back of this frame copies
/// the filter's output, the two passes run as [`filter`] and [`merge`].
pub(super) fn filter_and_merge(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let apart = ["indirect.filtered", "indirect.filtered_irradiance"].iter().any(|n| f.read_back.reads(n));
    if f.explain_pixel.is_some() || apart {
        filter(f, x, r, flow)?;
        return merge(f, x, r, flow);
    }
    let gathered = flow.light.take()?;
    let demodulate = merge_irradiance(f, x).is_some();
    let (ctx, depth_range) = (f.ctx, f.depth_range());
    let i = x.interleave.as_ref()?;
    let s = &f.settings.interleave;
    let irradiance = s.demodulate.then(|| crate::passes::view(&i.irradiance, "indirect.irradiance"));
    let params = i.prepare_fused(ctx, s, depth_range, &gathered, f.gbuffer, irradiance.as_ref());
    let t = x.temporal.as_mut()?;
    (t.store_confidence, t.decode_normals) = (stores_confidence(f), f.read_back.reads("temporal.prev_normal"));
    let filter = FusedFilter { demodulate, params, irradiance: irradiance.as_ref() };
    r.timer.scope(ctx, r.enc, "temporal.filter_merge", |e, slot| {
        let rec = PassRec { ctx, enc: e, slot };
        t.run_fused(rec, &f.settings.temporal, depth_range, &gathered, f.gbuffer, filter)
    });
    flow.light = Some(crate::passes::view(t.history(), "temporal.history"));
    Some(())
}

/// The irradiance the demodulated confidence merge keeps (`temporal.demodulate`, issue #51):
/// after the demodulated geometry-aware filter its window mean (`indirect.filtered_irradiance`),
/// after the HCB's coherence splatting the splatted irradiance (`hcb.irradiance`); None where
/// the merge blends the reflected light (the thesis' merge, or no irradiance to keep).
fn merge_irradiance(f: &FrameInputs, x: &StagePasses) -> Option<wgpu::TextureView> {
    let (s, p) = (f.settings, &f.settings.pipeline);
    if p.temporal != Temporal::ConfidenceMerge || !s.temporal.demodulate {
        return None;
    }
    match p.reconstruction {
        Reconstruction::GeometryAwareFilter if s.interleave.demodulate && !merges_first(s) => {
            x.interleave.as_ref().map(|i| crate::passes::view(&i.filtered_irradiance, "indirect.filtered_irradiance"))
        }
        Reconstruction::CoherenceSplatting if p.shading_points == ShadingPoints::HcbSamples => {
            x.hcb.as_ref().map(|h| crate::passes::view(&h.splat.irradiance, "hcb.irradiance"))
        }
        _ => None,
    }
}

/// Whether stage 7's confidence merge runs before the geometry-aware filter (`temporal.order`
/// MergeThenFilter, when both run).
pub(crate) fn merges_first(s: &LabSettings) -> bool {
    let p = &s.pipeline;
    p.reconstruction == Reconstruction::GeometryAwareFilter
        && p.temporal == Temporal::ConfidenceMerge
        && s.temporal.order == MergeOrder::MergeThenFilter
}
