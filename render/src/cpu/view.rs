//! CPU twin of the buffer viewer's colour mapping (`shaders/view/view.wgsl`): the tests compare the GPU view with it texel by texel.

use crate::passes::view::{Colormap, ViewMode, ViewSettings};

// False-colour tables: matplotlib's viridis and inferno and Google's Turbo, sampled at 65
// evenly spaced points of matplotlib's 256-entry tables and interpolated linearly (within
// 0.027 of matplotlib's own stepped lookup, i.e. within its step). The view pass uploads
// these same tables (`COLORMAP_TABLES`), so the data exists once.
pub const VIRIDIS: [[f32; 3]; 65] = [
    [0.2670, 0.0049, 0.3294],
    [0.2726, 0.0256, 0.3531],
    [0.2770, 0.0503, 0.3757],
    [0.2803, 0.0734, 0.3972],
    [0.2823, 0.0950, 0.4173],
    [0.2832, 0.1157, 0.4361],
    [0.2829, 0.1359, 0.4534],
    [0.2814, 0.1558, 0.4692],
    [0.2788, 0.1755, 0.4834],
    [0.2752, 0.1949, 0.4960],
    [0.2706, 0.2141, 0.5071],
    [0.2651, 0.2330, 0.5166],
    [0.2590, 0.2515, 0.5247],
    [0.2522, 0.2698, 0.5316],
    [0.2450, 0.2877, 0.5373],
    [0.2374, 0.3052, 0.5419],
    [0.2297, 0.3224, 0.5457],
    [0.2220, 0.3392, 0.5488],
    [0.2143, 0.3556, 0.5512],
    [0.2068, 0.3718, 0.5531],
    [0.1994, 0.3876, 0.5546],
    [0.1924, 0.4032, 0.5558],
    [0.1856, 0.4186, 0.5568],
    [0.1790, 0.4338, 0.5574],
    [0.1727, 0.4488, 0.5579],
    [0.1666, 0.4637, 0.5581],
    [0.1607, 0.4785, 0.5581],
    [0.1548, 0.4933, 0.5578],
    [0.1490, 0.5081, 0.5573],
    [0.1433, 0.5228, 0.5563],
    [0.1378, 0.5375, 0.5549],
    [0.1324, 0.5522, 0.5530],
    [0.1276, 0.5669, 0.5506],
    [0.1235, 0.5817, 0.5474],
    [0.1206, 0.5964, 0.5436],
    [0.1194, 0.6111, 0.5390],
    [0.1206, 0.6258, 0.5335],
    [0.1248, 0.6405, 0.5271],
    [0.1323, 0.6550, 0.5197],
    [0.1433, 0.6695, 0.5112],
    [0.1579, 0.6838, 0.5017],
    [0.1757, 0.6979, 0.4910],
    [0.1966, 0.7118, 0.4792],
    [0.2201, 0.7255, 0.4662],
    [0.2461, 0.7389, 0.4520],
    [0.2741, 0.7520, 0.4366],
    [0.3041, 0.7647, 0.4199],
    [0.3359, 0.7770, 0.4020],
    [0.3692, 0.7889, 0.3829],
    [0.4040, 0.8003, 0.3626],
    [0.4401, 0.8111, 0.3410],
    [0.4775, 0.8214, 0.3182],
    [0.5160, 0.8312, 0.2943],
    [0.5555, 0.8403, 0.2693],
    [0.5958, 0.8487, 0.2433],
    [0.6369, 0.8565, 0.2166],
    [0.6785, 0.8637, 0.1895],
    [0.7204, 0.8703, 0.1626],
    [0.7624, 0.8764, 0.1371],
    [0.8042, 0.8820, 0.1150],
    [0.8456, 0.8873, 0.0997],
    [0.8863, 0.8924, 0.0954],
    [0.9261, 0.8973, 0.1041],
    [0.9649, 0.9023, 0.1239],
    [0.9932, 0.9062, 0.1439],
];

pub const TURBO: [[f32; 3]; 65] = [
    [0.1900, 0.0718, 0.2322],
    [0.2086, 0.1180, 0.3461],
    [0.2250, 0.1635, 0.4510],
    [0.2392, 0.2083, 0.5469],
    [0.2511, 0.2524, 0.6337],
    [0.2607, 0.2957, 0.7116],
    [0.2682, 0.3382, 0.7805],
    [0.2733, 0.3801, 0.8404],
    [0.2763, 0.4212, 0.8912],
    [0.2770, 0.4615, 0.9331],
    [0.2754, 0.5011, 0.9659],
    [0.2711, 0.5402, 0.9893],
    [0.2586, 0.5796, 0.9988],
    [0.2387, 0.6193, 0.9949],
    [0.2138, 0.6589, 0.9796],
    [0.1862, 0.6977, 0.9550],
    [0.1584, 0.7355, 0.9231],
    [0.1328, 0.7716, 0.8858],
    [0.1117, 0.8057, 0.8452],
    [0.0975, 0.8371, 0.8034],
    [0.0927, 0.8655, 0.7623],
    [0.0996, 0.8904, 0.7239],
    [0.1201, 0.9119, 0.6866],
    [0.1532, 0.9315, 0.6431],
    [0.1966, 0.9490, 0.5947],
    [0.2480, 0.9642, 0.5430],
    [0.3051, 0.9770, 0.4899],
    [0.3658, 0.9870, 0.4369],
    [0.4278, 0.9942, 0.3857],
    [0.4888, 0.9983, 0.3382],
    [0.5466, 0.9991, 0.2958],
    [0.5989, 0.9964, 0.2604],
    [0.6436, 0.9900, 0.2336],
    [0.6849, 0.9794, 0.2160],
    [0.7260, 0.9647, 0.2064],
    [0.7661, 0.9463, 0.2031],
    [0.8047, 0.9245, 0.2046],
    [0.8413, 0.8999, 0.2093],
    [0.8753, 0.8727, 0.2155],
    [0.9061, 0.8434, 0.2219],
    [0.9330, 0.8124, 0.2267],
    [0.9556, 0.7801, 0.2284],
    [0.9732, 0.7468, 0.2254],
    [0.9855, 0.7125, 0.2165],
    [0.9931, 0.6741, 0.2035],
    [0.9965, 0.6319, 0.1874],
    [0.9959, 0.5870, 0.1690],
    [0.9915, 0.5404, 0.1491],
    [0.9836, 0.4929, 0.1285],
    [0.9723, 0.4456, 0.1080],
    [0.9580, 0.3996, 0.0883],
    [0.9408, 0.3557, 0.0703],
    [0.9211, 0.3149, 0.0548],
    [0.8989, 0.2782, 0.0424],
    [0.8742, 0.2453, 0.0330],
    [0.8466, 0.2141, 0.0249],
    [0.8161, 0.1846, 0.0181],
    [0.7826, 0.1569, 0.0126],
    [0.7462, 0.1310, 0.0085],
    [0.7068, 0.1068, 0.0057],
    [0.6645, 0.0844, 0.0042],
    [0.6192, 0.0637, 0.0041],
    [0.5710, 0.0447, 0.0053],
    [0.5199, 0.0276, 0.0078],
    [0.4796, 0.0158, 0.0106],
];

pub const INFERNO: [[f32; 3]; 65] = [
    [0.0015, 0.0005, 0.0139],
    [0.0060, 0.0047, 0.0386],
    [0.0140, 0.0112, 0.0719],
    [0.0258, 0.0193, 0.1059],
    [0.0423, 0.0281, 0.1411],
    [0.0613, 0.0366, 0.1776],
    [0.0820, 0.0433, 0.2153],
    [0.1046, 0.0470, 0.2534],
    [0.1293, 0.0473, 0.2908],
    [0.1558, 0.0446, 0.3253],
    [0.1834, 0.0403, 0.3550],
    [0.2111, 0.0370, 0.3786],
    [0.2383, 0.0366, 0.3964],
    [0.2648, 0.0396, 0.4093],
    [0.2908, 0.0456, 0.4186],
    [0.3163, 0.0535, 0.4251],
    [0.3415, 0.0623, 0.4294],
    [0.3665, 0.0716, 0.4320],
    [0.3915, 0.0809, 0.4331],
    [0.4163, 0.0902, 0.4329],
    [0.4412, 0.0993, 0.4316],
    [0.4661, 0.1083, 0.4291],
    [0.4910, 0.1172, 0.4256],
    [0.5160, 0.1260, 0.4209],
    [0.5409, 0.1347, 0.4151],
    [0.5659, 0.1436, 0.4083],
    [0.5907, 0.1526, 0.4003],
    [0.6155, 0.1618, 0.3912],
    [0.6401, 0.1714, 0.3811],
    [0.6645, 0.1815, 0.3698],
    [0.6887, 0.1922, 0.3576],
    [0.7124, 0.2037, 0.3444],
    [0.7357, 0.2159, 0.3302],
    [0.7584, 0.2291, 0.3153],
    [0.7805, 0.2433, 0.2995],
    [0.8019, 0.2587, 0.2831],
    [0.8224, 0.2752, 0.2661],
    [0.8420, 0.2929, 0.2486],
    [0.8605, 0.3119, 0.2306],
    [0.8780, 0.3321, 0.2123],
    [0.8943, 0.3534, 0.1936],
    [0.9094, 0.3759, 0.1746],
    [0.9232, 0.3994, 0.1552],
    [0.9357, 0.4238, 0.1354],
    [0.9470, 0.4492, 0.1153],
    [0.9569, 0.4754, 0.0947],
    [0.9654, 0.5022, 0.0739],
    [0.9726, 0.5298, 0.0533],
    [0.9784, 0.5579, 0.0349],
    [0.9829, 0.5866, 0.0247],
    [0.9860, 0.6158, 0.0256],
    [0.9876, 0.6453, 0.0399],
    [0.9879, 0.6753, 0.0653],
    [0.9867, 0.7055, 0.0957],
    [0.9841, 0.7361, 0.1295],
    [0.9800, 0.7668, 0.1664],
    [0.9746, 0.7977, 0.2063],
    [0.9680, 0.8285, 0.2500],
    [0.9606, 0.8591, 0.2980],
    [0.9532, 0.8889, 0.3514],
    [0.9476, 0.9174, 0.4107],
    [0.9469, 0.9433, 0.4750],
    [0.9545, 0.9659, 0.5404],
    [0.9712, 0.9853, 0.6022],
    [0.9884, 0.9984, 0.6449],
];

/// The tables in the view shader's order (map index − 1).
pub const COLORMAP_TABLES: [&[[f32; 3]; 65]; 3] = [&VIRIDIS, &TURBO, &INFERNO];

fn lookup(table: &[[f32; 3]; 65], t: f32) -> [f32; 3] {
    let s = t.clamp(0.0, 1.0) * 64.0;
    let i = (s as usize).min(63);
    let f = s - i as f32;
    [0, 1, 2].map(|k| table[i][k] + (table[i + 1][k] - table[i][k]) * f)
}

/// A map's display-encoded colour at t ∈ [0, 1].
pub fn colormap(map: Colormap, t: f32) -> [f32; 3] {
    let x = t.clamp(0.0, 1.0);
    let c = match map {
        Colormap::Grey => [x; 3],
        Colormap::Viridis => lookup(&VIRIDIS, x),
        Colormap::Turbo => lookup(&TURBO, x),
        Colormap::Inferno => lookup(&INFERNO, x),
    };
    c.map(|v| v.clamp(0.0, 1.0))
}

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

/// Bins of the GPU auto-range's histogram (`RANGE_BINS` in `shaders/view/view.wgsl`).
pub const RANGE_BINS: usize = 4096;
/// Bytes of the GPU auto-range's statistics: min key, max key, count, unused, the bins.
pub const RANGE_STATS_BYTES: u64 = (4 + RANGE_BINS as u64) * 4;

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
