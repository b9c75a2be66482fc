//! The frame's loops (issue #54 point 1; docs/port-kit.md, "Loops"): dispatches of one
//! pipeline one after another (a pyramid built level by level) and passes repeated per level
//! or round (`soler.gather.k`, each round of Gautron et al.'s record creation). Their counts
//! are fitted to W, H and the settings ([`joint_fit::fit_count`]) and a loop's iterations'
//! workgroups to the iteration ([`joint_fit::fit_iteration`]), over the captures of
//! [`super::settings_probe`].

use super::expressions::step_numbers;
use super::joint_fit::{self, Obs};
use super::manifest::{Manifest, PassRepeat, Run, runs_of};
use super::settings_probe::{self, Captured};

/// The iterations of the run `run` of pass `pass` of frame `frame` of `m` in `other`, each
/// as its step's numbers: the pass by name and occurrence, the run by pipeline and
/// occurrence; none where the pass has no such run (a loop of no levels), None where it has
/// no such pass.
fn run_in(m: &Manifest, (frame, pass, run): (usize, usize, usize), other: &Manifest) -> Option<Vec<Vec<u64>>> {
    let (mine, p) = settings_probe::same_pass(m, frame, pass, other)?;
    let r = mine.runs.get(run)?;
    let same = |x: &Run| x.kind == r.kind && x.pipeline == r.pipeline;
    let nth = runs_of(&mine.steps, true).into_iter().filter(same).position(|x| x.first == r.first)?;
    let Some(there) = runs_of(&p.steps, true).into_iter().filter(same).nth(nth) else { return Some(Vec::new()) };
    Some(p.steps[there.first..there.first + there.count as usize].iter().map(step_numbers).collect())
}

/// Writes each pass's loops (`runs`) and the passes repeated (`repeated_passes`) into `m`.
pub fn annotate(m: &mut Manifest, c: &Captured) {
    annotate_runs(m, c);
    if let Some(last) = m.frame_passes.last() {
        m.passes = last.clone();
    }
    m.repeated_passes = repeated_passes(m, c);
}

/// Each loop's count as an expression of W, H and the settings it follows
/// ([`joint_fit::fit_count`]), and its iterations' workgroups as expressions of the iteration
/// ([`joint_fit::fit_iteration`]), over the kit, the image probes and the settings' variants.
fn annotate_runs(m: &mut Manifest, c: &Captured) {
    let (kw, kh) = (m.size[0] as u64, m.size[1] as u64);
    let (w0, h0) = (c.images[settings_probe::AT].0.0 as u64, c.images[settings_probe::AT].0.1 as u64);
    for frame in 0..m.frame_passes.len() {
        for pass in 0..m.frame_passes[frame].len() {
            // Every group of dispatches, a loop of one level among them; those that are not
            // loops (one, whatever the image and the settings) are left out after.
            let p = &mut m.frame_passes[frame][pass];
            p.runs = runs_of(&p.steps, true);
            for run in 0..m.frame_passes[frame][pass].runs.len() {
                let at = (frame, pass, run);
                let p = &m.frame_passes[frame][pass];
                let r = &p.runs[run];
                let mine: Vec<Vec<u64>> =
                    p.steps[r.first..r.first + r.count as usize].iter().map(step_numbers).collect();
                let mut names = Vec::new();
                for (var, manifests) in &c.variants {
                    if manifests.iter().any(|(_, mm)| run_in(m, at, mm).is_none_or(|x| x.len() != mine.len())) {
                        names.push(var.path.clone());
                    }
                }
                names.sort();
                // The iterations' numbers also follow what their steps follow.
                let mut iter_names = names.clone();
                for st in &p.steps[r.first..r.first + r.count as usize] {
                    iter_names.extend(st.counts_depend_on.iter().cloned());
                }
                iter_names.sort();
                iter_names.dedup();
                // Every capture of the loop: its image, the settings changed and its iterations.
                let mut captures = vec![(kw, kh, None, mine)];
                let mut whole = true;
                for ((w, h), mm) in c.images {
                    match run_in(m, at, mm) {
                        Some(x) => captures.push((*w as u64, *h as u64, None, x)),
                        None => whole = false,
                    }
                }
                for (var, manifests) in c.variants.iter().filter(|(v, _)| iter_names.contains(&v.path)) {
                    for (x, mm) in manifests {
                        match run_in(m, at, mm) {
                            Some(its) => captures.push((w0, h0, Some((var.path.as_str(), *x)), its)),
                            None => whole = false,
                        }
                    }
                }
                let count_obs: Vec<Obs> = captures
                    .iter()
                    .filter(|(_, _, x, _)| x.is_none_or(|(v, _)| names.iter().any(|n| n == v)))
                    .map(|(w, h, x, its)| Obs { w: *w, h: *h, s: c.values(&names, *x), q: its.len() as u64 })
                    .collect();
                let count_expr = if whole { joint_fit::fit_count(&names, &count_obs) } else { None };
                let axes = captures[0].3.first().map_or(0, Vec::len);
                let mut iteration_expr = Vec::new();
                for k in 0..axes {
                    let mut obs = Vec::new();
                    for (w, h, x, its) in &captures {
                        let n = its.len() as u64;
                        for (i, numbers) in its.iter().enumerate() {
                            let s = c.values(&iter_names, *x);
                            let q = numbers.get(k).copied().unwrap_or(0);
                            obs.push(joint_fit::IterObs { o: Obs { w: *w, h: *h, s, q }, n, i: i as u64 });
                        }
                    }
                    iteration_expr.push(if whole { joint_fit::fit_iteration(&iter_names, &obs) } else { None });
                }
                let r = &mut m.frame_passes[frame][pass].runs[run];
                r.count_expr = count_expr;
                r.depends_on = names;
                r.iteration_expr = iteration_expr;
            }
            let runs = &mut m.frame_passes[frame][pass].runs;
            runs.retain(|r| r.count > 1 || r.count_expr.as_deref().is_some_and(|e| e != "1"));
        }
    }
}

/// A pass's name with a level's number at its end written `{k}` (`soler.gather.{k}`), and the
/// number; the name itself otherwise.
fn pattern(name: &str) -> (String, Option<u64>) {
    match name.rsplit_once('.') {
        Some((stem, k)) if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) => {
            (format!("{stem}.{{k}}"), k.parse().ok())
        }
        _ => (name.to_string(), None),
    }
}

/// The passes of `passes` named by `pat`: how many, and the first level's number.
fn repeats(passes: &[super::manifest::Pass], pat: &str) -> (u64, Option<u64>) {
    let ks: Vec<Option<u64>> = passes.iter().map(|p| pattern(&p.name)).filter(|x| x.0 == pat).map(|x| x.1).collect();
    (ks.len() as u64, ks.iter().flatten().min().copied())
}

/// A quantity of passes repeated, of their (count, first level's number).
type Quantity = dyn Fn(&(u64, Option<u64>)) -> Option<u64>;

/// The passes of the last frame that repeat — one name several times (a round each), or one
/// name but a level's number (a pass per level) — with how many and, for levels, the first
/// level's number as expressions of W, H and the settings, fitted over every capture.
fn repeated_passes(m: &Manifest, c: &Captured) -> Vec<PassRepeat> {
    let mut out: Vec<PassRepeat> = Vec::new();
    let (kw, kh) = (m.size[0] as u64, m.size[1] as u64);
    let (w0, h0) = (c.images[settings_probe::AT].0.0 as u64, c.images[settings_probe::AT].0.1 as u64);
    let last = |mm: &Manifest| mm.frame_passes.last().cloned().unwrap_or_default();
    for p in m.passes.iter().filter(|p| p.role != "between") {
        let (pat, k) = pattern(&p.name);
        if out.iter().any(|r| r.name == pat) {
            continue;
        }
        let (count, first) = repeats(&m.passes, &pat);
        if count < 2 && k.is_none() {
            continue;
        }
        // Every capture's count and first level: the image probes, each setting's values.
        let mut seen = vec![(kw, kh, None, (count, first))];
        for ((w, h), mm) in c.images {
            seen.push((*w as u64, *h as u64, None, repeats(&last(mm), &pat)));
        }
        for (var, manifests) in &c.variants {
            for (x, mm) in manifests {
                seen.push((w0, h0, Some((var.path.as_str(), *x)), repeats(&last(mm), &pat)));
            }
        }
        // A quantity (how many, the first level) with the settings it follows, fitted.
        let fitted = |q: &Quantity| -> (Option<String>, Vec<String>) {
            let mine = q(&(count, first));
            let mut names: Vec<String> = Vec::new();
            for (var, manifests) in &c.variants {
                if manifests.iter().any(|(_, mm)| q(&repeats(&last(mm), &pat)) != mine) {
                    names.push(var.path.clone());
                }
            }
            names.sort();
            let obs: Option<Vec<Obs>> = seen
                .iter()
                .filter(|(_, _, x, _)| x.is_none_or(|(v, _)| names.iter().any(|n| n == v)))
                .map(|(w, h, x, r)| Some(Obs { w: *w, h: *h, s: c.values(&names, *x), q: q(r)? }))
                .collect();
            (obs.and_then(|o| joint_fit::fit_count(&names, &o)), names)
        };
        let (count_expr, names) = fitted(&|r| Some(r.0));
        let first_expr = first.and_then(|_| fitted(&|r| r.1).0);
        // One pass that no setting repeats is not a loop.
        if count < 2 && count_expr.as_deref() == Some("1") {
            continue;
        }
        let passes = m.passes.iter().enumerate().filter(|(_, q)| pattern(&q.name).0 == pat).map(|(j, _)| j).collect();
        out.push(PassRepeat { name: pat, passes, count, count_expr, first, first_expr, depends_on: names });
    }
    out
}
