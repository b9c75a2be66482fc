//! The fuzz targets: what one input is run through, and the properties checked on the way.
//! A property that does not hold panics (with a message saying which), like a bug in the
//! code under test; the runner catches both the same way.
//!
//! - `gltf`: [`load_gltf_bytes`] from memory with the default options; a scene that loads is
//!   then evaluated (hierarchy and animations at three times), bounded and searched for
//!   emitters, as the app does before it uploads it. An error must have a message.
//! - `preset`: [`LabSettings::from_ron`] (a preset that parses and validates must survive
//!   `to_ron` and parse again to the same settings, strictly and leniently, without
//!   problems); the raw RON read through `migrate`, `validate`, `clamp_all` (after which no
//!   field is out of its range) and `to_ron`, which must parse back to the same value; and
//!   [`load_lenient`] (its result has no field out of range and round-trips too).
//! - `set`: each line of the input is one `--set` assignment ([`LabSettings::apply_override`])
//!   applied in turn: a refused assignment leaves the settings unchanged, an accepted one
//!   leaves no field out of its range. `apply_override` checks each field's range, not the
//!   combinations (`validate`'s power-of-two and stage-choice rules), which the renderer
//!   reports when it is created, so the combination errors are not asserted here.

use gi_render::LabSettings;
use gi_render::preset::load_lenient;
use gi_render::scene::emitters::Emitters;
use gi_render::scene::{LoadOptions, load_gltf_bytes};
use gi_render::settings::check_range;

use crate::rng::Rng;
use crate::seeds::Seed;

/// What a target did with an input (the corpus keeps accepted mutants: they reach deeper).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// The input was loaded or applied.
    Accepted,
    /// The input was refused with an error.
    Rejected,
}

/// The three fuzz targets of issue #19.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// The glTF/GLB loader.
    Gltf,
    /// The preset parsers (strict, raw with clamping, lenient).
    Preset,
    /// The `--set group.field=value` parser.
    Set,
}

impl Target {
    /// Every target, in the order of the CLI's help.
    pub const ALL: [Target; 3] = [Target::Gltf, Target::Preset, Target::Set];

    /// The target's name on the command line and in file names.
    pub fn name(self) -> &'static str {
        match self {
            Target::Gltf => "gltf",
            Target::Preset => "preset",
            Target::Set => "set",
        }
    }

    /// The target named `name`.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The seed corpus (`large`: include the big real scenes, glTF only).
    pub fn seeds(self, large: bool) -> Vec<Seed> {
        match self {
            Target::Gltf => crate::seeds::gltf_seeds(large),
            Target::Preset => crate::seeds::preset_seeds(),
            Target::Set => crate::seeds::set_seeds(),
        }
    }

    /// The largest input a mutation may produce.
    pub fn max_len(self) -> usize {
        match self {
            Target::Gltf => crate::gltf_mutate::MAX_LEN,
            Target::Preset => 64 << 10,
            Target::Set => 4 << 10,
        }
    }

    /// One mutation of `data` (`other`: another corpus input to splice or copy from).
    pub fn mutate(self, rng: &mut Rng, data: &mut Vec<u8>, other: Option<&[u8]>, dictionary: &[&str]) {
        match self {
            Target::Gltf => crate::gltf_mutate::mutate_gltf(rng, data, other),
            Target::Preset | Target::Set => {
                if rng.below(4) == 0 {
                    crate::mutate::mutate_bytes(rng, data, other, self.max_len());
                } else {
                    crate::mutate::mutate_text(rng, data, dictionary, other, self.max_len());
                }
            }
        }
    }

    /// Runs one input; panics when the code under test panics or a property fails.
    pub fn execute(self, input: &[u8]) -> Outcome {
        self.execute_with_message(input).0
    }

    /// [`Self::execute`], with a description of what happened (the error message, or what
    /// was loaded): the runner keeps mutants whose description it has not seen yet.
    pub fn execute_with_message(self, input: &[u8]) -> (Outcome, String) {
        match self {
            Target::Gltf => gltf(input),
            Target::Preset => preset(input),
            Target::Set => set(input),
        }
    }
}

/// The fields of `s` outside their declared range, as `group.field: message`.
pub fn range_errors(s: &LabSettings) -> Vec<String> {
    let mut errors = Vec::new();
    for (group, fields) in LabSettings::groups() {
        for m in fields {
            let path = format!("{group}.{}", m.name);
            if let Some(v) = s.get(&path)
                && let Err(e) = check_range(m, &v)
            {
                errors.push(format!("{path}: {e}"));
            }
        }
    }
    errors
}

/// The glTF target.
pub fn gltf(input: &[u8]) -> (Outcome, String) {
    match load_gltf_bytes(input, None, &LoadOptions::default()) {
        Ok(scene) => {
            let duration = scene.animation_duration();
            for t in [0.0, 0.5 * duration, duration] {
                let state = scene.evaluate(t);
                let _ = Emitters::collect(&scene, &state);
            }
            let _ = scene.bounds(0.0);
            (Outcome::Accepted, format!("{} {}", scene.animations.len(), scene.warnings.join(" ")))
        }
        Err(e) => {
            let message = e.to_string();
            assert!(!message.is_empty(), "a load error without a message");
            (Outcome::Rejected, message)
        }
    }
}

/// The preset target.
pub fn preset(input: &[u8]) -> (Outcome, String) {
    let text = String::from_utf8_lossy(input);
    let mut outcome = Outcome::Rejected;
    let strict = LabSettings::from_ron(&text, "fuzz input");
    let mut message = match &strict {
        Ok(_) => "strict ok".to_string(),
        Err(e) => e.to_string().chars().take(48).collect(),
    };
    if let Ok(s) = strict {
        outcome = Outcome::Accepted;
        let errors = s.validate();
        assert!(errors.is_empty(), "from_ron returned settings that do not validate: {errors:?}");
        let ron = s.to_ron();
        match LabSettings::from_ron(&ron, "round trip") {
            Ok(back) => assert!(back == s, "to_ron then from_ron changed a valid preset:\n{ron}"),
            Err(e) => panic!("a valid preset written by to_ron does not parse again: {e}\n{ron}"),
        }
        match load_lenient(&ron, "round trip") {
            Ok(l) => {
                assert!(l.problems.is_empty(), "load_lenient finds problems in to_ron's output: {:?}", l.problems);
                assert!(l.settings == s, "load_lenient reads to_ron's output differently:\n{ron}");
            }
            Err(e) => panic!("load_lenient cannot read to_ron's output: {e}\n{ron}"),
        }
    }
    if let Ok(raw) = ron::from_str::<LabSettings>(&text) {
        let mut s = raw.migrate();
        let _ = s.validate();
        let _ = s.clamp_all();
        let out_of_range = range_errors(&s);
        assert!(out_of_range.is_empty(), "fields out of range after clamp_all: {out_of_range:?}");
        // Version-1 fields of a newer-version file are not written (they are not settings),
        // so the written text, not the value, is the fixed point.
        let ron = s.to_ron();
        match ron::from_str::<LabSettings>(&ron) {
            Ok(back) => assert!(back.to_ron() == ron, "to_ron then parsing changed clamped settings:\n{ron}"),
            Err(e) => panic!("to_ron's output does not parse: {e}\n{ron}"),
        }
    }
    if let Ok(l) = load_lenient(&text, "fuzz input") {
        outcome = Outcome::Accepted;
        for p in &l.problems {
            message.push(' ');
            message.push_str(&p.field);
        }
        let out_of_range = range_errors(&l.settings);
        assert!(out_of_range.is_empty(), "load_lenient kept fields out of range: {out_of_range:?}");
        let ron = l.settings.to_ron();
        match load_lenient(&ron, "round trip") {
            Ok(back) => {
                assert!(back.problems.is_empty(), "problems in to_ron's output: {:?}", back.problems);
                assert!(back.settings == l.settings, "to_ron then load_lenient changed the settings:\n{ron}");
            }
            Err(e) => panic!("load_lenient cannot read to_ron's output: {e}\n{ron}"),
        }
        if l.settings.validate().is_empty() {
            assert!(LabSettings::from_ron(&ron, "round trip").is_ok(), "valid lenient settings fail from_ron:\n{ron}");
        }
    }
    (outcome, message)
}

/// The `--set` target: every line is one assignment, applied in order.
pub fn set(input: &[u8]) -> (Outcome, String) {
    let text = String::from_utf8_lossy(input);
    let mut s = LabSettings::default();
    let mut outcome = Outcome::Rejected;
    let mut message = String::new();
    for line in text.split('\n').take(256) {
        let before = s.clone();
        match s.apply_override(line) {
            Ok(()) => {
                outcome = Outcome::Accepted;
                let out_of_range = range_errors(&s);
                assert!(
                    out_of_range.is_empty(),
                    "--set '{line}' was accepted with fields out of range: {out_of_range:?}"
                );
            }
            Err(e) => {
                assert!(s == before, "--set '{line}' was refused ({e}) but changed the settings");
                assert!(!e.is_empty(), "--set '{line}' was refused without a message");
                let kind: String = e.chars().take(24).collect();
                if !message.contains(&kind) {
                    message.push_str(&kind);
                    message.push(' ');
                }
            }
        }
    }
    // What the renderer does with the result: validation must not panic.
    let _ = s.validate();
    (outcome, message)
}
