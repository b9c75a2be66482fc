//! The light of a scene that has none (issue #18 point 3). Most GI test scenes carry no
//! `KHR_lights_punctual` light; the lab adds one so that the first image is not black, and
//! says so (the scene's warnings, shown in the Scene panel and the status bar):
//!
//! 1. When the scene's first glTF camera stands inside a room (rays up and down hit
//!    something, and so do three of the four horizontal axis directions: a door or a window
//!    may open the fourth) and sees something, a **point light in the camera's view**:
//!    halfway from the camera to what the centre of the view sees, then halfway up to the
//!    ceiling above that point; its intensity gives the surface in the centre of the view
//!    about π W/m² (a white surface shows radiance ≈ 1 before exposure).
//! 2. Otherwise a **spot light looking down** from 85 % of the bounds' height above their
//!    centre, with a cone wide enough to reach the walls — moved under the ceiling when that
//!    place is above one (the first surface straight down is seen from its back: a ceiling
//!    from above, or the roof of a closed room), to 85 % of the way from the floor to it.

use glam::{Quat, Vec3};

use super::{Light, LightKind, Node, Scene, Transform};
use crate::cpu::raycast::TriangleSoup;

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
        let state = self.evaluate(0.0);
        let soup = TriangleSoup::new(self, &state);
        let inside = state.cameras.first().and_then(|c| {
            let eye = c.world.transform_point3(Vec3::ZERO);
            let forward = c.world.transform_vector3(-Vec3::Z).normalize_or_zero();
            light_in_view(&soup, eye, forward)
        });
        if let Some((pos, intensity)) = inside {
            self.push_light(
                "default point",
                LightKind::Point,
                intensity,
                Transform { translation: pos, rotation: Quat::IDENTITY, scale: Vec3::ONE },
            );
            self.warnings.push(format!(
                "{NO_LIGHTS}: added a point light in the view of its camera, which stands inside a room, at {pos:.2}"
            ));
            return;
        }
        let b = self.bounds(0.0);
        let ext = b.extent();
        let c = b.center();
        let mut pos = Vec3::new(c.x, b.min.y + 0.85 * ext.y.max(1e-3), c.z);
        let mut moved = false;
        if let Some(below) = under_the_ceiling(&soup, pos, ext.length().max(1e-3)) {
            pos = below;
            moved = true;
        }
        // Under a found ceiling the floor is what lies below it; otherwise the bounds' bottom
        // (the rule's place and cone unchanged for the scenes it served).
        let floor =
            if moved { soup.intersect_camera(pos, -Vec3::Y).map_or(b.min.y, |h| h.position.y) } else { b.min.y };
        let height = (pos.y - floor).max(1e-3);
        let half_width = 0.5 * ext.x.max(ext.z);
        let outer = (1.5 * half_width / height).atan().clamp(0.5, 1.35);
        // −Z rotated to −Y: the light looks straight down.
        let rotation = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
        let kind = LightKind::Spot { inner_cone: outer * 0.6, outer_cone: outer };
        let intensity = std::f32::consts::PI * height * height;
        self.push_light("default spot", kind, intensity, Transform { translation: pos, rotation, scale: Vec3::ONE });
        self.warnings.push(if moved {
            format!("{NO_LIGHTS}: added a default spot light under the ceiling (the top of its bounds is above a surface seen from behind), at {pos:.2}")
        } else {
            format!("{NO_LIGHTS}: added a default spot light under the top of its bounds, at {pos:.2}")
        });
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

/// A point light's place and intensity in the view of a camera at `eye` looking along
/// `forward`, when the camera stands inside a room and sees something; None otherwise.
fn light_in_view(soup: &TriangleSoup, eye: Vec3, forward: Vec3) -> Option<(Vec3, f32)> {
    if forward == Vec3::ZERO {
        return None;
    }
    // Inside a room: something above and below, and walls in at least three of the four
    // horizontal directions (a door or a window may open the fourth).
    let hits = |d: Vec3| soup.intersect(eye, d, 0.0, f32::INFINITY).is_some();
    let walls = [Vec3::X, -Vec3::X, Vec3::Z, -Vec3::Z].into_iter().filter(|&d| hits(d)).count();
    if !(hits(Vec3::Y) && hits(-Vec3::Y) && walls >= 3) {
        return None;
    }
    let target = soup.intersect(eye, forward, 0.0, f32::INFINITY)?;
    let mid = eye + forward * (0.5 * target.t);
    let pos = match soup.intersect(mid, Vec3::Y, 0.0, f32::INFINITY) {
        Some(up) => mid + Vec3::Y * (0.5 * up.t),
        None => mid,
    };
    let d = pos.distance(target.position).max(1e-3);
    Some((pos, std::f32::consts::PI * d * d))
}

/// When the first surface straight down from `pos` is seen from its back (all faces hit
/// before the front faces), `pos` is above a ceiling: a place 85 % of the way from the floor
/// below that ceiling to it.
fn under_the_ceiling(soup: &TriangleSoup, pos: Vec3, reach: f32) -> Option<Vec3> {
    let any = soup.intersect(pos, -Vec3::Y, 0.0, f32::INFINITY)?;
    let front = soup.intersect_camera(pos, -Vec3::Y).map_or(f32::INFINITY, |h| h.t);
    if any.t >= front - 1e-4 * reach {
        return None;
    }
    let ceiling = any.position.y;
    let start = any.position - Vec3::Y * (1e-4 * reach);
    let floor = soup.intersect_camera(start, -Vec3::Y).map_or(ceiling - 0.5 * reach, |h| h.position.y);
    Some(Vec3::new(pos.x, floor + 0.85 * (ceiling - floor), pos.z))
}
