//! The light of a scene that has none (issues #18 point 3 and #37 point 3). Most GI test
//! scenes carry no `KHR_lights_punctual` light; the lab adds one so that the first image is
//! not black, and says so (the scene's warnings, shown in the Scene panel and the status bar;
//! the Scene panel's "Remove the default light" takes it away):
//!
//! 1. When the view the scene opens on ([`super::framing`], or its first glTF camera) stands
//!    inside a room (rays up and down hit something, and so do three of the four horizontal
//!    axis directions: a door or a window may open the fourth) and sees something, a **point
//!    light under the ceiling, in the camera's view**: above the point halfway from the
//!    camera to what the centre of the view sees, 80 % of the way up to the ceiling; its
//!    intensity gives the surface in the centre of the view about π W/m² (a white surface
//!    shows radiance ≈ 1 before exposure).
//! 2. Otherwise (an object, an open layout) **a sun and the sky**: a directional light with
//!    shadows at 45° elevation, from behind the camera and 45° to its side, of irradiance π
//!    W/m² (a white surface facing it shows radiance 1), and a neutral constant sky of
//!    radiance 0.25 (π/4 W/m² on an open floor).
//!
//! The path tracer reads the same lights and sky, so the ground truth sees them too.

use glam::{Quat, Vec3};

use super::framing::{ViewKind, ViewPreference, choose_view_with};
use super::{Light, LightKind, Node, Scene, Transform};
use crate::scene::bvh::SceneBvh;

/// The start of the warning that names the added light (the Scene panel and the status bar
/// show it).
pub const NO_LIGHTS: &str = "the scene has no lights";

/// The start of the note that says a scene is lit by its emissive surfaces alone.
pub const LIT_BY_EMITTERS: &str = "the scene is lit by its emissive surfaces";

impl Scene {
    /// Adds the default light when the scene has none (see the module doc). Emissive surfaces
    /// are lights (`passes::emitters`): a scene with them gets no default light, and a note
    /// says what lights it.
    pub fn ensure_light(&mut self) {
        self.ensure_light_with(None);
    }

    /// [`Self::ensure_light`] over a BVH of the scene at time 0 that the caller already has.
    pub fn ensure_light_with(&mut self, bvh: Option<&SceneBvh>) {
        if !self.lights.is_empty() {
            return;
        }
        if self.has_emitters() {
            let state = self.evaluate(0.0);
            let e = super::emitters::Emitters::collect(self, &state);
            self.warnings.push(format!(
                "{LIT_BY_EMITTERS}: {} emissive triangles, {:.3} W in all (no punctual light; turning emitters.enabled off leaves it dark)",
                e.triangles.len(),
                e.luminance_power()
            ));
            return;
        }
        let built;
        let bvh = match bvh {
            Some(b) => b,
            None => {
                built = SceneBvh::new(self, &self.evaluate(0.0));
                &built
            }
        };
        let view = match &self.view {
            Some(v) => v.clone(),
            None => choose_view_with(self, 16.0 / 9.0, ViewPreference::Auto, Some(bvh)),
        };
        let eye = view.camera.position;
        // The framing's interior view stands in a room by construction; a glTF camera is tested.
        let known_inside = view.kind == ViewKind::Interior;
        let inside = light_in_view(bvh, eye, view.camera.forward(), known_inside);
        if let Some((pos, intensity)) = inside {
            self.push_light(
                "default point",
                LightKind::Point,
                intensity,
                Transform { translation: pos, rotation: Quat::IDENTITY, scale: Vec3::ONE },
            );
            let whose = match view.kind {
                ViewKind::SceneCamera { .. } => "its camera, which stands inside a room",
                _ => "the view from inside",
            };
            self.warnings.push(format!(
                "{NO_LIGHTS}: added a point light under the ceiling in the view of {whose}, at {pos:.2}"
            ));
            return;
        }
        // A sun from behind the camera and 45° to its side, 45° up.
        let f = view.camera.forward();
        let back = Vec3::new(-f.x, 0.0, -f.z).normalize_or(Vec3::Z);
        let side = Quat::from_rotation_y(std::f32::consts::FRAC_PI_4) * back;
        let to_sun = (side + Vec3::Y).normalize();
        let rotation = Quat::from_rotation_arc(Vec3::NEG_Z, -to_sun);
        self.push_light(
            "default sun",
            LightKind::Directional,
            std::f32::consts::PI,
            Transform { translation: Vec3::ZERO, rotation, scale: Vec3::ONE },
        );
        let had_sky = self.sky.is_lit();
        if !had_sky {
            self.sky = super::sky::Sky::constant(Vec3::ONE, 0.25);
        }
        self.warnings.push(format!(
            "{NO_LIGHTS}: added a sun (45° up, from behind the camera){} for an open view",
            if had_sky { "" } else { " and a neutral sky" }
        ));
    }

    /// Removes the light the lab added (and the neutral sky it turned on with a sun), with
    /// their note: the user's "Remove the default light".
    pub fn remove_default_light(&mut self) {
        let added_sky = self.warnings.iter().any(|w| w.starts_with(NO_LIGHTS) && w.contains("neutral sky"));
        let keep: Vec<bool> = self.lights.iter().map(|l| !is_default_light(&l.name)).collect();
        let mut new_index = Vec::with_capacity(keep.len());
        let mut next = 0;
        for k in &keep {
            new_index.push(if *k { Some(next) } else { None });
            if *k {
                next += 1;
            }
        }
        for n in &mut self.nodes {
            n.light = n.light.and_then(|i| new_index.get(i).copied().flatten());
        }
        let mut i = 0;
        self.lights.retain(|_| {
            i += 1;
            keep[i - 1]
        });
        if added_sky {
            self.sky.enabled = false;
        }
        self.warnings.retain(|w| !w.starts_with(NO_LIGHTS));
    }

    /// The note on the default light, when the scene got one, or on the emitters that light a
    /// scene without punctual lights.
    pub fn default_light_note(&self) -> Option<&str> {
        self.warnings.iter().find(|w| w.starts_with(NO_LIGHTS) || w.starts_with(LIT_BY_EMITTERS)).map(|w| w.as_str())
    }

    fn push_light(&mut self, name: &str, kind: LightKind, intensity: f32, transform: Transform) {
        self.lights.push(Light { name: name.into(), kind, color: Vec3::ONE, intensity, range: None });
        self.nodes.push(Node {
            name: name.into(),
            transform,
            children: vec![],
            mesh: None,
            light: Some(self.lights.len() - 1),
            camera: None,
        });
        self.roots.push(self.nodes.len() - 1);
    }
}

/// Whether a light of this name is one the lab added ([`Scene::ensure_light`]).
pub fn is_default_light(name: &str) -> bool {
    matches!(name, "default point" | "default sun" | "default spot")
}

/// A point light's place and intensity in the view of a camera at `eye` looking along
/// `forward`, when the camera stands inside a room and sees something; None otherwise.
fn light_in_view(bvh: &SceneBvh, eye: Vec3, forward: Vec3, known_inside: bool) -> Option<(Vec3, f32)> {
    if forward == Vec3::ZERO || !eye.is_finite() {
        return None;
    }
    // Inside a room: something above and below, and walls in at least three of the four
    // horizontal directions (a door or a window may open the fourth).
    let hits = |d: Vec3| bvh.intersect(eye, d, 0.0, f32::INFINITY).is_some();
    let walls = [Vec3::X, -Vec3::X, Vec3::Z, -Vec3::Z].into_iter().filter(|&d| hits(d)).count();
    let room = hits(Vec3::Y) && hits(-Vec3::Y) && walls >= 3;
    if !(known_inside || room) {
        return None;
    }
    let target = bvh.intersect(eye, forward, 0.0, f32::INFINITY)?;
    let mid = eye + forward * (0.5 * target.t);
    let pos = match bvh.intersect(mid, Vec3::Y, 0.0, f32::INFINITY) {
        Some(up) => mid + Vec3::Y * (0.8 * up.t),
        None => mid,
    };
    let d = pos.distance(target.p).max(1e-3);
    Some((pos, std::f32::consts::PI * d * d))
}
