// The demodulated confidence merge's split history (issue #51, knecht/temporal/confidence.wgsl): the
// irradiance E and the specular light S of L = k·E + S, six half floats in an Rgba32Uint texel,
// and the pixel's normal (issue #53): x = E.rg, y = (E.b, S.r), z = S.gb as pack2x16float,
// w = the normal as common/normal.wgsl packs it (the camera G-buffer's own word), or
// NO_NORMAL where no surface covers the pixel. The normal is next frame's n_prev (Eq. 3.2): kept in the word the
// split left free, it spares the merge a normals texture written and read (16 bytes a pixel).
// CPU twins: cpu::knecht::SplitLight, cpu::knecht::pack_normal / unpack_normal.
#import common/normal.wgsl

// E, S and the normal's word (pack_normal: the G-buffer's own) in one texel.
fn pack_split(e: vec3<f32>, s: vec3<f32>, normal_word: u32) -> vec4<u32> {
    return vec4<u32>(pack2x16float(e.xy), pack2x16float(vec2<f32>(e.z, s.x)), pack2x16float(s.yz), normal_word);
}

fn unpack_irradiance(v: vec4<u32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(v.x), unpack2x16float(v.y).x);
}

fn unpack_specular(v: vec4<u32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(v.y).y, unpack2x16float(v.z));
}
