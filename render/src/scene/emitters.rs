//! Emissive surfaces as lights (issue #18 point 1): the scene's emissive triangles in world
//! space, with the power each emits, and the two ways the lab samples them.
//!
//! - A Lambertian emitter of radiance L_e and area A emits the power Φ = π · L_e · A from each
//!   side it emits on: the side its vertex normals face, and with `emitters.two_sided` the
//!   back too when its material is `doubleSided` (off by default: exporters mark most
//!   materials double-sided, and a light panel just under a ceiling — the real Cornell
//!   box's — would pour half its power into the gap, measured ≈ 30 % of that box's first
//!   bounce, as noisy light leaking from a 1 cm slit). Its radiant intensity toward ω is L_e · A · cos θ, which is the intensity
//!   Φ · cos θ / π of a diffuse VPL of flux Φ: **an emitter sample is a VPL** with f = 1/π.
//! - [`Emitters::vpls`]: `count` such VPLs, importance-sampled by power (a triangle with
//!   probability ∝ its luminance power, a point uniform on it, a side uniform among its
//!   sides) from the Halton points (h₂, h₃, h₅)(j + 1): a stratified set, the same every frame.
//!   Each carries Φ_j = π · L_e(y_j) / (pdf_A(y_j) · count), so that Σ_j Φ_j · cos θ / π · … is
//!   an unbiased estimate of the emitters' light (Keller 1997's instant radiosity starts its
//!   light paths on the lights this way; Ritschel et al. 2008 light area lights with ISMs of
//!   such VPLs).
//! - [`Emitters::sample`]: one point with its area density, for the path tracer's next-event
//!   estimation (`cpu::pathtrace`), so that ground truth samples the same emitters.
//!
//! Emission is the material's emissive factor × `KHR_materials_emissive_strength`
//! ([`super::Material::emissive`]) × its emissive texture (the G-buffer's `gbuffer.emission`
//! reads the same). A textured triangle is picked by its mean emitted power (the texture's
//! mean over the triangle, [`super::TextureImage::triangle_mean`]) and its samples carry the
//! texture's radiance at their point, so that the estimate stays unbiased where the texture
//! varies within a triangle; triangles whose texels are all black emit nothing.

use glam::{Mat4, Vec2, Vec3, Vec4Swizzles};

use super::{Scene, SceneState, TextureImage};
use crate::maths::halton;

/// One emissive triangle in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterTriangle {
    pub v: [Vec3; 3],
    /// Unit normal of the emitting side (for two-sided emitters, the front one).
    pub normal: Vec3,
    /// Emitted radiance L_e (W/(m²·sr)), the mean over the triangle for a textured emitter.
    pub radiance: Vec3,
    pub area: f32,
    /// 1, or 2 for a double-sided material (it emits from both sides).
    pub sides: u32,
    /// Emissive texture (index into [`Emitters::textures`]), its UVs at the corners and the
    /// factor it multiplies; None: `radiance` everywhere.
    pub texture: Option<(usize, [Vec2; 3], Vec3)>,
    /// An alpha cutout (glTF alphaMode MASK, issue #37): where it is cut out nothing emits
    /// (`radiance` is then the mean over the triangle, the cut part counted as dark).
    pub cutout: Option<Cutout>,
}

/// The alpha mask of an emitting triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cutout {
    /// The base colour texture (index into [`Emitters::textures`]) and its UVs at the corners.
    pub texture: usize,
    pub uv: [Vec2; 3],
    /// The base colour's alpha factor and the material's cutoff.
    pub factor: f32,
    pub cutoff: f32,
    /// The radiance where the surface is kept, for an emitter without an emissive texture.
    pub kept: Vec3,
}

impl EmitterTriangle {
    /// Power emitted, all sides: π · L_e · A · sides (W per channel).
    pub fn power(&self) -> Vec3 {
        self.radiance * (std::f32::consts::PI * self.area * self.sides as f32)
    }
}

/// A point on an emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSample {
    pub position: Vec3,
    /// Unit normal of the side it emits from.
    pub normal: Vec3,
    pub radiance: Vec3,
    /// Probability density of the point per unit area of that side.
    pub pdf_area: f32,
}

/// A VPL on an emitter: position, normal and flux Φ (W).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterVpl {
    pub position: Vec3,
    pub normal: Vec3,
    pub flux: Vec3,
}

/// The emissive triangles of a scene at one instant, with the distribution that samples them.
#[derive(Clone, Debug, Default)]
pub struct Emitters {
    pub triangles: Vec<EmitterTriangle>,
    /// Cumulative luminance power, ending at 1 (empty without emitters).
    cdf: Vec<f32>,
    /// Total power emitted, all sides (W per channel).
    pub power: Vec3,
    /// Total emitting area, all sides (m²).
    pub area: f32,
    /// The emissive textures the triangles read (shared with the scene, not copied).
    pub textures: Vec<TextureImage>,
}

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl Emitters {
    /// The emissive triangles of `state`'s draws (materials with a non-zero emission;
    /// degenerate triangles are skipped), emitting from their front side.
    pub fn collect(scene: &Scene, state: &SceneState) -> Self {
        Self::collect_sides(scene, state, false)
    }

    /// As [`Self::collect`]; `two_sided`: double-sided materials emit from both sides.
    pub fn collect_sides(scene: &Scene, state: &SceneState, two_sided: bool) -> Self {
        let mut triangles = Vec::new();
        // Scene texture → index into `textures`.
        let mut textures: Vec<TextureImage> = Vec::new();
        let mut texture_map = std::collections::HashMap::new();
        for d in &state.draws {
            let Some(p) = scene.meshes.get(d.mesh).and_then(|m| m.primitives.get(d.primitive)) else { continue };
            let Some(m) = scene.materials.get(p.material) else { continue };
            if luminance(m.emissive) <= 0.0 {
                continue;
            }
            // A material cut out everywhere (its alpha factor below the cutoff, no texture)
            // emits nothing.
            if let Some(cutoff) = m.alpha_cutoff
                && m.base_color_texture.is_none()
                && m.base_color.w < cutoff
            {
                continue;
            }
            let mut texture_index = |t: usize| {
                let image = scene.textures.get(t)?;
                Some(*texture_map.entry(t).or_insert_with(|| {
                    textures.push(image.clone());
                    textures.len() - 1
                }))
            };
            let texture = m.emissive_texture.and_then(&mut texture_index);
            let mask = m.alpha_cutoff.and_then(|c| Some((m.base_color_texture.and_then(&mut texture_index)?, c)));
            let nm: Mat4 = d.world.inverse().transpose();
            for t in p.indices.chunks_exact(3) {
                let Some(vs) = t.iter().map(|&i| p.vertices.get(i as usize)).collect::<Option<Vec<_>>>() else {
                    continue;
                };
                let v = [0, 1, 2].map(|k| d.world.transform_point3(Vec3::from(vs[k].position)));
                let cross = (v[1] - v[0]).cross(v[2] - v[0]);
                let area = 0.5 * cross.length();
                if !(area > 0.0 && area.is_finite()) {
                    continue;
                }
                let shading: Vec3 = vs.iter().map(|x| (nm * Vec3::from(x.normal).extend(0.0)).xyz()).sum();
                let mut normal = cross / (2.0 * area);
                if shading.dot(normal) < 0.0 {
                    normal = -normal;
                }
                let sides = if two_sided && m.double_sided { 2 } else { 1 };
                let uv = [0, 1, 2].map(|k| Vec2::from(vs[k].uv));
                let (mut radiance, texture) = match texture {
                    Some(ti) => (m.emissive * textures[ti].triangle_mean(uv), Some((ti, uv, m.emissive))),
                    None => (m.emissive, None),
                };
                let cutout = mask.map(|(texture, cutoff)| Cutout {
                    texture,
                    uv,
                    factor: m.base_color.w,
                    cutoff,
                    kept: radiance,
                });
                if let Some(c) = cutout {
                    radiance *= textures[c.texture].triangle_coverage(uv, c.factor, c.cutoff);
                }
                if luminance(radiance) <= 0.0 {
                    continue;
                }
                triangles.push(EmitterTriangle { v, normal, radiance, area, sides, texture, cutout });
            }
        }
        Self { textures, ..Self::from_triangles(triangles) }
    }

    pub fn from_triangles(triangles: Vec<EmitterTriangle>) -> Self {
        let mut cdf = Vec::with_capacity(triangles.len());
        let mut total = 0.0f64;
        let (mut power, mut area) = (Vec3::ZERO, 0.0);
        for t in &triangles {
            total += luminance(t.power()) as f64;
            cdf.push(total as f32);
            power += t.power();
            area += t.area * t.sides as f32;
        }
        if total > 0.0 {
            for c in &mut cdf {
                *c = (*c as f64 / total) as f32;
            }
            if let Some(last) = cdf.last_mut() {
                *last = 1.0;
            }
        } else {
            cdf.clear();
        }
        Self { triangles, cdf, power, area, textures: Vec::new() }
    }

    /// Whether there is anything to sample.
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// Luminance of the total power (W).
    pub fn luminance_power(&self) -> f32 {
        luminance(self.power)
    }

    /// The triangle that `u` ∈ [0, 1) picks (∝ luminance power) and its probability.
    /// The running sum of the triangles' power shares up to triangle `i` (1 at the last),
    /// what [`Self::sample`]'s first uniform is compared with (the GPU path tracer's table).
    pub fn cdf_at(&self, i: usize) -> f32 {
        self.cdf.get(i).copied().unwrap_or(1.0)
    }

    fn pick(&self, u: f32) -> (usize, f32) {
        let i = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (i, (self.cdf[i] - lo).max(f32::MIN_POSITIVE))
    }

    /// The point of `u` ∈ [0, 1)³: u.x picks the triangle, (u.y, u.z) a uniform point on it
    /// (the square-root warp), and for two-sided triangles the side (u.x rescaled within the
    /// triangle's interval). None without emitters.
    pub fn sample(&self, u: [f32; 3]) -> Option<EmitterSample> {
        if self.is_empty() {
            return None;
        }
        let (i, p_tri) = self.pick(u[0]);
        let t = &self.triangles[i];
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let within = ((u[0] - lo) / p_tri).clamp(0.0, 1.0);
        let normal = if t.sides == 2 && within >= 0.5 { -t.normal } else { t.normal };
        let s = u[1].sqrt();
        let (b1, b2) = (1.0 - s, u[2] * s);
        let position = t.v[0] * b1 + t.v[1] * b2 + t.v[2] * (1.0 - b1 - b2);
        let pdf_area = p_tri / (t.area * t.sides as f32);
        let mut radiance = match t.texture.and_then(|(i, uv, factor)| Some((self.textures.get(i)?, uv, factor))) {
            Some((image, uv, factor)) => {
                factor * image.sample_linear(uv[0] * b1 + uv[1] * b2 + uv[2] * (1.0 - b1 - b2))
            }
            None => t.radiance,
        };
        if let Some((c, image)) = t.cutout.and_then(|c| Some((c, self.textures.get(c.texture)?))) {
            let at = c.uv[0] * b1 + c.uv[1] * b2 + c.uv[2] * (1.0 - b1 - b2);
            if c.factor * image.sample_rgba(at, true).w < c.cutoff {
                radiance = Vec3::ZERO;
            } else if t.texture.is_none() {
                // Untextured emission: the kept part emits the full factor.
                radiance = c.kept;
            }
        }
        Some(EmitterSample { position, normal, radiance, pdf_area })
    }

    /// `count` VPLs on the emitters (see the module doc): Halton points `first + 1` ….
    pub fn vpls(&self, count: u32, first: u32) -> Vec<EmitterVpl> {
        (0..count)
            .filter_map(|j| {
                let k = first + j + 1;
                let s = self.sample([halton(k, 2), halton(k, 3), halton(k, 5)])?;
                let flux = s.radiance * std::f32::consts::PI / (s.pdf_area * count as f32);
                Some(EmitterVpl { position: s.position, normal: s.normal, flux })
            })
            .collect()
    }

    /// Mean spacing of `count` samples over the emitting area: √(A / count).
    pub fn spacing(&self, count: u32) -> f32 {
        (self.area / count.max(1) as f32).sqrt()
    }
}

/// Adds a glowing UV sphere (`rings` × `segments` quads, two triangles each; the pole rows
/// degenerate to one) of emitted radiance `radiance` to `scene`: the many-emitter case of
/// issue #18 (tests and `gi-lab bench --suite scenes`). Returns its triangle count.
pub fn add_glowing_sphere(
    scene: &mut Scene,
    center: Vec3,
    radius: f32,
    rings: u32,
    segments: u32,
    radiance: Vec3,
) -> usize {
    use super::{Material, Mesh, Node, Primitive, Transform, Vertex};
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut vertices = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            vertices.push(Vertex {
                position: (n * radius).to_array(),
                normal: n.to_array(),
                uv: [j as f32 / segments as f32, i as f32 / rings as f32],
                tangent: [0.0; 4],
            });
        }
    }
    let mut indices = Vec::new();
    let row = segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (i * row + j, (i + 1) * row + j);
            // Counter-clockwise seen from outside.
            if i > 0 {
                indices.extend_from_slice(&[a, a + 1, b]);
            }
            if i + 1 < rings {
                indices.extend_from_slice(&[a + 1, b + 1, b]);
            }
        }
    }
    let triangles = indices.len() / 3;
    scene.materials.push(Material {
        name: "glow".into(),
        base_color: glam::Vec4::new(0.8, 0.8, 0.8, 1.0),
        emissive: radiance,
        ..Material::default()
    });
    let material = scene.materials.len() - 1;
    scene
        .meshes
        .push(Mesh { name: "glowing sphere".into(), primitives: vec![Primitive { vertices, indices, material }] });
    scene.nodes.push(Node {
        name: "glowing sphere".into(),
        transform: Transform { translation: center, ..Transform::default() },
        children: vec![],
        mesh: Some(scene.meshes.len() - 1),
        light: None,
        camera: None,
    });
    scene.roots.push(scene.nodes.len() - 1);
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(radiance: Vec3, sides: u32) -> Vec<EmitterTriangle> {
        let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 2.0), Vec3::new(0.0, 0.0, 2.0));
        let n = Vec3::NEG_Y;
        vec![
            EmitterTriangle { v: [a, b, c], normal: n, radiance, area: 1.0, sides, texture: None, cutout: None },
            EmitterTriangle { v: [a, c, d], normal: n, radiance, area: 1.0, sides, texture: None, cutout: None },
        ]
    }

    #[test]
    fn vpl_fluxes_add_up_to_the_emitted_power() {
        for sides in [1, 2] {
            let e = Emitters::from_triangles(quad(Vec3::new(1.0, 2.0, 0.5), sides));
            let expected = Vec3::new(1.0, 2.0, 0.5) * std::f32::consts::PI * 2.0 * sides as f32;
            assert!((e.power - expected).length() < 1e-4);
            let vpls = e.vpls(64, 0);
            assert_eq!(vpls.len(), 64);
            let sum: Vec3 = vpls.iter().map(|v| v.flux).sum();
            assert!((sum - expected).length() < 1e-3 * expected.length(), "{sum} vs {expected}");
            let down = vpls.iter().filter(|v| v.normal == Vec3::NEG_Y).count();
            assert_eq!(down, if sides == 1 { 64 } else { 32 }, "a two-sided emitter emits from both sides");
            for v in &vpls {
                assert!((0.0..=1.0).contains(&v.position.x) && (0.0..=2.0).contains(&v.position.z));
                assert!(v.position.y.abs() < 1e-6);
            }
        }
    }

    #[test]
    fn brighter_triangles_get_more_samples() {
        let mut tris = quad(Vec3::ONE, 1);
        tris[1].radiance = Vec3::splat(3.0);
        let e = Emitters::from_triangles(tris);
        let vpls = e.vpls(400, 0);
        // Triangle 0 is the half with x > z/2.
        let on_bright = vpls.iter().filter(|v| v.position.x < v.position.z * 0.5).count();
        assert!((290..=310).contains(&on_bright), "{on_bright} of 400 on the triangle with 3/4 of the power");
        // Equal flux per VPL: the importance sampling is by power.
        assert!(vpls.iter().all(|v| (v.flux - vpls[0].flux).length() < 1e-4));
    }

    #[test]
    fn textured_emitters_emit_where_their_texture_is_bright() {
        // The quad's uv is (x, z / 2); its texture is black for u < ½ and white beyond. Both
        // triangles straddle the edge: the samples must carry light only at x ≥ ½, with the
        // power of the white half.
        let rgba8: Vec<u8> = (0..32 * 32).flat_map(|i| if i % 32 < 16 { [0, 0, 0, 255] } else { [255; 4] }).collect();
        let image = TextureImage { name: "half".into(), width: 32, height: 32, rgba8: rgba8.into() };
        let factor = Vec3::new(2.0, 1.0, 0.5);
        let uv = |p: Vec3| Vec2::new(p.x, p.z * 0.5);
        let tris: Vec<EmitterTriangle> = quad(Vec3::ONE, 1)
            .into_iter()
            .map(|t| {
                let corners = t.v.map(uv);
                EmitterTriangle {
                    radiance: factor * image.triangle_mean(corners),
                    texture: Some((0, corners, factor)),
                    ..t
                }
            })
            .collect();
        let e = Emitters { textures: vec![image], ..Emitters::from_triangles(tris) };
        // The white half (x > ½ of the 1 × 2 quad, with the bilinear ramp over the middle texel).
        let expected = factor * std::f32::consts::PI * 1.0;
        assert!((e.power - expected).length() < 0.03 * expected.length(), "{} vs {expected}", e.power);
        let vpls = e.vpls(512, 0);
        let lit: Vec<&EmitterVpl> = vpls.iter().filter(|v| v.flux.max_element() > 0.0).collect();
        // (x < 1/64: the repeat wrap blends the last, white column in, as the GPU sampler does.)
        assert!(lit.iter().all(|v| v.position.x > 0.48 || v.position.x < 1.0 / 64.0), "only where it is bright");
        // Triangles are picked by their mean power and sampled uniformly: here half of each
        // triangle is black, so about half the samples carry nothing (unbiased, not efficient).
        assert!(lit.len() > 230, "{} of 512 samples lit", lit.len());
        let sum: Vec3 = vpls.iter().map(|v| v.flux).sum();
        assert!((sum - expected).length() < 0.03 * expected.length(), "{sum} vs {expected}");
        // Inside the white half the flux is the factor's colour.
        let v = lit.iter().find(|v| v.position.x > 0.7).expect("a sample well inside");
        assert!((v.flux / v.flux.x - factor / factor.x).length() < 1e-4);
    }

    /// Issue #37: an emitter with an alpha mask (clear for u < ½) emits from its kept half
    /// only, with the full factor there and half the power.
    #[test]
    fn cut_out_emitters_emit_only_where_they_are_kept() {
        let rgba8: Vec<u8> =
            (0..32 * 32).flat_map(|i| if i % 32 < 16 { [255, 255, 255, 0] } else { [255; 4] }).collect();
        let mask = TextureImage { name: "mask".into(), width: 32, height: 32, rgba8: rgba8.into() };
        let radiance = Vec3::new(2.0, 1.0, 0.5);
        let uv = |p: Vec3| Vec2::new(p.x, p.z * 0.5);
        let tris: Vec<EmitterTriangle> = quad(radiance, 1)
            .into_iter()
            .map(|t| {
                let c = Cutout { texture: 0, uv: t.v.map(uv), factor: 1.0, cutoff: 0.5, kept: radiance };
                EmitterTriangle { radiance: radiance * mask.triangle_coverage(c.uv, 1.0, 0.5), cutout: Some(c), ..t }
            })
            .collect();
        let e = Emitters { textures: vec![mask], ..Emitters::from_triangles(tris) };
        let full = radiance * std::f32::consts::PI * 2.0;
        assert!((e.power - 0.5 * full).length() < 0.03 * full.length(), "{} vs half of {full}", e.power);
        let vpls = e.vpls(512, 0);
        let lit: Vec<&EmitterVpl> = vpls.iter().filter(|v| v.flux.max_element() > 0.0).collect();
        assert!(lit.iter().all(|v| v.position.x > 0.45 || v.position.x < 1.0 / 32.0), "only where it is kept");
        let sum: Vec3 = vpls.iter().map(|v| v.flux).sum();
        assert!((sum - 0.5 * full).length() < 0.04 * full.length(), "{sum} vs {}", 0.5 * full);
    }

    #[test]
    fn no_emitters_no_samples() {
        let e = Emitters::from_triangles(quad(Vec3::ZERO, 1));
        assert!(e.is_empty() && e.vpls(8, 0).is_empty() && e.sample([0.5; 3]).is_none());
    }
}
