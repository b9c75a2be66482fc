//! The hierarchical coherence buffer's recompute pattern (Nguyen et al. 000 §5.3), shared by
//! the HCB's passes (uploaded as a uniform) and its CPU twin (`cpu::hcb`).

/// §5.3's 4×4 index pattern (Fig. 8a): the recompute phase of a new sample at texel (x, y)
/// of its level is `pattern[y mod 4][x mod 4]`.
///
/// Departures, both measured on the default scene: (1) ⚠[nguyen.pattern-per-level] the paper
/// tiles the sample buffer at G-buffer resolution, where every sample above level 1 (at pixels
/// that are multiples of 4) would fall on one cell, so we tile each level's texels; (2)
/// ⚠[nguyen.pattern-latin] a randomly shuffled pattern let the lines of level-0 samples along
/// borders and silhouettes fall on few phases (groups of 838 to 1441 samples at 256²), so the
/// 16 cells hold 4·L1 + L2 for two orthogonal Latin squares over GF(4) — L1 = x ⊕ y, L2 = x
/// ⊕ 2y — with the symbols scrambled by a fixed random relabelling: every row, column and
/// diagonal of the tile then holds each of the four phases of period 4 once, and the values
/// modulo 2, 8 and 16 stay balanced too.
pub fn recompute_pattern(period: u32) -> [[u32; 4]; 4] {
    // Multiplication by 2 in GF(4) = {0, 1, a, a + 1} with a² = a + 1.
    const TIMES_2: [u32; 4] = [0, 2, 3, 1];
    // Fixed random relabellings of the two squares' symbols.
    const RELABEL_1: [u32; 4] = [2, 0, 3, 1];
    const RELABEL_2: [u32; 4] = [1, 3, 0, 2];
    let p = period.max(1);
    std::array::from_fn(|y| {
        std::array::from_fn(|x| {
            let (x, y) = (x as u32, y as u32);
            let (l1, l2) = (RELABEL_1[(x ^ y) as usize], RELABEL_2[(x ^ TIMES_2[y as usize]) as usize]);
            (4 * l1 + l2) % p
        })
    })
}
