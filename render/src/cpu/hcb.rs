//! CPU reference of the hierarchical coherence buffer (Nguyen et al., 000 §3): the base
//! level from a G-buffer, Algorithm 1 with the distance accumulation of §3.5, and the mask
//! buffer and sample identification of §3.6. The GPU passes (`shaders/hcb/*.wgsl`) are
//! tested against these on synthetic G-buffers.
//!
//! Readings of the paper, where it leaves room:
//! - ⚠[nguyen.pose-test] Pose coherence, Eq. 3: its first line detects backward lighting
//!   (âb·n_a ≤ 0 or b̂a·n_b ≤ 0, the two not facing each other), and only then does the second
//!   restrict the angle, |âb·n_a| ≤ cos γ_max (âb normalised). This is how Eq. 8 uses the same
//!   terms — the pose error is ρ √|âb·n_a| / √cos γ_max with ρ = 1 exactly when the first line
//!   holds — so Algorithm 1 and the splat weights agree: two points facing each other are
//!   pose-coherent (the normal test judges them), a step between parallel planes is not.
//! - ⚠[nguyen.distance-accumulated] Distance coherence, Eq. 1, is tested on the accumulated
//!   distance R'_c = ‖a − c‖ + R_c (§3.5) — the conservative bound of a's distance to every
//!   texel that c stands for, as Eq. 6 is for the normals: c is coherent to a only if R'_c ≤
//!   d_max.
//! - ⚠[nguyen.incoherent-edges] Background texels (normal w = 0 in the G-buffer) have coherence
//!   0, and a 3×3 block with a texel outside the level is incoherent (it would stand for pixels
//!   that do not exist).
//! - ⚠[nguyen.level-size] Level k has ⌈w/2⌉ × ⌈h/2⌉ texels of level k − 1; texel (x, y) covers
//!   the 3×3 block centred at (2x, 2y) and is the G-buffer pixel (2^k x, 2^k y).

use glam::Vec3;

pub use crate::settings::hcb::Thresholds;

/// One texel of an HCB level: the world-space point, the sphere radius a^w (the texel
/// footprint at level 0, the accumulated distance above), the normal and the group coherence
/// n^w (1 at level 0, 0 for incoherent blocks and the background).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HcbTexel {
    pub position: Vec3,
    pub distance: f32,
    pub normal: Vec3,
    pub coherence: f32,
}

impl HcbTexel {
    pub const BACKGROUND: Self = Self { position: Vec3::ZERO, distance: 0.0, normal: Vec3::Z, coherence: 0.0 };
}

/// One level: `width` × `height` texels, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<HcbTexel>,
}

impl Level {
    pub fn at(&self, x: i64, y: i64) -> Option<&HcbTexel> {
        (x >= 0 && y >= 0 && x < self.width as i64 && y < self.height as i64)
            .then(|| &self.texels[(y * self.width as i64 + x) as usize])
    }
}

/// World-space footprint of a pixel (§3.5): the square root of its back-projected area — the
/// pixel's width at view depth `depth` (`pixel_scale` = 2 tan(fov_y / 2) / height) over
/// √|cos| of the angle between the normal and the direction to the eye (|cos| clamped below
/// at `min_cos`, `hcb.footprint_min_cos`, so that grazing pixels stay finite).
pub fn footprint(depth: f32, pixel_scale: f32, normal: Vec3, to_eye: Vec3, min_cos: f32) -> f32 {
    depth * pixel_scale / normal.dot(to_eye).abs().max(min_cos).sqrt()
}

/// Level 0 from G-buffer texels: `position` = (world xyz, view depth), `normal` = (xyz,
/// coverage w), `eye` the camera position.
pub fn base_level(
    position: &[[f32; 4]],
    normal: &[[f32; 4]],
    width: u32,
    height: u32,
    eye: Vec3,
    pixel_scale: f32,
    min_cos: f32,
) -> Level {
    let texels = position
        .iter()
        .zip(normal)
        .map(|(p, n)| {
            if n[3] < 0.5 {
                return HcbTexel::BACKGROUND;
            }
            let (pos, nrm) = (Vec3::new(p[0], p[1], p[2]), Vec3::new(n[0], n[1], n[2]).normalize_or(Vec3::Z));
            HcbTexel {
                position: pos,
                distance: footprint(p[3], pixel_scale, nrm, (eye - pos).normalize_or_zero(), min_cos),
                normal: nrm,
                coherence: 1.0,
            }
        })
        .collect();
    Level { width, height, texels }
}

/// Eq. 3 (see the module documentation for the reading).
pub fn pose_coherent(a: Vec3, n_a: Vec3, b: Vec3, n_b: Vec3, cos_gamma_max: f32) -> bool {
    let ab = (b - a).normalize_or_zero();
    if ab == Vec3::ZERO {
        return true;
    }
    let backward = ab.dot(n_a) <= 0.0 || (-ab).dot(n_b) <= 0.0;
    !backward || ab.dot(n_a).abs() <= cos_gamma_max
}

/// Algorithm 1 with §3.5 for texel (x, y) of the level above `prev`, with §5.2's
/// modification: the normal coherence uses |n^w| and the result keeps a sign (the centre's,
/// or positive when any texel of the block is, see [`Thresholds::spread_incomplete`]).
pub fn build_texel(prev: &Level, x: u32, y: u32, t: Thresholds) -> HcbTexel {
    let (cx, cy) = (2 * x as i64, 2 * y as i64);
    let Some(&a) = prev.at(cx, cy) else { return HcbTexel::BACKGROUND };
    let mut out = HcbTexel { coherence: 0.0, ..a };
    if a.coherence == 0.0 {
        return out;
    }
    let (mut coherence, mut distance, mut all) = (a.coherence.abs(), a.distance, true);
    let mut positive = a.coherence > 0.0;
    for (dx, dy) in (-1..=1).flat_map(|j| (-1..=1).map(move |i| (i, j))).filter(|&d| d != (0, 0)) {
        let Some(c) = prev.at(cx + dx, cy + dy) else {
            all = false;
            break;
        };
        let temp = c.coherence.abs() * a.normal.dot(c.normal);
        let reach = (c.position - a.position).length() + c.distance;
        let coherent = c.coherence != 0.0
            && temp >= t.cos_theta_max
            && pose_coherent(a.position, a.normal, c.position, c.normal, t.cos_gamma_max)
            && reach <= t.d_max;
        if !coherent {
            all = false;
            break;
        }
        coherence = coherence.min(temp);
        distance = distance.max(reach);
        positive |= t.spread_incomplete && c.coherence > 0.0;
    }
    if all {
        out.coherence = if positive { coherence } else { -coherence };
        out.distance = distance;
    }
    out
}

/// The level above `prev` (Algorithm 1 at every texel).
pub fn build_level(prev: &Level, t: Thresholds) -> Level {
    let (width, height) = (prev.width.div_ceil(2).max(1), prev.height.div_ceil(2).max(1));
    let texels =
        (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| build_texel(prev, x, y, t)).collect();
    Level { width, height, texels }
}

/// Levels 0 … `levels` − 1 (level 0 is `base`).
pub fn build(base: Level, levels: u32, t: Thresholds) -> Vec<Level> {
    let mut out = vec![base];
    for _ in 1..levels.max(1) {
        let next = build_level(out.last().expect("level 0"), t);
        out.push(next);
    }
    out
}

/// The mask buffer of §3.6: for every level below the top, whether each texel lies inside
/// the 3×3 splat of a coherent texel (n^w > 0: with §5.2's signs, a positive one) of the level above (the top level's mask is all
/// outside). Every coherent texel splats, so the traversal needs no order.
pub fn masks(levels: &[Level]) -> Vec<Vec<bool>> {
    let mut out: Vec<Vec<bool>> = levels.iter().map(|l| vec![false; l.texels.len()]).collect();
    for k in 1..levels.len() {
        let (parent, child) = (&levels[k], &levels[k - 1]);
        for y in 0..parent.height {
            for x in 0..parent.width {
                if parent.texels[(y * parent.width + x) as usize].coherence <= 0.0 {
                    continue;
                }
                for (dx, dy) in (-1..=1).flat_map(|j| (-1..=1).map(move |i| (i, j))) {
                    let (cx, cy) = (2 * x as i64 + dx, 2 * y as i64 + dy);
                    if cx >= 0 && cy >= 0 && cx < child.width as i64 && cy < child.height as i64 {
                        out[k - 1][(cy * child.width as i64 + cx) as usize] = true;
                    }
                }
            }
        }
    }
    out
}

/// A sample of §3.6: the level and the texel there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Sample {
    pub level: u32,
    pub x: u32,
    pub y: u32,
}

/// The samples: coherent texels at the top level, and coherent texels outside the splat
/// regions at the others, ordered by level then row.
pub fn samples(levels: &[Level], masks: &[Vec<bool>]) -> Vec<Sample> {
    let top = levels.len().saturating_sub(1);
    let mut out = Vec::new();
    for (k, l) in levels.iter().enumerate() {
        for (i, t) in l.texels.iter().enumerate() {
            if t.coherence > 0.0 && (k == top || !masks[k][i]) {
                out.push(Sample { level: k as u32, x: i as u32 % l.width, y: i as u32 / l.width });
            }
        }
    }
    out
}

/// The supplementary G-buffer of §5.2 as the HCB's base: every texel of `base` with n^w =
/// +1 where `incomplete` (the splatted weight below the threshold) and −1 elsewhere; the
/// background stays 0. Built with [`build`], only positive groups become samples.
pub fn supplementary_base(mut base: Level, incomplete: &[bool]) -> Level {
    for (t, &inc) in base.texels.iter_mut().zip(incomplete) {
        if t.coherence != 0.0 {
            t.coherence = if inc { 1.0 } else { -1.0 };
        }
    }
    base
}

/// §5.3's counter: one frame later a sample's counter `c` is c + 1, and when it reaches the
/// period the light is recomputed and the counter restarts at 0; a sample whose light was
/// never gathered (`lit` false: a frame of the hemisphere mix could not fit it, issue #53)
/// is recomputed at once, its counter's phase kept. Returns (counter, recompute).
pub fn advance_counter(c: u32, period: u32, lit: bool) -> (u32, bool) {
    let next = c + 1;
    if next >= period.max(1) { (0, true) } else { (next, !lit) }
}

/// What §5.1's "updating cache" makes of a cached sample in the current view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CacheStatus {
    /// Outside the view (or behind the eye): dropped.
    Dropped,
    /// The G-buffer there agrees within the thresholds: reused.
    Valid,
    /// The G-buffer there differs (another surface, the background): removed, and the
    /// samples in the quad around it with it.
    Invalid,
}

/// §5.1: a cached sample at `a` (normal `n_a`) is invalid when the G-buffer point `g` (normal
/// `n_g`, `covered` false for the background) it projects to lies farther than `max_distance`
/// or its normal diverges by more than acos(`cos_max_angle`).
pub fn validate(
    a: Vec3,
    n_a: Vec3,
    g: Vec3,
    n_g: Vec3,
    covered: bool,
    max_distance: f32,
    cos_max_angle: f32,
) -> CacheStatus {
    if covered && (g - a).length() <= max_distance && n_a.dot(n_g) >= cos_max_angle {
        CacheStatus::Valid
    } else {
        CacheStatus::Invalid
    }
}

/// The coherence error of point b (normal n_b) toward sample a (§4.2, Eq. 8): the largest
/// of the distance error ‖a − b‖ / a^w, the normal error √(1 − n_a·n_b) / √(1 − cos θ_max)
/// and the pose error ρ √|âb·n_a| / √cos γ_max, with ρ = 1 when the two do not face each
/// other (the first line of Eq. 3) and 0 otherwise. b is coherent to a when it is ≤ 1 (Eq. 9).
pub fn coherence_errors(a: &HcbTexel, b: Vec3, n_b: Vec3, t: Thresholds) -> [f32; 3] {
    let d = b - a.position;
    let len = d.length();
    let e1 = len / a.distance.max(1e-12);
    // 1 − n_a·n_b = ½‖n_a − n_b‖² for unit normals: exact 0 for equal ones, where the square
    // root would magnify the rounding of the dot product.
    let e2 = (0.5 * (a.normal - n_b).length_squared()).sqrt() / (1.0 - t.cos_theta_max).max(1e-12).sqrt();
    let e3 = if len > 0.0 {
        let ab = d / len;
        let rho = if ab.dot(a.normal) <= 0.0 || (-ab).dot(n_b) <= 0.0 { 1.0 } else { 0.0 };
        rho * ab.dot(a.normal).abs().sqrt() / t.cos_gamma_max.max(1e-12).sqrt()
    } else {
        0.0
    };
    [e1, e2, e3]
}

/// The weight of sample a toward b (Eq. 10), or None when b is not coherent to a (Eq. 9).
pub fn weight(a: &HcbTexel, b: Vec3, n_b: Vec3, t: Thresholds) -> Option<f32> {
    let [e1, e2, e3] = coherence_errors(a, b, n_b, t);
    (e1.max(e2).max(e3) <= 1.0).then_some((1.0 - e1) * (1.0 - e2) * (1.0 - e3))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::maths::recompute_pattern;

    fn plane(w: u32, h: u32, spacing: f32) -> Level {
        let texels = (0..w * h)
            .map(|i| HcbTexel {
                position: Vec3::new((i % w) as f32 * spacing, (i / w) as f32 * spacing, 0.0),
                distance: spacing,
                normal: Vec3::Z,
                coherence: 1.0,
            })
            .collect();
        Level { width: w, height: h, texels }
    }

    const LOOSE: Thresholds =
        Thresholds { cos_theta_max: 0.9, cos_gamma_max: 0.5, d_max: 1e9, spread_incomplete: false };

    /// Whether texel (x, y) of level k of a w×w image has every texel it stands for inside
    /// the image (its block, its children's blocks, … down to level 0).
    fn inside(k: u32, x: i64, y: i64, w: &[u32]) -> bool {
        if k == 0 {
            return x >= 0 && y >= 0 && x < w[0] as i64 && y < w[0] as i64;
        }
        (-1..=1).all(|j| (-1..=1).all(|i| inside(k - 1, 2 * x + i, 2 * y + j, w)))
    }

    #[test]
    fn a_plane_is_coherent_up_to_the_top_wherever_its_blocks_lie_inside() {
        let levels = build(plane(17, 17, 0.1), 4, LOOSE);
        let sizes: Vec<u32> = levels.iter().map(|l| l.width).collect();
        assert_eq!(sizes, [17, 9, 5, 3]);
        for (k, l) in levels.iter().enumerate().skip(1) {
            for (i, t) in l.texels.iter().enumerate() {
                let (x, y) = ((i as u32 % l.width) as i64, (i as u32 / l.width) as i64);
                let want = if inside(k as u32, x, y, &sizes) { 1.0 } else { 0.0 };
                assert_eq!(t.coherence, want, "level {k} texel ({x}, {y})");
            }
        }
        assert_eq!(levels[3].at(1, 1).expect("t").coherence, 1.0, "the top's centre stands for the plane");
        // The accumulated distance of level 1 is the diagonal neighbour's ‖a − c‖ + R_c.
        let d1 = levels[1].at(1, 1).expect("texel").distance;
        assert!((d1 - (0.1 * 2f32.sqrt() + 0.1)).abs() < 1e-5, "{d1}");
        // Every pixel is a sample or inside a splat; the top's centre is a sample.
        let m = masks(&levels);
        let s = samples(&levels, &m);
        assert!(s.contains(&Sample { level: 3, x: 1, y: 1 }));
        assert!(m[0].iter().zip(&levels[0].texels).enumerate().all(|(i, (&inside, _))| {
            inside || s.contains(&Sample { level: 0, x: i as u32 % 17, y: i as u32 / 17 })
        }));
        assert!(s.len() < 17 * 17 / 2, "{} samples", s.len());
    }

    #[test]
    fn d_max_bounds_the_accumulated_distance() {
        let levels = build(plane(17, 17, 0.1), 4, Thresholds { d_max: 0.5, ..LOOSE });
        // Level 1 reaches 0.24; level 2 would reach 0.24 + 0.28 > 0.5.
        assert_eq!(levels[1].at(4, 4).expect("t").coherence, 1.0);
        assert!(levels[2].texels.iter().chain(&levels[3].texels).all(|t| t.coherence == 0.0));
        let m = masks(&levels);
        let s = samples(&levels, &m);
        assert!(s.iter().all(|s| s.level <= 1));
    }

    #[test]
    fn a_step_between_parallel_planes_is_rejected_by_the_pose_test() {
        let n = Vec3::Z;
        let (a, b) = (Vec3::ZERO, Vec3::new(0.1, 0.0, -0.2));
        assert!(!pose_coherent(a, n, b, n, 0.5));
        assert!(pose_coherent(a, n, Vec3::new(0.1, 0.0, 0.0), n, 0.5));
        // Two points facing each other (a concave crease): no backward lighting, so the pose
        // test passes (the normal test judges them); bent the other way (convex) it applies.
        let (na, nb) = (Vec3::new(0.5, 0.0, 1.0).normalize(), Vec3::new(-0.5, 0.0, 1.0).normalize());
        assert!(pose_coherent(Vec3::ZERO, na, Vec3::new(0.1, 0.0, 0.0), nb, 0.1));
        assert!(!pose_coherent(Vec3::ZERO, nb, Vec3::new(0.1, 0.0, 0.0), na, 0.1));
    }

    #[test]
    fn background_and_border_blocks_are_incoherent_and_level_0_outside_splats_are_samples() {
        let mut base = plane(6, 6, 0.1);
        base.texels[0] = HcbTexel::BACKGROUND;
        let levels = build(base, 2, LOOSE);
        // Level 1 is 3×3: (0,0) has the background in its block, (2,y) and (x,2) reach x = 5,
        // y = 5 (inside) but not 6; only blocks centred at 2 and 4 with all 9 inside count.
        assert_eq!(levels[1].at(0, 0).expect("t").coherence, 0.0);
        assert_eq!(levels[1].at(1, 1).expect("t").coherence, 1.0);
        assert_eq!(levels[1].at(2, 2).expect("t").coherence, 1.0);
        let m = masks(&levels);
        let s = samples(&levels, &m);
        // Level-0 samples: covered pixels outside every coherent block.
        for smp in s.iter().filter(|s| s.level == 0) {
            assert!(!m[0][(smp.y * 6 + smp.x) as usize]);
            assert!(smp.x == 0 || smp.y == 0, "{smp:?}");
        }
        assert!(!s.contains(&Sample { level: 0, x: 0, y: 0 }), "the background is no sample");
    }

    #[test]
    fn the_supplementary_hcb_samples_only_groups_with_incomplete_texels_and_fig_7d_spreads_them() {
        // A 17×17 plane whose pixels (4…6, 4…6) are incomplete.
        let incomplete: Vec<bool> =
            (0..17 * 17).map(|i| (4..=6).contains(&(i % 17)) && (4..=6).contains(&(i / 17))).collect();
        let base = supplementary_base(plane(17, 17, 0.1), &incomplete);
        assert_eq!(base.at(5, 5).expect("t").coherence, 1.0);
        assert_eq!(base.at(0, 0).expect("t").coherence, -1.0);
        for spread in [false, true] {
            let t = Thresholds { spread_incomplete: spread, ..LOOSE };
            let levels = build(base.clone(), 4, t);
            // Coherence magnitudes are those of the unsigned HCB.
            let plain = build(plane(17, 17, 0.1), 4, t);
            for (l, p) in levels.iter().zip(&plain) {
                for (a, b) in l.texels.iter().zip(&p.texels) {
                    assert_eq!(a.coherence.abs(), b.coherence, "spread {spread}");
                    assert_eq!(a.distance, b.distance);
                }
            }
            let s = samples(&levels, &masks(&levels));
            assert!(!s.is_empty(), "the incomplete texels get samples (spread {spread})");
            // Every incomplete pixel lies in the 3^k-footprint of a sample.
            for i in (0..17 * 17).filter(|&i| incomplete[i]) {
                let (x, y) = ((i % 17) as i64, (i / 17) as i64);
                let covered = s.iter().any(|smp| {
                    let r = (3i64.pow(smp.level) - 1) / 2;
                    let (sx, sy) = ((smp.x as i64) << smp.level, (smp.y as i64) << smp.level);
                    (x - sx).abs() <= r && (y - sy).abs() <= r
                });
                assert!(covered, "pixel ({x}, {y}) spread {spread}");
            }
            let outside = s.iter().any(|smp| {
                let (sx, sy) = (smp.x << smp.level, smp.y << smp.level);
                !(4..=6).contains(&sx) || !(4..=6).contains(&sy)
            });
            if spread {
                assert!(outside, "Fig. 7d: a sample outside the incomplete texels: {s:?}");
            } else {
                assert!(!outside, "Fig. 7c: samples only on incomplete texels: {s:?}");
            }
        }
        // A fully complete base has no samples at all.
        let none = supplementary_base(plane(17, 17, 0.1), &vec![false; 17 * 17]);
        let levels = build(none, 4, LOOSE);
        assert!(samples(&levels, &masks(&levels)).is_empty());
    }

    #[test]
    fn the_recompute_pattern_splits_a_tile_evenly_and_the_counter_fires_once_per_period() {
        for period in [1u32, 2, 4, 8, 16] {
            let p = recompute_pattern(period);
            let mut counts = vec![0u32; period as usize];
            for row in p {
                for c in row {
                    counts[c as usize] += 1;
                }
            }
            assert!(counts.iter().all(|&c| c == 16 / period), "period {period}: {counts:?}");
            // Each counter fires exactly once in `period` frames.
            for start in 0..period {
                let (mut c, mut fired) = (start, 0);
                for _ in 0..period {
                    let (next, recompute) = advance_counter(c, period, true);
                    fired += recompute as u32;
                    c = next;
                }
                assert_eq!((fired, c), (1, start), "period {period} start {start}");
                // A sample never lit is recomputed at once, its phase kept.
                let (next, _) = advance_counter(start, period, true);
                assert_eq!(advance_counter(start, period, false), (next, true), "period {period} start {start}");
            }
        }
        // Period 4: each row, column and diagonal holds each phase once.
        let p = recompute_pattern(4);
        let all = |cells: [u32; 4]| {
            let mut c = cells;
            c.sort();
            c == [0, 1, 2, 3]
        };
        for i in 0..4 {
            assert!(all(p[i]), "row {i}: {p:?}");
            assert!(all(std::array::from_fn(|y| p[y][i])), "column {i}: {p:?}");
        }
        assert!(all(std::array::from_fn(|i| p[i][i])), "diagonal: {p:?}");
        assert!(all(std::array::from_fn(|i| p[i][3 - i])), "anti-diagonal: {p:?}");
    }

    #[test]
    fn a_cached_sample_is_invalid_when_the_g_buffer_moved_or_turned() {
        let (a, n) = (Vec3::ZERO, Vec3::Z);
        let cos = 20f32.to_radians().cos();
        assert_eq!(validate(a, n, Vec3::new(0.01, 0.0, 0.0), n, true, 0.05, cos), CacheStatus::Valid);
        assert_eq!(validate(a, n, Vec3::new(0.0, 0.0, 0.3), n, true, 0.05, cos), CacheStatus::Invalid);
        assert_eq!(validate(a, n, a, Vec3::X, true, 0.05, cos), CacheStatus::Invalid);
        assert_eq!(validate(a, n, a, n, false, 0.05, cos), CacheStatus::Invalid);
    }
}
