//! Dynamic diffuse global illumination (DDGI), the CPU twin of the stage choice
//! `pipeline.gather = Probes` (issue #56 point 3; `passes::ddgi`, docs/architecture.md "Rays on
//! the GPU"). Majercik,
//! Guertin, Nowrouzezahrai and McGuire, "Dynamic Diffuse Global Illumination with Ray-Traced
//! Irradiance Fields", JCGT 8(2), 2019 (cited below as 2019 §n), and Majercik, Marrs, Spjut
//! and McGuire, "Scaling Probe-Based Real-Time Dynamic Global Illumination for Production",
//! JCGT 10(2), 2021 (2021 §n):
//!
//! - a grid of probes over the scene's box or the room the camera is in ([`ProbeGrid`]);
//! - per probe and frame, rays in a spherical Fibonacci pattern under a random rotation
//!   ([`spherical_fibonacci`], [`random_rotation`]; 2019 §3.1);
//! - per probe an octahedral tile of irradiance and one of distance moments (mean, mean²),
//!   each with a one-texel border copied from the opposite edges so that bilinear lookups
//!   wrap ([`oct_encode`], [`Atlas`]; 2019 §3.2, Fig. 3), blended into the old values with a
//!   hysteresis ([`update_irradiance`], [`update_distance`]; 2019 §3.3, Eq. 3–4);
//! - shading: the eight probes of the point's cell, each weighted by trilinear, a smooth
//!   backface term and Chebyshev's visibility from the distance moments at the point moved by
//!   the normal and view bias ([`sample`]; 2019 §3.4, Eq. 5–6; 2021 §4.2);
//! - probe classification and relocation, so that probes inside walls neither shade nor leak
//!   ([`classify`], [`relocate`]; 2021 §5.2–5.3).
//!
//! Irradiance is stored divided by π: a texel holds Σ max(0, d·ω) L / Σ max(0, d·ω), the
//! cosine-weighted mean of the radiance about its direction d, which is E(d)/π for directions
//! ω spread evenly over the sphere (∫ max(0, d·ω) dω = π); [`sample`] multiplies by π.

use glam::{Mat3, UVec3, Vec2, Vec3};

use crate::maths::Aabb;

/// A regular grid of probes: `counts` along each axis, the first at `origin`, `spacing`
/// apart (2019 §3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeGrid {
    pub origin: Vec3,
    pub spacing: Vec3,
    pub counts: UVec3,
}

/// Why a grid was made smaller than asked (the device's limits, issue #56 "Bad input").
#[derive(Clone, Debug, PartialEq)]
pub struct GridClamp {
    pub asked: UVec3,
    pub given: UVec3,
    pub reason: String,
}

impl ProbeGrid {
    /// `counts` probes (at least 2 a side) spanning `bounds` inset by half a cell, so that the
    /// outer probes sit inside the box and not on its walls; a flat box gets the spacing of
    /// its largest side on the flat axis (the probes hover over the plane, at half a cell).
    /// At most `max_probes` in all: a larger grid keeps its proportions and says so.
    pub fn fit(bounds: Aabb, counts: UVec3, max_probes: u32) -> (Self, Option<GridClamp>) {
        let asked = counts.max(UVec3::splat(2));
        let mut given = asked;
        let mut clamp = None;
        let total = |c: UVec3| c.x as u64 * c.y as u64 * c.z as u64;
        if total(given) > max_probes.max(8) as u64 {
            let k = (max_probes.max(8) as f64 / total(given) as f64).cbrt();
            given = UVec3::new(
                ((given.x as f64 * k).floor() as u32).max(2),
                ((given.y as f64 * k).floor() as u32).max(2),
                ((given.z as f64 * k).floor() as u32).max(2),
            );
            while total(given) > max_probes.max(8) as u64 {
                let m = given.max_element();
                if given.x == m {
                    given.x -= 1;
                } else if given.y == m {
                    given.y -= 1;
                } else {
                    given.z -= 1;
                }
            }
            clamp = Some(GridClamp {
                asked,
                given,
                reason: format!(
                    "{}×{}×{} probes are more than the device holds ({max_probes}): {}×{}×{}",
                    asked.x, asked.y, asked.z, given.x, given.y, given.z
                ),
            });
        }
        let (min, max) = if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            (Vec3::splat(-1.0), Vec3::splat(1.0))
        } else {
            (bounds.min, bounds.max)
        };
        let mut extent = max - min;
        let largest = extent.max_element().max(1e-3);
        // A flat axis (a ground plane, a wall): as deep as the largest side over the grid.
        let mut centre = (min + max) * 0.5;
        for k in 0..3 {
            if extent[k] < largest * 1e-3 {
                extent[k] = largest / given.max_element() as f32 * (given[k] - 1) as f32;
                centre[k] = min[k] + extent[k] * 0.5;
            }
        }
        // Cells of extent / counts, the probes at the cells' centres.
        let spacing = extent / given.as_vec3();
        let origin = centre - spacing * (given.as_vec3() - Vec3::ONE) * 0.5;
        (Self { origin, spacing, counts: given }, clamp)
    }

    pub fn len(&self) -> usize {
        (self.counts.x * self.counts.y * self.counts.z) as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The probe's grid coordinates (x fastest, then y, then z).
    pub fn coords(&self, index: usize) -> UVec3 {
        let i = index as u32;
        UVec3::new(i % self.counts.x, (i / self.counts.x) % self.counts.y, i / (self.counts.x * self.counts.y))
    }

    pub fn index(&self, c: UVec3) -> usize {
        (c.x + self.counts.x * (c.y + self.counts.y * c.z)) as usize
    }

    /// The probe's place on the grid (before relocation).
    pub fn position(&self, index: usize) -> Vec3 {
        self.origin + self.spacing * self.coords(index).as_vec3()
    }

    /// The cell of `p`: its lowest probe's coordinates (clamped to the grid) and the position
    /// within it, each axis in [0, 1] (2019 §3.4's trilinear weights).
    pub fn cell(&self, p: Vec3) -> (UVec3, Vec3) {
        let g = (p - self.origin) / self.spacing;
        let hi = (self.counts.as_vec3() - Vec3::splat(2.0)).max(Vec3::ZERO);
        let base = g.floor().clamp(Vec3::ZERO, hi);
        (base.as_uvec3(), (g - base).clamp(Vec3::ZERO, Vec3::ONE))
    }
}

/// Direction `i` of `n` on the spherical Fibonacci lattice (Keinert et al. 2015; 2019 §3.1):
/// cos θ = 1 − (2i + 1)/n, φ = 2π · frac(i · (√5 − 1)/2): even cover of the sphere.
pub fn spherical_fibonacci(i: u32, n: u32) -> Vec3 {
    let golden = (5f32.sqrt() - 1.0) * 0.5;
    let s = i as f32 * golden;
    let phi = std::f32::consts::TAU * (s - s.floor());
    let cos_theta = 1.0 - (2.0 * i as f32 + 1.0) / n.max(1) as f32;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(phi.cos() * sin_theta, phi.sin() * sin_theta, cos_theta)
}

/// A uniformly random rotation from three uniforms (Shoemake 1992, "Uniform random
/// rotations"): the frame's rotation of every probe's rays (2019 §3.1), so that over frames
/// the fixed lattice covers every direction.
pub fn random_rotation(u: [f32; 3]) -> Mat3 {
    let (s1, s2) = ((1.0 - u[0]).max(0.0).sqrt(), u[0].max(0.0).sqrt());
    let (t1, t2) = (std::f32::consts::TAU * u[1], std::f32::consts::TAU * u[2]);
    let q = glam::Quat::from_xyzw(s1 * t1.sin(), s1 * t1.cos(), s2 * t2.sin(), s2 * t2.cos()).normalize();
    Mat3::from_quat(q)
}

fn sign_not_zero(v: Vec2) -> Vec2 {
    Vec2::new(if v.x >= 0.0 { 1.0 } else { -1.0 }, if v.y >= 0.0 { 1.0 } else { -1.0 })
}

/// The octahedral coordinates in [−1, 1]² of a unit direction (Cigolle et al. 2014, used by
/// 2019 §3.2): the sphere folded onto an octahedron, its lower half unfolded to the corners.
pub fn oct_encode(d: Vec3) -> Vec2 {
    let l1 = d.x.abs() + d.y.abs() + d.z.abs();
    if l1 <= 0.0 || !l1.is_finite() {
        return Vec2::ZERO;
    }
    let p = Vec2::new(d.x, d.y) / l1;
    if d.z < 0.0 { (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * sign_not_zero(p) } else { p }
}

/// The unit direction of octahedral coordinates `e` ∈ [−1, 1]² ([`oct_encode`]'s inverse).
pub fn oct_decode(e: Vec2) -> Vec3 {
    let z = 1.0 - e.x.abs() - e.y.abs();
    let xy = if z < 0.0 { (Vec2::ONE - Vec2::new(e.y.abs(), e.x.abs())) * sign_not_zero(e) } else { e };
    Vec3::new(xy.x, xy.y, z).normalize_or(Vec3::Z)
}

/// One kind of probe data (irradiance or distance): per probe a square tile of `interior`²
/// texels inside a one-texel border, the tiles in a row-major atlas of `columns` tiles.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    pub interior: u32,
    pub probes: usize,
    pub columns: u32,
    /// RGB (irradiance / π) or (mean, mean², 0) of every texel, borders included.
    pub texels: Vec<Vec3>,
}

impl Atlas {
    pub fn new(interior: u32, probes: usize, fill: Vec3) -> Self {
        let interior = interior.max(2);
        let (columns, width, height) = Self::layout(interior, probes);
        Self { interior, probes, columns, texels: vec![fill; (width * height) as usize] }
    }

    /// The layout of an atlas of `probes` tiles of `interior` texels: (tiles a row, width,
    /// height) in texels; a square of tiles.
    pub fn layout(interior: u32, probes: usize) -> (u32, u32, u32) {
        let columns = (probes.max(1) as f32).sqrt().ceil() as u32;
        let rows = (probes.max(1) as u32).div_ceil(columns);
        let tile = interior.max(2) + 2;
        (columns, columns * tile, rows * tile)
    }

    pub fn tile(&self) -> u32 {
        self.interior + 2
    }

    pub fn width(&self) -> u32 {
        self.columns * self.tile()
    }

    pub fn height(&self) -> u32 {
        (self.probes.max(1) as u32).div_ceil(self.columns) * self.tile()
    }

    /// The atlas texel (x, y) of a probe's tile texel (tx, ty), borders at 0 and tile − 1.
    pub fn texel(&self, probe: usize, tx: u32, ty: u32) -> (u32, u32) {
        let t = self.tile();
        ((probe as u32 % self.columns) * t + tx, (probe as u32 / self.columns) * t + ty)
    }

    pub fn get(&self, probe: usize, tx: u32, ty: u32) -> Vec3 {
        let (x, y) = self.texel(probe, tx, ty);
        self.texels[(y * self.width() + x) as usize]
    }

    pub fn set(&mut self, probe: usize, tx: u32, ty: u32, v: Vec3) {
        let (x, y) = self.texel(probe, tx, ty);
        let w = self.width();
        self.texels[(y * w + x) as usize] = v;
    }

    /// The direction of interior texel (i, j) ∈ [0, interior)² of a tile: its centre's
    /// octahedral coordinates decoded.
    pub fn direction(&self, i: u32, j: u32) -> Vec3 {
        let n = self.interior as f32;
        oct_decode(Vec2::new((i as f32 + 0.5) / n * 2.0 - 1.0, (j as f32 + 0.5) / n * 2.0 - 1.0))
    }

    /// Copies each tile's interior edges into its border as the octahedron folds (2019 Fig. 3):
    /// a border texel takes the interior texel mirrored across the edge's midpoint, a corner
    /// the opposite corner, so that a bilinear lookup at the edge blends the texels that are
    /// neighbours on the sphere.
    pub fn fill_borders(&mut self, probe: usize) {
        let n = self.interior;
        for k in 0..n {
            let m = n - 1 - k;
            // Top and bottom rows: the edge row mirrored in x.
            let top = self.get(probe, 1 + m, 1);
            self.set(probe, 1 + k, 0, top);
            let bottom = self.get(probe, 1 + m, n);
            self.set(probe, 1 + k, n + 1, bottom);
            // Left and right columns: the edge column mirrored in y.
            let left = self.get(probe, 1, 1 + m);
            self.set(probe, 0, 1 + k, left);
            let right = self.get(probe, n, 1 + m);
            self.set(probe, n + 1, 1 + k, right);
        }
        let corners = [(0, 0, n, n), (n + 1, 0, 1, n), (0, n + 1, n, 1), (n + 1, n + 1, 1, 1)];
        for (x, y, sx, sy) in corners {
            let v = self.get(probe, sx, sy);
            self.set(probe, x, y, v);
        }
    }

    /// The tile's value toward `d`, bilinear between texel centres (the border covers the
    /// half texel past the interior's edge), as the GPU's sampler reads it.
    pub fn lookup(&self, probe: usize, d: Vec3) -> Vec3 {
        let e = oct_encode(d);
        let n = self.interior as f32;
        // Tile coordinates in texels, texel centres at k + 0.5, the interior from 1 to n + 1.
        let p = (e * 0.5 + Vec2::splat(0.5)) * n + Vec2::ONE - Vec2::splat(0.5);
        let f = p.floor();
        let t = p - f;
        let hi = (n + 1.0) as u32;
        let at = |x: f32, y: f32| self.get(probe, (x as u32).min(hi), (y as u32).min(hi));
        let top = at(f.x, f.y).lerp(at(f.x + 1.0, f.y), t.x);
        let bottom = at(f.x, f.y + 1.0).lerp(at(f.x + 1.0, f.y + 1.0), t.x);
        top.lerp(bottom, t.y)
    }
}

/// What one of a probe's rays found: the radiance toward the probe (or the sky's), the
/// distance to its hit (`f32::INFINITY`: none) and whether it met a back face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeRay {
    pub dir: Vec3,
    pub radiance: Vec3,
    pub distance: f32,
    pub backface: bool,
}

/// The DDGI settings the twin needs (the panel's, with the papers' symbols).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DdgiParams {
    /// Hysteresis α: the share of the old value kept each update (2019 §3.3; 0.97).
    pub hysteresis: f32,
    /// The distance weight's exponent (2019 §3.3, "depth sharpness", 50).
    pub distance_sharpness: f32,
    /// The longest distance a ray records (misses record it), in probe spacings (1.5).
    pub max_distance: f32,
    /// Normal and view bias as fractions of the smallest spacing (2021 §4.2: 0.2·n + 0.8·v
    /// times 0.75 of the spacing times a tunable; here the two factors).
    pub normal_bias: f32,
    pub view_bias: f32,
}

impl Default for DdgiParams {
    fn default() -> Self {
        Self { hysteresis: 0.97, distance_sharpness: 50.0, max_distance: 1.5, normal_bias: 0.1, view_bias: 0.3 }
    }
}

/// The rays an inactive probe still casts a frame (2021 §5.2: an inactive probe shades
/// nothing, so it is not updated): a spherical Fibonacci lattice of its own of this many under
/// the frame's rotation, enough to see a surface come near and wake the probe.
pub const INACTIVE_RAYS: u32 = 32;

/// The distance an inactive probe's rays past [`INACTIVE_RAYS`] record: not traced (a miss
/// records 1e30).
pub const UNTRACED: f32 = 3.0e38;

/// The lattice a probe's `n` rays of a frame lie on, from the distance its record
/// [`INACTIVE_RAYS`] holds (`w_at`: the record's w by ray index): [`INACTIVE_RAYS`] when the
/// probe was inactive (that record was not traced), else `n`. Ray k's direction is
/// `rotation · spherical_fibonacci(k, lattice)` for k below it.
pub fn lattice(n: u32, w_at: impl Fn(u32) -> Option<f32>) -> u32 {
    if n > INACTIVE_RAYS && w_at(INACTIVE_RAYS).is_some_and(|w| w >= UNTRACED) { INACTIVE_RAYS } else { n }
}

/// The share of a texel's old value kept at the `updates`-th update of a probe grid (0 on
/// the first, whose old values count for nothing): α as printed (2019 §3.3), or with
/// `running_mean` min(α, k/(k+1)), which makes the first 1/(1 − α) updates an even mean of
/// their frames (⚠[ddgi.cold-start], `ddgi.running_mean_start`).
pub fn blend_share(hysteresis: f32, running_mean: bool, updates: u32) -> f32 {
    if running_mean { hysteresis.min(updates as f32 / (updates as f32 + 1.0)) } else { hysteresis }
}

/// A probe's irradiance tile updated from its rays (2019 §3.3, Eq. 3): each interior texel
/// of direction d becomes lerp(Σ max(0, d·ω) L / Σ max(0, d·ω), old, α); back-face hits
/// carry no light (they are inside geometry, 2021 §5.2). Borders refilled.
pub fn update_irradiance(atlas: &mut Atlas, probe: usize, rays: &[ProbeRay], hysteresis: f32) {
    for j in 0..atlas.interior {
        for i in 0..atlas.interior {
            let d = atlas.direction(i, j);
            let (mut sum, mut w) = (Vec3::ZERO, 0.0);
            for r in rays {
                let c = d.dot(r.dir).max(0.0);
                if c > 0.0 {
                    sum += if r.backface { Vec3::ZERO } else { r.radiance } * c;
                    w += c;
                }
            }
            if w > 0.0 {
                let old = atlas.get(probe, 1 + i, 1 + j);
                atlas.set(probe, 1 + i, 1 + j, (sum / w).lerp(old, hysteresis.clamp(0.0, 1.0)));
            }
        }
    }
    atlas.fill_borders(probe);
}

/// A probe's distance tile updated from its rays (2019 §3.3, Eq. 4): mean and mean² of the
/// distance (misses and distances past `max_distance` record it; back-face hits a fifth of
/// theirs, 2021 §5.3, so that the probe sees itself close to the wall it is behind), weighted
/// by max(0, d·ω)^sharpness.
pub fn update_distance(
    atlas: &mut Atlas,
    probe: usize,
    rays: &[ProbeRay],
    hysteresis: f32,
    sharpness: f32,
    max_distance: f32,
) {
    for j in 0..atlas.interior {
        for i in 0..atlas.interior {
            let d = atlas.direction(i, j);
            let (mut sum, mut w) = (Vec2::ZERO, 0.0);
            for r in rays {
                let c = d.dot(r.dir).max(0.0).powf(sharpness);
                if c > 0.0 {
                    let mut t = r.distance.min(max_distance);
                    if r.backface {
                        t *= 0.2;
                    }
                    sum += Vec2::new(t, t * t) * c;
                    w += c;
                }
            }
            if w > 0.0 {
                let old = atlas.get(probe, 1 + i, 1 + j);
                let fresh = (sum / w).extend(0.0);
                atlas.set(probe, 1 + i, 1 + j, fresh.lerp(old, hysteresis.clamp(0.0, 1.0)));
            }
        }
    }
    atlas.fill_borders(probe);
}

/// A probe's state (2021 §5.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProbeState {
    Active,
    /// Inside geometry (most of its rays meet back faces), or with no surface within its cell:
    /// not updated, not sampled.
    Inactive,
}

/// Classification (2021 §5.2): a probe whose rays meet back faces more than `backface_ratio`
/// of the time is inside geometry; one whose nearest front-face hit is farther than its cell
/// reaches (the spacing on every axis) lights nothing near it. Both are inactive.
pub fn classify(rays: &[ProbeRay], spacing: Vec3, backface_ratio: f32) -> ProbeState {
    let n = rays.len().max(1) as f32;
    let back = rays.iter().filter(|r| r.backface && r.distance.is_finite()).count() as f32;
    if back / n > backface_ratio {
        return ProbeState::Inactive;
    }
    let near = rays.iter().any(|r| {
        !r.backface && r.distance.is_finite() && {
            let p = (r.dir * r.distance).abs();
            p.x <= spacing.x && p.y <= spacing.y && p.z <= spacing.z
        }
    });
    if near { ProbeState::Active } else { ProbeState::Inactive }
}

/// Relocation (2021 §5.3): a probe inside geometry (more than `backface_ratio` of back-face
/// hits) moves through the nearest back face toward the open side; one closer than
/// `min_frontface` (a fraction of the spacing) to a front face moves away from it. The
/// offset stays within ±0.45 of a spacing so that the probe keeps to its cell.
pub fn relocate(offset: Vec3, rays: &[ProbeRay], spacing: Vec3, backface_ratio: f32, min_frontface: f32) -> Vec3 {
    let n = rays.len().max(1) as f32;
    let hits = |back: bool| rays.iter().filter(move |r| r.backface == back && r.distance.is_finite());
    let back = hits(true).count() as f32;
    let nearest = |back: bool| hits(back).min_by(|a, b| a.distance.total_cmp(&b.distance));
    let scale = spacing.min_element();
    let mut o = offset;
    if back / n > backface_ratio {
        if let Some(r) = nearest(true) {
            // Just past the back face, into the open.
            o += r.dir * (r.distance + 0.05 * scale);
        }
    } else if let Some(r) = nearest(false)
        && r.distance < min_frontface * scale
    {
        o -= r.dir * (min_frontface * scale - r.distance);
    }
    o.clamp(-0.45 * spacing, 0.45 * spacing)
}

/// One of the eight probes a shading point reads, with its weights (the pixel explanation
/// lists them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeWeight {
    pub probe: usize,
    pub trilinear: f32,
    /// The smooth backface term ((dir·n + 1)/2)² + 0.2 (2019 §3.4).
    pub normal: f32,
    /// Chebyshev's bound from the distance moments, cubed (2019 Eq. 6).
    pub visibility: f32,
    /// The product, small weights crushed (below 0.2: w³/0.04), 0 for an inactive probe.
    pub weight: f32,
    /// The probe's irradiance toward n (E / π).
    pub irradiance: Vec3,
}

/// The probes as a frame samples them: the grid, both atlases, and per probe its relocation
/// offset and its state.
#[derive(Clone, Copy)]
pub struct Probes<'a> {
    pub grid: &'a ProbeGrid,
    pub irradiance: &'a Atlas,
    pub distance: &'a Atlas,
    pub offsets: &'a [Vec3],
    pub states: &'a [ProbeState],
}

/// The irradiance at a surface point `p` of normal `n` seen from direction `v` (toward the
/// eye) from the probes (2019 §3.4, Eq. 5–6; 2021 §4.2): the point moved by the normal and
/// view bias; per probe of its cell the trilinear weight, the backface term, Chebyshev's
/// visibility from the distance moments toward the moved point; the weighted mean of the
/// probes' irradiance toward n, times π. `offsets` and `states` per probe (relocation and
/// classification). Returns E and the eight probes' weights.
pub fn sample(probes: &Probes<'_>, p: Vec3, n: Vec3, v: Vec3, params: &DdgiParams) -> (Vec3, [ProbeWeight; 8]) {
    let Probes { grid, irradiance, distance, offsets, states } = *probes;
    let scale = grid.spacing.min_element();
    let biased = p + (n * params.normal_bias + v * params.view_bias) * scale;
    let (base, alpha) = grid.cell(biased);
    let mut out =
        [ProbeWeight { probe: 0, trilinear: 0.0, normal: 0.0, visibility: 0.0, weight: 0.0, irradiance: Vec3::ZERO };
            8];
    let (mut sum, mut total) = (Vec3::ZERO, 0.0);
    for (k, slot) in out.iter_mut().enumerate() {
        let corner = UVec3::new(k as u32 & 1, (k as u32 >> 1) & 1, (k as u32 >> 2) & 1);
        let c = (base + corner).min(grid.counts - UVec3::ONE);
        let probe = grid.index(c);
        let at = grid.position(probe) + offsets.get(probe).copied().unwrap_or(Vec3::ZERO);
        let t = Vec3::select(corner.cmpeq(UVec3::ONE), alpha, Vec3::ONE - alpha);
        let trilinear = t.x * t.y * t.z;
        let to_probe = (at - p).normalize_or_zero();
        let normal = ((to_probe.dot(n) + 1.0) * 0.5).powi(2) + 0.2;
        let from_probe = biased - at;
        let r = from_probe.length();
        let moments = distance.lookup(probe, from_probe.normalize_or(Vec3::Z));
        let visibility = if r > moments.x {
            let variance = (moments.y - moments.x * moments.x).abs();
            let d = r - moments.x;
            (variance / (variance + d * d).max(1e-12)).powi(3)
        } else {
            1.0
        };
        let active = states.get(probe).is_none_or(|s| *s == ProbeState::Active);
        let mut w = (normal * visibility).max(1e-6);
        if w < 0.2 {
            w = w * w * w / 0.04;
        }
        w *= trilinear;
        if !active {
            w = 0.0;
        }
        let e = irradiance.lookup(probe, n);
        *slot = ProbeWeight { probe, trilinear, normal, visibility, weight: w, irradiance: e };
        sum += e * w;
        total += w;
    }
    let e = if total > 0.0 { sum / total * std::f32::consts::PI } else { Vec3::ZERO };
    (e, out)
}

/// The irradiance the probes give toward `dir` at the point that `weights` ([`sample`]'s) were
/// found for: the same eight weights, each probe's tile read toward `dir`, times π. With `dir`
/// the mirror direction of the view, E(dir)/π is the cosine-weighted mean radiance about it,
/// what a glossy receiver reflects (⚠[ddgi.glossy-receiver], `ddgi.receiver`).
pub fn irradiance_toward(probes: &Probes<'_>, weights: &[ProbeWeight; 8], dir: Vec3) -> Vec3 {
    let (mut sum, mut total) = (Vec3::ZERO, 0.0);
    for w in weights {
        sum += probes.irradiance.lookup(w.probe, dir) * w.weight;
        total += w.weight;
    }
    if total > 0.0 { sum / total * std::f32::consts::PI } else { Vec3::ZERO }
}

#[cfg(test)]
mod tests;
