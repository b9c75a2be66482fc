//! Soler et al.'s steps (docs/readings.md, "Soler"): the mip levels (§5.1, stage 5), the ring
//! gather with its voting filter and voxel visibility (§5.2–5.3), the joint bilateral
//! upsampling (§5.4, stage 6) and Eq. 6's warped blend (stage 7), run together; as the near
//! field beside a VPL gather (`pipeline.near_field`); or the ring gather at the HCB's samples
//! (GI Lab's mix).

use super::{Flow, Recorder, StagePasses};
use crate::passes::stages::FrameInputs;

/// Stages 5–7: the screen-space indirect light (`soler.indirect`), or the near field's.
pub(super) fn levels(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    flow.light = Some(x.soler.as_mut()?.run(f, r.enc, r.timer));
    Some(())
}

/// Stage 6: the ring gather of every level at each of the HCB's samples (GI Lab's mix).
pub(super) fn at_hcb_samples(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, _: &mut Flow) -> Option<()> {
    let (hcb, soler) = (x.hcb.as_ref()?, x.soler.as_ref()?);
    soler.gather_at_samples(f, r.enc, r.timer, hcb.sample_buffers());
    Some(())
}
