// The next coarser mip level by voting (Soler et al. 004 §4 "Filtering of mipmap levels",
// Eq. 5, Fig. 5). Each coarse texel scores the sub-pixels of its 2×2 block with
// s(p_i) = Σ_{|p_i − p_j|₁ ≤ 1} g₁(|p_i − p_j|) g₂(1 − n_j·n_i) g₃((z_j − z_i)/z_i) over the
// L1 neighbourhood (which reaches one texel outside the block: the apron) and keeps the
// winner's position, depth, normal and material (SI, SP: the glossy reflection's) — no
// averaging. Radiance goes down as the block's mean (background is black); with
// `vote_power`, each sub-pixel's weighted by its Eq. 2 area over the winner's, so that the
// coarse texel, whose area Eq. 2 takes from the winner, emits its sub-pixels' power
// Σ L_i ds_i (the plain mean loses what the winner's smaller area leaves out); with
// `vote_consistent`, each sub-pixel's also weighted by g₂ on its normal against the winner's,
// so that the texel does not emit along the winner's normal the light of a sub-pixel that
// faces elsewhere (docs/readings.md, soler.vote-consistent).
// CPU twin: cpu::soler_vote::vote_level.
#import soler/common.wgsl

// Rust twin: passes::soler::pyramid::VoteParams.
struct VoteParams {
    // σ₁ (texels), σ₂ (on 1 − n·n), σ₃ (relative depth), 1 with `vote_consistent` else 0
    sigma: vec4<f32>,
    // xyz: the eye, w: Eq. 2's least cos β (< 0: the plain mean, no area weights)
    power: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: VoteParams;
@group(0) @binding(1) var fine_position: texture_2d<f32>;
@group(0) @binding(2) var fine_normal: texture_2d<f32>;
@group(0) @binding(3) var fine_radiance: texture_2d<f32>;
@group(0) @binding(4) var out_position: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var out_normal: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var out_radiance: texture_storage_2d<rgba32float, write>;
@group(0) @binding(7) var out_winner: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var fine_material: texture_2d<f32>;
@group(0) @binding(9) var out_material: texture_storage_2d<rgba32float, write>;

fn valid(p: vec2<i32>, size: vec2<u32>) -> bool {
    return inside(p, size) && textureLoad(fine_normal, p, 0).w > 0.5;
}

fn score(p: vec2<i32>, size: vec2<u32>) -> f32 {
    let n_i = textureLoad(fine_normal, p, 0).xyz;
    let z_i = textureLoad(fine_position, p, 0).w;
    var s = 0.0;
    var offsets = array<vec2<i32>, 5>(vec2<i32>(0, 0), vec2<i32>(1, 0), vec2<i32>(-1, 0), vec2<i32>(0, 1), vec2<i32>(0, -1));
    for (var j = 0; j < 5; j = j + 1) {
        let q = p + offsets[j];
        if (!valid(q, size)) {
            continue;
        }
        let n_j = textureLoad(fine_normal, q, 0).xyz;
        let z_j = textureLoad(fine_position, q, 0).w;
        let dist = f32(abs(offsets[j].x) + abs(offsets[j].y));
        s = s + gaussian(dist, params.sigma.x) * gaussian(1.0 - dot(n_i, n_j), params.sigma.y)
            * gaussian((z_j - z_i) / z_i, params.sigma.z);
    }
    return s;
}

// A sub-pixel's radiance as it enters the block's sum: weighted by its Eq. 2 area with
// `vote_power` (power.w ≥ 0), else as it is.
fn weighted_radiance(p: vec2<i32>) -> vec3<f32> {
    var weight = 1.0;
    if (params.power.w >= 0.0) {
        weight = area_factor(textureLoad(fine_position, p, 0), textureLoad(fine_normal, p, 0).xyz, params.power.xyz, params.power.w);
    }
    return textureLoad(fine_radiance, p, 0).rgb * weight;
}

// How far a sub-pixel of normal `n` faces as the winner (normal `n_w`) does: Eq. 5's g₂ on
// 1 − n·n_w, centred on the winner, with `vote_consistent`; 1 for every sub-pixel without it
// (cpu::soler_vote::consistency).
fn consistency(n: vec3<f32>, n_w: vec3<f32>) -> f32 {
    if (params.sigma.w < 0.5) {
        return 1.0;
    }
    return gaussian(1.0 - dot(n, n_w), params.sigma.y);
}

// The coarse texel's radiance from its 2×2 block, whose winner has `position` and `normal`:
// the sum of the sub-pixels' (area-weighted with `vote_power`) radiance, each weighted by its
// consistency w with the winner, over the sum of the weights (w for a surface sub-pixel, 1 for
// background inside the image: the block's count without `vote_consistent`) and, with
// `vote_power`, the winner's Eq. 2 area. The texel so stands for the winner's surface over the
// whole block, as Eq. 5 makes it for the depth and normal (a corner block keeps the winner's
// light instead of losing the other wall's).
fn block_radiance(gid: vec2<u32>, size: vec2<u32>, position: vec4<f32>, normal: vec3<f32>) -> vec4<f32> {
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    for (var i = 0; i < 4; i = i + 1) {
        let p = vec2<i32>(2 * i32(gid.x) + i % 2, 2 * i32(gid.y) + i / 2);
        if (!inside(p, size)) {
            continue;
        }
        if (!valid(p, size)) {
            count = count + 1.0;
            continue;
        }
        let w = consistency(textureLoad(fine_normal, p, 0).xyz, normal);
        sum = sum + w * weighted_radiance(p);
        count = count + w;
    }
    var winner_area = 1.0;
    if (params.power.w >= 0.0) {
        winner_area = max(area_factor(position, normal, params.power.xyz, params.power.w), 1e-20);
    }
    return vec4<f32>(sum / (max(count, 1.0) * winner_area), 1.0);
}

@compute @workgroup_size(8, 8, 1)
fn cs_vote(@builtin(global_invocation_id) gid: vec3<u32>) {
    let out_size = textureDimensions(out_position);
    if (gid.x >= out_size.x || gid.y >= out_size.y) {
        return;
    }
    let size = textureDimensions(fine_position);
    var best = -1;
    var best_score = 0.0;
    for (var i = 0; i < 4; i = i + 1) {
        let p = vec2<i32>(2 * i32(gid.x) + i % 2, 2 * i32(gid.y) + i / 2);
        if (!valid(p, size)) {
            continue;
        }
        let s = score(p, size);
        if (best < 0 || s > best_score) {
            best = i;
            best_score = s;
        }
    }
    var position = vec4<f32>(0.0);
    var normal = vec4<f32>(0.0);
    var radiance = vec4<f32>(0.0);
    var material = vec4<f32>(0.0);
    if (best >= 0) {
        let p = vec2<i32>(2 * i32(gid.x) + best % 2, 2 * i32(gid.y) + best / 2);
        position = textureLoad(fine_position, p, 0);
        normal = vec4<f32>(textureLoad(fine_normal, p, 0).xyz, 1.0);
        radiance = block_radiance(gid.xy, size, position, normal.xyz);
        material = textureLoad(fine_material, p, 0);
    }
    textureStore(out_position, gid.xy, position);
    textureStore(out_normal, gid.xy, normal);
    textureStore(out_radiance, gid.xy, radiance);
    textureStore(out_winner, gid.xy, vec4<f32>(f32(best), 0.0, 0.0, 0.0));
    textureStore(out_material, gid.xy, material);
}

// The radiance alone, with the winners of the vote already made this frame (004 §5.3:
// "successive bounces of indirect illumination share the mipmapping of G-Buffers"): a later
// bounce's light goes down the same levels, the block's (power-weighted) mean over the
// winner's Eq. 2 area, without voting again. The same values as cs_vote's radiance.
@group(0) @binding(10) var in_winner: texture_2d<f32>;
@group(0) @binding(11) var coarse_position: texture_2d<f32>;
@group(0) @binding(12) var coarse_normal: texture_2d<f32>;

@compute @workgroup_size(8, 8, 1)
fn cs_vote_radiance(@builtin(global_invocation_id) gid: vec3<u32>) {
    let out_size = textureDimensions(out_radiance);
    if (gid.x >= out_size.x || gid.y >= out_size.y) {
        return;
    }
    let size = textureDimensions(fine_position);
    var radiance = vec4<f32>(0.0);
    let c = vec2<i32>(gid.xy);
    if (textureLoad(in_winner, c, 0).x >= 0.0) {
        radiance = block_radiance(gid.xy, size, textureLoad(coarse_position, c, 0), textureLoad(coarse_normal, c, 0).xyz);
    }
    textureStore(out_radiance, gid.xy, radiance);
}
