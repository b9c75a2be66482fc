//! No circles between modules (issue #52 point 2): in `render/src` and `app/src`, the
//! modules of every folder — the crate's top-level modules, and the files and subfolders of
//! each folder — import one another without a cycle, so that each can be read, tested and
//! split knowing only what lies below it (CONTRIBUTING.md, "Splitting a file").
//!
//! An import is any `crate::…` or `super::…` path in the code (comments left out), a group
//! `crate::a::{b, c::d}` included; a name the crate root re-exports (`crate::LabSettings`)
//! counts as an import of the module it comes from. Module `a::b` importing `a::c::d` is an
//! edge b → c between the siblings of folder `a`.
//!
//! Issue #52 removed the last cycles (the render crate's top-level knot and the app's `ui`
//! knot around `ui::State`); [`KNOWN`] is empty and stays so: the test fails on any cycle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Cycles allowed, as "folder: a b c" (folder `<root>` for the crate's top level; modules
/// sorted): none.
const KNOWN: &[&str] = &[];

type ModPath = Vec<String>;

/// `a/b/c.rs` → [a, b, c]; `a/mod.rs` → [a]; `lib.rs` / `main.rs` → [].
fn module_of(root: &Path, file: &Path) -> ModPath {
    let rel = file.strip_prefix(root).expect("under the root").with_extension("");
    let mut parts: ModPath = rel.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
    if parts.last().is_some_and(|l| l == "mod") || parts == ["lib"] || parts == ["main"] {
        parts.pop();
    }
    parts
}

/// The source without its comments (line comments, doc comments and block comments; string
/// literals are kept as they are: a path in a string is still a path someone wrote).
fn code_of(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let b = src.as_bytes();
    let (mut i, mut depth, mut in_str) = (0, 0usize, false);
    while i < b.len() {
        if depth == 0 && !in_str && b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        if !in_str && b[i..].starts_with(b"/*") {
            depth += 1;
            i += 2;
            continue;
        }
        if depth > 0 {
            if b[i..].starts_with(b"*/") {
                depth -= 1;
                i += 2;
            } else {
                i += 1;
            }
            continue;
        }
        if b[i] == b'"' && (i == 0 || b[i - 1] != b'\\') && (i == 0 || b[i - 1] != b'\'') {
            in_str = !in_str;
        }
        out.push(b[i] as char);
        i += 1;
    }
    out
}

fn ident_at(s: &[u8], mut i: usize) -> (String, usize) {
    let start = i;
    while i < s.len() && (s[i].is_ascii_alphanumeric() || s[i] == b'_') {
        i += 1;
    }
    (String::from_utf8_lossy(&s[start..i]).into_owned(), i)
}

fn skip_ws(s: &[u8], mut i: usize) -> usize {
    while i < s.len() && s[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// The paths that start at byte `i` (just after `crate::` or the `super::`s): `a::b::c`,
/// `a::{b, c::{d, e}}` (each leaf of a group its own path), each prefixed with `prefix`.
fn paths_at(s: &[u8], i: usize, prefix: &ModPath, out: &mut Vec<ModPath>) -> usize {
    let mut path = prefix.clone();
    let mut i = skip_ws(s, i);
    loop {
        if i < s.len() && s[i] == b'{' {
            i += 1;
            loop {
                i = skip_ws(s, i);
                if i >= s.len() {
                    return i;
                }
                if s[i] == b'}' {
                    return i + 1;
                }
                if s[i] == b',' {
                    i += 1;
                    continue;
                }
                let before = i;
                i = paths_at(s, i, &path, out);
                // `as x`, `self`: skip what is not a path.
                while i < s.len() && !matches!(s[i], b',' | b'}') {
                    i += 1;
                }
                if i == before {
                    i += 1;
                }
            }
        }
        let (name, next) = ident_at(s, i);
        if name.is_empty() {
            break;
        }
        if name != "self" {
            path.push(name);
        }
        i = next;
        if s[i..].starts_with(b"::") {
            i = skip_ws(s, i + 2);
        } else {
            break;
        }
    }
    out.push(path);
    i
}

/// Every module path the code of module `me` names.
fn imports(code: &str, me: &ModPath) -> Vec<ModPath> {
    let s = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let word_start = i == 0 || !(s[i - 1].is_ascii_alphanumeric() || s[i - 1] == b'_' || s[i - 1] == b':');
        if word_start && s[i..].starts_with(b"crate::") {
            i = paths_at(s, i + 7, &Vec::new(), &mut out);
            continue;
        }
        if word_start && s[i..].starts_with(b"super::") {
            let mut ups = 0;
            while s[i..].starts_with(b"super::") {
                ups += 1;
                i += 7;
            }
            let base: ModPath = me[..me.len().saturating_sub(ups)].to_vec();
            i = paths_at(s, i, &base, &mut out);
            continue;
        }
        i += 1;
    }
    out
}

/// Names the crate root re-exports (`pub use a::b::X;`, `pub use a::{X, Y};`) → module `a`.
fn root_reexports(lib: &str) -> BTreeMap<String, String> {
    let mut map = BTreeMap::new();
    for stmt in code_of(lib).split(';') {
        let Some(rest) = stmt.trim().strip_prefix("pub use ") else { continue };
        let mut paths = Vec::new();
        paths_at(rest.as_bytes(), 0, &Vec::new(), &mut paths);
        for p in paths {
            if let (Some(first), Some(last)) = (p.first(), p.last())
                && p.len() > 1
            {
                map.insert(last.clone(), first.clone());
            }
        }
    }
    map
}

/// The cycles among the siblings of every folder of the crate at `root`, as
/// "folder: a b c" lines, sorted.
fn cycles(root: &Path) -> Vec<String> {
    let files = gi_lab_tests::rust_sources(root);
    let modules: BTreeSet<ModPath> = files.iter().map(|f| module_of(root, f)).collect();
    let lib = ["lib.rs", "main.rs"].iter().map(|n| root.join(n)).find(|p| p.exists()).expect("a crate root");
    let reexports = root_reexports(&std::fs::read_to_string(&lib).expect("crate root"));
    // Edges between siblings: (parent, from, to).
    let mut edges: BTreeMap<ModPath, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for f in &files {
        let me = module_of(root, f);
        let code = code_of(&std::fs::read_to_string(f).expect("source"));
        for mut path in imports(&code, &me) {
            if path.len() == 1
                && let Some(m) = reexports.get(&path[0])
            {
                path = vec![m.clone(), path[0].clone()];
            }
            // The longest prefix that is a module.
            let mut k = path.len();
            while k > 0 && !modules.contains(&path[..k]) {
                k -= 1;
            }
            let target = &path[..k];
            let common = me.iter().zip(target).take_while(|(a, b)| a == b).count();
            if common == me.len() || common == target.len() {
                continue; // itself, an ancestor or a descendant
            }
            edges
                .entry(me[..common].to_vec())
                .or_default()
                .entry(me[common].clone())
                .or_default()
                .insert(target[common].clone());
        }
    }
    let mut found = Vec::new();
    for (parent, graph) in &edges {
        for scc in strongly_connected(graph) {
            if scc.len() > 1 {
                let folder = if parent.is_empty() { "<root>".to_string() } else { parent.join("::") };
                found.push(format!("{folder}: {}", scc.into_iter().collect::<Vec<_>>().join(" ")));
            }
        }
    }
    found.sort();
    found
}

/// Tarjan's strongly connected components.
fn strongly_connected(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<BTreeSet<String>> {
    struct T<'a> {
        g: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<BTreeSet<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let n = t.index.len();
        t.index.insert(v, n);
        t.low.insert(v, n);
        t.stack.push(v);
        t.on.insert(v);
        if let Some(ws) = t.g.get(v) {
            for w in ws {
                if !t.index.contains_key(w.as_str()) {
                    visit(t, w);
                    let lw = t.low[w.as_str()];
                    let lv = t.low.get_mut(v).expect("visited");
                    *lv = (*lv).min(lw);
                } else if t.on.contains(w.as_str()) {
                    let iw = t.index[w.as_str()];
                    let lv = t.low.get_mut(v).expect("visited");
                    *lv = (*lv).min(iw);
                }
            }
        }
        if t.low[v] == t.index[v] {
            let mut scc = BTreeSet::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                scc.insert(w.to_string());
                if w == v {
                    break;
                }
            }
            t.out.push(scc);
        }
    }
    let mut t = T {
        g: graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    let nodes: BTreeSet<&str> =
        graph.iter().flat_map(|(k, vs)| std::iter::once(k.as_str()).chain(vs.iter().map(String::as_str))).collect();
    for v in nodes {
        if !t.index.contains_key(v) {
            visit(&mut t, v);
        }
    }
    t.out
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn no_module_imports_itself_through_its_siblings() {
    let mut found = Vec::new();
    for (krate, dir) in [("render", "render/src"), ("app", "app/src")] {
        found.extend(cycles(&repo().join(dir)).into_iter().map(|c| format!("{krate} {c}")));
    }
    let known: BTreeSet<&str> = KNOWN.iter().copied().collect();
    let new: Vec<&String> = found.iter().filter(|c| !known.contains(c.as_str())).collect();
    let gone: Vec<&&str> = known.iter().filter(|k| !found.iter().any(|c| c == **k)).collect();
    assert!(
        new.is_empty() && gone.is_empty(),
        "module cycles (crate folder: modules in one cycle):\nnew, not allowed:\n  {}\nlisted in KNOWN but gone (strike them):\n  {}",
        new.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("\n  "),
        gone.iter().map(|s| **s).collect::<Vec<_>>().join("\n  ")
    );
}

/// The parser sees what it must: grouped, nested, `super` and re-exported paths, and no
/// path inside a comment.
#[test]
fn the_import_parser_reads_groups_supers_and_skips_comments() {
    let me: ModPath = vec!["passes".into(), "knecht".into(), "ism".into()];
    let code = code_of(
        "use crate::a::{b, c::{d, e as f}, self};\n// crate::commented\n/* crate::blocked */\nlet x = super::super::cpu::halton(1);\nuse super::point_cloud::PointCloud;",
    );
    let mut got = imports(&code, &me);
    got.sort();
    let p = |s: &str| s.split("::").map(String::from).collect::<ModPath>();
    let mut want = vec![
        p("a::b"),
        p("a::c::d"),
        p("a::c::e"),
        p("a"),
        p("passes::cpu::halton"),
        p("passes::knecht::point_cloud::PointCloud"),
    ];
    want.sort();
    assert_eq!(got, want);
    let re = root_reexports("pub use buffers::{BufferKind, ImageF32};\npub use settings::LabSettings;\npub mod x;");
    assert_eq!(re.get("ImageF32").map(String::as_str), Some("buffers"));
    assert_eq!(re.get("LabSettings").map(String::as_str), Some("settings"));
}

/// The search finds a cycle where there is one: a crate of three modules, `a` and `b` importing
/// each other through a group and a `super` path, and a folder whose two files do the same.
#[test]
fn a_planted_cycle_is_found() {
    let root = std::env::temp_dir().join(format!("gi-lab-modules-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(root.join("c")).expect("temp crate");
    let files = [
        ("lib.rs", "pub mod a;\npub mod b;\npub mod c;\n"),
        ("a.rs", "use crate::{b::Y, c};\npub struct X;\n"),
        ("b.rs", "// crate::a is only named in a comment here\npub fn y() -> super::a::X { super::a::X }\n"),
        ("c/mod.rs", "pub mod d;\npub mod e;\n"),
        ("c/d.rs", "use super::e::E;\npub struct D;\n"),
        ("c/e.rs", "pub struct E(pub crate::c::d::D);\n"),
    ];
    for (name, text) in files {
        std::fs::write(root.join(name), text).expect("write");
    }
    let found = cycles(&root);
    let _ = std::fs::remove_dir_all(&root);
    assert_eq!(found, vec!["<root>: a b".to_string(), "c: d e".to_string()]);
}
