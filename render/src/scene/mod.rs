//! Scenes: the CPU-side description the renderer draws (meshes, materials, node
//! hierarchy, lights, cameras, animations), glTF 2.0 loading, and the embedded
//! default Cornell box.
//!
//! The scene is kept as glTF structures it: a node hierarchy with local TRS transforms that
//! animations drive, meshes of triangle primitives referenced by nodes, and lights and
//! cameras attached to nodes. [`Scene::evaluate`] turns it into world-space draw items
//! and lights for one instant of the deterministic clock.

mod animation;
pub mod bvh;
pub mod cornell;
pub mod default_light;
pub mod emitters;
pub mod framing;
pub mod framing_cases;
mod gltf_load;
pub mod raycast;
pub mod sah;
pub mod sky;
mod texture;
pub mod two_level;
pub mod upload;

pub use crate::camera::{CameraDef, Projection};
pub use crate::maths::Aabb;
pub use animation::{Animation, Channel, ChannelTarget, Interpolation};
pub use gltf_load::{LoadOptions, SceneError, load_gltf_bytes, load_gltf_file};

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};

/// One vertex as the G-buffer pass consumes it (object space).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    /// Tangent (xyz, object space) and bitangent sign (w = ±1) for normal textures: from the
    /// file's TANGENT attribute, else generated (MikkTSpace) where the material has a normal
    /// texture; all zero where none is needed (the shaders then keep the vertex normal).
    pub tangent: [f32; 4],
}

/// A triangle mesh primitive with one material.
#[derive(Clone, Debug)]
pub struct Primitive {
    pub vertices: Vec<Vertex>,
    /// Triangle list, three indices per triangle, all `< vertices.len()`.
    pub indices: Vec<u32>,
    /// Index into [`Scene::materials`].
    pub material: usize,
}

#[derive(Clone, Debug)]
pub struct Mesh {
    pub name: String,
    pub primitives: Vec<Primitive>,
}

/// An RGBA8 texture in sRGB encoding (base colour textures are sRGB in glTF).
#[derive(Clone, Debug)]
pub struct TextureImage {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// `width * height * 4` bytes, sRGB-encoded RGBA (shared: the emitters' light samples
    /// read emissive textures every frame without copying them).
    pub rgba8: std::sync::Arc<[u8]>,
}

/// Surface description in the terms of Knecht's G-buffer (002 §4.2): colour `c`,
/// diffuse intensity DI, specular intensity SI and specular power SP.
///
/// Mapping from glTF metallic/roughness (chosen here; the thesis predates PBR materials):
/// - `c` = base colour (factor × texture, linear);
/// - DI = 1 − metallic: metals have no diffuse lobe;
/// - SI = 0.04 · (1 − metallic) + luminance(base colour factor) · metallic: the normal-incidence
///   Fresnel reflectance of a dielectric (4 %) blended toward the metal's colour;
/// - SP = 2 / α² − 2 with α = roughness², the Blinn-Phong exponent whose lobe matches a
///   Beckmann distribution of roughness α (Walter et al. 2007), clamped to [1, 4096].
///
/// The BRDF that uses these values is documented once in [`crate::cpu::brdf`].
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Linear base colour factor (RGBA).
    pub base_color: Vec4,
    /// Index into [`Scene::textures`] of the base colour texture, if any.
    pub base_color_texture: Option<usize>,
    pub metallic: f32,
    pub roughness: f32,
    /// Linear emitted radiance (emissive factor × strength); the emitted radiance of a point
    /// is this × the emissive texture there.
    pub emissive: Vec3,
    /// Index into [`Scene::textures`] of the emissive texture (sRGB), read with the same UVs
    /// as the base colour texture.
    pub emissive_texture: Option<usize>,
    /// Per-object weight an artist gives to point-cloud sampling (Knecht §5.1); 1 by default.
    pub sample_weight: f32,
    /// glTF `doubleSided`: when false, back faces are culled in the camera G-buffer (a
    /// closed room seen from outside shows its inside, as in every glTF viewer).
    pub double_sided: bool,
    /// Specular intensity SI set explicitly instead of derived from metallic (test scenes
    /// such as the white furnace need a purely Lambertian surface: Some(0)).
    pub specular_override: Option<f32>,
    /// glTF `alphaMode` MASK: fragments whose base colour alpha (factor × texture) is below
    /// this cutoff are cut out in every rasterisation and for every ray (BLEND is drawn as
    /// MASK at 0.5). None: opaque.
    pub alpha_cutoff: Option<f32>,
    /// Index into [`Scene::textures`] of the tangent-space normal texture (linear RGB), and
    /// its `scale` (glTF `normalTexture.scale`: x and y of the sampled normal × scale).
    pub normal_texture: Option<usize>,
    pub normal_scale: f32,
    /// Index into [`Scene::textures`] of the metallic-roughness texture (linear; B = metallic,
    /// G = roughness, multiplied into the factors).
    pub metallic_roughness_texture: Option<usize>,
    /// Index into [`Scene::textures`] of the occlusion texture (R, linear): loaded and
    /// shown by the buffer viewer (the alpha of `gbuffer.emission`), never multiplied into
    /// computed light.
    pub occlusion_texture: Option<usize>,
}

impl Material {
    /// Diffuse intensity DI (002 §4.2).
    pub fn diffuse_intensity(&self) -> f32 {
        1.0 - self.metallic.clamp(0.0, 1.0)
    }
    /// Specular intensity SI (002 §4.2), see the type's documentation for the mapping.
    pub fn specular_intensity(&self) -> f32 {
        if let Some(si) = self.specular_override {
            return si;
        }
        let m = self.metallic.clamp(0.0, 1.0);
        let c = self.base_color;
        let lum = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
        0.04 * (1.0 - m) + lum * m
    }
    /// Specular power SP (002 §4.2), see the type's documentation for the mapping.
    pub fn specular_power(&self) -> f32 {
        specular_power(self.roughness)
    }

    /// DI, SI and SP at a point whose metallic-roughness texel is `mr` (linear; B = metallic,
    /// G = roughness, multiplied into the factors), with base colour `c` (factor × texture),
    /// by the mapping of the type's documentation — as `gbuffer.wgsl` computes them per
    /// fragment.
    pub fn intensities_at(&self, c: Vec3, mr: Option<Vec4>) -> (f32, f32, f32) {
        let (metallic, roughness) = match mr {
            Some(t) => ((self.metallic * t.z).clamp(0.0, 1.0), (self.roughness * t.y).clamp(0.0, 1.0)),
            None => (self.metallic.clamp(0.0, 1.0), self.roughness.clamp(0.0, 1.0)),
        };
        let si = match self.specular_override {
            Some(si) => si,
            None => {
                // With a metallic texture the metal's colour is the textured base colour;
                // without one the factor's (as before textures were read).
                let lum_of = if mr.is_some() { c } else { self.base_color.truncate() };
                let lum = 0.2126 * lum_of.x + 0.7152 * lum_of.y + 0.0722 * lum_of.z;
                0.04 * (1.0 - metallic) + lum * metallic
            }
        };
        (1.0 - metallic, si, specular_power(roughness))
    }
}

/// SP = 2 / α² − 2 with α = roughness², clamped to [1, 4096] (see [`Material`]).
pub fn specular_power(roughness: f32) -> f32 {
    let a = roughness.clamp(0.0, 1.0).powi(2).max(1e-3);
    (2.0 / (a * a) - 2.0).clamp(1.0, 4096.0)
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 0.0,
            roughness: 1.0,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            sample_weight: 1.0,
            double_sided: false,
            specular_override: None,
            alpha_cutoff: None,
            normal_texture: None,
            normal_scale: 1.0,
            metallic_roughness_texture: None,
            occlusion_texture: None,
        }
    }
}

/// Local transform of a node (glTF TRS).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Default for Transform {
    fn default() -> Self {
        Self { translation: Vec3::ZERO, rotation: Quat::IDENTITY, scale: Vec3::ONE }
    }
}

impl Transform {
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

#[derive(Clone, Debug)]
pub struct Node {
    pub name: String,
    pub transform: Transform,
    pub children: Vec<usize>,
    pub mesh: Option<usize>,
    pub light: Option<usize>,
    pub camera: Option<usize>,
}

/// KHR_lights_punctual light types.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Radiant intensity in W/sr (glTF: candela).
    Point,
    /// Cone angles in radians around the light's −Z axis.
    Spot { inner_cone: f32, outer_cone: f32 },
    /// Irradiance in W/m² (glTF: lux), shining along the node's −Z axis.
    Directional,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    /// Linear colour.
    pub color: Vec3,
    /// Candela for point and spot lights, lux for directional lights (glTF units).
    pub intensity: f32,
    /// Distance beyond which the light has no effect (None: infinite).
    pub range: Option<f32>,
}

/// A loaded scene. Node indices, mesh indices etc. are into the vectors here.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub name: String,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<TextureImage>,
    pub nodes: Vec<Node>,
    /// Root nodes of the active glTF scene.
    pub roots: Vec<usize>,
    pub lights: Vec<Light>,
    pub cameras: Vec<CameraDef>,
    pub animations: Vec<Animation>,
    /// Non-fatal problems found while loading (unsupported extensions, …).
    pub warnings: Vec<String>,
    /// The sky around the scene (off unless the user turns it on; see [`sky`]).
    pub sky: sky::Sky,
    /// The view the loader chose for a person opening the scene ([`framing`]); None: chosen
    /// when first asked (`renderer::default_camera`).
    pub view: Option<framing::Framing>,
    /// The unit the loader read from the scene's extent and the factor it applied to reach
    /// metres, with the sentence that says so (None: metres, or `--unit-scale` given).
    pub units: Option<(f32, String)>,
}

/// A primitive to draw with its world transform, as of one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawItem {
    pub node: usize,
    pub mesh: usize,
    pub primitive: usize,
    pub world: Mat4,
}

/// A light placed in the world, as of one instant.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldLight {
    pub light: Light,
    pub position: Vec3,
    /// Unit direction the light points to (−Z of its node).
    pub direction: Vec3,
}

/// A camera placed in the world, as of one instant.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldCamera {
    pub camera: CameraDef,
    pub world: Mat4,
}

/// The scene evaluated at one instant: world transforms of everything.
#[derive(Clone, Debug, Default)]
pub struct SceneState {
    /// World matrix of every node.
    pub node_world: Vec<Mat4>,
    pub draws: Vec<DrawItem>,
    pub lights: Vec<WorldLight>,
    pub cameras: Vec<WorldCamera>,
}

impl Primitive {
    /// Bounds of the vertices in the mesh's own space.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for v in &self.vertices {
            b.grow(Vec3::from(v.position));
        }
        b
    }
}

impl Scene {
    /// Number of triangles of all primitives referenced by nodes (instanced meshes
    /// count once per node that uses them).
    pub fn triangle_count(&self) -> usize {
        let state = self.evaluate(0.0);
        state.draws.iter().map(|d| self.meshes[d.mesh].primitives[d.primitive].indices.len() / 3).sum()
    }

    /// Whether a drawn primitive has an emissive material (`emitters::Emitters` finds its
    /// triangles).
    pub fn has_emitters(&self) -> bool {
        let drawn = |mesh: usize| self.nodes.iter().any(|n| n.mesh == Some(mesh));
        self.meshes.iter().enumerate().any(|(i, m)| {
            m.primitives
                .iter()
                .any(|p| self.materials.get(p.material).is_some_and(|mat| mat.emissive.max_element() > 0.0) && drawn(i))
        })
    }

    /// Evaluates animations at `time_s` and the hierarchy into world space.
    pub fn evaluate(&self, time_s: f32) -> SceneState {
        let mut locals: Vec<Transform> = self.nodes.iter().map(|n| n.transform).collect();
        for anim in &self.animations {
            anim.apply(time_s, &mut locals);
        }
        let mut node_world = vec![Mat4::IDENTITY; self.nodes.len()];
        let mut visited = vec![false; self.nodes.len()];
        let mut stack: Vec<(usize, Mat4)> = self.roots.iter().rev().map(|&r| (r, Mat4::IDENTITY)).collect();
        let mut order = Vec::new();
        while let Some((n, parent)) = stack.pop() {
            if n >= self.nodes.len() || visited[n] {
                continue; // the loader rejects cycles; this keeps evaluation total anyway
            }
            visited[n] = true;
            let w = parent * locals[n].matrix();
            node_world[n] = w;
            order.push(n);
            for &c in self.nodes[n].children.iter().rev() {
                stack.push((c, w));
            }
        }
        let mut state = SceneState { node_world, ..Default::default() };
        for &n in &order {
            let node = &self.nodes[n];
            let w = state.node_world[n];
            if let Some(m) = node.mesh {
                for p in 0..self.meshes[m].primitives.len() {
                    state.draws.push(DrawItem { node: n, mesh: m, primitive: p, world: w });
                }
            }
            if let Some(l) = node.light {
                let position = w.transform_point3(Vec3::ZERO);
                let direction = w.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Y);
                state.lights.push(WorldLight { light: self.lights[l].clone(), position, direction });
            }
            if let Some(c) = node.camera {
                state.cameras.push(WorldCamera { camera: self.cameras[c].clone(), world: w });
            }
        }
        state
    }

    /// World-space bounds of one draw's vertices (empty without vertices).
    pub fn draw_bounds(&self, d: &DrawItem) -> Aabb {
        let mut b = Aabb::EMPTY;
        for v in &self.meshes[d.mesh].primitives[d.primitive].vertices {
            b.grow(d.world.transform_point3(Vec3::from(v.position)));
        }
        b
    }

    /// World-space bounds of the geometry at `time_s`.
    pub fn bounds(&self, time_s: f32) -> Aabb {
        let state = self.evaluate(time_s);
        let mut b = Aabb::EMPTY;
        for d in &state.draws {
            let w = self.draw_bounds(d);
            if !w.is_empty() {
                b.grow(w.min);
                b.grow(w.max);
            }
        }
        if b.is_empty() {
            b = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        }
        b
    }

    /// Duration of the longest animation in seconds (0 without animations).
    pub fn animation_duration(&self) -> f32 {
        self.animations.iter().map(|a| a.duration()).fold(0.0, f32::max)
    }
}

/// Used by loaders and generators: a flat-shaded vertex.
pub fn vertex(p: Vec3, n: Vec3, uv: Vec2) -> Vertex {
    Vertex { position: p.into(), normal: n.into(), uv: uv.into(), tangent: [0.0; 4] }
}
