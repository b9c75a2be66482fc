//! The CPU twin of Gautron, Křivánek et al.'s irradiance cache splatting (`cpu::gautron`)
//! against closed forms, finite differences and brute force (pure CPU, no GPU). Run with
//! `--nocapture` to see the measured numbers.

use gi_render::cpu::gautron::{
    HemisphereTable, Interpolation, Record, RecordTerms, TexelTerms, accumulate, candidates, extrapolate, frame,
    reduce, reduce_in_frame, sphere_ndc_rect, weight,
};
use gi_render::passes::gautron::BorderCompensation;
use glam::{Quat, Vec3};
use std::f64::consts::{PI, TAU};

/// Larsen et al.'s aperture: tan(aperture / 2) = 2.
const APERTURE: f32 = 126.869_9;

/// A small deterministic generator (64-bit LCG, Knuth's MMIX constants, top 24 bits) for
/// reproducible scenes.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    fn unit(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let s = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

/// World directions of the table's texels in the frame (t, b, n).
fn world_dirs(tab: &HemisphereTable, t: Vec3, b: Vec3, n: Vec3) -> Vec<Vec3> {
    (0..tab.texels.len()).map(|k| tab.world_dir(k, t, b, n)).collect()
}

/// The cosine-weighted fraction of the hemisphere inside the square pyramid of half-width T,
/// by a fine midpoint integration in φ of ∫_0^{θ_max(φ)} cos θ sin θ dθ = sin² θ_max / 2, where
/// tan θ_max(φ) = T / max(|cos φ|, |sin φ|) (the direction leaves the square there).
fn pyramid_cosine_fraction(t: f64) -> f64 {
    let steps = 1_000_000;
    let dphi = TAU / steps as f64;
    let mut sum = 0.0;
    for s in 0..steps {
        let phi = (s as f64 + 0.5) * dphi;
        let tan_max = t / phi.cos().abs().max(phi.sin().abs());
        sum += tan_max * tan_max / (1.0 + tan_max * tan_max) * 0.5 * dphi;
    }
    sum / PI
}

/// Test 1: the layout, the frame, Σ Ω_p against the pyramid's exact solid angle with the
/// midpoint rule's predicted error, and the bands filling the rest of the hemisphere.
#[test]
fn texel_solid_angles_sum_to_the_pyramid_and_the_bands_fill_the_hemisphere() {
    assert_eq!(std::mem::size_of::<TexelTerms>(), 64, "the GPU reads 4 vec4 per texel");
    for n in [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::new(0.3, -0.5, 0.8).normalize(), Vec3::new(0.01, 0.0, 1.0).normalize()]
    {
        let (t, b) = frame(n);
        assert!((t.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
        assert!(t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6 && t.dot(b).abs() < 1e-6);
        assert!((t.cross(b) - n).length() < 1e-6, "right-handed frame for n = {n}");
    }

    let side = 32u32;
    let tab = HemisphereTable::new(side, APERTURE, BorderCompensation::CosineWeighted);
    let t = f64::from(tab.tan_half);
    assert!((t - 2.0).abs() < 1e-5, "126.87° is tan = 2, got {t}");
    let sum: f64 = tab.texels.iter().map(|x| f64::from(x.dir[3])).sum();
    let exact = 4.0 * (t * t / (1.0 + t * t)).asin();
    let rel = (sum - exact) / exact;
    // The midpoint rule on cells of side h: ∫f − Σ h² f(centre) = (h²/24) ∫ ∇²f + O(h⁴), and
    // ∫ ∇²f = ∮ ∂f/∂ν (divergence theorem) with f = (1 + x² + y²)^{-3/2}: on x = T,
    // ∂f/∂x = −3T (1 + T² + y²)^{-5/2}, and ∫_{-T}^{T} (a² + y²)^{-5/2} dy =
    // 2 T (2T² + 3a²) / (3 a⁴ (a² + T²)^{3/2}) with a² = 1 + T². At n = 32, T = 2 that is
    // +1.9e-4 relative: the reason Σ Ω_p is within 0.1 %.
    let h = 2.0 * t / f64::from(side);
    let a2 = 1.0 + t * t;
    let line = 2.0 * t * (2.0 * t * t + 3.0 * a2) / (3.0 * a2 * a2 * (a2 + t * t).powf(1.5));
    let flux = 4.0 * (-3.0 * t) * line;
    let predicted = -(h * h / 24.0) * flux / exact;
    let literal: f64 = tab.texels.iter().map(|x| f64::from(x.dir[2]) * h * h).sum();
    eprintln!(
        "[1] n=32: Σ Ω_p = {sum:.6}, exact 4·asin(T²/(1+T²)) = {exact:.6}, rel error {rel:+.3e}, \
         midpoint-rule prediction {predicted:+.3e}; the printed A·cosθ/d² (d = 1) would sum to {literal:.4} \
         ({:+.1} %)",
        (literal - exact) / exact * 100.0
    );
    assert!(rel.abs() < 1e-3, "Σ Ω_p off the pyramid by {rel}");
    // The next term is O(h⁴): (h / T)² = 1/256 of this one, so 10 % is a loose bound.
    assert!((rel - predicted).abs() < 0.1 * predicted, "error {rel} is not the midpoint rule's {predicted}");
    assert!((literal - exact).abs() / exact > 0.2, "the literal A·cosθ/d² should be far off");

    let bands: f64 = tab.texels.iter().map(|x| f64::from(x.band[1])).sum();
    let total = sum + bands;
    let rel_total = (total - TAU) / TAU;
    let rel_bands = (bands - (TAU - exact)) / (TAU - exact);
    eprintln!(
        "[1] Σ band.y = {bands:.6} (exact complement 2π − Ω_pyr = {:.6}, rel {rel_bands:+.3e}); \
         Σ Ω_p + Σ band.y = {total:.6} vs 2π: rel {rel_total:+.3e}",
        TAU - exact
    );
    assert!(rel_total.abs() < 5e-3, "Σ Ω_p + Σ band.y = {total}, not 2π");
    // Only the tile's boundary texels carry a band; Off carries none.
    for (k, x) in tab.texels.iter().enumerate() {
        let (i, j) = (k as u32 % side, k as u32 / side);
        let border = i == 0 || j == 0 || i + 1 == side || j + 1 == side;
        assert_eq!(border, x.band[1] > 0.0, "texel ({i}, {j}) band {:?}", x.band);
        assert_eq!(i + 1 == side, x.right == [0.0; 4]);
        assert_eq!(j + 1 == side, x.down == [0.0; 4]);
        if i + 1 < side {
            assert!(x.right[0] > 0.0 && x.right[3] > 0.0, "right edge normal toward +x");
        }
        if j + 1 < side {
            assert!(x.down[1] < 0.0 && x.down[3] > 0.0, "down edge normal toward −y");
        }
    }
    let off = HemisphereTable::new(side, APERTURE, BorderCompensation::Off);
    assert!(off.texels.iter().all(|x| x.band == [0.0; 4]));
    assert!(off.texels.iter().zip(&tab.texels).all(|(a, b)| a.dir == b.dir && a.right == b.right));
}

/// Test 2: uniform incident radiance L = 1 gives E = π with the cosine-weighted bands, the
/// pyramid's cosine-weighted fraction of π without, and more than π with the text's reading.
#[test]
fn uniform_radiance_gives_pi_with_cosine_weighted_compensation() {
    let side = 32;
    let e_of = |c| {
        let tab = HemisphereTable::new(side, APERTURE, c);
        let count = tab.texels.len();
        reduce(&tab, Vec3::new(0.2, 0.3, 0.9).normalize(), &vec![Vec3::ONE; count], &vec![1.0; count])
    };
    let cw = e_of(BorderCompensation::CosineWeighted);
    let off = e_of(BorderCompensation::Off);
    let paper = e_of(BorderCompensation::Paper);
    let t = 2.0f64;
    let fraction = pyramid_cosine_fraction(t);
    // The same as a closed form: the form factor of a square to a parallel differential area,
    // 4 × the corner rectangle's (1/2π)[a/√(1+a²) atan(b/√(1+a²)) + (a ↔ b)], a = b = T.
    let s = t / (1.0 + t * t).sqrt();
    let closed = 4.0 / PI * s * s.atan();
    assert!((fraction - closed).abs() < 1e-9, "θφ integration {fraction} vs form factor {closed}");
    let pi = std::f32::consts::PI;
    eprintln!(
        "[2] n=32, L=1: E/π CosineWeighted = {:.5}, Off = {:.5} (exact cosine-weighted fraction of the \
         square pyramid {fraction:.5}), Paper = {:.5}; H = {}",
        cw.e.x / pi,
        off.e.x / pi,
        paper.e.x / pi,
        cw.h
    );
    assert!((cw.e.x / pi - 1.0).abs() < 5e-3, "E = {} ≠ π", cw.e.x);
    assert!((f64::from(off.e.x / pi) - fraction).abs() < 5e-3 * fraction, "Off: E/π = {}", off.e.x / pi);
    assert!(paper.e.x > pi * 1.01, "Paper overestimates: E/π = {}", paper.e.x / pi);
    assert_eq!(cw.e.x, cw.e.y);
    assert!((cw.h - 1.0).abs() < 1e-5, "every texel at distance 1: H = {}", cw.h);
    // Constant radiance has no gradients (the tile is symmetric; no edge sees a difference).
    assert!(cw.rot[0].length() < 1e-4 && cw.trans[0] == Vec3::ZERO, "{:?} {:?}", cw.rot, cw.trans);
    let count = 32 * 32;
    let none = reduce(
        &HemisphereTable::new(side, APERTURE, BorderCompensation::Off),
        Vec3::Z,
        &vec![Vec3::ZERO; count],
        &vec![f32::INFINITY; count],
    );
    assert_eq!(none.h, f32::INFINITY);
    assert_eq!(none.trans, [Vec3::ZERO; 3], "an edge with two misses adds 0 (no NaN)");
}

/// The n → ∞ limits, for L linear in ω, of the two discretisations the rotational test
/// compares, as fractions of the exact value k (2π/3): the derivative of the compensated E
/// under a rotation of the frame is k a·((Σ w_k ω_k) × d) = s k a·(n × d) with
/// s = Σ (c_k Ω_k + band.x) c_k, and ∇_r = k n × (M d) with M's tangential diagonal
/// m = Σ Ω_k ω_x² + Σ ω_{k,x} band.zw (the 4-fold symmetry makes both isotropic). Both differ
/// from 2π/3 in the band, where the border texel's direction stands for the band's: its cosine
/// is larger than the band's and its sine smaller. With θ_m(φ) the aperture's edge
/// (tan θ_m = T / max(|cos φ|, |sin φ|)) and the band measures of `HemisphereTable::new`:
/// s∞ = ∫ [(1 − cos³θ_m)/3 + cos²θ_m/2 · cos θ_m] dφ (pyramid ∫cos² + band measure × cos θ_m),
/// m∞ = ∫ cos²φ [2/3 − cos θ_m + cos³θ_m/3 + K(θ_m) sin θ_m] dφ (pyramid ∫ω_x² + band).
fn band_model(t: f64) -> (f64, f64) {
    let steps = 200_000;
    let dphi = TAU / steps as f64;
    let (mut s, mut m) = (0.0, 0.0);
    for i in 0..steps {
        let phi = (i as f64 + 0.5) * dphi;
        let theta = (t / phi.cos().abs().max(phi.sin().abs())).atan();
        let c = theta.cos();
        let k = (PI / 2.0 - theta) / 2.0 + (2.0 * theta).sin() / 4.0;
        s += ((1.0 - c * c * c) / 3.0 + c * c * c / 2.0) * dphi;
        m += phi.cos().powi(2) * (2.0 / 3.0 - c + c * c * c / 3.0 + k * theta.sin()) * dphi;
    }
    (s / (TAU / 3.0), m / (TAU / 3.0))
}

/// The rotational check at one resolution and aperture, L = (1 + 0.8 ω·d, 1 + 0.5 ω·d2, 2):
/// (worst |FD − a·∇_r| / |∇_r| over the axes and the two varying channels, the worst
/// |FD − ρ a·∇_r| / |∇_r| with ρ the band model's s∞/m∞, the mean FD / exact and ∇_r / exact).
fn rotational_errors(side: u32, aperture: f32, n: Vec3, d: Vec3, d2: Vec3, rho: f32) -> [f32; 4] {
    let tab = HemisphereTable::new(side, aperture, BorderCompensation::CosineWeighted);
    let count = tab.texels.len();
    let e_in = |t: Vec3, b: Vec3, n: Vec3| -> RecordTerms {
        let rad: Vec<Vec3> = world_dirs(&tab, t, b, n)
            .iter()
            .map(|w| Vec3::new(1.0 + 0.8 * w.dot(d), 1.0 + 0.5 * w.dot(d2), 2.0))
            .collect();
        reduce_in_frame(&tab, t, b, n, &rad, &vec![1.0; count])
    };
    let (t, b) = frame(n);
    let base = e_in(t, b, n);
    // ∫_hemisphere ω ωᵀ dω = 2π/3 I, so the exact ∇_r of L = 1 + k ω·d is k (2π/3) n × d, and
    // the exact derivative of E under the rotation δ·a is a·∇_r.
    let exact = [0.8 * TAU as f32 / 3.0 * n.cross(d), 0.5 * TAU as f32 / 3.0 * n.cross(d2)];
    let (mut raw, mut model, mut fd_exact, mut r_exact, mut count_axes) = (0.0f32, 0.0f32, 0.0, 0.0, 0.0);
    for (g, ex) in base.rot.iter().zip(&exact) {
        r_exact += g.dot(*ex) / ex.length_squared() / 2.0;
    }
    // Small enough that the FD's O(ε²) term (≈ ε²/6 relative) is 2e-5; large enough that
    // f32 rounding of E (≈ 1e-6 of π) is 1e-4 of the difference.
    let eps = 0.01f32;
    for a in [t, b, (t + b).normalize(), (t - 2.0 * b).normalize()] {
        let (qp, qm) = (Quat::from_axis_angle(a, eps), Quat::from_axis_angle(a, -eps));
        let ep = e_in(qp * t, qp * b, qp * n);
        let em = e_in(qm * t, qm * b, qm * n);
        let fd = (ep.e - em.e) / (2.0 * eps);
        for ch in 0..2 {
            let g = a.dot(base.rot[ch]);
            raw = raw.max((fd[ch] - g).abs() / base.rot[ch].length());
            model = model.max((fd[ch] - rho * g).abs() / base.rot[ch].length());
            let ex = a.dot(exact[ch]);
            if ex.abs() > 0.2 * exact[ch].length() {
                fd_exact += fd[ch] / ex;
                count_axes += 1.0;
            }
        }
        assert!(fd.z.abs() < 1e-3, "constant channel changed under rotation: {}", fd.z);
    }
    assert!(base.rot[2].length() < 1e-4, "constant radiance has ∇_r = {}", base.rot[2]);
    [raw, model, fd_exact / count_axes, r_exact]
}

/// Test 3: ∇_r against central differences of E under rotations of the whole frame.
///
/// At 126.87° the bands hold 58 % of ∫ω_x² dω (∇_r is not cosine-weighted: the grazing
/// directions dominate it), and the compensation's "extend the border texel" moves both
/// discretisations off the exact value in opposite directions by an amount that does not
/// shrink with n: [`band_model`] predicts the limits, the test checks the measurement converges
/// to them and that, once the model's ratio is divided out, FD and ∇_r agree to the
/// discretisation's ~1 % (shrinking with n). A near-180° aperture (band ≈ 0) checks the raw
/// agreement.
#[test]
fn rotational_gradient_matches_finite_differences() {
    let n = Vec3::new(0.3, -0.5, 0.8).normalize();
    let d = Vec3::new(0.7, 0.2, 0.4).normalize();
    let d2 = Vec3::new(-0.3, 0.9, -0.2).normalize();
    let (s_inf, m_inf) = band_model(2.0);
    let rho = (s_inf / m_inf) as f32;
    eprintln!(
        "[3] band model at 126.87° (n → ∞): FD/exact → s∞ = {s_inf:.4}, ∇_r/exact → m∞ = {m_inf:.4}, \
         FD/∇_r → {rho:.4}"
    );
    let mut results = Vec::new();
    for side in [16, 32, 64] {
        let [raw, model, fd_ex, r_ex] = rotational_errors(side, APERTURE, n, d, d2, rho);
        eprintln!(
            "[3] 126.87°, n={side}: worst |FD − a·∇_r|/|∇_r| = {raw:.4}, after the band model's ratio {model:.4}; \
             FD/exact = {fd_ex:.4}, ∇_r/exact = {r_ex:.4}"
        );
        results.push((raw, model, fd_ex, r_ex));
    }
    let (raw32, model32, fd32, r32) = results[1];
    let (_, model64, fd64, r64) = results[2];
    assert!((fd32 - s_inf as f32).abs() < 0.01 && (r32 - m_inf as f32).abs() < 0.01, "the band model is off");
    assert!((fd64 - s_inf as f32).abs() <= (fd32 - s_inf as f32).abs() + 1e-3);
    assert!((r64 - m_inf as f32).abs() <= (r32 - m_inf as f32).abs() + 1e-3);
    assert!(model32 < 0.01, "n=32: FD and ρ·∇_r differ by {model32}");
    assert!(model64 <= model32, "n=64 ({model64}) is no closer than n=32 ({model32})");
    assert!(raw32 < (rho - 1.0).abs() + 0.01, "n=32: the raw gap {raw32} exceeds the band model's");
    // 170°: tan 85° = 11.4, the band is ≈ 0 of the hemisphere.
    let (s170, m170) = band_model(f64::from(85f32.to_radians().tan()));
    let mut wide = Vec::new();
    for side in [32, 64] {
        let [raw, _, fd_ex, r_ex] = rotational_errors(side, 170.0, n, d, d2, 1.0);
        eprintln!(
            "[3] 170°, n={side}: worst |FD − a·∇_r|/|∇_r| = {raw:.4}; FD/exact = {fd_ex:.4} (model {s170:.4}), \
             ∇_r/exact = {r_ex:.4} (model {m170:.4})"
        );
        wide.push(raw);
    }
    // Without a band the raw FD and ∇_r agree to the discretisation's O(1/n) (half a texel of
    // the boundary direction against a 0.3 rad wide periphery at n = 32: a few %).
    assert!(wide[0] < 0.03, "170°, n=32: FD and ∇_r differ by {}", wide[0]);
    assert!(wide[1] < wide[0], "170°: n=64 ({}) is no closer than n=32 ({})", wide[1], wide[0]);
}

/// Radiance and distance of one ray from `p` along `w` in the smooth scene: a ceiling z = 1
/// with L = (1 + 0.5 sin x, 1 + 0.5 sin y, 1).
fn smooth_scene(p: Vec3, w: Vec3) -> (Vec3, f32) {
    let s = (1.0 - p.z) / w.z;
    let x = p + w * s;
    (Vec3::new(1.0 + 0.5 * x.x.sin(), 1.0 + 0.5 * x.y.sin(), 1.0), s)
}

/// The occluder scene: a bright ceiling z = 1 (L = 1) behind a dark square (L = 0) at
/// z = 0.5, [0.05, 0.65] × [−0.45, 0.15] in its own axes, turned 0.5 rad about z.
fn occluder_scene(p: Vec3, w: Vec3) -> (Vec3, f32) {
    let s = (0.5 - p.z) / w.z;
    let x = p + w * s;
    // The square's own axes, turned 0.5 rad from the texel rows (see the test).
    let (c, si) = (0.5f32.cos(), 0.5f32.sin());
    let (qx, qy) = (c * x.x + si * x.y, -si * x.x + c * x.y);
    if (0.05..=0.65).contains(&qx) && (-0.45..=0.15).contains(&qy) {
        return (Vec3::ZERO, s);
    }
    (Vec3::ONE, (1.0 - p.z) / w.z)
}

/// The record's terms at `p` on the floor (n = +Z) by casting each texel's ray into `scene`.
fn cast(tab: &HemisphereTable, p: Vec3, scene: fn(Vec3, Vec3) -> (Vec3, f32)) -> RecordTerms {
    let n = Vec3::Z;
    let (t, b) = frame(n);
    let (rad, dist): (Vec<Vec3>, Vec<f32>) = world_dirs(tab, t, b, n).iter().map(|&w| scene(p, w)).unzip();
    reduce(tab, n, &rad, &dist)
}

/// The worst |FD − u·∇_t| / |∇_t| over the directions u and the varying channels, with the
/// step `eps`, against the table's own ∇_t.
fn translational_error(
    tab: &HemisphereTable,
    p: Vec3,
    scene: fn(Vec3, Vec3) -> (Vec3, f32),
    eps: f32,
    channels: usize,
) -> (f32, RecordTerms) {
    let base = cast(tab, p, scene);
    let mut worst = 0.0f32;
    for u in [Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0).normalize(), Vec3::new(1.0, -2.0, 0.0).normalize()] {
        let fd = (cast(tab, p + u * eps, scene).e - cast(tab, p - u * eps, scene).e) / (2.0 * eps);
        for ch in 0..channels {
            // Only the tangential part is compared (u ⊥ n); ∇_t also has a normal part.
            let g = base.trans[ch];
            worst = worst.max((fd[ch] - u.dot(g)).abs() / g.reject_from(Vec3::Z).length());
        }
    }
    (worst, base)
}

/// Test 4: ∇_t against central differences of E under translations, in a smooth scene and
/// across an occluder's silhouette.
#[test]
fn translational_gradient_matches_finite_differences() {
    let p = Vec3::new(0.3, -0.2, 0.0);
    // Off: FD and ∇_t are two discretisations of the same pyramid integral's derivative
    // (O(1/n): the edges reach from texel centre to texel centre, half a texel short of the
    // tile's boundary). CosineWeighted: the bands take their border texel's radiance, which
    // changes as the record moves; ∇_t has no term for that (the bands are far away on the
    // ceiling, 0.14 of E), so that gap does not shrink with n.
    let mut smooth = Vec::new();
    for c in [BorderCompensation::Off, BorderCompensation::CosineWeighted] {
        for side in [32, 64] {
            let tab = HemisphereTable::new(side, APERTURE, c);
            let (err, base) = translational_error(&tab, p, smooth_scene, 0.01, 2);
            eprintln!(
                "[4] smooth ceiling, {c:?}, n={side}: worst |FD − u·∇_t|/|∇_t,tangential| = {err:.4} \
                 (∇_t red {}, green {}; H = {:.4})",
                base.trans[0], base.trans[1], base.h
            );
            assert!(base.trans[2].length() < 1e-4, "the constant channel has ∇_t = {}", base.trans[2]);
            assert!(err < 0.05, "smooth case, {c:?}, n={side}: FD and ∇_t differ by {err}");
            smooth.push(err);
        }
    }
    assert!(smooth[1] < smooth[0], "Off: n=64 ({}) is no closer than n=32 ({})", smooth[1], smooth[0]);
    // The silhouette: the image of the occluder (0.5–0.9 away) moves by ε / r. Its sides are
    // turned 0.5 rad from the texel rows: along a side aligned with the rows a whole row of
    // texels flips at once and E(P) is a staircase of few tall steps. ε = 0.15 is 0.17–0.3 rad,
    // 1.3–2.4 centre texels (0.125 rad) and more towards the border, where texels are smaller:
    // the FD counts many flips along the silhouette, not 0 or 1 per row as at ε = 0.005
    // (printed below: quantised). Larger ε pays the FD's O(ε²) curvature, which the fine
    // table (n = 512) measures: its FD at ε = 0.01 (≈ 2 of its texels) against ε = 0.15.
    let p = Vec3::ZERO;
    let fine = HemisphereTable::new(512, APERTURE, BorderCompensation::Off);
    let fine_fd = |eps: f32| {
        let d = |u: Vec3| {
            (cast(&fine, p + u * eps, occluder_scene).e - cast(&fine, p - u * eps, occluder_scene).e) / (2.0 * eps)
        };
        Vec3::new(d(Vec3::X).x, d(Vec3::Y).x, 0.0)
    };
    let (fine_grad, fine_wide) = (fine_fd(0.01), fine_fd(0.15));
    eprintln!(
        "[4] occluder, fine table n=512: FD(ε=0.01) = {fine_grad}, FD(ε=0.15) = {fine_wide} \
         (the O(ε²) curvature at ε = 0.15: {:.4} relative)",
        (fine_wide - fine_grad).length() / fine_grad.length()
    );
    // The occluder stays off the tile's border texels at P ± ε: there the bands would take
    // its radiance too, a change ∇_t has no term for (as in the smooth case, but in steps).
    let tab = HemisphereTable::new(32, APERTURE, BorderCompensation::Off);
    let (t, b) = frame(Vec3::Z);
    for q in [Vec3::ZERO, Vec3::X * 0.15, -Vec3::X * 0.15, Vec3::Y * 0.15, -Vec3::Y * 0.15] {
        for (k, w) in world_dirs(&tab, t, b, Vec3::Z).into_iter().enumerate() {
            let (i, j) = (k % 32, k / 32);
            if i == 0 || j == 0 || i == 31 || j == 31 {
                assert_eq!(occluder_scene(p + q, w).0, Vec3::ONE, "border texel ({i}, {j}) sees the occluder");
            }
        }
    }
    for c in [BorderCompensation::Off, BorderCompensation::CosineWeighted] {
        let tab = HemisphereTable::new(32, APERTURE, c);
        let (err, base) = translational_error(&tab, p, occluder_scene, 0.15, 1);
        let g = base.trans[0].reject_from(Vec3::Z);
        let vs_fine = (g - fine_grad).length() / fine_grad.length();
        let sweep: Vec<String> = [0.005f32, 0.02, 0.05, 0.1, 0.2, 0.3]
            .iter()
            .map(|&eps| format!("ε={eps}: {:.3}", translational_error(&tab, p, occluder_scene, eps, 1).0))
            .collect();
        eprintln!(
            "[4] occluder, {c:?}, n=32, ε=0.15: worst |FD − u·∇_t|/|∇_t,tangential| = {err:.4}; ∇_t = {g} \
             (normal part {:.4}), |∇_t − fine FD|/|fine FD| = {vs_fine:.4}; the same worst error for other ε: {}",
            base.trans[0].z,
            sweep.join(", ")
        );
        assert!(err < 0.15, "occluder case: FD and ∇_t differ by {err}");
        // The staircase silhouette puts each side's ends within half a texel of the true
        // ones; the sides are ≈ 6–10 texels long at n = 32: ≲ 1/10.
        assert!(vs_fine < 0.1, "occluder case: ∇_t and the fine FD differ by {vs_fine}");
    }
}

fn record(p: Vec3, n: Vec3, r: f32, e: Vec3) -> Record {
    Record { p, n, r, e, rot: [Vec3::ZERO; 3], trans: [Vec3::ZERO; 3] }
}

/// Test 5: Ward's weight, the extrapolation and one record's accumulation.
#[test]
fn weight_extrapolation_and_accumulation() {
    let n = Vec3::new(0.0, 0.6, 0.8);
    let (t, _) = frame(n);
    let mut rec = record(Vec3::new(1.0, 2.0, 3.0), n, 0.5, Vec3::new(0.4, 0.5, 0.6));
    rec.rot = [Vec3::new(0.1, 0.0, 0.0), Vec3::new(0.0, 0.2, 0.0), Vec3::new(0.0, 0.0, 0.3)];
    rec.trans = [Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, -0.4, 0.0), Vec3::new(0.0, 0.0, 0.3)];
    let w_max = 100.0;
    assert_eq!(weight(&rec, rec.p, n, w_max, Some(0.05)), w_max);
    let mut last = f32::INFINITY;
    for s in [0.001f32, 0.01, 0.1, 0.3, 1.0, 3.0] {
        let w = weight(&rec, rec.p + t * s, n, w_max, Some(0.05));
        let expect = (rec.r / s).min(w_max);
        assert!((w - expect).abs() <= 1e-5 * expect, "w({s}) = {w}, expected {expect}");
        assert!(w <= last && (w < last || w == w_max));
        last = w;
    }
    // Normal divergence: 60° gives 1/√(1 − ½).
    let tilted = Quat::from_axis_angle(t, std::f32::consts::FRAC_PI_3) * n;
    assert!((weight(&rec, rec.p, tilted, w_max, Some(0.05)) - 2f32.sqrt()).abs() < 1e-5);
    // Ward's "in front" test: a record 0.1 in front of P with R = 0.5 is past −0.05 R =
    // −0.025; 0.01 is not. With tolerance 0.25 (−0.125) neither is; without the test (as 003
    // prints the interpolation) the weight is the plain formula's.
    assert_eq!(weight(&rec, rec.p - n * 0.1, n, w_max, Some(0.05)), 0.0);
    assert!(weight(&rec, rec.p - n * 0.01, n, w_max, Some(0.05)) > 0.0);
    assert!(weight(&rec, rec.p - n * 0.1, n, w_max, Some(0.25)) > 0.0);
    let plain = weight(&rec, rec.p - n * 0.1, n, w_max, None);
    assert!((plain - rec.r / 0.1).abs() < 1e-4, "{plain}");

    let q = rec.p + t * 0.2;
    assert_eq!(extrapolate(&rec, q, tilted, false, false), rec.e);
    let with_t = extrapolate(&rec, q, n, false, true);
    let expect = rec.e + Vec3::new(rec.trans[0].dot(t * 0.2), rec.trans[1].dot(t * 0.2), rec.trans[2].dot(t * 0.2));
    assert!((with_t - expect.max(Vec3::ZERO)).length() < 1e-6, "{with_t} vs {expect}");
    let far = extrapolate(&rec, rec.p - Vec3::X * 10.0, n, false, true);
    assert_eq!(far.x, 0.0, "clamped at 0");
    let axis = n.cross(tilted);
    let with_r = extrapolate(&rec, rec.p, tilted, true, false);
    let expect_r = rec.e + Vec3::new(axis.dot(rec.rot[0]), axis.dot(rec.rot[1]), axis.dot(rec.rot[2]));
    assert!((with_r - expect_r.max(Vec3::ZERO)).length() < 1e-6);

    // At P_k the gradients add nothing: (E_k w_max, w_max).
    let (sum, w) = accumulate(&[rec], rec.p, n, &interp(0.4, w_max, true));
    assert_eq!(w, w_max);
    assert!((sum - rec.e * w_max).length() < 1e-4 * w_max);
    // Beyond a·R the record does not pass w > 1/a: nothing accumulates.
    assert_eq!(accumulate(&[rec], rec.p + t * 0.21, n, &interp(0.4, w_max, true)), (Vec3::ZERO, 0.0));
    let (s2, w2) = accumulate(&[rec], rec.p + t * 0.19, n, &interp(0.4, w_max, false));
    assert!((w2 - 0.5 / 0.19).abs() < 1e-4 && (s2 - rec.e * w2).length() < 1e-5);
}

/// Test 6: the splat's NDC rectangle contains the projected sphere and touches it on every
/// side (the brief asked for 1 %: the refined search allows 1e-3, f32 rounding of NDC values
/// up to ~60 being ~1e-5 of the size).
#[test]
fn sphere_ndc_rect_is_a_tight_bound() {
    let mut rng = Rng(7);
    let (p00, p11, near) = (1.2f32, 1.6f32, 0.1f32);
    let project = |q: Vec3| [p00 * q.x / -q.z, p11 * q.y / -q.z];
    let on_sphere = |th: f32, ph: f32| Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
    // A (θ, φ) grid on the sphere (spacing ≈ 0.05 rad).
    let grid: Vec<(f32, f32)> = (0..64)
        .flat_map(|i| {
            let th = (i as f32 + 0.5) / 64.0 * std::f32::consts::PI;
            (0..128).map(move |j| (th, j as f32 / 128.0 * std::f32::consts::TAU))
        })
        .collect();
    let (mut worst_out, mut worst_grid, mut worst_refined) = (0.0f32, 0.0f32, 0.0f32);
    let mut paper_misses = 0;
    for s in 0..2000 {
        let radius = rng.range(0.01, 3.0);
        // Near ones (a hair past the near plane) and far ones; off-axis up to 2× the depth.
        let gap = if s % 4 == 0 { rng.range(1e-3, 0.05) } else { rng.range(0.05, 20.0) };
        let w = near + radius + gap;
        let c = Vec3::new(rng.range(-2.0, 2.0) * w, rng.range(-2.0, 2.0) * w, -w);
        let rect = sphere_ndc_rect(c, radius, p00, p11, near).expect("the sphere is in front of the near plane");
        let point = |th: f32, ph: f32| project(c + on_sphere(th, ph) * radius);
        // Containment: 500 random surface points and the grid.
        let random: Vec<Vec3> = (0..500).map(|_| rng.unit()).collect();
        // ⚠[gautron.splat-bounds] "Algorithm"'s TransformVertex: the centre ± (a·H, a·H) in view space, projected.
        let [px0, py0] = project(c - Vec3::new(radius, radius, 0.0));
        let [px1, py1] = project(c + Vec3::new(radius, radius, 0.0));
        let misses = random.iter().any(|u| {
            let [x, y] = project(c + *u * radius);
            x < px0 || x > px1 || y < py0 || y > py1
        });
        paper_misses += usize::from(misses);
        let grid_points = grid.iter().map(|&(th, ph)| on_sphere(th, ph));
        for u in random.iter().copied().chain(grid_points) {
            let [x, y] = project(c + u * radius);
            let tol = |e: f32| 1e-5 * e.abs().max(1.0);
            for (v, lo, hi) in [(x, rect[0], rect[2]), (y, rect[1], rect[3])] {
                worst_out = worst_out.max((lo - v) / lo.abs().max(1.0)).max((v - hi) / hi.abs().max(1.0));
                assert!(v >= lo - tol(lo) && v <= hi + tol(hi), "sphere {s} (c {c}, r {radius}): {v} outside {rect:?}");
            }
        }
        // Tightness: per edge, the grid's most extreme point, then a pattern search in (θ, φ)
        // from it (steps halving from the grid's spacing). Near off-axis spheres stretch the
        // neighbourhood of the tangent point over tens of NDC units, where the grid alone
        // misses the edge by up to ~0.5 % of the rectangle; the search reaches f32 rounding.
        let (wx, wy) = (rect[2] - rect[0], rect[3] - rect[1]);
        let edges: [(usize, f32, f32, f32); 4] =
            [(0, -1.0, rect[0], wx), (1, -1.0, rect[1], wy), (0, 1.0, rect[2], wx), (1, 1.0, rect[3], wy)];
        for (axis, sign, edge, size) in edges {
            let f = |th: f32, ph: f32| sign * point(th, ph)[axis];
            let (mut th, mut ph) = grid.iter().copied().max_by(|a, b| f(a.0, a.1).total_cmp(&f(b.0, b.1))).unwrap();
            let mut best = f(th, ph);
            worst_grid = worst_grid.max((sign * edge - best) / size);
            let mut step = std::f32::consts::PI / 64.0;
            while step > 1e-6 {
                let mut moved = false;
                for (dt, dp) in [
                    (1.0, 0.0),
                    (-1.0, 0.0),
                    (0.0, 1.0),
                    (0.0, -1.0),
                    (1.0, 1.0),
                    (-1.0, -1.0),
                    (1.0, -1.0),
                    (-1.0, 1.0),
                ] {
                    let v = f(th + dt * step, ph + dp * step);
                    if v > best {
                        (best, th, ph, moved) = (v, th + dt * step, ph + dp * step, true);
                    }
                }
                if !moved {
                    step *= 0.5;
                }
            }
            let g = (sign * edge - best) / size;
            worst_refined = worst_refined.max(g);
            assert!(g < 1e-3, "sphere {s} (c {c}, r {radius}): the rect {rect:?} is loose by {g} on edge {edge}");
        }
    }
    eprintln!(
        "[6] 2000 spheres × (500 random + 8192 grid) points: worst excursion outside the rect {worst_out:.2e} \
         (relative to max(1, |edge|)); worst gap between an edge and the most extreme surface point, as a \
         fraction of the rect's size: grid {worst_grid:.2e}, refined {worst_refined:.2e}; the text's \
         TransformVertex quad misses surface points of {paper_misses} of the 2000 spheres"
    );
    assert!(paper_misses > 100, "the off-axis spheres should show TransformVertex's error");
    // Reaching the near plane or behind the eye: no rectangle.
    assert!(sphere_ndc_rect(Vec3::new(0.0, 0.0, -1.0), 0.91, p00, p11, near).is_none());
    assert!(sphere_ndc_rect(Vec3::new(0.0, 0.0, -1.0), 0.95, p00, p11, near).is_none());
    assert!(sphere_ndc_rect(Vec3::new(3.0, 0.0, -0.5), 0.5, p00, p11, near).is_none());
    assert!(sphere_ndc_rect(Vec3::new(0.0, 0.0, 2.0), 0.5, p00, p11, near).is_none());
    assert!(sphere_ndc_rect(Vec3::new(0.0, 0.0, -1.0), 0.89, p00, p11, near).is_some());
}

/// A 64×48 G-buffer of a floor (y = 0, |x| ≤ 4, −3 ≤ z ≤ 3) and a back wall (z = −3,
/// |x| ≤ 4, 0 ≤ y ≤ 2.5) seen from (0, 1.2, 3); pixels above the wall see nothing.
/// Per pixel: (position, normal, R) where R is the distance to the other plane clamped to
/// 0.3 … 1.5 (a stand-in for the harmonic mean distance: the nearest surface dominates it).
fn gbuffer(width: u32, height: u32) -> Vec<Option<(Vec3, Vec3, f32)>> {
    let eye = Vec3::new(0.0, 1.2, 3.0);
    let forward = Vec3::new(0.0, -0.25, -1.0).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let tan_y = 0.5;
    let tan_x = tan_y * width as f32 / height as f32;
    let mut out = Vec::new();
    for y in 0..height {
        for x in 0..width {
            let u = (2.0 * (x as f32 + 0.5) / width as f32 - 1.0) * tan_x;
            let v = (1.0 - 2.0 * (y as f32 + 0.5) / height as f32) * tan_y;
            let d = (forward + right * u + up * v).normalize();
            let mut best: Option<(f32, Vec3, Vec3, f32)> = None;
            if d.y < 0.0 {
                let s = -eye.y / d.y;
                let q = eye + d * s;
                if q.x.abs() <= 4.0 && (-3.0..=3.0).contains(&q.z) {
                    best = Some((s, q, Vec3::Y, (q.z + 3.0).clamp(0.3, 1.5)));
                }
            }
            if d.z < 0.0 {
                let s = (-3.0 - eye.z) / d.z;
                let q = eye + d * s;
                if q.x.abs() <= 4.0 && (0.0..=2.5).contains(&q.y) && best.is_none_or(|b| s < b.0) {
                    best = Some((s, q, Vec3::Z, q.y.clamp(0.3, 1.5)));
                }
            }
            out.push(best.map(|(_, q, n, r)| (q, n, r)));
        }
    }
    out
}

/// The default interpolation's rules at accuracy `a` and clamp `w_max`, the gradients on or off.
fn interp(a: f32, w_max: f32, gradients: bool) -> Interpolation {
    Interpolation { a, w_max, in_front: Some(0.05), rotational: gradients, translational: gradients }
}

fn coverage(records: &[Record], gb: &[Option<(Vec3, Vec3, f32)>], a: f32, w_max: f32) -> Vec<(Vec3, f32)> {
    gb.iter()
        .map(|g| g.map_or((Vec3::ZERO, 0.0), |(p, n, _)| accumulate(records, p, n, &interp(a, w_max, true))))
        .collect()
}

fn shuffle<T>(v: &mut [T], rng: &mut Rng) {
    for i in (1..v.len()).rev() {
        let j = ((rng.next() * (i + 1) as f32) as usize).min(i);
        v.swap(i, j);
    }
}

/// Test 7: creation rounds until no candidate leave every valid pixel covered; the candidates
/// and the accumulation do not depend on the records' order.
#[test]
fn creation_rounds_cover_every_valid_pixel_independently_of_record_order() {
    // Tie-breaking on a hand-made image: a 16×8 image, two 8×8 tiles, all uncovered.
    let (w0, h0) = (16u32, 8u32);
    let mut valid = vec![true; (w0 * h0) as usize];
    let zero = vec![0.0; (w0 * h0) as usize];
    assert_eq!(candidates(&zero, &valid, w0, h0, 8, 0.4, 10), vec![(3, 3), (11, 3)]);
    assert_eq!(candidates(&zero, &valid, w0, h0, 8, 0.4, 1), vec![(3, 3)]);
    valid[(3 * w0 + 3) as usize] = false;
    assert_eq!(candidates(&zero, &valid, w0, h0, 8, 0.4, 10), vec![(4, 3), (11, 3)], "ties: lowest row-major");
    let mut cov = zero.clone();
    cov[(3 * w0 + 11) as usize] = 2.5;
    assert_eq!(candidates(&cov, &valid, w0, h0, 8, 0.4, 10)[1], (12, 3), "covered (Σw = 1/a) is not a candidate");
    // Partial tiles keep the nominal centre (3.5 from the tile's origin): in a 10×10 image
    // the tile at x = 8 holds columns 8–9 only.
    let open = vec![true; 100];
    assert_eq!(candidates(&[0.0; 100], &open, 10, 10, 8, 0.4, 10), vec![(3, 3), (9, 3), (3, 9), (9, 9)]);

    let (width, height, tile) = (64u32, 48u32, 8u32);
    let (a, w_max, budget) = (0.4f32, 100.0f32, 16u32);
    let gb = gbuffer(width, height);
    let valid: Vec<bool> = gb.iter().map(Option::is_some).collect();
    let n_valid = valid.iter().filter(|v| **v).count();
    assert!(n_valid > 1000 && n_valid < gb.len(), "the G-buffer has both planes and sky: {n_valid}");
    let mut rng = Rng(11);
    let mut records: Vec<Record> = Vec::new();
    let mut rounds = 0;
    let mut checked_order = 0;
    loop {
        let cov = coverage(&records, &gb, a, w_max);
        let wsum: Vec<f32> = cov.iter().map(|c| c.1).collect();
        let cands = candidates(&wsum, &valid, width, height, tile, a, budget);
        // Only records passing w > 1/a add up, so a pixel's Σw is 0 or above 1/a: the
        // creation test has no rounding-dependent margin.
        assert!(wsum.iter().all(|&w| w == 0.0 || w > 1.0 / a));
        // The records' order changes neither the candidates nor (beyond rounding) the sums.
        if records.len() > 8 {
            let mut shuffled = records.clone();
            shuffle(&mut shuffled, &mut rng);
            let cov2 = coverage(&shuffled, &gb, a, w_max);
            let wsum2: Vec<f32> = cov2.iter().map(|c| c.1).collect();
            assert_eq!(candidates(&wsum2, &valid, width, height, tile, a, budget), cands);
            for (x, y) in cov.iter().zip(&cov2) {
                assert!((x.1 - y.1).abs() <= 1e-5 * x.1.max(y.1), "Σw {} vs {}", x.1, y.1);
                assert!((x.0 - y.0).length() <= 1e-5 * x.0.length().max(y.0.length()), "Σ wE {} vs {}", x.0, y.0);
            }
            checked_order += 1;
        }
        if cands.is_empty() {
            for (k, v) in valid.iter().enumerate() {
                if *v {
                    assert!(wsum[k] >= 1.0 / a, "pixel {k} uncovered after the rounds: Σw = {}", wsum[k]);
                }
            }
            break;
        }
        assert!(cands.len() <= budget as usize);
        for &(x, y) in &cands {
            let k = (y * width + x) as usize;
            assert!(valid[k] && wsum[k] < 1.0 / a);
            let (p, n, r) = gb[k].expect("a candidate has geometry");
            let mut rec = record(p, n, r, Vec3::new(rng.range(0.1, 2.0), rng.range(0.1, 2.0), rng.range(0.1, 2.0)));
            for ch in 0..3 {
                rec.rot[ch] = (rng.unit() * 0.3).reject_from(n);
                rec.trans[ch] = (rng.unit() * 0.5).reject_from(n);
            }
            records.push(rec);
        }
        rounds += 1;
        assert!(rounds < 500, "the creation does not converge");
    }
    eprintln!(
        "[7] 64×48, tile 8, a = {a}, budget {budget}: {n_valid} valid pixels covered by {} records in {rounds} rounds \
         (order independence checked in {checked_order} rounds)",
        records.len()
    );
    assert!(checked_order > 0);
}

/// The record cache's invalidation (stage 7): a record lying on a moved object goes, one that
/// saw it or faces its new place is invalid (dropped or stale by the policy), one facing away
/// that never saw it stays; a light change invalidates every record.
#[test]
fn invalidation_drops_or_refreshes_what_a_change_touches() {
    use gi_render::cpu::gautron::{Changes, Fate, fate};
    let unit = (Vec3::splat(-0.5), Vec3::splat(0.5));
    let moved = (unit.0 + Vec3::X, unit.1 + Vec3::X);
    let changes =
        |refresh| Changes { moved: vec![5], bounds: vec![(unit, moved)], margin: 1e-3, lights: false, refresh };
    let none = [0u32; 4];
    let saw_5 = [1 << 5, 0, 0, 0];
    let saw_133 = [1 << 5, 0, 0, 0]; // draw 133 shares draw 5's bit: conservative
    let (c, r) = (changes(false), changes(true));
    // On the object (old or new place, or within the margin of its face).
    assert_eq!(fate(Vec3::new(0.0, 0.5005, 0.0), Vec3::Y, none, false, &c), Fate::Drop);
    assert_eq!(fate(Vec3::new(1.2, 0.0, 0.0), Vec3::Y, none, false, &r), Fate::Drop);
    // Facing away from both places, never saw it: kept (a stale one stays stale).
    let away = Vec3::new(-3.0, 0.0, 0.0);
    assert_eq!(fate(away, Vec3::NEG_X, none, false, &c), Fate::Keep);
    assert_eq!(fate(away, Vec3::NEG_X, none, true, &c), Fate::Stale);
    // Saw it (its bit): invalid, even facing away from the new place.
    assert_eq!(fate(away, Vec3::NEG_X, saw_5, false, &c), Fate::Drop);
    assert_eq!(fate(away, Vec3::NEG_X, saw_133, false, &r), Fate::Stale);
    // Facing the new place: it could see it now.
    assert_eq!(fate(away, Vec3::X, none, false, &c), Fate::Drop);
    assert_eq!(fate(away, Vec3::X, none, false, &r), Fate::Stale);
    // A plane through the box's far side facing away: the box is behind it.
    assert_eq!(fate(Vec3::new(1.6, 3.0, 0.0), Vec3::X, none, false, &c), Fate::Keep);
    // A light change: every record.
    let lights = Changes { lights: true, refresh: true, ..Default::default() };
    assert_eq!(fate(away, Vec3::NEG_X, none, false, &lights), Fate::Stale);
}
