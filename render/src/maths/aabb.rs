//! Axis-aligned bounds: of meshes, scenes, rooms and cameras' framing.

use glam::{Mat4, Vec3};

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
    /// Radius of the bounding sphere around the centre.
    pub fn radius(&self) -> f32 {
        self.extent().length() * 0.5
    }
    /// The bounds of this box's eight corners under `m`.
    pub fn transformed(&self, m: Mat4) -> Aabb {
        let mut b = Aabb::EMPTY;
        for k in 0..8 {
            let pick = |bit: u32, lo: f32, hi: f32| if k & bit == 0 { lo } else { hi };
            let c = Vec3::new(
                pick(1, self.min.x, self.max.x),
                pick(2, self.min.y, self.max.y),
                pick(4, self.min.z, self.max.z),
            );
            b.grow(m.transform_point3(c));
        }
        b
    }
}
