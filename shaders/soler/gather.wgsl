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
#import soler/ring_texel.wgsl

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
    let r = ring_receiver(x);
    var hidden = vec3<f32>(0.0);
    var lit = 0u;
    var seen = 0u;
    var e = vec3<f32>(0.0);
    var spec = vec3<f32>(0.0);
    for (var i = 0u; i < params.counts.x; i = i + 1u) {
        let t = ring_term(x, r, i);
        if (!t.lit) {
            continue;
        }
        lit = lit + 1u;
        if (!t.visible) {
            hidden = hidden + t.light;
            continue;
        }
        seen = seen + 1u;
        e = e + t.light;
        spec = spec + t.spec;
    }
    textureStore(out_light, gid.xy, vec4<f32>(e, 1.0));
    textureStore(out_occlusion, gid.xy, vec4<f32>(hidden, f32(seen) / f32(max(lit, 1u))));
    textureStore(out_specular, gid.xy, vec4<f32>(spec, 1.0));
}
