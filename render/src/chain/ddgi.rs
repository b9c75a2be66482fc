//! DDGI's step (issue #56 point 3; Majercik et al. 2019 §3, 2021 §4–5): the probes' trace and
//! update, and the reading at every pixel, in one step of stages 5–7 (the hysteresis is the
//! probes' own history).

use super::{Flow, Recorder, StagePasses};
use crate::passes::stages::FrameInputs;

/// Stages 5–7: the probes updated and read at every pixel (`ddgi.indirect`).
pub(super) fn probes(f: &FrameInputs, x: &mut StagePasses, r: &mut Recorder, flow: &mut Flow) -> Option<()> {
    flow.light = Some(x.ddgi.as_mut()?.run(f, r.enc, r.timer));
    Some(())
}
