//! CPU twin of the buffer viewer's colour mapping (`shaders/view/view.wgsl`): the tests compare the GPU view with it texel by texel.

use crate::maths::colormap::RANGE_BINS;
pub use crate::maths::colormap::colormap;
use crate::settings::view::{ViewMode, ViewSettings};

/// NaN maps to 0 (black) when the overlay is off.
fn normalise(s: &ViewSettings, x: f32) -> f32 {
    if x.is_nan() {
        return 0.0;
    }
    let (lo, hi) = (s.range[0], s.range[1]);
    if s.log {
        let l = lo.max(1e-8);
        let h = hi.max(l * 1.000_001);
        return ((x.max(l) / l).log2() / (h / l).log2()).clamp(0.0, 1.0);
    }
    ((x - lo) / (hi - lo).max(1e-20)).clamp(0.0, 1.0)
}

fn srgb_encode(c: f32) -> f32 {
    if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// Overlay colours: NaN, ±Inf, negative.
pub const NAN_COLOUR: [f32; 3] = [1.0, 0.0, 1.0];
pub const INF_COLOUR: [f32; 3] = [0.0, 1.0, 0.0];
pub const NEGATIVE_COLOUR: [f32; 3] = [0.0, 0.9, 1.0];

/// The display colour of one raw texel under the view settings.
pub fn map_texel(s: &ViewSettings, v: [f32; 4]) -> [f32; 3] {
    let comps: Vec<f32> = match s.mode {
        ViewMode::Channel => vec![v[(s.channel as usize).min(3)]],
        _ => v[..3].to_vec(),
    };
    if s.flag_nan_inf {
        if comps.iter().any(|c| c.is_nan()) {
            return NAN_COLOUR;
        }
        if comps.iter().any(|c| c.is_infinite()) {
            return INF_COLOUR;
        }
    }
    if s.flag_negative && comps.iter().any(|c| *c < 0.0) {
        return NEGATIVE_COLOUR;
    }
    let scale = s.exposure_ev.exp2();
    match s.mode {
        ViewMode::Rgb => {
            let c = [0, 1, 2].map(|i| normalise(s, v[i] * scale));
            if s.srgb { c.map(srgb_encode) } else { c }
        }
        ViewMode::Channel => colormap(s.colormap, normalise(s, comps[0] * scale)),
        ViewMode::Length => {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            colormap(s.colormap, normalise(s, l * scale))
        }
    }
}

/// A u32 that orders as the float does (`order_key` in view.wgsl).
pub fn order_key(x: f32) -> u32 {
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 { !b } else { b ^ 0x8000_0000 }
}

/// The float of an order key.
pub fn from_order_key(k: u32) -> f32 {
    f32::from_bits(if k & 0x8000_0000 != 0 { k ^ 0x8000_0000 } else { !k })
}

/// The range [`auto_range`] gives, from the GPU's statistics of the same values (the
/// viewer's `cs_range_*`; `words` as read back, `RANGE_STATS_BYTES`): min–max exactly; a
/// percentile range to within one bin of the histogram, widened (the low end is its bin's
/// lower edge, the high end its bin's upper edge). None when no value is finite.
pub fn range_from_stats(words: &[u32], exposure_ev: f32, percentile: f32) -> Option<[f32; 2]> {
    let (lo, hi, count) = (*words.first()?, *words.get(1)?, *words.get(2)? as u64);
    if count == 0 || hi < lo {
        return None;
    }
    let scale = exposure_ev.exp2();
    if percentile <= 0.0 {
        return Some([from_order_key(lo) * scale, from_order_key(hi) * scale]);
    }
    let bins = words.get(4..4 + RANGE_BINS)?;
    let bits = 32 - (hi - lo).leading_zeros();
    let shift = bits.saturating_sub(12);
    let p = percentile.clamp(0.0, 49.9) / 100.0;
    let rank = |q: f32| ((count - 1) as f32 * q).round() as u64;
    // The bin holding the value of rank r in ascending order.
    let bin_of = |r: u64| {
        let mut seen = 0u64;
        for (b, n) in bins.iter().enumerate() {
            seen += *n as u64;
            if seen > r {
                return b as u32;
            }
        }
        (RANGE_BINS - 1) as u32
    };
    let (b_lo, b_hi) = (bin_of(rank(p)), bin_of(rank(1.0 - p)));
    let low = lo + (b_lo << shift);
    let high = (lo as u64 + ((b_hi as u64 + 1) << shift) - 1).min(hi as u64) as u32;
    Some([from_order_key(low) * scale, from_order_key(high) * scale])
}

/// The range that auto min–max or a percentile range gives for the values the mode shows
/// (finite values only). `percentile` = 0 gives min–max; p gives the [p, 100 − p] % range.
pub fn auto_range(s: &ViewSettings, img: &crate::ImageF32, percentile: f32) -> Option<[f32; 2]> {
    let mut vals: Vec<f32> = Vec::with_capacity(img.data.len() * 3);
    for v in &img.data {
        match s.mode {
            ViewMode::Rgb => vals.extend(v[..3].iter().copied()),
            ViewMode::Channel => vals.push(v[(s.channel as usize).min(3)]),
            ViewMode::Length => vals.push((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()),
        }
    }
    vals.retain(|v| v.is_finite());
    if vals.is_empty() {
        return None;
    }
    let scale = s.exposure_ev.exp2();
    if percentile <= 0.0 {
        let lo = vals.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = vals.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        return Some([lo * scale, hi * scale]);
    }
    vals.sort_by(f32::total_cmp);
    let p = percentile.clamp(0.0, 49.9) / 100.0;
    let at = |q: f32| vals[((vals.len() - 1) as f32 * q).round() as usize];
    Some([at(p) * scale, at(1.0 - p) * scale])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::maths::colormap::Colormap;

    fn near(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
        a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
    }

    /// The tables reproduce the maps' published anchor colours (matplotlib's viridis and
    /// inferno hex values at 0, ½, 1; Turbo's table at 0, ½, 1).
    #[test]
    fn order_keys_order_as_the_floats() {
        let xs = [f32::NEG_INFINITY, -1e30, -2.0, -1.0, -1e-30, -0.0, 0.0, 1e-30, 0.5, 1.0, 3.0, 1e30, f32::INFINITY];
        for w in xs.windows(2) {
            assert!(order_key(w[0]) <= order_key(w[1]), "{} {}", w[0], w[1]);
        }
        for x in xs {
            assert_eq!(from_order_key(order_key(x)).to_bits(), x.to_bits());
        }
    }

    /// The statistics a GPU would make of some values give auto_range's min–max exactly
    /// and its percentile range within one bin.
    #[test]
    fn stats_give_the_auto_range() {
        let values: Vec<f32> = (0..5000).map(|i| ((i * 7919) % 5000) as f32 * 0.01 - 3.0).chain([1e6, -1e5]).collect();
        let keys: Vec<u32> = values.iter().map(|v| order_key(*v)).collect();
        let (lo, hi) = (*keys.iter().min().unwrap(), *keys.iter().max().unwrap());
        let shift = (32 - (hi - lo).leading_zeros()).saturating_sub(12);
        let mut words = vec![0u32; 4 + RANGE_BINS];
        (words[0], words[1], words[2]) = (lo, hi, keys.len() as u32);
        for k in &keys {
            words[4 + ((k - lo) >> shift) as usize] += 1;
        }
        let img = crate::ImageF32 {
            width: values.len() as u32,
            height: 1,
            data: values.iter().map(|v| [*v, 0.0, 0.0, 1.0]).collect(),
        };
        let s = ViewSettings { mode: ViewMode::Channel, channel: 0, exposure_ev: 1.0, ..ViewSettings::default() };
        assert_eq!(range_from_stats(&words, 1.0, 0.0), auto_range(&s, &img, 0.0));
        let exact = auto_range(&s, &img, 1.0).unwrap();
        let got = range_from_stats(&words, 1.0, 1.0).unwrap();
        let bin = 1u32 << shift;
        assert!(got[0] <= exact[0] && order_key(exact[0] / 2.0) - order_key(got[0] / 2.0) < bin, "{got:?} {exact:?}");
        assert!(got[1] >= exact[1] && order_key(got[1] / 2.0) - order_key(exact[1] / 2.0) < bin, "{got:?} {exact:?}");
        // The outliers stay out of the 1 % range.
        assert!(got[1] < 100.0 && got[0] > -100.0, "{got:?}");
    }

    #[test]
    fn colormaps_match_published_anchors() {
        let hex = |h: u32| [(h >> 16) as f32 / 255.0, ((h >> 8) & 255) as f32 / 255.0, (h & 255) as f32 / 255.0];
        for (t, want) in [(0.0, hex(0x440154)), (0.5, hex(0x21918c)), (1.0, hex(0xfde725))] {
            let c = colormap(Colormap::Viridis, t);
            assert!(near(c, want, 0.01), "viridis({t}) = {c:?}, want {want:?}");
        }
        for (t, want) in [(0.0, hex(0x000004)), (0.5, hex(0xbc3754)), (1.0, hex(0xfcffa4))] {
            let c = colormap(Colormap::Inferno, t);
            assert!(near(c, want, 0.01), "inferno({t}) = {c:?}, want {want:?}");
        }
        for (t, want) in [
            (0.0, [0.18995, 0.07176, 0.23217]),
            (0.5, [0.64362, 0.98999, 0.23356]),
            (1.0, [0.4796, 0.01583, 0.01055]),
            (0.25, [0.15844, 0.73551, 0.92305]),
        ] {
            let c = colormap(Colormap::Turbo, t);
            assert!(near(c, want, 0.01), "turbo({t}) = {c:?}, want {want:?}");
        }
    }

    #[test]
    fn overlay_flags_bad_values_and_ranges_map_linearly() {
        let s = ViewSettings { range: [0.0, 2.0], srgb: false, ..Default::default() };
        assert_eq!(map_texel(&s, [f32::NAN, 0.0, 0.0, 1.0]), NAN_COLOUR);
        assert_eq!(map_texel(&s, [0.0, f32::INFINITY, 0.0, 1.0]), INF_COLOUR);
        assert_eq!(map_texel(&s, [0.0, 0.0, -1.0, 1.0]), NEGATIVE_COLOUR);
        assert_eq!(map_texel(&s, [1.0, 2.0, 4.0, 1.0]), [0.5, 1.0, 1.0]);
        let log = ViewSettings { range: [1.0, 100.0], log: true, srgb: false, ..Default::default() };
        assert!((map_texel(&log, [10.0, 1.0, 100.0, 1.0])[0] - 0.5).abs() < 1e-5);
    }
}
