//! Sizes and counts that follow a setting (issue #54 point 1; docs/port-kit.md, "Sizes that
//! follow a setting"). After the image probes ([`super::expressions`]), the frame is captured
//! once more at the first probe size for each integer setting of the groups the stage choices
//! use, set to each of two other values (half and double, or as near as its range allows; a
//! variant the settings' rules refuse is skipped). Every texture dimension, buffer
//! size and dispatch or draw count that changes with the setting names it in `depends_on`;
//! where it follows that one setting alone and not the image, it is fitted over the three
//! values by `a * g(S) + b` with `g` the setting `S`, its square, a tiling `ceil(S / d)` or a
//! floor `max(m, S)`, and that expression (`256 * ism.points`) replaces the constant.

use super::expressions::{affine_text, solve_linear, step_numbers};
use super::manifest::Manifest;
use crate::LabSettings;
use crate::settings::{FieldKind, Value};

/// An integer setting and the settings with it at two other values.
pub struct Variant {
    pub path: String,
    pub value: u32,
    pub others: Vec<(u32, LabSettings)>,
}

/// Two other values of an integer setting within `[min, max]`, spread so that a floor or a
/// ceiling shows: half and double, else double and triple, else the next two, else the two
/// below.
fn nearby(v: u32, min: f64, max: f64) -> Vec<u32> {
    let v = v as u64;
    let ok = |x: u64| x >= 1 && x != v && (x as f64) >= min && (x as f64) <= max;
    for pick in [[v / 2, 2 * v], [2 * v, 3 * v], [v + 1, v + 2], [v.saturating_sub(1), v.saturating_sub(2)]] {
        if pick.iter().all(|&x| ok(x)) && pick[0] != pick[1] {
            return pick.iter().map(|&x| x as u32).collect();
        }
    }
    Vec::new()
}

/// Every integer setting of the groups `s`'s stage choices use, with two nearby values whose
/// settings validate;
/// `only`: these settings alone (a test's), None: all.
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
            if others.len() == 2 {
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

/// Writes `depends_on` and the settings' expressions into `m` from the manifest of the base
/// settings at the first probe size (`base`) and those of each variant (`captured`: per
/// variant, per other value, its manifest at that size). Returns how many numbers follow a
/// setting and how many of those got an expression of it.
pub fn annotate(m: &mut Manifest, base: &Manifest, captured: &[(&Variant, Vec<Manifest>)]) -> (usize, usize) {
    let (mut following, mut fitted) = (0, 0);
    for r in &mut m.resources {
        let Some(b) = base.resources.iter().find(|x| x.name == r.name) else { continue };
        let mut depends: Vec<(usize, String, Option<String>)> = Vec::new();
        for (v, manifests) in captured {
            for (k, &q0) in b.size.iter().enumerate() {
                let mut points = vec![(v.value as u64, q0)];
                for ((x, _), mm) in v.others.iter().zip(manifests) {
                    if let Some(q) = mm.resources.iter().find(|y| y.name == r.name).and_then(|y| y.size.get(k)) {
                        points.push((*x as u64, *q));
                    }
                }
                if points.len() == 3 && points.iter().any(|p| p.1 != q0) {
                    depends.push((k, v.path.clone(), fit(&v.path, &points)));
                }
            }
        }
        for (k, path, e) in &depends {
            following += 1;
            if !r.depends_on.contains(path) {
                r.depends_on.push(path.clone());
            }
            // One setting alone, and not the image: the setting's expression.
            let alone = depends.iter().filter(|d| d.0 == *k).count() == 1;
            let constant = r.size_expr.get(*k).and_then(|x| x.as_ref()).is_some_and(|x| x.parse::<u64>().is_ok());
            if let (true, true, Some(e)) = (alone, constant, e) {
                r.size_expr[*k] = Some(e.clone());
                fitted += 1;
            }
        }
    }
    let frames = m.frame_passes.len();
    for k in 0..frames {
        for pi in 0..m.frame_passes[k].len() {
            for si in 0..m.frame_passes[k][pi].steps.len() {
                let name = m.frame_passes[k][pi].name.clone();
                let find = |mm: &Manifest| -> Option<Vec<u64>> {
                    let f = mm.frame_passes.get(k.min(mm.frame_passes.len().saturating_sub(1)))?;
                    let pass = f.get(pi).filter(|x| x.name == name)?;
                    let step = pass.steps.get(si)?;
                    let mine = &m.frame_passes[k][pi].steps[si];
                    (step.kind == mine.kind && step.pipeline == mine.pipeline).then(|| step_numbers(step))
                };
                let Some(n0) = find(base) else { continue };
                let mut depends: Vec<(usize, String, Option<String>)> = Vec::new();
                for (v, manifests) in captured {
                    let others: Vec<Option<Vec<u64>>> = manifests.iter().map(find).collect();
                    for (i, &q0) in n0.iter().enumerate() {
                        let mut points = vec![(v.value as u64, q0)];
                        for ((x, _), o) in v.others.iter().zip(&others) {
                            if let Some(q) = o.as_ref().and_then(|o| o.get(i)) {
                                points.push((*x as u64, *q));
                            }
                        }
                        if points.len() == 3 && points.iter().any(|p| p.1 != q0) {
                            depends.push((i, v.path.clone(), fit(&v.path, &points)));
                        }
                    }
                }
                let step = &mut m.frame_passes[k][pi].steps[si];
                for (i, path, e) in &depends {
                    following += 1;
                    if !step.counts_depend_on.contains(path) {
                        step.counts_depend_on.push(path.clone());
                    }
                    let alone = depends.iter().filter(|d| d.0 == *i).count() == 1;
                    let constant =
                        step.counts_expr.get(*i).and_then(|x| x.as_ref()).is_some_and(|x| x.parse::<u64>().is_ok());
                    if let (true, true, Some(e)) = (alone, constant, e) {
                        step.counts_expr[*i] = Some(e.clone());
                        fitted += 1;
                    }
                }
            }
        }
    }
    if let Some(last) = m.frame_passes.last() {
        m.passes = last.clone();
    }
    (following, fitted)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_count_that_follows_a_setting_is_fitted_in_its_name() {
        assert_eq!(nearby(7, 1.0, 16.0), [3, 14]);
        assert_eq!(nearby(1, 1.0, 4.0), [2, 3], "no half: double and triple");
        assert_eq!(nearby(12, 1.0, 16.0), [13, 14], "no double: the next two");
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
