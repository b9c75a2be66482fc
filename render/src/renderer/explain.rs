//! Explain a pixel (issue #42): the renderer's side. `set_explain` pins a pixel; every frame
//! then replays its gather after the steps that lit it (`chain::explain`; Soler's stage
//! replays inside its run, bounce by bounce), and `explanation` (blocking: the command line,
//! tests) or `explanation_later` (the window, without waiting) decode it (`crate::explain`);
//! the near/far mix joins the far field's replay with Soler's (`NearFar`). Tests:
//! `tests/tests/explain/`.

use crate::explain::{Explanation, Replay};
use crate::readback::{Readback, Readout};
use crate::renderer::Renderer;
use crate::settings::pipeline::{Gather, NearField, Reconstruction, ShadingPoints, VplSource};

/// The read-back key of the explanation: one per stage choices, so that a copy made before
/// the choices changed is never decoded by another technique's replay.
fn key(p: &crate::settings::pipeline::PipelineSettings) -> String {
    format!("explain.{:?}.{:?}.{:?}.{:?}", p.vpl_source, p.shading_points, p.gather, p.near_field)
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
        let ddgi = p.gather == Gather::Probes;
        (!vpl_gather && !gautron && !soler && !hcb && !reference && !ddgi).then(|| {
            format!(
                "explaining a pixel is written for the VPL gather at every pixel or interleaved tiles, \
                 the exact-VPL reference, the HCB's samples, Gautron's records, Soler's levels (and \
                 their mixes) and DDGI's probes; not for {:?} VPLs gathered by {:?} at {:?} ({:?}, {:?})",
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
        if self.settings.pipeline.gather == Gather::Probes {
            return Ok(self.stages.explain_ddgi.as_ref().ok_or_else(none)?);
        }
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
