//! CPU twin of Gautron, Křivánek et al.'s irradiance cache splatting (003, SIGGRAPH 2008
//! course notes). The text has no section numbers: the docs cite its slide headings.
//!
//! - The hemisphere camera ("From Ray Tracing to Rasterization", "Simple plane sampling"): the
//!   per-texel terms [`TexelTerms`] of an `n`×`n` image plane at distance 1 along the record's
//!   normal, with the border compensation of the missing grazing directions. The GPU uploads
//!   [`HemisphereTable::texels`] verbatim (64 bytes a texel, row-major).
//! - The record's terms ("Irradiance Caching": position, normal, irradiance, gradients, mean
//!   distance) from the hemisphere's radiance and distances: [`reduce`].
//! - The interpolation ("From Octree to Splatting": "Irradiance Interpolation", "Weighting
//!   Function", "Principle"): [`weight`], [`extrapolate`], [`accumulate`], and the splat's
//!   screen bounds [`sphere_ndc_rect`].
//! - The creation ("Algorithm": records are made where the splatted coverage is
//!   insufficient): [`candidates`], one pixel per screen tile and round.
//!
//! Readings chosen where the text is inconsistent (each tagged with its id, docs/readings.md; also in the items' docs):
//! - ⚠[gautron.texel-solid-angle] "Simple plane sampling" prints Ω_p = A·cos θ / d² with d "the distance between the point
//!   of interest and the image plane". For a plane at distance d the solid angle of a small
//!   texel of area A is A·cos θ / r² with r = d / cos θ the distance to the *texel*, i.e.
//!   A·cos³ θ / d². We use Ω_p = A / (1 + x² + y²)^{3/2} (d = 1); the tests check that Σ Ω_p is
//!   the pyramid's exact solid angle.
//! - ⚠[gautron.border-cosine] The compensation Ω_border = Ω_p + cos θ_border · δφ is a solid angle, but irradiance
//!   needs cosine-weighted measure; [`BorderCompensation`] selects the reading (`Paper`: the
//!   band's solid angle reflected with the border texel's own cosine, `CosineWeighted`: the
//!   band's own cosines, cos² θ_b / 2 · δφ). θ_border is taken per boundary edge, at the
//!   edge's middle (the text's "largest θ covered by the aperture" varies along the edge).
//! - ⚠[gautron.weight-with-radius] "Weighting Function" prints w = 1/(√(‖P−P_k‖² + √(1 − n·n_k))) with no R_k; the next
//!   slide ("Simplified Weighting Function") and Ward 1988 have ‖P−P_k‖/R_k + √(1 − n·n_k): we
//!   use that one, clamped to `w_max` (it is unbounded at P = P_k).
//! - ⚠[gautron.coverage-test] "Irradiance Interpolation" takes S = {k : w_k > 1/a} while "Algorithm"'s creation test
//!   is "W < a": one reading for both, a point is covered iff some record passes w_k > 1/a.
//! - ⚠[gautron.splat-bounds] "Algorithm"'s TransformVertex offsets the centre by ±a·H in view x, y before the
//!   projection: that square is too small, slightly on the optical axis (the silhouette's
//!   half-width is ρ/√(w² − ρ²), not ρ/w, at depth w) and badly off it (the perspective
//!   stretches the projection outward). We bound the sphere exactly from its tangent planes
//!   through the eye ([`sphere_ndc_rect`]).
//!
//! What the border compensation costs the gradients (measured in `tests/tests/gautron_cpu.rs`
//! at 126.87°, tan = 2):
//! - The square pyramid holds 83.1 % of the cosine-weighted hemisphere (the form factor of the
//!   square, 4/π · T/√(1+T²) · atan(T/√(1+T²))), not the 86 % "Simple plane sampling" quotes
//!   from Larsen et al.; `Off` loses 16.9 % of a uniform sky's irradiance.
//! - ∇_r is not cosine-weighted, so the grazing directions dominate it: the bands hold 58 % of
//!   ∫ ω_x² dω. Each band takes the radiance seen in its border texel's direction (more
//!   upright than the band), so for radiance linear in ω ∇_r tends (n → ∞) to 0.964 × the
//!   exact value, while the derivative of the compensated E under a rotation of the frame
//!   tends to 1.035 ×: the two differ by 7.4 % at any n (at a 170° aperture, without bands,
//!   they agree to 0.7 % at n = 32).
//! - ∇_t has no term for the bands' radiance, which follows the border texels as the record
//!   moves: 2 % of the gradient on a smooth ceiling, and steps where a silhouette crosses the
//!   tile's border.

use glam::Vec3;

pub use crate::maths::hemisphere::{HemisphereTable, TexelTerms};

/// Tangent frame of a record's hemisphere camera: (t, b) with t, b, n orthonormal,
/// right-handed (t × b = n).
/// If |n.z| < 0.999: t = normalize(cross(Vec3::Z, n)), else t = normalize(cross(Vec3::X, n));
/// b = cross(n, t).
pub fn frame(n: Vec3) -> (Vec3, Vec3) {
    let t = if n.z.abs() < 0.999 { Vec3::Z.cross(n) } else { Vec3::X.cross(n) }.normalize();
    (t, n.cross(t))
}

/// Rec. 709 luminance weights (the shaders' dot with (0.2126, 0.7152, 0.0722)).
const LUMA: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// A record's terms from its hemisphere ("Irradiance Caching": position, normal, irradiance,
/// gradients, harmonic mean distance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordTerms {
    pub e: Vec3,
    /// Harmonic mean distance (f32::INFINITY when nothing was hit).
    pub h: f32,
    /// ∇_r E per colour channel (world space).
    pub rot: [Vec3; 3],
    /// ∇_t E per colour channel (world space).
    pub trans: [Vec3; 3],
    /// Σ lum(L) cos θ Ω ω (world space): the direction sum of the glossy receiver
    /// (`cpu::brdf::receive_irradiance`; the border band is not included).
    pub dir: Vec3,
}

/// `radiance[k]` (rgb) is the radiance arriving from texel k (0 for the background),
/// `distance[k]` the distance to what texel k sees (f32::INFINITY for the background); `n` the
/// record's normal (its frame is [`frame`]`(n)`). See [`reduce_in_frame`] for the terms.
pub fn reduce(table: &HemisphereTable, n: Vec3, radiance: &[Vec3], distance: &[f32]) -> RecordTerms {
    let (t, b) = frame(n);
    reduce_in_frame(table, t, b, n, radiance, distance)
}

/// [`reduce`] in an explicit right-handed orthonormal frame (t, b, n) (texel k looks along
/// `to_world(dir_k)`, to_world(v) = v.x·t + v.y·b + v.z·n). Sums over the texels k (L_k the
/// radiance, c_k = dir.z, Ω_k = dir.w, ω_k = to_world(dir.xyz)):
///
/// - E = Σ L_k c_k Ω_k + Σ L_k band.x (the compensated bands carry their border texel's
///   radiance, "Simple plane sampling").
/// - H = (Σ_all c_k Ω_k) / (Σ_hit c_k Ω_k / r_k): Ward's harmonic mean, cosine-weighted; a
///   miss counts as infinitely far; ∞ when nothing is hit.
/// - ∇_r = Σ L_k Ω_k (n × ω_k) + Σ L_k to_world(band.z, band.w, 0). Rotating n by a small
///   rotation δ·a (n' = n + δ a × n) changes E = ∫ L max(0, n·ω) dω by
///   δ ∫ L (a × n)·ω dω = δ a·∫ L (n × ω) dω (the max's kink lies on the horizon, where the
///   integrand is 0, so it adds nothing): that integral is ∇_r, and the texels and bands are
///   its quadrature (Ward & Heckbert 1992, "Irradiance Interpolation"'s (n_k × n)·∇_r).
/// - ∇_t = −Σ_edges (L_a − L_b) (cos θ_e l_e) m_e / min(r_a, r_b) over the right and down
///   edges of every texel a with neighbour b (world m_e); an edge whose two sides both miss
///   adds 0. Derivation (Ward & Heckbert 1992; Křivánek et al. 2005's cell boundaries): the
///   radiance is constant per texel and the texels move nowhere, but their *boundaries* do:
///   translating the record by t moves the image of a surface at distance r by −t_⊥ / r on the
///   sphere (t_⊥: t's part orthogonal to the direction), and a boundary moves with the closer
///   of its two surfaces (it occludes the other). The edge's motion along its normal m_e
///   (tangent to the sphere, toward b) is −(t·m_e)/min(r_a, r_b); the cell a then grows into b
///   by that times the edge's length l_e, a sliver of cosine-weighted measure cos θ_e l_e
///   which changes from L_b to L_a: dE = −Σ (L_a − L_b) cos θ_e l_e (m_e·t) / min(r_a, r_b).
///   The tile's outer boundary is fixed (the camera only translates) and the bands keep their
///   border texel's radiance, so neither adds a term.
pub fn reduce_in_frame(
    table: &HemisphereTable,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    radiance: &[Vec3],
    distance: &[f32],
) -> RecordTerms {
    let count = table.texels.len();
    assert_eq!(radiance.len(), count, "one radiance per texel");
    assert_eq!(distance.len(), count, "one distance per texel");
    let to_world = |x: f32, y: f32, z: f32| t * x + b * y + n * z;
    let side = table.n as usize;
    let mut e = Vec3::ZERO;
    let (mut all, mut hit) = (0.0f32, 0.0f32);
    let mut rot = [Vec3::ZERO; 3];
    let mut trans = [Vec3::ZERO; 3];
    let mut dir = Vec3::ZERO;
    for (k, tx) in table.texels.iter().enumerate() {
        let l = radiance[k];
        let [dx, dy, c, omega] = tx.dir;
        e += l * (c * omega + tx.band[0]);
        dir += l.dot(LUMA) * c * omega * to_world(dx, dy, c);
        all += c * omega;
        if distance[k].is_finite() {
            hit += c * omega / distance[k];
        }
        // n × ω_k = to_world((0,0,1) × dir) = to_world(−dir.y, dir.x, 0) (a rotation keeps ×).
        let g = to_world(-dy, dx, 0.0) * omega + to_world(tx.band[2], tx.band[3], 0.0);
        for (ch, r) in rot.iter_mut().enumerate() {
            *r += g * l[ch];
        }
        let (i, j) = (k % side, k / side);
        let neighbours = [(tx.right, i + 1 < side, k + 1), (tx.down, j + 1 < side, k + side)];
        for (edge, exists, nb) in neighbours {
            if !exists {
                continue;
            }
            let (ra, rb) = (distance[k], distance[nb]);
            if !ra.is_finite() && !rb.is_finite() {
                continue;
            }
            let m = to_world(edge[0], edge[1], edge[2]) * (edge[3] / ra.min(rb));
            let dl = l - radiance[nb];
            for (ch, g) in trans.iter_mut().enumerate() {
                *g -= m * dl[ch];
            }
        }
    }
    let h = if hit > 0.0 { all / hit } else { f32::INFINITY };
    RecordTerms { e, h, rot, trans, dir }
}

/// An irradiance record as the splat reads it ("Irradiance Caching", "Irradiance
/// Interpolation").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    pub p: Vec3,
    pub n: Vec3,
    /// R_k after the clamps.
    pub r: f32,
    pub e: Vec3,
    /// ∇_r E per colour channel.
    pub rot: [Vec3; 3],
    /// ∇_t E per colour channel.
    pub trans: [Vec3; 3],
}

/// How the records are blended at a point ("Irradiance Interpolation"), from
/// `GautronSettings` (`Interpolation::of`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interpolation {
    /// Ward's accuracy a: a record contributes where w_k > 1/a.
    pub a: f32,
    /// The clamp of Ward's weight, unbounded at P = P_k.
    pub w_max: f32,
    /// Ward's "in front" test's tolerance × R_k (⚠[gautron.in-front-tolerance]); None: no
    /// test, as 003 prints the interpolation.
    pub in_front: Option<f32>,
    pub rotational: bool,
    pub translational: bool,
}

impl Interpolation {
    /// The interpolation the settings ask for.
    pub fn of(s: &crate::settings::gautron::GautronSettings) -> Self {
        Self {
            a: s.accuracy,
            w_max: s.weight_clamp,
            in_front: s.in_front_test.then_some(s.in_front_tolerance),
            rotational: s.rotational_gradient,
            translational: s.translational_gradient,
        }
    }
}

/// Ward's weight ("Simplified Weighting Function", Ward 1988) 1/(‖P−P_k‖/R_k + √(1 − n·n_k))
/// (1 − n·n_k clamped at 0 under the root), clamped to `w_max` (⚠[gautron.weight-clamp]
/// unbounded at P = P_k; ⚠[gautron.weight-with-radius] the "Weighting Function" slide's
/// √(‖P−P_k‖² + …) without R_k is not used). 0 when the record lies in front of P by Ward's
/// "in front" test (Ward 1988, not in 003): (P − P_k)·(n + n_k)/2 < −tol·R_k, `in_front` =
/// Some(tol); None: no test.
pub fn weight(rec: &Record, p: Vec3, n: Vec3, w_max: f32, in_front: Option<f32>) -> f32 {
    let d = p - rec.p;
    if in_front.is_some_and(|tol| d.dot((n + rec.n) * 0.5) < -tol * rec.r) {
        return 0.0;
    }
    let denom = d.length() / rec.r + (1.0 - n.dot(rec.n)).max(0.0).sqrt();
    // 1/0 = ∞ at P = P_k, n = n_k: the clamp gives w_max.
    (1.0 / denom).min(w_max)
}

/// A record's contribution at (P, n) ("Irradiance Interpolation"):
/// E_k + (n_k × n)·∇_r E_k + (P − P_k)·∇_t E_k per channel, each gradient on or off, clamped to
/// ≥ 0 per channel (a gradient extrapolated far can turn negative) (⚠[gautron.non-negative-extrapolation]).
pub fn extrapolate(rec: &Record, p: Vec3, n: Vec3, rotational: bool, translational: bool) -> Vec3 {
    let axis = rec.n.cross(n);
    let d = p - rec.p;
    let mut out = rec.e;
    for ch in 0..3 {
        if rotational {
            out[ch] += axis.dot(rec.rot[ch]);
        }
        if translational {
            out[ch] += d.dot(rec.trans[ch]);
        }
    }
    out.max(Vec3::ZERO)
}

/// The splat's accumulation at one point ("Principle": the RGB of the blended splats is
/// Σ w_k E'_k, their alpha Σ w_k): (Σ w_k E'_k, Σ w_k) over the records with w_k > 1/a
/// (⚠[gautron.coverage-test] the text's set S = {w_k > 1/a} and its creation test "W < a": one reading for both, a
/// point is covered iff some record passes, i.e. Σ w_k ≥ 1/a; otherwise the sum is exactly 0).
/// The irradiance estimate is the first over the second.
pub fn accumulate(records: &[Record], p: Vec3, n: Vec3, i: &Interpolation) -> (Vec3, f32) {
    let threshold = 1.0 / i.a;
    let mut sum = Vec3::ZERO;
    let mut wsum = 0.0;
    for rec in records {
        let w = weight(rec, p, n, i.w_max, i.in_front);
        if w > threshold {
            sum += extrapolate(rec, p, n, i.rotational, i.translational) * w;
            wsum += w;
        }
    }
    (sum, wsum)
}

/// NDC rectangle [x0, y0, x1, y1] bounding the perspective projection of the sphere of
/// `radius` about `center_view` (view space, camera looking down −z; NDC x = p00 · x_v / (−z_v),
/// y = p11 · y_v / (−z_v)); `None` when the sphere reaches the plane z_v = −near or lies
/// behind it (then the splat covers the whole screen).
///
/// "Principle" splats "a quadrilateral tightly enclosing the splatted sphere" (of radius a·R_k
/// where the simplified weight passes, "Simplified Weighting Function"); ⚠[gautron.splat-bounds] "Algorithm"'s
/// TransformVertex (centre ± a·H before the projection) is too small: ρ/w instead of
/// ρ/√(w² − ρ²) on the axis, and off the axis it misses the perspective's stretching.
/// Exact bounds: the values of x_v/(−z_v) are constant on the planes x + k z = 0 through the
/// eye (containing the y axis), so the extremes over the sphere are the k whose plane is
/// tangent to it: (c_x + k c_z)² = ρ²(1 + k²), with w = −c_z:
/// k = (c_x w ± ρ √(c_x² + w² − ρ²)) / (w² − ρ²); the same in y separately.
pub fn sphere_ndc_rect(center_view: Vec3, radius: f32, p00: f32, p11: f32, near: f32) -> Option<[f32; 4]> {
    let w = -center_view.z;
    if w - radius <= near {
        return None;
    }
    let den = w * w - radius * radius;
    let bounds = |c: f32, scale: f32| {
        let s = radius * (c * c + den).sqrt();
        let (lo, hi) = ((c * w - s) / den * scale, (c * w + s) / den * scale);
        (lo.min(hi), lo.max(hi))
    };
    let (x0, x1) = bounds(center_view.x, p00);
    let (y0, y1) = bounds(center_view.y, p11);
    Some([x0, y0, x1, y1])
}

/// One creation round's candidates ("Algorithm": a record is made where "W < a", read as no
/// record passing w_k > 1/a, i.e. coverage Σ w < 1/a; the GPU does the detection per tile):
/// per tile of `tile`×`tile` pixels (row-major tiles; partial tiles at the right and bottom),
/// the pixel with geometry (`valid`) and `coverage` < 1/a nearest the tile's centre
/// ((tile − 1)/2 from the tile's origin in both axes, also for partial tiles; ties: the lowest
/// row-major index); the candidates in tile order, at most `budget`.
pub fn candidates(
    coverage: &[f32],
    valid: &[bool],
    width: u32,
    height: u32,
    tile: u32,
    a: f32,
    budget: u32,
) -> Vec<(u32, u32)> {
    let count = (width * height) as usize;
    assert_eq!(coverage.len(), count, "one coverage per pixel");
    assert_eq!(valid.len(), count, "one validity per pixel");
    assert!(tile >= 1, "tiles have at least one pixel");
    let threshold = 1.0 / a;
    let mut out = Vec::new();
    for ty in 0..height.div_ceil(tile) {
        for tx in 0..width.div_ceil(tile) {
            if out.len() >= budget as usize {
                return out;
            }
            let (x0, y0) = (tx * tile, ty * tile);
            // Twice the offset from the centre, in integers: exact distances and ties.
            let mut best: Option<(i64, u32, u32)> = None;
            for y in y0..(y0 + tile).min(height) {
                for x in x0..(x0 + tile).min(width) {
                    let k = (y * width + x) as usize;
                    if !valid[k] || coverage[k] >= threshold {
                        continue;
                    }
                    let dx = 2 * i64::from(x - x0) - i64::from(tile - 1);
                    let dy = 2 * i64::from(y - y0) - i64::from(tile - 1);
                    let d2 = dx * dx + dy * dy;
                    // Row-major scan: a strict < keeps the lowest index on ties.
                    if best.is_none_or(|(b, _, _)| d2 < b) {
                        best = Some((d2, x, y));
                    }
                }
            }
            if let Some((_, x, y)) = best {
                out.push((x, y));
            }
        }
    }
    out
}

/// The text's creation order ("Algorithm": for each pixel in turn, if W < a make a record
/// and splat it before the next pixel), the reference the GPU's batched rounds are compared
/// with (issue #41 point 7): the pixels in scanline order, each with its surface point
/// (`points`, None: background) and the radius a record made there would get (`radius`,
/// R_k after the clamps, from the same H the GPU's hemisphere sees); a record is made where
/// the records made so far leave the coverage Σ w below 1/a (`accumulate`'s reading). Returns
/// the pixels of the records made, in order.
pub fn sequential_scan(
    points: &[Option<(Vec3, Vec3)>],
    radius: &[f32],
    width: u32,
    interp: &Interpolation,
) -> Vec<(u32, u32)> {
    assert_eq!(points.len(), radius.len(), "one radius per pixel");
    let threshold = 1.0 / interp.a;
    let mut records: Vec<Record> = Vec::new();
    let mut made = Vec::new();
    for (k, point) in points.iter().enumerate() {
        let Some((p, n)) = *point else { continue };
        let w: f32 =
            records.iter().map(|r| weight(r, p, n, interp.w_max, interp.in_front)).filter(|&w| w > threshold).sum();
        if w >= threshold || !radius[k].is_finite() || radius[k] <= 0.0 {
            continue;
        }
        let zero = [Vec3::ZERO; 3];
        records.push(Record { p, n, r: radius[k], e: Vec3::ZERO, rot: zero, trans: zero });
        made.push((k as u32 % width, k as u32 / width));
    }
    made
}

/// What the record cache does with a record when something changed (stage 7, the cache
/// across frames; GPU twin `fate` in `shaders/gautron/create.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fate {
    Drop,
    Keep,
    /// Kept and splatted with its old value until computed again in place.
    Stale,
}

/// What changed since the last frame, as the invalidation sees it.
#[derive(Clone, Debug, Default)]
pub struct Changes {
    /// The moved scene draws' indices.
    pub moved: Vec<usize>,
    /// Each moved draw's world bounds (min, max) last frame and now.
    pub bounds: Vec<((Vec3, Vec3), (Vec3, Vec3))>,
    /// How far outside a moved object's bounds a record still counts as lying on it.
    pub margin: f32,
    /// A light changed: every record is invalid.
    pub lights: bool,
    /// Invalid records are kept stale (`Invalidation::Refresh`) instead of dropped.
    pub refresh: bool,
}

/// A record at `p` with normal `n`, whose hemisphere saw the draws of the 128-bit `seen`
/// (bit draw mod 128), already `stale` or not: dropped when it lies on a moved object (inside
/// its old or new bounds, within the margin); invalid when its hemisphere saw a moved draw
/// (by the bits: conservative, a draw 128 further shares the bit), when a moved object's new
/// bounds reach into the half-space in front of it (it could see it now), or when a light
/// changed; an invalid record is dropped or kept stale.
pub fn fate(p: Vec3, n: Vec3, seen: [u32; 4], stale: bool, changes: &Changes) -> Fate {
    let mut invalid = changes.lights;
    for &d in &changes.moved {
        invalid |= seen[(d % 128) / 32] & (1 << (d % 32)) != 0;
    }
    let m = Vec3::splat(changes.margin);
    for &((old_lo, old_hi), (new_lo, new_hi)) in &changes.bounds {
        let inside = |lo: Vec3, hi: Vec3| p.cmpge(lo - m).all() && p.cmple(hi + m).all();
        if inside(old_lo, old_hi) || inside(new_lo, new_hi) {
            return Fate::Drop;
        }
        let (c, e) = ((new_lo + new_hi) * 0.5, (new_hi - new_lo) * 0.5);
        invalid |= (c - p).dot(n) + e.dot(n.abs()) > 0.0;
    }
    match (invalid, changes.refresh) {
        (false, _) if stale => Fate::Stale,
        (false, _) => Fate::Keep,
        (true, true) => Fate::Stale,
        (true, false) => Fate::Drop,
    }
}

/// Neighbour clamping (Křivánek et al. 2006; GPU twins `cs_clamp_cached`, `cs_clamp_new`,
/// `cs_clamp_store` in `shaders/gautron/create.wgsl`): `fresh[i]` marks a round's fresh
/// records (its new ones and the stale ones it computed again), `r[i]` every record's R
/// before; neighbours are records whose influence spheres overlap, ‖P_k − P_j‖ ≤ a·(R_k +
/// R_j). First each other record j: R_j ← min(R_j, R_k + d) over the fresh k; then each fresh
/// k: R_k ← min(R_k, R_j + d) over all j ≠ k, with the others' clamped values and the fresh
/// ones' unclamped values; `lower` re-applies R's lower clamps to a value that changed.
pub fn neighbour_clamp(p: &[Vec3], r: &mut [f32], fresh: &[bool], a: f32, lower: &dyn Fn(usize, f32) -> f32) {
    let unclamped = r.to_vec();
    let fresh_ones: Vec<usize> = (0..p.len()).filter(|&k| fresh[k]).collect();
    for j in (0..p.len()).filter(|&j| !fresh[j]) {
        let mut c = unclamped[j];
        for &k in &fresh_ones {
            let d = p[k].distance(p[j]);
            if d <= a * (unclamped[k] + unclamped[j]) {
                c = c.min(unclamped[k] + d);
            }
        }
        if c < unclamped[j] {
            r[j] = lower(j, c);
        }
    }
    for &k in &fresh_ones {
        let own = unclamped[k];
        let mut c = own;
        for j in (0..p.len()).filter(|&j| j != k) {
            let rj = if fresh[j] { unclamped[j] } else { r[j] };
            let d = p[k].distance(p[j]);
            if d <= a * (own + rj) {
                c = c.min(rj + d);
            }
        }
        if c < own {
            r[k] = lower(k, c);
        }
    }
}

/// Irradiance at `x` (normal `n`) from one VPL, visibility not included (GI Lab's mix of
/// records lit by instant radiosity; twin of `vpl_irradiance` in `shaders/common/vpl.wgsl`):
/// Φ · f_y(ω_in, y→x) · cos θ_y · cos θ_x / max(d², d_min²) (Knecht 002 Eq. 4.7–4.8); a VPL
/// closer than `near` (the near field's cut) sends nothing.
pub fn vpl_irradiance(vpl: &crate::cpu::knecht::Vpl, x: Vec3, n: Vec3, d_min: f32, near: f32) -> Vec3 {
    let w = vpl.position - x;
    let d2 = w.length_squared();
    if d2 < near * near {
        return Vec3::ZERO;
    }
    let l = w / d2.max(1e-12).sqrt();
    let (cos_x, cos_y) = (n.dot(l), -vpl.normal.dot(l));
    if cos_x <= 0.0 || cos_y <= 0.0 {
        return Vec3::ZERO;
    }
    let f_y = crate::cpu::brdf::eval(vpl.normal, vpl.incident, -l, vpl.albedo, vpl.di, vpl.si, vpl.sp);
    vpl.flux * f_y * cos_y * cos_x / d2.max(d_min * d_min)
}

/// A record lit by VPLs instead of a hemisphere (twin of `cs_vpl_records` in
/// `shaders/gautron/vpl_records.wgsl`), in the record's frame (t, b, n):
///
/// - E = Σ V_i E_i(P, n), with `visibility(i)` ∈ [0, 1] held at P for every term;
/// - ⚠[gautron.vpl-record-h] H = Σ ℓ_i / Σ (ℓ_i / d_i), ℓ_i the luminance of V_i E_i(P, n): the harmonic mean of the
///   visible VPLs' distances weighted by what each sends (∞ when none sends anything);
/// - ∇_t = t·D_t + b·D_b with D_u = (E(P + ε_t u) − E(P − ε_t u)) / 2ε_t, and ∇_r = t·R_t +
///   b·R_b with R_u the central difference of E over n turned by ±ε_r about u (about t: n ∓
///   ε_r b; about b: n ± ε_r t, normalised), so that E(n') ≈ E + (n × n')·∇_r as the
///   hemisphere's ∇_r.
pub fn vpl_record(
    vpls: &[crate::cpu::knecht::Vpl],
    visibility: &dyn Fn(usize) -> f32,
    (p, t, b, n): (Vec3, Vec3, Vec3, Vec3),
    d_min: f32,
    near: f32,
    eps_t: f32,
    eps_r: f32,
) -> RecordTerms {
    let nt = [(n - eps_r * b).normalize(), (n + eps_r * b).normalize()];
    let nb = [(n + eps_r * t).normalize(), (n - eps_r * t).normalize()];
    let mut e = Vec3::ZERO;
    let (mut h_num, mut h_den) = (0.0f32, 0.0f32);
    let mut d = [Vec3::ZERO; 8];
    let mut dir = Vec3::ZERO;
    for (i, vpl) in vpls.iter().enumerate() {
        let v = visibility(i);
        if v <= 0.0 {
            continue;
        }
        let at = |x: Vec3, m: Vec3| vpl_irradiance(vpl, x, m, d_min, near) * v;
        let ei = at(p, n);
        e += ei;
        let l = ei.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        if l > 0.0 {
            h_num += l;
            h_den += l / vpl.position.distance(p).max(1e-6);
            dir += l * (vpl.position - p).normalize_or_zero();
        }
        let terms = [
            at(p + eps_t * t, n),
            at(p - eps_t * t, n),
            at(p + eps_t * b, n),
            at(p - eps_t * b, n),
            at(p, nt[0]),
            at(p, nt[1]),
            at(p, nb[0]),
            at(p, nb[1]),
        ];
        for (acc, term) in d.iter_mut().zip(terms) {
            *acc += term;
        }
    }
    let (gt, gb) = ((d[0] - d[1]) / (2.0 * eps_t), (d[2] - d[3]) / (2.0 * eps_t));
    let (rt, rb) = ((d[4] - d[5]) / (2.0 * eps_r), (d[6] - d[7]) / (2.0 * eps_r));
    let channel = |u: Vec3, w: Vec3, c: usize| t * u[c] + b * w[c];
    RecordTerms {
        e,
        h: if h_den > 0.0 { h_num / h_den } else { f32::INFINITY },
        rot: [channel(rt, rb, 0), channel(rt, rb, 1), channel(rt, rb, 2)],
        trans: [channel(gt, gb, 0), channel(gt, gb, 1), channel(gt, gb, 2)],
        dir,
    }
}
