//! Stages 3–7 as a list of steps (issue #52; docs/architecture.md, "The frame as a list").
//! When the stage choices (`pipeline.*`) change, [`StepList::build`] composes them into a list
//! of named steps; `frame.rs` runs the list every frame without knowing any paper. A step
//! reads the frame ([`FrameInputs`]), runs the passes its choice brought ([`StagePasses`]) and
//! hands its output on in the [`Flow`]: stage 3's VPLs, stage 4's visibility, the light so far.
//! Each paper's steps live in its file here (`knecht`, `reference`, `hcb`, `gautron`,
//! `soler`), the replays of a pinned pixel (issue #42) in `explain`; a mix of papers is a list
//! that takes steps from several of them, composed in `build`, never a branch of the frame.

mod ddgi;
mod ensure;
mod explain;
mod gautron;
mod hcb;
mod knecht;
mod reference;
mod soler;

pub(crate) use ensure::{Needs, needs_direct_diffuse};
pub(crate) use knecht::merges_first;

use crate::buffers::BufferRegistry;
use crate::lab_settings::LabSettings;
use crate::passes::emitters::EmitterPass;
use crate::passes::gautron::stage::GautronStage;
use crate::passes::hcb::stage::HcbStage;
use crate::passes::knecht::interleave::InterleavePass;
use crate::passes::knecht::stage::KnechtVpls;
use crate::passes::knecht::temporal::TemporalPass;
use crate::passes::reference::stage::ReferenceVpls;
use crate::passes::soler::stage::SolerStage;
use crate::passes::stages::{FrameInputs, Visibility, VplSet};
use crate::settings::pipeline::{Gather, Reconstruction, ShadingPoints, Temporal, VplSource, VplVisibility};
pub(crate) use crate::timing::Recorder;

/// The passes of stages 3–7, each present while a stage's choice names it, and the emitters'
/// VPLs of stage 2 while the scene has emitters and `emitters.enabled` is on
/// (`Renderer::ensure_passes_for` creates and drops them).
#[derive(Default)]
pub(crate) struct StagePasses {
    /// Emissive surfaces as lights (stage 2; their first bounce in stage 3).
    pub emitters: Option<EmitterPass>,
    /// VPL source "importance warping" with its visibility (Knecht).
    pub knecht: Option<KnechtVpls>,
    /// VPL source "uniform batches": the exact-VPL reference (its visibility, gather and
    /// running average included).
    pub reference: Option<ReferenceVpls>,
    /// Shading points "every pixel" (n = 1) or "interleaved tiles", the VPL gather there and
    /// the geometry-aware filter (Knecht).
    pub interleave: Option<InterleavePass>,
    /// Shading points "HCB samples", their gather, coherence splatting and the sample cache
    /// (Nguyen).
    pub hcb: Option<HcbStage>,
    /// Temporal "confidence merge" (Knecht).
    pub temporal: Option<TemporalPass>,
    /// Shading points "mip levels", the screen-space gather and the upsampling (Soler).
    pub soler: Option<SolerStage>,
    /// Irradiance records, their hemispheres, the splatting and the record cache (Gautron).
    pub gautron: Option<GautronStage>,
    /// DDGI's probes (Majercik et al.), and why they could not be made when they could not
    /// (the scene does not fit the ray caster on this device).
    pub ddgi: Option<crate::passes::ddgi::stage::DdgiStage>,
    pub ddgi_error: Option<String>,
    /// The replay of DDGI's eight probes at the pinned pixel.
    pub explain_ddgi: Option<crate::passes::ddgi::explain::DdgiExplainPass>,
    /// The pinned pixel to explain (issue #42), and the replay of the VPL gather at tiles or
    /// pixels (created when a pixel is first explained).
    pub explain_pixel: Option<(u32, u32)>,
    pub explain_vpl: Option<crate::passes::knecht::explain::VplExplainPass>,
    /// The replay of the exact-VPL reference's batch.
    pub explain_reference: Option<crate::passes::reference::explain::ReferenceExplainPass>,
    /// The replay of Gautron's splat of irradiance records (created when a pixel is first
    /// explained with them).
    pub explain_gautron: Option<crate::passes::gautron::explain::GautronExplainPass>,
    /// The replay of the HCB's coherence splatting (Nguyen et al. §4.2–4.3; created when a
    /// pixel is first explained with HCB samples).
    pub explain_hcb: Option<crate::passes::hcb::explain::HcbExplainPass>,
}

impl StagePasses {
    /// Names this frame's temporal histories in the registry (they ping-pong) and the
    /// splatting's sums.
    pub(crate) fn register_histories(&self, reg: &mut BufferRegistry) {
        if let Some(t) = &self.temporal {
            t.register(reg);
        }
        if let Some(t) = self.soler.as_ref().and_then(|s| s.temporal.as_ref()) {
            t.register(reg);
        }
        if let Some(g) = &self.gautron {
            g.register_sums(reg);
        }
        if let Some(h) = &self.hcb {
            h.register_sums(reg);
        }
    }
}

/// What the steps hand on to the next.
#[derive(Default)]
pub(crate) struct Flow {
    /// Stage 3's VPLs.
    pub vpls: Option<VplSet>,
    /// Stage 4's visibility of them.
    pub vis: Option<Visibility>,
    /// The indirect light so far (the last step's is the frame's).
    pub light: Option<wgpu::TextureView>,
    /// A step ended the list early with its light (the exact reference's complete average).
    pub done: bool,
}

impl Flow {
    /// Stage 3's and 4's outputs, once both ran.
    fn vpl_light(&self) -> Option<(&VplSet, &Visibility)> {
        Some((self.vpls.as_ref()?, self.vis.as_ref()?))
    }
}

/// A step's work. None: a pass its choice needs is missing (which `ensure_passes_for`
/// prevents), and the frame has no indirect light.
pub(crate) type StepFn = fn(&FrameInputs, &mut StagePasses, &mut Recorder, &mut Flow) -> Option<()>;

/// One step of the list: its stage (3–7), its name (the paper's pass, for the docs and the
/// tests) and its work.
#[derive(Clone, Copy)]
pub(crate) struct Step {
    pub stage: u8,
    pub name: &'static str,
    pub run: StepFn,
}

const fn step(stage: u8, name: &'static str, run: StepFn) -> Step {
    Step { stage, name, run }
}

/// Stage 4 "none": every VPL is visible.
fn no_visibility(_: &FrameInputs, _: &mut StagePasses, _: &mut Recorder, flow: &mut Flow) -> Option<()> {
    flow.vis = Some(Visibility::None);
    Some(())
}

/// The steps of the stage choices, built when they change.
#[derive(Default)]
pub(crate) struct StepList {
    /// The choices the list was built for (None: not built yet).
    key: Option<ListKey>,
    /// Stages 3–7's indirect light (empty: direct light only).
    pub indirect: Vec<Step>,
    /// Stage 6's near field (`pipeline.near_field`), added to the indirect light by the compose.
    pub near_field: Vec<Step>,
    /// The step of the last frame that found no pass to run (the frame then had no indirect
    /// light, or no near field); None when every step ran.
    pub failed: Option<&'static str>,
}

impl StepList {
    /// Builds the list again when the stage choices in `s` changed.
    pub(crate) fn update(&mut self, s: &LabSettings) {
        if self.key.as_ref() != Some(&list_key(s)) {
            *self = Self::build(s);
        }
    }

    /// The steps of `s`'s stage choices, in frame order.
    pub(crate) fn build(s: &LabSettings) -> Self {
        let p = &s.pipeline;
        let near_field = if p.gather == Gather::Vpl && p.uses_soler() {
            vec![step(6, "soler.near_field", soler::levels)]
        } else {
            vec![]
        };
        Self { key: Some(list_key(s)), indirect: indirect_steps(s), near_field, failed: None }
    }

    /// Runs the indirect light's steps, then the near field's: (indirect, near field).
    pub(crate) fn run(
        &mut self,
        f: &FrameInputs,
        x: &mut StagePasses,
        r: &mut Recorder,
    ) -> (Option<wgpu::TextureView>, Option<wgpu::TextureView>) {
        let indirect = run(&self.indirect, f, x, r);
        let near_field = run(&self.near_field, f, x, r);
        let failed = indirect.as_ref().err().or(near_field.as_ref().err()).copied();
        if let Some(step) = failed.filter(|_| failed != self.failed) {
            log::warn!("frame: the step {step} found no pass to run; the frame has no indirect light from its list");
        }
        self.failed = failed;
        (indirect.ok().flatten(), near_field.ok().flatten())
    }

    /// The steps' names, stage by stage (the docs' and the tests' view of the list).
    pub(crate) fn names(&self) -> Vec<(u8, &'static str)> {
        self.indirect.iter().chain(&self.near_field).map(|s| (s.stage, s.name)).collect()
    }

    /// Whether a step reads the camera G-buffer's position and normal (`gbuffer.position`,
    /// `gbuffer.normal`), which are then filled in the frame (issue #53,
    /// `passes::gbuffer_position`); `pinned`: a pixel is explained (the `explain.*` steps
    /// run). Knecht's steps read the linear depth and the packed normals and unpack them
    /// themselves; every other step reads the position and the normal.
    pub(crate) fn needs_position(&self, pinned: bool) -> bool {
        const LINEAR_DEPTH: &[&str] = &[
            "knecht.vpls",
            "knecht.visibility",
            "knecht.gather",
            "knecht.filter",
            "knecht.merge",
            "knecht.filter_and_merge",
        ];
        self.indirect
            .iter()
            .chain(&self.near_field)
            .any(|s| !LINEAR_DEPTH.contains(&s.name) && (pinned || !s.name.starts_with("explain.")))
    }

    /// The passes the list's steps keep while the frame is unchanged
    /// (`FrameInputs::unchanged`): the HCB's samples that another gather lights, and
    /// Gautron's hemispheres at them.
    pub(crate) fn kept_when_unchanged(&self) -> Vec<&'static str> {
        let names: Vec<&str> = self.indirect.iter().map(|s| s.name).collect();
        let mut kept = Vec::new();
        if names.contains(&"hcb.build") {
            kept.push("hcb.build");
        }
        if names.contains(&"hcb.select") && names.contains(&"gautron.at_hcb_samples") {
            kept.extend(["hcb.cache.update", "hcb.cache.splat", "hcb.build"]);
        }
        if names.contains(&"gautron.at_hcb_samples") {
            kept.extend(["gautron.create", "gautron.hemispheres"]);
        }
        kept
    }
}

/// What the list depends on: the stage choices and the order of the filter and the merge.
type ListKey = (crate::settings::pipeline::PipelineSettings, crate::passes::knecht::temporal::MergeOrder);

fn list_key(s: &LabSettings) -> ListKey {
    (s.pipeline.clone(), s.temporal.order)
}

/// Runs `steps` in order: the light of the last (None: direct light only), or the name of
/// the step whose pass is missing.
fn run(
    steps: &[Step],
    f: &FrameInputs,
    x: &mut StagePasses,
    r: &mut Recorder,
) -> Result<Option<wgpu::TextureView>, &'static str> {
    let mut flow = Flow::default();
    for s in steps {
        (s.run)(f, x, r, &mut flow).ok_or(s.name)?;
        if flow.done {
            break;
        }
    }
    Ok(flow.light)
}

/// Stages 3–7 of `s`'s choices (the pipeline table of docs/principles.md; the mixes are GI
/// Lab's compositions of the papers' choices, docs/architecture.md).
fn indirect_steps(s: &LabSettings) -> Vec<Step> {
    let p = &s.pipeline;
    let at_hcb_samples = p.shading_points == ShadingPoints::HcbSamples;
    match p.gather {
        Gather::None => vec![],
        // Gautron et al.: irradiance records, their hemispheres, Ward-weight splatting and the
        // record cache, run together; or the hemispheres at the HCB's samples, splatted by
        // coherence (GI Lab's mix).
        Gather::Hemispheres if at_hcb_samples && p.temporal == Temporal::HcbSampleCache => vec![
            step(5, "hcb.select", gautron::select_for_hemispheres),
            step(6, "gautron.at_hcb_samples", gautron::at_hcb_samples),
            step(6, "hcb.splat", hcb::splat),
            step(6, "explain.hcb", explain::hcb),
        ],
        Gather::Hemispheres if at_hcb_samples => vec![
            step(5, "hcb.build", hcb::build_samples),
            step(6, "gautron.at_hcb_samples", gautron::at_hcb_samples),
            step(6, "hcb.splat", hcb::splat),
            step(6, "explain.hcb", explain::hcb),
        ],
        Gather::Hemispheres => {
            vec![step(5, "gautron.records", gautron::hemispheres), step(6, "explain.gautron", explain::gautron)]
        }
        // Soler et al.: mip levels, the ring gather, the joint bilateral upsampling and Eq. 6's
        // warped blend; or the ring gather at the HCB's samples (GI Lab's mix).
        Gather::ScreenSpace if at_hcb_samples => vec![
            step(5, "hcb.build", hcb::build_samples),
            step(6, "soler.at_hcb_samples", soler::at_hcb_samples),
            step(6, "hcb.splat", hcb::splat),
            step(6, "explain.hcb", explain::hcb),
        ],
        Gather::ScreenSpace => vec![step(5, "soler.levels", soler::levels)],
        // Majercik et al.: the probes' trace, update and reading at every pixel.
        Gather::Probes => vec![step(6, "ddgi.probes", ddgi::probes), step(6, "explain.ddgi", explain::ddgi)],
        Gather::Vpl => vpl_steps(s),
    }
}

/// A VPL gather's steps: stage 3's source, stage 4's visibility, then the shading points,
/// the gather, the reconstruction and the temporal choice.
fn vpl_steps(s: &LabSettings) -> Vec<Step> {
    let p = &s.pipeline;
    let mut list = match p.vpl_source {
        VplSource::None => return vec![],
        VplSource::ImportanceWarping => vec![step(3, "knecht.vpls", knecht::vpls)],
        VplSource::UniformBatches => vec![step(3, "reference.vpls", reference::vpls)],
    };
    list.push(match (p.vpl_visibility, p.vpl_source) {
        (VplVisibility::None, _) => step(4, "visibility.none", no_visibility),
        (_, VplSource::UniformBatches) => step(4, "reference.visibility", reference::visibility),
        _ => step(4, "knecht.visibility", knecht::visibility),
    });
    // GI Lab's mix with Gautron et al.: irradiance records lit by the VPLs (stages 5–7 are
    // Gautron's creation, splatting and cache).
    if p.shading_points == ShadingPoints::IrradianceRecords {
        list.push(step(5, "gautron.records_lit_by_vpls", gautron::lit_by_vpls));
        list.push(step(6, "explain.gautron", explain::gautron));
        return list;
    }
    // Stages 5–6: the shading points and the gather there. The HCB sample cache (stage 7's
    // choice) acts in the selection (Nguyen §5, Fig. 5); the reference's gather folds the
    // batch into its running average (stage 7), replayed around it.
    match (p.vpl_source, p.shading_points) {
        (VplSource::UniformBatches, _) => list.extend([
            step(6, "explain.reference_before", explain::reference_before),
            step(6, "reference.gather", reference::gather),
            step(6, "explain.reference_after", explain::reference_after),
        ]),
        (_, ShadingPoints::HcbSamples) => {
            list.extend([step(5, "hcb.select", hcb::select), step(6, "hcb.gather_and_splat", hcb::gather_and_splat)])
        }
        _ => list.push(step(6, "knecht.gather", knecht::gather)),
    }
    // Stages 6–7: the geometry-aware filter and the confidence merge, in the order
    // `temporal.order` says when both run. Coherence splatting ran with the HCB's gather; the
    // sample cache in its selection; the running average in the reference's gather.
    let filter =
        (p.reconstruction == Reconstruction::GeometryAwareFilter).then(|| step(6, "knecht.filter", knecht::filter));
    let merge = (p.temporal == Temporal::ConfidenceMerge).then(|| step(7, "knecht.merge", knecht::merge));
    if merges_first(s) {
        list.extend(merge.into_iter().chain(filter));
    } else if filter.is_some() && merge.is_some() {
        // Filter, then merge: one pass (issue #53, `knecht::filter_and_merge`).
        list.push(step(7, "knecht.filter_and_merge", knecht::filter_and_merge));
    } else {
        list.extend(filter.into_iter().chain(merge));
    }
    // A pinned pixel's replay (issue #42), after the chain that lit it.
    match p.shading_points {
        ShadingPoints::HcbSamples => list.push(step(7, "explain.hcb", explain::hcb)),
        ShadingPoints::EveryPixel | ShadingPoints::InterleavedTiles if p.vpl_source == VplSource::ImportanceWarping => {
            list.push(step(7, "explain.vpl_gather", explain::vpl_gather))
        }
        _ => {}
    }
    list
}
