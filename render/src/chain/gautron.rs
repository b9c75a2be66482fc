//! Gautron et al.'s steps (docs/readings.md, "Gautron"): irradiance records created where
//! the splatted weights fall short, lit by their rasterised hemispheres (§3) or, GI Lab's mix,
//! by the VPL gather, splatted with Ward's weight (Eq. 1–2) and kept by the record cache
//! (§4); or the hemispheres at the HCB's samples (GI Lab's mix).

use super::{Flow, Recorder, StagePasses};
use crate::passes::gautron::at_samples::SampleSet;
use crate::passes::stages::FrameInputs;

/// Stages 5–7: records lit by their hemispheres (`gautron.indirect`).
pub(super) fn hemispheres(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    flow.light = Some(x.gautron.as_mut()?.run(f, r.enc, r.timer, None));
    Some(())
}

/// Stages 5–7: records lit by stage 3's VPLs through stage 4's visibility (GI Lab's mix).
pub(super) fn lit_by_vpls(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let light = flow.vpl_light()?;
    let view = x.gautron.as_mut()?.run(f, r.enc, r.timer, Some(light));
    flow.light = Some(view);
    Some(())
}

/// Stage 6: a hemisphere at each of the HCB's samples (GI Lab's mix), for its splat; with
/// the HCB's sample cache (stage 7's choice, issue #53) only at the cached samples due for
/// recomputation and the new ones. The samples and their light are kept from the last frame
/// when nothing the screen depends on changed (issue #53: the samples, the scene the
/// hemispheres see and its light are the same).
pub(super) fn at_hcb_samples(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, _: &mut Flow) -> Option<()> {
    let (hcb, gautron) = (x.hcb.as_ref()?, x.gautron.as_mut()?);
    if f.unchanged {
        return Some(());
    }
    let set = match hcb.recompute_queue() {
        Some(queue) => SampleSet::DueAndNew(queue),
        None => SampleSet::All,
    };
    if let Err(e) = gautron.gather_at_samples(f, r.enc, r.timer, hcb.sample_buffers(), set) {
        log::warn!("gautron: the HCB's sample count could not be read: {e}");
    }
    Some(())
}

/// Stage 5 of the hemisphere mix with the HCB's sample cache (Nguyen §5, Fig. 5; issue #53):
/// last frame's samples validated and splatted (with their earlier light: that splat decides
/// by its weights where the build adds samples), and the build; the due and the new samples
/// then get their hemispheres ([`at_hcb_samples`]). Kept, as the build is, while the frame
/// is unchanged.
pub(super) fn select_for_hemispheres(
    f: &FrameInputs,
    x: &mut StagePasses,
    r: &mut Recorder,
    _: &mut Flow,
) -> Option<()> {
    let (hcb, gautron) = (x.hcb.as_mut()?, x.gautron.as_mut()?);
    if f.unchanged {
        return Some(());
    }
    if hcb.update_cache(f, r.enc, r.timer) {
        gautron.cached_splat_args(f, r.enc, hcb.sample_buffers());
    }
    hcb.build_after_cache(f, r.enc, r.timer);
    Some(())
}
