//! Path-traced ground truth on the CPU (issue #3, part 1).
//!
//! The same camera, punctual lights, materials and BRDF (`cpu::brdf`) as the renderer, over
//! the scene's world-space triangles in a BVH (the `obvhs` crate's CWBVH). Paths start with
//! a ray through the pixel centre (the rasteriser has no anti-aliasing either), punctual
//! lights are reached by next-event estimation (they cannot be hit), emissive surfaces are
//! lights too (issue #18): at every vertex one point of the emitters is sampled by power
//! ([`crate::scene::emitters::Emitters::sample`], the distribution the renderer's emitter VPLs
//! come from) and its light L_e · f · cos θ_x · cos θ_y / (d² · pdf_A) added when unoccluded,
//! so a path that hits an emitter after a bounce does not add its emission again (only the
//! camera's first hit shows it); with [`PathTracer::set_emitter_lights`] off, emitters only
//! glow (their emission at the first hit, no light). Emission is factor × emissive texture at
//! the hit's UVs. Surfaces are read as the G-buffer reads them (issue #37): base colour factor ×
//! texture, normal textures, metallic-roughness textures, alpha cutouts. The scene's sky (`Scene::sky`, issue #18)
//! is reached the same way: one direction per vertex, ∝ cos θ for a constant sky, by the
//! image's radiance otherwise ([`crate::scene::sky::SkySampler::sample_at`], continuously: the
//! truth the lab's directions estimate),
//! L · f · cos θ / p(ω) when nothing is in the way; a camera ray that leaves the scene sees the
//! sky (as the lab's `sky.background` draws it; [`PathTracer::set_sky_background`]), later
//! escaping segments add nothing (next-event estimation took that light). Each bounce samples the BRDF: a cosine lobe
//! for c·DI/π and the normalised Blinn-Phong lobe (SP) for the specular term, mixed by
//! their weights. Every pixel and sample has its own seeded random stream, so results do
//! not depend on thread scheduling: identical seeds give identical images. Rendering is
//! progressive: [`Accumulator`] adds samples per pass.
//!
//! Output: `direct` (emission + direct light at the first hit), `indirect` (everything
//! after the first bounce, up to `bounces`), and `full` = direct + indirect.
//!
//! [`Senders::ScreenVisible`] keeps only the paths whose first bounce lands on a surface the
//! camera sees (inside the frustum, unoccluded from the eye): the ground truth of what a
//! screen-space gather such as Soler et al.'s (004 §3) can know. Against it the gather's own
//! errors (sampling, visibility) show apart from the light no screen-space method has
//! (surfaces hidden from the camera or off screen).

use glam::{Mat4, Vec2, Vec3, Vec4Swizzles};
use rayon::prelude::*;

use crate::buffers::ImageF32;
use crate::cpu::brdf;
use crate::scene::bvh::SceneBvh;
use crate::scene::emitters::Emitters;
use crate::scene::raycast::primary_ray;
use crate::scene::sky::{Sky, SkySampler};
use crate::scene::{Material, Scene, TextureImage, WorldLight};

/// Version of the estimator: bump it whenever a change alters the images (references
/// stored under `tests/data/` record the version they were made with). 2 (issue #51):
/// camera hits read textures from the mip level the G-buffer samples.
pub const PATH_TRACER_VERSION: u32 = 2;

/// Settings of a path-traced render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PtSettings {
    /// Indirect bounces: 0 = direct light only, 1 = one indirect bounce, N.
    pub bounces: u32,
    /// Samples per pixel of one pass.
    pub spp: u32,
    pub seed: u64,
    pub senders: Senders,
}

impl Default for PtSettings {
    fn default() -> Self {
        Self { bounces: 1, spp: 1, seed: 1, senders: Senders::All }
    }
}

/// Which surfaces a path's first bounce may land on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Senders {
    /// Every surface: the full ground truth.
    #[default]
    All,
    /// Only surfaces the camera sees (in its frustum and unoccluded from the eye); a path whose
    /// first bounce lands elsewhere carries no indirect light.
    ScreenVisible,
}

/// The camera a [`Senders::ScreenVisible`] render tests the first bounce against.
#[derive(Clone, Copy, Debug)]
struct Viewer {
    eye: Vec3,
    view_proj: Mat4,
}

/// The scene prepared for ray tracing at one instant.
pub struct PathTracer {
    bvh: SceneBvh,
    materials: Vec<Material>,
    /// The scene's textures (shared), each with its box-filtered mip levels (level 0 first,
    /// `TextureImage::box_mips`): camera hits read them trilinearly as the G-buffer does.
    textures: Vec<Vec<TextureImage>>,
    lights: Vec<WorldLight>,
    /// The emissive triangles, sampled by next-event estimation (empty: emitters only glow).
    emitters: Emitters,
    /// The scene's sky when it is on ([`crate::scene::sky`]), sampled by next-event
    /// estimation from its radiance distribution (continuously, not in the lab's directions).
    sky: Option<Sky>,
    /// Whether camera rays that leave the scene see the sky (`sky.background`, on by default).
    sky_background: bool,
    /// Offset for secondary rays, relative to the scene size.
    eps: f32,
}

/// A surface point with its material read there (textures included), as the G-buffer has it.
struct Hit {
    p: Vec3,
    /// The shading normal (bent by the normal texture), facing the ray's origin.
    n: Vec3,
    uv: Vec2,
    /// At a camera hit, ∂uv/∂x and ∂uv/∂y per pixel (the mip level the G-buffer reads).
    duv: Option<(Vec2, Vec2)>,
    material: usize,
    /// Base colour c and DI, SI, SP at the point (`Material::intensities_at`).
    c: Vec3,
    di: f32,
    si: f32,
    sp: f32,
}

/// A camera ray's neighbours one pixel to the right and one below (origin, direction): where
/// they meet the hit triangle's plane gives the pixel's texture-coordinate derivatives, as
/// the G-buffer's quads do (ray differentials).
struct Footprint {
    right: (Vec3, Vec3),
    below: (Vec3, Vec3),
}

impl Footprint {
    /// The camera ray of pixel (x, y) of a `width`×`height` image (`inv`: the inverse
    /// view-projection) and its footprint.
    fn pixel(inv: Mat4, x: u32, y: u32, width: u32, height: u32) -> ((Vec3, Vec3), Footprint) {
        let right = primary_ray(inv, x + 1, y, width, height);
        let below = primary_ray(inv, x, y + 1, width, height);
        (primary_ray(inv, x, y, width, height), Footprint { right, below })
    }

    /// (∂uv/∂x, ∂uv/∂y) at the hit of texture coordinates `uv` on `tri` (None: a neighbour
    /// ray parallel to its plane, or a degenerate triangle).
    fn uv_derivatives(&self, tri: &crate::scene::bvh::BvhTri, uv: Vec2) -> Option<(Vec2, Vec2)> {
        let (e1, e2) = (tri.v[1] - tri.v[0], tri.v[2] - tri.v[0]);
        let plane = e1.cross(e2);
        let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = d00 * d11 - d01 * d01;
        let at = |(o, d): (Vec3, Vec3)| {
            let den = plane.dot(d);
            if den.abs() <= 1e-30 || det.abs() <= 1e-30 {
                return None;
            }
            let w = o + d * (plane.dot(tri.v[0] - o) / den) - tri.v[0];
            let (d20, d21) = (w.dot(e1), w.dot(e2));
            let (b1, b2) = ((d11 * d20 - d01 * d21) / det, (d00 * d21 - d01 * d20) / det);
            let q = tri.uv[0] * (1.0 - b1 - b2) + tri.uv[1] * b1 + tri.uv[2] * b2;
            q.is_finite().then_some(q - uv)
        };
        Some((at(self.right)?, at(self.below)?))
    }
}

/// Small, fast, seedable generator (PCG32, O'Neill 2014).
struct Pcg(u64);

impl Pcg {
    fn new(seed: u64, stream: u64) -> Self {
        let mut p = Pcg(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ stream.wrapping_mul(0xD1B5_4A32_D192_ED03));
        p.next();
        p.next();
        p
    }
    fn next(&mut self) -> u32 {
        let old = self.0;
        self.0 = old.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        let x = (((old >> 18) ^ old) >> 27) as u32;
        x.rotate_right((old >> 59) as u32)
    }
    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next() >> 8) as f32 / (1u32 << 24) as f32
    }
}

fn onb(n: Vec3) -> (Vec3, Vec3) {
    let t = n.any_orthonormal_vector();
    (t, n.cross(t))
}

impl PathTracer {
    /// Prepares the scene as evaluated at `time_s`.
    pub fn new(scene: &Scene, time_s: f32) -> Self {
        let state = scene.evaluate(time_s);
        let bvh = SceneBvh::new(scene, &state);
        let eps = scene.bounds(time_s).radius().max(1e-3) * 1e-4;
        let materials = if scene.materials.is_empty() { vec![Material::default()] } else { scene.materials.clone() };
        let emitters = Emitters::collect(scene, &state);
        let sky = scene.sky.is_lit().then(|| scene.sky.clone());
        let textures =
            scene.textures.iter().map(|t| std::iter::once(t.clone()).chain(t.box_mips()).collect()).collect();
        Self { bvh, materials, textures, lights: state.lights, emitters, sky, sky_background: true, eps }
    }

    /// Whether emissive surfaces light the scene (`emitters.enabled`, on by default) or only
    /// glow.
    pub fn set_emitter_lights(&mut self, on: bool, scene: &Scene, time_s: f32) {
        self.emitters = if on { Emitters::collect(scene, &scene.evaluate(time_s)) } else { Emitters::default() };
    }

    /// Whether camera rays that leave the scene see the sky, as the lab's `sky.background`
    /// (it is on by default; with the sky off there is nothing to see).
    pub fn set_sky_background(&mut self, on: bool) {
        self.sky_background = on;
    }

    /// The emitters as the lab's `emitters.*` settings say (on or off, one or two sides).
    pub fn use_emitter_settings(&mut self, s: &crate::settings::emitters::EmitterSettings, scene: &Scene, time_s: f32) {
        self.emitters = if s.enabled {
            Emitters::collect_sides(scene, &scene.evaluate(time_s), s.two_sided)
        } else {
            Emitters::default()
        };
    }

    /// Texture `t` at `uv` (RGB sRGB-decoded when `srgb`): at a camera hit (`duv`, the
    /// pixel's texture-coordinate derivatives) filtered trilinearly from the mip level the
    /// G-buffer's sampler picks, elsewhere bilinearly from level 0. Issue #51: read at level 0
    /// everywhere, a patterned carpet at 128² was a different image from the G-buffer's
    /// (the hotel's FLIP of every technique halved with the G-buffer forced to level 0).
    fn read(&self, t: Option<usize>, uv: Vec2, duv: Option<(Vec2, Vec2)>, srgb: bool) -> Option<glam::Vec4> {
        let levels = self.textures.get(t?)?;
        let base = levels.first()?;
        Some(match duv {
            Some(d) => TextureImage::sample_trilinear(levels, uv, base.lod(d), srgb),
            None => base.sample_rgba(uv, srgb),
        })
    }

    /// Closest hit in (tmin, tmax), cut-outs (alphaMode MASK) passed through; the surface is
    /// read as the G-buffer reads it: base colour factor × texture (sRGB decoded), the
    /// normal bent by the normal texture in the MikkTSpace frame, DI, SI and SP from the
    /// metallic-roughness texture; the normal faces the ray.
    /// `pixel`: a camera ray's neighbours one pixel to the right and below, whose
    /// texture coordinates on the hit's plane choose the mip level (None: level 0).
    fn intersect(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32, pixel: Option<&Footprint>) -> Option<Hit> {
        let h = self.closest_hit(o, d, tmin, tmax)?;
        let m = &self.materials[h.material.min(self.materials.len() - 1)];
        let tri = &self.bvh.tris[h.tri];
        let duv = pixel.and_then(|f| f.uv_derivatives(tri, h.uv));
        let c = m.base_color.xyz() * self.read(m.base_color_texture, h.uv, duv, true).map_or(Vec3::ONE, |t| t.xyz());
        let mr = self.read(m.metallic_roughness_texture, h.uv, duv, false);
        let (di, si, sp) = m.intensities_at(c, mr);
        let mut n = h.n;
        if let Some(s) = self.read(m.normal_texture, h.uv, duv, false) {
            let (u, v) = (h.bary.x, h.bary.y);
            let w = 1.0 - u - v;
            let geo = (tri.n[0] * w + tri.n[1] * u + tri.n[2] * v).normalize_or_zero();
            let tan = tri.t[0] * w + tri.t[1] * u + tri.t[2] * v;
            let sign = if tri.t[0].w < 0.0 { -1.0 } else { 1.0 };
            if geo != Vec3::ZERO && tan.xyz().length_squared() > 1e-12 && tri.t[0].w != 0.0 {
                let tx = (tan.xyz() - geo * geo.dot(tan.xyz())).normalize_or_zero();
                let b = geo.cross(tx) * sign;
                let s = s.xyz() * 2.0 - Vec3::ONE;
                let s = Vec3::new(s.x * m.normal_scale, s.y * m.normal_scale, s.z);
                let bent = (tx * s.x + b * s.y + geo * s.z).normalize_or_zero();
                if bent != Vec3::ZERO {
                    // Turned to the side the ray comes from, as the interpolated one was.
                    n = if geo.dot(h.n) < 0.0 { -bent } else { bent };
                }
            }
        }
        Some(Hit { p: h.p, n, uv: h.uv, duv, material: h.material, c, di, si, sp })
    }

    /// Whether a hit at barycentrics `bary` of `tri` survives its material's alpha cutout
    /// (base colour alpha, factor × texture at level 0, at least the cutoff).
    pub fn alpha_passes(&self, tri: &crate::scene::bvh::BvhTri, bary: Vec2) -> bool {
        let m = &self.materials[tri.material.min(self.materials.len() - 1)];
        let Some(cutoff) = m.alpha_cutoff else { return true };
        let uv = tri.uv[0] * (1.0 - bary.x - bary.y) + tri.uv[1] * bary.x + tri.uv[2] * bary.y;
        let a = m.base_color.w * self.read(m.base_color_texture, uv, None, true).map_or(1.0, |t| t.w);
        a >= cutoff
    }

    /// The closest hit in (tmin, tmax) on every face, cutouts passed through: the walk every
    /// path vertex and shadow ray makes, and the twin of the GPU ray caster (issue #56,
    /// `shaders/rays/scene.wgsl`).
    pub fn closest_hit(&self, o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Option<crate::scene::bvh::BvhHit> {
        self.bvh.intersect_where(o, d, tmin, tmax, |tri, _, bary| self.alpha_passes(tri, bary))
    }

    /// The scene's triangles as the path tracer holds them.
    pub fn bvh(&self) -> &SceneBvh {
        &self.bvh
    }

    fn occluded(&self, a: Vec3, b: Vec3) -> bool {
        let d = b - a;
        let len = d.length();
        len > 2.0 * self.eps && self.intersect(a, d / len, self.eps, len - self.eps, None).is_some()
    }

    /// Direct light at a hit: every punctual light (exact, so no noise) and one point of the
    /// emitters (next-event estimation with the area density of [`Emitters::sample`]).
    fn direct(&self, h: &Hit, v: Vec3, rng: &mut Pcg) -> Vec3 {
        let origin = h.p + h.n * self.eps;
        let mut sum = Vec3::ZERO;
        let surface = (h.c, h.di, h.si, h.sp);
        for wl in &self.lights {
            let (radiance, target) = brdf::punctual_radiance(wl, h.p, h.n, v, surface, 1e6);
            if radiance != Vec3::ZERO && !self.occluded(origin, target) {
                sum += radiance;
            }
        }
        // Without emitters no random number is drawn: images of scenes without them are the
        // ones of version 1.
        let sample = if self.emitters.is_empty() { None } else { self.emitters.sample([rng.f(), rng.f(), rng.f()]) };
        if let Some(s) = sample {
            let w = s.position - h.p;
            let d2 = w.length_squared();
            let l = w / d2.sqrt().max(1e-12);
            let (cos_x, cos_y) = (h.n.dot(l), -s.normal.dot(l));
            if cos_x > 0.0 && cos_y > 0.0 && d2 > 0.0 && !self.occluded(origin, s.position) {
                let f = brdf::eval(h.n, l, v, h.c, h.di, h.si, h.sp);
                sum += s.radiance * f * (cos_x * cos_y / (d2 * s.pdf_area));
            }
        }
        // The sky, one direction by its radiance; a path that escapes adds nothing, so the sky
        // is counted once. Without a sky no random number is drawn.
        if let Some(sky) = &self.sky
            && let Some((l, radiance, pdf)) = SkySampler::new(sky).sample_at(h.n, [rng.f(), rng.f()])
        {
            let cos_x = h.n.dot(l);
            if cos_x > 0.0 && self.intersect(origin, l, 0.0, f32::INFINITY, None).is_none() {
                sum += radiance * brdf::eval(h.n, l, v, h.c, h.di, h.si, h.sp) * (cos_x / pdf);
            }
        }
        sum
    }

    /// Samples a direction from the BRDF mixture at a hit; returns (l, f·cos/pdf).
    fn sample_brdf(&self, h: &Hit, v: Vec3, rng: &mut Pcg) -> Option<(Vec3, Vec3)> {
        let (c, di, si, sp) = (h.c, h.di, h.si, h.sp);
        let wd = di * (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z);
        let ws = si.max(0.0);
        if wd + ws <= 0.0 {
            return None;
        }
        let pd = wd / (wd + ws);
        let (t, b) = onb(h.n);
        let (u1, u2) = (rng.f(), rng.f());
        let l = if rng.f() < pd {
            // Cosine-weighted hemisphere.
            let r = u1.sqrt();
            let phi = std::f32::consts::TAU * u2;
            (t * (r * phi.cos()) + b * (r * phi.sin()) + h.n * (1.0 - u1).max(0.0).sqrt()).normalize()
        } else {
            // Half vector from the normalised Blinn-Phong distribution, cos θh = u^(1/(SP+1)).
            let ct = u1.powf(1.0 / (sp + 1.0));
            let st = (1.0 - ct * ct).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u2;
            let hv = (t * (st * phi.cos()) + b * (st * phi.sin()) + h.n * ct).normalize();
            -v.reflect(hv) // l = 2(v·h)h − v
        };
        let ndl = h.n.dot(l);
        if ndl <= 0.0 {
            return None;
        }
        let hv = (l + v).normalize_or_zero();
        let ndh = h.n.dot(hv).max(0.0);
        let vdh = v.dot(hv).abs().max(1e-6);
        let pdf_d = ndl / std::f32::consts::PI;
        let pdf_s = (sp + 1.0) / std::f32::consts::TAU * ndh.powf(sp) / (4.0 * vdh);
        let pdf = pd * pdf_d + (1.0 - pd) * pdf_s;
        if pdf <= 0.0 {
            return None;
        }
        let f = brdf::eval(h.n, l, v, c, di, si, sp);
        Some((l, f * ndl / pdf))
    }

    /// Whether the camera sees point `p`: inside its frustum and nothing between the eye and
    /// `p` (up to a relative ε, which leaves `p`'s own surface out).
    fn seen(&self, viewer: &Viewer, p: Vec3) -> bool {
        let clip = viewer.view_proj * p.extend(1.0);
        if clip.w <= 0.0 || clip.x.abs() > clip.w || clip.y.abs() > clip.w {
            return false;
        }
        let d = p - viewer.eye;
        let len = d.length();
        len <= 2.0 * self.eps || self.intersect(viewer.eye, d / len, 0.0, len - 2.0 * self.eps, None).is_none()
    }

    /// One path through pixel (x, y): (direct, indirect). With a `viewer`, the first bounce
    /// counts only where the camera sees its hit ([`Senders::ScreenVisible`]).
    fn trace(
        &self,
        origin: Vec3,
        dir: Vec3,
        pixel: &Footprint,
        bounces: u32,
        viewer: Option<&Viewer>,
        rng: &mut Pcg,
    ) -> (Vec3, Vec3) {
        let Some(mut h) = self.intersect(origin, dir, 0.0, f32::INFINITY, Some(pixel)) else {
            // A camera ray that leaves the scene sees the sky (stage 7 of the lab draws it).
            let sky = self.sky.as_ref().filter(|_| self.sky_background);
            return (sky.map_or(Vec3::ZERO, |s| SkySampler::new(s).radiance(dir)), Vec3::ZERO);
        };
        let mut v = -dir;
        let emission = |h: &Hit| {
            let m = &self.materials[h.material.min(self.materials.len() - 1)];
            m.emissive * self.read(m.emissive_texture, h.uv, h.duv, true).map_or(Vec3::ONE, |t| t.xyz())
        };
        let direct = emission(&h) + self.direct(&h, v, rng);
        let mut indirect = Vec3::ZERO;
        let mut throughput = Vec3::ONE;
        for bounce in 0..bounces {
            let Some((l, weight)) = self.sample_brdf(&h, v, rng) else { break };
            throughput *= weight;
            let Some(next) = self.intersect(h.p + h.n * self.eps, l, 0.0, f32::INFINITY, None) else { break };
            if bounce == 0 && viewer.is_some_and(|c| !self.seen(c, next.p)) {
                break;
            }
            v = -l;
            // Emitters are lights: their light came by next-event estimation at `h`.
            indirect += throughput * self.direct(&next, v, rng);
            h = next;
            if throughput.max_element() <= 0.0 {
                break;
            }
        }
        (direct, indirect)
    }

    /// Renders `settings.spp` samples per pixel for a camera (view-projection and eye).
    pub fn render(&self, view_proj: Mat4, eye: Vec3, width: u32, height: u32, settings: PtSettings) -> PtImages {
        let mut acc = Accumulator::new(width, height);
        acc.add_pass(self, view_proj, eye, settings);
        acc.images()
    }

    /// The first surface along a ray (every face, as a path's camera ray meets it), read as
    /// the G-buffer reads it; for the CPU irradiance cache ([`crate::cpu::irradiance_cache`]).
    pub fn surface(&self, o: Vec3, d: Vec3) -> Option<SurfacePoint> {
        let h = self.intersect(o, d, 0.0, f32::INFINITY, None)?;
        Some(SurfacePoint { p: h.p, n: h.n, albedo: h.c * h.di })
    }

    /// The surface a camera ray of pixel (x, y) of a `width`×`height` image meets, with its
    /// material read as the path's first vertex reads it (textures at the G-buffer's mip
    /// level, issue #51); None where the ray leaves the scene.
    pub fn camera_surface(&self, view_proj: Mat4, x: u32, y: u32, width: u32, height: u32) -> Option<SurfacePoint> {
        let ((o, d), pixel) = Footprint::pixel(view_proj.inverse(), x, y, width, height);
        let h = self.intersect(o, d, 0.0, f32::INFINITY, Some(&pixel))?;
        Some(SurfacePoint { p: h.p, n: h.n, albedo: h.c * h.di })
    }

    /// The light that the first surface along a ray sends back toward the ray's origin when
    /// lit directly, as a path's vertex after the first bounce is lit (next-event estimation:
    /// every punctual light, one emitter point and one sky direction, with shadow rays; its
    /// own emission left out, emitters being lights), and the surface's distance; None when
    /// the ray leaves the scene (an escaping bounce adds nothing). `seed` and `stream` seed
    /// the emitter's and the sky's random numbers. The radiance a record's hemisphere ray
    /// gathers in the CPU irradiance cache (one bounce, as `trace`'s `bounces: 1`).
    pub fn reflected_direct(&self, o: Vec3, d: Vec3, seed: u64, stream: u64) -> Option<(f32, Vec3)> {
        let h = self.intersect(o, d, 0.0, f32::INFINITY, None)?;
        let mut rng = Pcg::new(seed, stream);
        Some(((h.p - o).length(), self.direct(&h, -d, &mut rng)))
    }

    /// The offset of secondary rays from their surface (relative to the scene's size).
    pub fn ray_offset(&self) -> f32 {
        self.eps
    }
}

/// A surface point for the CPU irradiance cache ([`PathTracer::surface`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub p: Vec3,
    /// The shading normal, facing the ray's origin.
    pub n: Vec3,
    /// The diffuse reflectance c·DI (base colour × diffuse intensity): the lab's resolve
    /// reflects irradiance E as c·DI·E/π.
    pub albedo: Vec3,
}

/// The path tracer's images (averages over all samples so far).
#[derive(Clone, Debug)]
pub struct PtImages {
    pub direct: ImageF32,
    pub indirect: ImageF32,
    pub full: ImageF32,
    pub spp: u32,
}

/// Progressive accumulation: each pass adds samples with a pass-specific seed.
pub struct Accumulator {
    width: u32,
    height: u32,
    direct: Vec<Vec3>,
    indirect: Vec<Vec3>,
    spp: u32,
}

impl Accumulator {
    pub fn new(width: u32, height: u32) -> Self {
        let n = (width * height) as usize;
        Self { width, height, direct: vec![Vec3::ZERO; n], indirect: vec![Vec3::ZERO; n], spp: 0 }
    }

    /// Adds `settings.spp` samples per pixel (multithreaded over rows; deterministic).
    pub fn add_pass(&mut self, pt: &PathTracer, view_proj: Mat4, eye: Vec3, settings: PtSettings) {
        let inv = view_proj.inverse();
        let viewer = (settings.senders == Senders::ScreenVisible).then_some(Viewer { eye, view_proj });
        let (w, h) = (self.width, self.height);
        let first = self.spp;
        let rows: Vec<Vec<(Vec3, Vec3)>> = (0..h)
            .into_par_iter()
            .map(|y| {
                (0..w)
                    .map(|x| {
                        let ((o, d), pixel) = Footprint::pixel(inv, x, y, w, h);
                        let o = if o.is_finite() { o } else { eye };
                        let mut sum = (Vec3::ZERO, Vec3::ZERO);
                        for s in 0..settings.spp {
                            let stream = ((y as u64 * w as u64 + x as u64) << 20) ^ (first + s) as u64;
                            let mut rng = Pcg::new(settings.seed, stream);
                            let (dl, il) = pt.trace(o, d, &pixel, settings.bounces, viewer.as_ref(), &mut rng);
                            sum.0 += dl;
                            sum.1 += il;
                        }
                        sum
                    })
                    .collect()
            })
            .collect();
        for (i, (dl, il)) in rows.into_iter().flatten().enumerate() {
            self.direct[i] += dl;
            self.indirect[i] += il;
        }
        self.spp += settings.spp;
    }

    pub fn images(&self) -> PtImages {
        let k = 1.0 / self.spp.max(1) as f32;
        let img = |f: &dyn Fn(usize) -> Vec3| ImageF32 {
            width: self.width,
            height: self.height,
            data: (0..self.direct.len()).map(|i| f(i).extend(1.0).to_array()).collect(),
        };
        PtImages {
            direct: img(&|i| self.direct[i] * k),
            indirect: img(&|i| self.indirect[i] * k),
            full: img(&|i| (self.direct[i] + self.indirect[i]) * k),
            spp: self.spp,
        }
    }
}
