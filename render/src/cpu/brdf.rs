//! The one BRDF of GI Lab, used by the GPU passes (`shaders/common/brdf.wgsl`) and by
//! every CPU reference.
//!
//! Knecht's thesis (002 Eq. 4.9) shades a point with colour c, diffuse intensity DI,
//! specular intensity SI and specular power SP as `c·DI + SI·max(0, n·h)^SP`. We use the
//! energy-normalised form of the same lobes, so that radiance is in physical units and a
//! white Lambertian surface reflects exactly what it receives:
//!
//! ```text
//! f(l, v) = c · DI / π  +  SI · (SP + 8) / (8π) · max(0, n·h)^SP,    h = normalize(l + v)
//! ```
//!
//! Outgoing radiance from a punctual light is `L = f(l, v) · E · max(0, n·l)` with
//! `E = I · falloff / d²` for point and spot lights (I in W/sr) and `E` the irradiance
//! of a directional light.

use glam::Vec3;

/// Evaluates f(l, v) for unit vectors n, l, v.
pub fn eval(n: Vec3, l: Vec3, v: Vec3, albedo: Vec3, di: f32, si: f32, sp: f32) -> Vec3 {
    let h = (l + v).normalize_or_zero();
    let ndh = n.dot(h).max(0.0);
    let spec = si * (sp + 8.0) / (8.0 * std::f32::consts::PI) * ndh.powf(sp);
    albedo * di / std::f32::consts::PI + Vec3::splat(spec)
}

/// KHR_lights_punctual spot falloff t² with t = saturate((cos θ − cos θ_outer) /
/// (cos θ_inner − cos θ_outer)); `cos_theta` is between the spot axis and the direction
/// from the light to the surface.
pub fn spot_falloff(cos_theta: f32, inner: f32, outer: f32) -> f32 {
    let (co, ci) = (outer.cos(), inner.cos());
    let t = ((cos_theta - co) / (ci - co).max(1e-4)).clamp(0.0, 1.0);
    t * t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_lambert_is_one_over_pi() {
        let f = eval(Vec3::Y, Vec3::Y, Vec3::Y, Vec3::ONE, 1.0, 0.0, 1.0);
        assert!((f.x - 1.0 / std::f32::consts::PI).abs() < 1e-6);
    }

    #[test]
    fn spot_falloff_edges() {
        assert_eq!(spot_falloff(1.0, 0.5, 0.8), 1.0);
        assert_eq!(spot_falloff(0.8f32.cos() - 0.01, 0.5, 0.8), 0.0);
        let mid = ((0.5f32.cos() + 0.8f32.cos()) * 0.5).clamp(-1.0, 1.0);
        assert!((spot_falloff(mid, 0.5, 0.8) - 0.25).abs() < 1e-5);
    }
}
