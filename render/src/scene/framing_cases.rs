//! Small generated scenes, one per case of the framing rule (issue #37 "Tests"), written as
//! glTF 2.0 binaries so that they go through the loader like a user's file — units
//! detection included: each case is made in metres or in millimetres (positions × 1,000).
//! No lights and no cameras unless the case is about cameras: the lab's default light and
//! view are what is tested.
//!
//! The cases: a closed box room with furniture; two rooms joined by a door; a long closed
//! corridor; a closed sphere; an object with no floor; a floor plan without a ceiling; a
//! room with two cameras.

use glam::{Quat, Vec3};
use serde_json::json;

/// The framing cases, by name.
pub const CASES: [&str; 7] = ["box-room", "two-rooms", "corridor", "sphere", "object", "floor-plan", "two-cameras"];

/// A mesh under construction: triangles with flat normals and one material.
#[derive(Default)]
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    indices: Vec<u32>,
    material: usize,
}

impl Part {
    fn new(material: usize) -> Self {
        Self { material, ..Self::default() }
    }

    /// A quad `o + s·u + t·v`, facing `u × v`.
    fn quad(&mut self, o: Vec3, u: Vec3, v: Vec3) {
        let n = u.cross(v).normalize_or(Vec3::Y);
        let base = self.positions.len() as u32;
        for p in [o, o + u, o + u + v, o + v] {
            self.positions.push(p);
            self.normals.push(n);
        }
        self.indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// The six faces of the box `min..max`, facing out (`inward` false) or in.
    fn cuboid(&mut self, min: Vec3, max: Vec3, inward: bool) {
        let e = max - min;
        let (x, y, z) = (Vec3::X * e.x, Vec3::Y * e.y, Vec3::Z * e.z);
        let faces = [
            (min, z, y),     // −x: (z × y) = −x
            (min + x, y, z), // +x
            (min, x, z),     // −y: x × z = −y
            (min + y, z, x), // +y
            (min, y, x),     // −z: y × x = −z
            (min + z, x, y), // +z
        ];
        for (o, u, v) in faces {
            if inward { self.quad(o, v, u) } else { self.quad(o, u, v) }
        }
    }

    /// The wall `o + s·u + t·v` with a rectangular hole (`hole` = s0, s1, t0, t1 in [0, 1]),
    /// facing `u × v`.
    fn wall_with_hole(&mut self, o: Vec3, u: Vec3, v: Vec3, hole: [f32; 4]) {
        let [s0, s1, t0, t1] = hole;
        self.quad(o, u * s0, v);
        self.quad(o + u * s1, u * (1.0 - s1), v);
        self.quad(o + u * s0, u * (s1 - s0), v * t0);
        self.quad(o + u * s0 + v * t1, u * (s1 - s0), v * (1.0 - t1));
    }

    /// A UV sphere, facing out or in.
    fn sphere(&mut self, centre: Vec3, radius: Vec3, inward: bool, rings: u32, segments: u32) {
        let base = self.positions.len() as u32;
        for i in 0..=rings {
            let theta = std::f32::consts::PI * i as f32 / rings as f32;
            for j in 0..=segments {
                let phi = std::f32::consts::TAU * j as f32 / segments as f32;
                let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
                self.positions.push(centre + n * radius);
                self.normals.push(if inward { -n } else { n });
            }
        }
        let row = segments + 1;
        for i in 0..rings {
            for j in 0..segments {
                let (a, b) = (base + i * row + j, base + (i + 1) * row + j);
                // With this parametrisation (a, a+1, b+1) and (a, b+1, b) face outward.
                if inward {
                    self.indices.extend_from_slice(&[a, b + 1, a + 1, a, b, b + 1]);
                } else {
                    self.indices.extend_from_slice(&[a, a + 1, b + 1, a, b + 1, b]);
                }
            }
        }
    }
}

/// Materials of the cases: name, linear base colour.
const MATERIALS: [(&str, [f32; 3]); 4] = [
    ("wall", [0.75, 0.75, 0.72]),
    ("floor", [0.55, 0.45, 0.35]),
    ("furniture", [0.3, 0.45, 0.7]),
    ("object", [0.8, 0.3, 0.25]),
];
const WALL: usize = 0;
const FLOOR: usize = 1;
const FURNITURE: usize = 2;
const OBJECT: usize = 3;

/// A closed room `min..max` facing in: walls and ceiling `WALL`, floor `FLOOR`.
fn room(parts: &mut Vec<Part>, min: Vec3, max: Vec3) {
    let mut walls = Part::new(WALL);
    let mut floor = Part::new(FLOOR);
    let e = max - min;
    floor.quad(min, Vec3::Z * e.z, Vec3::X * e.x);
    walls.quad(min + Vec3::Y * e.y, Vec3::X * e.x, Vec3::Z * e.z);
    // Four walls facing in.
    walls.quad(min, Vec3::X * e.x, Vec3::Y * e.y); // z = min, faces +z
    walls.quad(min + Vec3::Z * e.z, Vec3::Y * e.y, Vec3::X * e.x); // z = max, faces −z
    walls.quad(min, Vec3::Y * e.y, Vec3::Z * e.z); // x = min, faces +x
    walls.quad(min + Vec3::X * e.x, Vec3::Z * e.z, Vec3::Y * e.y); // x = max, faces −x
    parts.push(walls);
    parts.push(floor);
}

/// Furniture: a table and a cabinet in a room `min..max`.
fn furniture(parts: &mut Vec<Part>, min: Vec3, max: Vec3) {
    let mut f = Part::new(FURNITURE);
    let e = max - min;
    let c = min + e * Vec3::new(0.5, 0.0, 0.5);
    f.cuboid(c + Vec3::new(-0.6, 0.7, -0.4), c + Vec3::new(0.6, 0.75, 0.4), false);
    f.cuboid(c + Vec3::new(-0.55, 0.0, -0.35), c + Vec3::new(-0.5, 0.7, -0.3), false);
    f.cuboid(c + Vec3::new(0.5, 0.0, 0.3), c + Vec3::new(0.55, 0.7, 0.35), false);
    f.cuboid(Vec3::new(max.x - 0.6, min.y, min.z + 0.2), Vec3::new(max.x - 0.1, min.y + 1.8, min.z + 1.2), false);
    parts.push(f);
}

/// A camera's place and orientation.
type CameraAt = (Vec3, Quat);

/// The parts and cameras of a case, in metres.
fn case_parts(name: &str) -> Option<(Vec<Part>, Vec<CameraAt>)> {
    let mut parts = Vec::new();
    let mut cameras = Vec::new();
    match name {
        "box-room" => {
            let (min, max) = (Vec3::ZERO, Vec3::new(5.0, 2.7, 4.0));
            room(&mut parts, min, max);
            furniture(&mut parts, min, max);
        }
        "two-rooms" => {
            // Room A x ∈ [0, 5], room B x ∈ [5, 8.5], joined by a door in the wall x = 5.
            let h = 2.7;
            let mut walls = Part::new(WALL);
            let mut floor = Part::new(FLOOR);
            let (x0, x1, x2, d) = (0.0, 5.0, 8.5, 4.0);
            floor.quad(Vec3::ZERO, Vec3::Z * d, Vec3::X * x2);
            walls.quad(Vec3::Y * h, Vec3::X * x2, Vec3::Z * d);
            walls.quad(Vec3::ZERO, Vec3::X * x2, Vec3::Y * h);
            walls.quad(Vec3::Z * d, Vec3::Y * h, Vec3::X * x2);
            walls.quad(Vec3::X * x0, Vec3::Y * h, Vec3::Z * d);
            walls.quad(Vec3::X * x2, Vec3::Z * d, Vec3::Y * h);
            let door = [0.4, 0.6, 0.0, 2.1 / h];
            // The shared wall, one face into each room.
            walls.wall_with_hole(Vec3::X * x1, Vec3::Z * d, Vec3::Y * h, door); // faces −x (into A)
            let mut back = Part::new(WALL);
            back.wall_with_hole(Vec3::X * x1 + Vec3::Z * d, Vec3::Z * -d, Vec3::Y * h, door); // faces +x (into B)
            parts.push(walls);
            parts.push(back);
            parts.push(floor);
            furniture(&mut parts, Vec3::ZERO, Vec3::new(x1, h, d));
        }
        "corridor" => room(&mut parts, Vec3::ZERO, Vec3::new(30.0, 2.5, 2.0)),
        "sphere" => {
            let mut s = Part::new(WALL);
            s.sphere(Vec3::new(0.0, 3.0, 0.0), Vec3::splat(3.0), true, 16, 32);
            parts.push(s);
            let mut o = Part::new(OBJECT);
            o.cuboid(Vec3::new(-0.5, 0.6, -0.5), Vec3::new(0.5, 1.6, 0.5), false);
            parts.push(o);
        }
        "object" => {
            let mut o = Part::new(OBJECT);
            o.sphere(Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.6, 0.45, 0.4), false, 12, 24);
            o.sphere(Vec3::new(0.45, 0.95, 0.0), Vec3::splat(0.25), false, 8, 16);
            parts.push(o);
        }
        "floor-plan" => {
            let mut floor = Part::new(FLOOR);
            floor.quad(Vec3::ZERO, Vec3::Z * 10.0, Vec3::X * 12.0);
            parts.push(floor);
            let mut w = Part::new(WALL);
            let t = 0.12;
            let h = 2.5;
            for (a, b) in [
                (Vec3::new(0.0, 0.0, 0.0), Vec3::new(12.0, h, t)),
                (Vec3::new(0.0, 0.0, 10.0 - t), Vec3::new(12.0, h, 10.0)),
                (Vec3::new(0.0, 0.0, 0.0), Vec3::new(t, h, 10.0)),
                (Vec3::new(12.0 - t, 0.0, 0.0), Vec3::new(12.0, h, 10.0)),
                (Vec3::new(5.0, 0.0, 0.0), Vec3::new(5.0 + t, h, 4.0)),
                (Vec3::new(5.0, 0.0, 5.0), Vec3::new(5.0 + t, h, 10.0)),
                (Vec3::new(5.0, 0.0, 6.0), Vec3::new(12.0, h, 6.0 + t)),
            ] {
                w.cuboid(a, b, false);
            }
            parts.push(w);
            furniture(&mut parts, Vec3::ZERO, Vec3::new(5.0, h, 10.0));
        }
        "two-cameras" => {
            let (min, max) = (Vec3::ZERO, Vec3::new(5.0, 2.7, 4.0));
            room(&mut parts, min, max);
            furniture(&mut parts, min, max);
            let look = |from: Vec3, to: Vec3| (from, Quat::from_rotation_arc(Vec3::NEG_Z, (to - from).normalize()));
            cameras.push(look(Vec3::new(0.5, 1.6, 3.5), Vec3::new(4.0, 1.0, 0.5)));
            cameras.push(look(Vec3::new(4.5, 1.6, 0.5), Vec3::new(1.0, 1.0, 3.5)));
        }
        _ => return None,
    }
    Some((parts, cameras))
}

/// The case `name` as a glTF binary, its coordinates × `unit` (1 for metres, 1,000 for
/// millimetres). None for an unknown name.
pub fn case_glb(name: &str, unit: f32) -> Option<Vec<u8>> {
    let (parts, cameras) = case_parts(name)?;
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for (i, part) in parts.iter().enumerate() {
        let positions: Vec<Vec3> = part.positions.iter().map(|p| *p * unit).collect();
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in &positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let mut push_view = |bytes: &[u8], target: u32| {
            let offset = bin.len();
            bin.extend_from_slice(bytes);
            while !bin.len().is_multiple_of(4) {
                bin.push(0);
            }
            views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target}));
            views.len() - 1
        };
        let pos_view = push_view(bytemuck::cast_slice(&positions), 34962);
        let nrm_view = push_view(bytemuck::cast_slice(&part.normals), 34962);
        let idx_view = push_view(bytemuck::cast_slice(&part.indices), 34963);
        let a = accessors.len();
        accessors.push(json!({"bufferView": pos_view, "componentType": 5126, "count": positions.len(), "type": "VEC3",
            "min": lo.to_array(), "max": hi.to_array()}));
        accessors
            .push(json!({"bufferView": nrm_view, "componentType": 5126, "count": part.normals.len(), "type": "VEC3"}));
        accessors.push(
            json!({"bufferView": idx_view, "componentType": 5125, "count": part.indices.len(), "type": "SCALAR"}),
        );
        meshes
            .push(json!({"name": format!("part {i}"), "primitives": [{"attributes": {"POSITION": a, "NORMAL": a + 1},
            "indices": a + 2, "material": part.material}]}));
        nodes.push(json!({"name": format!("part {i}"), "mesh": i}));
    }
    let mut camera_defs = Vec::new();
    for (i, (at, rotation)) in cameras.iter().enumerate() {
        camera_defs.push(json!({"name": format!("camera {}", i + 1), "type": "perspective",
            "perspective": {"yfov": 1.0, "znear": 0.05 * unit}}));
        nodes.push(json!({"name": format!("camera {}", i + 1), "camera": i,
            "translation": (*at * unit).to_array(), "rotation": rotation.to_array()}));
    }
    let materials: Vec<_> = MATERIALS
        .iter()
        .map(|(n, c)| {
            json!({"name": n, "pbrMetallicRoughness": {"baseColorFactor": [c[0], c[1], c[2], 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 0.9}})
        })
        .collect();
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "GI Lab framing cases"},
        "scene": 0,
        "scenes": [{"name": name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    if !camera_defs.is_empty() {
        doc["cameras"] = json!(camera_defs);
    }
    let json = serde_json::to_vec(&doc).ok()?;
    Some(super::cornell::glb(json, bin))
}
