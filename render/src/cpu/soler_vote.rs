//! CPU twin of the voting filter of Soler et al.'s mip levels (004 §4, Eq. 5, Fig. 5) and of
//! the light that goes down with it: `shaders/soler/vote.wgsl`, compared texel by texel in
//! tests/soler.rs. The readings (soler.vote-depth-relative, soler.vote-apron,
//! soler.vote-radiance-power, soler.vote-consistent) are in `cpu::soler`'s module doc and
//! docs/readings.md.

use glam::Vec3;

use crate::cpu::soler::{Level, Texel, area_factor, gaussian};

/// The σ of the voting filter's three gaussians (Eq. 5; ⚠[soler.vote-sigmas] the paper gives
/// none).
#[derive(Clone, Copy, Debug)]
pub struct VoteSigmas {
    /// g₁ on the texel distance |p_i − p_j| (0 or 1 in the L1 neighbourhood), texels.
    pub pixel: f32,
    /// g₂ on 1 − n_i·n_j.
    pub normal: f32,
    /// g₃ on (z_j − z_i) / z_i.
    pub depth: f32,
    /// `vote_power`: the eye and Eq. 2's least cos β; the sub-pixels' radiance is weighted by
    /// their Eq. 2 areas over the winner's. None: the block's plain mean.
    pub power: Option<(Vec3, f32)>,
    /// `vote_consistent`: the sub-pixels' radiance is also weighted by [`consistency`] with the
    /// winner's normal.
    pub consistent: bool,
}

/// How far a sub-pixel of normal `n` faces as the winner (normal `n_w`) does, with
/// `vote_consistent`: Eq. 5's g₂ on 1 − n·n_w centred on the winner (our reading, the row
/// soler.vote-consistent of docs/readings.md: the coarse texel emits along n_w, so the light of a sub-pixel facing
/// elsewhere would leave in directions it never lit); 1 without it.
pub fn consistency(n: Vec3, n_w: Vec3, s: VoteSigmas) -> f32 {
    if s.consistent { gaussian(1.0 - n.dot(n_w), s.normal) } else { 1.0 }
}

/// Eq. 5: the score of sub-pixel `i` at (x, y) of `fine` over its L1 neighbourhood.
pub fn vote_score(fine: &Level, x: i64, y: i64, s: VoteSigmas) -> f32 {
    let Some(pi) = fine.at(x, y).filter(|t| t.valid()) else { return -1.0 };
    let mut score = 0.0;
    for (dx, dy) in [(0i64, 0i64), (1, 0), (-1, 0), (0, 1), (0, -1)] {
        let Some(pj) = fine.at(x + dx, y + dy).filter(|t| t.valid()) else { continue };
        let dist = (dx.abs() + dy.abs()) as f32;
        score += gaussian(dist, s.pixel)
            * gaussian(1.0 - pi.normal.dot(pj.normal), s.normal)
            * gaussian((pj.depth - pi.depth) / pi.depth, s.depth);
    }
    score
}

/// The next coarser level of `fine` by voting (Eq. 5, Fig. 5), and each texel's winner
/// (0–3: x + 2y in its 2×2 block; −1 where the whole block is background).
pub fn vote_level(fine: &Level, s: VoteSigmas) -> (Level, Vec<i32>) {
    let (w, h) = (fine.width.div_ceil(2), fine.height.div_ceil(2));
    let mut texels = Vec::with_capacity((w * h) as usize);
    let mut winners = Vec::with_capacity((w * h) as usize);
    for cy in 0..h as i64 {
        for cx in 0..w as i64 {
            let mut best = (-1i32, 0.0f32);
            for i in 0..4i64 {
                let (x, y) = (2 * cx + i % 2, 2 * cy + i / 2);
                let Some(t) = fine.at(x, y) else { continue };
                if !t.valid() {
                    continue;
                }
                let score = vote_score(fine, x, y, s);
                if best.0 < 0 || score > best.1 {
                    best = (i as i32, score);
                }
            }
            let mut out = Texel::default();
            if best.0 >= 0 {
                let i = best.0 as i64;
                let win = fine.at(2 * cx + i % 2, 2 * cy + i / 2).copied().unwrap_or_default();
                // Each sub-pixel weighs its consistency with the winner (background inside the
                // image 1, as black): the texel stands for the winner's surface over the block.
                let (mut sum, mut weight) = (Vec3::ZERO, 0.0f32);
                for t in (0..4i64).filter_map(|j| fine.at(2 * cx + j % 2, 2 * cy + j / 2)) {
                    if !t.valid() {
                        weight += 1.0;
                        continue;
                    }
                    let w = consistency(t.normal, win.normal, s);
                    sum += t.radiance * s.power.map_or(1.0, |(eye, m)| area_factor(t, eye, m)) * w;
                    weight += w;
                }
                let area = s.power.map_or(1.0, |(eye, m)| area_factor(&win, eye, m).max(1e-20));
                out = Texel { radiance: sum / (weight.max(1.0) * area), ..win };
            }
            texels.push(out);
            winners.push(best.0);
        }
    }
    (Level { width: w, height: h, texels }, winners)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A texel at `p` (its depth −z) with normal `n` and grey radiance `l`.
    fn t(p: Vec3, n: Vec3, l: f32) -> Texel {
        Texel { position: p, depth: -p.z, normal: n, radiance: Vec3::splat(l), ..Default::default() }
    }

    /// Fig. 5: a lone sub-pixel of another surface loses the vote, and the winner's depth
    /// and normal are kept, not averaged.
    #[test]
    fn voting_keeps_the_larger_surface_and_never_averages() {
        let t = |n: Vec3, z: f32| Texel {
            position: Vec3::new(0.0, 0.0, -z),
            depth: z,
            normal: n,
            radiance: Vec3::ONE,
            ..Default::default()
        };
        let wall = t(Vec3::Z, 2.0);
        let post = t(Vec3::X, 1.0);
        // A 4×4 level: the wall everywhere but texel (1, 1), the post.
        let mut texels = vec![wall; 16];
        texels[5] = post;
        let fine = Level { width: 4, height: 4, texels };
        let s = VoteSigmas { pixel: 1.0, normal: 0.2, depth: 0.05, power: None, consistent: false };
        let (coarse, winners) = vote_level(&fine, s);
        assert_eq!((coarse.width, coarse.height), (2, 2));
        assert_ne!(winners[0], 3, "the post (x + 2y = 3 in block 0) loses");
        assert_eq!((coarse.texels[0].normal, coarse.texels[0].depth), (Vec3::Z, 2.0));
        // Background: no winner, no light.
        let empty = Level { width: 2, height: 2, texels: vec![Texel::default(); 4] };
        let (c, w) = vote_level(&empty, s);
        assert_eq!(w, vec![-1]);
        assert!(!c.texels[0].valid());
    }

    /// `vote_power`: a block of a grazing floor and a wall facing the eye keeps its power
    /// Σ L_i a_i (Eq. 2's area factors) in the winner's area; the plain mean does not.
    #[test]
    fn the_power_preserving_vote_keeps_the_blocks_power() {
        let eye = Vec3::ZERO;
        // Block: two texels of a wall facing the eye (z = −2), two of a floor seen at a
        // grazing angle below them.
        let wall = |x: f32| t(Vec3::new(x, 0.0, -2.0), Vec3::Z, 1.0);
        let floor = |x: f32| t(Vec3::new(x, -0.3, -2.0), Vec3::Y, 3.0);
        let fine = Level { width: 2, height: 2, texels: vec![wall(0.0), wall(0.01), floor(0.0), floor(0.01)] };
        let power = |tx: &[Texel]| tx.iter().map(|t| t.radiance.x * area_factor(t, eye, 0.05)).sum::<f32>();
        let sig = |power| VoteSigmas { pixel: 1.0, normal: 0.2, depth: 0.05, power, consistent: false };
        let (kept, _) = vote_level(&fine, sig(Some((eye, 0.05))));
        let (mean, _) = vote_level(&fine, sig(None));
        let fine_power = power(&fine.texels);
        let coarse = |c: &Level| 4.0 * power(&c.texels);
        assert!((coarse(&kept) - fine_power).abs() < 1e-4 * fine_power, "{} vs {fine_power}", coarse(&kept));
        assert!(
            (coarse(&mean) - fine_power).abs() > 0.1 * fine_power,
            "the plain mean: {} vs {fine_power}",
            coarse(&mean)
        );
    }

    /// `vote_consistent` (issue #51): a block won by an unlit back facing the eye (three
    /// sub-pixels) with one sunlit seat sub-pixel facing up emits no light along the back's
    /// normal; without it the seat's light leaves along the back's normal, amplified by the
    /// areas' ratio with `vote_power`. A block of one surface is the same either way.
    #[test]
    fn the_consistent_vote_keeps_a_sub_pixels_light_off_a_normal_it_does_not_face() {
        let eye = Vec3::ZERO;
        let back = |x: f32| t(Vec3::new(x, 0.0, -2.0), Vec3::Z, 0.0);
        let seat = t(Vec3::new(0.01, -0.3, -2.0), Vec3::Y, 5.0);
        let fine = Level { width: 2, height: 2, texels: vec![back(0.0), back(0.01), back(0.02), seat] };
        let sig =
            |consistent| VoteSigmas { pixel: 1.0, normal: 0.2, depth: 0.05, power: Some((eye, 0.05)), consistent };
        let (on, w_on) = vote_level(&fine, sig(true));
        let (off, w_off) = vote_level(&fine, sig(false));
        assert_eq!(w_on, w_off, "the flag changes the light, not the vote");
        assert_eq!(on.texels[0].normal, Vec3::Z, "the back wins");
        assert!(off.texels[0].radiance.x > 1.0, "without it the seat's light leaves along the back's normal");
        // With it the seat (the only lit sub-pixel) enters weighted by g = g₂(1 − 0) = e^{−12.5},
        // and the block's weight is 3 + g instead of 4.
        let g = gaussian(1.0, 0.2);
        let (on, off) = (on.texels[0].radiance.x, off.texels[0].radiance.x);
        assert!((on - off * g * 4.0 / (3.0 + g)).abs() <= 1e-6 * off && on < 1e-4, "with it: {on}, without: {off}");
        // A corner (two wall sub-pixels facing the eye, two of a floor): the texel keeps the
        // light of the winner's surface over the whole block instead of losing the other's.
        let wall = |x: f32| t(Vec3::new(x, 0.0, -2.0), Vec3::Z, 1.0);
        let floor = |x: f32| t(Vec3::new(x, -0.3, -2.0), Vec3::Y, 3.0);
        let corner = Level { width: 2, height: 2, texels: vec![wall(0.0), wall(0.01), floor(0.0), floor(0.01)] };
        let c = vote_level(&corner, sig(true)).0.texels[0];
        let own = if c.normal == Vec3::Z { 1.0 } else { 3.0 };
        assert!(
            (c.radiance.x - own).abs() < 0.01 * own,
            "winner {:?}: {} against its own {own}",
            c.normal,
            c.radiance.x
        );
        // One surface: the weights are all 1.
        let wall = Level { width: 2, height: 2, texels: vec![t(Vec3::new(0.0, 0.0, -2.0), Vec3::Z, 2.0); 4] };
        assert_eq!(
            vote_level(&wall, sig(true)).0.texels[0].radiance,
            vote_level(&wall, sig(false)).0.texels[0].radiance
        );
    }
}
