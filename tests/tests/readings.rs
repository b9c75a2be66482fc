//! The readings of the papers (docs/readings.md): every place where the code interprets an
//! ambiguous, garbled or inconsistent formula, departs from the text or adds a constant the
//! text does not give carries a warning sign followed by its id in brackets, `[paper.slug]`,
//! in a comment. These tests check, without a GPU, that
//! - every warning sign in the sources (`render/`, `shaders/`, `app/`, `tests/`; `*.rs` and
//!   `*.wgsl`) is followed by a well-formed id;
//! - every id in the sources has a row in docs/readings.md and every row's id is in the
//!   sources;
//! - every setting a row names (a dotted path in backticks in its setting column) exists.
//!
//! The sign is written `\u{26a0}` here so that this file does not mark a reading itself.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const SIGN: char = '\u{26a0}';
const PAPERS: [&str; 5] = ["nguyen", "knecht", "gautron", "soler", "ddgi"];
const SCANNED: [&str; 4] = ["render", "shaders", "app", "tests"];
/// The columns of a row: id | the text's words | GI Lab's choice | why | setting | measured effect.
const COLUMNS: usize = 6;
const SETTING: usize = 4;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `paper.slug`: one of the four papers, then lowercase words joined by hyphens.
fn valid_id(id: &str) -> bool {
    let Some((paper, slug)) = id.split_once('.') else { return false };
    PAPERS.contains(&paper)
        && !slug.is_empty()
        && slug.split('-').all(|w| !w.is_empty() && w.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit()))
}

fn source_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().to_string();
        if p.is_dir() {
            if name != "target" && !name.starts_with('.') {
                source_files(&p, out);
            }
        } else if name.ends_with(".rs") || name.ends_with(".wgsl") {
            out.push(p);
        }
    }
}

/// Every id tagged in the sources with the places it is tagged at, and every sign that is not
/// followed by a well-formed `[id]` (as `file:line: text`).
fn scan_sources() -> (BTreeMap<String, Vec<String>>, Vec<String>) {
    let root = root();
    let mut files = Vec::new();
    for d in SCANNED {
        source_files(&root.join(d), &mut files);
    }
    files.sort();
    assert!(files.len() > 100, "found only {} source files under {}", files.len(), root.display());
    let (mut ids, mut bad) = (BTreeMap::<String, Vec<String>>::new(), Vec::new());
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap_or_default();
        let rel = f.strip_prefix(&root).unwrap_or(&f).display().to_string();
        for (n, line) in text.lines().enumerate() {
            let place = format!("{rel}:{}", n + 1);
            for (i, _) in line.match_indices(SIGN) {
                let rest = &line[i + SIGN.len_utf8()..];
                let id = rest.strip_prefix('[').and_then(|r| r.split_once(']')).map(|(id, _)| id);
                match id {
                    Some(id) if valid_id(id) => ids.entry(id.to_string()).or_default().push(place.clone()),
                    _ => bad.push(format!("{place}: {}", line.trim())),
                }
            }
        }
    }
    (ids, bad)
}

/// A table row's cells, split at the `|` that are not escaped as `\|`.
fn cells(row: &str) -> Vec<String> {
    let inner = row.trim().trim_start_matches('|').trim_end_matches('|');
    let mut out = vec![String::new()];
    let mut prev = ' ';
    for c in inner.chars() {
        if c == '|' && prev != '\\' {
            out.push(String::new());
        } else {
            out.last_mut().expect("a cell").push(c);
        }
        prev = c;
    }
    out.into_iter().map(|c| c.trim().to_string()).collect()
}

/// The spans in backticks of a cell.
fn code_spans(cell: &str) -> Vec<&str> {
    cell.split('`').skip(1).step_by(2).collect()
}

/// A dotted settings path, `group.field`.
fn is_path(s: &str) -> bool {
    let Some((g, f)) = s.split_once('.') else { return false };
    let word = |w: &str| {
        w.chars().next().is_some_and(|c| c.is_ascii_lowercase())
            && w.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
    };
    word(g) && word(f)
}

struct Row {
    id: String,
    line: usize,
    cells: Vec<String>,
}

/// The rows of docs/readings.md whose first cell is an id in backticks.
fn rows() -> Vec<Row> {
    let path = root().join("docs/readings.md");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim_start().starts_with('|'))
        .filter_map(|(n, l)| {
            let cells = cells(l);
            let first = cells.first()?;
            let id = first.strip_prefix('`')?.strip_suffix('`')?.to_string();
            valid_id(&id).then(|| Row { id, line: n + 1, cells })
        })
        .collect()
}

#[test]
fn every_warning_sign_names_a_reading() {
    let (ids, bad) = scan_sources();
    assert!(
        bad.is_empty(),
        "{} warning sign(s) not followed by [paper.slug] (paper: {}):\n{}",
        bad.len(),
        PAPERS.join(", "),
        bad.join("\n")
    );
    assert!(!ids.is_empty(), "no reading is tagged in the sources");
}

#[test]
fn every_reading_has_one_row_and_every_row_a_reading() {
    let (ids, _) = scan_sources();
    let rows = rows();
    let mut seen = BTreeMap::<&str, usize>::new();
    let mut problems = Vec::new();
    for r in &rows {
        if let Some(first) = seen.insert(&r.id, r.line) {
            problems.push(format!("docs/readings.md:{}: `{}` has a row already at line {first}", r.line, r.id));
        }
        if r.cells.len() != COLUMNS {
            problems.push(format!(
                "docs/readings.md:{}: `{}` has {} cells, not {COLUMNS} (escape a | inside a cell as \\|)",
                r.line,
                r.id,
                r.cells.len()
            ));
        }
        if !ids.contains_key(&r.id) {
            problems.push(format!("docs/readings.md:{}: `{}` is tagged nowhere in the sources", r.line, r.id));
        }
    }
    let documented: BTreeSet<&str> = rows.iter().map(|r| r.id.as_str()).collect();
    for (id, places) in &ids {
        if !documented.contains(id.as_str()) {
            problems.push(format!("{}: `{id}` has no row in docs/readings.md", places.join(", ")));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn every_setting_a_row_names_exists() {
    let mut problems = Vec::new();
    let mut named = 0;
    for r in rows() {
        let Some(cell) = r.cells.get(SETTING) else { continue };
        for path in code_spans(cell).into_iter().filter(|s| is_path(s)) {
            named += 1;
            if gi_render::lab_settings::LabSettings::field(path).is_none() {
                problems.push(format!("docs/readings.md:{}: `{}` names `{path}`, which is no setting", r.line, r.id));
            }
        }
    }
    assert!(named > 0, "no row of docs/readings.md names a setting");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_parsers_read_what_they_should() {
    assert!(valid_id("soler.vote-depth-relative") && valid_id("nguyen.d-max"));
    assert!(!valid_id("soler") && !valid_id("hcb.d-max") && !valid_id("soler.Vote") && !valid_id("soler.a--b"));
    assert_eq!(cells("| `a.b` | x \\| y | z |"), ["`a.b`", "x \\| y", "z"]);
    assert_eq!(code_spans("`soler.sender`: `Diffuse` / `ViewDependent`"), ["soler.sender", "Diffuse", "ViewDependent"]);
    assert!(is_path("soler.sender") && is_path("hcb.d_max_m"));
    assert!(!is_path("0.05") && !is_path("Diffuse") && !is_path("presets/x.ron") && !is_path("a.b.c"));
}
