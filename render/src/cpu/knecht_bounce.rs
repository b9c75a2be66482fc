//! CPU references of instant radiosity's further bounces (Knecht 002 §3.6 and the IRSM
//! baseline after Ritschel et al. 2008): the light a VPL sends to a point-cloud sample, the
//! selection of the next bounce's VPL and the VPL it becomes, and the IRSM draw. Twins of
//! `shaders/knecht/vpl/bounce.wgsl`, `shaders/common/bounce.wgsl` and `shaders/knecht/vpl/irsm.wgsl`;
//! built on the VPL and receiver types of [`crate::cpu::knecht`].

use glam::Vec3;

use crate::cpu::knecht::{Receiver, Vpl};
use crate::maths::pcg_hash;

/// Uniform number in (0, 1) of sample `j` for the proportional bounce selection.
pub fn bounce_uniform(seed: u32, j: u32) -> f32 {
    let h = pcg_hash(j ^ pcg_hash(seed));
    ((h >> 8) as f32 + 0.5) / 16_777_216.0
}

/// A point-cloud sample as the bounce selection sees it (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BounceSample {
    pub surface: Receiver,
    /// W / w_s: the cloud's weighted area over the sample's object weight.
    pub weighted_area: f32,
}

/// Flux arriving at sample `s` from `vpl` and the sample's contribution (Knecht 002
/// §3.6.1, twin of `incident` in `shaders/knecht/vpl/bounce.wgsl`):
///
/// - Φ_s = Φ_v · f_v(ω_in, v→s) · cos θ_v · cos θ_s / max(d², d_min²) · A_s with the glossy
///   VPL emission of Eq. 4.8 (the one BRDF, [`crate::cpu::brdf`]) and the geometry term of
///   Eq. 4.7; A_s = W / (w_s · P_v) is the area the sample stands for among the P_v samples
///   assigned to the VPL;
/// - C_s = lum(Φ_s ⊙ (c_s·DI_s + SI_s)), the light the sample would send on (Φ_s already
///   holds the source's BRDF, see [`bounce_vpl`]).
///
/// `visible` is the ISM test's result. Returns (Φ_s, C_s); zero when facing away or hidden.
pub fn bounce_incident(vpl: &Vpl, sample: &BounceSample, per_vpl: u32, d_min: f32, visible: bool) -> (Vec3, f32) {
    let s = &sample.surface;
    let w = s.position - vpl.position;
    let d2 = w.length_squared();
    let l = w / d2.max(1e-12).sqrt();
    let (cos_v, cos_s) = (vpl.normal.dot(l), -s.normal.dot(l));
    if cos_v <= 0.0 || cos_s <= 0.0 || !visible {
        return (Vec3::ZERO, 0.0);
    }
    let f_v = crate::cpu::brdf::eval(vpl.normal, vpl.incident, l, vpl.albedo, vpl.di, vpl.si, vpl.sp);
    let area = sample.weighted_area / per_vpl as f32;
    let flux = vpl.flux * f_v * cos_v * cos_s / d2.max(d_min * d_min) * area;
    let reflect = s.albedo * s.di + Vec3::splat(s.si);
    (flux, luminance(flux * reflect))
}

/// Rec. 709 luminance.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// How the next bounce's VPL is chosen (twin of `BounceSelection`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    /// Largest C_s (Knecht §3.6.1's depth test).
    Strongest,
    /// Exponential race with this seed: the largest C_s / (−ln u_s) wins, i.e. sample s with
    /// probability C_s / ΣC (Knecht §6.1's future work).
    Proportional { seed: u32 },
}

/// Bounce selection for one VPL (twin of the reduction in `shaders/knecht/vpl/bounce.wgsl`):
/// among `samples` (index j, contribution C_j) the one with the largest key — C_j, or
/// C_j / (−ln u_j) — ties to the lowest index, and ΣC. None when no C_j > 0.
pub fn select_bounce(samples: &[(u32, f32)], selection: Selection) -> Option<(u32, f32)> {
    let mut best: Option<(u32, f32)> = None;
    let mut sum = 0.0f32;
    for &(j, c) in samples {
        if c <= 0.0 {
            continue;
        }
        sum += c;
        let key = match selection {
            Selection::Strongest => c,
            Selection::Proportional { seed } => c / -bounce_uniform(seed, j).ln(),
        };
        if best.is_none_or(|(bj, bk)| key > bk || (key == bk && j < bj)) {
            best = Some((j, key));
        }
    }
    best.map(|(j, _)| (j, sum))
}

/// The next bounce's VPL from sample `s` with incident flux `flux` and contribution `c`
/// out of `sum` (Knecht §3.6.1): Φ = Φ_s · ΣC / C_s, ω_in toward the source VPL, and the
/// sample's own material (DI_s, SI_s, SP_s).
///
/// ⚠[knecht.bounce-si] The thesis sets SI = SI_s · SI_v, "necessary to get correct specular
/// light bounces"; that holds for VPLs whose flux is the diffuse colour alone. Here Φ_s = Φ_v ·
/// f_v · G already went through the source's whole BRDF, glossy lobe included (Eq. 4.8), so the
/// new VPL reflects it with the sample's BRDF only; the product would apply SI_v twice. Energy
/// is conserved along a chain: the light the new VPL sends is what the sample's surface
/// reflects, f_s · E_s (test: `bounce_vpl_reflects_with_the_samples_own_brdf`).
pub fn bounce_vpl(source: &Vpl, sample: &BounceSample, flux: Vec3, c: f32, sum: f32) -> Vpl {
    let s = &sample.surface;
    Vpl {
        position: s.position,
        normal: s.normal,
        flux: flux * (sum / c),
        incident: (source.position - s.position).normalize_or_zero(),
        albedo: s.albedo,
        di: s.di,
        si: s.si,
        sp: s.sp,
    }
}

/// IRSM importance sampling (the baseline of §3.6 after Ritschel et al.; twin of `cs_sample`
/// in `shaders/knecht/vpl/irsm.wgsl`): new VPL `k` of `n` picks an IRSM with the stratified
/// u₁ = (k + ξ)/n over the running sum of `totals`, then a texel with u₂ = ξ' inside that
/// IRSM's inclusive prefix sums `cdf[i]` (the first entry above u). Returns (IRSM, texel), or
/// None when every total is 0.
pub fn irsm_pick(totals: &[f32], cdf: &[Vec<f32>], k: u32, seed: u32) -> Option<(usize, usize)> {
    let n = totals.len();
    let running: Vec<f32> = totals
        .iter()
        .scan(0.0f32, |acc, t| {
            *acc += t;
            Some(*acc)
        })
        .collect();
    let grand = *running.last()?;
    if grand.is_nan() || grand <= 0.0 {
        return None;
    }
    let first_above = |v: &[f32], u: f32| v.partition_point(|&c| c <= u).min(v.len() - 1);
    let u1 = (k as f32 + bounce_uniform(seed, 2 * k)) / n as f32 * grand;
    let i = first_above(&running, u1);
    let u2 = bounce_uniform(seed, 2 * k + 1) * totals[i];
    Some((i, first_above(&cdf[i], u2)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounce_selection_takes_the_largest_contribution_and_sums() {
        let samples = [(4, 0.5), (9, 2.0), (13, 0.0), (21, 2.0), (30, 1.0)];
        assert_eq!(select_bounce(&samples, Selection::Strongest), Some((9, 5.5)));
        assert_eq!(select_bounce(&[(1, 0.0)], Selection::Strongest), None);
    }

    #[test]
    fn proportional_selection_follows_the_contributions() {
        // Exponential race: sample k wins with probability C_k / ΣC.
        let samples = [(0, 1.0), (1, 3.0), (2, 0.0), (3, 4.0)];
        let mut wins = [0u32; 4];
        let trials = 20000;
        for seed in 0..trials {
            let (j, _) = select_bounce(&samples, Selection::Proportional { seed }).expect("a winner");
            wins[j as usize] += 1;
        }
        for (k, expect) in [(0, 1.0 / 8.0), (1, 3.0 / 8.0), (2, 0.0), (3, 4.0 / 8.0)] {
            let p = wins[k] as f64 / trials as f64;
            assert!((p - expect).abs() < 0.015, "sample {k}: {p} vs {expect}");
        }
    }

    #[test]
    fn bounce_vpl_reflects_with_the_samples_own_brdf() {
        // A glossy source VPL lights a glossy sample. Φ_s already went through the source's
        // BRDF (Eq. 4.8), so the light the new VPL sends toward any ω must be what the
        // sample's own surface reflects: Φ_s · f_s(ω_in, ω). Thesis' SI = SI_s · SI_v gives
        // 0.8 · 0.5 = 0.4 here and fails near the mirror direction.
        let source = Vpl {
            position: Vec3::new(0.0, 1.0, 0.0),
            normal: Vec3::new(0.0, -1.0, 0.0),
            flux: Vec3::splat(10.0),
            incident: Vec3::new(0.3, -1.0, 0.0).normalize(),
            albedo: Vec3::new(0.7, 0.6, 0.5),
            di: 0.6,
            si: 0.5,
            sp: 64.0,
        };
        let surface = Receiver {
            position: Vec3::new(0.4, 0.0, 0.1),
            normal: Vec3::Y,
            albedo: Vec3::new(0.2, 0.5, 0.8),
            di: 0.5,
            si: 0.8,
            sp: 200.0,
        };
        let sample = BounceSample { surface, weighted_area: 2.0 };
        let (flux, c) = bounce_incident(&source, &sample, 1, 0.1, true);
        assert!(c > 0.0 && flux.max_element() > 0.0);
        let reflect = surface.albedo * surface.di + Vec3::splat(surface.si);
        assert!((c - luminance(flux * reflect)).abs() <= 1e-6 * c, "C_s reflects with the sample's material");
        // One sample stands for the whole VPL (ΣC = C_s): the new VPL's flux is Φ_s.
        let v = bounce_vpl(&source, &sample, flux, c, c);
        let to_source = (source.position - surface.position).normalize();
        let mirror = (2.0 * surface.normal.dot(to_source) * surface.normal - to_source).normalize();
        for w in [mirror, Vec3::new(-0.2, 1.0, 0.3).normalize(), Vec3::new(0.9, 0.2, -0.1).normalize()] {
            let sent = v.flux * crate::cpu::brdf::eval(v.normal, v.incident, w, v.albedo, v.di, v.si, v.sp);
            let reflected = flux
                * crate::cpu::brdf::eval(
                    surface.normal,
                    to_source,
                    w,
                    surface.albedo,
                    surface.di,
                    surface.si,
                    surface.sp,
                );
            assert!(
                (sent - reflected).abs().max_element() <= 1e-4 * reflected.max_element(),
                "{sent} vs {reflected} toward {w}"
            );
        }
    }
}
