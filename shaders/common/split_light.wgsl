// The demodulated confidence merge's split history (issue #51, knecht/temporal/confidence.wgsl): the
// irradiance E and the specular light S of L = k·E + S, six half floats in an Rgba32Uint texel,
// and the pixel's normal (issue #53): x = E.rg, y = (E.b, S.r), z = S.gb as pack2x16float,
// w = the normal in octahedral coordinates as pack2x16snorm, or SPLIT_NO_NORMAL where no
// surface covers the pixel. The normal is next frame's n_prev (Eq. 3.2): kept in the word the
// split left free, it spares the merge a normals texture written and read (16 bytes a pixel).
// CPU twins: cpu::knecht::SplitLight, cpu::knecht::pack_normal / unpack_normal.

// pack2x16snorm never writes −32768 (it rounds clamp(v, −1, 1) · 32767), so this word is no
// normal's.
const SPLIT_NO_NORMAL: u32 = 0x80008000u;

// The octahedral map of a unit vector (Cigolle et al. 2014, "A Survey of Efficient Representations for Independent
// Unit Vectors", JCGT 3(2), §3.3):
// the upper half projected onto the square |x| + |y| ≤ 1, the lower half folded over its edges.
fn octahedral_fold(v: vec2<f32>) -> vec2<f32> {
    let s = select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
    return (vec2<f32>(1.0) - abs(v.yx)) * s;
}

fn pack_normal(n: vec4<f32>) -> u32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if (n.w < 0.5 || l1 <= 0.0) {
        return SPLIT_NO_NORMAL;
    }
    var p = n.xy / l1;
    if (n.z < 0.0) {
        p = octahedral_fold(p);
    }
    return pack2x16snorm(p);
}

// The normal (xyz, unit) and its coverage (w = 1), or 0 where the word holds none.
fn unpack_normal(w: u32) -> vec4<f32> {
    if (w == SPLIT_NO_NORMAL) {
        return vec4<f32>(0.0);
    }
    let p = unpack2x16snorm(w);
    var n = vec3<f32>(p, 1.0 - abs(p.x) - abs(p.y));
    if (n.z < 0.0) {
        n = vec3<f32>(octahedral_fold(n.xy), n.z);
    }
    return vec4<f32>(normalize(n), 1.0);
}

// E, S and the normal n (w: coverage) in one texel.
fn pack_split(e: vec3<f32>, s: vec3<f32>, n: vec4<f32>) -> vec4<u32> {
    return vec4<u32>(pack2x16float(e.xy), pack2x16float(vec2<f32>(e.z, s.x)), pack2x16float(s.yz), pack_normal(n));
}

fn unpack_irradiance(v: vec4<u32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(v.x), unpack2x16float(v.y).x);
}

fn unpack_specular(v: vec4<u32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(v.y).y, unpack2x16float(v.z));
}
