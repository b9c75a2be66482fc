//! A binary bounding volume hierarchy by the surface area heuristic over binned centroids
//! (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies", §3: 16 bins
//! per axis, the split of least A_L·N_L + A_R·N_R), in the flat layout the GPU ray caster
//! walks (`shaders/rays/scene.wgsl`, docs/architecture.md "Rays on the GPU"). One builder
//! for both levels of the two-level hierarchy ([`super::two_level`]): the triangles of a mesh
//! in its own space, and the instances of a scene in the world.

use glam::Vec3;

use crate::maths::Aabb;

/// One node, 32 bytes; WGSL twin: `BvhNode` in `shaders/rays/scene.wgsl`. An inner node has
/// `count` 0 and its two children at `first` and `first + 1`; a leaf holds the `count`
/// primitives `first … first + count − 1` of the build's order.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub lo: [f32; 3],
    pub first: u32,
    pub hi: [f32; 3],
    pub count: u32,
}

impl BvhNode {
    pub fn bounds(&self) -> Aabb {
        Aabb { min: Vec3::from(self.lo), max: Vec3::from(self.hi) }
    }
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A built hierarchy: nodes (root first) and the primitives in leaf order.
#[derive(Clone, Debug, Default)]
pub struct Built {
    pub nodes: Vec<BvhNode>,
    /// `order[k]`: the input index of the k-th primitive of the leaves.
    pub order: Vec<u32>,
    /// The deepest leaf's depth (the root is 0).
    pub depth: u32,
}

/// Bins per axis (Wald 2007 uses 16 to 32: the tree's cost is within a few per cent of a
/// full sweep).
const BINS: usize = 16;

/// Below this depth splits follow the heuristic; deeper, ranges are halved by count, so no
/// leaf lies deeper than `SAH_DEPTH` + log₂ n: the traversal's stack (`RAY_STACK` in
/// `shaders/rays/scene.wgsl`, 64 entries) holds one entry per level.
const SAH_DEPTH: u32 = 38;

/// The deepest a built tree can be for `n` primitives (≤ 64 below 2²⁶ primitives).
pub fn max_depth(n: usize) -> u32 {
    SAH_DEPTH + usize::BITS - n.max(1).leading_zeros()
}

fn area(b: &Aabb) -> f32 {
    if b.is_empty() {
        return 0.0;
    }
    let e = b.extent();
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

fn union(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb { min: a.min.min(b.min), max: a.max.max(b.max) }
}

/// Builds the hierarchy over `boxes` (every box finite and not empty: the callers leave out
/// what is not), leaves of at most `max_leaf` primitives where the heuristic prefers a leaf
/// (at most 1 … 8; a leaf of more arises only from primitives whose centroids coincide and
/// cannot be told apart, halved by count then).
pub fn build(boxes: &[Aabb], max_leaf: usize) -> Built {
    let mut out =
        Built { nodes: Vec::with_capacity(boxes.len() * 2), order: (0..boxes.len() as u32).collect(), depth: 0 };
    if boxes.is_empty() {
        return out;
    }
    let centroids: Vec<Vec3> = boxes.iter().map(|b| b.center()).collect();
    out.nodes.push(BvhNode::default());
    // (node, start, end, depth): the ranges still to split, iteratively (no recursion limit).
    let mut work = vec![(0usize, 0usize, boxes.len(), 0u32)];
    let max_leaf = max_leaf.clamp(1, 8);
    while let Some((node, start, end, depth)) = work.pop() {
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for &i in &out.order[start..end] {
            bounds = union(&bounds, &boxes[i as usize]);
            cbounds.grow(centroids[i as usize]);
        }
        let n = end - start;
        let leaf = |out: &mut Built| {
            out.nodes[node] =
                BvhNode { lo: bounds.min.to_array(), first: start as u32, hi: bounds.max.to_array(), count: n as u32 };
            out.depth = out.depth.max(depth);
        };
        if n == 1 {
            leaf(&mut out);
            continue;
        }
        let split = if depth < SAH_DEPTH {
            sah_split(boxes, &centroids, &mut out.order[start..end], &cbounds, &bounds)
        } else {
            None
        };
        let mid = match split {
            Some((mid, cost)) if n > max_leaf || cost < n as f32 => start + mid,
            // The heuristic prefers a leaf, and the leaf is small enough.
            _ if n <= max_leaf => {
                leaf(&mut out);
                continue;
            }
            // No split found (centroids that coincide) or too deep: halves by count.
            _ => start + n / 2,
        };
        let left = out.nodes.len();
        out.nodes.push(BvhNode::default());
        out.nodes.push(BvhNode::default());
        out.nodes[node] =
            BvhNode { lo: bounds.min.to_array(), first: left as u32, hi: bounds.max.to_array(), count: 0 };
        work.push((left + 1, mid, end, depth + 1));
        work.push((left, start, mid, depth + 1));
    }
    out
}

/// The binned SAH split of `order` (partitioned in place): the count that goes left and the
/// split's cost relative to the node (traversal 1, intersection 1 per primitive), or None
/// when no binned plane separates the centroids.
fn sah_split(
    boxes: &[Aabb],
    centroids: &[Vec3],
    order: &mut [u32],
    cbounds: &Aabb,
    bounds: &Aabb,
) -> Option<(usize, f32)> {
    let extent = cbounds.extent();
    let parent = area(bounds).max(f32::MIN_POSITIVE);
    let mut best: Option<(usize, usize, f32)> = None; // (axis, bins to the left, cost)
    for axis in 0..3 {
        if extent[axis].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin_of = |c: Vec3| (((c[axis] - cbounds.min[axis]) * scale) as usize).min(BINS - 1);
        let mut counts = [0usize; BINS];
        let mut bin_boxes = [Aabb::EMPTY; BINS];
        for &i in order.iter() {
            let b = bin_of(centroids[i as usize]);
            counts[b] += 1;
            bin_boxes[b] = union(&bin_boxes[b], &boxes[i as usize]);
        }
        // Sweeps from the right, then from the left: cost of each of the BINS − 1 planes.
        let mut right_area = [0f32; BINS];
        let mut acc = Aabb::EMPTY;
        for k in (1..BINS).rev() {
            acc = union(&acc, &bin_boxes[k]);
            right_area[k] = area(&acc);
        }
        let (mut acc, mut left_n) = (Aabb::EMPTY, 0usize);
        for k in 1..BINS {
            acc = union(&acc, &bin_boxes[k - 1]);
            left_n += counts[k - 1];
            let right_n = order.len() - left_n;
            if left_n == 0 || right_n == 0 {
                continue;
            }
            let cost = 1.0 + (area(&acc) * left_n as f32 + right_area[k] * right_n as f32) / parent;
            if best.is_none_or(|b| cost < b.2) {
                best = Some((axis, k, cost));
            }
        }
    }
    let (axis, k, cost) = best?;
    let scale = BINS as f32 / extent[axis];
    let goes_left = |i: u32| ((((centroids[i as usize][axis] - cbounds.min[axis]) * scale) as usize).min(BINS - 1)) < k;
    let mut mid = 0;
    for j in 0..order.len() {
        if goes_left(order[j]) {
            order.swap(j, mid);
            mid += 1;
        }
    }
    (mid > 0 && mid < order.len()).then_some((mid, cost))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(c: Vec3, r: f32) -> Aabb {
        Aabb { min: c - Vec3::splat(r), max: c + Vec3::splat(r) }
    }

    /// Every node's box holds its children's (or its primitives'), every primitive is in one
    /// leaf, and no leaf lies deeper than the traversal's stack.
    fn check(boxes: &[Aabb], built: &Built) {
        let mut seen = vec![0u32; boxes.len()];
        let mut stack = vec![(0usize, 0u32)];
        let inside = |a: &Aabb, b: &Aabb| a.min.cmpge(b.min).all() && a.max.cmple(b.max).all();
        while let Some((i, depth)) = stack.pop() {
            let n = built.nodes[i];
            assert!(depth <= built.depth && depth <= max_depth(boxes.len()));
            if n.is_leaf() {
                for k in n.first..n.first + n.count {
                    let p = built.order[k as usize] as usize;
                    seen[p] += 1;
                    assert!(inside(&boxes[p], &n.bounds()), "primitive {p} outside its leaf {i}");
                }
            } else {
                for c in [n.first as usize, n.first as usize + 1] {
                    assert!(inside(&built.nodes[c].bounds(), &n.bounds()), "child {c} outside {i}");
                    stack.push((c, depth + 1));
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1), "each primitive in exactly one leaf");
    }

    #[test]
    fn a_grid_of_boxes_splits_into_small_leaves() {
        let boxes: Vec<Aabb> =
            (0..1000).map(|i| cube(Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32), 0.3)).collect();
        let built = build(&boxes, 4);
        check(&boxes, &built);
        let leaves: Vec<&BvhNode> = built.nodes.iter().filter(|n| n.is_leaf()).collect();
        assert!(leaves.iter().all(|n| n.count <= 4));
        // A balanced tree over a regular grid: about log₂(1000 / leaf size) levels.
        assert!(built.depth <= 12, "depth {}", built.depth);
    }

    #[test]
    fn coincident_and_degenerate_boxes_still_build() {
        // 300 copies of one flat box (a wall's triangles stacked): no plane separates them,
        // they are halved by count.
        let flat = Aabb { min: Vec3::new(0.0, 0.0, 1.0), max: Vec3::new(1.0, 1.0, 1.0) };
        let boxes = vec![flat; 300];
        let built = build(&boxes, 4);
        check(&boxes, &built);
        assert!(built.nodes.iter().filter(|n| n.is_leaf()).all(|n| n.count <= 4));
        assert!(built.depth <= max_depth(300));
        assert!(build(&[], 4).nodes.is_empty());
        let one = build(&[flat], 4);
        assert_eq!((one.nodes.len(), one.nodes[0].count), (1, 1));
    }

    #[test]
    fn a_skewed_distribution_stays_within_the_stack() {
        // Boxes at 2^-k: the heuristic peels one off at a time; the depth bound holds.
        let boxes: Vec<Aabb> = (0..2000).map(|k| cube(Vec3::X * 0.5f32.powi(k % 120), 1e-3)).collect();
        let built = build(&boxes, 2);
        check(&boxes, &built);
        assert!(built.depth <= max_depth(2000) && max_depth(2000) <= 64, "{} {}", built.depth, max_depth(2000));
    }
}
