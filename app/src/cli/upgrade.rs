//! `gi-lab upgrade`: rewrites presets of an older version in the current one (the same
//! migration the loader applies, `gi_render::preset::load_lenient`), keeping each file's
//! leading comment. A file with problems beyond the migration is left untouched.

use std::path::PathBuf;

use clap::Args;
use gi_render::files::write_atomic;
use gi_render::preset::load_lenient;
use gi_render::settings::PRESET_VERSION;

use crate::error::CliError;

#[derive(Args, Debug, Clone)]
pub struct UpgradeArgs {
    /// Preset files (RON) to rewrite in place; the old text is kept as `<name>.bak`.
    #[arg(required = true)]
    pub presets: Vec<PathBuf>,
}

/// The comment lines before a preset's opening parenthesis (its description).
fn header(text: &str) -> String {
    text.lines()
        .take_while(|l| l.trim_start().starts_with("//") || l.trim().is_empty())
        .filter(|l| !l.trim().is_empty())
        .map(|l| format!("{l}\n"))
        .collect()
}

pub(super) fn upgrade(a: &UpgradeArgs) -> Result<(), CliError> {
    let mut failed = Vec::new();
    for path in &a.presets {
        let shown = path.display().to_string();
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) => {
                failed.push(format!("{shown}: {e}"));
                continue;
            }
        };
        let loaded = match load_lenient(&text, &shown) {
            Ok(l) => l,
            Err(e) => {
                failed.push(e.to_string());
                continue;
            }
        };
        if !loaded.problems.is_empty() {
            let list: Vec<String> = loaded.problems.iter().map(|p| format!("  {}: {}", p.field, p.message)).collect();
            failed.push(format!("{shown}: not rewritten, fix these first:\n{}", list.join("\n")));
            continue;
        }
        if loaded.migrations.is_empty() {
            println!("{shown}: already version {PRESET_VERSION}");
            continue;
        }
        let out = format!("{}{}", header(&text), loaded.settings.to_ron());
        write_atomic(path, &out).map_err(|e| CliError::input(format!("{shown}: {e}")))?;
        println!("{shown}: {} (old text in {shown}.bak)", loaded.migrations.join("; "));
    }
    if failed.is_empty() { Ok(()) } else { Err(CliError::input(failed.join("\n"))) }
}

#[cfg(test)]
mod tests {
    use super::header;

    #[test]
    fn header_keeps_the_leading_comment_only() {
        let text = "// a\n// b\n\n(\n    // inner\n    version: 1,\n)\n";
        assert_eq!(header(text), "// a\n// b\n");
        assert_eq!(header("(version: 2)"), "");
    }
}
