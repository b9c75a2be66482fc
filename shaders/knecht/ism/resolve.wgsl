// Stage 4: the splatted distances (inverted f32 bits, 0 = empty) become distances in scene
// units (ISM_EMPTY in holes). `cs_resolve_pull` writes them straight into level 0 of
// `ism.atlas_pulled` and does pull-push's first pull in the same invocation, a 2×2 block of
// level 0 for each texel of level 1 (issue #53: no copy of the atlas, no second read of level
// 0; docs/architecture.md "The ISM's pull-push in fewer passes"); `cs_resolve` writes one
// level only: level 0 when pull-push has no levels, and `ism.atlas` (the maps as splatted)
// when something reads it.
const ISM_EMPTY: f32 = 1.0e30;

// The call's first row (`ism.rs` `IsmPass::finish_maps`: only the rows of the maps splatted
// since the last resolve) and the first pull's threshold; the twin of pull_push.wgsl's
// LevelParams: `cs_resolve` reads the level-0 push slot (tile.y: its first level-0 row),
// `cs_resolve_pull` the level-0 pull slot (threshold.x: t_pull at level 0; tile.y: its first
// level-1 row).
struct LevelParams {
    threshold: vec4<f32>,
    tile: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> depth: array<u32>;
@group(0) @binding(1) var atlas: texture_storage_2d<r32float, write>;
@group(0) @binding(2) var<uniform> lp: LevelParams;
// `cs_resolve_pull`: level 1 of the pulled atlas (`atlas` is its level 0).
@group(0) @binding(3) var level1: texture_storage_2d<r32float, write>;

// The distance splatted into texel i (ISM_EMPTY where nothing was).
fn distance_at(i: u32) -> f32 {
    let v = depth[i];
    if (v == 0u) {
        return ISM_EMPTY;
    }
    return bitcast<f32>(~v);
}

@compute @workgroup_size(8, 8, 1)
fn cs_resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(atlas);
    let g = vec2<u32>(gid.x, gid.y + lp.tile.y);
    if (g.x >= size.x || g.y >= size.y) {
        return;
    }
    textureStore(atlas, g, vec4<f32>(distance_at(g.y * size.x + g.x), 0.0, 0.0, 0.0));
}

// (sum, count) with v added when it is a distance within t of the nearest child.
fn pull_add(acc: vec2<f32>, v: f32, nearest: f32, t: f32) -> vec2<f32> {
    if (v < ISM_EMPTY && v - nearest <= t) {
        return acc + vec2<f32>(v, 1.0);
    }
    return acc;
}

// One texel of level 1: its four children resolved into level 0 and pulled as pull_push.wgsl's
// `cs_pull` does (the same sums in the same order; CPU twin: cpu::knecht::pull_push).
@compute @workgroup_size(8, 8, 1)
fn cs_resolve_pull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(level1);
    let g = vec2<u32>(gid.x, gid.y + lp.tile.y);
    if (g.x >= size.x || g.y >= size.y) {
        return;
    }
    let width = textureDimensions(atlas).x;
    let c = g * 2u;
    let i = c.y * width + c.x;
    let v0 = distance_at(i);
    let v1 = distance_at(i + 1u);
    let v2 = distance_at(i + width);
    let v3 = distance_at(i + width + 1u);
    textureStore(atlas, c, vec4<f32>(v0, 0.0, 0.0, 0.0));
    textureStore(atlas, c + vec2<u32>(1u, 0u), vec4<f32>(v1, 0.0, 0.0, 0.0));
    textureStore(atlas, c + vec2<u32>(0u, 1u), vec4<f32>(v2, 0.0, 0.0, 0.0));
    textureStore(atlas, c + vec2<u32>(1u, 1u), vec4<f32>(v3, 0.0, 0.0, 0.0));
    let nearest = min(min(v0, v1), min(v2, v3));
    var out = ISM_EMPTY;
    if (nearest < ISM_EMPTY) {
        let t = lp.threshold.x;
        var acc = pull_add(vec2<f32>(0.0), v0, nearest, t);
        acc = pull_add(acc, v1, nearest, t);
        acc = pull_add(acc, v2, nearest, t);
        acc = pull_add(acc, v3, nearest, t);
        out = acc.x / acc.y;
    }
    textureStore(level1, g, vec4<f32>(out, 0.0, 0.0, 0.0));
}
