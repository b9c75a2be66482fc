//! The one BRDF of GI Lab, used by the GPU passes (`shaders/common/brdf.wgsl`) and by
//! every CPU reference.
//!
//! Knecht's thesis (002 Eq. 4.9) shades a point with colour c, diffuse intensity DI, specular
//! intensity SI and specular power SP as `c·DI + SI·max(0, n·h)^SP`. ⚠[knecht.brdf-normalised]
//! We use the energy-normalised form of the same lobes, so that radiance is in physical units
//! and a white Lambertian surface reflects exactly what it receives:
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

/// 1/(4κ), κ the sharpness of a von Mises–Fisher lobe whose mean resultant length is `r`
/// (Banerjee et al.'s approximation κ ≈ r(3 − r²)/(1 − r²)): 0 for r = 1 (one direction);
/// r is clamped to [10⁻⁴, 1].
pub fn receiver_spread(r: f32) -> f32 {
    let q = r.clamp(1e-4, 1.0);
    (1.0 - q * q) / (4.0 * q * (3.0 - q * q))
}

/// How a pixel reflects the irradiance `e` that a technique interpolated to it, given the
/// irradiance's luminance-weighted mean incident direction `d` = Σ lum(E_k) ω_k / Σ lum(E_k)
/// (|d| = r ≤ 1: 1 for light from one direction, 2/3 for a uniform hemisphere). WGSL twin:
/// `receive_irradiance` in `shaders/common/receiver.wgsl`.
///
/// The readings ⚠[nguyen.glossy-receiver] and ⚠[gautron.glossy-receiver]: the HCB (000 §4.1) and Gautron's records (003) reflect irradiance
/// diffusely, c·DI/π·E, so a glossy receiver loses its indirect specular light (issue #51:
/// the chair's dark wood, whose look is its specular lobe). GI Lab keeps the irradiance's
/// dominant direction beside it and adds the specular lobe lit from that direction:
/// `SI·(SP' + 8)/(8π)·(n·h)^SP'·E`, h = normalize(l + v), l = d/|d|, where the lobe is widened by
/// the spread of the light: modelling the incident light as a von Mises–Fisher lobe of
/// sharpness κ (from r), whose angle in the half-vector is half the light's, 1/SP' = 1/SP +
/// 1/(4κ). Light from one direction (r → 1) gives the exact reflection f(l, v)·E; the diffuse
/// term is always exact. `glossy` false is the papers' diffuse-only receiver.
pub fn receive_irradiance(e: Vec3, d: Vec3, rx: &Receiver) -> Vec3 {
    receiver_factor(d, rx) * e
}

/// The receiving pixel of [`receive_irradiance`]: its normal `n`, the direction `v` to the eye,
/// its material (albedo c, diffuse and specular intensities DI and SI, specular power SP), and
/// whether it reflects with the specular lobe (`glossy`; false: the papers' diffuse receiver).
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    pub n: Vec3,
    pub v: Vec3,
    pub albedo: Vec3,
    pub di: f32,
    pub si: f32,
    pub sp: f32,
    pub glossy: bool,
}

/// The reflected radiance per unit irradiance of [`receive_irradiance`] (per channel: c·DI/π
/// plus the specular lobe's factor), so that a replay can split the pixel's light over the
/// contributions to E. WGSL twin: `receiver_factor`.
pub fn receiver_factor(d: Vec3, rx: &Receiver) -> Vec3 {
    let Receiver { n, v, albedo, di, si, sp, glossy } = *rx;
    let diffuse = albedo * di / std::f32::consts::PI;
    let r = d.length();
    if !glossy || si <= 0.0 || r <= 1e-4 {
        return diffuse;
    }
    let l = d / r;
    let sp_eff = 1.0 / (1.0 / sp.max(1e-3) + receiver_spread(r));
    let ndh = n.dot((l + v).normalize_or_zero()).max(0.0);
    diffuse + Vec3::splat(si * (sp_eff + 8.0) / (8.0 * std::f32::consts::PI) * ndh.powf(sp_eff))
}

/// KHR_lights_punctual spot falloff t² with t = saturate((cos θ − cos θ_outer) /
/// (cos θ_inner − cos θ_outer)); `cos_theta` is between the spot axis and the direction
/// from the light to the surface.
pub fn spot_falloff(cos_theta: f32, inner: f32, outer: f32) -> f32 {
    let (co, ci) = (outer.cos(), inner.cos());
    let t = ((cos_theta - co) / (ci - co).max(1e-4)).clamp(0.0, 1.0);
    t * t
}

/// Unshadowed radiance that a punctual light sends from surface point `p` (normal `n`)
/// toward `v`, and the point toward which its visibility is to be tested (the light, or far
/// along the direction of a directional light). KHR_lights_punctual units and falloffs:
/// I·falloff·window/d² for point and spot lights, E for directional lights. The surface is
/// (c, DI, SI, SP) at `p` (its textures read: [`crate::scene::Material::intensities_at`]).
pub fn punctual_radiance(
    wl: &crate::scene::WorldLight,
    p: Vec3,
    n: Vec3,
    v: Vec3,
    (c, di, si, sp): (Vec3, f32, f32, f32),
    far: f32,
) -> (Vec3, Vec3) {
    use crate::scene::LightKind;
    let (l, e, target) = match wl.light.kind {
        LightKind::Directional => {
            let l = -wl.direction;
            (l, wl.light.intensity, p + l * far)
        }
        LightKind::Point | LightKind::Spot { .. } => {
            let to_l = wl.position - p;
            let d2 = to_l.length_squared().max(1e-12);
            let d = d2.sqrt();
            let l = to_l / d;
            let falloff = match wl.light.kind {
                LightKind::Spot { inner_cone, outer_cone } => {
                    spot_falloff(wl.direction.dot(-l), inner_cone, outer_cone)
                }
                _ => 1.0,
            };
            let window = wl.light.range.map_or(1.0, |r| (1.0 - (d / r).powi(4)).clamp(0.0, 1.0));
            (l, wl.light.intensity * falloff * window / d2, wl.position)
        }
    };
    let ndl = n.dot(l);
    if ndl <= 0.0 || e <= 0.0 {
        return (Vec3::ZERO, target);
    }
    let f = eval(n, l, v, c, di, si, sp);
    (f * wl.light.color * e * ndl, target)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rx(n: Vec3, v: Vec3, albedo: Vec3, (di, si, sp): (f32, f32, f32), glossy: bool) -> Receiver {
        Receiver { n, v, albedo, di, si, sp, glossy }
    }

    /// Light from one direction (r → 1) is reflected exactly as the BRDF reflects it; the
    /// diffuse-only receiver is c·DI/π·E; no direction known: diffuse only.
    #[test]
    fn the_glossy_receiver_is_exact_for_light_from_one_direction() {
        let (n, v) = (Vec3::Y, Vec3::new(0.6, 0.8, 0.0));
        let l = Vec3::new(-0.6, 0.8, 0.0);
        let (c, e) = (Vec3::new(0.5, 0.2, 0.1), Vec3::new(2.0, 1.0, 0.5));
        let exact = eval(n, l, v, c, 0.9, 0.3, 64.0) * e;
        let one = receive_irradiance(e, l * 0.99999, &rx(n, v, c, (0.9, 0.3, 64.0), true));
        assert!((one - exact).length() < 1e-3 * exact.length(), "{one} vs {exact}");
        let diffuse = c * 0.9 / std::f32::consts::PI * e;
        assert_eq!(receive_irradiance(e, l, &rx(n, v, c, (0.9, 0.3, 64.0), false)), diffuse);
        assert_eq!(receive_irradiance(e, Vec3::ZERO, &rx(n, v, c, (0.9, 0.3, 64.0), true)), diffuse);
    }

    /// Spread light widens the lobe: the mirror direction gets less, a direction far from it
    /// more, and the reflected energy of the lobe (∫ over the views of the specular part ·
    /// cos θ_v) stays within 25 % of the energy for one direction (at most SI·E).
    #[test]
    fn spread_light_widens_the_specular_lobe_and_keeps_its_energy() {
        let n = Vec3::Y;
        let l = Vec3::new(-0.5, 0.866, 0.0).normalize();
        let e = Vec3::ONE;
        let spec = |r: f32, v: Vec3| receive_irradiance(e, l * r, &rx(n, v, Vec3::ZERO, (0.0, 0.5, 128.0), true)).x;
        let mirror = Vec3::new(0.5, 0.866, 0.0).normalize();
        let off = Vec3::new(0.0, 0.8, 0.6).normalize();
        assert!(spec(0.6, mirror) < spec(0.99, mirror));
        assert!(spec(0.6, off) > spec(0.99, off));
        // ∫ f_s cos θ_v dω_v over the hemisphere of views, by a fine grid in (cos θ, φ).
        let energy = |r: f32| {
            let (m, k) = (200, 400);
            let mut sum = 0.0;
            for i in 0..m {
                let ct = (i as f32 + 0.5) / m as f32;
                let st = (1.0 - ct * ct).sqrt();
                for j in 0..k {
                    let phi = std::f32::consts::TAU * (j as f32 + 0.5) / k as f32;
                    let v = Vec3::new(st * phi.cos(), ct, st * phi.sin());
                    sum += spec(r, v) * ct;
                }
            }
            sum * std::f32::consts::TAU / (m * k) as f32
        };
        let (sharp, wide) = (energy(0.999), energy(0.5));
        assert!(sharp > 0.3 && sharp <= 0.5 * 1.05, "{sharp}");
        assert!((wide / sharp - 1.0).abs() < 0.25, "{wide} vs {sharp}");
    }

    /// Issue #51's limits: roughness 0 and 1 (SP 4096 and 1, `material_specular_power`), a
    /// black metal, no light, light from one direction or spread over the hemisphere, views
    /// along the surface: the receiver's light stays finite and non-negative.
    #[test]
    fn the_glossy_receiver_is_finite_at_the_limits() {
        let n = Vec3::Y;
        for sp in [1.0, 4096.0] {
            for (c, di, si) in [(Vec3::ONE, 1.0, 0.04), (Vec3::ZERO, 0.0, 1.0)] {
                for r in [0.0, 1e-6, 0.5, 2.0 / 3.0, 0.999_999, 1.0, 1.000_001] {
                    for v in [Vec3::Y, Vec3::new(1.0, 1e-6, 0.0).normalize(), Vec3::new(-1.0, 0.0, 0.0)] {
                        let d = Vec3::new(0.3, 0.9, 0.1).normalize() * r;
                        let f = receiver_factor(d, &rx(n, v, c, (di, si, sp), true));
                        assert!(f.is_finite() && f.min_element() >= 0.0, "SP {sp} r {r} v {v}: {f}");
                        assert_eq!(receive_irradiance(Vec3::ZERO, d, &rx(n, v, c, (di, si, sp), true)), Vec3::ZERO);
                    }
                }
            }
        }
    }

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
