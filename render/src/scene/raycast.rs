//! CPU ray casting against the scene's world-space triangles: the reference for the
//! G-buffer (position, normal, albedo at a pixel) and for shadow tests. Brute force over a
//! flat triangle list with a bounding-box cull per draw; meant for small test scenes.

use glam::{Mat4, Vec3, Vec4};

use crate::scene::{Aabb, Scene, SceneState};

/// One world-space triangle with the data the G-buffer writes.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    pub v: [Vec3; 3],
    /// Interpolated-normal inputs (world space).
    pub n: [Vec3; 3],
    pub material: usize,
    pub draw: usize,
    /// glTF `doubleSided` of the material.
    pub double_sided: bool,
}

#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub position: Vec3,
    /// Shading normal, flipped toward the ray origin (the G-buffer shades back faces with
    /// the flipped normal).
    pub normal: Vec3,
    pub material: usize,
    pub draw: usize,
}

/// All triangles of a scene state in world space.
pub struct TriangleSoup {
    pub triangles: Vec<Triangle>,
    boxes: Vec<(Aabb, std::ops::Range<usize>)>,
}

impl TriangleSoup {
    pub fn new(scene: &Scene, state: &SceneState) -> Self {
        let mut triangles = Vec::new();
        let mut boxes = Vec::new();
        for (di, d) in state.draws.iter().enumerate() {
            let p = &scene.meshes[d.mesh].primitives[d.primitive];
            let nm: Mat4 = d.world.inverse().transpose();
            let start = triangles.len();
            let mut b = Aabb::EMPTY;
            for t in p.indices.chunks_exact(3) {
                let get = |i: u32| &p.vertices[i as usize];
                let v = [0, 1, 2].map(|k| d.world.transform_point3(Vec3::from(get(t[k]).position)));
                let n = [0, 1, 2].map(|k| (nm * Vec4::from((Vec3::from(get(t[k]).normal), 0.0))).truncate());
                v.iter().for_each(|x| b.grow(*x));
                let double_sided = scene.materials.get(p.material).is_none_or(|m| m.double_sided);
                triangles.push(Triangle { v, n, material: p.material, draw: di, double_sided });
            }
            boxes.push((b, start..triangles.len()));
        }
        Self { triangles, boxes }
    }

    /// Closest hit along `origin + t·dir` with t in (t_min, t_max), all faces (shadow rays).
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        self.intersect_culled(origin, dir, t_min, t_max, false)
    }

    /// Closest hit as the camera G-buffer sees it: back faces of single-sided materials
    /// (counter-clockwise front faces, glTF) are skipped.
    pub fn intersect_camera(&self, origin: Vec3, dir: Vec3) -> Option<Hit> {
        self.intersect_culled(origin, dir, 0.0, f32::INFINITY, true)
    }

    fn intersect_culled(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32, cull: bool) -> Option<Hit> {
        let mut best: Option<(f32, usize, f32, f32)> = None;
        let inv = dir.recip();
        for (b, range) in &self.boxes {
            let limit = best.map(|x| x.0).unwrap_or(t_max);
            if !slab(b, origin, inv, limit) {
                continue;
            }
            for i in range.clone() {
                let tri = &self.triangles[i];
                if cull && !tri.double_sided && (tri.v[1] - tri.v[0]).cross(tri.v[2] - tri.v[0]).dot(dir) > 0.0 {
                    continue;
                }
                if let Some((t, u, v)) = moller_trumbore(origin, dir, tri.v)
                    && t > t_min
                    && t < best.map(|x| x.0).unwrap_or(t_max)
                {
                    best = Some((t, i, u, v));
                }
            }
        }
        let (t, i, u, v) = best?;
        let tri = &self.triangles[i];
        let mut n = (tri.n[0] * (1.0 - u - v) + tri.n[1] * u + tri.n[2] * v).normalize_or_zero();
        if n.dot(dir) > 0.0 {
            n = -n;
        }
        Some(Hit { t, position: origin + dir * t, normal: n, material: tri.material, draw: tri.draw })
    }

    /// Whether anything blocks the segment from `a` to `b` (endpoints excluded by `eps`).
    pub fn occluded(&self, a: Vec3, b: Vec3, eps: f32) -> bool {
        let d = b - a;
        let len = d.length();
        if len <= 2.0 * eps {
            return false;
        }
        self.intersect(a, d / len, eps, len - eps).is_some()
    }
}

fn slab(b: &Aabb, o: Vec3, inv: Vec3, t_max: f32) -> bool {
    let t0 = (b.min - o) * inv;
    let t1 = (b.max - o) * inv;
    let lo = t0.min(t1).max_element().max(0.0);
    let hi = t0.max(t1).min_element().min(t_max);
    lo <= hi * (1.0 + 1e-5) + 1e-6
}

/// Ray-triangle intersection (Möller & Trumbore 1997): (t, u, v) with barycentrics u, v.
pub fn moller_trumbore(o: Vec3, d: Vec3, v: [Vec3; 3]) -> Option<(f32, f32, f32)> {
    moller_trumbore_within(o, d, v, 0.0)
}

/// [`moller_trumbore`] with the triangle reaching `slack` of its size past its edges (the
/// barycentric bounds widened; the GPU ray caster's test, `two_level::triangle_hit`).
pub fn moller_trumbore_within(o: Vec3, d: Vec3, v: [Vec3; 3], slack: f32) -> Option<(f32, f32, f32)> {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - v[0];
    let u = s.dot(p) * inv;
    if !(-slack..=1.0 + slack).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let w = d.dot(q) * inv;
    if w < -slack || u + w > 1.0 + slack {
        return None;
    }
    Some((e2.dot(q) * inv, u, w))
}

/// The primary ray through the centre of pixel (x, y) of a `width`×`height` image, from a
/// view-projection matrix (WebGPU depth [0, 1]).
pub fn primary_ray(inv_view_proj: Mat4, x: u32, y: u32, width: u32, height: u32) -> (Vec3, Vec3) {
    let ndc_x = (x as f32 + 0.5) / width as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) / height as f32 * 2.0;
    let near = inv_view_proj.project_point3(Vec3::new(ndc_x, ndc_y, 0.0));
    let far = inv_view_proj.project_point3(Vec3::new(ndc_x, ndc_y, 1.0));
    (near, (far - near).normalize())
}
