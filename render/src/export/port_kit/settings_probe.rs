//! Sizes and counts that follow a setting (issue #54 point 1; docs/port-kit.md, "Sizes that
//! follow a setting"). After the image probes ([`super::expressions`]), the frame is captured
//! once more at one probe size ([`AT`], 160×103) for each integer setting of the groups the stage choices
//! use, set to each of two other values (half and double, or as near as its range allows; a
//! variant the settings' rules refuse is skipped). Every texture dimension, buffer
//! size and dispatch or draw count that changes with the setting names it in `depends_on`;
//! where it follows that one setting alone and not the image, it is fitted over the three
//! values by `a * g(S) + b` with `g` the setting `S`, its square, a tiling `ceil(S / d)` or a
//! floor `max(m, S)`, and that expression (`256 * ism.points`) replaces the constant.

use super::expressions::{affine_text, solve_linear, step_numbers};
use super::joint_fit::{self, Obs};
use super::manifest::{Manifest, Pass};
use crate::LabSettings;
use crate::settings::{FieldKind, Value};

/// The probe size (of [`super::expressions::PROBES`]) at which each setting's variants are
/// captured: 160×103, large enough that a count of chunks of tiles (Gautron et al.'s record
/// creation, 256 tiles of `gautron.creation_tile_px`² a chunk) changes with the tile's size;
/// at 67×41 it was one chunk whatever the tile, and the dependence went unseen.
pub const AT: usize = 3;

/// An integer setting and the settings with it at other values, in the order to try them:
/// the first two the device draws are captured, and a neighbour ([`Variant::neighbour`]).
pub struct Variant {
    pub path: String,
    pub value: u32,
    pub others: Vec<(u32, LabSettings)>,
}

impl Variant {
    /// The setting one or two from the preset's value, not in `got`: a third capture, odd
    /// where the others are powers of two, that tells a grid's rows from its columns and
    /// shows a rounding.
    pub fn neighbour(&self, got: &[u32]) -> Option<&(u32, LabSettings)> {
        self.others.iter().find(|(x, _)| x.abs_diff(self.value) <= 2 && !got.contains(x))
    }
}

/// Other values of an integer setting within `[min, max]`, in the order to try them, spread
/// so that a floor or a ceiling shows: half and double, then triple and a quarter, then the
/// next two, then the two below.
fn nearby(v: u32, min: f64, max: f64) -> Vec<u32> {
    let v = v as u64;
    let ok = |x: u64| x >= 1 && x != v && (x as f64) >= min && (x as f64) <= max && x <= u32::MAX as u64;
    let mut out: Vec<u32> = Vec::new();
    for x in [v / 2, 2 * v, 3 * v, v / 4, v + 1, v + 2, v.saturating_sub(1), v.saturating_sub(2)] {
        if ok(x) && !out.contains(&(x as u32)) {
            out.push(x as u32);
        }
    }
    out
}

/// Every integer setting of the groups `s`'s stage choices use, with the nearby values whose
/// settings validate (at least two); `only`: these settings alone (a test's), None: all.
pub fn variants(s: &LabSettings, only: Option<&[&str]>) -> Vec<Variant> {
    let mut out = Vec::new();
    for (group, fields) in LabSettings::groups() {
        if !s.pipeline.group_in_use(group) {
            continue;
        }
        for f in fields.iter().filter(|f| matches!(f.kind, FieldKind::U32)) {
            let path = format!("{group}.{}", f.name);
            if only.is_some_and(|o| !o.contains(&path.as_str())) {
                continue;
            }
            let Some(Value::U32(v)) = s.get(&path) else { continue };
            let mut others = Vec::new();
            for x in nearby(v, f.min, f.max) {
                let mut t = s.clone();
                if t.set(&path, &Value::U32(x)).is_ok() && t.validate().is_empty() {
                    others.push((x, t));
                }
            }
            if others.len() >= 2 {
                out.push(Variant { path, value: v, others });
            }
        }
    }
    out
}

/// `g(S)` of [`fit`], with its text.
type SettingBasis = Box<dyn Fn(u64) -> u64>;

/// `a * g(S) + b` through the three points (S, value), `b` = 0 preferred; the expression in
/// the setting's name.
fn fit(name: &str, points: &[(u64, u64)]) -> Option<String> {
    let mut bases: Vec<(String, SettingBasis)> =
        vec![(name.to_string(), Box::new(|s| s)), (format!("{name} * {name}"), Box::new(|s| s * s))];
    // A capacity with a floor.
    for k in 0..=16 {
        let m = 1u64 << k;
        bases.push((format!("max({m}, {name})"), Box::new(move |s| s.max(m))));
    }
    for d in [2u64, 4, 8, 16, 32, 64, 128, 256] {
        bases.push((format!("ceil({name} / {d})"), Box::new(move |s| s.div_ceil(d))));
    }
    let qs: Vec<i128> = points.iter().map(|p| p.1 as i128).collect();
    for offset in [false, true] {
        for (text, g) in &bases {
            let gs: Vec<i128> = points.iter().map(|p| g(p.0) as i128).collect();
            if let Some((a, c)) = solve_linear(&gs, &qs, offset) {
                return Some(affine_text(text.clone(), text.contains(" * "), a, c));
            }
        }
    }
    None
}

/// Where a number is in a manifest: a resource's dimension, or a step's count.
#[derive(Clone, Debug)]
enum At {
    Resource { name: String, k: usize },
    Step { frame: usize, pass: usize, step: usize, i: usize },
}

/// Every size and count of `m`.
fn numbers(m: &Manifest) -> Vec<(At, u64)> {
    let mut out = Vec::new();
    for r in m.resources.iter().filter(|r| r.kind != "sampler") {
        out.extend(r.size.iter().enumerate().map(|(k, &v)| (At::Resource { name: r.name.clone(), k }, v)));
    }
    for (frame, passes) in m.frame_passes.iter().enumerate() {
        for (pass, p) in passes.iter().enumerate() {
            for (step, s) in p.steps.iter().enumerate() {
                let n = step_numbers(s);
                out.extend(n.into_iter().enumerate().map(|(i, v)| (At::Step { frame, pass, step, i }, v)));
            }
        }
    }
    out
}

/// The number at `at` of `m` in `other`, a capture of the same frame at another size or
/// settings: a resource by name; a step by frame (`other`'s last for a later one), by its
/// pass (the same name, and as many of that name before it) and by its pipeline (the same
/// kind and pipeline, and as many of them before it in the pass), so that steps a setting adds
/// (another bounce's) do not shift those after them.
fn value_in(m: &Manifest, at: &At, other: &Manifest) -> Option<u64> {
    match at {
        At::Resource { name, k } => other.resources.iter().find(|r| &r.name == name)?.size.get(*k).copied(),
        At::Step { frame, pass, step, i } => {
            let (mine, p) = same_pass(m, *frame, *pass, other)?;
            let t = mine.steps.get(*step)?;
            let same = |s: &&super::manifest::Step| s.kind == t.kind && s.pipeline == t.pipeline;
            let nth = mine.steps[..*step].iter().filter(same).count();
            let s = p.steps.iter().filter(same).nth(nth)?;
            step_numbers(s).get(*i).copied()
        }
    }
}

/// The expression of the image of the number at `at`.
fn expr_of(m: &Manifest, at: &At) -> Option<String> {
    match at {
        At::Resource { name, k } => m.resources.iter().find(|r| &r.name == name)?.size_expr.get(*k)?.clone(),
        At::Step { frame, pass, step, i } => {
            m.frame_passes.get(*frame)?.get(*pass)?.steps.get(*step)?.counts_expr.get(*i)?.clone()
        }
    }
}

/// The expression and the settings named of the number at `at`.
fn slot<'m>(m: &'m mut Manifest, at: &At) -> Option<(&'m mut Option<String>, &'m mut Vec<String>)> {
    match at {
        At::Resource { name, k } => {
            let r = m.resources.iter_mut().find(|r| &r.name == name)?;
            Some((r.size_expr.get_mut(*k)?, &mut r.depends_on))
        }
        At::Step { frame, pass, step, i } => {
            let s = m.frame_passes.get_mut(*frame)?.get_mut(*pass)?.steps.get_mut(*step)?;
            Some((s.counts_expr.get_mut(*i)?, &mut s.counts_depend_on))
        }
    }
}

/// The captures of the frame the settings' fits use: the image probes at the preset's
/// settings ([`super::expressions::PROBES`]), each setting at two other values alone at the
/// probe size [`AT`], and the settings a number follows changed together ([`Joint`]).
pub struct Captured<'a> {
    pub images: &'a [((u32, u32), Manifest)],
    pub variants: Vec<(&'a Variant, Vec<(u32, Manifest)>)>,
    pub joints: Vec<Joint>,
}

impl Captured<'_> {
    /// The values of the settings `names` in a capture: the preset's, but for `changed` (a
    /// setting's variant) where given.
    pub fn values(&self, names: &[String], changed: Option<(&str, u32)>) -> Vec<u64> {
        let value = |n: &String| match changed {
            Some((v, x)) if v == n => x as u64,
            _ => self.variants.iter().find(|(v, _)| &v.path == n).map_or(0, |(v, _)| v.value as u64),
        };
        names.iter().map(value).collect()
    }
}

/// Pass `pass` of frame `frame` of `m`, and the same pass in `other` (a capture at another
/// size or settings): the one of the same name with as many of that name before it, in the
/// frame of the same number (`other`'s last for a later one).
pub(crate) fn same_pass<'m>(
    m: &'m Manifest,
    frame: usize,
    pass: usize,
    other: &'m Manifest,
) -> Option<(&'m Pass, &'m Pass)> {
    let passes = m.frame_passes.get(frame)?;
    let mine = passes.get(pass)?;
    let nth = passes[..pass].iter().filter(|p| p.name == mine.name).count();
    let f = other.frame_passes.get(frame.min(other.frame_passes.len().checked_sub(1)?))?;
    Some((mine, f.iter().filter(|p| p.name == mine.name).nth(nth)?))
}

/// The frame with several settings (and the image) changed at once.
pub struct Joint {
    /// The settings changed, sorted by name, with their values.
    pub settings: Vec<(String, u32)>,
    pub size: (u32, u32),
    pub manifest: Manifest,
}

/// What a number of `m` follows.
struct Following {
    at: At,
    /// Its value in the kit.
    value: u64,
    /// The settings whose variants change it, or at some of whose values it does not exist
    /// (a step of a loop's level, of a later round): its `depends_on`.
    depends: Vec<String>,
    /// Those whose variants change its value where it exists: what an expression is fitted
    /// in. A setting that only adds or removes it (the rounds, for a later round's step) is
    /// not one.
    names: Vec<String>,
    /// Whether every variant of `names` has it (else no expression is fitted).
    whole: bool,
}

/// What each number of `m` follows ([`Following`]).
fn following(m: &Manifest, c: &Captured) -> Vec<Following> {
    let base = &c.images[AT].1;
    let mut out = Vec::new();
    for (at, value) in numbers(m) {
        let Some(q0) = value_in(m, &at, base) else { continue };
        let (mut depends, mut names, mut whole) = (Vec::new(), Vec::new(), true);
        for (var, manifests) in &c.variants {
            let qs: Vec<Option<u64>> = manifests.iter().map(|(_, mm)| value_in(m, &at, mm)).collect();
            if qs.iter().any(|q| *q != Some(q0)) {
                depends.push(var.path.clone());
            }
            if qs.iter().any(|q| q.is_some_and(|q| q != q0)) {
                names.push(var.path.clone());
                whole &= qs.iter().all(Option::is_some);
            }
        }
        if !depends.is_empty() {
            depends.sort();
            names.sort();
            out.push(Following { at, value, depends, names, whole });
        }
    }
    out
}

/// Whether the number's expression of the image is a constant (or there is none).
fn constant(e: &Option<String>) -> bool {
    e.as_ref().is_none_or(|x| x.parse::<u64>().is_ok())
}

/// The sets of settings to change together ([`Joint`]): those of each number that follows
/// several settings, or a setting and the image.
pub fn joint_sets(m: &Manifest, c: &Captured) -> Vec<Vec<String>> {
    let mut out: Vec<Vec<String>> = Vec::new();
    for Following { at, names, whole, .. } in following(m, c) {
        let image = expr_of(m, &at);
        let wanted = whole && (names.len() > 1 || (!names.is_empty() && image.is_some() && !constant(&image)));
        if wanted && !out.contains(&names) {
            out.push(names);
        }
    }
    out
}

/// Writes `depends_on` and the settings' expressions into `m` (the kit's manifest, at the
/// preset's settings, with the image's expressions). Returns how many numbers follow a
/// setting and how many of those got an expression of the settings.
pub fn annotate(m: &mut Manifest, c: &Captured) -> (usize, usize) {
    let (mut follow, mut fitted) = (0, 0);
    let (kw, kh) = (m.size[0] as u64, m.size[1] as u64);
    for Following { at, value: v, depends, names, whole } in following(m, c) {
        follow += 1;
        let image = expr_of(m, &at);
        let at_base = |x: Option<(&str, u32)>| c.values(&names, x);
        // One setting alone and not the image: the three values of its variant.
        let alone =
            c.variants.iter().find(|(var, _)| whole && names.len() == 1 && constant(&image) && var.path == names[0]);
        let single = alone.and_then(|(var, manifests)| {
            let mut points = vec![(var.value as u64, value_in(m, &at, &c.images[AT].1)?)];
            points.extend(manifests.iter().filter_map(|(x, mm)| Some((*x as u64, value_in(m, &at, mm)?))));
            fit(&names[0], &points)
        });
        let e = single.or_else(|| {
            if names.is_empty() {
                return None;
            }
            // Every capture: the kit, the image probes, each setting alone, them together.
            let mut obs = vec![Obs { w: kw, h: kh, s: at_base(None), q: v }];
            for ((w, h), mm) in c.images {
                obs.extend(value_in(m, &at, mm).map(|q| Obs { w: *w as u64, h: *h as u64, s: at_base(None), q }));
            }
            let (w0, h0) = (c.images[AT].0.0 as u64, c.images[AT].0.1 as u64);
            for (var, manifests) in c.variants.iter().filter(|(var, _)| names.contains(&var.path)) {
                for (x, mm) in manifests {
                    let s = at_base(Some((&var.path, *x)));
                    obs.extend(value_in(m, &at, mm).map(|q| Obs { w: w0, h: h0, s, q }));
                }
            }
            let mut joints = 0;
            for j in c.joints.iter().filter(|j| j.settings.iter().map(|s| &s.0).eq(names.iter())) {
                let s = j.settings.iter().map(|s| s.1 as u64).collect();
                if let Some(q) = value_in(m, &at, &j.manifest) {
                    obs.push(Obs { w: j.size.0 as u64, h: j.size.1 as u64, s, q });
                    joints += 1;
                }
            }
            let image = image.filter(|e| !constant(&Some(e.clone())));
            // Without a capture of them changed together, no formula of several is checked.
            (whole && (joints > 0 || (names.len() == 1 && image.is_none())))
                .then(|| joint_fit::fit(&names, image.as_deref(), &obs))
                .flatten()
        });
        let Some((slot, named)) = slot(m, &at) else { continue };
        for n in &depends {
            if !named.contains(n) {
                named.push(n.clone());
            }
        }
        if let Some(e) = e {
            *slot = Some(e);
            fitted += 1;
        }
    }
    if let Some(last) = m.frame_passes.last() {
        m.passes = last.clone();
    }
    (follow, fitted)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_count_that_follows_a_setting_is_fitted_in_its_name() {
        assert_eq!(nearby(7, 1.0, 16.0), [3, 14, 1, 8, 9, 6, 5]);
        assert_eq!(nearby(1, 1.0, 4.0), [2, 3], "no half: double and triple");
        assert_eq!(nearby(12, 1.0, 16.0), [6, 3, 13, 14, 11, 10], "no double: half and a quarter");
        assert_eq!(nearby(16, 9.0, 16.0), [15, 14], "the top of the range: the two below");
        assert_eq!(nearby(1, 1.0, 1.0), Vec::<u32>::new());
        let pts = |f: fn(u64) -> u64| [1024u64, 1025, 1026].map(|s| (s, f(s)));
        assert_eq!(fit("vpl.count", &pts(|s| 32 * s)).as_deref(), Some("32 * vpl.count"));
        assert_eq!(fit("vpl.count", &pts(|s| s.div_ceil(64))).as_deref(), Some("ceil(vpl.count / 64)"));
        assert_eq!(fit("ism.size", &pts(|s| 4 * s * s)).as_deref(), Some("4 * (ism.size * ism.size)"));
        assert_eq!(fit("vpl.count", &pts(|s| 16 * s + 16)).as_deref(), Some("16 * vpl.count + 16"));
        // A capacity of at least 256 VPLs, seen at half and double the preset's 256.
        let floor = [128u64, 256, 512].map(|s| (s, 80 * s.max(256)));
        assert_eq!(fit("vpl.count", &floor).as_deref(), Some("80 * max(256, vpl.count)"));
    }
}
