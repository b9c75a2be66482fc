//! Explain a pixel (issue #42): the renderer's side. `set_explain` pins a pixel; every frame
//! then replays its gather after the passes that lit it (`explain_vpl_gather`, called by
//! `frame.rs`), and `explanation` (blocking: the command line, tests) or `explanation_later`
//! (the window, without waiting) decode it (`crate::explain`).

use crate::explain::{Explanation, Replay};
use crate::passes::knecht::explain::{ChainInfo, ExplainInputs, VplExplainPass};
use crate::passes::knecht::temporal::MergeOrder;
use crate::pipeline::{Gather, NearField, Reconstruction, ShadingPoints, Temporal, VplSource};
use crate::readback::{Readback, Readout};
use crate::renderer::{Renderer, StagePasses};
use crate::stages::{FrameInputs, Visibility, VplSet};

/// The read-back key of the explanation.
const KEY: &str = "explain";

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
    let merge_first = filter && temporal == Some(MergeOrder::MergeThenFilter);
    let buffer = if merge_first || (filter && temporal.is_none()) {
        "indirect.filtered"
    } else if temporal.is_some() {
        "temporal.history"
    } else {
        "indirect.merged"
    };
    let info = ChainInfo {
        pixel,
        count: vpls.count,
        filter,
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
        temporal: temporal.and_then(|_| x.temporal.as_ref()),
        last,
    };
    let camera = crate::passes::bgl::uniform(0, wgpu::ShaderStages::COMPUTE);
    let pass = x.explain_vpl.get_or_insert_with(|| VplExplainPass::new(f.ctx, camera));
    pass.run(f.ctx, enc, &inputs, info);
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
        words.push("far field only (the near field's screen-space light is not explained)".into());
    }
    words.join(", ")
}

impl Renderer {
    /// Pins `pixel` for explaining (None: none); from the next frame on, each frame replays
    /// its gather.
    pub fn set_explain(&mut self, pixel: Option<(u32, u32)>) {
        if pixel.is_none() {
            self.read_forget(KEY);
        }
        self.stages.explain_pixel = pixel;
    }

    pub fn explain_pixel(&self) -> Option<(u32, u32)> {
        self.stages.explain_pixel
    }

    /// Why the current stage choices cannot be explained yet (None: they can).
    pub fn explain_unsupported(&self) -> Option<String> {
        let p = &self.settings.pipeline;
        let vpl_gather = p.gather == Gather::Vpl
            && p.vpl_source == VplSource::ImportanceWarping
            && matches!(p.shading_points, ShadingPoints::EveryPixel | ShadingPoints::InterleavedTiles);
        (!vpl_gather).then(|| {
            format!(
                "explaining a pixel is written for instant radiosity's VPL gather at every pixel or at \
                 interleaved tiles (with its filter and confidence merge); not yet for {:?} VPLs gathered \
                 by {:?} at {:?} ({:?}, {:?})",
                p.vpl_source, p.gather, p.shading_points, p.reconstruction, p.temporal
            )
        })
    }

    /// The replay of the current stage choices, once a frame ran with a pinned pixel.
    fn replay(&self) -> Result<&dyn Replay, String> {
        let none = || "no frame was rendered with a pinned pixel".to_string();
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
        let a = self.read_later(KEY, Readback::Storage(replay.parts()?), 0)?;
        match &a.data {
            Ok(Readout::Bytes(parts)) => {
                Some(replay.decode(parts).ok_or_else(|| "the replay's output did not match its frame".into()))
            }
            Ok(_) => None,
            Err(e) => Some(Err(e.clone())),
        }
    }
}
