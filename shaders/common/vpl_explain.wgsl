// A VPL's term at a receiver, as the replays of a pinned pixel show it (issue #42): the VPL
// gather at tiles or pixels (knecht/interleave/explain.wgsl) and the exact-VPL reference
// (reference/explain.wgsl). The term is vpl_radiance's (Knecht 002 Eq. 4.7–4.9), the very function
// their gathers call; this adds what made it. Needs common/vpl.wgsl.

// One VPL slot's term (passes::knecht::explain::GpuTerm).
struct VplTerm {
    // x: slot k; y: flags (EXPLAIN_*); z: the pixel it reached p through (x | y << 16; the
    // tiles' replay); w: its interleaving tile
    slot: vec4<u32>,
    // rgb: its light, visibility and the tile's N / N_t included (what the gather adds);
    // a: visibility
    light: vec4<f32>,
    // rgb: the same without visibility; a: geometry term cos θ_x cos θ_y / max(d², d_min²)
    unshadowed: vec4<f32>,
    // x: f_y, the VPL's BRDF toward the receiver (luminance); y: f_x, the receiver's BRDF
    // toward the eye (luminance); z: the map's stored depth; w: the receiver's depth in it
    detail: vec4<f32>,
    // rgb: its light as it reaches the pinned pixel: `light`, or after the demodulated filter
    // (knecht/interleave/explain.wgsl) its irradiance reflected with that pixel's colour
    reach: vec4<f32>,
}

const EXPLAIN_EMPTY: u32 = 1u;        // an empty slot (no VPL)
const EXPLAIN_OUTSIDE: u32 = 2u;      // its tile's pixel of the window is not p's (no filter) or outside the image
const EXPLAIN_FACING: u32 = 4u;       // the receiver faces away from it or it faces away from the receiver
const EXPLAIN_NEAR: u32 = 8u;         // closer than the near field's cut
const EXPLAIN_OCCLUDED: u32 = 16u;    // the visibility map hides the receiver
const EXPLAIN_FILTERED: u32 = 32u;    // the receiver is not on p's surface: the filter leaves it out
const EXPLAIN_CLAMPED: u32 = 64u;     // d < d_min: the geometry term is clamped
const EXPLAIN_BACKGROUND: u32 = 128u; // the receiver has no surface

// The term of `vpl` at receiver x (normal nx, colour c, material m = (DI, SI, SP)) seen from
// `eye`, before visibility: its light (`unshadowed`), the flags of the distance and the
// facing, the geometry term and both BRDFs.
fn vpl_term(vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, eye: vec3<f32>, c: vec3<f32>, m: vec3<f32>, dmin2: f32, near2: f32) -> VplTerm {
    var t: VplTerm;
    let l = vpl_radiance(vpl, x, nx, eye, c, m, dmin2, near2);
    let w = vpl.position.xyz - x;
    let d2 = dot(w, w);
    let dir = w * inverseSqrt(max(d2, 1e-12));
    let cos_x = dot(nx, dir);
    let cos_y = -dot(vpl.normal.xyz, dir);
    var flags = 0u;
    if (d2 < near2) {
        flags = flags | EXPLAIN_NEAR;
    } else if (cos_x <= 0.0 || cos_y <= 0.0) {
        flags = flags | EXPLAIN_FACING;
    }
    if (d2 < dmin2) {
        flags = flags | EXPLAIN_CLAMPED;
    }
    let lum = vec3<f32>(0.2126, 0.7152, 0.0722);
    let f_y = brdf_eval(vpl.normal.xyz, vpl.incident.xyz, -dir, vpl.albedo.rgb, vpl.normal.w, vpl.flux.a, vpl.incident.w);
    let f_x = brdf_eval(nx, dir, normalize(eye - x), c, m.x, m.y, m.z);
    t.slot = vec4<u32>(0u, flags, 0u, 0u);
    t.unshadowed = vec4<f32>(l, max(cos_x, 0.0) * max(cos_y, 0.0) / max(d2, dmin2));
    t.detail = vec4<f32>(dot(f_y, lum), dot(f_x, lum), 0.0, 0.0);
    return t;
}

// `t` with its visibility test (visibility, the map's stored depth, the receiver's), scaled by
// `scale` (the tile's N / N_t; 1 for every VPL of a batch).
fn vpl_term_seen(t: VplTerm, test: vec3<f32>, scale: f32) -> VplTerm {
    var s = t;
    let l = t.unshadowed.rgb;
    if (max(l.r, max(l.g, l.b)) > 0.0 && test.x < 0.5) {
        s.slot.y = s.slot.y | EXPLAIN_OCCLUDED;
    }
    s.light = vec4<f32>(l * test.x * scale, test.x);
    s.unshadowed = vec4<f32>(l * scale, t.unshadowed.a);
    s.detail = vec4<f32>(t.detail.xy, test.yz);
    s.reach = s.light;
    return s;
}
