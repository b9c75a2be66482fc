//! Explain a pixel (issue #42): where a pixel's indirect light comes from, as the stage
//! choices made it. A GPU pass replays the pixel's gather with the frame's own inputs, after
//! the frame's passes and in its encoder (`passes::knecht::explain` for the VPL gather at
//! tiles or pixels, its filter and its confidence merge; `passes::gautron::explain` for
//! Gautron's splatted irradiance records; `passes::hcb::explain` for the HCB's coherence
//! splatting, Nguyen et al. §4.2–4.3); this module holds what every
//! technique's replay decodes into: the contributions, largest first, the rejected ones with
//! why, and the checks of their sum against the buffers the frame wrote
//! (docs/architecture.md, "Explain a pixel").

use glam::Vec3;

/// A technique's replay of the pinned pixel: what to read back after the frame, and how to
/// decode it. Each technique's pass implements it (`passes::knecht::explain::VplExplainPass`,
/// …); `Renderer::explanation` reads its parts blocking, `Renderer::explanation_later`
/// without waiting.
pub trait Replay {
    /// The storage buffers to read back, each with the bytes wanted (None before a run).
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>>;
    /// The explanation from the parts' bytes, in `parts`' order (None when they do not
    /// match the run, e.g. read back across a settings change).
    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation>;
}

/// Why a contributor gives the pixel nothing (or less than its own light).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Rejection {
    /// The visibility map (ISM or exact) hides the receiver from it.
    Occluded,
    /// The receiver faces away from it, or it faces away from the receiver.
    Facing,
    /// Closer than the near field's cut: the screen-space gather takes its light.
    NearField,
    /// It reached the pixel through a neighbour that the geometry-aware filter leaves out.
    Filter,
    /// Its tile's pixel of the filter's window lies outside the image or on the background.
    Outside,
    /// An irradiance record whose splat's bound (the screen bound of its sphere a·R_k) does
    /// not hold the pixel.
    OutsideBound,
    /// An irradiance record lying in front of the pixel's point by Ward's test (its weight is 0).
    InFront,
    /// An irradiance record whose Ward weight at the pixel is at most 1/a (the splat discards it).
    WeightBelowCutoff,
    /// An irradiance record whose hemisphere is being computed (it splats nothing yet).
    Pending,
    /// An HCB sample whose splat's quad holds the pixel, to which the pixel is not coherent
    /// (Nguyen et al. §4.2, Eq. 9: an error of Eq. 8 above 1; the splat adds nothing).
    Incoherent,
}

impl Rejection {
    pub fn label(&self) -> &'static str {
        match self {
            Rejection::Occluded => "occluded (visibility)",
            Rejection::Facing => "facing away",
            Rejection::NearField => "near field's",
            Rejection::Filter => "filter: other surface",
            Rejection::Outside => "window: outside or background",
            Rejection::OutsideBound => "outside its splat's bound",
            Rejection::InFront => "in front of P (Ward's test)",
            Rejection::WeightBelowCutoff => "w ≤ 1/a (Ward's weight)",
            Rejection::Pending => "being computed",
            Rejection::Incoherent => "incoherent (Eq. 9)",
        }
    }
}

/// One contributor to the pixel's indirect light.
#[derive(Clone, Debug, PartialEq)]
pub struct Contribution {
    /// What it is: "VPL 17", "history".
    pub name: String,
    /// Where it comes from: "light 0 view 0, bounce 1", "emitters", "previous frame".
    pub source: String,
    /// Its world position (None for the history).
    pub position: Option<Vec3>,
    /// Its share of the pixel's indirect radiance, after every weight that carried it.
    pub value: Vec3,
    /// The factor from its own light to its share (the tile's N / N_t, the filter's 1 / m,
    /// the merge's 1 − c …), already in `value`.
    pub weight: f32,
    /// Why it gives nothing, when it does not.
    pub rejected: Option<Rejection>,
    /// The pixel it reached this one through (the filter's window), when not itself.
    pub via: Option<(u32, u32)>,
    /// The technique's own quantities, named as the paper names them.
    pub fields: Vec<(&'static str, f32)>,
}

/// A sum checked against a buffer the frame wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Check {
    /// What is summed: "Σ VPL terms at (12, 40)".
    pub what: String,
    pub sum: Vec3,
    /// The buffer read at the pixel, and its value.
    pub buffer: String,
    pub value: Vec3,
}

impl Check {
    /// |sum − value| relative to the larger magnitude (0 when both are 0).
    pub fn relative_error(&self) -> f32 {
        let scale = self.sum.abs().max_element().max(self.value.abs().max_element());
        if scale <= 0.0 { 0.0 } else { (self.sum - self.value).abs().max_element() / scale }
    }
}

/// A pixel explained.
#[derive(Clone, Debug, PartialEq)]
pub struct Explanation {
    pub pixel: (u32, u32),
    /// The stage choices it replays, in words.
    pub technique: String,
    /// Largest share first; the rejected ones after, by their unshadowed light.
    pub contributions: Vec<Contribution>,
    /// The pixel's indirect value as the frame wrote it, and which buffer holds it.
    pub buffer: String,
    pub value: Vec3,
    /// The sums checked along the way (the gather, the filter, the merge).
    pub checks: Vec<Check>,
    /// Lines of context (N, N_t, the window, the confidence …).
    pub notes: Vec<String>,
}

/// Luminance (Rec. 709), for ordering and shares.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl Explanation {
    /// The sum of the contributions.
    pub fn sum(&self) -> Vec3 {
        self.contributions.iter().map(|c| c.value).sum()
    }

    /// The contributions' sum against the pixel's value (relative, as [`Check`]).
    pub fn total_check(&self) -> Check {
        Check { what: "Σ contributions".into(), sum: self.sum(), buffer: self.buffer.clone(), value: self.value }
    }

    /// Sorts the accepted contributions by luminance, largest first, then the rejected ones.
    pub fn sort(&mut self) {
        self.contributions.sort_by(|a, b| {
            (a.rejected.is_some(), -luminance(a.value))
                .partial_cmp(&(b.rejected.is_some(), -luminance(b.value)))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
    }

    /// A contribution's share of the pixel's luminance (0 when the pixel is black).
    pub fn share(&self, c: &Contribution) -> f32 {
        let total = luminance(self.value);
        if total.abs() <= 0.0 { 0.0 } else { luminance(c.value) / total }
    }

    /// The field names every contribution may carry, in first-seen order.
    fn field_names(&self) -> Vec<&'static str> {
        let mut names: Vec<&'static str> = Vec::new();
        for c in &self.contributions {
            for (n, _) in &c.fields {
                if !names.contains(n) {
                    names.push(n);
                }
            }
        }
        names
    }

    /// The table as CSV: one row per contribution, with its share, value, weight, rejection,
    /// position, the pixel it came through and the technique's fields.
    pub fn to_csv(&self) -> String {
        let names = self.field_names();
        let mut out = String::from("name,source,share,r,g,b,weight,rejected,x,y,z,via_x,via_y");
        for n in &names {
            out.push(',');
            out.push_str(&csv_field(n));
        }
        out.push('\n');
        for c in &self.contributions {
            let p = c.position.map(|p| format!("{},{},{}", p.x, p.y, p.z)).unwrap_or_else(|| ",,".into());
            let via = c.via.map(|(x, y)| format!("{x},{y}")).unwrap_or_else(|| ",".into());
            out.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{}",
                csv_field(&c.name),
                csv_field(&c.source),
                self.share(c),
                c.value.x,
                c.value.y,
                c.value.z,
                c.weight,
                c.rejected.as_ref().map(|r| r.label()).unwrap_or(""),
                p,
                via
            ));
            for n in &names {
                out.push(',');
                if let Some((_, v)) = c.fields.iter().find(|(k, _)| k == n) {
                    out.push_str(&v.to_string());
                }
            }
            out.push('\n');
        }
        out
    }

    /// The table as text (the command line's `render --explain`): the checks, the notes, then
    /// up to `rows` contributions (all with 0).
    pub fn to_text(&self, rows: usize) -> String {
        let mut out = format!("pixel ({}, {}) — {}\n", self.pixel.0, self.pixel.1, self.technique);
        let v = self.value;
        out.push_str(&format!("  {} = ({:.6e}, {:.6e}, {:.6e})\n", self.buffer, v.x, v.y, v.z));
        for c in std::iter::once(self.total_check()).chain(self.checks.iter().cloned()) {
            out.push_str(&format!(
                "  {} = ({:.6e}, {:.6e}, {:.6e}) against {}: relative difference {:.2e}\n",
                c.what,
                c.sum.x,
                c.sum.y,
                c.sum.z,
                c.buffer,
                c.relative_error()
            ));
        }
        for n in &self.notes {
            out.push_str(&format!("  {n}\n"));
        }
        let accepted = self.contributions.iter().filter(|c| c.rejected.is_none()).count();
        out.push_str(&format!("  {} contributors, {} rejected\n", accepted, self.contributions.len() - accepted));
        out.push_str(&format!(
            "  {:<16} {:<36} {:>8} {:>36} {:>9}  {}\n",
            "name", "source", "share", "value (rgb)", "weight", "rejected / fields"
        ));
        let shown = if rows == 0 { self.contributions.len() } else { rows.min(self.contributions.len()) };
        for c in &self.contributions[..shown] {
            let mut fields: Vec<String> = c.fields.iter().map(|(k, v)| format!("{k} {v:.4e}")).collect();
            if let Some((x, y)) = c.via {
                fields.insert(0, format!("via ({x}, {y})"));
            }
            out.push_str(&format!(
                "  {:<16} {:<36} {:>7.2}% ({:.4e}, {:.4e}, {:.4e}) {:>9.4}  {}{}\n",
                c.name,
                c.source,
                100.0 * self.share(c),
                c.value.x,
                c.value.y,
                c.value.z,
                c.weight,
                c.rejected.as_ref().map(|r| format!("{}; ", r.label())).unwrap_or_default(),
                fields.join(", ")
            ));
        }
        if shown < self.contributions.len() {
            out.push_str(&format!(
                "  … {} more (all with --explain-rows 0, or as CSV)\n",
                self.contributions.len() - shown
            ));
        }
        out
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) { format!("\"{}\"", s.replace('"', "\"\"")) } else { s.to_string() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(name: &str, v: f32, rejected: Option<Rejection>) -> Contribution {
        Contribution {
            name: name.into(),
            source: "light 0, view 0".into(),
            position: Some(Vec3::ONE),
            value: Vec3::splat(v),
            weight: 1.0,
            rejected,
            via: None,
            fields: vec![("G", 0.5)],
        }
    }

    #[test]
    fn sorts_largest_first_and_rejected_last() {
        let mut e = Explanation {
            pixel: (1, 2),
            technique: "t".into(),
            contributions: vec![c("a", 0.1, None), c("b", 0.0, Some(Rejection::Occluded)), c("c", 0.3, None)],
            buffer: "indirect.merged".into(),
            value: Vec3::splat(0.4),
            checks: vec![],
            notes: vec![],
        };
        e.sort();
        let names: Vec<&str> = e.contributions.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["c", "a", "b"]);
        assert!(e.total_check().relative_error() < 1e-6);
        assert!((e.share(&e.contributions[0]) - 0.75).abs() < 1e-6);
        let csv = e.to_csv();
        assert_eq!(csv.lines().count(), 4);
        assert!(csv.lines().next().is_some_and(|h| h.ends_with(",G")));
        // The source's comma is quoted, so every row has the header's column count.
        let cols = |l: &str| l.split(',').count() - l.matches("\"light 0, view 0\"").count();
        assert!(csv.lines().all(|l| cols(l) == 14), "{csv}");
        assert!(e.to_text(0).contains("occluded (visibility)"));
    }
}
