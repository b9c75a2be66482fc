//! CPU twin of Soler et al.'s multi-resolution screen-space indirect illumination (004 §3–4):
//! the screen-to-surface area (Eq. 2), the point-to-disc form factor (Eq. 4), the voting
//! filter of the mip levels (Eq. 5), the ring of samples (§4, Fig. 3), the gather at one
//! texel (Eq. 3) and the joint bilateral upsampling weights. The GPU kernels are
//! `shaders/soler/{vote,gather,upsample}.wgsl`; tests compare them texel by texel.
//!
//! Readings chosen where the text is garbled or silent (also in `docs/preset-schema.md`):
//! - ⚠[soler.eq3-half-angles] Eq. 3 prints `4 tan f_h tan f_v`; Eq. 2's half angles
//!   `4 tan(f_h/2) tan(f_v/2)` are the area of the screen rectangle at unit depth, so we use
//!   those.
//! - ⚠[soler.form-factor-pi] Eq. 4 (point-to-disc) is the *form factor*
//!   F = R² cosθ / (r² + R²): for r ≫ R it tends to cosθ cosθ' ds / (π r²), 1/π of Eq. 1's
//!   kernel. Eq. 1 carries the BRDF ρ (ρ_d/π for a diffuse receiver), so the kernel that
//!   replaces Eq. 1's is π F; the receiver then reflects E = Σ L_i π F_i as c·DI/π · E.
//!   [`kernel`] returns π F (or Eq. 1's kernel).
//! - ⚠[soler.vote-depth-relative] Eq. 5's g₃ takes z_j − z_i in scene units; we divide by z_i
//!   (relative depth) so that σ₃ does not depend on the scene's scale. ⚠[soler.vote-apron] The
//!   L1 neighbourhood of a sub-pixel reaches one texel outside its 2×2 block (the apron);
//!   texels outside the image or on the background take no part. The winner's position, depth
//!   and normal go down (no averaging); radiance goes down as the mean over the block's texels
//!   inside the image (background counts as black), so that a coarse texel emits the power of
//!   its sub-pixels.
//! - ⚠[soler.ring-spiral] The ring (Fig. 3): the first (finest) gathered level samples the full
//!   disc of radius r, every other level the annulus r/2 … r, both in the level's own texels; N
//!   samples on a Vogel spiral (radius √ of the area fraction, golden-angle steps) rotated per
//!   texel and frame, each standing for 1/N of the area. ⚠[soler.level-scale] The factor 2^{2k}
//!   of §4 is in Eq. 2's W, H: they are the level's size.

use glam::{Vec2, Vec3};

use crate::maths::{GOLDEN_ANGLE, pcg_hash};

/// One texel of a mip level (or of the G-buffer at level 0).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Texel {
    /// World position.
    pub position: Vec3,
    /// View depth z (> 0 on a surface; 0 on the background).
    pub depth: f32,
    pub normal: Vec3,
    /// Radiance leaving the texel (the previous bounce; direct light for the first).
    pub radiance: Vec3,
    /// Specular intensity SI and power SP (the G-buffer's material, voted down with the
    /// winner); only the glossy reflection reads it.
    pub material: Vec2,
}

impl Texel {
    pub fn valid(&self) -> bool {
        self.depth > 0.0
    }
}

/// A mip level: `width` × `height` texels, row-major.
#[derive(Clone, Debug, Default)]
pub struct Level {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Texel>,
}

impl Level {
    pub fn at(&self, x: i64, y: i64) -> Option<&Texel> {
        if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
            return None;
        }
        self.texels.get((y as u64 * self.width as u64 + x as u64) as usize)
    }
}

/// exp(−x² / 2σ²).
pub fn gaussian(x: f32, sigma: f32) -> f32 {
    (-(x * x) / (2.0 * sigma * sigma).max(1e-12)).exp()
}

/// Sample `i` of `n` of the ring at one texel (Fig. 3): its offset in the level's texels
/// (rounded to the nearest texel) and the screen area dP it stands for (level texels²).
/// `full_disc`: the first gathered level samples the whole disc of radius `r`.
pub fn ring_sample(i: u32, n: u32, r: f32, full_disc: bool, rotation: f32) -> (Vec2, f32) {
    let (rho, dp) = ring_radius(i, n, r, full_disc);
    (ring_offset(rho, rotation + i as f32 * GOLDEN_ANGLE), dp)
}

/// The distance of sample `i` of `n` from the texel (√ of its area fraction of the ring) and
/// the area dP each sample stands for.
pub fn ring_radius(i: u32, n: u32, r: f32, full_disc: bool) -> (f32, f32) {
    let inner = if full_disc { 0.0 } else { 0.5 * r };
    let u = (i as f32 + 0.5) / n.max(1) as f32;
    let rho = (inner * inner + u * (r * r - inner * inner)).sqrt();
    (rho, std::f32::consts::PI * (r * r - inner * inner) / n.max(1) as f32)
}

/// The texel offset at distance `rho` and angle `phi` (rounded to the nearest texel).
pub fn ring_offset(rho: f32, phi: f32) -> Vec2 {
    // WGSL's round() rounds halves to even, Rust's round() away from zero.
    Vec2::new((rho * phi.cos()).round_ties_even(), (rho * phi.sin()).round_ties_even())
}

/// The spiral's rotation at texel (x, y) of level `level` in frame `frame` (radians).
pub fn ring_rotation(x: u32, y: u32, level: u32, frame: u32) -> f32 {
    let h = pcg_hash(x ^ pcg_hash(y ^ pcg_hash(level ^ pcg_hash(frame))));
    (h >> 8) as f32 / (1u32 << 24) as f32 * std::f32::consts::TAU
}

/// The camera quantities Eq. 2 needs.
#[derive(Clone, Copy, Debug)]
pub struct ScreenCamera {
    pub eye: Vec3,
    /// tan(f_h/2), tan(f_v/2).
    pub tan_half: Vec2,
    /// The level's size in texels (W, H of Eq. 2).
    pub size: Vec2,
}

/// Eq. 2: the scene area ds a screen area `dp` (level texels²) covers at texel `t`:
/// z² · 4 tan(f_h/2) tan(f_v/2) · dP / (W H) · cos α / cos β, with α the angle between the
/// view ray and the optical axis (cos α = z / distance) and β between the surface normal and
/// the ray (cos β clamped below by `min_cos_beta`, our bound: grazing texels would stand for
/// unbounded areas).
pub fn surface_area(t: &Texel, dp: f32, cam: &ScreenCamera, min_cos_beta: f32) -> f32 {
    area_factor(t, cam.eye, min_cos_beta) * 4.0 * cam.tan_half.x * cam.tan_half.y * dp / (cam.size.x * cam.size.y)
}

/// Eq. 2's z² · cos α / cos β at texel `t` seen from `eye` (cos β clamped below by
/// `min_cos_beta`): its surface area per unit screen area, up to the level's constant.
pub fn area_factor(t: &Texel, eye: Vec3, min_cos_beta: f32) -> f32 {
    let to_eye = eye - t.position;
    let dist = to_eye.length().max(1e-12);
    let cos_alpha = (t.depth / dist).min(1.0);
    let cos_beta = (t.normal.dot(to_eye) / dist).abs().max(min_cos_beta);
    t.depth * t.depth * cos_alpha / cos_beta
}

/// The kernel that multiplies a sample's radiance: Eq. 1's cosθ cosθ' ds / r², or (with
/// `disc`) π × Eq. 4's point-to-disc form factor, R² = cosθ' ds / π (see the module).
pub fn kernel(cos_theta: f32, cos_theta_p: f32, ds: f32, r2: f32, disc: bool) -> f32 {
    if disc {
        let big_r2 = cos_theta_p * ds / std::f32::consts::PI;
        std::f32::consts::PI * big_r2 * cos_theta / (r2 + big_r2).max(1e-20)
    } else {
        cos_theta * cos_theta_p * ds / r2.max(1e-20)
    }
}

/// The gather's parameters at one level.
#[derive(Clone, Copy, Debug)]
pub struct GatherParams {
    pub samples: u32,
    pub radius: f32,
    pub full_disc: bool,
    pub level: u32,
    pub frame: u32,
    pub disc: bool,
    pub min_cos_beta: f32,
    /// The near field's cut (`pipeline.near_field`): senders at this distance or farther
    /// are left to the VPL gather. 0: none.
    pub near_cut: f32,
}

/// A level's voxel grid (004 §4 "Visibility"): `words` u32 per column of `slices` bits, bit s
/// set where slice s of view depth z₀ + (z₁ − z₀)·[s, s + 1)/slices is inside a solid.
#[derive(Clone, Debug, Default)]
pub struct VoxelGrid {
    pub width: u32,
    pub height: u32,
    pub words: u32,
    pub slices: u32,
    pub z0: f32,
    pub z1: f32,
    pub bits: Vec<u32>,
}

/// The slice of view depth `z` (0 in front of the grid, `slices` behind it).
pub fn slice_of(z: f32, z0: f32, z1: f32, slices: u32) -> i32 {
    let s = ((z - z0) / (z1 - z0).max(1e-12) * slices as f32).floor();
    s.clamp(0.0, slices as f32) as i32
}

/// The depth a surface crossing toggles its column at (`voxel_toggle_depth` in
/// `shaders/soler/voxel_common.wgsl`): its view depth `z` at the column's centre, moved back by
/// `bias` × `slope` (|∂z/∂x| + |∂z/∂y| per texel), at most `cap` (a depth), where the surface
/// faces the viewer; a surface facing away stays at `z`.
pub fn toggle_depth(z: f32, slope: f32, facing: bool, bias: f32, cap: f32) -> f32 {
    if facing { z + (bias * slope).min(cap) } else { z }
}

/// Word `w` of the bits a surface at slice `first` toggles: slices `first` … `slices` − 1.
pub fn mask_from(first: i32, w: u32, slices: u32) -> u32 {
    let lo = (w * 32) as i32;
    let hi = (lo + 32).min(slices as i32);
    if first >= hi {
        return 0;
    }
    let mut m = u32::MAX;
    if first > lo {
        m <<= (first - lo) as u32;
    }
    if hi - lo < 32 {
        m &= (1u32 << (hi - lo) as u32) - 1;
    }
    m
}

/// One column of the solid voxelization: the XOR of what every surface crossing the column
/// at view depth `depths[i]` toggles (Eisemann & Décoret).
pub fn voxelize_column(depths: &[f32], z0: f32, z1: f32, slices: u32, words: u32) -> Vec<u32> {
    let mut col = vec![0u32; words as usize];
    for &z in depths {
        let first = slice_of(z, z0, z1, slices);
        for (w, c) in col.iter_mut().enumerate() {
            *c ^= mask_from(first, w as u32, slices);
        }
    }
    col
}

/// The next coarser grid: each column the AND of the (up to four) columns of its 2×2 block.
pub fn and_down(fine: &VoxelGrid) -> VoxelGrid {
    let (w, h, n) = (fine.width.div_ceil(2), fine.height.div_ceil(2), fine.words as usize);
    let mut bits = vec![u32::MAX; (w * h) as usize * n];
    for y in 0..h {
        for x in 0..w {
            for i in 0..4 {
                let (fx, fy) = (2 * x + i % 2, 2 * y + i / 2);
                if fx < fine.width && fy < fine.height {
                    let src = ((fy * fine.width + fx) as usize) * n;
                    let dst = ((y * w + x) as usize) * n;
                    for k in 0..n {
                        bits[dst + k] &= fine.bits[src + k];
                    }
                }
            }
        }
    }
    VoxelGrid { width: w, height: h, bits, ..fine.clone() }
}

/// v_i of the march from texel `a` (view depth `za`) to texel `b` (`zb`): false when a solid
/// voxel lies on the way. Steps of one texel along the major axis, depth interpolated as 1/z
/// (perspective-correct), `bias_px` texels skipped at both ends, the slice tested
/// `depth_bias` slices in front of the line.
pub fn march_visible(
    g: &VoxelGrid,
    a: (i64, i64),
    za: f32,
    b: (i64, i64),
    zb: f32,
    bias_px: f32,
    depth_bias: f32,
) -> bool {
    let d = Vec2::new((b.0 - a.0) as f32, (b.1 - a.1) as f32);
    let n = d.x.abs().max(d.y.abs());
    let steps = n.ceil() as i64;
    for i in 1..steps {
        let fi = i as f32;
        if fi < bias_px || n - fi < bias_px {
            continue;
        }
        let t = fi / n;
        // As WGSL's round(): halves to even (a + d·t often lands on one: d = (4, 2), t = ¼).
        let q = Vec2::new(a.0 as f32, a.1 as f32) + d * t;
        let p = Vec2::new(q.x.round_ties_even(), q.y.round_ties_even());
        let (px, py) = (p.x as i64, p.y as i64);
        if px < 0 || py < 0 || px >= g.width as i64 || py >= g.height as i64 {
            continue;
        }
        let z = 1.0 / (1.0 / za + (1.0 / zb - 1.0 / za) * t);
        let sf = ((z - g.z0) / (g.z1 - g.z0).max(1e-12) * g.slices as f32 - depth_bias).floor();
        if sf < 0.0 || sf >= g.slices as f32 {
            continue;
        }
        let s = sf as u32;
        let word = g.bits[((py as u64 * g.width as u64 + px as u64) * g.words as u64 + (s / 32) as u64) as usize];
        if (word >> (s % 32)) & 1 != 0 {
            return false;
        }
    }
    true
}

/// Eq. 3 at texel (x, y) of `level`: the irradiance E = Σ L_i K_i of the ring's samples
/// (no visibility: v_i = 1). Samples off the image, on the background or on the texel
/// itself add nothing.
pub fn gather(level: &Level, x: u32, y: u32, cam: &ScreenCamera, p: GatherParams) -> Vec3 {
    gather_visible(level, x, y, cam, p, None)
}

/// [`gather`] with visibility: each sample's path marched through `vis` (the level's grid,
/// the march's end bias in texels and depth bias in slices); hidden samples add nothing.
pub fn gather_visible(
    level: &Level,
    x: u32,
    y: u32,
    cam: &ScreenCamera,
    p: GatherParams,
    vis: Option<(&VoxelGrid, f32, f32)>,
) -> Vec3 {
    gather_glossy(level, x, y, cam, p, vis, None).0
}

/// [`gather_visible`] with the glossy reflection (`cpu::soler_glossy`): the irradiance E
/// and the light the receiver's specular lobe reflects toward the eye, Σ L_i K_i f_s(l_i, v);
/// with `gloss`, a glossy receiver draws its samples' angles from f(θ) and each stands for
/// dP / (2π p(θ)).
pub fn gather_glossy(
    level: &Level,
    x: u32,
    y: u32,
    cam: &ScreenCamera,
    p: GatherParams,
    vis: Option<(&VoxelGrid, f32, f32)>,
    gloss: Option<&crate::cpu::soler_glossy::Gloss>,
) -> (Vec3, Vec3) {
    let Some(rx) = level.at(x as i64, y as i64).filter(|t| t.valid()) else { return (Vec3::ZERO, Vec3::ZERO) };
    gather_for(level, (x, y), rx, cam, p, vis, gloss)
}

/// GI Lab's mix with Nguyen et al. (`shaders/soler/hcb_gather.wgsl`): the irradiance one
/// level sends a point `x` (an HCB sample: its position, normal and view depth) that lies
/// under G-buffer pixel `pixel`: the ring of the level's texel `pixel >> level` with `x` as
/// the receiver. The sample's irradiance is the sum over the gathered levels.
pub fn gather_at(
    level: &Level,
    pixel: (u32, u32),
    x: &Texel,
    cam: &ScreenCamera,
    p: GatherParams,
    vis: Option<(&VoxelGrid, f32, f32)>,
) -> Vec3 {
    let q = (
        (pixel.0 >> p.level).min(level.width.saturating_sub(1)),
        (pixel.1 >> p.level).min(level.height.saturating_sub(1)),
    );
    gather_for(level, q, x, cam, p, vis, None).0
}

/// The ring of texel (x, y) of `level` gathered at receiver `rx` (the texel itself, or a
/// point under it): the irradiance and, with `gloss`, the glossy reflection.
fn gather_for(
    level: &Level,
    (x, y): (u32, u32),
    rx: &Texel,
    cam: &ScreenCamera,
    p: GatherParams,
    vis: Option<(&VoxelGrid, f32, f32)>,
    gloss: Option<&crate::cpu::soler_glossy::Gloss>,
) -> (Vec3, Vec3) {
    let march = |a: (i64, i64), rx: &Texel, b: (i64, i64), s: &Texel| match vis {
        Some((g, bias_px, depth_bias)) => march_visible(g, a, rx.depth, b, s.depth, bias_px, depth_bias),
        None => true,
    };
    gather_with(level, (x, y), rx, cam, p, &march, gloss)
}

/// A visibility test between receiver texel a (the point `rx`) and sender texel b (`s`).
pub type VisibleFn<'a> = dyn Fn((i64, i64), &Texel, (i64, i64), &Texel) -> bool + 'a;

/// The ring of texel (x, y) of `level` gathered at receiver `rx` with any visibility test
/// (the voxel march, none, or exact ray casts in tests): irradiance and glossy reflection.
pub fn gather_with(
    level: &Level,
    (x, y): (u32, u32),
    rx: &Texel,
    cam: &ScreenCamera,
    p: GatherParams,
    visible: &VisibleFn<'_>,
    gloss: Option<&crate::cpu::soler_glossy::Gloss>,
) -> (Vec3, Vec3) {
    use crate::cpu::soler_glossy as glossy;
    let v = (cam.eye - rx.position).normalize_or_zero();
    let (mut e, mut spec) = (Vec3::ZERO, Vec3::ZERO);
    for (o, dp) in receiver_samples(rx, x, y, cam, p, gloss) {
        if o == Vec2::ZERO {
            continue;
        }
        let Some(s) = level.at(x as i64 + o.x as i64, y as i64 + o.y as i64).filter(|t| t.valid()) else {
            continue;
        };
        let Some((w, r2, cos_t, cos_tp)) = facing(rx, s, p.near_cut) else { continue };
        if !visible((x as i64, y as i64), rx, (x as i64 + o.x as i64, y as i64 + o.y as i64), s) {
            continue;
        }
        let ds = surface_area(s, dp, cam, p.min_cos_beta);
        let light = s.radiance * kernel(cos_t, cos_tp, ds, r2, p.disc);
        e += light;
        if gloss.is_some() {
            spec += light * glossy::specular(rx.normal, w, v, rx.material);
        }
    }
    (e, spec)
}

/// The ring samples of receiver `rx` at texel (x, y) (Fig. 3): each one's texel offset and
/// the screen area it stands for (dP, or dP / (2π p(θ)) where `gloss` importance samples
/// the receiver).
pub fn receiver_samples(
    rx: &Texel,
    x: u32,
    y: u32,
    cam: &ScreenCamera,
    p: GatherParams,
    gloss: Option<&crate::cpu::soler_glossy::Gloss>,
) -> Vec<(Vec2, f32)> {
    use crate::cpu::soler_glossy as glossy;
    let rotation = ring_rotation(x, y, p.level, p.frame);
    let lobe = gloss.and_then(|g| glossy::receiver_lobe(g, rx.position, rx.normal, cam.eye, rx.material, cam.tan_half));
    let alpha = gloss.map_or(0.0, |g| g.alpha);
    (0..p.samples)
        .map(|i| {
            let (rho, dp) = ring_radius(i, p.samples, p.radius, p.full_disc);
            let (phi, weight) = glossy::warp(rotation + i as f32 * GOLDEN_ANGLE, lobe, alpha);
            (ring_offset(rho, phi), dp * weight)
        })
        .collect()
}

/// Whether sender `s` can light receiver `rx` (Eq. 1's cosines both positive, closer than
/// the near field's cut when there is one): the unit direction to it, r², cos θ and cos θ'.
pub fn facing(rx: &Texel, s: &Texel, near_cut: f32) -> Option<(Vec3, f32, f32, f32)> {
    let d = s.position - rx.position;
    let r2 = d.length_squared();
    if r2 <= 0.0 || (near_cut > 0.0 && r2 >= near_cut * near_cut) {
        return None;
    }
    let w = d / r2.sqrt();
    let (cos_t, cos_tp) = (rx.normal.dot(w).max(0.0), (-s.normal.dot(w)).max(0.0));
    (cos_t > 0.0 && cos_tp > 0.0).then_some((w, r2, cos_t, cos_tp))
}

/// The σ of the upsampling's range weights (joint bilateral upsampling, Kopf et al.;
/// ⚠[soler.upsample-weights] 004 §4 gives no weights).
#[derive(Clone, Copy, Debug)]
pub struct UpsampleSigmas {
    /// On the relative depth difference (z_c − z) / z.
    pub depth: f32,
    /// On 1 − n·n_c.
    pub normal: f32,
}

/// The four coarse texels under fine texel (x, y) and their bilinear weights.
pub fn coarse_footprint(x: u32, y: u32) -> [((i64, i64), f32); 4] {
    let c = Vec2::new((x as f32 + 0.5) * 0.5 - 0.5, (y as f32 + 0.5) * 0.5 - 0.5);
    let q = c.floor();
    let f = c - q;
    let (qx, qy) = (q.x as i64, q.y as i64);
    [
        ((qx, qy), (1.0 - f.x) * (1.0 - f.y)),
        ((qx + 1, qy), f.x * (1.0 - f.y)),
        ((qx, qy + 1), (1.0 - f.x) * f.y),
        ((qx + 1, qy + 1), f.x * f.y),
    ]
}

/// Joint bilateral upsampling of `coarse_light` (one value per texel of `coarse`) at fine texel
/// `fine`, (x, y): bilinear × depth × normal weights over the four coarse texels, background
/// texels excluded. ⚠[soler.upsample-fallback] When every weight vanishes (a thin feature no
/// coarse texel resembles), the most similar valid coarse texel of the four (depth × normal
/// weight alone) gives its light; with none valid, zero. Light never comes from the background.
pub fn upsample(coarse: &Level, coarse_light: &[Vec3], fine: &Texel, x: u32, y: u32, s: UpsampleSigmas) -> Vec3 {
    if !fine.valid() {
        return Vec3::ZERO;
    }
    let (mut sum, mut wsum) = (Vec3::ZERO, 0.0);
    let mut best = (0.0f32, Vec3::ZERO);
    for ((cx, cy), b) in coarse_footprint(x, y) {
        let Some(c) = coarse.at(cx, cy).filter(|t| t.valid()) else { continue };
        let light = coarse_light[(cy as u64 * coarse.width as u64 + cx as u64) as usize];
        let range = gaussian((c.depth - fine.depth) / fine.depth, s.depth)
            * gaussian(1.0 - fine.normal.dot(c.normal), s.normal);
        sum += light * b * range;
        wsum += b * range;
        if range > best.0 {
            best = (range, light);
        }
    }
    if wsum > 1e-6 { sum / wsum } else { best.1 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    /// Eq. 4 against the form factor of a disc integrated numerically: a receiver facing a
    /// disc of radius R on its axis at distance r (cosθ = cosθ' = 1) has
    /// F = ∫ cosθ cosθ' / (π d²) dA = R² / (r² + R²); our kernel is π F, and for r ≫ R both
    /// tend to Eq. 1's cosθ cosθ' ds / r².
    #[test]
    fn the_point_to_disc_kernel_is_pi_times_the_integrated_disc_form_factor() {
        for (r, big_r) in [(1.0f32, 0.1f32), (1.0, 0.5), (0.3, 1.0), (2.0, 0.05)] {
            let n_r = 2000;
            let mut f = 0.0f64;
            for i in 0..n_r {
                let rho = (i as f64 + 0.5) / n_r as f64 * big_r as f64;
                let d2 = (r as f64).powi(2) + rho * rho;
                let cos = r as f64 / d2.sqrt();
                let ring = 2.0 * std::f64::consts::PI * rho * (big_r as f64 / n_r as f64);
                f += cos * cos / (std::f64::consts::PI * d2) * ring;
            }
            let ds = PI * big_r * big_r;
            let k = kernel(1.0, 1.0, ds, r * r, true);
            assert!((k as f64 - PI as f64 * f).abs() <= 1e-3 * PI as f64 * f, "r {r} R {big_r}: {k} vs π·{f}");
            if r > 10.0 * big_r {
                let point = kernel(1.0, 1.0, ds, r * r, false);
                assert!((k - point).abs() <= 0.01 * point, "far field: disc {k} vs point {point}");
            }
        }
        // Bounded where Eq. 1's kernel is not.
        assert!(kernel(1.0, 1.0, 0.01, 0.0, true).is_finite());
        assert!(kernel(1.0, 1.0, 0.01, 1e-8, false) > 1e5);
    }

    /// Eq. 2 over every texel of a plane facing the camera sums to the plane's visible area
    /// (2 z tan(f_h/2)) · (2 z tan(f_v/2)): cos α = cos β for a plane parallel to the screen.
    #[test]
    fn screen_areas_of_a_facing_plane_sum_to_its_visible_area() {
        let (w, h, z) = (64u32, 36u32, 3.0f32);
        let tan_half = Vec2::new(0.7, 0.7 * 36.0 / 64.0);
        let cam = ScreenCamera { eye: Vec3::ZERO, tan_half, size: Vec2::new(w as f32, h as f32) };
        let mut sum = 0.0;
        for y in 0..h {
            for x in 0..w {
                let ndc = Vec2::new((x as f32 + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h as f32 * 2.0);
                let p = Vec3::new(ndc.x * tan_half.x * z, ndc.y * tan_half.y * z, -z);
                let t = Texel { position: p, depth: z, normal: Vec3::Z, radiance: Vec3::ONE, ..Default::default() };
                sum += surface_area(&t, 1.0, &cam, 0.01);
            }
        }
        let want = 4.0 * z * z * tan_half.x * tan_half.y;
        assert!((sum - want).abs() <= 1e-3 * want, "{sum} vs {want}");
    }

    /// Fig. 3: the first level's samples fill the disc, the others the ring r/2 … r, and
    /// their areas dP add up to it.
    #[test]
    fn the_ring_samples_cover_the_annulus_and_its_area() {
        let (n, r) = (64u32, 20.0f32);
        for full in [true, false] {
            let inner = if full { 0.0 } else { 0.5 * r };
            let mut area = 0.0;
            let mut inside_half = 0;
            for i in 0..n {
                let (o, dp) = ring_sample(i, n, r, full, 0.3);
                let rho = o.length();
                assert!(rho <= r + 0.75 && rho >= inner - 0.75, "sample {i} at {rho}");
                inside_half += (rho < 0.5 * r) as u32;
                area += dp;
            }
            assert!((area - PI * (r * r - inner * inner)).abs() < 1e-2, "{area}");
            // Uniform in area: a quarter of the disc's samples lie inside r/2.
            if full {
                assert!((14..=18).contains(&inside_half), "{inside_half} of {n} inside r/2");
            }
        }
        assert_ne!(ring_rotation(3, 4, 1, 0), ring_rotation(3, 4, 1, 1), "the spiral turns each frame");
    }

    /// The slope bias (voxel_toggle_depth): a surface facing the viewer toggles b × its slope
    /// behind its centre's depth, at most the cap; one facing away, and b = 0 (the paper), at
    /// the centre's depth.
    #[test]
    fn a_facing_surface_toggles_behind_its_texel_and_a_receding_one_at_its_centre() {
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        assert!(close(toggle_depth(2.0, 0.4, true, 0.5, 1.0), 2.2));
        assert!(close(toggle_depth(2.0, 10.0, true, 0.5, 1.0), 3.0), "capped");
        assert_eq!(toggle_depth(2.0, 0.4, false, 0.5, 1.0), 2.0);
        assert_eq!(toggle_depth(2.0, 0.4, true, 0.0, 1.0), 2.0);
    }

    /// Solid voxelization of one column: inside a closed box (entered at 2, left at 3) the
    /// parity is 1, outside 0; a second box behind it adds its own interval.
    #[test]
    fn voxel_parity_is_one_inside_closed_boxes_and_zero_outside() {
        let (z0, z1, slices) = (0.0, 8.0, 128u32);
        let col = voxelize_column(&[3.0, 2.0, 5.0, 6.0], z0, z1, slices, 4);
        let bit = |z: f32| {
            let s = slice_of(z, z0, z1, slices) as u32;
            (col[(s / 32) as usize] >> (s % 32)) & 1
        };
        for (z, want) in
            [(1.0, 0), (1.99, 0), (2.0, 1), (2.5, 1), (2.99, 1), (3.01, 0), (4.0, 0), (5.5, 1), (6.5, 0), (7.9, 0)]
        {
            assert_eq!(bit(z), want, "z {z}");
        }
        // An open surface leaves the column "inside" to its back.
        let open = voxelize_column(&[2.0], z0, z1, slices, 4);
        assert_eq!(open[3] >> 31, 1);
        // Fewer slices than bits: the unused bits stay 0.
        assert_eq!(voxelize_column(&[0.0], z0, z1, 40, 2), vec![u32::MAX, 0xff]);
    }

    /// The march: a wall of solid voxels between two texels hides, a path in front of it
    /// does not; AND-down keeps only what all four sub-columns hold.
    #[test]
    fn the_march_is_blocked_by_solid_voxels_only() {
        let (w, h, slices) = (16u32, 4u32, 32u32);
        let mut g =
            VoxelGrid { width: w, height: h, words: 1, slices, z0: 0.0, z1: 32.0, bits: vec![0; (w * h) as usize] };
        // A block solid from depth 10 to 20 in columns x = 8, every row.
        for y in 0..h {
            g.bits[(y * w + 8) as usize] = voxelize_column(&[10.0, 20.0], 0.0, 32.0, slices, 1)[0];
        }
        assert!(!march_visible(&g, (2, 1), 15.0, (14, 1), 15.0, 1.0, 0.0), "through the block");
        assert!(march_visible(&g, (2, 1), 5.0, (14, 1), 5.0, 1.0, 0.0), "in front of it");
        assert!(march_visible(&g, (2, 1), 25.0, (14, 1), 25.0, 1.0, 0.0), "behind it");
        assert!(march_visible(&g, (2, 1), 15.0, (6, 1), 15.0, 1.0, 0.0), "short of it");
        let c = and_down(&g);
        assert_eq!((c.width, c.height), (8, 2));
        // Column 8 is solid, 9 is not: their AND is empty.
        assert_eq!(c.bits[4], 0);
        let mut full = g.clone();
        for y in 0..h {
            full.bits[(y * w + 9) as usize] = full.bits[(y * w + 8) as usize];
        }
        assert_eq!(and_down(&full).bits[4], g.bits[8]);
    }

    /// The upsampling takes nothing from a coarse texel of another surface or the background.
    #[test]
    fn upsampling_never_bleeds_across_a_depth_edge() {
        let near =
            Texel { position: Vec3::ZERO, depth: 1.0, normal: Vec3::Z, radiance: Vec3::ZERO, ..Default::default() };
        let far = Texel { depth: 5.0, ..near };
        let coarse = Level { width: 2, height: 2, texels: vec![near, far, Texel::default(), far] };
        let light = [Vec3::ONE, Vec3::splat(100.0), Vec3::splat(1000.0), Vec3::splat(100.0)];
        let s = UpsampleSigmas { depth: 0.1, normal: 0.2 };
        let got = upsample(&coarse, &light, &near, 1, 1, s);
        assert!((got - Vec3::ONE).length() < 1e-3, "{got}");
        assert_eq!(upsample(&coarse, &light, &Texel::default(), 1, 1, s), Vec3::ZERO);
    }

    /// Issue #41 point 5: the 1/pdf weight of the warped angles on the sample's area keeps
    /// the point-to-point kernel (linear in the area) unbiased, but the point-to-disc kernel
    /// (concave in it) is biased low where the disc's radius R reaches the distance r.
    /// Expectation over the warped angles (a fine stratification of the spiral's angle) of a
    /// constant sender at one distance, against the same kernel with the unweighted area.
    #[test]
    fn the_disc_kernel_biases_the_weighted_area_low_where_the_disc_reaches_the_receiver() {
        use crate::cpu::soler_glossy::warp;
        use std::f32::consts::PI;
        let (alpha, s, theta_r) = (0.1f32, 20.0f32, 0.7f32);
        let n = 200_000;
        let expectation = |ds: f32, r2: f32, disc: bool| -> f64 {
            (0..n)
                .map(|i| {
                    let phi = (i as f32 + 0.5) / n as f32 * 2.0 * PI;
                    let (_, w) = warp(phi, Some((theta_r, s)), alpha);
                    kernel(0.8, 0.9, ds * w, r2, disc) as f64
                })
                .sum::<f64>()
                / n as f64
        };
        let mut biases = Vec::new();
        for ratio in [0.1f32, 1.0, 3.0] {
            // R² = cos θ' ds / π = (ratio · r)², r = 1.
            let ds = (ratio * ratio) * PI / 0.9;
            let exact_disc = kernel(0.8, 0.9, ds, 1.0, true) as f64;
            let exact_point = kernel(0.8, 0.9, ds, 1.0, false) as f64;
            let disc = expectation(ds, 1.0, true) / exact_disc - 1.0;
            let point = expectation(ds, 1.0, false) / exact_point - 1.0;
            println!("R = {ratio} r: point to disc {:+.2} %, point to point {:+.3} %", 100.0 * disc, 100.0 * point);
            assert!(point.abs() < 2e-3, "the point-to-point kernel stays unbiased: {point}");
            biases.push(disc);
        }
        // Measured: −0.9 % at R = r/10, −20.5 % at R = r, −9.9 % at R = 3r (where the disc
        // covers the receiver's view the kernel saturates and the weight matters less).
        assert!(biases[0] < 0.0 && biases[0] > -0.015, "far samples: nearly unbiased: {biases:?}");
        assert!(biases[1] < -0.1 && biases[1] < biases[2] && biases[2] < 0.0, "biased low, most at R ~ r: {biases:?}");
    }
}
