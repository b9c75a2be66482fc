// One receiver texel's ring gather, term by term (Soler et al. 004 §3–4, Eq. 1–4, Fig. 3;
// glossy reflection §4 "Screen-space importance sampling"), shared by the gather on every
// texel (soler/gather.wgsl) and its replay at a pixel being explained
// (soler/explain_ring.wgsl), so that the replay's terms are the gather's. Needs
// soler/common.wgsl, soler/voxel_common.wgsl, soler/glossy.wgsl, common/random.wgsl and
// soler/ring.wgsl; the includer binds `params`, `grid`, `level_position`, `level_normal`,
// `level_radiance` and `level_material`.

// The receiver texel x: its position, normal, ring, rotation and glossy lobe.
struct RingReceiver {
    // xyz: position, w: view depth
    position: vec4<f32>,
    normal: vec3<f32>,
    inner: f32,
    dp: f32,
    rot: f32,
    // the receiver's lobe (cpu::soler_glossy::receiver_lobe) and whether it warps the angles
    lobe: vec2<f32>,
    warped: bool,
    // SI, SP of the texel
    material: vec2<f32>,
    // toward the eye
    v: vec3<f32>,
}

fn ring_receiver(x: vec2<i32>) -> RingReceiver {
    var r: RingReceiver;
    r.position = textureLoad(level_position, x, 0);
    r.normal = textureLoad(level_normal, x, 0).xyz;
    r.inner = ring_inner();
    r.dp = ring_area(r.inner);
    r.rot = rotation(vec2<u32>(x));
    let flags = u32(params.gloss.w);
    r.material = textureLoad(level_material, x, 0).xy;
    r.lobe = vec2<f32>(0.0);
    r.warped = false;
    if ((flags & 2u) != 0u && r.material.x > 0.0 && r.material.y >= params.gloss.z) {
        let a = params.right.xyz;
        let l = gloss_lobe_angle(r.position.xyz, r.normal, params.eye.xyz, a, params.up.xyz, params.forward.xyz, params.screen.xy);
        r.warped = l.y > 0.0;
        r.lobe = vec2<f32>(l.x, params.gloss.y * max(r.material.y, 0.0));
    }
    r.v = normalize(params.eye.xyz - r.position.xyz);
    return r;
}

// Sample i of receiver x's ring: its sender texel, its light L·K, whether it counts at all
// (a non-zero offset on a lit sender: `lit`) and whether the voxel march lets it through.
struct RingTerm {
    q: vec2<i32>,
    light: vec3<f32>,
    // its light through the receiver's specular lobe (with the glossy reflection)
    spec: vec3<f32>,
    lit: bool,
    visible: bool,
}

fn ring_term(x: vec2<i32>, r: RingReceiver, i: u32) -> RingTerm {
    var t: RingTerm;
    t.lit = false;
    t.visible = false;
    t.light = vec3<f32>(0.0);
    t.spec = vec3<f32>(0.0);
    let pw = gloss_warp(r.rot + f32(i) * GOLDEN_ANGLE, r.lobe, r.warped, params.gloss.x);
    let o = ring_offset(i, r.inner, pw.x);
    t.q = x + o;
    if (o.x == 0 && o.y == 0) {
        return t;
    }
    let sq = sender(t.q, r.position.xyz, r.normal);
    if (!sq.lit) {
        return t;
    }
    let ds = surface_area(sq.position, sq.normal, r.dp * pw.y);
    t.light = textureLoad(level_radiance, t.q, 0).rgb * kernel(sq.cos_t, sq.cos_tp, ds, sq.r2);
    t.lit = true;
    t.visible = params.voxels.grid.x == 0u || visible(x, r.position.w, t.q, sq.position.w);
    if ((u32(params.gloss.w) & 1u) != 0u) {
        t.spec = t.light * gloss_specular(r.normal, sq.w, r.v, r.material.x, r.material.y);
    }
    return t;
}
