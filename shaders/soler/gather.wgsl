// The indirect lighting shader of Soler et al. (004 §3–4, Eq. 1–4, Fig. 3), run on one mip
// level: every texel gathers N samples of a ring of radius r/2 … r (the full disc of radius r
// on the first, finest gathered level) in the level's own texels, a Vogel spiral rotated per
// texel and frame, each sample standing for 1/N of the ring's area dP. A sample's radiance L
// (the previous bounce) reaches the texel through Eq. 3: ds by Eq. 2 (with the half angles,
// W H the level's size — the 2^{2k} of §4), and the point-to-disc form factor of Eq. 4 times
// π in place of cosθ cosθ' ds / r² (or that point-to-point term, a setting). The texel keeps
// the irradiance E = Σ L_i K_i; the receiver reflects it with c·DI/π after upsampling.
// Visibility v_i (004 §4 "Visibility", a setting): a march through this level's voxel grid
// from the receiver's texel to the sample's, depth interpolated as 1/z (perspective-correct),
// skipping `bias` texels at both ends and testing the slice `depth bias` slices in front of
// the line; a solid voxel on the way hides the sample. Without it v_i = 1. The second output
// keeps, per texel, the light the visibility removed (rgb) and the visible fraction of the
// samples that carried light (a). Glossy reflection (004 §4 "Screen-space importance
// sampling", soler/glossy.wgsl): each sample also adds L_i K_i f_s(l_i, v) into the third
// output, and a glossy receiver draws its angles from f(θ). As the near field of a VPL gather (`pipeline.near_field`), senders
// at the cut distance or farther are skipped: the VPLs take them. CPU twin: cpu::soler::{ring_sample, ring_rotation, surface_area,
// kernel, gather}.
#import soler/common.wgsl
#import soler/voxel_common.wgsl
#import soler/glossy.wgsl
#import common/random.wgsl

#import soler/ring.wgsl

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var level_position: texture_2d<f32>;
@group(0) @binding(2) var level_normal: texture_2d<f32>;
@group(0) @binding(3) var level_radiance: texture_2d<f32>;
@group(0) @binding(4) var out_light: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var<storage, read> grid: array<u32>;
@group(0) @binding(6) var out_occlusion: texture_storage_2d<rgba32float, write>;
// SI (r), SP (g) of the level's texels.
@group(0) @binding(7) var level_material: texture_2d<f32>;
@group(0) @binding(8) var out_specular: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(level_position);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let x = vec2<i32>(gid.xy);
    let nx = textureLoad(level_normal, x, 0);
    if (nx.w < 0.5) {
        textureStore(out_light, gid.xy, vec4<f32>(0.0));
        textureStore(out_occlusion, gid.xy, vec4<f32>(0.0));
        textureStore(out_specular, gid.xy, vec4<f32>(0.0));
        return;
    }
    let px4 = textureLoad(level_position, x, 0);
    let px = px4.xyz;
    var hidden = vec3<f32>(0.0);
    var lit = 0u;
    var seen = 0u;
    let n = nx.xyz;
    let count = params.counts.x;
    let inner = ring_inner();
    let dp = ring_area(inner);
    let rot = rotation(gid.xy);
    var e = vec3<f32>(0.0);
    // The glossy reflection: the receiver's lobe (cpu::soler_glossy::receiver_lobe).
    let flags = u32(params.gloss.w);
    let glossy = (flags & 1u) != 0u;
    let mat = textureLoad(level_material, x, 0).xy;
    var lobe = vec2<f32>(0.0);
    var warped = false;
    if ((flags & 2u) != 0u && mat.x > 0.0 && mat.y >= params.gloss.z) {
        let a = params.right.xyz;
        let l = gloss_lobe_angle(px, n, params.eye.xyz, a, params.up.xyz, params.forward.xyz, params.screen.xy);
        warped = l.y > 0.0;
        lobe = vec2<f32>(l.x, params.gloss.y * max(mat.y, 0.0));
    }
    let v = normalize(params.eye.xyz - px);
    var spec = vec3<f32>(0.0);
    for (var i = 0u; i < count; i = i + 1u) {
        let pw = gloss_warp(rot + f32(i) * GOLDEN_ANGLE, lobe, warped, params.gloss.x);
        let o = ring_offset(i, inner, pw.x);
        if (o.x == 0 && o.y == 0) {
            continue;
        }
        let q = x + o;
        let sq = sender(q, px, n);
        if (!sq.lit) {
            continue;
        }
        let w = sq.w;
        let ds = surface_area(sq.position, sq.normal, dp * pw.y);
        let light = textureLoad(level_radiance, q, 0).rgb * kernel(sq.cos_t, sq.cos_tp, ds, sq.r2);
        lit = lit + 1u;
        if (params.voxels.grid.x > 0u && !visible(x, px4.w, q, sq.position.w)) {
            hidden = hidden + light;
            continue;
        }
        seen = seen + 1u;
        e = e + light;
        if (glossy) {
            spec = spec + light * gloss_specular(n, w, v, mat.x, mat.y);
        }
    }
    textureStore(out_light, gid.xy, vec4<f32>(e, 1.0));
    textureStore(out_occlusion, gid.xy, vec4<f32>(hidden, f32(seen) / f32(max(lit, 1u))));
    textureStore(out_specular, gid.xy, vec4<f32>(spec, 1.0));
}
