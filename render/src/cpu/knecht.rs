//! CPU references of the kernels of instant radiosity with imperfect shadow maps and
//! temporal coherence (Knecht 002, chapters 2.6.5, 3 and 4). Each function is the twin of a
//! shader; tests run both on small synthetic inputs and compare.
//!
//! | kernel | here | shader |
//! |---|---|---|
//! | Halton sequence (§3.3) | [`halton`] | `knecht/vpl/warp.wgsl` `halton` |
//! | importance pyramid + hierarchical warping (§3.3, Clarberg et al. 2005) | [`Pyramid`], [`Pyramid::warp`] | `knecht/vpl/importance.wgsl`, `knecht/vpl/warp.wgsl` |
//! | VPL budget split over lights by power (§4.4) | [`split_budget`] | — (CPU) |
//! | paraboloid projection of a VPL's hemisphere (§2.6.5, Brabec et al. 2002) | [`paraboloid_project`], [`paraboloid_unproject`] | `common/ism.wgsl` |
//! | pull-push hole filling (§2.6.5) | [`pull_push`] | `knecht/ism/pull_push.wgsl` |
//! | one VPL's light at a pixel, Eq. 4.7–4.9 | [`vpl_radiance`] | `common/vpl.wgsl` `vpl_radiance` |
//! | geometry-aware n×n box filter (§3.4.1) | [`geometry_aware_filter`] | `knecht/interleave/filter.wgsl` |
//! | confidence, Eq. 3.1–3.4, and the merge Eq. 3.6 | [`confidence`] | `knecht/temporal/confidence.wgsl` |
//! | bounce selection, §3.6.1 | [`crate::cpu::knecht_bounce`]: `bounce_incident`, `select_bounce`, `bounce_vpl` | `knecht/vpl/bounce.wgsl` |

use glam::{UVec2, Vec2, Vec3};

use crate::maths::{halton, pcg_hash};

/// Point `j` of the exact-VPL reference's sampling set in the light view's uv square: the
/// Halton point (h₂(j+1), h₃(j+1)) shifted by a toroidal offset drawn from `seed`
/// (Cranley–Patterson rotation), so that every point is uniform over the view while the set
/// stays stratified (twin of `reference_uv` in `shaders/reference/sample.wgsl`).
pub fn reference_uv(seed: u32, j: u32) -> Vec2 {
    let h = pcg_hash(seed);
    let offset = Vec2::new((h >> 8) as f32, (pcg_hash(h) >> 8) as f32) / 16_777_216.0;
    let p = Vec2::new(halton(j + 1, 2), halton(j + 1, 3)) + offset;
    p - p.floor()
}

/// A mip pyramid of an importance map: `levels[0]` is the finest (`size`² texels, `size` a
/// power of two), each coarser level the average of its 2×2 children, the last one 1×1
/// (the GPU keeps it as the mip chain of `vpl.importance`).
#[derive(Clone, Debug, PartialEq)]
pub struct Pyramid {
    pub size: u32,
    pub levels: Vec<Vec<f32>>,
}

/// Chooses between two halves with probability `p` of the first and rescales `u` to [0, 1)
/// within the chosen half (one step of Clarberg et al.'s warping).
fn split(u: f32, p: f32) -> (bool, f32) {
    if p <= 0.0 {
        return (true, u);
    }
    if p >= 1.0 {
        return (false, u);
    }
    if u < p { (false, u / p) } else { (true, ((u - p) / (1.0 - p)).min(0.99999994)) }
}

impl Pyramid {
    /// Builds the pyramid of a `size`² map (row-major, row 0 at the top).
    pub fn new(size: u32, finest: Vec<f32>) -> Self {
        assert!(size.is_power_of_two() && finest.len() == (size * size) as usize);
        let mut levels = vec![finest];
        let mut s = size;
        while s > 1 {
            let prev = levels.last().map(Vec::as_slice).unwrap_or(&[]);
            let h = s / 2;
            let mut next = vec![0.0; (h * h) as usize];
            for y in 0..h {
                for x in 0..h {
                    let at = |dx: u32, dy: u32| prev[((2 * y + dy) * s + 2 * x + dx) as usize];
                    next[(y * h + x) as usize] = (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1)) * 0.25;
                }
            }
            levels.push(next);
            s = h;
        }
        Self { size, levels }
    }

    fn at(&self, level: usize, x: u32, y: u32) -> f32 {
        let s = self.size >> level;
        self.levels[level][(y * s + x) as usize]
    }

    /// Hierarchical warping (Clarberg et al. 2005, as Knecht §3.3 performs it per sample):
    /// from the 2×2 level down to the finest, a vertical split by the summed importance of
    /// the upper and lower children, then a horizontal split within the chosen row; the
    /// sample is rescaled into the chosen child each time. Returns the texel, the warped
    /// position in [0, 1)² and the density over that square (importance / mean), or None
    /// when the map is zero everywhere.
    pub fn warp(&self, u: Vec2) -> Option<(UVec2, Vec2, f32)> {
        let top = self.levels.len() - 1;
        let mean = self.at(top, 0, 0);
        if mean <= 0.0 {
            return None;
        }
        let (mut u, mut cell) = (u, UVec2::ZERO);
        for level in (0..top).rev() {
            let (x, y) = (2 * cell.x, 2 * cell.y);
            let (a00, a10, a01, a11) = (
                self.at(level, x, y),
                self.at(level, x + 1, y),
                self.at(level, x, y + 1),
                self.at(level, x + 1, y + 1),
            );
            let (upper, lower) = (a00 + a10, a01 + a11);
            let (down, v) = split(u.y, if upper + lower > 0.0 { upper / (upper + lower) } else { 0.5 });
            let (l, r) = if down { (a01, a11) } else { (a00, a10) };
            let (right, w) = split(u.x, if l + r > 0.0 { l / (l + r) } else { 0.5 });
            u = Vec2::new(w, v);
            cell = UVec2::new(x + right as u32, y + down as u32);
        }
        let pdf = self.at(0, cell.x, cell.y) / mean;
        Some((cell, (cell.as_vec2() + u) / self.size as f32, pdf))
    }
}

/// Orthonormal basis (t, b, n) around a unit n (Duff et al. 2017); twin of `vpl_basis`.
pub fn basis(n: Vec3) -> (Vec3, Vec3, Vec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x), Vec3::new(b, s + n.y * n.y * a, -n.y), n)
}

/// Paraboloid projection of a VPL's upper hemisphere (Brabec et al. 2002, the map form of
/// ISMs, Knecht §2.6.5): a direction q (VPL-local, z along the normal) maps to
/// (q.x, q.y) / (1 + q.z) in the unit disk, then to texture coordinates in [0, 1]² with v
/// downward. Directions below the horizon return None.
pub fn paraboloid_project(q: Vec3) -> Option<Vec2> {
    let q = q.normalize_or_zero();
    if q.z < 0.0 || q == Vec3::ZERO {
        return None;
    }
    let p = Vec2::new(q.x, q.y) / (1.0 + q.z);
    Some(Vec2::new(p.x * 0.5 + 0.5, 0.5 - p.y * 0.5))
}

/// Inverse of [`paraboloid_project`]: the unit direction of texture coordinates `uv`.
pub fn paraboloid_unproject(uv: Vec2) -> Vec3 {
    let p = Vec2::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let r2 = p.length_squared();
    let z = (1.0 - r2) / (1.0 + r2);
    Vec3::new(p.x * (1.0 + z), p.y * (1.0 + z), z)
}

/// How [`ism_visible`] reads a VPL's imperfect shadow map: the map's size (texels), the
/// eye's lift above the VPL, the depth bias (a fraction of the distance) and the receiver's
/// normal offset (texels).
#[derive(Clone, Copy, Debug)]
pub struct IsmTest {
    pub size: u32,
    pub eye_offset: f32,
    pub bias: f32,
    pub normal_offset: f32,
}

/// The ISM shadow test of a receiver x with normal nx (twin of `ism_visibility` in
/// `shaders/common/ism.wgsl`): x is moved along nx by `normal_offset` texels of the map at
/// its distance from the eye (the eye is the VPL lifted by `eye_offset` along its normal; a
/// paraboloid texel at cos θ spans 2 (1 + cos θ) / size radians), then its distance less
/// `bias` × that distance is tested against `stored(tx, ty)`, the map's value at the texel
/// it projects to. Points below the VPL's horizon are hidden.
pub fn ism_visible(
    stored: impl Fn(u32, u32) -> f32,
    test: &IsmTest,
    (vpl_position, vpl_normal): (Vec3, Vec3),
    (x, nx): (Vec3, Vec3),
) -> bool {
    let IsmTest { size, eye_offset, bias, normal_offset } = *test;
    let eye = vpl_position + vpl_normal * eye_offset;
    let w0 = x - eye;
    let d0 = w0.length();
    let cos0 = w0.dot(vpl_normal) / d0.max(1e-9);
    let texel_angle = 2.0 * (1.0 + cos0.max(0.0)) / size as f32;
    let w = w0 + nx * (normal_offset * d0 * texel_angle);
    let d = w.length();
    let (t, b, n) = basis(vpl_normal);
    let q = Vec3::new(w.dot(t), w.dot(b), w.dot(n)) / d.max(1e-9);
    if q.z < 0.0 {
        return false;
    }
    let Some(uv) = paraboloid_project(q) else { return false };
    let tx = ((uv.x * size as f32) as u32).min(size - 1);
    let ty = ((uv.y * size as f32) as u32).min(size - 1);
    d * (1.0 - bias) <= stored(tx, ty)
}

/// What a tangent-plane splat (`ism.splat_depth`) writes into the texel at paraboloid
/// coordinates `uv` (texel centre): the distance along the texel's ray from the eye to the
/// plane through the point (`local`, relative to the eye in the VPL's frame, at distance `d`)
/// with normal `normal` (same frame), kept within ± `reach` of `d`; a ray that misses the
/// plane in front takes `d + reach`. Twin of `texel_key` in `shaders/knecht/ism/splat.wgsl`.
pub fn splat_distance(local: Vec3, normal: Vec3, d: f32, reach: f32, uv: Vec2) -> f32 {
    let ray = paraboloid_unproject(uv);
    let den = ray.dot(normal);
    let hit = if den.abs() > 1e-6 { local.dot(normal) / den } else { -1.0 };
    let s = if hit > 0.0 { hit } else { d + reach };
    s.clamp((d - reach).max(1e-6), d + reach)
}

/// Depth of an empty ISM texel (a hole): any value at or above it is invalid.
pub const ISM_EMPTY: f32 = 1.0e30;

/// Pull-push hole filling of an ISM atlas (Knecht §2.6.5 after Marroquim et al. 2008 and
/// Grossman and Dally 1998). `atlas` is `width`×`height` distances (holes ≥ [`ISM_EMPTY`])
/// made of `tile`² maps; `tile` is a multiple of 2^`levels`, so no 2×2 block straddles two
/// maps. Returns every level after the push (index 0 the finest; the last one is the
/// coarsest pull result).
///
/// - Pull (level l → l+1): the average of the valid children within `t_pull`·2^l of the
///   nearest valid child (outliers behind are rejected); no valid child leaves a hole.
/// - Push (level l+1 → l, from coarse to fine): the coarse value at a fine texel is the
///   bilinear interpolation of the valid coarse texels around it within the same map; it
///   replaces the fine value if that is a hole or lies farther than `t_push`·2^l behind it —
///   anywhere (the thesis), or with `inside_only` only where the four coarse texels around
///   it are valid and agree within `t_push`·2^l (inside a surface, not at a silhouette;
///   `ism.push_behind`).
pub fn pull_push(
    atlas: &[f32],
    width: u32,
    height: u32,
    tile: u32,
    levels: u32,
    [t_pull, t_push]: [f32; 2],
    inside_only: bool,
) -> Vec<Vec<f32>> {
    let mut pyr = vec![atlas.to_vec()];
    for l in 0..levels {
        let (w, h) = (width >> l, height >> l);
        let (cw, ch) = (w / 2, h / 2);
        let fine = &pyr[l as usize];
        let mut coarse = vec![ISM_EMPTY; (cw * ch) as usize];
        let threshold = t_pull * (1u32 << l) as f32;
        for y in 0..ch {
            for x in 0..cw {
                let c = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| fine[((2 * y + dy) * w + 2 * x + dx) as usize]);
                let nearest = c.iter().copied().fold(ISM_EMPTY, f32::min);
                if nearest >= ISM_EMPTY {
                    continue;
                }
                let (mut sum, mut n) = (0.0f32, 0.0f32);
                for v in c {
                    if v < ISM_EMPTY && v - nearest <= threshold {
                        sum += v;
                        n += 1.0;
                    }
                }
                coarse[(y * cw + x) as usize] = sum / n;
            }
        }
        pyr.push(coarse);
    }
    for l in (0..levels).rev() {
        let (w, h) = (width >> l, height >> l);
        let cw = w / 2;
        let ct = (tile >> (l + 1)).max(1);
        let threshold = t_push * (1u32 << l) as f32;
        let coarse = pyr[l as usize + 1].clone();
        let fine = &mut pyr[l as usize];
        for y in 0..h {
            for x in 0..w {
                let (c, agree) = coarse_at(&coarse, cw, ct, x, y, threshold);
                let f = &mut fine[(y * w + x) as usize];
                if c < ISM_EMPTY && (*f >= ISM_EMPTY || ((agree || !inside_only) && *f - c > threshold)) {
                    *f = c;
                }
            }
        }
    }
    pyr
}

/// Bilinear interpolation of the valid coarse texels around fine texel (x, y), within the
/// coarse map (`ct`² texels) that contains it, and whether all four are valid and agree
/// within `threshold`; twin of `coarse_at` in `knecht/ism/pull_push.wgsl`.
fn coarse_at(coarse: &[f32], cw: u32, ct: u32, x: u32, y: u32, threshold: f32) -> (f32, bool) {
    let (px, py) = ((x as f32 + 0.5) * 0.5 - 0.5, (y as f32 + 0.5) * 0.5 - 0.5);
    let (x0, y0) = (px.floor(), py.floor());
    let (fx, fy) = (px - x0, py - y0);
    let (tx, ty) = ((x / 2) / ct * ct, (y / 2) / ct * ct);
    let (mut sum, mut wsum, mut lo, mut hi, mut taps) = (0.0f32, 0.0f32, ISM_EMPTY, 0.0f32, 0);
    for (dx, dy, w) in
        [(0, 0, (1.0 - fx) * (1.0 - fy)), (1, 0, fx * (1.0 - fy)), (0, 1, (1.0 - fx) * fy), (1, 1, fx * fy)]
    {
        let cx = (x0 as i32 + dx).clamp(tx as i32, (tx + ct - 1) as i32) as u32;
        let cy = (y0 as i32 + dy).clamp(ty as i32, (ty + ct - 1) as i32) as u32;
        let v = coarse[(cy * cw + cx) as usize];
        if v < ISM_EMPTY {
            (lo, hi, taps) = (lo.min(v), hi.max(v), taps + 1);
        }
        if v < ISM_EMPTY && w > 0.0 {
            sum += w * v;
            wsum += w;
        }
    }
    let agree = taps == 4 && hi - lo <= threshold;
    if wsum > 0.0 { (sum / wsum, agree) } else { (ISM_EMPTY, false) }
}

/// A VPL as the shading kernel sees it (twin of `Vpl` in `shaders/common/vpl.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    pub position: Vec3,
    pub normal: Vec3,
    /// Incident flux Φ.
    pub flux: Vec3,
    /// Unit direction toward the light (or previous-bounce VPL) it came from.
    pub incident: Vec3,
    pub albedo: Vec3,
    pub di: f32,
    pub si: f32,
    pub sp: f32,
}

/// A surface point to shade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    pub position: Vec3,
    pub normal: Vec3,
    pub albedo: Vec3,
    pub di: f32,
    pub si: f32,
    pub sp: f32,
}

/// Radiance toward the eye at `eye` that one VPL sends to `x` (visibility not included),
/// Knecht 002 Eq. 4.7–4.9 with the one BRDF of [`crate::cpu::brdf`] at both ends:
///
/// - Eq. 4.7, geometry term η = max(0, cos θ_s)·max(0, cos θ_r) / max(d_min², d²); the
///   thesis clamps with 1 (its scene units); d_min is a setting here.
/// - Eq. 4.8, the VPL's emission toward x: Φ · f(y; ω_in, y→x), whose glossy lobe depends
///   on ω_in, the direction to the light or to the previous-bounce VPL (the thesis'
///   reflection vector `ref`); its diffuse part is I_VPL·DI_VPL.
/// - Eq. 4.9, the light leaving x toward the eye: f(x; x→y, v).
pub fn vpl_radiance(vpl: &Vpl, x: &Receiver, eye: Vec3, d_min: f32) -> Vec3 {
    let e = vpl_irradiance(vpl, x, d_min);
    if e.max_element() <= 0.0 {
        return Vec3::ZERO;
    }
    let l = (vpl.position - x.position).normalize_or_zero();
    let v = (eye - x.position).normalize_or_zero();
    e * crate::cpu::brdf::eval(x.normal, l, v, x.albedo, x.di, x.si, x.sp)
}

/// The irradiance one VPL gives `x` (Eq. 4.7–4.8: Φ · f(y) · η, visibility not included):
/// [`vpl_radiance`] before the receiver's BRDF. The gather at tiles keeps its sum apart
/// (`indirect.irradiance`) for the demodulated filter ([`geometry_aware_filter`], issue #51).
pub fn vpl_irradiance(vpl: &Vpl, x: &Receiver, d_min: f32) -> Vec3 {
    let w = vpl.position - x.position;
    let d2 = w.length_squared();
    let l = w / d2.max(1e-12).sqrt();
    let (cos_x, cos_y) = (x.normal.dot(l), -vpl.normal.dot(l));
    if cos_x <= 0.0 || cos_y <= 0.0 {
        return Vec3::ZERO;
    }
    let f_y = crate::cpu::brdf::eval(vpl.normal, vpl.incident, -l, vpl.albedo, vpl.di, vpl.si, vpl.sp);
    vpl.flux * f_y * cos_y * cos_x / d2.max(d_min * d_min)
}

/// One pixel of the geometry-aware box filter's inputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterTexel {
    /// The gathered light L (`indirect.merged`).
    pub value: Vec3,
    /// Linear view depth (0: background).
    pub depth: f32,
    pub normal: Vec3,
    /// The demodulated filter's inputs (issue #51): the gathered irradiance E
    /// (`indirect.irradiance`) and the pixel's diffuse reflectance k = c·DI/π, so that
    /// L = k·E + S with S the specular light. Both 0: the thesis' filter of L.
    pub irradiance: Vec3,
    pub reflectance: Vec3,
}

/// The window of the n×n box filter around a pixel: offsets −⌊n/2⌋ … n−1−⌊n/2⌋, one pixel
/// of every interleaving tile.
pub fn filter_window(n: u32) -> std::ops::RangeInclusive<i32> {
    let lo = -((n / 2) as i32);
    lo..=lo + n as i32 - 1
}

/// Geometry-aware n×n box filter (Knecht §3.4.1 after Laine et al. 2007): the average over
/// the window of the pixels on the same surface as the centre — depth difference at most
/// α in the thesis' linear depth (Eq. 4.2: view depth / (z_far − z_near), so the threshold
/// is α · `depth_range`) and normals with a dot product of at least β. Background pixels
/// stay 0.
///
/// Demodulated (issue #51, ⚠[knecht.demodulated-filter]): the window's mean of the
/// irradiance E is reflected with the centre's own reflectance k_p and the mean of the
/// specular light S = L − k·E is added, k_p·mean(E) + mean(S), so that the albedo's texture
/// stays sharp; with E = k = 0 this is the thesis' mean of L.
pub fn geometry_aware_filter(
    img: &[FilterTexel],
    width: u32,
    height: u32,
    n: u32,
    alpha: f32,
    beta: f32,
    depth_range: f32,
) -> Vec<Vec3> {
    filter_with_irradiance(img, width, height, n, alpha, beta, depth_range).into_iter().map(|(l, _)| l).collect()
}

/// [`geometry_aware_filter`] with the window's mean irradiance beside each pixel's light
/// (`indirect.filtered_irradiance`, what the demodulated merge keeps, [`merge_demodulated`]).
pub fn filter_with_irradiance(
    img: &[FilterTexel],
    width: u32,
    height: u32,
    n: u32,
    alpha: f32,
    beta: f32,
    depth_range: f32,
) -> Vec<(Vec3, Vec3)> {
    let mut out = vec![(Vec3::ZERO, Vec3::ZERO); img.len()];
    for y in 0..height as i32 {
        for x in 0..width as i32 {
            let c = img[(y as u32 * width + x as u32) as usize];
            if c.depth <= 0.0 {
                continue;
            }
            let (mut sum, mut irradiance, mut count) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
            for dy in filter_window(n) {
                for dx in filter_window(n) {
                    let (qx, qy) = (x + dx, y + dy);
                    if qx < 0 || qy < 0 || qx >= width as i32 || qy >= height as i32 {
                        continue;
                    }
                    let q = img[(qy as u32 * width + qx as u32) as usize];
                    if q.depth <= 0.0
                        || (q.depth - c.depth).abs() > alpha * depth_range
                        || q.normal.dot(c.normal) < beta
                    {
                        continue;
                    }
                    sum += q.value - q.reflectance * q.irradiance;
                    irradiance += q.irradiance;
                    count += 1.0;
                }
            }
            out[(y as u32 * width + x as u32) as usize] =
                ((c.reflectance * irradiance + sum) / count.max(1.0), irradiance / count.max(1.0));
        }
    }
    out
}

/// The weights of the confidence (Knecht §3.5.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConfidenceWeights {
    pub c_base: f32,
    pub w_pos: f32,
    pub w_normal: f32,
    pub w_illumination: f32,
}

/// What one pixel knows of itself and of its reprojected previous value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConfidenceInput {
    /// Movement buffer value (previous − current position) in pixels.
    pub motion_px: Vec2,
    pub size: Vec2,
    /// View depth and the previous one (scene units) and z_far − z_near of the camera. The GPU
    /// compares both as half floats, the history's format (`temporal/confidence.wgsl`, issue
    /// #53): pass half-exact depths to compare with it.
    pub depth: f32,
    pub depth_prev: f32,
    pub depth_range: f32,
    pub normal: Vec3,
    pub normal_prev: Vec3,
    pub illumination: Vec3,
    pub illumination_prev: Vec3,
}

/// Confidence in the previous frame's indirect light, Knecht 002 Eq. 3.1–3.4:
///
/// - Eq. 3.1, Δpos = ‖(Δx, Δy, Δd) · w_pos‖ with the screen movement in fractions of the image
///   (Δx/width, Δy/height) and the depth in the thesis' linear depth (Eq. 4.2, view depth /
///   (z_far − z_near)) — ⚠[knecht.confidence-units] our reading of its screen and depth units,
///   so that w_pos does not depend on the resolution;
/// - Eq. 3.2, Δnormal = (1 − n·n_prev) · w_normal;
/// - Eq. 3.3, Δillumination = saturate(‖I_new − I_prev‖³) · w_illumination with the difference
///   relative to the larger of the two magnitudes (⚠[knecht.confidence-relative]; the thesis'
///   light values were display-referred; ours are radiance in any unit);
/// - Eq. 3.4, confidence = c_base · saturate(1 − max(Δpos, Δnormal, Δillumination)).
pub fn confidence(i: &ConfidenceInput, w: &ConfidenceWeights) -> f32 {
    let rel_depth = (i.depth - i.depth_prev) / i.depth_range.max(1e-6);
    let d_pos = Vec3::new(i.motion_px.x / i.size.x, i.motion_px.y / i.size.y, rel_depth).length() * w.w_pos;
    let d_normal = (1.0 - i.normal.dot(i.normal_prev)) * w.w_normal;
    let scale = i.illumination.length().max(i.illumination_prev.length()).max(1e-6);
    let diff = (i.illumination - i.illumination_prev).length() / scale;
    let d_illum = (diff * diff * diff).clamp(0.0, 1.0) * w.w_illumination;
    w.c_base * (1.0 - d_pos.max(d_normal).max(d_illum)).clamp(0.0, 1.0)
}

/// The merge of Eq. 3.6: I = I_prev · confidence + (1 − confidence) · I_new.
pub fn merge(i_new: Vec3, i_prev: Vec3, confidence: f32) -> Vec3 {
    i_prev * confidence + (1.0 - confidence) * i_new
}

/// Light split as the demodulated filter splits it: L = k·E + S.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitLight {
    /// The irradiance E (the filter's window mean).
    pub irradiance: Vec3,
    /// The specular light S = L − k·E.
    pub specular: Vec3,
}

impl SplitLight {
    /// L split with the pixel's diffuse reflectance k and the irradiance E it reflects.
    pub fn of(light: Vec3, k: Vec3, irradiance: Vec3) -> Self {
        Self { irradiance, specular: light - k * irradiance }
    }

    /// The light a pixel of diffuse reflectance k gives back: k·E + S.
    pub fn reflect(&self, k: Vec3) -> Vec3 {
        k * self.irradiance + self.specular
    }
}

/// The word no normal packs to (pack2x16snorm never writes −32768): a pixel without a surface
/// (`NO_NORMAL` in `shaders/common/normal.wgsl`, the camera G-buffer's clear value).
pub const NO_NORMAL: u32 = 0x8000_8000;

/// The split history's normal word (issue #53; twin of `shaders/common/split_light.wgsl`'s
/// `pack_normal`): the unit normal's octahedral coordinates (Cigolle et al. 2014, JCGT 3(2),
/// §3.3) as two 16-bit snorms, rounded as WGSL's `pack2x16snorm` rounds; None (no surface) is
/// a word that no normal packs to.
pub fn pack_normal(n: Option<Vec3>) -> u32 {
    let Some(n) = n else { return NO_NORMAL };
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if l1 <= 0.0 {
        return NO_NORMAL;
    }
    let mut p = Vec2::new(n.x, n.y) / l1;
    if n.z < 0.0 {
        p = octahedral_fold(p);
    }
    let snorm = |v: f32| ((0.5 + 32767.0 * v.clamp(-1.0, 1.0)).floor() as i32 as i16 as u16) as u32;
    snorm(p.x) | (snorm(p.y) << 16)
}

/// The normal a [`pack_normal`] word holds (unit), None for the word of no surface.
pub fn unpack_normal(w: u32) -> Option<Vec3> {
    if w == NO_NORMAL {
        return None;
    }
    let snorm = |h: u32| ((h as u16 as i16) as f32 / 32767.0).max(-1.0);
    let p = Vec2::new(snorm(w & 0xffff), snorm(w >> 16));
    let mut n = Vec3::new(p.x, p.y, 1.0 - p.x.abs() - p.y.abs());
    if n.z < 0.0 {
        let f = octahedral_fold(Vec2::new(n.x, n.y));
        n = Vec3::new(f.x, f.y, n.z);
    }
    Some(n.normalize())
}

/// The normal the passes shade with at a camera G-buffer pixel whose packed word is `w`
/// (issue #53; twin of `gbuffer_normal` in `shaders/common/normal.wgsl`): the word unpacked
/// and rounded to half floats, as `gbuffer.normal` stores it. None for no surface.
pub fn gbuffer_normal(w: u32) -> Option<Vec3> {
    unpack_normal(w).map(|n| n.to_array().map(crate::buffers::round_to_half).into())
}

/// The octahedral map's fold of the lower half over the square's edges.
fn octahedral_fold(v: Vec2) -> Vec2 {
    let s = Vec2::new(if v.x >= 0.0 { 1.0 } else { -1.0 }, if v.y >= 0.0 { 1.0 } else { -1.0 });
    (Vec2::ONE - Vec2::new(v.y.abs(), v.x.abs())) * s
}

/// The demodulated merge (issue #51, ⚠[knecht.demodulated-merge]; twin of the demodulated path
/// of `shaders/knecht/temporal/confidence.wgsl`): Eq. 3.6 applied to E and S apart, the result
/// reflected with this pixel's own k. Eq. 3.3's I_prev is the history as this pixel reflects
/// it, `prev.reflect(k)`. Returns the merged light and the split history to keep.
pub fn merge_demodulated(k: Vec3, new: SplitLight, prev: SplitLight, confidence: f32) -> (Vec3, SplitLight) {
    let m = SplitLight {
        irradiance: merge(new.irradiance, prev.irradiance, confidence),
        specular: merge(new.specular, prev.specular, confidence),
    };
    (m.reflect(k), m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_packed_normal_comes_back_within_the_snorms_step() {
        // Both hemispheres, the axes, the octahedron's edges and its folded corners.
        let count = 2000;
        let mut dirs: Vec<Vec3> = (0..count)
            .map(|i| {
                // A Fibonacci sphere: every direction's neighbourhood.
                let z = 1.0 - 2.0 * (i as f32 + 0.5) / count as f32;
                let phi = i as f32 * 2.399_963;
                let r = (1.0 - z * z).sqrt();
                Vec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect();
        dirs.extend([Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]);
        dirs.extend(
            [Vec3::new(1.0, 1.0, 0.0), Vec3::new(-1.0, 0.0, -1.0), Vec3::new(0.3, -0.7, -0.2)].map(Vec3::normalize),
        );
        for n in dirs {
            let w = pack_normal(Some(n));
            assert_ne!(w, pack_normal(None), "{n} packs to the no-surface word");
            let back = unpack_normal(w).expect("a normal");
            // A few snorm16 steps (3·10⁻⁵) of the octahedron's side: under 10⁻⁴ rad.
            assert!(back.cross(n).length() < 1e-4 && back.dot(n) > 0.0, "{n} came back as {back}");
        }
        assert_eq!(unpack_normal(pack_normal(None)), None);
        assert_eq!(pack_normal(Some(Vec3::ZERO)), pack_normal(None));
    }

    #[test]
    fn the_reference_sampling_set_is_stratified_and_uniform() {
        // 4,096 points (the exact-VPL reference's default) on a 16×16 grid: 16 expected per
        // cell. The rotated Halton set stays within 5 for every seed tried (0…19: 2 to 5);
        // the independent texels it replaced spread with σ = 4, about 12 at worst.
        let worst = |pts: &mut dyn Iterator<Item = Vec2>| {
            let mut cells = [0i32; 256];
            for p in pts {
                assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y), "{p}");
                cells[(p.y * 16.0) as usize * 16 + (p.x * 16.0) as usize] += 1;
            }
            cells.iter().map(|c| (c - 16).abs()).max().unwrap_or(0)
        };
        for seed in 0..20 {
            let w = worst(&mut (0..4096).map(|j| reference_uv(seed, j)));
            assert!(w <= 6, "seed {seed}: a cell is {w} points off the 16 expected");
        }
        // The old sampling (two hashes per VPL) fails the same bound.
        let old = |j: u32| {
            let h = pcg_hash(pcg_hash(1) ^ j.wrapping_mul(0x9E37_79B9));
            Vec2::new((h >> 8) as f32, (pcg_hash(h) >> 8) as f32) / 16_777_216.0
        };
        let w = worst(&mut (0..4096).map(old));
        assert!(w > 6, "independent points happened to be stratified ({w})");
        // Unbiased: over seeds, one point is uniform on the square (mean 0.5, variance 1/12).
        let pts: Vec<Vec2> = (0..20_000).map(|s| reference_uv(s, 5)).collect();
        let mean = pts.iter().copied().sum::<Vec2>() / pts.len() as f32;
        let var = pts.iter().map(|p| (*p - mean) * (*p - mean)).sum::<Vec2>() / pts.len() as f32;
        assert!((mean - Vec2::splat(0.5)).abs().max_element() < 0.01, "mean {mean}");
        assert!((var - Vec2::splat(1.0 / 12.0)).abs().max_element() < 0.005, "variance {var}");
    }

    #[test]
    fn warping_a_uniform_map_is_the_identity() {
        let p = Pyramid::new(8, vec![1.0; 64]);
        for i in 0..100 {
            let u = Vec2::new(halton(i, 2), halton(i, 3));
            let (_, uv, pdf) = p.warp(u).expect("non-zero map");
            assert!((uv - u).length() < 1e-5, "{u} → {uv}");
            assert!((pdf - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn warping_never_lands_on_zero_importance() {
        let mut map = vec![0.0; 16 * 16];
        map[5 * 16 + 9] = 3.0;
        map[12 * 16 + 2] = 1.0;
        let p = Pyramid::new(16, map);
        let mut hits = [0u32; 2];
        for i in 0..400 {
            let (t, _, pdf) = p.warp(Vec2::new(halton(i, 2), halton(i, 3))).expect("non-zero");
            match (t.x, t.y) {
                (9, 5) => hits[0] += 1,
                (2, 12) => hits[1] += 1,
                other => panic!("landed on {other:?}"),
            }
            assert!(pdf > 0.0);
        }
        // 3 : 1 by importance, to the discrepancy of 400 Halton points.
        assert!(hits[0].abs_diff(300) <= 4 && hits[0] + hits[1] == 400, "{hits:?}");
    }

    #[test]
    fn paraboloid_round_trips() {
        for i in 0..200 {
            let (a, b) = (halton(i, 2) * std::f32::consts::TAU, halton(i, 3));
            let z = b;
            let r = (1.0 - z * z).sqrt();
            let q = Vec3::new(r * a.cos(), r * a.sin(), z);
            let uv = paraboloid_project(q).expect("upper hemisphere");
            assert!((paraboloid_unproject(uv) - q).length() < 1e-5);
        }
        assert!(paraboloid_project(Vec3::new(0.0, 0.0, -1.0)).is_none());
    }

    #[test]
    fn a_tangent_plane_splat_lies_on_its_surface() {
        // A ceiling 1 above the eye (z = 1, facing it) seen at 45°: the point's own texel and
        // the texels around it hold the distance along their rays to the ceiling; a box
        // splat would hold d in all of them and stand out of the ceiling on one side.
        let normal = Vec3::new(0.0, 0.0, -1.0);
        let local = Vec3::new(1.0, 0.0, 1.0);
        let d = local.length();
        let size = 64.0;
        let centre = paraboloid_project(local / d).expect("in the hemisphere") * size;
        for (dx, dy) in [(0.0, 0.0), (2.0, 0.0), (-2.0, 0.0), (0.0, 2.0), (1.0, -1.0)] {
            let uv = (centre.floor() + Vec2::new(dx + 0.5, dy + 0.5)) / size;
            let ray = paraboloid_unproject(uv);
            let exact = 1.0 / ray.z;
            let got = splat_distance(local, normal, d, 0.5, uv);
            assert!((got - exact).abs() < 1e-4 * exact, "({dx}, {dy}): {got} vs {exact}");
        }
        // A ray that grazes the plane is kept within reach of the point.
        let edge_on = splat_distance(local, Vec3::new(0.0, 1.0, 0.0), d, 0.1, Vec2::new(0.3, 0.5));
        assert!((edge_on - (d + 0.1)).abs() < 1e-6, "{edge_on}");
    }

    #[test]
    fn the_inside_only_push_fills_holes_but_keeps_silhouettes() {
        // Left half an occluder at 1, right half a wall at 3, one hole in the occluder.
        let mut a: Vec<f32> = (0..64).map(|i| if i % 8 < 4 { 1.0 } else { 3.0 }).collect();
        a[2 * 8 + 1] = ISM_EMPTY;
        let thesis = pull_push(&a, 8, 8, 8, 2, [0.1, 0.1], false);
        let inside = pull_push(&a, 8, 8, 8, 2, [0.1, 0.1], true);
        for out in [&thesis, &inside] {
            assert!((out[0][2 * 8 + 1] - 1.0).abs() < 1e-6, "the hole is filled");
        }
        // The thesis' push moves the wall texels next to the occluder nearer; inside-only
        // leaves every wall texel at 3.
        let grown = |out: &Vec<Vec<f32>>| (0..64).filter(|&i| i % 8 >= 4 && out[0][i] < 2.9).count();
        assert!(grown(&thesis) > 0, "the thesis' push dilates the occluder");
        assert_eq!(grown(&inside), 0, "the inside-only push keeps the silhouette");
    }

    #[test]
    fn pull_push_fills_a_hole_with_its_neighbours() {
        let mut a = vec![2.0; 16];
        a[5] = ISM_EMPTY;
        let out = pull_push(&a, 4, 4, 4, 2, [0.1, 0.1], false);
        assert!((out[0][5] - 2.0).abs() < 1e-6);
        assert!(out[0].iter().all(|&v| v < ISM_EMPTY));
    }

    #[test]
    fn confidence_is_c_base_for_a_still_pixel_and_zero_for_a_new_surface() {
        let w = ConfidenceWeights { c_base: 0.9, w_pos: 10.0, w_normal: 2.0, w_illumination: 1.0 };
        let still = ConfidenceInput {
            motion_px: Vec2::ZERO,
            size: Vec2::new(100.0, 100.0),
            depth: 2.0,
            depth_prev: 2.0,
            depth_range: 10.0,
            normal: Vec3::Z,
            normal_prev: Vec3::Z,
            illumination: Vec3::ONE,
            illumination_prev: Vec3::ONE,
        };
        assert_eq!(confidence(&still, &w), 0.9);
        let new = ConfidenceInput { depth_prev: 4.0, ..still };
        // Δpos = 0.2 · 10 ≥ 1.
        assert_eq!(confidence(&new, &w), 0.0);
    }
}
