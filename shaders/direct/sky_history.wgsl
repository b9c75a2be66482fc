// Stage 2's running average of the direct light over still frames while the sky's directions
// rotate (issue #51, `sky.rotate_each_frame`): each frame lights the screen with another
// shifted set of N_sky directions (scene::sky::sky_shift), and the average of k frames is the
// estimate of k·N_sky directions. history_k = history_{k−1} + (L_k − history_{k−1}) / k;
// k = 1 takes this frame's light alone (after any change). CPU twin: the arithmetic of
// passes::direct_history::running_average.

// x: 1/k, the weight of this frame's light
@group(0) @binding(0) var<uniform> params: vec4<f32>;
@group(0) @binding(1) var prev: texture_2d<f32>;
@group(0) @binding(2) var current: texture_2d<f32>;
@group(0) @binding(3) var next: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_average(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(next);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let l = textureLoad(current, gid.xy, 0);
    var h = l;
    if (params.x < 1.0) {
        let p = textureLoad(prev, gid.xy, 0);
        h = p + (l - p) * params.x;
    }
    textureStore(next, gid.xy, h);
}
