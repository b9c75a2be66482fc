//! The study's report (`index.html`, its plots, results.json and results.csv) from its
//! results, and `--merge`, which joins the shards' measurements into it.

use std::path::Path;

use super::results::{Part, Study, Winner, json, write};
use super::{page, svg};
use crate::cli::shard::shard_dirs;
use crate::cli::shard_status::check_complete;
use crate::error::CliError;

/// Writes the report of `study` into `out`: results.json, results.csv, plots/ and index.html
/// (the images of img/ are already there).
pub fn write_report(out: &Path, study: &Study) -> Result<(), CliError> {
    let out_abs = std::fs::canonicalize(out).map_err(|e| CliError::failure(format!("{}: {e}", out.display())))?;
    let mut study = study.clone();
    study.command = study.spec.command("gi-lab", &out_abs);
    for (i, s) in study.scenes.iter().enumerate() {
        write(&out.join(page::error_plot_file(s)), svg::error_against_time(&study, i).as_bytes())?;
        write(&out.join(page::passes_plot_file(s)), svg::pass_bars(&study, i).as_bytes())?;
    }
    write(&out.join("results.json"), json(&study)?.as_bytes())?;
    write(&out.join("results.csv"), study.csv().as_bytes())?;
    write(&out.join("index.html"), page::html(&study).as_bytes())?;
    println!("wrote {}", out.join("index.html").display());
    for s in &study.scenes {
        let name = |w: &Winner| w.row.map(|i| study.presets[s.rows[i].preset].name.clone());
        println!(
            "{}: equal time ({:.3} ms): {}; equal error (FLIP {:.4}): {}",
            s.info.name,
            s.equal_time.limit,
            name(&s.equal_time).unwrap_or_else(|| "none within the budget".into()),
            s.equal_error.limit,
            name(&s.equal_error).unwrap_or_else(|| "none reaches it".into()),
        );
    }
    Ok(())
}

/// `gi-lab study --merge DIR`: the shards of DIR joined into DIR's report.
pub fn merge(dir: &Path) -> Result<(), CliError> {
    let found = shard_dirs(dir, "shard.json").map_err(CliError::input)?;
    let mut parts = Vec::new();
    for (_, d) in &found {
        let path = d.join("shard.json");
        let text = std::fs::read_to_string(&path).map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
        let part: Part = serde_json::from_str(&text)
            .map_err(|e| CliError::input(format!("{}: not a study shard: {e}", path.display())))?;
        parts.push((d.clone(), part));
    }
    let shards: Vec<_> = parts.iter().map(|(d, p)| (d.clone(), p.shard)).collect();
    check_complete(dir, &shards, "shard.json").map_err(CliError::input)?;
    // The images, at the same relative paths as an unsharded run writes them.
    for (d, p) in &parts {
        let files = p.rows.iter().flat_map(|r| [&r.image, &r.flip_map]).chain(p.truths.iter().map(|(_, t)| &t.image));
        for f in files {
            let (from, to) = (d.join(f), dir.join(f));
            if let Some(parent) = to.parent() {
                std::fs::create_dir_all(parent).map_err(|e| CliError::failure(format!("{}: {e}", parent.display())))?;
            }
            std::fs::copy(&from, &to).map_err(|e| CliError::input(format!("{}: {e}", from.display())))?;
        }
    }
    let study = Study::assemble(parts.into_iter().map(|(_, p)| p).collect())?;
    write_report(dir, &study)
}
