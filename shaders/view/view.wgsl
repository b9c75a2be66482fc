// The buffer viewer (docs/principles.md principle 6): maps any registered texture — float, uint
// or depth, 2D or array, any level — to display colour. Raw texels are fetched with
// textureLoad (never filtered), so every format displays safely. CPU twin:
// `render/src/cpu/view.rs` (the tests compare the two).

struct ViewParams {
    // (lo, hi, 2^exposure, 0): the value range mapped to [0, 1] after the exposure scale.
    range: vec4<f32>,
    // (mode, channel, colormap, flags | source kind << 8); mode 0 = RGB, 1 = one channel,
    // 2 = length of xyz; source kinds as `SourceKind` in `render/src/passes/view.rs`.
    modes: vec4<u32>,
    // (layer, level, 0, 0) of the source texture.
    source: vec4<u32>,
};

const FLAG_LOG: u32 = 1u;
const FLAG_SRGB: u32 = 2u;
const FLAG_NAN_INF: u32 = 4u;
const FLAG_NEGATIVE: u32 = 8u;

@group(0) @binding(0) var<uniform> params: ViewParams;
@group(0) @binding(1) var src_float: texture_2d<f32>;
@group(0) @binding(2) var src_float_array: texture_2d_array<f32>;
@group(0) @binding(3) var src_uint: texture_2d<u32>;
@group(0) @binding(4) var src_uint_array: texture_2d_array<u32>;
@group(0) @binding(5) var src_depth: texture_depth_2d;
@group(0) @binding(6) var src_depth_array: texture_depth_2d_array;
// False-colour tables, 65 entries each: viridis, Turbo, inferno (sampled from matplotlib's
// tables; uploaded from `cpu::view::COLORMAP_TABLES`, the one copy of the data).
@group(0) @binding(7) var<storage, read> colormaps: array<vec4<f32>>;

// The auto-range's statistics (cs_range_*, issue #38: the range is reduced on the GPU and
// 16 KB are read back instead of the whole texture): [0] the smallest and [1] the largest
// order key of the finite values the mode shows, [2] their count, [3] unused, then a
// histogram of RANGE_BINS bins over [min key, max key] (key − min key shifted right until
// the span fits). CPU twin and decoding: cpu::view::{order_key, range_from_stats}.
@group(0) @binding(8) var<storage, read_write> range_stats: array<atomic<u32>>;

const LUT_SIZE: u32 = 65u;
const RANGE_BINS: u32 = 4096u;

// Map index: 0 grey, 1 viridis, 2 turbo, 3 inferno. The result is display-encoded (sRGB).
fn colormap(map: u32, t: f32) -> vec3<f32> {
    let x = clamp(t, 0.0, 1.0);
    if map == 0u || map > 3u {
        return vec3<f32>(x);
    }
    let s = x * f32(LUT_SIZE - 1u);
    let i = min(u32(s), LUT_SIZE - 2u);
    let base = (map - 1u) * LUT_SIZE;
    return mix(colormaps[base + i].rgb, colormaps[base + i + 1u].rgb, s - f32(i));
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the target.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn raw_value(p: vec2<i32>) -> vec4<f32> {
    let level = i32(params.source.y);
    let layer = i32(params.source.x);
    switch params.modes.w >> 8u {
        case 1u: { return textureLoad(src_float_array, p, layer, level); }
        case 2u: { return vec4<f32>(textureLoad(src_uint, p, level)); }
        case 3u: { return vec4<f32>(textureLoad(src_uint_array, p, layer, level)); }
        case 4u: { return vec4<f32>(textureLoad(src_depth, p, level), 0.0, 0.0, 1.0); }
        case 5u: { return vec4<f32>(textureLoad(src_depth_array, p, layer, level), 0.0, 0.0, 1.0); }
        default: { return textureLoad(src_float, p, level); }
    }
}

fn is_nan(x: f32) -> bool {
    // NaN is the only value that is not equal to itself; written with bit patterns so that
    // no compiler may fold the comparison away.
    let b = bitcast<u32>(x);
    return (b & 0x7f800000u) == 0x7f800000u && (b & 0x007fffffu) != 0u;
}

fn is_inf(x: f32) -> bool {
    let b = bitcast<u32>(x);
    return (b & 0x7fffffffu) == 0x7f800000u;
}

// Maps a scaled value to [0, 1] over the range, linearly or logarithmically.
// NaN maps to 0 (black) when the overlay is off.
fn normalise(x: f32) -> f32 {
    if is_nan(x) {
        return 0.0;
    }
    let lo = params.range.x;
    let hi = params.range.y;
    if (params.modes.w & FLAG_LOG) != 0u {
        let l = max(lo, 1e-8);
        let h = max(hi, l * 1.000001);
        return clamp(log2(max(x, l) / l) / log2(h / l), 0.0, 1.0);
    }
    return clamp((x - lo) / max(hi - lo, 1e-20), 0.0, 1.0);
}

fn srgb_encode(c: f32) -> f32 {
    if c <= 0.0031308 { return 12.92 * c; }
    return 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

@fragment
fn fs_main(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let v = raw_value(vec2<i32>(frag.xy));
    let mode = params.modes.x;
    let flags = params.modes.w;
    // The components the mode looks at: the overlay only flags values that are shown.
    var n = 3u;
    var comps = v;
    if mode == 1u {
        comps = vec4<f32>(v[min(params.modes.y, 3u)]);
        n = 1u;
    }
    if (flags & FLAG_NAN_INF) != 0u {
        for (var i = 0u; i < n; i++) {
            if is_nan(comps[i]) { return vec4<f32>(1.0, 0.0, 1.0, 1.0); }
        }
        for (var i = 0u; i < n; i++) {
            if is_inf(comps[i]) { return vec4<f32>(0.0, 1.0, 0.0, 1.0); }
        }
    }
    if (flags & FLAG_NEGATIVE) != 0u {
        for (var i = 0u; i < n; i++) {
            if comps[i] < 0.0 && !is_nan(comps[i]) { return vec4<f32>(0.0, 0.9, 1.0, 1.0); }
        }
    }
    let scale = params.range.z;
    var rgb: vec3<f32>;
    if mode == 0u {
        rgb = vec3<f32>(normalise(v.x * scale), normalise(v.y * scale), normalise(v.z * scale));
        if (params.modes.w & FLAG_SRGB) != 0u {
            rgb = vec3<f32>(srgb_encode(rgb.x), srgb_encode(rgb.y), srgb_encode(rgb.z));
        }
    } else {
        var s = comps.x;
        if mode == 2u { s = length(v.xyz); }
        rgb = colormap(params.modes.z, normalise(s * scale));
    }
    return vec4<f32>(rgb, 1.0);
}

// ---- Auto-range on the GPU -----------------------------------------------------------

// A u32 that orders as the float does (negative values reversed below the positive ones).
fn order_key(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b ^ 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

// The size of the source's level.
fn source_size() -> vec2<i32> {
    let level = i32(params.source.y);
    switch params.modes.w >> 8u {
        case 1u: { return vec2<i32>(textureDimensions(src_float_array, level)); }
        case 2u: { return vec2<i32>(textureDimensions(src_uint, level)); }
        case 3u: { return vec2<i32>(textureDimensions(src_uint_array, level)); }
        case 4u: { return vec2<i32>(textureDimensions(src_depth, level)); }
        case 5u: { return vec2<i32>(textureDimensions(src_depth_array, level)); }
        default: { return vec2<i32>(textureDimensions(src_float, level)); }
    }
}

// The values the mode shows at p (xyz, the first n of them), as cpu::view::auto_range takes
// them: RGB its three, one channel, or the length of xyz.
fn shown_values(p: vec2<i32>) -> vec4<f32> {
    let v = raw_value(p);
    switch params.modes.x {
        case 1u: { return vec4<f32>(v[min(params.modes.y, 3u)], 0.0, 0.0, 1.0); }
        case 2u: { return vec4<f32>(length(v.xyz), 0.0, 0.0, 1.0); }
        default: { return vec4<f32>(v.xyz, 3.0); }
    }
}

fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

@compute @workgroup_size(256, 1, 1)
fn cs_range_clear(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x < arrayLength(&range_stats)) {
        atomicStore(&range_stats[gid.x], select(0u, 0xffffffffu, gid.x == 0u));
    }
}

var<workgroup> wg_min: atomic<u32>;
var<workgroup> wg_max: atomic<u32>;
var<workgroup> wg_count: atomic<u32>;

@compute @workgroup_size(8, 8, 1)
fn cs_range_minmax(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if (li == 0u) {
        atomicStore(&wg_min, 0xffffffffu);
        atomicStore(&wg_max, 0u);
        atomicStore(&wg_count, 0u);
    }
    workgroupBarrier();
    let p = vec2<i32>(gid.xy);
    let size = source_size();
    if (p.x < size.x && p.y < size.y) {
        let v = shown_values(p);
        for (var i = 0u; i < u32(v.w); i = i + 1u) {
            if (finite(v[i])) {
                let k = order_key(v[i]);
                atomicMin(&wg_min, k);
                atomicMax(&wg_max, k);
                atomicAdd(&wg_count, 1u);
            }
        }
    }
    workgroupBarrier();
    if (li == 0u && atomicLoad(&wg_count) > 0u) {
        atomicMin(&range_stats[0], atomicLoad(&wg_min));
        atomicMax(&range_stats[1], atomicLoad(&wg_max));
        atomicAdd(&range_stats[2], atomicLoad(&wg_count));
    }
}

@compute @workgroup_size(8, 8, 1)
fn cs_range_histogram(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = vec2<i32>(gid.xy);
    let size = source_size();
    let lo = atomicLoad(&range_stats[0]);
    let hi = atomicLoad(&range_stats[1]);
    if (p.x >= size.x || p.y >= size.y || hi < lo) {
        return;
    }
    let bits = 32u - countLeadingZeros(hi - lo);
    let shift = select(0u, bits - 12u, bits > 12u);
    let v = shown_values(p);
    for (var i = 0u; i < u32(v.w); i = i + 1u) {
        if (finite(v[i])) {
            atomicAdd(&range_stats[4u + ((order_key(v[i]) - lo) >> shift)], 1u);
        }
    }
}
