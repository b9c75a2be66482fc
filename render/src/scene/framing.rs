//! The view a scene without a glTF camera opens on, and the units it is in (issue #37
//! points 1 and 2). A person who opens a closed room stands in it; one who opens an object or
//! an open layout looks at it from a raised three-quarter view that it fills. The rule is
//! the same everywhere (window, `render`, `bench`, `reference`, `soak`, `sweep`): every path
//! asks [`crate::renderer::default_camera`], which reads the [`Framing`] the loader stored in
//! the scene, or makes one.
//!
//! **Interior or exterior.** Points on a grid inside the bounds are probed with 48 rays
//! each (a Fibonacci sphere). A point is *in a room* when at least 92 % of them hit
//! something, rays straight up and down both do, and at least 80 % of the hits are front faces
//! (a point inside a solid object, a bunny or a wall, sees back faces); more probes stand at
//! the quantiles of the geometry's vertices (where the geometry is, whatever lies far
//! outside). The scene is an interior when its centre is in a room, at least half of the grid's
//! probes are, or the storey of the chosen room holds at least half of the geometry's vertices;
//! otherwise (an
//! object, an open layout, a box open on one side) it is an exterior.
//!
//! **Interior view.** The room is the probe with the largest floor area (wall-to-wall spans
//! measured just under its ceiling) times ½ + the share of the geometry between its floor and
//! ceiling (of two storeys alike, the furnished one) times 1 + ½ × how low its floor lies in the
//! bounds (then the ground floor), moved to the middle of those spans. The camera stands at eye
//! height: 1.6 m above the floor in a room at least 2.4 m high, else 0.6 × its height. It
//! looks along the longest free horizontal direction (16 tried), stepped back towards the
//! opposite wall so that the room is in view, slightly down, with a 63° vertical field.
//!
//! **Exterior view.** Sixteen azimuths (22.5° apart, 11.25° off the axes: three-quarter
//! views of every side) at three elevations (25°, 45° and 60°) are tried; each camera is fitted to the geometry's projected
//! extent (its vertices, not its bounding sphere) and scored by the share of a 40 × 24 ray
//! image that sees a surface as the G-buffer does (back faces of single-sided materials
//! culled) up to 70 % (past that a large floor fills any view), weighted by the share of
//! those surfaces that face other geometry (a box open on one side is seen through its
//! opening, not by its outer walls), with small preferences for looking across the largest
//! horizontal extent, from the front (+z: glTF's assets face +z) and from low.

use glam::{Vec2, Vec3};

use super::{Aabb, Scene};
use crate::camera::Camera;
use crate::scene::bvh::SceneBvh;

/// What the user asked for: the rule's choice, or a side.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ViewPreference {
    #[default]
    Auto,
    Inside,
    Outside,
}

/// Which kind of view the rule chose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewKind {
    /// The scene's own glTF camera (`index` of `count`).
    SceneCamera {
        index: usize,
        count: usize,
    },
    Interior,
    Exterior,
}

/// The room the interior camera stands in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Room {
    /// Floor and ceiling heights (world y).
    pub floor: f32,
    pub ceiling: f32,
    /// The middle of the room at eye height.
    pub center: Vec3,
    /// The room's mean short and long wall-to-wall spans.
    pub size: Vec2,
    /// The box from wall to wall along x and z (through the middle) and floor to ceiling.
    pub bounds: Aabb,
}

/// A chosen view: the camera and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Framing {
    pub camera: Camera,
    pub kind: ViewKind,
    /// One sentence for the status bar: which view and why.
    pub reason: String,
    /// The room of an interior view.
    pub room: Option<Room>,
    /// Up to 4,096 world points of the geometry, to fit an exterior view to another aspect.
    pub fit_points: Vec<Vec3>,
}

impl Framing {
    /// The same view for another aspect: an exterior view is fitted again to its points.
    pub fn for_aspect(&self, aspect: f32, bounds: Aabb) -> Framing {
        let mut f = self.clone();
        if self.kind == ViewKind::Exterior && !self.fit_points.is_empty() {
            f.camera = fit_camera(&self.fit_points, self.camera.forward(), self.camera.yfov, aspect, usable(bounds));
        }
        f
    }
}

/// Fibonacci-sphere directions.
fn sphere_directions(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let phi = golden * i as f32;
            Vec3::new(r * phi.cos(), y, r * phi.sin())
        })
        .collect()
}

/// Whether `p` stands in a room (see the module doc): not on or against a surface either
/// (its nearest hit at least 2 % of the mean distance away).
fn in_room(bvh: &SceneBvh, p: Vec3, dirs: &[Vec3]) -> bool {
    let (mut hits, mut fronts) = (0usize, 0usize);
    let (mut nearest, mut sum) = (f32::INFINITY, 0.0);
    for &d in dirs {
        if let Some(h) = bvh.intersect(p, d, 0.0, f32::INFINITY) {
            hits += 1;
            nearest = nearest.min(h.t);
            sum += h.t;
            if h.front || bvh.tris[h.tri].double_sided {
                fronts += 1;
            }
        }
    }
    if hits == 0 || nearest < 0.02 * sum / hits as f32 {
        return false;
    }
    let up = bvh.intersect(p, Vec3::Y, 0.0, f32::INFINITY).is_some();
    let down = bvh.intersect(p, Vec3::NEG_Y, 0.0, f32::INFINITY).is_some();
    up && down && hits * 100 >= dirs.len() * 92 && fronts * 100 >= hits * 80
}

/// Distance from `p` (inside `b`) along `d` to where the ray leaves `b`.
fn exit(b: Aabb, p: Vec3, d: Vec3) -> f32 {
    let inv = d.recip();
    let t1 = (b.min - p) * inv;
    let t2 = (b.max - p) * inv;
    let far = t1.max(t2);
    let t = far.min_element();
    if t.is_finite() { t.max(0.0) } else { 0.0 }
}

/// Distance to the first surface along `d` (infinite when none).
fn free(bvh: &SceneBvh, p: Vec3, d: Vec3) -> f32 {
    bvh.intersect(p, d, 0.0, f32::INFINITY).map_or(f32::INFINITY, |h| h.t)
}

/// The bounds made usable: finite, within the BVH's coordinates, with a positive size.
fn usable(b: Aabb) -> Aabb {
    if !(b.min.is_finite() && b.max.is_finite()) || b.is_empty() {
        return Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
    }
    let limit = Vec3::splat(crate::scene::bvh::MAX_COORDINATE);
    let b = Aabb { min: b.min.clamp(-limit, limit), max: b.max.clamp(-limit, limit) };
    let pad = (b.extent().max_element() * 1e-3).max(1e-3);
    Aabb { min: b.min - Vec3::splat(pad), max: b.max + Vec3::splat(pad) }
}

/// The view the rule chooses for `scene` at `aspect` (the scene's first glTF camera when it
/// has one and `prefer` is `Auto`).
pub fn choose_view(scene: &Scene, aspect: f32, prefer: ViewPreference) -> Framing {
    choose_view_with(scene, aspect, prefer, None)
}

/// [`choose_view`] over a BVH of the scene at time 0 that the caller already has (the
/// loader builds one for the view and the default light).
pub fn choose_view_with(scene: &Scene, aspect: f32, prefer: ViewPreference, bvh: Option<&SceneBvh>) -> Framing {
    let state = scene.evaluate(0.0);
    let bounds = usable(scene.bounds(0.0));
    if prefer == ViewPreference::Auto
        && let Some(c) = state.cameras.first()
    {
        return Framing {
            camera: Camera::from_node(c.world, &c.camera, bounds),
            kind: ViewKind::SceneCamera { index: 0, count: state.cameras.len() },
            reason: format!("the scene's camera '{}'", c.camera.name),
            room: None,
            fit_points: Vec::new(),
        };
    }
    let built;
    let bvh = match bvh {
        Some(b) => b,
        None => {
            built = SceneBvh::new(scene, &state);
            &built
        }
    };
    let fit_points = sample_points(bvh);
    if bvh.tris.is_empty() {
        return Framing {
            camera: Camera::frame_bounds(bounds, aspect),
            kind: ViewKind::Exterior,
            reason: "the scene has no triangles: a view of its bounds".into(),
            room: None,
            fit_points,
        };
    }
    let dirs = sphere_directions(48);
    let (centre_in_room, mut rooms, probes) = probe_rooms(bvh, bounds, &dirs);
    let grid_rooms = rooms.len();
    rooms.extend(probe_where_the_geometry_is(bvh, &fit_points, &dirs));
    let mut interior = centre_in_room || grid_rooms * 2 >= probes;
    // A room that holds most of the geometry makes an interior too, whatever lies far
    // outside it (a lamp post above the roof, a stray object).
    let mut geometry_in_room = None;
    if !interior
        && prefer == ViewPreference::Auto
        && !fit_points.is_empty()
        && let Some(f) = interior_view(bvh, &rooms, &dirs, bounds, fit_points.clone())
        && let Some(room) = f.room
    {
        let share = storey_share(&fit_points, room.floor, room.ceiling);
        if share >= 0.5 {
            interior = true;
            geometry_in_room = Some(share);
        }
    }
    let want_inside = match prefer {
        ViewPreference::Auto => interior,
        ViewPreference::Inside => true,
        ViewPreference::Outside => false,
    };
    if want_inside && let Some(f) = interior_view(bvh, &rooms, &dirs, bounds, fit_points.clone()) {
        let why = if prefer == ViewPreference::Inside {
            "asked for a view from inside".to_string()
        } else if centre_in_room {
            "the scene encloses its centre".to_string()
        } else if let Some(share) = geometry_in_room {
            format!("{:.0} % of its geometry lies in the storey of one room", share * 100.0)
        } else {
            format!("{grid_rooms} of {probes} probes of its volume stand in rooms")
        };
        return Framing { reason: format!("inside: {why}; {}", f.reason), ..f };
    }
    let mut f = exterior_view(bvh, bounds, aspect, fit_points);
    let why = match prefer {
        ViewPreference::Outside => "asked for a view from outside".to_string(),
        ViewPreference::Inside => "asked for a view from inside, but no point of the scene stands in a room".into(),
        ViewPreference::Auto => "an object or an open scene (its centre is not enclosed)".into(),
    };
    f.reason = format!("outside: {why}; {}", f.reason);
    f
}

/// Probes a grid of points: whether the centre is in a room, the points that are, and how
/// many were probed.
fn probe_rooms(bvh: &SceneBvh, b: Aabb, dirs: &[Vec3]) -> (bool, Vec<Vec3>, usize) {
    let centre = in_room(bvh, b.center(), dirs);
    let (nx, ny, nz) = (7, 4, 7);
    let mut rooms = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                let f =
                    Vec3::new((i as f32 + 0.5) / nx as f32, (j as f32 + 0.5) / ny as f32, (k as f32 + 0.5) / nz as f32);
                let p = b.min + f * b.extent();
                if in_room(bvh, p, dirs) {
                    rooms.push(p);
                }
            }
        }
    }
    if centre {
        rooms.push(b.center());
    }
    (centre, rooms, nx * ny * nz)
}

/// The share of `points` between heights `floor` and `ceiling` (5 % of the storey's height
/// of margin).
fn storey_share(points: &[Vec3], floor: f32, ceiling: f32) -> f32 {
    if points.is_empty() || !(floor.is_finite() && ceiling.is_finite()) {
        return 0.0;
    }
    let pad = 0.05 * (ceiling - floor).abs();
    let inside = points.iter().filter(|p| p.y >= floor - pad && p.y <= ceiling + pad).count();
    inside as f32 / points.len() as f32
}

/// Probes at the quantiles of the geometry's vertices along each axis (5 × 5 × 5): where
/// the geometry is, whatever lies far outside it (a room under a tall antenna), those in a room.
fn probe_where_the_geometry_is(bvh: &SceneBvh, points: &[Vec3], dirs: &[Vec3]) -> Vec<Vec3> {
    if points.is_empty() {
        return Vec::new();
    }
    // Midway between consecutive sextiles: a quantile itself is a vertex, often on a wall.
    let quantiles = |axis: usize| {
        let mut v: Vec<f32> = points.iter().map(|p| p[axis]).collect();
        v.sort_by(f32::total_cmp);
        let q = |f: f32| v[((f * (v.len() - 1) as f32) as usize).min(v.len() - 1)];
        (0..5).map(|i| 0.5 * (q(i as f32 / 5.0) + q((i + 1) as f32 / 5.0))).collect::<Vec<f32>>()
    };
    let (xs, ys, zs) = (quantiles(0), quantiles(1), quantiles(2));
    let mut out = Vec::new();
    for &x in &xs {
        for &y in &ys {
            for &z in &zs {
                let p = Vec3::new(x, y, z);
                if in_room(bvh, p, dirs) {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// The camera inside the largest room (see the module doc), or None when no probe stands in
/// a room.
fn interior_view(bvh: &SceneBvh, rooms: &[Vec3], dirs: &[Vec3], b: Aabb, fit_points: Vec<Vec3>) -> Option<Framing> {
    // A ray through a door or a window ends where it leaves the bounds.
    let span = |p: Vec3, d: Vec3| free(bvh, p, d).min(exit(b, p, d));
    let reach = b.extent().length();
    // The room of each probe, from 16 horizontal rays just under its ceiling (above the
    // furniture and the door lintels, so that neither shortens nor lengthens the room): its
    // floor area (the mean of the four shortest of the 8 wall-to-wall spans times the mean
    // of the four longest, so that an opening that lengthens one or two spans does not make
    // a corridor the largest room) and its middle (the mean of the points the rays reach).
    // The largest wins.
    let best = rooms
        .iter()
        .map(|&p| {
            let (up, down) = (free(bvh, p, Vec3::Y), free(bvh, p, Vec3::NEG_Y));
            let q = if up.is_finite() && down.is_finite() { p + Vec3::Y * (up - 0.08 * (up + down)) } else { p };
            let ends: Vec<Vec3> = (0..16)
                .map(|i| {
                    let a = std::f32::consts::TAU * i as f32 / 16.0;
                    let d = Vec3::new(a.sin(), 0.0, -a.cos());
                    q + d * span(q, d)
                })
                .collect();
            let mut spans: Vec<f32> = (0..8).map(|i| ends[i].distance(ends[i + 8])).collect();
            spans.sort_by(f32::total_cmp);
            let (short, long) = (spans[..4].iter().sum::<f32>() / 4.0, spans[4..].iter().sum::<f32>() / 4.0);
            let mid = ends.iter().fold(Vec3::ZERO, |s, e| s + *e) / 16.0;
            let centre = Vec3::new(mid.x, p.y, mid.z);
            // The share of the geometry's points between the probe's floor and ceiling: of
            // two storeys alike, the furnished one.
            let share = storey_share(&fit_points, p.y - down, p.y + up);
            // And of two storeys alike, the lower: the one a person walks in on.
            let height = (p.y - down - b.min.y) / b.extent().y.max(1e-6);
            let ground = 1.0 + 0.5 * (1.0 - height.clamp(0.0, 1.0));
            ((short * long) * (0.5 + share) * ground, centre, Vec2::new(short, long), p)
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))?;
    let (_, mut centre, size, probe) = best;
    // The middle of the spans may be inside furniture: keep the probe's own place then.
    if !in_room(bvh, centre, dirs) {
        centre = probe;
    }
    // Floor and ceiling: the lowest floor and the highest ceiling straight below and above
    // the middle and four points around it (a table under the middle is not the floor).
    let r = 0.25 * size.x;
    let around = [Vec3::ZERO, Vec3::X * r, Vec3::NEG_X * r, Vec3::Z * r, Vec3::NEG_Z * r];
    let (mut floor, mut ceiling) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut tops = Vec::new();
    for o in around {
        let p = centre + o;
        let up = p.y + free(bvh, p, Vec3::Y);
        tops.push(up);
        if !in_room(bvh, p, dirs) && o != Vec3::ZERO {
            continue;
        }
        floor = floor.min(p.y - free(bvh, p, Vec3::NEG_Y));
        ceiling = ceiling.max(up);
    }
    if !(floor.is_finite() && ceiling.is_finite()) {
        return None;
    }
    // A room has a ceiling over most of it: four of the five points see one near the same
    // height (not the top of a table with open sky around it).
    let height = ceiling - floor;
    if tops.iter().filter(|t| t.is_finite() && (*t - ceiling).abs() <= 0.15 * height).count() < 4 {
        return None;
    }
    let eye_h = if (2.1..=8.0).contains(&height) { 1.6 } else { 0.6 * height };
    let mut eye = Vec3::new(centre.x, floor + eye_h, centre.z);
    if !in_room(bvh, eye, dirs) {
        eye = centre;
    }
    // The room's longest free horizontal direction, measured just under the ceiling (above
    // the furniture and the door lintels, so that a door does not lengthen it: looking along
    // it shows the room, not the corridor behind a door), then a step back towards the
    // opposite wall.
    let top = Vec3::new(eye.x, ceiling - 0.08 * height, eye.z);
    let (dir, length, _) = (0..16)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / 16.0;
            let d = Vec3::new(a.sin(), 0.0, -a.cos());
            let t = free(bvh, top, d);
            let s = span(top, d);
            (d, span(eye, d).min(s), if t.is_finite() { s } else { 0.5 * s })
        })
        .max_by(|a, b| a.2.total_cmp(&b.2))?;
    // Back towards the opposite wall, but not through a door behind: at most half the way
    // ahead, and only while the place stays in a room.
    let back = span(eye, -dir);
    let margin = (0.1 * height).max(0.05 * back);
    let mut step = ((back - margin) * 0.8).clamp(0.0, 0.5 * length);
    while step > 0.05 * height && !in_room(bvh, eye - dir * step, dirs) {
        step *= 0.5;
    }
    let position = eye - dir * step;
    let pitch = -8f32.to_radians();
    let forward = Vec3::new(dir.x * pitch.cos(), pitch.sin(), dir.z * pitch.cos());
    let target = position + forward * (length + step).min(reach).max(1e-3);
    let mut camera = Camera::look_at(position, target, 1.1, b);
    camera.znear = (0.01 * height).clamp(1e-3, 0.05);
    let along = |d: Vec3| span(eye, d);
    let room_box = Aabb {
        min: Vec3::new(eye.x - along(Vec3::NEG_X), floor, eye.z - along(Vec3::NEG_Z)),
        max: Vec3::new(eye.x + along(Vec3::X), ceiling, eye.z + along(Vec3::Z)),
    };
    let room = Room { floor, ceiling, center: eye, size, bounds: room_box };
    Some(Framing {
        camera,
        kind: ViewKind::Interior,
        reason: format!(
            "camera in the largest room ({:.1} × {:.1} × {:.1}) at eye height {:.2}, looking along its longest free direction ({:.1})",
            size.x,
            size.y,
            height,
            eye.y - floor,
            length + step
        ),
        room: Some(room),
        fit_points,
    })
}

/// Up to 4,096 vertices of the geometry, evenly strided.
fn sample_points(bvh: &SceneBvh) -> Vec<Vec3> {
    let n = bvh.tris.len() * 3;
    let stride = n.div_ceil(4096).max(1);
    (0..n).step_by(stride).map(|i| bvh.tris[i / 3].v[i % 3]).filter(|p| p.is_finite()).collect()
}

/// A camera looking along `forward` at the points, at the distance where they all fit the
/// view of vertical field `yfov` and `aspect` (3 % margin), its target moved to the middle of
/// their projection.
pub fn fit_camera(points: &[Vec3], forward: Vec3, yfov: f32, aspect: f32, b: Aabb) -> Camera {
    let f = forward.normalize_or(Vec3::NEG_Z);
    let r = f.cross(Vec3::Y).normalize_or(Vec3::X);
    let u = r.cross(f);
    let ty = (yfov * 0.5).tan() * 0.97;
    let tx = ty * aspect.max(1e-3);
    // The distance from `target` at which every point is in the frame.
    let distance = |target: Vec3| {
        let need = points.iter().fold(0f32, |acc, p| {
            let q = *p - target;
            let (x, y, z) = (q.dot(r), q.dot(u), q.dot(f));
            acc.max(x.abs() / tx - z).max(y.abs() / ty - z)
        });
        need.max(1e-3)
    };
    let mut target = b.center();
    for _ in 0..2 {
        let dist = distance(target);
        // Re-centre on the projection's middle (in the image plane through the target).
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for p in points {
            let q = *p - target;
            let depth = (dist + q.dot(f)).max(1e-6);
            let s = Vec2::new(q.dot(r), q.dot(u)) * (dist / depth);
            lo = lo.min(s);
            hi = hi.max(s);
        }
        if lo.is_finite() && hi.is_finite() {
            let mid = 0.5 * (lo + hi);
            target += r * mid.x + u * mid.y;
        }
    }
    // A final fit at the re-centred target.
    let dist = distance(target);
    let position = target - f * dist;
    let mut c = Camera::look_at(position, target, yfov, b);
    c.orbit_distance = dist;
    c
}

/// The exterior view (see the module doc).
fn exterior_view(bvh: &SceneBvh, b: Aabb, aspect: f32, fit_points: Vec<Vec3>) -> Framing {
    let yfov = 0.8f32;
    let ext = b.extent();
    let long_axis = if ext.x >= ext.z { Vec3::X } else { Vec3::Z };
    let mut best: Option<(f32, Camera, f32, f32, f32)> = None;
    for elevation in [25f32, 45.0, 60.0] {
        for k in 0..16 {
            let azimuth = (11.25 + 22.5 * k as f32).to_radians();
            let (se, ce) = elevation.to_radians().sin_cos();
            // The camera sits at azimuth (from +Z towards +X) and looks back at the scene.
            let from = Vec3::new(azimuth.sin() * ce, se, azimuth.cos() * ce);
            let cam = fit_camera(&fit_points, -from, yfov, aspect, b);
            let (coverage, facing) = view_score(bvh, &cam, aspect);
            let across = 1.0 - from.dot(long_axis).abs();
            // glTF: "the front of a glTF asset faces +Z" (§3.4): seen from the front.
            let front = 0.06 * from.z.max(0.0);
            // Coverage counts up to 70 %: past that a large floor fills any view, and the
            // lower, more natural elevation wins.
            let low = match elevation as u32 {
                25 => 0.02,
                45 => 0.01,
                _ => 0.0,
            };
            let score = coverage.min(0.7) * (0.75 + 0.25 * facing) + 0.05 * across + front + low;
            if best.as_ref().is_none_or(|x| score > x.0) {
                best = Some((score, cam, azimuth.to_degrees(), elevation, coverage));
            }
        }
    }
    let (_, camera, azimuth, elevation, cover) = match best {
        Some(x) => x,
        None => {
            let camera = Camera::frame_bounds(b, aspect);
            (0.0, camera, 0.0, 20.0, coverage(bvh, &camera, aspect))
        }
    };
    Framing {
        camera,
        kind: ViewKind::Exterior,
        reason: format!(
            "a three-quarter view from azimuth {azimuth:.0}° and {elevation:.0}° up, fitted to the geometry ({:.0} % of the frame)",
            cover * 100.0
        ),
        room: None,
        fit_points,
    }
}

/// The share of a 40 × 24 ray image from `cam` that meets a surface the G-buffer draws.
pub fn coverage(bvh: &SceneBvh, cam: &Camera, aspect: f32) -> f32 {
    view_score(bvh, cam, aspect).0
}

/// The share of a 40 × 24 ray image from `cam` that meets a surface the G-buffer draws, and
/// the share of those surfaces that face other geometry (a ray along their normal hits
/// something): the inside of a box open on one side, not its outer walls.
fn view_score(bvh: &SceneBvh, cam: &Camera, aspect: f32) -> (f32, f32) {
    let (w, h) = (40u32, 24u32);
    let inv = cam.view_proj(aspect).inverse();
    let (mut hit, mut facing) = (0, 0);
    let eps = 1e-4 * cam.orbit_distance.max(1e-3);
    for y in 0..h {
        for x in 0..w {
            let (o, d) = crate::scene::raycast::primary_ray(inv, x, y, w, h);
            if let Some(s) = bvh.intersect_camera(o, d, 0.0, f32::INFINITY) {
                hit += 1;
                if bvh.intersect(s.p + s.n * eps, s.n, 0.0, f32::INFINITY).is_some() {
                    facing += 1;
                }
            }
        }
    }
    (hit as f32 / (w * h) as f32, facing as f32 / hit.max(1) as f32)
}

/// The scale that turns a scene of largest extent `extent` (file units) into metres, and the
/// unit it names, when the extent says it is not in metres: beyond 3,000 units millimetres
/// (a 10 m room is 10,000), beyond 300 centimetres (a 4 m room is 400); glTF's own unit is
/// the metre, so anything smaller stays.
pub fn detect_unit_scale(extent: f32) -> Option<(f32, &'static str)> {
    if !extent.is_finite() || extent <= 0.0 {
        return None;
    }
    if extent > 3000.0 {
        Some((0.001, "millimetres"))
    } else if extent > 300.0 {
        Some((0.01, "centimetres"))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Mesh, Node, Primitive, Transform, vertex};

    /// A scene of one mesh made of these triangles (no lights, no cameras).
    fn scene_of(points: &[Vec3]) -> Scene {
        let vertices = points.iter().map(|p| vertex(*p, Vec3::Y, Vec2::ZERO)).collect::<Vec<_>>();
        let indices = (0..vertices.len() as u32).collect();
        Scene {
            meshes: vec![Mesh { name: "m".into(), primitives: vec![Primitive { vertices, indices, material: 0 }] }],
            materials: vec![crate::scene::Material::default()],
            nodes: vec![Node {
                name: "m".into(),
                transform: Transform::default(),
                children: vec![],
                mesh: Some(0),
                light: None,
                camera: None,
            }],
            roots: vec![0],
            ..Scene::default()
        }
    }

    fn usable_camera(f: &Framing) {
        assert_eq!(f.camera.problem(), None, "{:?}: {}", f.camera, f.reason);
    }

    /// Bad input (issue #37): degenerate bounds, NaN, huge coordinates and an empty scene give
    /// a usable view and say why, never a panic.
    #[test]
    fn degenerate_scenes_still_get_a_usable_view() {
        let one_point = scene_of(&[Vec3::splat(2.0); 3]);
        usable_camera(&choose_view(&one_point, 1.5, ViewPreference::Auto));
        let nan = scene_of(&[Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Z, Vec3::ZERO, Vec3::X, Vec3::Z]);
        usable_camera(&choose_view(&nan, 1.5, ViewPreference::Auto));
        let huge = scene_of(&[Vec3::ZERO, Vec3::new(1e9, 0.0, 0.0), Vec3::new(0.0, 0.0, 1e9)]);
        for p in [ViewPreference::Auto, ViewPreference::Inside, ViewPreference::Outside] {
            usable_camera(&choose_view(&huge, 1.5, p));
        }
        let empty = Scene::default();
        let f = choose_view(&empty, 1.5, ViewPreference::Auto);
        usable_camera(&f);
        assert!(f.reason.contains("no triangles"), "{}", f.reason);
        assert_eq!(detect_unit_scale(f32::NAN), None);
        assert_eq!(detect_unit_scale(1e9), Some((0.001, "millimetres")));
    }

    /// The exterior fit: every vertex projects inside the frame, and the geometry spans most
    /// of it in one direction.
    #[test]
    fn the_exterior_fit_keeps_every_point_in_the_frame() {
        let pts: Vec<Vec3> =
            (0..200).map(|i| Vec3::new((i % 20) as f32, ((i / 20) % 3) as f32, (i / 60) as f32)).collect();
        let b = {
            let mut b = Aabb::EMPTY;
            pts.iter().for_each(|p| b.grow(*p));
            b
        };
        let cam = fit_camera(&pts, Vec3::new(-0.5, -0.5, -0.7), 0.8, 1.6, b);
        let vp = cam.view_proj(1.6);
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for p in &pts {
            let c = vp.project_point3(*p);
            assert!(c.x.abs() <= 1.0 && c.y.abs() <= 1.0, "{p} projects to {c}");
            lo = lo.min(c.truncate());
            hi = hi.max(c.truncate());
        }
        let span = hi - lo;
        assert!(span.x > 1.8 || span.y > 1.8, "the geometry spans {span} of the 2 × 2 frame");
    }
}
