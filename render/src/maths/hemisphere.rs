//! The per-texel table of Gautron et al.'s hemisphere camera (003, "Simple plane sampling"):
//! each texel's direction and solid angle, the border band its compensation adds, and the
//! edge terms of the translational gradient. The GPU pass (`passes::gautron::hemisphere`)
//! uploads it and the CPU twin (`cpu::gautron`) reads it, so both use one table. The one
//! import of the crate is the compensation's setting, a leaf.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

use crate::settings::gautron::BorderCompensation;

/// Per-texel terms of the hemisphere camera ("Simple plane sampling"), 4 vec4 = 64 bytes: the
/// layout the GPU reads (a `storage` array of 4 × `vec4<f32>`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TexelTerms {
    /// xyz: unit direction through the texel centre in the local frame (x along t, y along b,
    /// z along n); w: its solid angle Ω_p = A / (1 + x² + y²)^{3/2} (⚠[gautron.texel-solid-angle] not the printed
    /// A·cos θ / d², see the module docs).
    pub dir: [f32; 4],
    /// x: the band's irradiance weight for the chosen compensation (0 for interior texels or
    /// `Off`); y: the band's solid angle (Σ over the texel's boundary edges of cos θ_b · δφ;
    /// 0 for interior texels or `Off`); zw: the band's ∫(n × ω) dω in the local frame (x, y
    /// components; z is 0) (0 for interior texels or `Off`).
    pub band: [f32; 4],
    /// The edge shared with the right neighbour (i+1, j): xyz = unit normal m_e of the edge on
    /// the sphere pointing toward the neighbour, w = cos θ_e · l_e (cosine at the edge's middle
    /// direction times the edge's angular length); all 0 for the last column.
    pub right: [f32; 4],
    /// The edge shared with the neighbour below (i, j+1): the same; all 0 for the last row.
    pub down: [f32; 4],
}

/// The hemisphere camera's per-texel table ("Simple plane sampling"): an `n`×`n` image plane
/// at distance 1 along the normal, half-width `tan_half` = tan(aperture / 2). Texel (i = column,
/// j = row, row 0 at the top) has its centre at x = (2(i+½)/n − 1)·T, y = (1 − 2(j+½)/n)·T.
#[derive(Clone, Debug, PartialEq)]
pub struct HemisphereTable {
    pub n: u32,
    pub tan_half: f32,
    pub compensation: BorderCompensation,
    /// Row-major, index j·n + i.
    pub texels: Vec<TexelTerms>,
}

/// The band beyond one boundary edge of the tile (p0, p1: its endpoints on the plane z = 1):
/// (cos θ_b · δφ, cos² θ_b / 2 · δφ, ∫_band (n × ω) dω in local x, y).
fn edge_band(p0: Vec2, p1: Vec2) -> (f32, f32, Vec2) {
    let (fa, fb) = (p0.y.atan2(p0.x), p1.y.atan2(p1.x));
    // Wrapped difference in (−π, π]: the left edge (x = −T) straddles φ = ±π.
    let mut d = fb - fa;
    if d > std::f32::consts::PI {
        d -= std::f32::consts::TAU;
    } else if d <= -std::f32::consts::PI {
        d += std::f32::consts::TAU;
    }
    // Integrate in increasing φ so that δφ > 0.
    let (phi0, dphi) = if d >= 0.0 { (fa, d) } else { (fb, -d) };
    let phi1 = phi0 + dphi;
    let mid = (p0 + p1) * 0.5;
    let theta_b = mid.length().atan();
    let cos_b = theta_b.cos();
    let k = (std::f32::consts::FRAC_PI_2 - theta_b) * 0.5 + (2.0 * theta_b).sin() * 0.25;
    let zw = Vec2::new(phi1.cos() - phi0.cos(), phi1.sin() - phi0.sin()) * k;
    (cos_b * dphi, cos_b * cos_b * 0.5 * dphi, zw)
}

/// An interior edge between two texels (p0, p1: its endpoints on the plane z = 1; `toward`:
/// the side of the neighbour): [m_e, cos θ_e · l_e].
fn edge_terms(p0: Vec2, p1: Vec2, toward: Vec3) -> [f32; 4] {
    let e0 = p0.extend(1.0).normalize();
    let e1 = p1.extend(1.0).normalize();
    let c = e0.cross(e1);
    let len = c.length().atan2(e0.dot(e1));
    let cos_e = (e0 + e1).normalize().z;
    let mut m = c.normalize();
    if m.dot(toward) < 0.0 {
        m = -m;
    }
    [m.x, m.y, m.z, cos_e * len]
}

impl HemisphereTable {
    /// The table of an `n`×`n` camera of full aperture `aperture_deg` (Larsen et al.'s 126.87°:
    /// tan(aperture/2) = 2).
    ///
    /// Border compensation ("Simple plane sampling": the border pixels are "extended" to the
    /// horizon): each texel edge on the tile's boundary (corner texels have two) spans the
    /// azimuths φ0 … φ1 of its endpoints (δφ = |φ1 − φ0| wrapped; Σ δφ = 2π over the boundary)
    /// and has θ_b = the polar angle of its middle point. The band θ_b … 90° over δφ has solid
    /// angle cos θ_b · δφ and cosine-weighted measure cos² θ_b / 2 · δφ. `band.x` is
    /// `Off`: 0; `Paper`: cos θ_texel · Σ cos θ_b δφ (the text's Ω_border = Ω_p + cos θ_b δφ
    /// reflected with the texel's own cosine: the extra over Ω_p cos θ_texel); `CosineWeighted`:
    /// Σ cos² θ_b / 2 · δφ. `band.zw` = ∫_band (n × ω) dω with ω = (sin θ cos φ, sin θ sin φ,
    /// cos θ), n × ω = (−sin θ sin φ, sin θ cos φ, 0): K·(cos φ1 − cos φ0, sin φ1 − sin φ0),
    /// K = ∫_{θ_b}^{π/2} sin² θ dθ = (π/2 − θ_b)/2 + sin(2θ_b)/4.
    pub fn new(n: u32, aperture_deg: f32, compensation: BorderCompensation) -> Self {
        assert!(n >= 1, "the hemisphere camera needs at least one texel");
        let tan_half = (aperture_deg.to_radians() * 0.5).tan();
        let nf = n as f32;
        // Plane coordinates of column boundary i and row boundary j (fractional: centres).
        let px = |i: f32| (2.0 * i / nf - 1.0) * tan_half;
        let py = |j: f32| (1.0 - 2.0 * j / nf) * tan_half;
        let area = (2.0 * tan_half / nf).powi(2);
        let mut texels = Vec::with_capacity((n * n) as usize);
        for j in 0..n {
            for i in 0..n {
                let (fi, fj) = (i as f32, j as f32);
                let centre = Vec3::new(px(fi + 0.5), py(fj + 0.5), 1.0);
                let d = centre.normalize();
                let omega = area / centre.length_squared().powf(1.5);
                // The tile's boundary edges of this texel.
                let (x0, x1, y0, y1) = (px(fi), px(fi + 1.0), py(fj), py(fj + 1.0));
                let mut edges = Vec::new();
                if j == 0 {
                    edges.push((Vec2::new(x0, y0), Vec2::new(x1, y0)));
                }
                if j + 1 == n {
                    edges.push((Vec2::new(x0, y1), Vec2::new(x1, y1)));
                }
                if i == 0 {
                    edges.push((Vec2::new(x0, y0), Vec2::new(x0, y1)));
                }
                if i + 1 == n {
                    edges.push((Vec2::new(x1, y0), Vec2::new(x1, y1)));
                }
                let (mut solid, mut cosw, mut zw) = (0.0, 0.0, Vec2::ZERO);
                for (p0, p1) in edges {
                    let (s, c, z) = edge_band(p0, p1);
                    solid += s;
                    cosw += c;
                    zw += z;
                }
                let band = match compensation {
                    BorderCompensation::Off => [0.0; 4],
                    BorderCompensation::Paper => [d.z * solid, solid, zw.x, zw.y],
                    BorderCompensation::CosineWeighted => [cosw, solid, zw.x, zw.y],
                };
                let right =
                    if i + 1 < n { edge_terms(Vec2::new(x1, y0), Vec2::new(x1, y1), Vec3::X) } else { [0.0; 4] };
                let down =
                    if j + 1 < n { edge_terms(Vec2::new(x0, y1), Vec2::new(x1, y1), Vec3::NEG_Y) } else { [0.0; 4] };
                texels.push(TexelTerms { dir: [d.x, d.y, d.z, omega], band, right, down });
            }
        }
        Self { n, tan_half, compensation, texels }
    }

    /// Texel k's direction in a world frame (t, b, n).
    pub fn world_dir(&self, k: usize, t: Vec3, b: Vec3, n: Vec3) -> Vec3 {
        let d = self.texels[k].dir;
        t * d[0] + b * d[1] + n * d[2]
    }
}
