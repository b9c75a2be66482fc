// The demodulated confidence merge's split history (issue #51, knecht/temporal/confidence.wgsl): the
// irradiance E and the specular light S of L = k·E + S, six half floats in an Rgba32Uint texel:
// x = E.rg, y = (E.b, S.r), z = S.gb as pack2x16float, w unused. CPU twin: cpu::knecht::SplitLight.

fn pack_split(e: vec3<f32>, s: vec3<f32>) -> vec4<u32> {
    return vec4<u32>(pack2x16float(e.xy), pack2x16float(vec2<f32>(e.z, s.x)), pack2x16float(s.yz), 0u);
}

fn unpack_irradiance(v: vec4<u32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(v.x), unpack2x16float(v.y).x);
}

fn unpack_specular(v: vec4<u32>) -> vec3<f32> {
    return vec3<f32>(unpack2x16float(v.y).y, unpack2x16float(v.z));
}
