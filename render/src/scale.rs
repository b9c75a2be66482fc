//! The length that scene-relative settings are fractions of (issue #51 point 4; docs/
//! architecture.md, "Scene scale"): the HCB's d_max when it is 0 (`hcb.d_max_m`), the clamps
//! of Gautron's record radii (`gautron.r_min_scene`, `gautron.r_max_scene`) and the split of
//! the near field (`soler.near_field_distance`). The papers give them against "the scene";
//! for a room seen from inside, the whole model's bounding sphere is the wrong measure (the
//! hotel: 6.06 m for a room of 5.8 × 7.1 × 2.1 m, whose half diagonal is 4.70 m; a house of
//! many rooms, far more). The room is the one the loader framed the scene in
//! (`scene::framing::Room`) while the camera stands in it; anywhere else, and for scenes
//! opened from outside or from their own glTF camera, the model's sphere.
//!
//! What stays on the model's sphere: the VPL maps' clip planes and the imperfect shadow maps'
//! eye offset and pull-push thresholds, since a VPL's map sees the whole scene wherever the
//! camera stands, and the voxel grid's depth range, which must hold what the camera sees.

use glam::Vec3;

use crate::scene::Aabb;
use crate::scene::framing::Room;
pub use crate::settings::scale::{ScaleReference, ScaleSettings};

/// Where [`scale_radius`] took its length from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScaleSource {
    /// The room the camera is in: its box.
    Room(Aabb),
    /// The model's bounding sphere.
    Model,
}

/// The box of `room`: its wall-to-wall box (`Room::bounds`, measured along the axes through its
/// middle) cut to its longest mean span around its middle, since an axis ray through a door
/// runs on into the next room; None when empty.
pub fn room_box(room: &Room) -> Option<Aabb> {
    let half = 0.5 * room.size.max_element();
    let b = Aabb {
        min: room.bounds.min.max(Vec3::new(room.center.x - half, room.floor, room.center.z - half)),
        max: room.bounds.max.min(Vec3::new(room.center.x + half, room.ceiling, room.center.z + half)),
    };
    (!b.is_empty() && b.extent().min_element() > 0.0).then_some(b)
}

/// The radius scene-relative settings scale with, and where it came from: when `reference`
/// asks for the room and the eye stands in it ([`room_box`] grown by 5 % of the room's longest
/// span: a camera against a wall is still in the room), half the diagonal of its mean spans and
/// height (`Room::size`, robust to an opening that lengthens a span), never more than the
/// model's `bounds` radius; else the model's radius. Never 0.
pub fn scale_radius(reference: ScaleReference, room: Option<&Room>, eye: Vec3, bounds: Aabb) -> (f32, ScaleSource) {
    let model = bounds.radius();
    let model = if model.is_finite() { model.max(1e-3) } else { 1.0 };
    if reference == ScaleReference::Room
        && let Some(r) = room
        && let Some(b) = room_box(r)
    {
        let pad = Vec3::splat(0.05 * r.size.max_element());
        if eye.cmpge(b.min - pad).all() && eye.cmple(b.max + pad).all() {
            let radius = 0.5 * (r.size.length_squared() + (r.ceiling - r.floor).powi(2)).sqrt();
            if radius.is_finite() && radius > 0.0 {
                return (radius.clamp(1e-3, model), ScaleSource::Room(b));
            }
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
        // A door on the axis through the middle: the wall-to-wall box runs on into the next
        // room (x to 12); the room's box stops at its longest span, 7.1 m around its middle.
        let through_door = Room { bounds: Aabb { max: Vec3::new(12.0, 2.1, 7.1), ..r.bounds }, ..r };
        let b = room_box(&through_door).expect("a box");
        assert!((b.max.x - (2.9 + 3.55)).abs() < 1e-5, "{b:?}");
        let next_room = Vec3::new(10.0, 1.6, 3.55);
        assert_eq!(scale_radius(ScaleReference::Room, Some(&through_door), next_room, model).1, ScaleSource::Model);
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
        let big = room(Vec3::new(-50.0, 0.0, -50.0), Vec3::new(50.0, 2.1, 50.0));
        assert_eq!(scale_radius(ScaleReference::Room, Some(&big), inside, model).0, model.radius());
        // An empty model still gives a usable length.
        let empty = scale_radius(ScaleReference::Model, None, inside, Aabb::EMPTY).0;
        assert!(empty.is_finite() && empty > 0.0, "{empty}");
    }
}
