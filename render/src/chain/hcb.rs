//! Nguyen et al.'s steps (docs/readings.md, "Nguyen"): the hierarchical coherence buffer's
//! levels, masks and samples (§4.1, stage 5; the sample cache of §5 acts in the selection),
//! the gather at the samples and the coherence-weighted splatting (§4.2–4.3, Eq. 8–11,
//! stage 6). The mixes light the samples by another paper's gather between `build_samples`
//! and `splat`.

use super::{Flow, Recorder, StagePasses};
use crate::passes::stages::FrameInputs;

/// Stage 5 without VPLs: this frame's levels, masks and samples, for another gather to light;
/// kept from the last frame when nothing the screen depends on changed (issue #53).
pub(super) fn build_samples(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, _: &mut Flow) -> Option<()> {
    let hcb = x.hcb.as_ref()?;
    if !f.unchanged {
        hcb.build_only(f, r.enc, r.timer);
    }
    Some(())
}

/// Stage 6's coherence splatting of samples another gather lit (`hcb.indirect`).
pub(super) fn splat(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    flow.light = Some(x.hcb.as_ref()?.splat_only(f, r.enc, r.timer));
    Some(())
}

/// Stage 5 with VPLs: the cached samples validated, the due ones re-gathered and splatted
/// first, then the build (Nguyen §5, Fig. 5).
pub(super) fn select(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let light = flow.vpl_light()?;
    x.hcb.as_mut()?.select(f, r.enc, r.timer, light);
    Some(())
}

/// Stage 6: the VPL gather at the (new) samples and the splatting (`hcb.indirect`).
pub(super) fn gather_and_splat(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let light = flow.vpl_light()?;
    let view = x.hcb.as_ref()?.gather_and_splat(f, r.enc, r.timer, light);
    flow.light = Some(view);
    Some(())
}
