//! CPU lookups of a scene texture, as the GPU's material sampler reads it (repeat wrap,
//! bilinear, sRGB decoded to linear): the emitted radiance of emissive textures for the
//! emitters' light samples (`scene::emitters`) and the path tracer (issue #18 point 1).

use glam::{Vec2, Vec3};

use super::TextureImage;

/// sRGB → linear of each 8-bit value (IEC 61966-2-1).
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f32 / 255.0;
            if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
        })
    })
}

impl TextureImage {
    /// Linear RGB of texel (x, y), wrapped (a malformed image reads black).
    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let (w, h) = (self.width.max(1) as i64, self.height.max(1) as i64);
        let i = 4 * (y.rem_euclid(h) * w + x.rem_euclid(w)) as usize;
        match self.rgba8.get(i..i + 3) {
            Some(t) => {
                let lut = srgb_table();
                Vec3::new(lut[t[0] as usize], lut[t[1] as usize], lut[t[2] as usize])
            }
            None => Vec3::ZERO,
        }
    }

    /// Linear RGB at `uv` (texel centres at (i + ½) / size, repeat wrap, bilinear), as the
    /// GPU's `scene.material_sampler` reads mip level 0.
    pub fn sample_linear(&self, uv: Vec2) -> Vec3 {
        if !uv.is_finite() {
            return Vec3::ZERO;
        }
        // Wrapped into [0, 1] first: the texel index of a huge `uv` (a KHR_texture_transform
        // offset of 2⁶³, found by the fuzzer, issue #19) overflowed `x + 1`, and `uv · size`
        // can overflow f32. The f32 remainder is exact, so the wrap is the same.
        let p = uv.rem_euclid(Vec2::ONE) * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        let f = p.floor();
        let (x, y, t) = (f.x as i64, f.y as i64, p - f);
        let top = self.texel(x, y).lerp(self.texel(x + 1, y), t.x);
        let bottom = self.texel(x, y + 1).lerp(self.texel(x + 1, y + 1), t.x);
        top.lerp(bottom, t.y)
    }

    /// RGBA at `uv` as the GPU reads mip 0 (repeat wrap, bilinear): RGB sRGB-decoded when
    /// `srgb` (colours), raw in [0, 1] otherwise (normal, metallic-roughness, occlusion
    /// data); alpha is always linear.
    pub fn sample_rgba(&self, uv: Vec2, srgb: bool) -> glam::Vec4 {
        if !uv.is_finite() {
            return glam::Vec4::ZERO;
        }
        let p = uv.rem_euclid(Vec2::ONE) * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        let f = p.floor();
        let (x, y, t) = (f.x as i64, f.y as i64, p - f);
        let texel = |x: i64, y: i64| {
            let (w, h) = (self.width.max(1) as i64, self.height.max(1) as i64);
            let i = 4 * (y.rem_euclid(h) * w + x.rem_euclid(w)) as usize;
            match self.rgba8.get(i..i + 4) {
                Some(t) => {
                    let c = |k: usize| {
                        if srgb && k < 3 { srgb_table()[t[k] as usize] } else { t[k] as f32 / 255.0 }
                    };
                    glam::Vec4::new(c(0), c(1), c(2), c(3))
                }
                None => glam::Vec4::ZERO,
            }
        };
        let top = texel(x, y).lerp(texel(x + 1, y), t.x);
        let bottom = texel(x, y + 1).lerp(texel(x + 1, y + 1), t.x);
        top.lerp(bottom, t.y)
    }

    /// The box-filtered mip levels below this one, as `scene::upload` gives them to the GPU
    /// (the G-buffer samples them trilinearly) and the path tracer reads them at camera hits
    /// (issue #51): each level halves the one above (at least one texel), each byte the mean
    /// of its 2×2 parents' (rounded down). A malformed image has no levels.
    pub fn box_mips(&self) -> Vec<TextureImage> {
        let (mut w, mut h) = (self.width.max(1), self.height.max(1));
        if self.rgba8.len() != (w as usize * h as usize * 4) {
            return Vec::new();
        }
        let mut level: std::sync::Arc<[u8]> = self.rgba8.clone();
        let mut out = Vec::new();
        while w > 1 || h > 1 {
            let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
            let mut next = vec![0u8; (nw * nh * 4) as usize];
            for y in 0..nh {
                for x in 0..nw {
                    for c in 0..4 {
                        let mut s = 0u32;
                        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                            let (sx, sy) = ((2 * x + dx).min(w - 1), (2 * y + dy).min(h - 1));
                            s += level[((sy * w + sx) * 4 + c) as usize] as u32;
                        }
                        next[((y * nw + x) * 4 + c) as usize] = (s / 4) as u8;
                    }
                }
            }
            (w, h, level) = (nw, nh, next.into());
            out.push(TextureImage {
                name: format!("{}.mip{}", self.name, out.len() + 1),
                width: w,
                height: h,
                rgba8: level.clone(),
            });
        }
        out
    }

    /// The level of detail the GPU's sampler picks where the texture coordinates change by
    /// `duv` = (∂uv/∂x, ∂uv/∂y) per pixel: log₂ of the longer side of the pixel's footprint in
    /// texels of this level (the Vulkan specification's isotropic ρ; −∞ … 0 magnifies).
    pub fn lod(&self, duv: (Vec2, Vec2)) -> f32 {
        let size = Vec2::new(self.width as f32, self.height as f32);
        let rho = (duv.0 * size).length().max((duv.1 * size).length());
        if rho.is_finite() && rho > 0.0 { rho.log2() } else { 0.0 }
    }

    /// RGBA at `uv` filtered trilinearly at level of detail `lod` over `levels` (this level
    /// and its [`Self::box_mips`]), as the G-buffer's `scene.material_sampler` reads it: the
    /// bilinear lookups of the two levels around `lod` (clamped to the chain), blended.
    pub fn sample_trilinear(levels: &[TextureImage], uv: Vec2, lod: f32, srgb: bool) -> glam::Vec4 {
        let Some(top) = levels.len().checked_sub(1) else { return glam::Vec4::ZERO };
        let d = if lod.is_finite() { lod.clamp(0.0, top as f32) } else { 0.0 };
        let lo = d.floor() as usize;
        let a = levels[lo].sample_rgba(uv, srgb);
        match levels.get(lo + 1) {
            Some(next) if d > lo as f32 => a.lerp(next.sample_rgba(uv, srgb), d - lo as f32),
            _ => a,
        }
    }

    /// Mean linear RGB over the triangle `uv` of texture space, from a stratified set of
    /// barycentric points (about one per covered texel, 1 … 256).
    pub fn triangle_mean(&self, uv: [Vec2; 3]) -> Vec3 {
        let points = self.triangle_points(uv);
        points.iter().map(|p| self.sample_linear(*p)).sum::<Vec3>() / points.len().max(1) as f32
    }

    /// The share of the triangle `uv` whose alpha (× `factor`) reaches `cutoff` (glTF
    /// alphaMode MASK), over the same points as [`Self::triangle_mean`].
    pub fn triangle_coverage(&self, uv: [Vec2; 3], factor: f32, cutoff: f32) -> f32 {
        let points = self.triangle_points(uv);
        let kept = points.iter().filter(|p| factor * self.sample_rgba(**p, true).w >= cutoff).count();
        kept as f32 / points.len().max(1) as f32
    }

    /// A stratified set of points of the triangle `uv` of texture space: the centroids of the
    /// n² sub-triangles of its regular subdivision (about one per covered texel, 1 … 256).
    fn triangle_points(&self, uv: [Vec2; 3]) -> Vec<Vec2> {
        let texels = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs() * self.width as f32 * self.height as f32;
        let n = if texels.is_finite() { (texels.sqrt().ceil() as u32).clamp(1, 16) } else { 1 };
        let mut out = Vec::with_capacity((n * n) as usize);
        for i in 0..n {
            for j in 0..n - i {
                let (a, b) = (i as f32, j as f32);
                let up = [(a, b), (a + 1.0, b), (a, b + 1.0)];
                let mut cells = vec![up];
                if i + j + 1 < n {
                    cells.push([(a + 1.0, b), (a + 1.0, b + 1.0), (a, b + 1.0)]);
                }
                for c in cells {
                    let (s, t) =
                        ((c[0].0 + c[1].0 + c[2].0) / (3.0 * n as f32), (c[0].1 + c[1].1 + c[2].1) / (3.0 * n as f32));
                    out.push(uv[0] + (uv[1] - uv[0]) * s + (uv[2] - uv[0]) * t);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 4]) -> TextureImage {
        let rgba8: Vec<u8> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).flat_map(|(x, y)| f(x, y)).collect();
        TextureImage { name: "t".into(), width: w, height: h, rgba8: rgba8.into() }
    }

    #[test]
    fn lookups_decode_srgb_wrap_and_interpolate() {
        let t = image(2, 1, |x, _| if x == 0 { [0, 0, 0, 255] } else { [255, 188, 255, 255] });
        assert_eq!(t.sample_linear(Vec2::new(0.25, 0.5)), Vec3::ZERO);
        let white = t.sample_linear(Vec2::new(0.75, 0.5));
        assert!((white.x - 1.0).abs() < 1e-6 && (white.y - 0.5029).abs() < 1e-3, "sRGB 188 is linear 0.503: {white}");
        // Halfway between the texel centres, and the same one period over.
        let mid = t.sample_linear(Vec2::new(0.5, 0.5));
        assert!((mid.x - 0.5).abs() < 1e-6);
        assert!((t.sample_linear(Vec2::new(1.5, 3.5)) - mid).length() < 1e-6);
        // Repeat wrap across the left edge blends the last texel back in.
        assert!((t.sample_linear(Vec2::new(0.0, 0.5)).x - 0.5).abs() < 1e-6);
        assert_eq!(t.sample_linear(Vec2::NAN), Vec3::ZERO);
        // Coordinates far outside the texture wrap like any other (the texel index of 2⁶³
        // overflowed, found by the fuzzer, issue #19).
        for far in [Vec2::new(0.25, 9.223_372e18), Vec2::new(-1e30, 0.5), Vec2::splat(f32::MAX)] {
            let v = t.sample_linear(far);
            assert!(v.is_finite() && v.max_element() <= 1.0, "{far}: {v}");
        }
        assert_eq!(t.sample_linear(Vec2::new(0.25 + 4096.0, 0.5)), Vec3::ZERO, "a whole number of periods away");
        let broken = TextureImage { name: "short".into(), width: 4, height: 4, rgba8: vec![255; 8].into() };
        assert_eq!(broken.sample_linear(Vec2::new(0.6, 0.6)), Vec3::ZERO, "a short image reads black");
    }

    #[test]
    fn mips_average_their_parents_and_the_level_follows_the_footprint() {
        // 4×2 texels: the first level is 2×1 of the 2×2 blocks' byte means, the last 1×1.
        let t = image(4, 2, |x, y| [(x * 60 + y * 10) as u8, 200, 0, 255]);
        let mips = t.box_mips();
        assert_eq!(mips.iter().map(|m| (m.width, m.height)).collect::<Vec<_>>(), vec![(2, 1), (1, 1)]);
        assert_eq!(&mips[0].rgba8[..], &[35, 200, 0, 255, 155, 200, 0, 255]);
        assert_eq!(&mips[1].rgba8[..], &[95, 200, 0, 255]);
        let broken = TextureImage { name: "short".into(), width: 4, height: 4, rgba8: vec![255; 8].into() };
        assert!(broken.box_mips().is_empty(), "a malformed image has no levels");
        // One texel a pixel is level 0, four texels a pixel level 2 (the longer side counts).
        let big = image(64, 64, |_, _| [0, 0, 0, 255]);
        let texel = 1.0 / 64.0;
        assert!(big.lod((Vec2::new(texel, 0.0), Vec2::new(0.0, texel))).abs() < 1e-6);
        assert!((big.lod((Vec2::new(4.0 * texel, 0.0), Vec2::new(0.0, texel))) - 2.0).abs() < 1e-5);
        assert_eq!(big.lod((Vec2::ZERO, Vec2::ZERO)), 0.0);
        assert_eq!(big.lod((Vec2::NAN, Vec2::ZERO)), 0.0);
        // Trilinear: between two levels the blend of their bilinear lookups, clamped at the ends.
        let levels: Vec<TextureImage> = std::iter::once(t.clone()).chain(mips).collect();
        let uv = Vec2::new(0.3, 0.4);
        let (a, b) = (levels[0].sample_rgba(uv, true), levels[1].sample_rgba(uv, true));
        let half = TextureImage::sample_trilinear(&levels, uv, 0.5, true);
        assert!((half - (a + b) * 0.5).abs().max_element() < 1e-6, "{half} {a} {b}");
        assert_eq!(TextureImage::sample_trilinear(&levels, uv, -3.0, true), a);
        assert_eq!(TextureImage::sample_trilinear(&levels, uv, 9.0, true), levels[2].sample_rgba(uv, true));
        assert_eq!(TextureImage::sample_trilinear(&[], uv, 1.0, true), glam::Vec4::ZERO);
    }

    #[test]
    fn triangle_means_follow_the_covered_texels() {
        // Left half black, right half white (64² texels).
        let t = image(64, 64, |x, _| if x < 32 { [0, 0, 0, 255] } else { [255, 255, 255, 255] });
        let left = t.triangle_mean([Vec2::new(0.05, 0.1), Vec2::new(0.4, 0.1), Vec2::new(0.05, 0.9)]);
        let right = t.triangle_mean([Vec2::new(0.6, 0.1), Vec2::new(0.95, 0.1), Vec2::new(0.6, 0.9)]);
        assert!(left.length() < 1e-6 && (right - Vec3::ONE).length() < 1e-6, "{left} {right}");
        // A triangle over both halves: the white part's share of its area (1/2 here).
        let both = t.triangle_mean([Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)]);
        // x > ½ covers a quarter of the lower-left half square (the corner (½..1, 0..½)).
        assert!((both.x - 0.25).abs() < 0.03, "{both}");
    }
}
