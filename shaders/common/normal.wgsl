// A unit normal in one 32-bit word (issue #53): its octahedral coordinates (Cigolle et al.
// 2014, "A Survey of Efficient Representations for Independent Unit Vectors", JCGT 3(2),
// §3.3) as two 16-bit snorms, under 10⁻⁴ rad from the normal it packs. The camera G-buffer's
// normal target holds this word (`passes::gbuffer::PACKED_NORMAL_FORMAT`), and the
// demodulated merge's split history keeps it as next frame's n_prev (common/split_light.wgsl).
// CPU twins: cpu::knecht::pack_normal / unpack_normal.

// pack2x16snorm never writes −32768 (it rounds clamp(v, −1, 1) · 32767), so this word is no
// normal's: the word of a pixel no surface covers (the G-buffer's clear value).
const NO_NORMAL: u32 = 0x80008000u;

// The octahedral map's fold: the upper half projected onto the square |x| + |y| ≤ 1, the
// lower half folded over its edges.
fn octahedral_fold(v: vec2<f32>) -> vec2<f32> {
    let s = select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
    return (vec2<f32>(1.0) - abs(v.yx)) * s;
}

// The word of normal n.xyz where n.w (coverage) is 1, NO_NORMAL elsewhere.
fn pack_normal(n: vec4<f32>) -> u32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if (n.w < 0.5 || l1 <= 0.0) {
        return NO_NORMAL;
    }
    var p = n.xy / l1;
    if (n.z < 0.0) {
        p = octahedral_fold(p);
    }
    return pack2x16snorm(p);
}

// The normal (xyz, unit) and its coverage (w = 1), or 0 where the word holds none.
fn unpack_normal(w: u32) -> vec4<f32> {
    if (w == NO_NORMAL) {
        return vec4<f32>(0.0);
    }
    let p = unpack2x16snorm(w);
    var n = vec3<f32>(p, 1.0 - abs(p.x) - abs(p.y));
    if (n.z < 0.0) {
        n = vec3<f32>(octahedral_fold(n.xy), n.z);
    }
    return vec4<f32>(normalize(n), 1.0);
}

// x rounded to the nearest binary16 value, ties to even (CPU twin: buffers::round_to_half),
// for |x| ≤ 1: the mantissa's lowest 13 bits rounded off, or a multiple of 2⁻²⁴ below 2⁻¹⁴ (the
// half floats' subnormals). quantizeToF16 means the same, but lavapipe runs it several times
// slower (issue #53: with it the merge's filter took half again as long).
fn round_to_half(x: f32) -> f32 {
    if (abs(x) < 6.103515625e-05) {
        return round(x * 16777216.0) / 16777216.0;
    }
    let b = bitcast<u32>(x);
    return bitcast<f32>((b + 0xfffu + ((b >> 13u) & 1u)) & 0xffffe000u);
}

// The camera G-buffer's normal at a pixel from its packed word, as `gbuffer.normal` stores it
// (half floats, gbuffer/normal.wgsl): every pass shades with the normal the viewer, the probe,
// the pixel explanation and the CPU twins read back, bit for bit.
fn gbuffer_normal(w: u32) -> vec4<f32> {
    let n = unpack_normal(w);
    return vec4<f32>(round_to_half(n.x), round_to_half(n.y), round_to_half(n.z), n.w);
}
