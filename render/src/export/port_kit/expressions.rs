//! Sizes and counts as expressions of the image's width W and height H (issue #54 point 1;
//! docs/port-kit.md, "Sizes as expressions"). The kit's frame is captured once more at six
//! probe sizes; every texture dimension, buffer size, dispatch's workgroup count and draw's
//! count is then fitted, over the probes and the kit's own size, by the simplest expression
//! of a small family — a constant, `a * g(W, H) + b` with `g` a level of a pyramid
//! (`W`, `ceil(W / 4)`, `max(1, floor(H / 8))`), a tiling of one (`ceil(ceil(W / 2) / 8)`), a
//! product of two such, or a tiling of the pixel count (`ceil(W * H / 64)`) — that gives every
//! captured value exactly. What no expression of the family fits is left as captured.
//!
//! Only W and H vary between the probes: a size that follows a setting (a VPL count, an
//! atlas's resolution) is a constant here, with the preset's value.

use super::manifest::{Manifest, Step};

/// Probe sizes: odd and even, far apart and different in each axis, so that floors and
/// ceilings, W and H, and fine and coarse tilings give different values.
pub const PROBES: [(u32, u32); 6] = [(67, 41), (160, 41), (67, 103), (160, 103), (99, 57), (217, 133)];

/// How a pyramid's level rounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Round {
    Floor,
    Ceil,
}

/// `g(W, H)` of the family ([`family`]).
#[derive(Clone, Copy, Debug)]
pub enum Basis {
    /// `ceil(level(X, s) / d)`, X = W (false) or H (true).
    One { h: bool, s: u32, round: Round, d: u64 },
    /// The product of the two axes' `One`.
    Prod { s: u32, round: Round, d: u64 },
    /// `ceil(W * H / d)`.
    Area { d: u64 },
    /// Chunks of `d` tiles of `t`×`t` pixels: `ceil(ceil(W / t) * ceil(H / t) / d)`.
    Chunks { t: u64, d: u64 },
    /// The tiles and `k` words per chunk: `ceil(W / t) * ceil(H / t) + k * Chunks`.
    TilesChunks { t: u64, d: u64, k: u64 },
}

/// Level `s` of a pyramid over `x`: halved `s` times, rounded down (at least 1) or up.
fn level(x: u64, s: u32, round: Round) -> u64 {
    let p = 1u64 << s;
    match round {
        Round::Floor => (x / p).max(1),
        Round::Ceil => x.div_ceil(p),
    }
}

fn level_text(x: &str, s: u32, round: Round) -> String {
    match (s, round) {
        (0, _) => x.to_string(),
        (_, Round::Floor) => format!("max(1, floor({x} / {}))", 1u64 << s),
        (_, Round::Ceil) => format!("ceil({x} / {})", 1u64 << s),
    }
}

fn tiled_text(inner: String, d: u64) -> String {
    if d == 1 { inner } else { format!("ceil({inner} / {d})") }
}

impl Basis {
    fn eval(&self, w: u64, h: u64) -> u64 {
        match *self {
            Basis::One { h: axis, s, round, d } => level(if axis { h } else { w }, s, round).div_ceil(d),
            Basis::Prod { s, round, d } => level(w, s, round).div_ceil(d) * level(h, s, round).div_ceil(d),
            Basis::Area { d } => (w * h).div_ceil(d),
            Basis::Chunks { t, d } => (w.div_ceil(t) * h.div_ceil(t)).div_ceil(d),
            Basis::TilesChunks { t, d, k } => {
                let tiles = w.div_ceil(t) * h.div_ceil(t);
                tiles + k * tiles.div_ceil(d)
            }
        }
    }

    fn text(&self) -> String {
        match *self {
            Basis::One { h, s, round, d } => tiled_text(level_text(if h { "H" } else { "W" }, s, round), d),
            Basis::Prod { s, round, d } => {
                format!("{} * {}", tiled_text(level_text("W", s, round), d), tiled_text(level_text("H", s, round), d))
            }
            Basis::Area { d } => tiled_text("W * H".into(), d),
            Basis::Chunks { t, d } => format!("ceil(ceil(W / {t}) * ceil(H / {t}) / {d})"),
            Basis::TilesChunks { t, d, k } => {
                format!("ceil(W / {t}) * ceil(H / {t}) + {k} * ceil(ceil(W / {t}) * ceil(H / {t}) / {d})")
            }
        }
    }
}

/// The family of [`fit`], simplest first.
pub fn family() -> Vec<Basis> {
    // Workgroup widths first: a tiling by 8 or 16 is likelier than one by 2.
    const TILES: [u64; 9] = [1, 8, 16, 4, 32, 64, 2, 128, 256];
    let mut out = Vec::new();
    for d in TILES {
        for s in 0..=8 {
            for round in [Round::Ceil, Round::Floor] {
                if s == 0 && round == Round::Floor {
                    continue;
                }
                for h in [false, true] {
                    out.push(Basis::One { h, s, round, d });
                }
            }
        }
    }
    for d in TILES {
        for s in 0..=6 {
            for round in [Round::Ceil, Round::Floor] {
                // W * H itself is `Area`'s.
                if s == 0 && (round == Round::Floor || d == 1) {
                    continue;
                }
                out.push(Basis::Prod { s, round, d });
            }
        }
    }
    for d in [1u64, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024] {
        out.push(Basis::Area { d });
    }
    // Tiles gathered in chunks (a prefix sum over tiles, Gautron et al.'s record creation).
    for t in TILES.into_iter().filter(|&t| t > 1) {
        for d in [64u64, 128, 256, 512, 1024] {
            out.push(Basis::Chunks { t, d });
            for k in [1, 2] {
                out.push(Basis::TilesChunks { t, d, k });
            }
        }
    }
    out
}

/// The simplest expression of the family through every point (W, H, value), if any.
pub fn fit(points: &[(u64, u64, u64)], family: &[Basis]) -> Option<String> {
    let first = points.first()?.2;
    if points.iter().all(|p| p.2 == first) {
        return Some(first.to_string());
    }
    let q: Vec<i128> = points.iter().map(|p| p.2 as i128).collect();
    // First `g` itself (a = 1, b = 0), over the whole family; then `a * g + b`: a looser
    // form fits more by chance, so it is tried only when no exact level or tiling does.
    for b in family {
        if points.iter().all(|p| b.eval(p.0, p.1) == p.2) {
            return Some(b.text());
        }
    }
    // Then `a * g` (a stride times a count), and only then `a * g + b` (a header).
    for offset in [false, true] {
        if let Some(t) = fit_linear(points, &q, family, offset) {
            return Some(t);
        }
    }
    None
}

/// `a * g + b` through every point for the first `g` of `family` that gives one (`b` = 0
/// unless `offset`).
fn fit_linear(points: &[(u64, u64, u64)], q: &[i128], family: &[Basis], offset: bool) -> Option<String> {
    family.iter().find_map(|b| {
        let g: Vec<i128> = points.iter().map(|p| b.eval(p.0, p.1) as i128).collect();
        let (a, c) = solve_linear(&g, q, offset)?;
        Some(affine_text(b.text(), matches!(b, Basis::Prod { .. } | Basis::TilesChunks { .. }), a, c))
    })
}

/// `(a, b)` with `a > 0` and `a * g[k] + b = q[k]` at every point, integers (`b` = 0 unless
/// `offset`); the two points farthest apart in `g` give them. Also the settings' fits
/// (`super::settings_probe`).
pub(crate) fn solve_linear(g: &[i128], q: &[i128], offset: bool) -> Option<(i128, i128)> {
    let (mut i, mut j) = (0, 0);
    for x in 0..g.len() {
        for y in 0..g.len() {
            if (g[x] - g[y]).abs() > (g[i] - g[j]).abs() {
                (i, j) = (x, y);
            }
        }
    }
    let dg = g[i] - g[j];
    if dg == 0 || (q[i] - q[j]) % dg != 0 {
        return None;
    }
    let a = (q[i] - q[j]) / dg;
    let c = q[i] - a * g[i];
    (a > 0 && (c == 0 || offset) && (0..g.len()).all(|k| a * g[k] + c == q[k])).then_some((a, c))
}

/// `a * text + b` as written in a manifest (`text` in parentheses when it is a product or a
/// sum).
pub(crate) fn affine_text(text: String, compound: bool, a: i128, c: i128) -> String {
    let mut t = match (a, compound) {
        (1, _) => text,
        (_, true) => format!("{a} * ({text})"),
        _ => format!("{a} * {text}"),
    };
    if c > 0 {
        t = format!("{t} + {c}");
    } else if c < 0 {
        t = format!("{t} - {}", -c);
    }
    t
}

/// Writes the expressions into `m` (the kit's manifest at its own size) from the manifests
/// of the same frame captured at [`PROBES`] (`probes`, in that order): resources matched by
/// name, steps by frame, pass and position (a probe's frame 0 for the kit's frame 0, its last
/// for the later ones). Returns how many values got an expression and how many were left as
/// captured.
pub fn annotate(m: &mut Manifest, probes: &[((u32, u32), Manifest)]) -> (usize, usize) {
    let family = family();
    let (kw, kh) = (m.size[0] as u64, m.size[1] as u64);
    let (mut fitted, mut left) = (0, 0);
    let mut count = |e: &Option<String>| {
        if e.is_some() { fitted += 1 } else { left += 1 }
    };
    let point = |size: (u32, u32), v: u64| (size.0 as u64, size.1 as u64, v);
    for r in &mut m.resources {
        if r.kind == "sampler" {
            continue;
        }
        let mut exprs = Vec::new();
        for (k, &v) in r.size.iter().enumerate() {
            let mut points = vec![(kw, kh, v)];
            for (size, p) in probes {
                match p.resources.iter().find(|x| x.name == r.name && x.kind == r.kind).and_then(|x| x.size.get(k)) {
                    Some(&pv) => points.push(point(*size, pv)),
                    None => {
                        points.clear();
                        break;
                    }
                }
            }
            let e = if points.len() == probes.len() + 1 { fit(&points, &family) } else { None };
            count(&e);
            exprs.push(e);
        }
        r.size_expr = exprs;
    }
    let frames = m.frame_passes.len();
    for k in 0..frames {
        for pi in 0..m.frame_passes[k].len() {
            for si in 0..m.frame_passes[k][pi].steps.len() {
                let probe_steps: Vec<Option<&Step>> = probes
                    .iter()
                    .map(|(_, p)| {
                        let f = p.frame_passes.get(k.min(p.frame_passes.len().saturating_sub(1)))?;
                        let pass = f.get(pi).filter(|x| x.name == m.frame_passes[k][pi].name)?;
                        let step = pass.steps.get(si)?;
                        let mine = &m.frame_passes[k][pi].steps[si];
                        (step.kind == mine.kind && step.pipeline == mine.pipeline).then_some(step)
                    })
                    .collect();
                let step = &mut m.frame_passes[k][pi].steps[si];
                annotate_step(step, &probe_steps, (kw, kh), probes, &family, &mut count);
            }
        }
    }
    // `passes` is the last frame's list.
    if let Some(last) = m.frame_passes.last() {
        m.passes = last.clone();
    }
    (fitted, left)
}

/// Numbers of a step that follow the image: workgroup counts, and a draw's vertex or index
/// count and instance count.
pub(crate) fn step_numbers(s: &Step) -> Vec<u64> {
    let mut out = Vec::new();
    if let Some(w) = s.workgroups {
        out.extend(w.iter().map(|&x| x as u64));
    }
    if let Some(d) = &s.draw {
        let range =
            |key: &str| d[key].as_array().and_then(|r| Some(r.get(1)?.as_u64()?.saturating_sub(r.first()?.as_u64()?)));
        out.extend(range("vertices").or(range("indices")));
        out.extend(range("instances"));
    }
    out
}

fn annotate_step(
    step: &mut Step,
    probe_steps: &[Option<&Step>],
    (kw, kh): (u64, u64),
    probes: &[((u32, u32), Manifest)],
    family: &[Basis],
    count: &mut impl FnMut(&Option<String>),
) {
    let mine = step_numbers(step);
    if mine.is_empty() {
        return;
    }
    let theirs: Vec<Option<Vec<u64>>> = probe_steps.iter().map(|s| s.map(step_numbers)).collect();
    let mut exprs = Vec::new();
    for (k, &v) in mine.iter().enumerate() {
        let mut points = vec![(kw, kh, v)];
        for ((size, _), t) in probes.iter().zip(&theirs) {
            if let Some(pv) = t.as_ref().and_then(|t| t.get(k)) {
                points.push((size.0 as u64, size.1 as u64, *pv));
            }
        }
        let e = if points.len() == probes.len() + 1 { fit(&points, family) } else { None };
        count(&e);
        exprs.push(e);
    }
    step.counts_expr = exprs;
}

/// The value of an expression of [`fit`]'s grammar — integers, `W`, `H`, `+`, `-`, `*`, `/`,
/// parentheses, `ceil(x)`, `floor(x)`, `sqrt(x)`, `log2(x)`, `exp2(x)`, `max(x, y)`, `min(x, y)` — at the image `w` × `h`; None when it does
/// not parse. What a port evaluates at its own size (docs/port-kit.md, "Sizes as
/// expressions").
pub fn eval(expr: &str, w: u64, h: u64) -> Option<u64> {
    eval_with(expr, w, h, &|_| None)
}

/// [`eval`] with settings: a dotted name (`vpl.count`, docs/port-kit.md, "Sizes that follow a
/// setting") is the value `setting` gives it.
pub fn eval_with(expr: &str, w: u64, h: u64, setting: &dyn Fn(&str) -> Option<f64>) -> Option<u64> {
    let tokens: Vec<char> = expr.chars().filter(|c| !c.is_whitespace()).collect();
    let mut p = Parser { t: &tokens, i: 0, w: w as f64, h: h as f64, setting };
    let v = p.sum()?;
    (p.i == tokens.len() && v >= 0.0).then_some(v.round() as u64)
}

struct Parser<'a> {
    t: &'a [char],
    i: usize,
    w: f64,
    h: f64,
    setting: &'a dyn Fn(&str) -> Option<f64>,
}

impl Parser<'_> {
    fn peek(&self) -> Option<char> {
        self.t.get(self.i).copied()
    }

    fn eat(&mut self, c: char) -> Option<()> {
        (self.peek() == Some(c)).then(|| self.i += 1)
    }

    fn sum(&mut self) -> Option<f64> {
        let mut v = self.product()?;
        while let Some(c @ ('+' | '-')) = self.peek() {
            self.i += 1;
            let r = self.product()?;
            v = if c == '+' { v + r } else { v - r };
        }
        Some(v)
    }

    fn product(&mut self) -> Option<f64> {
        let mut v = self.atom()?;
        while let Some(c @ ('*' | '/')) = self.peek() {
            self.i += 1;
            let r = self.atom()?;
            v = if c == '*' { v * r } else { v / r };
        }
        Some(v)
    }

    fn atom(&mut self) -> Option<f64> {
        match self.peek()? {
            '(' => {
                self.i += 1;
                let v = self.sum()?;
                self.eat(')')?;
                Some(v)
            }
            'W' => {
                self.i += 1;
                Some(self.w)
            }
            'H' => {
                self.i += 1;
                Some(self.h)
            }
            c if c.is_ascii_digit() => {
                let start = self.i;
                while self.peek().is_some_and(|c| c.is_ascii_digit()) {
                    self.i += 1;
                }
                self.t[start..self.i].iter().collect::<String>().parse().ok()
            }
            _ => {
                let start = self.i;
                while self.peek().is_some_and(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_' || c == '.')
                {
                    self.i += 1;
                }
                let name: String = self.t[start..self.i].iter().collect();
                if name.is_empty() {
                    return None;
                }
                if self.peek() != Some('(') {
                    return (self.setting)(&name);
                }
                self.eat('(')?;
                let a = self.sum()?;
                let v = match name.as_str() {
                    "ceil" => a.ceil(),
                    "floor" => a.floor(),
                    "sqrt" => a.sqrt(),
                    "max" => {
                        self.eat(',')?;
                        a.max(self.sum()?)
                    }
                    "min" => {
                        self.eat(',')?;
                        a.min(self.sum()?)
                    }
                    "log2" => a.log2(),
                    "exp2" => a.exp2(),
                    _ => return None,
                };
                self.eat(')')?;
                Some(v)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points of `f` at the probes and a kit's size.
    fn points(f: impl Fn(u64, u64) -> u64) -> Vec<(u64, u64, u64)> {
        PROBES.iter().chain([(320, 180)].iter()).map(|&(w, h)| (w as u64, h as u64, f(w as u64, h as u64))).collect()
    }

    #[test]
    fn the_simplest_expression_through_the_probes_is_found_and_a_size_no_expression_gives_is_left() {
        let fam = family();
        assert_eq!(fit(&points(|_, _| 7), &fam).as_deref(), Some("7"));
        assert_eq!(fit(&points(|w, _| w), &fam).as_deref(), Some("W"));
        assert_eq!(fit(&points(|_, h| h.div_ceil(8)), &fam).as_deref(), Some("ceil(H / 8)"));
        // A pyramid's level 3 rounded down, tiled by 8 for a dispatch.
        assert_eq!(
            fit(&points(|w, _| (w / 8).max(1).div_ceil(8)), &fam).as_deref(),
            Some("ceil(max(1, floor(W / 8)) / 8)")
        );
        // A buffer of 16-byte texels over the image, plus a 16-byte header.
        assert_eq!(fit(&points(|w, h| 16 * w * h + 16), &fam).as_deref(), Some("16 * W * H + 16"));
        assert_eq!(
            fit(&points(|w, h| w.div_ceil(8) * h.div_ceil(8)), &fam).as_deref(),
            Some("ceil(W / 8) * ceil(H / 8)")
        );
        assert_eq!(fit(&points(|w, h| (w * h).div_ceil(64)), &fam).as_deref(), Some("ceil(W * H / 64)"));
        // 16-pixel tiles, and a count and an offset per chunk of 256 tiles, in 4-byte words.
        let tiles = |w: u64, h: u64| w.div_ceil(16) * h.div_ceil(16);
        let e = fit(&points(|w, h| 4 * (tiles(w, h) + 2 * tiles(w, h).div_ceil(256))), &fam).expect("fits");
        assert_eq!(e, "4 * (ceil(W / 16) * ceil(H / 16) + 2 * ceil(ceil(W / 16) * ceil(H / 16) / 256))");
        assert_eq!(eval(&e, 1920, 1080), Some(4 * (120 * 68 + 2 * 32)));
        // Every expression found evaluates back to the values it was fitted to.
        for f in [|w: u64, _h: u64| (w / 8).max(1).div_ceil(8), |w: u64, h: u64| 16 * w * h + 16] {
            let pts = points(f);
            let e = fit(&pts, &fam).expect("fits");
            for (w, h, v) in pts {
                assert_eq!(eval(&e, w, h), Some(v), "{e} at {w}x{h}");
            }
        }
        assert_eq!(eval("max(1, floor(W / 8)) - 1", 7, 1), Some(0));
        assert_eq!(eval("ceil(W / 8", 7, 1), None, "an unclosed call");
        assert_eq!(eval("32 * vpl.count", 7, 1), None, "a setting without its value");
        let count = |n: &str| (n == "vpl.count").then_some(256.0);
        assert_eq!(eval_with("32 * vpl.count + ceil(W / 8)", 17, 1, &count), Some(32 * 256 + 3));
        // Not in the family (a square root of the pixel count): left as captured.
        assert_eq!(fit(&points(|w, h| ((w * h) as f64).sqrt() as u64), &fam), None);
    }
}
