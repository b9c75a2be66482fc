//! Undo and redo of every edit a user makes in the window (issue #39 point 1): settings
//! (a slider drag is one step), technique and stage choices, preset open, new, revert and
//! import, lights (add, move, duplicate, remove, edit), the sky, camera bookmarks and the
//! scene. The History pane lists the steps and jumps to any.
//!
//! The history is a list of snapshots of what a user edits (not of the camera, the clock or
//! the layout, which are views, not edits) with a cursor at the current one. At the end of
//! each frame the window compares the live state with the snapshot at the cursor; when they
//! differ and the user is not in the middle of a gesture (a mouse button held, a text field
//! focused), the live state becomes a new step after the cursor, and the steps that could
//! have been redone are dropped. A drag over many frames is therefore one step, and so is a
//! typed value. Undo and redo put a snapshot back through the same calls the panels use
//! (`Lab::apply_settings`, the scene's light nodes with `reset_history_but_records`,
//! `State::open_scene`), so the renderer's temporal history restarts exactly as for the same
//! edit made by hand. A preset save is not a step: it tells the history what the file now
//! holds ([`History::saved`]), so that undo never marks a saved preset unsaved wrongly.
//!
//! Memory is bounded: at most [`MAX_STEPS`] steps are kept (the oldest go first). A step
//! holds the settings (about 2 KB), the bookmarks and, shared between the steps that did not
//! change them, the scene's nodes and lights (docs/usage.md, "Undo and history").

use std::path::PathBuf;
use std::sync::Arc;

use gi_render::LabSettings;
use gi_render::scene::sky::Sky;
use gi_render::scene::{Light, Node, Scene};

use crate::scene_lights::LightEdit;
use crate::ui::session::Bookmark;
use crate::ui::state::State;

/// The most steps the history keeps.
pub const MAX_STEPS: usize = 200;

/// The scene's lights as a user edits them: the node list (lights are nodes, and added ones
/// are appended), the light list and the sky; `key` is what a change is detected by.
pub struct LightsState {
    nodes: Vec<Node>,
    roots: Vec<usize>,
    lights: Vec<Light>,
    sky: Sky,
    key: Vec<LightEdit>,
}

impl LightsState {
    fn of(scene: &Scene) -> Self {
        Self {
            nodes: scene.nodes.clone(),
            roots: scene.roots.clone(),
            lights: scene.lights.clone(),
            sky: scene.sky.clone(),
            key: crate::scene_lights::light_edits(scene),
        }
    }

    fn matches(&self, scene: &Scene, key: &[LightEdit]) -> bool {
        self.nodes.len() == scene.nodes.len() && self.key == key && same_sky(&self.sky, &scene.sky)
    }

    fn put_back(&self, scene: &mut Scene) {
        scene.nodes = self.nodes.clone();
        scene.roots = self.roots.clone();
        scene.lights = self.lights.clone();
        scene.sky = self.sky.clone();
    }
}

/// Two skies are the same edit state: the same values and the same loaded image (compared
/// by identity: the image's pixels are never edited in place).
fn same_sky(a: &Sky, b: &Sky) -> bool {
    let image = match (&a.image, &b.image) {
        (None, None) => true,
        (Some((pa, ma)), Some((pb, mb))) => pa == pb && Arc::ptr_eq(ma, mb),
        _ => false,
    };
    a.enabled == b.enabled
        && a.color == b.color
        && a.intensity == b.intensity
        && a.rotation_deg == b.rotation_deg
        && image
}

/// What a user edits, as of one step.
#[derive(Clone)]
pub struct Snapshot {
    pub settings: LabSettings,
    /// The preset the settings came from and what its file holds (the unsaved marker).
    pub preset_path: Option<PathBuf>,
    pub baseline: LabSettings,
    pub scene: Option<PathBuf>,
    pub unit_scale: f32,
    pub bookmarks: Vec<Bookmark>,
    lights: Arc<LightsState>,
}

impl Snapshot {
    /// The window's state now, sharing `previous`'s lights when they did not change.
    fn take(st: &State, previous: Option<&Snapshot>) -> Option<Self> {
        let l = st.lab.as_ref().ok()?;
        let scene = l.renderer.scene();
        let key = crate::scene_lights::light_edits(scene);
        let lights = match previous {
            Some(p) if p.scene == l.scene_path && p.lights.matches(scene, &key) => p.lights.clone(),
            _ => Arc::new(LightsState::of(scene)),
        };
        Some(Self {
            settings: l.settings.clone(),
            preset_path: st.preset.path.clone(),
            baseline: st.preset.baseline.clone(),
            scene: l.scene_path.clone(),
            unit_scale: l.unit_scale,
            bookmarks: st.session.bookmarks.clone(),
            lights,
        })
    }

    /// Whether the window's state is this snapshot's.
    fn matches(&self, st: &State) -> bool {
        let Ok(l) = &st.lab else { return true };
        let scene = l.renderer.scene();
        self.settings == l.settings
            && self.preset_path == st.preset.path
            && self.baseline == st.preset.baseline
            && self.scene == l.scene_path
            && self.unit_scale == l.unit_scale
            && self.bookmarks == st.session.bookmarks
            && self.lights.matches(scene, &crate::scene_lights::light_edits(scene))
    }
}

/// The name of the step from `a` to `b`, as the Edit menu and the History pane show it.
pub fn describe(a: &Snapshot, b: &Snapshot) -> String {
    let file_name = |p: &Option<PathBuf>| {
        p.as_ref().and_then(|p| p.file_name()).map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
    };
    if a.scene != b.scene || a.unit_scale != b.unit_scale {
        let name = file_name(&b.scene);
        return if name.is_empty() { "open the default scene".into() } else { format!("open scene {name}") };
    }
    if a.preset_path != b.preset_path || a.baseline != b.baseline {
        return match &b.preset_path {
            None => "new preset".into(),
            Some(_) => format!("open preset {}", file_name(&b.preset_path)),
        };
    }
    if b.settings == b.baseline && a.settings != a.baseline && b.preset_path.is_some() {
        return "revert the preset".into();
    }
    if !Arc::ptr_eq(&a.lights, &b.lights) {
        return describe_lights(&a.lights, &b.lights);
    }
    if a.bookmarks != b.bookmarks {
        return describe_bookmarks(&a.bookmarks, &b.bookmarks);
    }
    let changed: Vec<(String, String, String)> = LabSettings::all_paths()
        .into_iter()
        .filter_map(|p| {
            let (x, y) = (a.settings.get(&p)?, b.settings.get(&p)?);
            (x != y).then(|| (p, x.to_string(), y.to_string()))
        })
        .collect();
    match changed.as_slice() {
        [] => "settings".into(),
        [(p, x, y)] => format!("{p} = {y} (was {x})"),
        [(p, ..), rest @ ..] => format!("{p} and {} more settings", rest.len()),
    }
}

fn light_name(e: &LightEdit) -> String {
    e.def.as_ref().map(|d| d.name.clone()).unwrap_or_else(|| format!("node {}", e.node))
}

fn describe_lights(a: &LightsState, b: &LightsState) -> String {
    let (ka, kb) = (&a.key, &b.key);
    if let Some(added) = kb.iter().find(|e| !ka.iter().any(|x| x.node == e.node)) {
        return format!("add light {}", light_name(added));
    }
    if let Some(removed) = ka.iter().find(|e| !kb.iter().any(|x| x.node == e.node)) {
        return format!("remove light {}", light_name(removed));
    }
    let differing: Vec<(&LightEdit, &LightEdit)> =
        ka.iter().filter_map(|x| kb.iter().find(|y| y.node == x.node).filter(|y| *y != x).map(|y| (x, y))).collect();
    match differing.as_slice() {
        [] if !same_sky(&a.sky, &b.sky) => "edit the sky".into(),
        [] => "lights".into(),
        [(x, y)] if x.translation != y.translation => format!("move light {}", light_name(y)),
        [(x, y)] if x.rotation != y.rotation => format!("aim light {}", light_name(y)),
        [(_, y)] => format!("edit light {}", light_name(y)),
        many => format!("edit {} lights", many.len()),
    }
}

fn describe_bookmarks(a: &[Bookmark], b: &[Bookmark]) -> String {
    if b.len() > a.len() {
        if let Some(n) = b.iter().find(|x| !a.contains(x)) {
            return format!("add bookmark {}", n.name);
        }
    } else if b.len() < a.len()
        && let Some(n) = a.iter().find(|x| !b.contains(x))
    {
        return format!("remove bookmark {}", n.name);
    }
    "edit bookmarks".into()
}

/// The steps and the cursor.
#[derive(Default)]
pub struct History {
    /// (name of the edit that led here, the state after it); the first is the start.
    steps: Vec<(String, Snapshot)>,
    cursor: usize,
    /// Steps dropped from the front to keep [`MAX_STEPS`].
    dropped: usize,
}

impl History {
    /// The steps' names, oldest first, and the index of the current one.
    pub fn steps(&self) -> (Vec<&str>, usize) {
        (self.steps.iter().map(|(n, _)| n.as_str()).collect(), self.cursor)
    }

    /// How many steps were dropped to stay within [`MAX_STEPS`].
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// The name of the edit undo would take back.
    pub fn undo_name(&self) -> Option<&str> {
        (self.cursor > 0).then(|| self.steps[self.cursor].0.as_str())
    }

    /// The name of the edit redo would make again.
    pub fn redo_name(&self) -> Option<&str> {
        self.steps.get(self.cursor + 1).map(|(n, _)| n.as_str())
    }

    /// The snapshot at the cursor (tests).
    pub fn current(&self) -> Option<&Snapshot> {
        self.steps.get(self.cursor).map(|(_, s)| s)
    }

    /// The preset that was `old` (None: a new one) was saved to `path` with `settings`. A
    /// save is not a step of its own: the steps around the current one that belong to `old`
    /// now belong to `path` (as a document keeps its new name through undo), and every step
    /// of `path` knows what the file holds, so that undo and redo show "unsaved" exactly
    /// when the live settings differ from the file.
    pub fn saved(&mut self, old: Option<&std::path::Path>, path: &std::path::Path, settings: &LabSettings) {
        if self.steps.is_empty() {
            return;
        }
        let belongs = |s: &Snapshot| s.preset_path.as_deref() == old;
        let (mut lo, mut hi) = (self.cursor, self.cursor);
        while lo > 0 && belongs(&self.steps[lo - 1].1) {
            lo -= 1;
        }
        while hi + 1 < self.steps.len() && belongs(&self.steps[hi + 1].1) {
            hi += 1;
        }
        for (_, s) in &mut self.steps[lo..=hi] {
            s.preset_path = Some(path.to_path_buf());
        }
        for (_, s) in &mut self.steps {
            if s.preset_path.as_deref() == Some(path) {
                s.baseline = settings.clone();
            }
        }
    }

    /// Forgets every step (a restarted lab starts a new history).
    pub fn clear(&mut self) {
        self.steps.clear();
        self.cursor = 0;
    }
}

impl State {
    /// End of a frame: the live state becomes a new step when it differs from the current
    /// one and `idle` (no gesture under way). The first call records the start.
    pub fn record_history(&mut self, idle: bool) {
        if self.lab.is_err() {
            return;
        }
        if self.history.steps.is_empty() {
            if let Some(s) = Snapshot::take(self, None) {
                self.history.steps.push(("start".into(), s));
                self.history.cursor = 0;
            }
            return;
        }
        let h = &self.history;
        let current = &h.steps[h.cursor].1;
        if !idle || current.matches(self) {
            return;
        }
        let Some(next) = Snapshot::take(self, Some(current)) else { return };
        let name = describe(current, &next);
        let h = &mut self.history;
        h.steps.truncate(h.cursor + 1);
        h.steps.push((name, next));
        h.cursor += 1;
        if h.steps.len() > MAX_STEPS {
            let extra = h.steps.len() - MAX_STEPS;
            h.steps.drain(..extra);
            h.cursor -= extra;
            h.dropped += extra;
        }
    }

    pub fn undo(&mut self) {
        if self.history.cursor > 0 {
            self.jump_to(self.history.cursor - 1);
        }
    }

    pub fn redo(&mut self) {
        if self.history.cursor + 1 < self.history.steps.len() {
            self.jump_to(self.history.cursor + 1);
        }
    }

    /// Puts step `k` back and moves the cursor there; the steps after it stay for redo.
    pub fn jump_to(&mut self, k: usize) {
        let Some((name, target)) = self.history.steps.get(k).cloned() else { return };
        if k == self.history.cursor {
            return;
        }
        let from = self.history.cursor;
        let Ok(l) = &self.lab else { return };
        // The scene first: the lights belong to it.
        if (l.scene_path != target.scene || l.unit_scale != target.unit_scale)
            && let Err(e) = self.open_scene(target.scene.clone(), target.unit_scale)
        {
            self.set_status(format!("cannot go back to that scene: {e}"));
            return;
        }
        let Ok(l) = &mut self.lab else { return };
        let scene = l.renderer.scene();
        if !target.lights.matches(scene, &crate::scene_lights::light_edits(scene)) {
            target.lights.put_back(l.renderer.scene_mut());
            l.renderer.reset_history_but_records();
        }
        l.settings = target.settings.clone();
        l.apply_settings();
        self.preset.path = target.preset_path.clone();
        self.preset.baseline = target.baseline.clone();
        self.session.bookmarks = target.bookmarks.clone();
        self.history.cursor = k;
        // What the renderer accepted (a refused or clamped value stays as it was): the step
        // holds the state as it is, so that the next frame does not see an edit.
        let kept = Snapshot::take(self, Some(&target)).unwrap_or(target);
        self.history.steps[k].1 = kept;
        let what = if k < from { format!("undo: {}", self.history.steps[from].0) } else { format!("redo: {name}") };
        self.set_status(what);
    }
}
