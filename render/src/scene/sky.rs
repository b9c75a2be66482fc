//! The sky light (#18 point 2): a constant colour or an equirectangular `.hdr` / `.exr` image
//! around the scene, for outdoor scenes; per scene, off by default.
//!
//! The lab lights with the sky as `n` **directional VPLs**: directions drawn from the sky's
//! radiance on a stratified Halton (2, 3) set — uniformly over the sphere for a constant sky,
//! by luminance × sin θ over the image's texels otherwise — each a directional light of
//! irradiance E_j = L(ω_j) / (p(ω_j) · n) (the Monte Carlo estimate of E = ∫ L(ω) cos θ dω,
//! one sample's share). They join the frame's punctual lights ([`Sky::world_lights`]), so
//! each gets an exact orthographic shadow map in stage 2 and is a light view of stage 3's VPL
//! sampling (Knecht's importance warping, split by power like every light): the sky lights
//! the screen, Gautron's hemispheres, and the first bounce of every technique.
//! The path tracer samples the same distribution continuously ([`SkySampler::sample`]), so the
//! ground truth is the true sky, not its `n` directions.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;

use super::{Light, LightKind, WorldLight};
use crate::maths::halton;
use crate::maths::luminance;

/// Where the sky's radiance comes from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sky {
    /// Whether the sky lights the scene (off by default).
    pub enabled: bool,
    /// Linear RGB of a constant sky (used when there is no image).
    pub color: Vec3,
    /// Radiance scale, W/(m²·sr) per unit of colour or image value.
    pub intensity: f32,
    /// The equirectangular image (None: the constant colour) and where it came from.
    pub image: Option<(PathBuf, Arc<EnvMap>)>,
    /// Rotation of the image about the up axis (+Y), degrees.
    pub rotation_deg: f32,
}

impl Sky {
    /// A constant sky of `color` × `intensity`, enabled.
    pub fn constant(color: Vec3, intensity: f32) -> Self {
        Self { enabled: true, color, intensity, image: None, rotation_deg: 0.0 }
    }

    /// Loads an equirectangular image (`.hdr` or `.exr`, width 2 × height) as the sky's
    /// radiance; the constant colour is kept for when the image is removed.
    pub fn load_image(&mut self, path: &Path) -> Result<(), String> {
        let img = crate::image_io::load_float_image(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let map = EnvMap::new(img.width, img.height, img.data.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect())
            .map_err(|e| format!("{}: {e}", path.display()))?;
        self.image = Some((path.to_path_buf(), Arc::new(map)));
        Ok(())
    }

    /// Whether the sky can light anything (enabled, with positive finite radiance somewhere).
    pub fn is_lit(&self) -> bool {
        self.enabled
            && self.intensity.is_finite()
            && self.intensity > 0.0
            && match &self.image {
                Some((_, map)) => map.total > 0.0,
                None => self.color.max_element() > 0.0 && self.color.is_finite(),
            }
    }

    /// The sky's `n` directional VPLs as directional lights (pointing *from* the sky), or none
    /// when the sky is off or dark.
    pub fn world_lights(&self, n: u32) -> Vec<WorldLight> {
        self.world_lights_shifted(n, 0)
    }

    /// [`Self::world_lights`] of the `k`-th rotation of the stratified set ([`sky_shift`]): the
    /// set frame k lights with when `sky.rotate_each_frame` is on (k = 0: the unrotated set).
    pub fn world_lights_shifted(&self, n: u32, k: u32) -> Vec<WorldLight> {
        if !self.is_lit() {
            return Vec::new();
        }
        let sampler = SkySampler::new(self);
        sampler
            .directions_shifted(n, sky_shift(k))
            .into_iter()
            .enumerate()
            .map(|(j, (dir, e))| {
                let peak = e.max_element().max(1e-30);
                WorldLight {
                    light: Light {
                        name: format!("sky {j}"),
                        kind: LightKind::Directional,
                        color: e / peak,
                        intensity: peak,
                        range: None,
                    },
                    position: Vec3::ZERO,
                    direction: -dir,
                }
            })
            .collect()
    }
}

/// An equirectangular radiance image: texel (x, y) covers φ ∈ 2π[x, x+1)/w and
/// θ ∈ π[y, y+1)/h from the up axis (+Y); the image centre looks along −Z.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
    /// Row-major luminance × texel solid angle weights' running sums, per row (conditional CDFs) and of
    /// the rows (marginal CDF); `total` is their sum.
    row_cdf: Vec<f32>,
    marginal: Vec<f32>,
    total: f32,
}

impl EnvMap {
    /// Checks the texels (finite, non-negative) and builds the sampling tables.
    pub fn new(width: u32, height: u32, texels: Vec<Vec3>) -> Result<Self, String> {
        if width == 0 || height == 0 || texels.len() != width as usize * height as usize {
            return Err(format!("a sky image needs texels, got {width}×{height} with {} values", texels.len()));
        }
        if let Some(bad) = texels.iter().position(|t| !t.is_finite() || t.min_element() < 0.0) {
            return Err(format!(
                "texel ({}, {}) is {} — a sky's radiance must be finite and non-negative",
                bad % width as usize,
                bad / width as usize,
                texels[bad]
            ));
        }
        let (w, h) = (width as usize, height as usize);
        let mut row_cdf = vec![0.0f32; w * h];
        let mut marginal = vec![0.0f32; h];
        let mut total = 0.0f64;
        for y in 0..h {
            let omega = texel_solid_angle(y as u32, width, height);
            let mut acc = 0.0f64;
            for x in 0..w {
                acc += f64::from(luminance(texels[y * w + x].to_array()) * omega);
                row_cdf[y * w + x] = acc as f32;
            }
            total += acc;
            marginal[y] = total as f32;
        }
        Ok(Self { width, height, texels, row_cdf, marginal, total: total as f32 })
    }
}

impl EnvMap {
    /// The sampling tables as the GPU path tracer takes them (`passes::rays::pathtrace`): the
    /// rows' running sums (row-major), the running sums of the rows, and their total.
    pub fn tables(&self) -> (&[f32], &[f32], f32) {
        (&self.row_cdf, &self.marginal, self.total)
    }
}

/// The polar angle's cosine at the top of row `y` of `height` (row `height` is the bottom).
fn row_cos(y: u32, height: u32) -> f32 {
    (std::f32::consts::PI * y as f32 / height as f32).cos()
}

/// The solid angle of a texel of row `y`: (2π / w) · (cos θ_top − cos θ_bottom).
fn texel_solid_angle(y: u32, width: u32, height: u32) -> f32 {
    std::f32::consts::TAU / width as f32 * (row_cos(y, height) - row_cos(y + 1, height))
}

/// First index whose running sum exceeds `target` (the sums are non-decreasing).
fn pick(cdf: &[f32], target: f32) -> usize {
    cdf.partition_point(|&c| c <= target).min(cdf.len().saturating_sub(1))
}

/// Samples directions of a sky by its radiance (see the module doc).
pub struct SkySampler<'a> {
    sky: &'a Sky,
    rotation: f32,
}

impl<'a> SkySampler<'a> {
    pub fn new(sky: &'a Sky) -> Self {
        Self { sky, rotation: sky.rotation_deg.to_radians() }
    }

    fn map(&self) -> Option<&'a EnvMap> {
        self.sky.image.as_ref().map(|(_, m)| m.as_ref())
    }

    /// The direction of image coordinates (u, v) ∈ [0, 1)².
    fn direction(&self, u: f32, v: f32) -> Vec3 {
        let phi = std::f32::consts::TAU * u - std::f32::consts::PI + self.rotation;
        let theta = std::f32::consts::PI * v;
        Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
    }

    /// Image coordinates (u, v) ∈ [0, 1)² of direction `d`.
    fn coords(&self, d: Vec3) -> (f32, f32) {
        let phi = d.x.atan2(-d.z) - self.rotation + std::f32::consts::PI;
        let u = (phi / std::f32::consts::TAU).rem_euclid(1.0);
        let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        (u, v)
    }

    /// The sky's radiance toward `-d` seen along direction `d` (d points into the sky).
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let k = self.sky.intensity;
        match self.map() {
            None => self.sky.color * k,
            Some(m) => {
                let (u, v) = self.coords(d);
                let x = ((u * m.width as f32) as usize).min(m.width as usize - 1);
                let y = ((v * m.height as f32) as usize).min(m.height as usize - 1);
                m.texels[y * m.width as usize + x] * k
            }
        }
    }

    /// The density over solid angle of [`SkySampler::sample`] toward `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        match self.map() {
            None => 1.0 / (4.0 * std::f32::consts::PI),
            Some(m) if m.total > 0.0 => {
                // A texel is drawn with probability lum · Ω / total and sampled uniformly over
                // its solid angle Ω (uniform in φ and cos θ): density lum / total.
                let (u, v) = self.coords(d);
                let (w, h) = (m.width as usize, m.height as usize);
                let x = ((u * w as f32) as usize).min(w - 1);
                let y = ((v * h as f32) as usize).min(h - 1);
                luminance(m.texels[y * w + x].to_array()) / m.total
            }
            Some(_) => 0.0,
        }
    }

    /// A direction into the sky for uniforms `u` ∈ [0, 1)², with its radiance and density over
    /// solid angle (None where the density is zero).
    pub fn sample(&self, u: [f32; 2]) -> Option<(Vec3, Vec3, f32)> {
        let d = match self.map() {
            None => {
                let z = 1.0 - 2.0 * u[0];
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = std::f32::consts::TAU * u[1];
                Vec3::new(r * phi.cos(), z, r * phi.sin())
            }
            Some(m) => {
                if m.total <= 0.0 {
                    return None;
                }
                let w = m.width as usize;
                let y = pick(&m.marginal, u[0] * m.total);
                let row_start = if y == 0 { 0.0 } else { m.marginal[y - 1] };
                let row_total = m.marginal[y] - row_start;
                // Row by u[0], column by u[1]; the position inside the texel is what is left of
                // each inside its interval, so the set's stratification carries through.
                let row = &m.row_cdf[y * w..(y + 1) * w];
                let x = pick(row, u[1] * row_total);
                let fy = ((u[0] * m.total - row_start) / row_total.max(1e-30)).clamp(0.0, 0.999_999);
                let before_x = if x == 0 { 0.0 } else { row[x - 1] };
                let fx = ((u[1] * row_total - before_x) / (row[x] - before_x).max(1e-30)).clamp(0.0, 0.999_999);
                // Uniform in cos θ inside the row: uniform over the texel's solid angle.
                let (c0, c1) = (row_cos(y as u32, m.height), row_cos(y as u32 + 1, m.height));
                let v = (c0 + fy * (c1 - c0)).clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
                self.direction((x as f32 + fx) / w as f32, v.clamp(0.0, 0.999_999))
            }
        };
        let pdf = self.pdf(d);
        (pdf > 0.0).then(|| (d, self.radiance(d), pdf))
    }

    /// A direction into the sky seen from a surface of normal `n`, with its radiance and
    /// density over solid angle: a constant sky is sampled ∝ cos θ about `n` (the only
    /// variance left is visibility's), an image by its radiance ([`SkySampler::sample`]).
    pub fn sample_at(&self, n: Vec3, u: [f32; 2]) -> Option<(Vec3, Vec3, f32)> {
        if self.map().is_some() {
            return self.sample(u);
        }
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let r = u[0].sqrt();
        let phi = std::f32::consts::TAU * u[1];
        let cos = (1.0 - u[0]).max(0.0).sqrt();
        let d = (t * (r * phi.cos()) + b * (r * phi.sin()) + n * cos).normalize();
        let pdf = n.dot(d).max(0.0) / std::f32::consts::PI;
        (pdf > 0.0).then(|| (d, self.radiance(d), pdf))
    }

    /// `n` directions on the stratified Halton (2, 3) set, with their irradiance share
    /// E_j = L(ω_j) / (p(ω_j) · n) (directions of zero density are left out).
    pub fn directions(&self, n: u32) -> Vec<(Vec3, Vec3)> {
        self.directions_shifted(n, [0.0, 0.0])
    }

    /// [`Self::directions`] with the set shifted by `shift` modulo 1 (a Cranley–Patterson
    /// rotation: each shifted set is as stratified as the set and, for a uniformly random
    /// shift, an unbiased estimate, so that averaging the sets of successive frames converges
    /// to the sky's integral).
    pub fn directions_shifted(&self, n: u32, shift: [f32; 2]) -> Vec<(Vec3, Vec3)> {
        (1..=n)
            .filter_map(|i| self.sample([(halton(i, 2) + shift[0]).fract(), (halton(i, 3) + shift[1]).fract()]))
            .map(|(d, l, pdf)| (d, l / (pdf * n as f32)))
            .collect()
    }
}

/// The shift of the sky's `k`-th rotated set: 0 for k = 0, then the Halton (5, 7) points, a
/// low-discrepancy sequence of shifts (their average over frames fills the square evenly).
pub fn sky_shift(k: u32) -> [f32; 2] {
    if k == 0 { [0.0, 0.0] } else { [halton(k, 5), halton(k, 7)] }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Σ E_j max(0, n·ω_j) estimates the irradiance π L of a constant sky on any plane.
    #[test]
    fn a_constant_skys_directions_give_pi_l_on_every_plane() {
        let sky = Sky::constant(Vec3::new(1.0, 0.5, 0.25), 2.0);
        let dirs = SkySampler::new(&sky).directions(256);
        assert_eq!(dirs.len(), 256);
        for n in [Vec3::Y, Vec3::NEG_Y, Vec3::X, Vec3::new(1.0, 1.0, -1.0).normalize()] {
            let e: Vec3 = dirs.iter().map(|(d, e)| *e * n.dot(*d).max(0.0)).sum();
            let expected = std::f32::consts::PI * Vec3::new(2.0, 1.0, 0.5);
            assert!((e - expected).abs().max_element() < 0.03 * expected.max_element(), "{n}: {e} vs {expected}");
        }
    }

    /// The image sampler's density integrates to one and matches where its samples land; a
    /// sky of one bright texel sends every direction through that texel with its radiance.
    #[test]
    fn image_sampling_follows_the_radiance() {
        let (w, h) = (16u32, 8u32);
        let mut texels = vec![Vec3::splat(0.1); (w * h) as usize];
        texels[(2 * w + 5) as usize] = Vec3::splat(50.0);
        let mut sky = Sky::constant(Vec3::ONE, 1.0);
        sky.image = Some((PathBuf::from("test"), Arc::new(EnvMap::new(w, h, texels).expect("map"))));
        let s = SkySampler::new(&sky);
        // ∫ pdf dω over a fine grid of directions.
        let (nu, nv) = (256, 128);
        let mut integral = 0.0;
        for j in 0..nv {
            for i in 0..nu {
                let (u, v) = ((i as f32 + 0.5) / nu as f32, (j as f32 + 0.5) / nv as f32);
                let d = s.direction(u, v);
                let d_omega = (std::f32::consts::TAU / nu as f32)
                    * (std::f32::consts::PI / nv as f32)
                    * (std::f32::consts::PI * v).sin();
                integral += s.pdf(d) * d_omega;
                let (cu, cv) = s.coords(d);
                assert!((cu - u).abs() < 1e-4 && (cv - v).abs() < 1e-4, "coords invert direction at ({u}, {v})");
            }
        }
        assert!((integral - 1.0).abs() < 0.01, "∫ pdf = {integral}");
        // E = ∫ L cos dω for the up-facing plane: the estimate over many directions agrees
        // with the grid's.
        let mut grid = Vec3::ZERO;
        for j in 0..nv {
            for i in 0..nu {
                let (u, v) = ((i as f32 + 0.5) / nu as f32, (j as f32 + 0.5) / nv as f32);
                let d = s.direction(u, v);
                let d_omega = (std::f32::consts::TAU / nu as f32)
                    * (std::f32::consts::PI / nv as f32)
                    * (std::f32::consts::PI * v).sin();
                grid += s.radiance(d) * d.y.max(0.0) * d_omega;
            }
        }
        let est: Vec3 = s.directions(4096).iter().map(|(d, e)| *e * d.y.max(0.0)).sum();
        assert!((est - grid).abs().max_element() < 0.03 * grid.max_element(), "{est} vs {grid}");

        let mut bright = vec![Vec3::ZERO; (w * h) as usize];
        bright[(2 * w + 5) as usize] = Vec3::new(3.0, 2.0, 1.0);
        sky.image = Some((PathBuf::from("test"), Arc::new(EnvMap::new(w, h, bright).expect("map"))));
        let s = SkySampler::new(&sky);
        for (d, _) in s.directions(64) {
            let (u, v) = s.coords(d);
            assert_eq!(((u * w as f32) as u32, (v * h as f32) as u32), (5, 2));
        }
    }

    #[test]
    fn bad_images_and_dark_skies_give_no_lights() {
        assert!(EnvMap::new(2, 1, vec![Vec3::ONE]).is_err());
        assert!(EnvMap::new(1, 1, vec![Vec3::splat(f32::NAN)]).unwrap_err().contains("finite"));
        assert!(EnvMap::new(1, 1, vec![Vec3::splat(-1.0)]).is_err());
        let mut sky = Sky::constant(Vec3::ONE, 1.0);
        assert_eq!(sky.world_lights(8).len(), 8);
        sky.enabled = false;
        assert!(sky.world_lights(8).is_empty());
        assert!(Sky::constant(Vec3::ZERO, 1.0).world_lights(8).is_empty());
        assert!(Sky::constant(Vec3::ONE, f32::NAN).world_lights(8).is_empty());
        let mut black = Sky::constant(Vec3::ONE, 1.0);
        black.image = Some((PathBuf::from("black"), Arc::new(EnvMap::new(1, 1, vec![Vec3::ZERO]).expect("map"))));
        assert!(black.world_lights(8).is_empty());
    }
}
