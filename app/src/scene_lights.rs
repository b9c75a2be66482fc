//! Light editing in the lab (issue #18 point 4): add, duplicate and remove punctual lights,
//! their colour, intensity and spot cones, kept in the session and in a small "scene
//! overrides" file beside the scene (`<scene>.lights.ron`, applied by
//! `scene_args::load_scene` for the window and the CLI alike), never in the user's glTF.

use std::path::{Path, PathBuf};

use gi_render::scene::sky::Sky;
use gi_render::scene::{Light, LightKind, Node, Scene, Transform};
use glam::{Quat, Vec3};

use serde::{Deserialize, Serialize};

/// A light's edited transform and intensity (by node index of the scene), and since issue
/// #18 its whole definition (a light the lab added has a node index past the file's nodes).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LightEdit {
    pub node: usize,
    pub translation: [f32; 3],
    pub rotation: [f32; 4],
    pub intensity: f32,
    #[serde(default)]
    pub def: Option<LightDef>,
}

/// A punctual light's kind, colour and name (`gi_render::scene::Light` less the intensity).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LightDef {
    pub name: String,
    pub kind: LightKindDef,
    /// Linear colour.
    pub color: [f32; 3],
    pub range: Option<f32>,
}

/// `gi_render::scene::LightKind` (cone angles in radians).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum LightKindDef {
    Point,
    Spot { inner_cone: f32, outer_cone: f32 },
    Directional,
}

/// The kinds the Scene panel adds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NewLight {
    Point,
    Spot,
    Directional,
}

fn def_of(l: &Light) -> LightDef {
    let kind = match l.kind {
        LightKind::Point => LightKindDef::Point,
        LightKind::Spot { inner_cone, outer_cone } => LightKindDef::Spot { inner_cone, outer_cone },
        LightKind::Directional => LightKindDef::Directional,
    };
    LightDef { name: l.name.clone(), kind, color: l.color.to_array(), range: l.range }
}

fn light_of(d: &LightDef, intensity: f32) -> Light {
    let kind = match d.kind {
        LightKindDef::Point => LightKind::Point,
        LightKindDef::Spot { inner_cone, outer_cone } => {
            let outer = outer_cone.clamp(1e-3, std::f32::consts::FRAC_PI_2);
            LightKind::Spot { inner_cone: inner_cone.clamp(0.0, outer), outer_cone: outer }
        }
        LightKindDef::Directional => LightKind::Directional,
    };
    let color = Vec3::from_array(d.color).max(Vec3::ZERO);
    Light { name: d.name.clone(), kind, color, intensity: intensity.max(0.0), range: d.range }
}

/// Every light node of the scene with its transform and whole definition.
pub fn light_edits(scene: &Scene) -> Vec<LightEdit> {
    scene
        .nodes
        .iter()
        .enumerate()
        .filter_map(|(i, n)| {
            let l = scene.lights.get(n.light?)?;
            Some(LightEdit {
                node: i,
                translation: n.transform.translation.to_array(),
                rotation: n.transform.rotation.to_array(),
                intensity: l.intensity,
                def: Some(def_of(l)),
            })
        })
        .collect()
}

/// Applies `edits` to a freshly loaded scene: edits of its light nodes, lights added past
/// its nodes (in order), and, when `complete`, the removal of its lights the list does not
/// name. Entries that do not fit the scene (a node without a light, a gap) are skipped.
pub fn apply_light_edits(scene: &mut Scene, edits: &[LightEdit], complete: bool) {
    if complete {
        let listed: std::collections::HashSet<usize> = edits.iter().map(|e| e.node).collect();
        for (i, n) in scene.nodes.iter_mut().enumerate() {
            if n.light.is_some() && !listed.contains(&i) {
                n.light = None;
            }
        }
    }
    for e in edits {
        let transform = Transform {
            translation: Vec3::from_array(e.translation),
            rotation: Quat::from_array(e.rotation).normalize(),
            scale: Vec3::ONE,
        };
        if e.node < scene.nodes.len() {
            let Some(li) = scene.nodes[e.node].light else { continue };
            scene.nodes[e.node].transform.translation = transform.translation;
            scene.nodes[e.node].transform.rotation = transform.rotation;
            if let Some(l) = scene.lights.get_mut(li) {
                *l = match &e.def {
                    Some(d) => light_of(d, e.intensity),
                    None => Light { intensity: e.intensity.max(0.0), ..l.clone() },
                };
            }
        } else if e.node == scene.nodes.len()
            && let Some(d) = &e.def
        {
            push_light(scene, light_of(d, e.intensity), transform);
        }
    }
}

fn push_light(scene: &mut Scene, light: Light, transform: Transform) -> usize {
    scene.lights.push(light);
    scene.nodes.push(Node {
        name: scene.lights[scene.lights.len() - 1].name.clone(),
        transform,
        children: vec![],
        mesh: None,
        light: Some(scene.lights.len() - 1),
        camera: None,
    });
    scene.roots.push(scene.nodes.len() - 1);
    scene.nodes.len() - 1
}

/// Adds a light of `kind` where the camera at `eye` looks along `forward`: a point light a
/// third of the scene's radius ahead, a spot there looking along the view, a directional
/// light shining along it; intensities that light a white surface at the scene's scale to
/// about radiance 1. Returns its node.
pub fn add_light(scene: &mut Scene, kind: NewLight, eye: Vec3, forward: Vec3, radius: f32) -> usize {
    let forward = forward.try_normalize().unwrap_or(-Vec3::Z);
    let d = (radius / 3.0).max(1e-3);
    let n = scene.lights.len() + 1;
    let (light_kind, name, intensity) = match kind {
        NewLight::Point => (LightKind::Point, format!("point {n}"), std::f32::consts::PI * d * d),
        NewLight::Spot => {
            (LightKind::Spot { inner_cone: 0.35, outer_cone: 0.6 }, format!("spot {n}"), std::f32::consts::PI * d * d)
        }
        NewLight::Directional => (LightKind::Directional, format!("directional {n}"), std::f32::consts::PI),
    };
    let rotation = Quat::from_rotation_arc(-Vec3::Z, forward);
    let light = Light { name, kind: light_kind, color: Vec3::ONE, intensity, range: None };
    push_light(scene, light, Transform { translation: eye + forward * d, rotation, scale: Vec3::ONE })
}

/// A copy of the light at `node` (at its world place), a little beside it. Returns its node.
pub fn duplicate_light(scene: &mut Scene, node: usize, radius: f32) -> Option<usize> {
    let li = scene.nodes.get(node)?.light?;
    let world = *scene.evaluate(0.0).node_world.get(node)?;
    let (_, rotation, translation) = world.to_scale_rotation_translation();
    let mut light = scene.lights.get(li)?.clone();
    light.name = format!("{} copy", light.name);
    let offset = Vec3::X * (0.05 * radius);
    Some(push_light(scene, light, Transform { translation: translation + offset, rotation, scale: Vec3::ONE }))
}

/// Removes the light of `node` (the node stays, without its light).
pub fn remove_light(scene: &mut Scene, node: usize) {
    if let Some(n) = scene.nodes.get_mut(node) {
        n.light = None;
    }
}

/// The scene overrides file beside a scene file: `<file>.lights.ron`.
pub fn overrides_path(scene_file: &Path) -> PathBuf {
    let mut name = scene_file.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(".lights.ron");
    scene_file.with_file_name(name)
}

/// The overrides file's content.
#[derive(Debug, Serialize, Deserialize)]
pub struct LightOverrides {
    pub lights: Vec<LightEdit>,
    /// The scene's sky (issue #18 point 2); files written before it have none.
    #[serde(default)]
    pub sky: Option<SkyDef>,
}

/// `gi_render::scene::sky::Sky` as the overrides file keeps it: the image by its path
/// (relative to the scene's folder when it lies inside it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkyDef {
    pub enabled: bool,
    /// Linear colour of a constant sky.
    pub color: [f32; 3],
    /// Radiance scale, W/(m²·sr).
    pub intensity: f32,
    pub image: Option<PathBuf>,
    pub rotation_deg: f32,
}

/// The sky of `scene` as saved beside `scene_file`.
pub fn sky_def(sky: &Sky, scene_file: &Path) -> SkyDef {
    let image = sky.image.as_ref().map(|(p, _)| {
        let dir = scene_file.parent().unwrap_or(Path::new("."));
        p.strip_prefix(dir).map(Path::to_path_buf).unwrap_or_else(|_| p.clone())
    });
    SkyDef {
        enabled: sky.enabled,
        color: sky.color.to_array(),
        intensity: sky.intensity,
        image,
        rotation_deg: sky.rotation_deg,
    }
}

/// Applies a saved sky to `scene` (an image path is relative to the scene's folder). Values
/// that are not finite, or a negative colour or intensity, are refused with the reason; an
/// image that cannot be read leaves the constant colour and says why.
pub fn apply_sky(scene: &mut Scene, def: &SkyDef, scene_file: &Path) -> Result<(), String> {
    let numbers = def.color.iter().chain([&def.intensity, &def.rotation_deg]);
    if numbers.clone().any(|x| !x.is_finite()) || def.color.iter().chain([&def.intensity]).any(|&x| x < 0.0) {
        return Err(format!(
            "the sky's colour {:?} and intensity {} must be finite and non-negative, its rotation {} finite",
            def.color, def.intensity, def.rotation_deg
        ));
    }
    let mut sky = Sky {
        enabled: def.enabled,
        color: Vec3::from(def.color),
        intensity: def.intensity,
        image: None,
        rotation_deg: def.rotation_deg,
    };
    let result = match &def.image {
        Some(p) => sky.load_image(&scene_file.parent().unwrap_or(Path::new(".")).join(p)),
        None => Ok(()),
    };
    scene.sky = sky;
    result
}

/// Writes the scene's lights beside `scene_file` atomically (a temporary file renamed over
/// it: `gi_render::files::write_atomic_bytes`), without a `.bak`.
pub fn save_overrides(scene: &Scene, scene_file: &Path) -> Result<PathBuf, String> {
    let path = overrides_path(scene_file);
    let overrides = LightOverrides { lights: light_edits(scene), sky: Some(sky_def(&scene.sky, scene_file)) };
    let text = ron::ser::to_string_pretty(&overrides, Default::default()).map_err(|e| e.to_string())?;
    let text = format!(
        "// GI Lab's lights for {} (every punctual light and the sky; the glTF is not changed)\n{text}\n",
        scene_file.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default()
    );
    // No .bak: the file is the lab's own, rewritten on each edit, and lives in the user's
    // scene folder.
    gi_render::files::write_atomic_bytes(&path, text.as_bytes(), gi_render::files::Backup::Skip)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// Reads the overrides beside `scene_file`: None when there is no file, an error when it
/// does not parse (the scene then keeps its own lights).
pub fn load_overrides(scene_file: &Path) -> Option<Result<LightOverrides, String>> {
    let path = overrides_path(scene_file);
    let text = std::fs::read_to_string(&path).ok()?;
    Some(ron::from_str::<LightOverrides>(&text).map_err(|e| format!("{}: {e}", path.display())))
}
