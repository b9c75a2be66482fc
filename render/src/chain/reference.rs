//! The exact-VPL reference's steps (docs/readings.md, "The exact-VPL reference"): uniform
//! batches of VPLs (stage 3), their exact cube-face maps (stage 4) and the gather at every
//! pixel folded into the running average (stages 6–7). Once the average is complete the list
//! ends with it.

use super::{Flow, Recorder, StagePasses};
use crate::passes::stages::FrameInputs;

/// Stage 3: the next batch; when the average is complete (or there is no light), the list
/// ends with the average.
pub(super) fn vpls(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let emitters = x.emitters.as_ref().filter(|e| e.stats.vpls > 0).map(|e| &e.emitters);
    let reference = x.reference.as_mut()?;
    match reference.vpls(f, r.enc, r.timer, f.view_proj, emitters) {
        Some(batch) => flow.vpls = Some(batch),
        None => {
            flow.light = Some(reference.average());
            flow.done = true;
        }
    }
    Some(())
}

/// Stage 4: the batch's exact cube-face maps (or none, by `pipeline.vpl_visibility`).
pub(super) fn visibility(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let vpls = flow.vpls.as_ref()?;
    flow.vis = Some(x.reference.as_mut()?.visibility(f, r.enc, r.timer, vpls));
    Some(())
}

/// Stages 6–7: the gather at every pixel, folded into the running average (`indirect.accum`).
pub(super) fn gather(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    let (vpls, vis) = flow.vpl_light()?;
    flow.light = Some(x.reference.as_mut()?.gather(f, r.enc, r.timer, vpls, vis));
    Some(())
}
