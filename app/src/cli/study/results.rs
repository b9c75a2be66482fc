//! A study's numbers: the rows each shard measured, joined into per-scene reports with the
//! Pareto front and the equal-time and equal-error winners, and written as `results.json`,
//! `results.csv`, SVG plots and the page. An unsharded run is one shard of one: the merge and
//! the single run share [`Study::assemble`] and [`write_report`].

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::jobs::{PresetInfo, SceneInfo, Spec};
use crate::cli::shard::Shard;
use crate::cli::sweep::pareto_flags;
use crate::error::CliError;

/// Where a share of the study ran.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Machine {
    pub host: String,
    pub os: String,
    pub cpu: String,
    pub cores: usize,
    pub adapter: String,
    /// GPU timestamps, or the wall clock per pass on a device whose timestamps are unreliable.
    pub timing_source: String,
}

/// A scene's path-traced truth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TruthInfo {
    /// Its PNG, relative to the report.
    pub image: String,
    /// Seconds spent tracing it (0 when it came from the cache).
    pub seconds: f64,
    pub cached: bool,
    /// Which path tracer traced it, in words (issue #56: the GPU's on a real GPU); empty in
    /// results written before.
    #[serde(default)]
    pub tracer: String,
}

/// One job's measurements.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The job's place in the study's job list (scene, then preset, then sweep point).
    pub job: usize,
    pub scene: usize,
    pub preset: usize,
    pub point: usize,
    /// The swept settings of its point, `(path, value)`.
    pub assignments: Vec<(String, String)>,
    pub technique: String,
    /// Mean GPU time of a frame: the sum of the passes' means (ms).
    pub frame_ms: f64,
    /// Mean wall-clock time of one frame's call (ms).
    pub wall_ms: f64,
    /// Each pass's mean time (ms) in the order the frame runs them.
    pub passes: Vec<(String, f64)>,
    /// Mean FLIP (tone-mapped) and RMSE (linear) of final.hdr against the scene's truth.
    pub flip: f64,
    pub rmse: f64,
    /// Temporal flicker with the scene paused (None: not measured).
    pub flicker: Option<f64>,
    /// Its image and FLIP map (PNG, relative to the report).
    pub image: String,
    pub flip_map: String,
    /// Index into the study's machines.
    pub machine: usize,
    /// On its scene's Pareto front of frame time against FLIP.
    pub pareto: bool,
}

/// What one shard (or an unsharded run) measured: `DIR/shard-I/shard.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Part {
    pub spec: Spec,
    pub shard: Shard,
    /// Jobs in the whole study.
    pub jobs: usize,
    pub scenes: Vec<SceneInfo>,
    pub presets: Vec<PresetInfo>,
    /// The swept settings' paths.
    pub params: Vec<String>,
    pub machine: Machine,
    pub rows: Vec<Row>,
    /// (scene index, its truth) for the scenes this share rendered.
    pub truths: Vec<(usize, TruthInfo)>,
}

/// A winner: the row of `rows` that wins below `limit`, and where the limit came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Winner {
    pub limit: f64,
    /// "--budget-ms", "--target-flip" or "the median of the scene's jobs".
    pub limit_from: String,
    /// Index into the scene's rows; None when no job is within the limit.
    pub row: Option<usize>,
}

/// One scene's part of the report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneReport {
    pub info: SceneInfo,
    pub truth: TruthInfo,
    pub rows: Vec<Row>,
    /// The pass names of its rows, in the order of first appearance.
    pub passes: Vec<String>,
    /// The Pareto front: indices into `rows`, fastest first.
    pub front: Vec<usize>,
    /// The lowest FLIP among the rows within the frame budget.
    pub equal_time: Winner,
    /// The fastest row whose FLIP reaches the target.
    pub equal_error: Winner,
}

/// The whole study: `results.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Study {
    pub gi_lab_version: String,
    /// The command that reproduces it (`gi-lab study …`).
    pub command: String,
    pub spec: Spec,
    pub jobs: usize,
    pub params: Vec<String>,
    pub machines: Vec<Machine>,
    pub presets: Vec<PresetInfo>,
    pub scenes: Vec<SceneReport>,
}

/// The lower median (a value that occurs), or None for no values.
fn lower_median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    v.get(v.len().saturating_sub(1) / 2).copied()
}

fn winner(
    rows: &[Row],
    limit: Option<f64>,
    flag: &str,
    within: impl Fn(&Row, f64) -> bool,
    key: impl Fn(&Row) -> f64,
    of: impl Fn(&Row) -> f64,
) -> Winner {
    let (limit, limit_from) = match limit {
        Some(l) => (l, flag.to_string()),
        None => (lower_median(rows.iter().map(&of).collect()).unwrap_or(0.0), "the median of the scene's jobs".into()),
    };
    let row =
        (0..rows.len()).filter(|&i| within(&rows[i], limit)).min_by(|&a, &b| key(&rows[a]).total_cmp(&key(&rows[b])));
    Winner { limit, limit_from, row }
}

impl Study {
    /// Joins the parts of one study (checked: one spec, every job exactly once).
    pub fn assemble(parts: Vec<Part>) -> Result<Self, CliError> {
        let first = parts.first().ok_or_else(|| CliError::input("no shard to join"))?.clone();
        let mut machines: Vec<Machine> = Vec::new();
        let mut rows: Vec<Row> = Vec::new();
        let mut truths: Vec<Option<TruthInfo>> = vec![None; first.scenes.len()];
        for p in &parts {
            if p.spec != first.spec || p.jobs != first.jobs {
                return Err(CliError::input(format!(
                    "shard {}/{} belongs to another study (its arguments differ from shard {}/{}'s)",
                    p.shard.index, p.shard.count, first.shard.index, first.shard.count
                )));
            }
            let m = match machines.iter().position(|m| *m == p.machine) {
                Some(m) => m,
                None => {
                    machines.push(p.machine.clone());
                    machines.len() - 1
                }
            };
            rows.extend(p.rows.iter().cloned().map(|mut r| {
                r.machine = m;
                r
            }));
            for (s, t) in &p.truths {
                if truths[*s].is_none() {
                    truths[*s] = Some(t.clone());
                }
            }
        }
        rows.sort_by_key(|r| r.job);
        let jobs: Vec<usize> = rows.iter().map(|r| r.job).collect();
        if jobs != (0..first.jobs).collect::<Vec<_>>() {
            return Err(CliError::input(format!(
                "the shards hold {} rows for {} jobs: a shard is missing, repeated or unfinished",
                rows.len(),
                first.jobs
            )));
        }
        let mut scenes = Vec::new();
        for (s, info) in first.scenes.iter().enumerate() {
            let mut scene_rows: Vec<Row> = rows.iter().filter(|r| r.scene == s).cloned().collect();
            let truth = truths[s].clone().ok_or_else(|| CliError::input(format!("no truth of {}", info.name)))?;
            let flags = pareto_flags(&scene_rows.iter().map(|r| (r.frame_ms, r.flip)).collect::<Vec<_>>());
            for (r, f) in scene_rows.iter_mut().zip(flags) {
                r.pareto = f;
            }
            let mut front: Vec<usize> = (0..scene_rows.len()).filter(|&i| scene_rows[i].pareto).collect();
            front.sort_by(|&a, &b| scene_rows[a].frame_ms.total_cmp(&scene_rows[b].frame_ms).then(a.cmp(&b)));
            let mut passes: Vec<String> = Vec::new();
            for r in &scene_rows {
                for (p, _) in &r.passes {
                    if !passes.contains(p) {
                        passes.push(p.clone());
                    }
                }
            }
            let equal_time = winner(
                &scene_rows,
                first.spec.budget_ms,
                "--budget-ms",
                |r, l| r.frame_ms <= l,
                |r| r.flip,
                |r| r.frame_ms,
            );
            let equal_error = winner(
                &scene_rows,
                first.spec.target_flip,
                "--target-flip",
                |r, l| r.flip <= l,
                |r| r.frame_ms,
                |r| r.flip,
            );
            scenes.push(SceneReport {
                info: info.clone(),
                truth,
                rows: scene_rows,
                passes,
                front,
                equal_time,
                equal_error,
            });
        }
        Ok(Self {
            gi_lab_version: env!("CARGO_PKG_VERSION").into(),
            command: String::new(),
            spec: first.spec.clone(),
            jobs: first.jobs,
            params: first.params.clone(),
            machines,
            presets: first.presets.clone(),
            scenes,
        })
    }

    /// `results.csv`: one row per scene × preset × sweep point.
    pub fn csv(&self) -> String {
        let mut passes: Vec<String> = Vec::new();
        for s in &self.scenes {
            for p in &s.passes {
                if !passes.contains(p) {
                    passes.push(p.clone());
                }
            }
        }
        let quote = |s: &str| {
            if s.contains([',', '"', '\n']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
        };
        let mut out = String::from("scene,preset,point");
        for p in &self.params {
            out += &format!(",{}", quote(p));
        }
        out += ",technique,frame_ms,wall_ms,flip,rmse,flicker,pareto,machine,image,flip_map";
        for p in &passes {
            out += &format!(",{}", quote(&format!("{p}_ms")));
        }
        out += "\n";
        for s in &self.scenes {
            for r in &s.rows {
                out += &format!("{},{},{}", quote(&s.info.name), quote(&self.presets[r.preset].name), r.point);
                for (_, v) in &r.assignments {
                    out += &format!(",{}", quote(v));
                }
                let flicker = r.flicker.map(|f| format!("{f}")).unwrap_or_default();
                out += &format!(
                    ",{},{},{},{},{},{flicker},{},{},{},{}",
                    quote(&r.technique),
                    r.frame_ms,
                    r.wall_ms,
                    r.flip,
                    r.rmse,
                    r.pareto,
                    r.machine,
                    quote(&r.image),
                    quote(&r.flip_map)
                );
                for p in &passes {
                    match r.passes.iter().find(|(n, _)| n == p) {
                        Some((_, ms)) => out += &format!(",{ms}"),
                        None => out += ",",
                    }
                }
                out += "\n";
            }
        }
        out
    }
}

pub(super) fn write(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| CliError::failure(format!("{}: {e}", parent.display())))?;
    }
    gi_render::files::write_atomic_bytes(path, bytes, gi_render::files::Backup::Skip)
        .map_err(|e| CliError::failure(format!("{}: {e}", path.display())))
}

pub(super) fn json<T: Serialize>(v: &T) -> Result<String, CliError> {
    serde_json::to_string_pretty(v).map_err(|e| CliError::failure(e.to_string()))
}

/// A shard's measurements: `DIR/shard-I/shard.json` (its images are already beside it).
pub fn write_shard(dir: &Path, part: &Part) -> Result<(), CliError> {
    write(&dir.join("shard.json"), json(part)?.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(rows: &[(f64, f64)], shard: Shard, spec: &Spec) -> Part {
        let scenes = vec![
            SceneInfo { name: "a".into(), slug: "a".into(), file: None },
            SceneInfo { name: "b".into(), slug: "b".into(), file: None },
        ];
        let presets: Vec<PresetInfo> = (0..3)
            .map(|i| PresetInfo {
                name: format!("p{i}"),
                slug: format!("p{i}"),
                file: None,
                technique: "t".into(),
                diff: Vec::new(),
            })
            .collect();
        let range = shard.range(rows.len());
        let all: Vec<Row> = rows
            .iter()
            .enumerate()
            .map(|(job, &(ms, flip))| Row {
                job,
                scene: job / 3,
                preset: job % 3,
                point: 0,
                assignments: Vec::new(),
                technique: "t".into(),
                frame_ms: ms,
                wall_ms: ms + 1.0,
                passes: vec![("gbuffer".into(), ms / 2.0), (format!("pass{}", job % 2), ms / 2.0)],
                flip,
                rmse: flip / 2.0,
                flicker: None,
                image: format!("img/{job}.png"),
                flip_map: format!("img/{job}-flip.png"),
                machine: 0,
                pareto: false,
            })
            .collect();
        let truth = |s: usize| {
            (s, TruthInfo { image: format!("img/{s}/truth.png"), seconds: 1.0, cached: false, tracer: String::new() })
        };
        let rows: Vec<Row> = all[range.clone()].to_vec();
        let mut truths: Vec<(usize, TruthInfo)> = rows.iter().map(|r| truth(r.scene)).collect();
        truths.dedup_by_key(|t| t.0);
        Part {
            spec: spec.clone(),
            shard,
            jobs: all.len(),
            scenes,
            presets,
            params: Vec::new(),
            machine: Machine {
                host: "h".into(),
                os: "o".into(),
                cpu: "c".into(),
                cores: 2,
                adapter: "a".into(),
                timing_source: "t".into(),
            },
            rows,
            truths,
        }
    }

    fn spec() -> Spec {
        Spec {
            scenes: Vec::new(),
            unit_scale: 0.0,
            presets: Vec::new(),
            overrides: Vec::new(),
            params: Vec::new(),
            size: (64, 64),
            frames: 2,
            flicker_frames: 0,
            bounces: 1,
            spp: 8,
            budget_ms: None,
            target_flip: Some(0.3),
        }
    }

    /// The merge is a function of the rows alone: any split of the same measurements joins
    /// into the study one part gives (front, winners, CSV and all).
    #[test]
    fn any_split_of_the_rows_assembles_into_the_unsplit_study() {
        let rows = [(3.0, 0.2), (1.0, 0.5), (2.0, 0.25), (4.0, 0.1), (1.5, 0.4), (9.0, 0.4)];
        let spec = spec();
        let whole = Study::assemble(vec![part(&rows, Shard { index: 1, count: 1 }, &spec)]).expect("whole");
        for n in 2..=6 {
            let parts = (1..=n).map(|i| part(&rows, Shard { index: i, count: n }, &spec)).rev().collect();
            let joined = Study::assemble(parts).expect("joined");
            assert_eq!(joined, whole, "{n} shards");
            assert_eq!(joined.csv(), whole.csv());
        }
        let a = &whole.scenes[0];
        assert_eq!(a.front, [1, 2, 0], "fastest first");
        // Budget: the lower median of 3, 1, 2 is 2 ms, within which 0.25 is the best FLIP.
        assert_eq!((a.equal_time.limit, a.equal_time.row), (2.0, Some(2)));
        assert_eq!((a.equal_error.limit, a.equal_error.row), (0.3, Some(2)));
        let b = &whole.scenes[1];
        assert_eq!(b.front, [1, 0], "job 5 is beaten by job 4");
        assert!(!b.rows[2].pareto);
        assert_eq!(b.equal_error.row, Some(0));
    }

    #[test]
    fn a_missing_repeated_or_foreign_shard_is_refused() {
        let rows = [(1.0, 0.1); 6];
        let spec = spec();
        let one = |i, n| part(&rows, Shard { index: i, count: n }, &spec);
        assert!(Study::assemble(vec![one(1, 3), one(3, 3)]).is_err(), "shard 2 missing");
        assert!(Study::assemble(vec![one(1, 2), one(1, 2), one(2, 2)]).is_err(), "shard 1 twice");
        let mut other = one(2, 2);
        other.spec.spp = 16;
        assert!(Study::assemble(vec![one(1, 2), other]).is_err(), "another study's shard");
    }

    #[test]
    fn the_lower_median_is_a_value_that_occurs() {
        assert_eq!(lower_median(vec![3.0, 1.0, 2.0, 4.0]), Some(2.0));
        assert_eq!(lower_median(vec![5.0]), Some(5.0));
        assert_eq!(lower_median(vec![]), None);
    }
}
