//! Sizes and counts that follow several settings at once, or a setting and the image (issue
//! #54 point 1; docs/port-kit.md, "Sizes that follow several settings"). The ISM atlas holds
//! one map per VPL and bounce, `ceil(sqrt(n))` maps a row: its width is
//! `ceil(sqrt(vpl.count * vpl.bounces)) * ism.map_size`, and Gautron et al.'s record creation
//! tiles the image by `gautron.creation_tile_px`. Such a number is captured at the preset's
//! settings, with each setting it follows at two other values alone, and with all of them
//! changed together at two other image sizes ([`super::settings_probe`]); an expression is
//! kept only if it gives every one of those captures exactly.
//!
//! Two families:
//! - a number that follows only settings: `a * ceil(G / d) + b`, `G` the product of one
//!   factor per setting (`S` or `S * S`) or of a group of them `P = S1 * S2 …` as a grid's
//!   columns `ceil(sqrt(P))`, rows `ceil(P / ceil(sqrt(P)))`, both, or a capacity
//!   `max(m, P)`, and the other settings' factors;
//! - a number that follows the image too: its expression of W and H with a constant that
//!   equals a setting's value at the preset replaced by the setting (`ceil(W / 8)` becomes
//!   `ceil(W / gautron.creation_tile_px)`).

use super::expressions::{affine_text, eval_with, solve_linear};

/// One capture of a number: the image, the values of the settings it follows (in the order
/// of [`fit`]'s `names`) and the number.
#[derive(Clone, Debug, PartialEq)]
pub struct Obs {
    pub w: u64,
    pub h: u64,
    pub s: Vec<u64>,
    pub q: u64,
}

/// `G` of the settings' values (in the order of the names).
type OfSettings = Box<dyn Fn(&[u64]) -> u64>;
/// A form of the product of a group of settings (`ceil(sqrt(P))`), shared by the factors
/// built on it.
type OfProduct = std::rc::Rc<dyn Fn(u64) -> u64>;

/// `G` of the settings' values, with its text.
struct Factor {
    text: String,
    f: OfSettings,
}

/// The simplest expression through every observation; `names`: the settings the number
/// follows; `image`: its expression of W and H at the preset's settings where it is not a
/// constant; `obs[0]` is the capture at the preset's settings. None: no expression of the two
/// families fits.
pub fn fit(names: &[String], image: Option<&str>, obs: &[Obs]) -> Option<String> {
    let base = obs.first()?;
    let found = match image {
        Some(e) => substituted(names, e, &base.s, obs),
        None => in_settings(names, obs),
    }?;
    // What the manifest says is what was checked: the text evaluates to every capture.
    obs.iter().all(|o| evaluate(&found, names, o) == Some(o.q)).then_some(found)
}

fn evaluate(e: &str, names: &[String], o: &Obs) -> Option<u64> {
    let setting = |n: &str| names.iter().position(|x| x == n).map(|i| o.s[i] as f64);
    eval_with(e, o.w, o.h, &setting)
}

/// The family of numbers that follow settings alone, simplest first.
fn factors(names: &[String]) -> Vec<Factor> {
    let n = names.len();
    let mut out = Vec::new();
    // Every setting alone (`S` or `S * S`), then a group of them as a grid or a capacity.
    for group in 0u32..(1 << n) {
        let members: Vec<usize> = (0..n).filter(|i| group & (1 << i) != 0).collect();
        let rest: Vec<usize> = (0..n).filter(|i| group & (1 << i) == 0).collect();
        let p_text = members.iter().map(|&i| names[i].clone()).collect::<Vec<_>>().join(" * ");
        let product = {
            let m = members.clone();
            move |s: &[u64]| m.iter().map(|&i| s[i]).product::<u64>()
        };
        let mut forms: Vec<(String, OfProduct)> = Vec::new();
        if members.is_empty() {
            forms.push((String::new(), std::rc::Rc::new(|_| 1)));
        } else {
            let cols = |p: u64| (p as f64).sqrt().ceil() as u64;
            forms.push((format!("ceil(sqrt({p_text}))"), std::rc::Rc::new(cols)));
            forms.push((
                format!("ceil({p_text} / ceil(sqrt({p_text})))"),
                std::rc::Rc::new(move |p| p.div_ceil(cols(p).max(1))),
            ));
            forms.push((
                format!("ceil(sqrt({p_text})) * ceil({p_text} / ceil(sqrt({p_text})))"),
                std::rc::Rc::new(move |p| cols(p) * p.div_ceil(cols(p).max(1))),
            ));
            for k in 0..=16 {
                let m = 1u64 << k;
                forms.push((format!("max({m}, {p_text})"), std::rc::Rc::new(move |p| p.max(m))));
            }
        }
        // Each other setting as `S` or `S * S`.
        for squares in 0u32..(1 << rest.len()) {
            let powers: Vec<(usize, u32)> =
                rest.iter().enumerate().map(|(j, &i)| (i, if squares & (1 << j) != 0 { 2 } else { 1 })).collect();
            for (form_text, form) in &forms {
                let mut parts: Vec<String> = Vec::new();
                if !form_text.is_empty() {
                    parts.push(form_text.clone());
                }
                for &(i, e) in &powers {
                    parts.push(if e == 2 { format!("{} * {}", names[i], names[i]) } else { names[i].clone() });
                }
                let (form, powers, product) = (form.clone(), powers.clone(), product.clone());
                out.push(Factor {
                    text: parts.join(" * "),
                    f: Box::new(move |s| form(product(s)) * powers.iter().map(|&(i, e)| s[i].pow(e)).product::<u64>()),
                });
            }
        }
    }
    out
}

/// `a * ceil(G / d) + b` over [`factors`] (b = 0 first, then d = 1 first), if every
/// expression of another `G` that gives the captures agrees with it between them (at settings
/// within the range of those captured): two that part there (a grid's rows and its columns,
/// seen only where they are equal) are not told apart, and neither is kept.
fn in_settings(names: &[String], obs: &[Obs]) -> Option<String> {
    if names.is_empty() {
        return None;
    }
    let family = factors(names);
    let q: Vec<i128> = obs.iter().map(|o| o.q as i128).collect();
    let mut found: Vec<(String, i128, i128, u64, &Factor)> = Vec::new();
    for offset in [false, true] {
        for d in (0..=12).map(|k| 1u64 << k) {
            for g in &family {
                let gs: Vec<i128> = obs.iter().map(|o| ((g.f)(&o.s)).div_ceil(d) as i128).collect();
                if let Some((a, c)) = solve_linear(&gs, &q, offset) {
                    let (text, compound) = if d == 1 {
                        (g.text.clone(), top_level_product(&g.text))
                    } else {
                        (format!("ceil({} / {d})", g.text), false)
                    };
                    found.push((affine_text(text, compound, a, c), a, c, d, g));
                }
            }
        }
    }
    let (first, rest) = found.split_first()?;
    let value = |(_, a, c, d, g): &(String, i128, i128, u64, &Factor), s: &[u64]| a * (g.f)(s).div_ceil(*d) as i128 + c;
    // Of one `G`, the first (b = 0, the finest tiling) is taken: a coarser tiling that the
    // captures happen to fill (`2 * ceil(G / 2)` of even values) is not a second structure.
    let rest: Vec<_> = rest.iter().filter(|f| !std::ptr::eq(f.4, first.4)).collect();
    for s in between(names, obs) {
        if rest.iter().any(|f| value(f, &s) != value(first, &s)) {
            return None;
        }
    }
    Some(first.0.clone())
}

/// Settings between the captured ones: 256 points, each setting drawn within the range of its
/// captured values, a power of two where the settings' rules want one (a fixed sequence, so
/// an export is reproducible).
fn between(names: &[String], obs: &[Obs]) -> Vec<Vec<u64>> {
    let n = obs.first().map_or(0, |o| o.s.len());
    let lo: Vec<u64> = (0..n).map(|i| obs.iter().map(|o| o.s[i]).min().unwrap_or(1)).collect();
    let hi: Vec<u64> = (0..n).map(|i| obs.iter().map(|o| o.s[i]).max().unwrap_or(1)).collect();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        state >> 33
    };
    let pow2: Vec<bool> =
        names.iter().map(|n| crate::lab_settings::POWER_OF_TWO_FIELDS.contains(&n.as_str())).collect();
    let draw = |i: usize, r: u64| {
        if pow2[i] && lo[i].is_power_of_two() {
            let (a, b) = (lo[i].ilog2() as u64, hi[i].max(1).ilog2() as u64);
            1 << (a + r % (b - a + 1))
        } else {
            lo[i] + r % (hi[i] - lo[i] + 1)
        }
    };
    (0..256).map(|_| (0..n).map(|i| draw(i, next())).collect()).collect()
}

/// Whether `e` is a product outside any parentheses (`a * b`, not `max(1, a * b)`).
fn top_level_product(e: &str) -> bool {
    let mut depth = 0i32;
    for c in e.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            '*' if depth == 0 => return true,
            _ => {}
        }
    }
    false
}

/// The integer constants of `e`: (start, end, value) of each.
fn constants(e: &str) -> Vec<(usize, usize, u64)> {
    let b = e.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let part_of_name = |k: usize| b[k].is_ascii_alphanumeric() || b[k] == b'_' || b[k] == b'.';
        if b[i].is_ascii_digit() && (i == 0 || !part_of_name(i - 1)) {
            let start = i;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            if let Ok(v) = e[start..i].parse() {
                out.push((start, i, v));
            }
        } else {
            i += 1;
        }
    }
    out
}

/// `e` with each constant that equals a setting's value at the preset (`base`) replaced by
/// the setting or kept, every choice but keeping them all; the first that gives every capture.
fn substituted(names: &[String], e: &str, base: &[u64], obs: &[Obs]) -> Option<String> {
    let consts = constants(e);
    // The distinct values that some setting has, each with its choices (keep, or a setting).
    let mut values: Vec<(u64, Vec<Option<usize>>)> = Vec::new();
    for &(_, _, v) in &consts {
        let settings: Vec<usize> = (0..names.len()).filter(|&i| base[i] == v).collect();
        if !settings.is_empty() && !values.iter().any(|x| x.0 == v) {
            values.push((v, std::iter::once(None).chain(settings.into_iter().map(Some)).collect()));
        }
    }
    let combos: usize = values.iter().map(|v| v.1.len()).product();
    for mut k in 1..combos.min(4096) {
        let mut choice: Vec<(u64, Option<usize>)> = Vec::new();
        for (v, options) in &values {
            choice.push((*v, options[k % options.len()]));
            k /= options.len();
        }
        let mut text = String::new();
        let mut at = 0;
        for &(start, end, v) in &consts {
            text.push_str(&e[at..start]);
            match choice.iter().find(|c| c.0 == v).and_then(|c| c.1) {
                Some(i) => text.push_str(&names[i]),
                None => text.push_str(&e[start..end]),
            }
            at = end;
        }
        text.push_str(&e[at..]);
        if obs.iter().all(|o| evaluate(&text, names, o) == Some(o.q)) {
            return Some(text);
        }
    }
    None
}

/// A term of a loop's count ([`fit_count`]): its text and value.
type Term = (String, Box<dyn Fn(&Obs) -> i64>);

/// The terms of a loop's count: each setting `S`, `floor(log2(S))` (a pyramid over it) or
/// `ceil(S / d)` (batches), and a pyramid over the image.
fn count_terms(names: &[String]) -> (Vec<Term>, Vec<Term>) {
    let log2 = |x: u64| x.max(1).ilog2() as i64;
    let mut settings: Vec<Term> = Vec::new();
    for (i, n) in names.iter().enumerate() {
        settings.push((n.clone(), Box::new(move |o: &Obs| o.s[i] as i64)));
        settings.push((format!("floor(log2({n}))"), Box::new(move |o: &Obs| log2(o.s[i]))));
        for d in [2u64, 4, 8, 16, 32, 64] {
            settings.push((format!("ceil({n} / {d})"), Box::new(move |o: &Obs| o.s[i].div_ceil(d) as i64)));
        }
    }
    let image: Vec<Term> = vec![
        ("floor(log2(W))".into(), Box::new(move |o: &Obs| log2(o.w))),
        ("floor(log2(H))".into(), Box::new(move |o: &Obs| log2(o.h))),
        ("floor(log2(min(W, H)))".into(), Box::new(move |o: &Obs| log2(o.w.min(o.h)))),
        ("floor(log2(max(W, H)))".into(), Box::new(move |o: &Obs| log2(o.w.max(o.h)))),
        (
            "ceil(log2(max(W, H)))".into(),
            Box::new(move |o: &Obs| o.w.max(o.h).max(1).next_power_of_two().ilog2() as i64),
        ),
    ];
    (settings, image)
}

fn plus(text: &str, b: i64) -> String {
    match b {
        0 => text.to_string(),
        b if b > 0 => format!("{text} + {b}"),
        b => format!("{text} - {}", -b),
    }
}

/// A loop's count (how many steps of one pipeline run one after another) through every
/// capture: a constant; a term plus a constant (`hcb.levels - 1`,
/// `floor(log2(vpl.light_gbuffer_size))`); or the smaller of two (a pyramid's levels, at
/// most as many as the image or the map has: `min(ism.pull_push_levels,
/// floor(log2(ism.map_size)))`). Every setting in `names` must appear.
pub fn fit_count(names: &[String], obs: &[Obs]) -> Option<String> {
    let first = obs.first()?.q;
    if names.is_empty() && obs.iter().all(|o| o.q == first) {
        return Some(first.to_string());
    }
    let (settings, image) = count_terms(names);
    let uses_all = |text: &str| names.iter().all(|n| text.contains(n.as_str()));
    let q: Vec<i64> = obs.iter().map(|o| o.q as i64).collect();
    let terms: Vec<&Term> = settings.iter().chain(&image).collect();
    // One term plus a constant.
    for (text, f) in &terms {
        let b = q[0] - f(&obs[0]);
        if uses_all(text) && obs.iter().zip(&q).all(|(o, q)| f(o) + b == *q) {
            return Some(plus(text, b));
        }
    }
    // The smaller of two.
    for (i, (t1, f1)) in terms.iter().enumerate() {
        for (t2, f2) in &terms[i + 1..] {
            if !uses_all(&format!("{t1} {t2}")) {
                continue;
            }
            for b1 in -3..=3 {
                for b2 in -3..=3 {
                    if obs.iter().zip(&q).all(|(o, q)| (f1(o) + b1).min(f2(o) + b2) == *q) {
                        return Some(format!("min({}, {})", plus(t1, b1), plus(t2, b2)));
                    }
                }
            }
        }
    }
    None
}

/// One iteration of a loop in one capture: the image, the settings' values (in the order of
/// [`fit_iteration`]'s names), the loop's count `n`, the iteration `i` and its number.
#[derive(Clone, Debug)]
pub struct IterObs {
    pub o: Obs,
    pub n: u64,
    pub i: u64,
}

/// `i` (ascending) or `n - 1 - i` (descending) plus `s0`, as written.
fn exponent(desc: bool, s0: i64) -> String {
    match (desc, s0) {
        (false, 0) => "i".into(),
        (false, s) => format!("i + {s}"),
        (true, s) => plus("n - i", s - 1),
    }
}

/// A loop's iterations' number (a dispatch's workgroups along one axis) through every
/// iteration of every capture: a constant, or a level of a pyramid over W, H or a setting
/// that each iteration halves or doubles — `ceil(X / exp2(i + s))` or
/// `max(1, floor(X / exp2(i + s)))`, `i` counted from the first iteration or (`n - i - 1`)
/// from the last — tiled by `d` (`ceil(… / 8)`).
pub fn fit_iteration(names: &[String], obs: &[IterObs]) -> Option<String> {
    let first = obs.first()?.o.q;
    if obs.iter().all(|x| x.o.q == first) {
        return Some(first.to_string());
    }
    let axes: Vec<String> = ["W".to_string(), "H".to_string()].into_iter().chain(names.iter().cloned()).collect();
    let value_of = |axis: usize, x: &IterObs| match axis {
        0 => x.o.w,
        1 => x.o.h,
        k => x.o.s[k - 2],
    };
    for d in [1u64, 8, 16, 4, 2, 32, 64, 128, 256] {
        for (axis, axis_name) in axes.iter().enumerate() {
            for desc in [false, true] {
                for s0 in 0..=10i64 {
                    for ceil in [true, false] {
                        let fits = obs.iter().all(|x| {
                            let s = if desc { x.n as i64 - 1 - x.i as i64 + s0 } else { x.i as i64 + s0 };
                            if !(0..63).contains(&s) {
                                return false;
                            }
                            let v = value_of(axis, x);
                            let level = if ceil { v.div_ceil(1 << s) } else { (v >> s).max(1) };
                            level.div_ceil(d) == x.o.q
                        });
                        if fits {
                            let e = exponent(desc, s0);
                            let level = if ceil {
                                format!("ceil({axis_name} / exp2({e}))")
                            } else {
                                format!("max(1, floor({axis_name} / exp2({e})))")
                            };
                            return Some(if d == 1 { level } else { format!("ceil({level} / {d})") });
                        }
                    }
                }
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(n: &[&str]) -> Vec<String> {
        n.iter().map(|s| s.to_string()).collect()
    }

    /// The captures `settings_probe` makes: the preset's values, each setting at two others
    /// and a neighbour alone, all of them together twice (at the first two others).
    fn captures(base: &[u64], others: &[&[u64]], f: impl Fn(u64, u64, &[u64]) -> u64) -> Vec<Obs> {
        let mut sets = vec![(320, 180, base.to_vec())];
        for (i, o) in others.iter().enumerate() {
            for &x in *o {
                let mut s = base.to_vec();
                s[i] = x;
                sets.push((67, 41, s));
            }
        }
        for (j, size) in [(160, 103), (217, 133)].into_iter().enumerate() {
            sets.push((size.0, size.1, others.iter().map(|o| o[j]).collect()));
        }
        sets.into_iter().map(|(w, h, s)| Obs { w, h, q: f(w, h, &s), s }).collect()
    }

    #[test]
    fn a_number_of_several_settings_or_of_a_setting_and_the_image_is_fitted_over_every_capture() {
        // The ISM atlas: ceil(sqrt(n)) maps a row of n = VPLs × bounces maps of size².
        let cols = |n: u64| (n as f64).sqrt().ceil() as u64;
        let n = names(&["vpl.count", "vpl.bounces", "ism.map_size"]);
        let others: [&[u64]; 3] = [&[128, 512, 257], &[2, 3], &[64, 256]];
        let width = captures(&[256, 1, 128], &others, |_, _, s| cols(s[0] * s[1]) * s[2]);
        assert_eq!(fit(&n, None, &width).as_deref(), Some("ceil(sqrt(vpl.count * vpl.bounces)) * ism.map_size"));
        let rows = |n: u64| n.div_ceil(cols(n));
        let splat =
            captures(&[256, 1, 128], &others, |_, _, s| 4 * cols(s[0] * s[1]) * rows(s[0] * s[1]) * s[2] * s[2]);
        let e = fit(&n, None, &splat).expect("the splat buffer fits");
        assert_eq!(
            e,
            "4 * (ceil(sqrt(vpl.count * vpl.bounces)) * ceil(vpl.count * vpl.bounces / ceil(sqrt(vpl.count * \
             vpl.bounces))) * ism.map_size * ism.map_size)"
        );
        // A count of workgroups over the atlas, and a capacity with a floor.
        let pull = captures(&[256, 1, 128], &others, |_, _, s| (cols(s[0] * s[1]) * s[2]).div_ceil(16));
        assert_eq!(
            fit(&n, None, &pull).as_deref(),
            Some("ceil(ceil(sqrt(vpl.count * vpl.bounces)) * ism.map_size / 16)")
        );
        let two = names(&["vpl.count", "vpl.bounces"]);
        let list = captures(&[256, 1], &[&[128, 512, 257], &[2, 3]], |_, _, s| 80 * (s[0] * s[1]).max(256));
        assert_eq!(fit(&two, None, &list).as_deref(), Some("80 * max(256, vpl.count * vpl.bounces)"));
        // A tiling of the image by a setting's tiles.
        let tile = names(&["gautron.creation_tile_px"]);
        let tiles = captures(&[8], &[&[4, 16]], |w, _, s| w.div_ceil(s[0]));
        assert_eq!(fit(&tile, Some("ceil(W / 8)"), &tiles).as_deref(), Some("ceil(W / gautron.creation_tile_px)"));
        // A grid's rows seen only where they equal its columns: the two are not told apart.
        let square = names(&["vpl.count"]);
        let pts = [1024u64, 512, 256].map(|c| Obs { w: 67, h: 41, s: vec![c], q: c.div_ceil(cols(c)) });
        assert_eq!(fit(&square, None, &pts), None, "rows or columns");
        let mut pts = pts.to_vec();
        pts.push(Obs { w: 67, h: 41, s: vec![1025], q: 32 });
        assert_eq!(fit(&square, None, &pts).as_deref(), Some("ceil(vpl.count / ceil(sqrt(vpl.count)))"));
        // Not in either family: nothing, rather than a formula that only the captures agree with.
        let odd = captures(&[256, 1], &[&[128, 512, 257], &[2, 3]], |_, _, s| s[0] % 7 + s[1]);
        assert_eq!(fit(&two, None, &odd), None);
        assert_eq!(fit(&tile, Some("ceil(W / 8)"), &captures(&[8], &[&[4, 16]], |w, _, _| w.div_ceil(8) + 1)), None);
        assert_eq!(constants("max(1, floor(H / 64)) * vpl.count2 + 128"), [(4, 5, 1), (17, 19, 64), (37, 40, 128)]);
        // Loops: a pyramid's levels over a setting, and at most as many as its map has.
        let levels = names(&["hcb.levels"]);
        let runs = captures(&[7], &[&[3, 8, 6]], |_, _, s| s[0] - 1);
        assert_eq!(fit_count(&levels, &runs).as_deref(), Some("hcb.levels - 1"));
        let pp = names(&["ism.map_size", "ism.pull_push_levels"]);
        let runs = captures(&[64, 2], &[&[32, 128], &[1, 4, 8]], |_, _, s| s[1].min(s[0].ilog2() as u64));
        let e = fit_count(&pp, &runs).expect("the pull-push levels");
        assert_eq!(e, "min(floor(log2(ism.map_size)), ism.pull_push_levels)");
        for o in &runs {
            assert_eq!(evaluate(&e, &pp, o), Some(o.q));
        }
        assert_eq!(fit_count(&[], &captures(&[], &[], |_, _, _| 8)).as_deref(), Some("8"));
        // A loop's iterations: the HCB's levels built coarse to fine, 8×8 pixels a workgroup.
        let iterations = |f: &dyn Fn(u64, u64, u64, u64) -> u64| -> Vec<IterObs> {
            let mut out = Vec::new();
            for (w, h, n) in [(64u64, 36u64, 6u64), (217, 133, 6), (160, 41, 2), (99, 57, 7)] {
                for i in 0..n {
                    out.push(IterObs { o: Obs { w, h, s: vec![n + 1], q: f(w, h, n, i) }, n, i });
                }
            }
            out
        };
        let mask = iterations(&|w, _, n, i| w.div_ceil(1 << (n - i)).div_ceil(8));
        let e = fit_iteration(&levels, &mask).expect("the mask's levels");
        assert_eq!(e, "ceil(W / exp2(n - i + 3))", "the tiling by 8 is three more halvings");
        for x in &mask {
            let v = |k: &str| match k {
                "i" => Some(x.i as f64),
                "n" => Some(x.n as f64),
                _ => None,
            };
            assert_eq!(eval_with(&e, x.o.w, x.o.h, &v), Some(x.o.q), "{x:?}");
        }
        let light = iterations(&|_, _, _, i| (256u64 >> (i + 4)).max(1));
        assert_eq!(fit_iteration(&levels, &light), None, "no W, H or hcb.levels gives it");
    }
}
