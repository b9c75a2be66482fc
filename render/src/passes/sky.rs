//! Stage 2, the sky light (issue #18 point 2) as `sky.directions` directional VPLs.
//!
//! The sky has no pass of its own: its directions ([`crate::scene::sky`]: drawn by radiance on
//! a stratified Halton set, irradiance E_j = L(ω_j)/(p(ω_j)·n)) join the frame's punctual
//! lights, so `passes::shadow` renders an exact orthographic shadow map for each (the
//! "directional VPLs with visibility" of the issue), `passes::direct` adds their light at every
//! pixel and at Gautron's hemisphere texels, and stage 3 treats each as a light view (Knecht's
//! importance warping gives the sky its share of the VPL budget by power). What the sky is —
//! on or off, colour or image, intensity, rotation — belongs to the scene (`Scene::sky`, saved
//! in the scene overrides file); how finely the lab samples it is this group.

use crate::scene::WorldLight;
use crate::scene::sky::Sky;
use crate::settings_group;

settings_group! {
    /// The sky light's sampling (stage 2; issue #18): how many directional VPLs stand for it.
    pub struct SkySettings: "sky" {
        /// Directions the sky is sampled in, each a directional light with its own shadow map
        /// (a layer of `direct.shadow_map` at `direct.shadow_map_size`², 4 MiB at 1024²) and
        /// light view. 16 shows banded penumbrae of wide occluders; 64 is smoother.
        directions: u32 = 16,
        unit "directions", symbol "N_sky", range 1..=64, cost "one shadow map (direct.shadow_map_size²) and one light view each, only with the scene's sky on", history true;
    }
}

/// The sky's directional lights, kept while neither the sky nor `sky.directions` changes
/// (an image sky's sampling tables are rebuilt only then).
#[derive(Default)]
pub struct SkyLights {
    key: Option<(Sky, u32)>,
    lights: Vec<WorldLight>,
}

/// Whether two skies light alike (images compared by identity, not texel by texel).
fn same_sky(a: &Sky, b: &Sky) -> bool {
    let image = match (&a.image, &b.image) {
        (None, None) => true,
        (Some((pa, ma)), Some((pb, mb))) => pa == pb && std::sync::Arc::ptr_eq(ma, mb),
        _ => false,
    };
    image
        && a.enabled == b.enabled
        && a.color == b.color
        && a.intensity == b.intensity
        && a.rotation_deg == b.rotation_deg
}

impl SkyLights {
    /// The directional lights of `sky` sampled in `n` directions (empty when it is off).
    pub fn get(&mut self, sky: &Sky, n: u32) -> &[WorldLight] {
        let fresh = self.key.as_ref().is_some_and(|(k, kn)| *kn == n && same_sky(k, sky));
        if !fresh {
            self.lights = sky.world_lights(n);
            self.key = Some((sky.clone(), n));
        }
        &self.lights
    }
}
