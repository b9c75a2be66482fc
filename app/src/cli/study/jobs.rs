//! A study's canonical spec (what every shard must agree on), its job list (scenes ×
//! presets × sweep points, the scene varying slowest) and the scripts of `--emit-jobs`.

use std::path::Path;

use gi_render::LabSettings;
use gi_render::settings::Value;
use serde::{Deserialize, Serialize};

use super::StudyArgs;
use crate::cli::shard::shell_word;
use crate::cli::sweep::{Param, grid, parse_param, settings_at};
use crate::error::CliError;

/// What a study renders and measures: every argument but where it writes and which share it
/// takes. Shards and the merge check that they share one spec.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spec {
    /// Scene files (absolute); empty: the embedded default scene.
    pub scenes: Vec<String>,
    pub unit_scale: f32,
    /// Preset files (absolute); empty: the shipped technique presets.
    pub presets: Vec<String>,
    pub overrides: Vec<String>,
    pub params: Vec<String>,
    pub size: (u32, u32),
    pub frames: u32,
    pub flicker_frames: u32,
    pub bounces: u32,
    pub spp: u32,
    pub budget_ms: Option<f64>,
    pub target_flip: Option<f64>,
}

fn absolute(p: &Path, what: &str) -> Result<String, CliError> {
    std::fs::canonicalize(p)
        .map(|a| a.display().to_string())
        .map_err(|e| CliError::input(format!("--{what} {}: {e}", p.display())))
}

impl Spec {
    pub fn from_args(a: &StudyArgs) -> Result<Self, CliError> {
        if a.frames == 0 {
            return Err(CliError::input("--frames must be at least 1"));
        }
        if a.flicker_frames == 1 {
            return Err(CliError::input("--flicker-frames must be 0 or at least 2"));
        }
        if a.spp == 0 {
            return Err(CliError::input("--spp must be at least 1"));
        }
        if a.bounces > 8 {
            return Err(CliError::input("--bounces must be at most 8"));
        }
        if let Some(b) = a.budget_ms.filter(|b| !(b.is_finite() && *b > 0.0)) {
            return Err(CliError::input(format!("--budget-ms {b} must be a positive number of milliseconds")));
        }
        if let Some(t) = a.target_flip.filter(|t| !(t.is_finite() && (0.0..=1.0).contains(t))) {
            return Err(CliError::input(format!("--target-flip {t} must be a mean FLIP in 0…1")));
        }
        if !(a.unit_scale.is_finite() && a.unit_scale >= 0.0) {
            return Err(CliError::input(format!("--unit-scale {} must be 0 or a positive number", a.unit_scale)));
        }
        Ok(Self {
            // An absolute path that is missing is kept: a shard loads only the scenes of its
            // own jobs (`measure::run`; `--emit-jobs` checks them all), so that one missing scene fails only the
            // shards that render it.
            scenes: a
                .scenes
                .iter()
                .map(
                    |p| if p.is_absolute() && !p.exists() { Ok(p.display().to_string()) } else { absolute(p, "scene") },
                )
                .collect::<Result<_, _>>()?,
            unit_scale: a.unit_scale,
            presets: a.presets.iter().map(|p| absolute(p, "preset")).collect::<Result<_, _>>()?,
            overrides: a.overrides.clone(),
            params: a.params.clone(),
            size: a.size,
            frames: a.frames,
            flicker_frames: a.flicker_frames,
            bounces: a.bounces,
            spp: a.spp,
            budget_ms: a.budget_ms,
            target_flip: a.target_flip,
        })
    }

    /// The arguments that give this spec back (without `--out` and `--shard`).
    pub fn args(&self) -> Vec<String> {
        let mut v = Vec::new();
        let mut push = |flag: &str, value: String| {
            v.push(flag.to_string());
            v.push(value);
        };
        for s in &self.scenes {
            push("--scene", s.clone());
        }
        if self.unit_scale != 0.0 {
            push("--unit-scale", self.unit_scale.to_string());
        }
        for p in &self.presets {
            push("--preset", p.clone());
        }
        for o in &self.overrides {
            push("--set", o.clone());
        }
        for p in &self.params {
            push("--param", p.clone());
        }
        push("--size", format!("{}x{}", self.size.0, self.size.1));
        push("--frames", self.frames.to_string());
        push("--flicker-frames", self.flicker_frames.to_string());
        push("--bounces", self.bounces.to_string());
        push("--spp", self.spp.to_string());
        if let Some(b) = self.budget_ms {
            push("--budget-ms", b.to_string());
        }
        if let Some(t) = self.target_flip {
            push("--target-flip", t.to_string());
        }
        v
    }

    /// The command line that reproduces the study into `out` (as the report prints it).
    pub fn command(&self, program: &str, out: &Path) -> String {
        let mut words = vec![shell_word(program), "study".to_string()];
        words.extend(self.args().iter().map(|a| shell_word(a)));
        words.push("--out".into());
        words.push(shell_word(&out.display().to_string()));
        words.join(" ")
    }
}

/// One scene of the study.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneInfo {
    pub name: String,
    /// The folder name of its images (unique in the study).
    pub slug: String,
    /// The file, or None for the embedded default scene.
    pub file: Option<String>,
}

/// One preset of the study with what it changes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PresetInfo {
    pub name: String,
    pub slug: String,
    /// The file, or None for a shipped technique preset.
    pub file: Option<String>,
    /// The technique its stage choices are, or "a mix of stages: …".
    pub technique: String,
    /// Its settings that differ from the defaults, as `path = value (default d)` (the study's
    /// --set overrides included).
    pub diff: Vec<String>,
}

/// One job: a scene, a preset and a sweep point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Job {
    pub scene: usize,
    pub preset: usize,
    pub point: usize,
}

/// The checked study: its scenes, presets with their settings, sweep points and jobs.
pub struct Plan {
    pub scenes: Vec<SceneInfo>,
    pub presets: Vec<PresetInfo>,
    pub preset_settings: Vec<LabSettings>,
    pub params: Vec<Param>,
    pub points: Vec<Vec<(String, Value)>>,
    pub jobs: Vec<Job>,
}

/// Lower-case letters, digits and dashes, unique among `taken`.
fn slug(name: &str, taken: &[String]) -> String {
    let mut s: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '-' }).collect();
    s = s.split('-').filter(|p| !p.is_empty()).collect::<Vec<_>>().join("-");
    if s.is_empty() {
        s = "x".into();
    }
    let mut out = s.clone();
    let mut k = 2;
    while taken.contains(&out) {
        out = format!("{s}-{k}");
        k += 1;
    }
    out
}

fn stem(path: &str) -> String {
    Path::new(path).file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_else(|| path.to_string())
}

/// The technique of `s` in words.
pub fn technique_of(s: &LabSettings) -> String {
    match gi_render::settings::pipeline::Technique::of(&s.pipeline) {
        Some(t) => t.label().to_string(),
        None => "a mix of stages (see the settings)".into(),
    }
}

/// The settings of `s` that differ from the defaults.
pub fn diff_from_defaults(s: &LabSettings) -> Vec<String> {
    s.differences(&LabSettings::default()).into_iter().map(|(p, a, b)| format!("{p} = {a} (default {b})")).collect()
}

impl Plan {
    pub fn new(spec: &Spec) -> Result<Self, CliError> {
        let mut scenes: Vec<SceneInfo> = Vec::new();
        if spec.scenes.is_empty() {
            scenes.push(SceneInfo { name: "Cornell box (embedded)".into(), slug: "cornell-box".into(), file: None });
        }
        for f in &spec.scenes {
            let taken: Vec<String> = scenes.iter().map(|s| s.slug.clone()).collect();
            let name = stem(f);
            scenes.push(SceneInfo { slug: slug(&name, &taken), name, file: Some(f.clone()) });
        }
        let mut loaded: Vec<(String, Option<String>, LabSettings)> = Vec::new();
        if spec.presets.is_empty() {
            for (name, text) in crate::cli::bench::run::TECHNIQUE_PRESETS {
                let s = gi_render::preset::load_lenient(text, name)
                    .map(|l| l.settings)
                    .map_err(|e| CliError::failure(format!("shipped preset {name}: {e}")))?;
                loaded.push((name.to_string(), None, s));
            }
        }
        for f in &spec.presets {
            let s = LabSettings::load(Path::new(f)).map_err(|e| CliError::input(format!("--preset {f}: {e}")))?;
            loaded.push((stem(f), Some(f.clone()), s));
        }
        let params: Vec<Param> =
            spec.params.iter().map(|p| parse_param(p)).collect::<Result<_, _>>().map_err(CliError::input)?;
        let points = grid(&params);
        let mut presets = Vec::new();
        let mut preset_settings = Vec::new();
        for (name, file, mut s) in loaded {
            // Like for like (issue #56): DDGI's probes add a bounce every frame; against a
            // one-bounce truth they take one, as the quality table's row does. The page lists
            // it among the preset's changes; `--set ddgi.infinite_bounces=true` keeps them.
            if spec.bounces == 1 && s.pipeline.gather == gi_render::settings::pipeline::Gather::Probes {
                s.ddgi.infinite_bounces = false;
            }
            for o in &spec.overrides {
                s.apply_override(o).map_err(|e| CliError::input(format!("--set {o}: {e}")))?;
            }
            // Every point of every preset is checked before anything renders.
            settings_at(&s, &points).map_err(|e| CliError::input(format!("preset {name}: {e}")))?;
            let taken: Vec<String> = presets.iter().map(|p: &PresetInfo| p.slug.clone()).collect();
            presets.push(PresetInfo {
                slug: slug(&name, &taken),
                technique: technique_of(&s),
                diff: diff_from_defaults(&s),
                name,
                file,
            });
            preset_settings.push(s);
        }
        let mut jobs = Vec::new();
        for scene in 0..scenes.len() {
            for preset in 0..presets.len() {
                for point in 0..points.len() {
                    jobs.push(Job { scene, preset, point });
                }
            }
        }
        Ok(Self { scenes, presets, preset_settings, params, points, jobs })
    }

    /// Checks that the scene files of `jobs` exist (before anything renders).
    pub fn check_scenes(&self, jobs: &[Job]) -> Result<(), CliError> {
        for j in jobs {
            if let Some(f) = &self.scenes[j.scene].file
                && !Path::new(f).is_file()
            {
                return Err(CliError::input(format!("--scene {f}: no such file")));
            }
        }
        Ok(())
    }

    /// The settings of a job: its preset with its sweep point.
    pub fn settings(&self, job: Job) -> LabSettings {
        let mut s = self.preset_settings[job.preset].clone();
        for (path, v) in &self.points[job.point] {
            // Checked in `new`.
            let _ = s.set(path, v);
        }
        s
    }

    /// The file name (without extension) of a job's images.
    pub fn job_slug(&self, job: Job) -> String {
        let p = &self.presets[job.preset].slug;
        if self.points.len() > 1 { format!("{p}-p{}", job.point) } else { p.clone() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_are_unique_and_plain() {
        assert_eq!(slug("Hotel Room (v2)", &[]), "hotel-room-v2");
        assert_eq!(slug("a", &["a".into(), "a-2".into()]), "a-3");
        assert_eq!(slug("%%", &[]), "x");
    }

    #[test]
    fn ddgi_takes_one_bounce_against_a_one_bounce_truth_unless_told_otherwise() {
        let spec = |bounces: u32, overrides: &[&str]| Spec {
            scenes: Vec::new(),
            unit_scale: 0.0,
            presets: Vec::new(),
            overrides: overrides.iter().map(|o| o.to_string()).collect(),
            params: Vec::new(),
            size: (32, 32),
            frames: 1,
            flicker_frames: 0,
            bounces,
            spp: 1,
            budget_ms: None,
            target_flip: None,
        };
        let bounces = |spec: &Spec| {
            let plan = Plan::new(spec).expect("the plan");
            let i = plan.presets.iter().position(|p| p.name == "ddgi").expect("the shipped presets hold DDGI's");
            let knecht = plan.presets.iter().position(|p| p.name == "knecht").expect("and Knecht's");
            assert_eq!(plan.preset_settings[knecht], {
                let t = crate::cli::bench::run::TECHNIQUE_PRESETS[0].1;
                gi_render::preset::load_lenient(t, "knecht").expect("loads").settings
            });
            plan.preset_settings[i].ddgi.infinite_bounces
        };
        assert!(!bounces(&spec(1, &[])), "one bounce against a one-bounce truth");
        assert!(bounces(&spec(3, &[])), "infinite bounces against a truth of three");
        assert!(bounces(&spec(1, &["ddgi.infinite_bounces=true"])), "--set wins");
    }
}
