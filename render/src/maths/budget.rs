//! The VPL budget: its split over light views by power (Knecht 002 §4.4) and the
//! interleaving of VPL slots over the n×n tiles (§3.4.1), shared by the VPL stage, the
//! interleaved gather and their CPU twins.

use crate::maths::pcg_hash;

/// Splits `total` VPLs over views in proportion to their power (Knecht §4.4 samples each
/// light's G-buffer; the split by power is ours): every view with power gets at least one
/// VPL while `total` allows, the remainder goes by largest fractional share.
pub fn split_budget(powers: &[f32], total: u32) -> Vec<u32> {
    let sum: f64 = powers.iter().map(|p| p.max(0.0) as f64).sum();
    if sum <= 0.0 || powers.is_empty() {
        return vec![0; powers.len()];
    }
    let shares: Vec<f64> = powers.iter().map(|p| p.max(0.0) as f64 / sum * total as f64).collect();
    let mut counts: Vec<u32> = shares.iter().map(|s| s.floor() as u32).collect();
    let mut left = total - counts.iter().sum::<u32>();
    for (c, p) in counts.iter_mut().zip(powers) {
        if *c == 0 && *p > 0.0 && left > 0 {
            *c = 1;
            left -= 1;
        }
    }
    let mut order: Vec<usize> = (0..powers.len()).collect();
    order.sort_by(|&a, &b| (shares[b] - shares[b].floor()).total_cmp(&(shares[a] - shares[a].floor())));
    for i in order.into_iter().cycle().take(left as usize) {
        counts[i] += 1;
    }
    counts
}

/// The per-frame slot→tile map of interleaved sampling (Knecht §3.4.1; twin of the loop in
/// `shaders/knecht/interleave/gather.wgsl`; ⚠[knecht.interleave-shuffle] the thesis does not say which
/// VPL shades which tile). Slots are cut into blocks of n² consecutive slots; in block b, tile
/// t takes slot b·n² + (t + o_b) mod n². One VPL per block per tile keeps every tile a
/// representative subset: consecutive slots hold consecutive Halton indices, which lie in
/// different strips of the light view (the radical inverse's leading digits are the index's
/// trailing ones), and the offsets o_b of every n² consecutive blocks are a permutation of
/// 0…n², so each tile takes each of the n² strips once per n² blocks. The offsets are
/// reshuffled every frame (seeded by `frame`), so that a tile's share — and the n×n pattern it
/// would leave — changes from frame to frame. The old map, tile = slot mod n², gave tile t the
/// same strip every frame (the 4×4 block pattern of issue #15). Returns one offset per block
/// (⌈count / n²⌉ of them).
pub fn tile_offsets(count: u32, n: u32, frame: u32) -> Vec<u32> {
    let stride = (n.max(1) * n.max(1)) as usize;
    let blocks = (count as usize).div_ceil(stride);
    let mut offsets = Vec::with_capacity(blocks + stride);
    let mut group = 0u32;
    while offsets.len() < blocks {
        let mut perm: Vec<u32> = (0..stride as u32).collect();
        let seed = pcg_hash(frame.wrapping_mul(0x9E37_79B9) ^ pcg_hash(group));
        for i in (1..stride).rev() {
            let k = (pcg_hash(seed ^ i as u32) as usize) % (i + 1);
            perm.swap(i, k);
        }
        offsets.extend(perm);
        group += 1;
    }
    offsets.truncate(blocks);
    offsets
}

/// The VPL slots of `tile` under [`tile_offsets`]: one per block, those below `count`.
pub fn tile_slots(tile: u32, count: u32, n: u32, offsets: &[u32]) -> impl Iterator<Item = u32> + '_ {
    let stride = n.max(1) * n.max(1);
    offsets.iter().enumerate().map(move |(b, &o)| b as u32 * stride + (tile + o) % stride).filter(move |&k| k < count)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_split_follows_power_and_gives_every_light_one() {
        assert_eq!(split_budget(&[3.0, 1.0], 256), vec![192, 64]);
        assert_eq!(split_budget(&[1000.0, 1.0], 10), vec![9, 1]);
        assert_eq!(split_budget(&[1.0, 0.0, 1.0], 5).iter().sum::<u32>(), 5);
        assert_eq!(split_budget(&[0.0], 5), vec![0]);
    }

    #[test]
    fn every_tile_takes_every_strip_once_and_the_map_changes_per_frame() {
        let (count, n) = (256u32, 4u32);
        let offsets = tile_offsets(count, n, 3);
        assert_eq!(offsets.len(), 16);
        let mut seen = vec![0u32; count as usize];
        for tile in 0..16 {
            let slots: Vec<u32> = tile_slots(tile, count, n, &offsets).collect();
            assert_eq!(slots.len(), 16, "tile {tile}");
            // One slot of each residue mod n² (each strip of the light view) per tile; the
            // old map (slot mod n² = tile) gave every slot the same residue.
            let mut residues: Vec<u32> = slots.iter().map(|k| k % 16).collect();
            residues.sort_unstable();
            assert_eq!(residues, (0..16).collect::<Vec<_>>(), "tile {tile}");
            for k in slots {
                seen[k as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&c| c == 1), "every slot belongs to exactly one tile");
        assert_ne!(offsets, tile_offsets(count, n, 4), "the map is reshuffled each frame");
        assert_eq!(offsets, tile_offsets(count, n, 3), "and deterministic");
        // A partial last block: 7 slots over 4 tiles; n = 1 keeps every slot in its tile.
        let short = tile_offsets(7, 2, 0);
        let sizes: Vec<usize> = (0..4).map(|t| tile_slots(t, 7, 2, &short).count()).collect();
        assert_eq!(sizes.iter().sum::<usize>(), 7);
        assert!(sizes.iter().all(|&c| c == 1 || c == 2), "{sizes:?}");
        assert_eq!(tile_slots(0, 5, 1, &tile_offsets(5, 1, 9)).collect::<Vec<_>>(), [0, 1, 2, 3, 4]);
    }
}
