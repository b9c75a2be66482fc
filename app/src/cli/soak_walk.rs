//! The soak's steps: what a user can do to the renderer without a window, drawn at random
//! (valid, boundary and invalid setting values, stage switches, resizes, camera jumps,
//! scene switches, broken shader reloads, animation), each applied and checked: a refused
//! input must say why and change nothing, an accepted one must have taken effect.

use std::path::{Path, PathBuf};

use gi_render::camera::Camera;
use gi_render::scene::{self, LoadOptions, Scene};
use gi_render::settings::{FieldKind, FieldMeta, Value};
use gi_render::{GpuContext, LabSettings, Renderer};

/// A seeded SplitMix64 generator: the walk is a function of the seed alone.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9e37_79b9_7f4a_7c15)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [0, n).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
    pub fn chance(&mut self, p: f64) -> bool {
        self.f64() < p
    }
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// A scene the walk can switch to.
pub enum SceneChoice {
    /// A scene that must load: its file (None: the embedded box) and, once loaded, a copy.
    Good { name: String, path: Option<PathBuf>, unit_scale: f32, cached: Option<Box<Scene>> },
    /// A file that must be refused with an error.
    Broken { name: String, path: PathBuf },
}

/// Writes the files the walk opens into `dir`: the embedded box without its lights (a file
/// with no light: the loader must give it the default light), and broken files (truncated,
/// garbage, empty, bad JSON, a missing buffer, a missing file).
pub fn scene_files(dir: &Path) -> Result<Vec<SceneChoice>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let glb = scene::cornell::DEFAULT_SCENE_GLB;
    let write = |name: &str, bytes: &[u8]| -> Result<PathBuf, String> {
        let p = dir.join(name);
        std::fs::write(&p, bytes).map_err(|e| format!("{}: {e}", p.display()))?;
        Ok(p)
    };
    let mut out = Vec::new();
    let no_light = write("no-light.glb", &without_lights(glb)?)?;
    out.push(SceneChoice::Good { name: "no-light.glb".into(), path: Some(no_light), unit_scale: 1.0, cached: None });
    let mut garbage = Rng::new(7);
    let noise: Vec<u8> = (0..4096).map(|_| garbage.next_u64() as u8).collect();
    let broken: [(&str, Vec<u8>); 5] = [
        ("truncated.glb", glb[..glb.len() / 2].to_vec()),
        ("garbage.glb", noise),
        ("empty.gltf", Vec::new()),
        ("bad-json.gltf", br#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":7"#.to_vec()),
        (
            "missing-buffer.gltf",
            br#"{"asset":{"version":"2.0"},"buffers":[{"uri":"nowhere.bin","byteLength":36}],"bufferViews":[{"buffer":0,"byteLength":36}],"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","max":[1,1,0],"min":[0,0,0]}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]}"#.to_vec(),
        ),
    ];
    for (name, bytes) in broken {
        out.push(SceneChoice::Broken { name: name.into(), path: write(name, &bytes)? });
    }
    out.push(SceneChoice::Broken { name: "missing.glb".into(), path: dir.join("does-not-exist.glb") });
    Ok(out)
}

/// The GLB `glb` without KHR_lights_punctual (the lights and the nodes' references to them).
fn without_lights(glb: &[u8]) -> Result<Vec<u8>, String> {
    let chunk = |at: usize| -> Option<(u32, &[u8])> {
        let len = u32::from_le_bytes(glb.get(at..at + 4)?.try_into().ok()?) as usize;
        let kind = u32::from_le_bytes(glb.get(at + 4..at + 8)?.try_into().ok()?);
        Some((kind, glb.get(at + 8..at + 8 + len)?))
    };
    let (_, json) = chunk(12).ok_or("the embedded GLB has no JSON chunk")?;
    let bin = chunk(20 + json.len()).map(|(_, b)| b.to_vec()).unwrap_or_default();
    let mut doc: serde_json::Value = serde_json::from_slice(json).map_err(|e| e.to_string())?;
    if let Some(ext) = doc.get_mut("extensions").and_then(|e| e.as_object_mut()) {
        ext.remove("KHR_lights_punctual");
    }
    for key in ["extensionsUsed", "extensionsRequired"] {
        if let Some(list) = doc.get_mut(key).and_then(|e| e.as_array_mut()) {
            list.retain(|x| x != "KHR_lights_punctual");
        }
    }
    if let Some(nodes) = doc.get_mut("nodes").and_then(|n| n.as_array_mut()) {
        for n in nodes {
            if let Some(ext) = n.get_mut("extensions").and_then(|e| e.as_object_mut()) {
                ext.remove("KHR_lights_punctual");
            }
        }
    }
    let json = serde_json::to_vec(&doc).map_err(|e| e.to_string())?;
    Ok(scene::cornell::glb(json, bin))
}

/// What a step did, for the log and the failure report.
pub struct Outcome {
    pub action: String,
    /// An input that was refused, with the message the user would see.
    pub refused: Option<String>,
    /// A check the step failed (an invalid input accepted, a refusal that changed state, a
    /// valid input lost).
    pub wrong: Option<String>,
}

impl Outcome {
    fn done(action: String) -> Self {
        Self { action, refused: None, wrong: None }
    }
}

/// A value for `meta`: valid (inside the range, often at a boundary) or invalid (outside it,
/// not a number, of the wrong type, an unknown choice).
pub fn random_value(rng: &mut Rng, meta: &FieldMeta, valid: bool) -> Value {
    let (lo, hi) = (meta.min, meta.max);
    if valid {
        return match meta.kind {
            FieldKind::Bool => Value::Bool(rng.chance(0.5)),
            FieldKind::Choice(names) => Value::Choice(names[rng.below(names.len())]),
            FieldKind::F32 => Value::F32(match rng.below(5) {
                0 => lo as f32,
                1 => hi as f32,
                2 if lo > 0.0 => (lo * (hi / lo).powf(rng.f64())) as f32,
                _ => (lo + (hi - lo) * rng.f64()) as f32,
            }),
            FieldKind::U32 => Value::U32(match rng.below(5) {
                0 => lo as u32,
                1 => hi as u32,
                2 if lo >= 1.0 => (lo * (hi / lo).powf(rng.f64())).round() as u32,
                _ => (lo + (hi - lo) * rng.f64()).round() as u32,
            }),
        };
    }
    match meta.kind {
        FieldKind::Bool => rng.pick(&[Value::F32(0.5), Value::Choice("maybe"), Value::U32(2)]).clone(),
        FieldKind::Choice(_) => {
            rng.pick(&[Value::Choice("no-such-choice"), Value::F32(1.0), Value::Bool(true)]).clone()
        }
        FieldKind::F32 => {
            let span = (hi - lo).abs().max(1.0);
            rng.pick(&[
                Value::F32(f32::NAN),
                Value::F32(f32::INFINITY),
                Value::F32(f32::NEG_INFINITY),
                Value::F32((lo - span) as f32),
                Value::F32((hi + span) as f32),
                Value::Bool(true),
            ])
            .clone()
        }
        FieldKind::U32 => {
            let mut bad = vec![Value::Bool(false), Value::F32(0.5), Value::F32(-1.0)];
            if hi < u32::MAX as f64 {
                bad.push(Value::U32(hi as u32 + 1));
                bad.push(Value::U32(u32::MAX));
            }
            if lo >= 1.0 {
                bad.push(Value::U32(lo as u32 - 1));
            }
            rng.pick(&bad).clone()
        }
    }
}

/// Sets one setting to a random valid or invalid value (`choices_only`: a stage choice),
/// through the path the lab and `--set` use, and checks the renderer's answer.
pub fn set_setting(rng: &mut Rng, r: &mut Renderer, choices_only: bool) -> Outcome {
    let groups = LabSettings::groups();
    let fields: Vec<(&str, &FieldMeta)> = groups
        .iter()
        .flat_map(|(g, fs)| fs.iter().map(move |m| (*g, m)))
        .filter(|(g, _)| !choices_only || *g == "pipeline")
        .collect();
    let (group, meta) = *rng.pick(&fields);
    let path = format!("{group}.{}", meta.name);
    let valid = choices_only || rng.chance(0.7);
    let before = r.settings().clone();
    // Half the invalid inputs come as text, the way `--set` and the UI's text boxes do.
    if !valid && rng.chance(0.5) {
        let text = *rng.pick(&["", "NaN", "-1", "1e40", "tru", "0x10", "1,5", "∞", "   ", "99999999999999999999"]);
        let action = format!("--set {path}={text:?}");
        let mut s = before.clone();
        let parsed = s.apply_override(&format!("{path}={text}"));
        return match parsed {
            Err(msg) if s == before => Outcome { action, refused: Some(msg), wrong: None },
            Err(msg) => Outcome {
                action,
                refused: Some(msg.clone()),
                wrong: Some(format!("refused ({msg}) but changed the settings")),
            },
            // Some texts are valid for some fields ("-1" is not, "NaN" is not, but "1e40"
            // parses for a field whose range reaches it — none does; "0x10" never parses).
            Ok(()) => apply(r, s, action, &before),
        };
    }
    let value = random_value(rng, meta, valid);
    let action = format!("set {path} = {value}{}", if valid { "" } else { " (invalid)" });
    let mut s = before.clone();
    match s.set(&path, &value) {
        Err(msg) if valid => {
            Outcome { action, refused: Some(msg.clone()), wrong: Some(format!("a valid value was refused: {msg}")) }
        }
        Err(msg) if s != before => Outcome {
            action,
            refused: Some(msg.clone()),
            wrong: Some(format!("refused ({msg}) but changed the settings")),
        },
        Err(msg) => Outcome { action, refused: Some(msg), wrong: None },
        Ok(()) if !valid => {
            let mut o = apply(r, s, action, &before);
            if o.refused.is_none() {
                o.wrong = Some("an invalid value was accepted".into());
            }
            o
        }
        Ok(()) => apply(r, s, action, &before),
    }
}

/// Hands `s` to the renderer: accepted, it must be the renderer's; refused (a device limit,
/// an invalid combination), the renderer's settings must be `before`.
fn apply(r: &mut Renderer, s: LabSettings, action: String, before: &LabSettings) -> Outcome {
    match r.set_settings(s.clone()) {
        Ok(_) if *r.settings() == s => Outcome::done(action),
        Ok(_) => {
            Outcome { action, refused: None, wrong: Some("accepted but the renderer holds other settings".into()) }
        }
        Err(e) if r.settings() == before => Outcome { action, refused: Some(e.to_string()), wrong: None },
        Err(e) => {
            Outcome { action, refused: Some(e.to_string()), wrong: Some("refused but the settings changed".into()) }
        }
    }
}

/// Resizes: ordinary sizes, 1×1, a side at the device's maximum, and sizes that must be
/// refused (0×0, one side 0, one side past the maximum).
pub fn resize(rng: &mut Rng, r: &mut Renderer, base: (u32, u32)) -> Outcome {
    let max = r.ctx.limits.max_texture_dimension_2d;
    let small = 1 + rng.below(160) as u32;
    let sizes = [
        ((0, 0), false),
        ((0, 64), false),
        ((max + 1, 1), false),
        ((1, 1), true),
        ((max, 1), true),
        ((1, max), true),
        ((small, 1 + rng.below(160) as u32), true),
        ((small, small), true),
        (base, true),
    ];
    let ((w, h), ok) = *rng.pick(&sizes);
    let action = format!("resize to {w}×{h}");
    let before = r.size();
    let result = r.resize(w, h);
    // A size the device holds may still be refused for the stage choices in use (the
    // interleaved split rounds up to whole tiles), with its message.
    if let Err(e @ gi_render::RenderError::SplitTooLarge { .. }) = &result
        && r.size() == before
    {
        return Outcome { action, refused: Some(e.to_string()), wrong: None };
    }
    match result {
        Ok(()) if ok && r.size() == (w, h) => Outcome::done(action),
        Ok(()) if ok => Outcome { action, refused: None, wrong: Some(format!("the renderer is {:?}", r.size())) },
        Ok(()) => Outcome { action, refused: None, wrong: Some("an impossible size was accepted".into()) },
        Err(e) if !ok && r.size() == before => Outcome { action, refused: Some(e.to_string()), wrong: None },
        Err(e) => Outcome {
            action,
            refused: Some(e.to_string()),
            wrong: Some(if ok { "a valid size was refused".into() } else { "refused but the size changed".into() }),
        },
    }
}

/// Moves the camera: inside the geometry, far away, looking anywhere, or broken the way a bad
/// preset or session could break it (NaN, zero field of view, far before near).
pub fn camera_jump(rng: &mut Rng, r: &mut Renderer) -> Outcome {
    let b = r.bounds();
    let inside = b.min + (b.max - b.min) * glam::Vec3::new(rng.f64() as f32, rng.f64() as f32, rng.f64() as f32);
    let mut c = r.camera;
    let kind = rng.below(8);
    let bad = kind >= 5;
    match kind {
        0 | 1 => c.position = inside,
        2 => c.position = b.center() + glam::Vec3::splat(1e6 * b.radius().max(1.0)),
        3 => c.position = glam::Vec3::new(1e30, -1e30, 1e30),
        4 => {
            c.yfov = [1e-3, 0.3, 2.5, 3.1][rng.below(4)];
            c.znear = [1e-4, 0.01, 1.0][rng.below(3)];
            c.zfar = c.znear * [1.01, 1e3, 1e7][rng.below(3)];
        }
        5 => c.position.y = f32::NAN,
        6 => c.yfov = [0.0, -1.0, 4.0, f32::INFINITY][rng.below(4)],
        _ => (c.znear, c.zfar) = (0.5, 0.1),
    }
    c.yaw = (rng.f64() as f32 - 0.5) * 20.0;
    c.pitch = (rng.f64() as f32 - 0.5) * 3.2;
    let action = format!("camera jump {kind} to {c:?}");
    r.camera = c;
    Outcome { action, refused: None, wrong: None }.then_check_camera(bad)
}

impl Outcome {
    /// A broken camera must be reported after the next frame (the renderer keeps the last
    /// good one); a good one must be kept. Checked by the soak after rendering.
    fn then_check_camera(mut self, bad: bool) -> Self {
        if bad {
            self.refused = Some("(a camera that cannot render: checked after the frame)".into());
        }
        self
    }
}

/// Loads `choice` as the lab's File → Open does; a good scene replaces the renderer (same
/// device, settings and size), a broken one must be refused and change nothing.
pub fn switch_scene(ctx: &GpuContext, r: &mut Renderer, choice: &mut SceneChoice) -> Outcome {
    // 0: the unit read from the scene, as the window and the commands do.
    let opts = |s: f32| {
        if s == 0.0 {
            LoadOptions::default()
        } else {
            LoadOptions { unit_scale: s, detect_units: false, ..LoadOptions::default() }
        }
    };
    match choice {
        SceneChoice::Broken { name, path } => {
            let action = format!("open broken scene {name}");
            match scene::load_gltf_file(path, &opts(1.0)) {
                Err(e) => Outcome { action, refused: Some(e.to_string()), wrong: None },
                Ok(_) => Outcome { action, refused: None, wrong: Some("a broken file loaded".into()) },
            }
        }
        SceneChoice::Good { name, path, unit_scale, cached } => {
            let action = format!("open scene {name}");
            if cached.is_none() {
                let loaded = match path {
                    None => scene::cornell::default_scene().map_err(|e| e.to_string()),
                    Some(p) => scene::load_gltf_file(p, &opts(*unit_scale)).map_err(|e| e.to_string()),
                };
                match loaded {
                    Ok(s) => *cached = Some(Box::new(s)),
                    Err(e) => {
                        return Outcome {
                            action,
                            refused: Some(e.clone()),
                            wrong: Some(format!("a good scene failed: {e}")),
                        };
                    }
                }
            }
            let Some(scene) = cached.as_deref().cloned() else { return Outcome::done(action) };
            if path.as_ref().is_some_and(|p| p.ends_with("no-light.glb")) && scene.lights.is_empty() {
                return Outcome {
                    action,
                    refused: None,
                    wrong: Some("a file without lights got no default light".into()),
                };
            }
            let (w, h) = r.size();
            let clock = r.clock;
            match Renderer::new(ctx.clone(), scene, r.settings().clone(), w, h) {
                Ok(mut new) => {
                    new.clock.playing = clock.playing;
                    *r = new;
                    Outcome::done(action)
                }
                // The current settings may not fit the new scene (its lights' shadow layers):
                // the lab keeps the old scene and says why.
                Err(e) => Outcome { action, refused: Some(e.to_string()), wrong: None },
            }
        }
    }
}

/// Breaks a shader's source (the hot reload's path): the reload must fail with the compiler's
/// message and keep the old passes; the restored source must reload.
pub fn broken_shader(rng: &mut Rng, r: &mut Renderer) -> Outcome {
    let entry = *rng.pick(gi_render::shaders::ENTRY_MODULES);
    let original = match gi_render::shaders::resolve(entry) {
        Ok(s) => s,
        Err(e) => return Outcome { action: format!("break {entry}"), refused: None, wrong: Some(e.to_string()) },
    };
    let broken = match rng.below(3) {
        0 => format!("{original}\nfn broken( {{"),
        1 => original.replacen("fn ", "fnn ", 1),
        _ => "@compute @workgroup_size(1) fn main() { let x: f32 = true; }".to_string(),
    };
    let action = format!("reload {entry} with a broken source");
    if let Err(e) = gi_render::shaders::set_override(entry, &broken) {
        return Outcome { action, refused: Some(e.to_string()), wrong: None };
    }
    let reloaded = r.reload_shaders(&[entry]);
    gi_render::shaders::clear_override(entry);
    let restored = r.reload_shaders(&[entry]);
    match (reloaded, restored) {
        (Err(e), Ok(_)) => Outcome { action, refused: Some(e), wrong: None },
        // A shader no pass in use compiles is not built (the pass that owns it, rebuilt, did
        // not read it): nothing to refuse. Had a pipeline been built from the broken source
        // outside the reload's error scope, the soak's GPU error count would say so.
        (Ok(_), Ok(_)) => Outcome::done(action),
        (Ok(_), Err(again)) => {
            Outcome { action, refused: None, wrong: Some(format!("the restored source does not reload: {again}")) }
        }
        (Err(e), Err(again)) => {
            Outcome { action, refused: Some(e), wrong: Some(format!("the restored source does not reload: {again}")) }
        }
    }
}

/// Plays, pauses, steps, scrubs (to negative, huge and non-finite times) and changes speed.
pub fn animation(rng: &mut Rng, r: &mut Renderer) -> Outcome {
    let c = &mut r.clock;
    let action = match rng.below(6) {
        0 => {
            c.playing = !c.playing;
            format!("playing = {}", c.playing)
        }
        1 => {
            c.step();
            "step".into()
        }
        2 => {
            let t = *rng.pick(&[0.0, 0.5, 3.0, -2.0, 1e9, f64::NAN, f64::INFINITY]);
            let before = c.time_s();
            c.seek(t);
            if !t.is_finite() && c.time_s() != before {
                return Outcome {
                    action: format!("seek {t}"),
                    refused: None,
                    wrong: Some("a non-finite seek moved the clock".into()),
                };
            }
            format!("seek {t}")
        }
        3 => {
            let s = *rng.pick(&[0.0, 0.25, 1.0, 4.0, -1.0, f64::NAN]);
            c.set_speed(s);
            format!("speed {s}")
        }
        4 => {
            c.loop_s = *rng.pick(&[0.0, 0.1, 2.0]);
            format!("loop {} s", c.loop_s)
        }
        _ => "idle".into(),
    };
    Outcome::done(action)
}

/// The camera that frames the scene, for the walk's resets.
pub fn home_camera(r: &Renderer) -> Camera {
    let (w, h) = r.size();
    gi_render::renderer::default_camera(r.scene(), r.bounds(), w as f32 / h as f32)
}
