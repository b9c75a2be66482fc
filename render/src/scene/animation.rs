//! glTF animations: translation / rotation / scale channels with step, linear and
//! cubic-spline interpolation, evaluated at a time given by the deterministic clock.

use super::Transform;
use glam::{Quat, Vec3, Vec4};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    /// Values are stored as (in-tangent, value, out-tangent) triples per key.
    CubicSpline,
}

#[derive(Clone, Debug, PartialEq)]
pub enum ChannelTarget {
    Translation(Vec<Vec3>),
    Rotation(Vec<Quat>),
    Scale(Vec<Vec3>),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub node: usize,
    pub interpolation: Interpolation,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// One value per key (three for cubic spline).
    pub target: ChannelTarget,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    pub name: String,
    pub channels: Vec<Channel>,
}

impl Animation {
    pub fn duration(&self) -> f32 {
        self.channels.iter().filter_map(|c| c.times.last().copied()).fold(0.0, f32::max)
    }

    /// Applies the animation at `time_s` to the local transforms, looping over its duration.
    pub fn apply(&self, time_s: f32, locals: &mut [Transform]) {
        let d = self.duration();
        let t = if d > 0.0 { time_s.rem_euclid(d) } else { 0.0 };
        for ch in &self.channels {
            let Some(local) = locals.get_mut(ch.node) else { continue };
            match &ch.target {
                ChannelTarget::Translation(v) => {
                    if let Some(x) = sample(ch, t, v, Vec3::lerp) {
                        local.translation = x;
                    }
                }
                ChannelTarget::Scale(v) => {
                    if let Some(x) = sample(ch, t, v, Vec3::lerp) {
                        local.scale = x;
                    }
                }
                ChannelTarget::Rotation(v) => {
                    if let Some(q) = sample_quat(ch, t, v) {
                        local.rotation = q;
                    }
                }
            }
        }
    }
}

/// Finds the key interval of `t`: (i, s) with t between times[i] and times[i+1], s ∈ [0,1].
fn locate(times: &[f32], t: f32) -> Option<(usize, f32)> {
    let n = times.len();
    if n == 0 {
        return None;
    }
    if n == 1 || t <= times[0] {
        return Some((0, 0.0));
    }
    if t >= times[n - 1] {
        return Some((n - 1, 0.0));
    }
    let i = times.partition_point(|&k| k <= t).saturating_sub(1).min(n - 2);
    let span = times[i + 1] - times[i];
    let s = if span > 0.0 { (t - times[i]) / span } else { 0.0 };
    Some((i, s.clamp(0.0, 1.0)))
}

fn sample<T>(ch: &Channel, t: f32, v: &[T], lerp: impl Fn(T, T, f32) -> T) -> Option<T>
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let (i, s) = locate(&ch.times, t)?;
    let n = ch.times.len();
    match ch.interpolation {
        Interpolation::Step => v.get(i).copied(),
        Interpolation::Linear => {
            let a = *v.get(i)?;
            if i + 1 >= n {
                return Some(a);
            }
            Some(lerp(a, *v.get(i + 1)?, s))
        }
        Interpolation::CubicSpline => {
            let p0 = *v.get(3 * i + 1)?;
            if i + 1 >= n {
                return Some(p0);
            }
            let dt = ch.times[i + 1] - ch.times[i];
            let m0 = *v.get(3 * i + 2)? * dt;
            let p1 = *v.get(3 * (i + 1) + 1)?;
            let m1 = *v.get(3 * (i + 1))? * dt;
            Some(hermite(p0, m0, p1, m1, s))
        }
    }
}

fn hermite<T>(p0: T, m0: T, p1: T, m1: T, s: f32) -> T
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let s2 = s * s;
    let s3 = s2 * s;
    p0 * (2.0 * s3 - 3.0 * s2 + 1.0) + m0 * (s3 - 2.0 * s2 + s) + p1 * (-2.0 * s3 + 3.0 * s2) + m1 * (s3 - s2)
}

fn sample_quat(ch: &Channel, t: f32, v: &[Quat]) -> Option<Quat> {
    match ch.interpolation {
        Interpolation::Linear => {
            let (i, s) = locate(&ch.times, t)?;
            let a = *v.get(i)?;
            if i + 1 >= ch.times.len() {
                return Some(a.normalize());
            }
            Some(a.slerp(*v.get(i + 1)?, s).normalize())
        }
        _ => {
            let as_vec: Vec<Vec4> = v.iter().map(|q| Vec4::from(*q)).collect();
            let x = sample(ch, t, &as_vec, Vec4::lerp)?;
            Some(Quat::from_vec4(x).normalize())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_translation_interpolates_and_loops() {
        let anim = Animation {
            name: "a".into(),
            channels: vec![Channel {
                node: 0,
                interpolation: Interpolation::Linear,
                times: vec![0.0, 2.0],
                target: ChannelTarget::Translation(vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0)]),
            }],
        };
        let mut l = vec![Transform::default()];
        anim.apply(0.5, &mut l);
        assert!((l[0].translation.x - 0.5).abs() < 1e-6);
        anim.apply(2.5, &mut l); // loops: 2.5 mod 2 = 0.5
        assert!((l[0].translation.x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn rotation_slerps() {
        let anim = Animation {
            name: "r".into(),
            channels: vec![Channel {
                node: 0,
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0, 2.0],
                target: ChannelTarget::Rotation(vec![
                    Quat::IDENTITY,
                    Quat::from_rotation_y(1.0),
                    Quat::from_rotation_y(2.0),
                ]),
            }],
        };
        let mut l = vec![Transform::default()];
        anim.apply(0.5, &mut l);
        let (axis, angle) = l[0].rotation.to_axis_angle();
        assert!((angle - 0.5).abs() < 1e-4, "{angle}");
        assert!(axis.y > 0.99);
    }
}
