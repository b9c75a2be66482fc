//! The viewing camera: a position with yaw and pitch, for orbit and fly navigation.
//! Camera motion between frames is what the movement buffer (Knecht 002 §3.5.1)
//! reprojects, so the renderer keeps last frame's matrices.

use glam::{Mat4, Vec3};

use crate::maths::Aabb;

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    pub position: Vec3,
    /// Rotation about +Y in radians; 0 looks toward −Z.
    pub yaw: f32,
    /// Rotation above the horizon in radians.
    pub pitch: f32,
    /// Vertical field of view in radians.
    pub yfov: f32,
    pub znear: f32,
    pub zfar: f32,
    /// Distance to the point orbiting turns around.
    pub orbit_distance: f32,
}

impl Camera {
    /// Why this camera cannot render (a non-finite number, a field of view outside
    /// (0°, 180°), near plane not positive or far plane not beyond it), if it cannot: a bad
    /// preset, session or bookmark can hold any of these.
    pub fn problem(&self) -> Option<String> {
        let finite = self.position.is_finite()
            && [self.yaw, self.pitch, self.yfov, self.znear, self.zfar].iter().all(|x| x.is_finite());
        if !finite {
            return Some(format!(
                "the camera has a value that is not a finite number (position {}, yaw {}, pitch {}, fov {}, near {}, far {})",
                self.position, self.yaw, self.pitch, self.yfov, self.znear, self.zfar
            ));
        }
        if !(self.yfov > 1e-4 && self.yfov < std::f32::consts::PI - 1e-4) {
            return Some(format!("the camera's field of view {}° is outside (0°, 180°)", self.yfov.to_degrees()));
        }
        if !(self.znear > 0.0 && self.zfar > self.znear * (1.0 + 1e-4)) {
            return Some(format!("the camera's near {} and far {} planes need 0 < near < far", self.znear, self.zfar));
        }
        None
    }

    /// Unit view direction.
    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(-sy * cp, sp, -cy * cp)
    }

    pub fn right(&self) -> Vec3 {
        self.forward().cross(Vec3::Y).normalize_or(Vec3::X)
    }

    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_to_mat4(self.position, self.forward(), Vec3::Y)
    }

    /// Perspective projection with depth in [0, 1] (WebGPU convention).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective(self.yfov, aspect.max(1e-4), self.znear, self.zfar)
    }

    pub fn view_proj(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }

    /// Looks at `target` from `position`.
    pub fn look_at(position: Vec3, target: Vec3, yfov: f32, bounds: Aabb) -> Self {
        let d = target - position;
        let len = d.length().max(1e-4);
        let f = d / len;
        let r = bounds.radius().max(1e-3);
        Self {
            position,
            yaw: (-f.x).atan2(-f.z),
            pitch: f.y.clamp(-1.0, 1.0).asin(),
            yfov,
            znear: (r * 0.005).max(1e-3),
            zfar: (position.distance(bounds.center()) + 2.0 * r) * 1.5,
            orbit_distance: len,
        }
    }

    /// A camera in front of the bounds (+Z side), raised about 20° above their centre and
    /// looking at it, at the distance where the bounding sphere fills the view.
    pub fn frame_bounds(bounds: Aabb, aspect: f32) -> Self {
        let yfov = 0.8f32;
        let half_fov = (yfov * 0.5).tan().min((yfov * 0.5).tan() * aspect.max(1e-3)).atan();
        let dist = bounds.radius().max(1e-3) / half_fov.sin();
        let c = bounds.center();
        Self::look_at(c + Vec3::new(0.0, 0.35, 1.0).normalize() * dist, c, yfov, bounds)
    }

    /// The camera of a glTF camera node.
    pub fn from_node(world: Mat4, def: &CameraDef, bounds: Aabb) -> Self {
        let position = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
        let dist = (bounds.center() - position).dot(forward).max(bounds.radius() * 0.5).max(1e-3);
        let yfov = match def.projection {
            Projection::Perspective { yfov, .. } => yfov,
            Projection::Orthographic { .. } => 0.8,
        };
        let mut cam = Self::look_at(position, position + forward * dist, yfov, bounds);
        // The clip planes are in the camera node's units: a unit scale above it (a file in
        // millimetres scaled to metres) scales them too.
        let scale = world.transform_vector3(Vec3::NEG_Z).length();
        let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
        if let Projection::Perspective { znear, zfar, .. } = def.projection {
            cam.znear = (znear * scale).max(1e-4);
            if let Some(f) = zfar {
                cam.zfar = (f * scale).max(cam.znear * 2.0);
            }
        }
        cam
    }

    /// Turns around the orbit point by the given angles (radians).
    pub fn orbit(&mut self, dyaw: f32, dpitch: f32) {
        let target = self.position + self.forward() * self.orbit_distance;
        self.yaw += dyaw;
        self.pitch = (self.pitch + dpitch).clamp(-1.5, 1.5);
        self.position = target - self.forward() * self.orbit_distance;
    }

    /// Moves in camera space: x right, y up, z forward.
    pub fn fly(&mut self, local: Vec3) {
        self.position += self.right() * local.x + Vec3::Y * local.y + self.forward() * local.z;
    }
}

/// A camera's projection as a glTF file describes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    Perspective { yfov: f32, znear: f32, zfar: Option<f32> },
    Orthographic { xmag: f32, ymag: f32, znear: f32, zfar: f32 },
}

#[derive(Clone, Debug, PartialEq)]
pub struct CameraDef {
    pub name: String,
    pub projection: Projection,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_camera_that_cannot_render_says_why() {
        let b = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        let good = Camera::frame_bounds(b, 1.5);
        assert_eq!(good.problem(), None);
        let far = Camera { position: Vec3::splat(1e30), ..good };
        assert_eq!(far.problem(), None, "far away is a place, not an error");
        let nan = Camera { position: Vec3::new(0.0, f32::NAN, 0.0), ..good };
        assert!(nan.problem().is_some_and(|p| p.contains("not a finite number")));
        for yfov in [0.0, -1.0, 4.0, f32::INFINITY] {
            assert!(Camera { yfov, ..good }.problem().is_some(), "fov {yfov}");
        }
        assert!(Camera { znear: 0.5, zfar: 0.1, ..good }.problem().is_some_and(|p| p.contains("near")));
        assert!(Camera { znear: 0.0, ..good }.problem().is_some());
    }
}
