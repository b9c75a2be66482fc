//! Creates, resizes or drops the passes of stages 3–7 (and the emitters' of stage 2) when the
//! stage choices, the scene or the size change: each choice brings its passes
//! (docs/architecture.md, "The frame as a list").

use super::StagePasses;
use crate::gpu::GpuContext;
use crate::lab_settings::LabSettings;
use crate::passes::ddgi::stage::DdgiStage;
use crate::passes::emitters::EmitterPass;
use crate::passes::gautron::stage::GautronStage;
use crate::passes::hcb::stage::HcbStage;
use crate::passes::knecht::interleave::InterleavePass;
use crate::passes::knecht::stage::KnechtVpls;
use crate::passes::knecht::temporal::TemporalPass;
use crate::passes::reference::stage::ReferenceVpls;
use crate::passes::soler::stage::SolerStage;
use crate::scene::upload::GpuScene;
use crate::scene::{Scene, SceneState};
use crate::settings::pipeline::{ShadingPoints, Temporal};

/// What the passes size themselves by.
pub(crate) struct Needs<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a Scene,
    pub gpu_scene: &'a GpuScene,
    /// The scene at this instant (its lights: Knecht's VPL budget per light view).
    pub state: &'a SceneState,
    pub settings: &'a LabSettings,
    /// The G-buffer's width and height.
    pub size: (u32, u32),
    /// How many light views the lights of `state` have.
    pub light_views: usize,
    /// The scene's bounds, and the room the camera stands in when it stands in one (DDGI's
    /// grid spans one of them).
    pub bounds: crate::maths::Aabb,
    pub room: Option<crate::maths::Aabb>,
}

/// Whether stage 2 keeps the direct light's diffuse part apart: Soler's first bounce gathers
/// it (`soler.sender` Diffuse, 004 §5.3).
pub(crate) fn needs_direct_diffuse(s: &LabSettings) -> bool {
    s.pipeline.uses_soler() && s.soler.sender == crate::passes::soler::Sender::Diffuse
}

impl StagePasses {
    /// Makes the passes the stage choices of `n.settings` name and drops the others; true when
    /// a pass was created, dropped or remade (its buffers must be registered again).
    pub(crate) fn ensure(&mut self, n: &Needs) -> bool {
        let (ctx, s, state) = (n.ctx, n.settings, n.state);
        let p = &s.pipeline;
        let (w, h) = n.size;
        let mut fresh = false;
        if s.emitters.enabled && n.scene.has_emitters() {
            let created = self.emitters.is_none();
            let e = self.emitters.get_or_insert_with(|| EmitterPass::new(ctx));
            fresh |= e.ensure(ctx, n.scene, state, n.gpu_scene, s) | created;
        } else {
            fresh |= self.emitters.take().is_some();
        }
        if p.uses_knecht_vpls() {
            let created = self.knecht.is_none();
            let k = self.knecht.get_or_insert_with(|| KnechtVpls::new(ctx, s));
            fresh |= k.ensure(ctx, n.scene, state, n.gpu_scene, s, n.light_views) | created;
        } else {
            fresh |= self.knecht.take().is_some();
        }
        if p.is_reference() {
            let created = self.reference.is_none();
            let r = self.reference.get_or_insert_with(|| ReferenceVpls::new(ctx, n.gpu_scene, s, w, h));
            fresh |= r.ensure(ctx, s) | created;
        } else {
            fresh |= self.reference.take().is_some();
        }
        let tiles = match p.shading_points {
            ShadingPoints::EveryPixel => Some(1),
            ShadingPoints::InterleavedTiles => Some(s.interleave.n),
            ShadingPoints::HcbSamples | ShadingPoints::MipLevels | ShadingPoints::IrradianceRecords => None,
        };
        match tiles.filter(|_| p.uses_knecht_vpls()) {
            Some(tiles) => {
                let created = self.interleave.is_none();
                let split = s.interleave.split_passes;
                let i = self.interleave.get_or_insert_with(|| InterleavePass::new(ctx, w, h, tiles, split));
                fresh |= i.ensure(ctx, w, h, tiles, split) | created;
            }
            None => fresh |= self.interleave.take().is_some(),
        }
        if p.uses_hcb() {
            let created = self.hcb.is_none();
            let hcb = self.hcb.get_or_insert_with(|| HcbStage::new(ctx, s, w, h));
            fresh |= hcb.ensure(ctx, s, w, h) | created;
        } else {
            fresh |= self.hcb.take().is_some();
        }
        if p.uses_knecht_vpls() && p.temporal == Temporal::ConfidenceMerge {
            let created = self.temporal.is_none();
            let t = self.temporal.get_or_insert_with(|| TemporalPass::new(ctx, w, h));
            fresh |= t.resize(ctx, w, h) | created;
        } else {
            fresh |= self.temporal.take().is_some();
        }
        if p.uses_soler() {
            let created = self.soler.is_none();
            let temporal = p.soler_temporal();
            let st = self.soler.get_or_insert_with(|| {
                let mut st = SolerStage::new(ctx, &s.soler, w, h, temporal);
                st.open_meshes = crate::passes::soler::voxels::open_meshes(n.scene);
                st
            });
            fresh |= st.ensure(ctx, &s.soler, w, h, temporal) | created;
        } else {
            fresh |= self.soler.take().is_some();
        }
        if p.uses_gautron() {
            let created = self.gautron.is_none();
            let st = self.gautron.get_or_insert_with(|| GautronStage::new(ctx, n.gpu_scene, &s.gautron, w, h));
            fresh |= st.ensure(ctx, &s.gautron, w, h) | created;
        } else {
            fresh |= self.gautron.take().is_some();
        }
        if p.uses_ddgi() {
            if self.ddgi.is_none() && self.ddgi_error.is_none() {
                match DdgiStage::new(ctx, n.scene, state, (w, h)) {
                    Ok(st) => self.ddgi = Some(st),
                    Err(e) => {
                        log::error!("DDGI: {e}");
                        self.ddgi_error = Some(e);
                    }
                }
                fresh = true;
            }
            if let Some(st) = self.ddgi.as_mut() {
                let fit = crate::passes::ddgi::stage::fit_box(&s.ddgi, n.bounds, n.room);
                fresh |= st.ensure(ctx, &s.ddgi, fit, (w, h));
            }
        } else {
            fresh |= self.ddgi.take().is_some();
            self.ddgi_error = None;
        }
        fresh
    }
}
