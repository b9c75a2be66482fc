//! The length that scene-relative settings are fractions of (issue #51 point 4; docs/
//! architecture.md, "Scene scale"): the HCB's d_max when it is 0 (`hcb.d_max_m`), the clamps
//! of Gautron's record radii (`gautron.r_min_scene`, `gautron.r_max_scene`) and the split of
//! the near field (`soler.near_field_distance`). The papers give them against "the scene";
//! for a room seen from inside, the whole model's bounding sphere is the wrong measure (the
//! hotel: 6.06 m for a room of 5.8 × 7.1 × 2.1 m, whose wall-to-wall box has a half diagonal
//! of 4.18 m; a house of many rooms, far more). The room is the one the loader framed the scene in
//! (`scene::framing::Room`) while the camera stands in it; anywhere else, and for scenes
//! opened from outside or from their own glTF camera, the model's sphere.
//!
//! What stays on the model's sphere: the VPL maps' clip planes and the imperfect shadow maps'
//! eye offset and pull-push thresholds, since a VPL's map sees the whole scene wherever the
//! camera stands, and the voxel grid's depth range, which must hold what the camera sees.

use glam::Vec3;

use crate::scene::Aabb;
use crate::scene::framing::Room;
use crate::{settings_enum, settings_group};

settings_enum! {
    /// What "the scene's radius" of the scene-relative settings means.
    pub enum ScaleReference {
        /// Half the diagonal of the room the camera stands in (the loader's interior view),
        /// else the model's bounding radius.
        Room = "the room the camera is in, else the model",
        /// The model's bounding radius (GI Lab before issue #51).
        Model = "the whole model's bounding sphere",
    }
    default Room
}

settings_group! {
    /// The scene's scale for its relative settings (HCB d_max, Gautron's radius clamps, the
    /// near field's split).
    pub struct ScaleSettings: "scale" {
        /// The length the scene-relative settings are fractions of.
        reference: ScaleReference = ScaleReference::Room,
        unit "", symbol "", range 0..=1, cost "free", history true;
    }
}

/// Where [`scale_radius`] took its length from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScaleSource {
    /// The room the camera is in: its box.
    Room(Aabb),
    /// The model's bounding sphere.
    Model,
}

/// The radius scene-relative settings scale with, and where it came from: half the diagonal
/// of `room` when `reference` asks for the room and the eye stands inside it (its box grown by
/// 5 % of its extent on every side: a camera against a wall is still in the room), never more
/// than the model's `bounds` radius; else the model's radius. Never 0.
pub fn scale_radius(reference: ScaleReference, room: Option<&Room>, eye: Vec3, bounds: Aabb) -> (f32, ScaleSource) {
    let model = bounds.radius();
    let model = if model.is_finite() { model.max(1e-3) } else { 1.0 };
    if reference == ScaleReference::Room
        && let Some(r) = room
        && !r.bounds.is_empty()
    {
        let pad = r.bounds.extent() * 0.05;
        let (lo, hi) = (r.bounds.min - pad, r.bounds.max + pad);
        if eye.cmpge(lo).all() && eye.cmple(hi).all() {
            return (r.bounds.radius().clamp(1e-3, model), ScaleSource::Room(r.bounds));
        }
    }
    (model, ScaleSource::Model)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    fn room(min: Vec3, max: Vec3) -> Room {
        let bounds = Aabb { min, max };
        Room {
            floor: min.y,
            ceiling: max.y,
            center: bounds.center(),
            size: Vec2::new(max.x - min.x, max.z - min.z),
            bounds,
        }
    }

    /// The hotel's case: a 5.8 × 2.1 × 7.1 m room in a model of radius 6.1 m.
    #[test]
    fn the_room_the_camera_stands_in_gives_the_scale_and_the_model_elsewhere() {
        let r = room(Vec3::new(0.0, 0.0, 0.0), Vec3::new(5.8, 2.1, 7.1));
        let model = Aabb { min: Vec3::new(-3.0, -1.0, -2.0), max: Vec3::new(8.0, 3.0, 7.1) };
        let inside = Vec3::new(2.0, 1.6, 3.0);
        let (s, from) = scale_radius(ScaleReference::Room, Some(&r), inside, model);
        assert!((s - 0.5 * (5.8f32 * 5.8 + 2.1 * 2.1 + 7.1 * 7.1).sqrt()).abs() < 1e-5, "{s}");
        assert_eq!(from, ScaleSource::Room(r.bounds));
        // Against a wall, still in.
        assert!(matches!(
            scale_radius(ScaleReference::Room, Some(&r), Vec3::new(-0.1, 1.6, 3.0), model).1,
            ScaleSource::Room(_)
        ));
        // Out of the room, asked for the model, or no room: the model's sphere.
        for (reference, eye, room) in [
            (ScaleReference::Room, Vec3::new(7.5, 1.6, 3.0), Some(&r)),
            (ScaleReference::Model, inside, Some(&r)),
            (ScaleReference::Room, inside, None),
        ] {
            assert_eq!(scale_radius(reference, room, eye, model), (model.radius(), ScaleSource::Model));
        }
        // A room larger than the model (a framing of a bounds-sized box) gives the model's.
        let big = room(Vec3::splat(-50.0), Vec3::splat(50.0));
        assert_eq!(scale_radius(ScaleReference::Room, Some(&big), inside, model).0, model.radius());
        // An empty model still gives a usable length.
        let empty = scale_radius(ScaleReference::Model, None, inside, Aabb::EMPTY).0;
        assert!(empty.is_finite() && empty > 0.0, "{empty}");
    }
}
