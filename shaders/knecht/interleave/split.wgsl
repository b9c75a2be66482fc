// Stage 5, interleaved sampling (Knecht 002 §3.4.1, after Keller and Heidrich 2001): the
// camera G-buffer is split into n×n tiles; pixel (a, b) of tile (i, j) is the G-buffer pixel
// (a·n + i, b·n + j), so that every tile shows the whole image at 1/n resolution. Tiles are
// ⌈W/n⌉ × ⌈H/n⌉; split pixels without a source pixel are background (normal.w = 0).
#import common/fullscreen.wgsl
#import common/normal.wgsl

struct SplitParams {
    // x: n, y: tile width, z: tile height
    n: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: SplitParams;
// The camera G-buffer's linear depth (issue #53): the gather rebuilds the point from it at the
// split pixel's source pixel.
@group(0) @binding(1) var g_position: texture_2d<f32>;
// Its packed normals (common/normal.wgsl, issue #53): the split holds them unpacked, as
// `gbuffer.normal` shows them.
@group(0) @binding(2) var g_normal: texture_2d<u32>;
@group(0) @binding(3) var g_albedo: texture_2d<f32>;
@group(0) @binding(4) var g_material: texture_2d<f32>;
@group(0) @binding(5) var s_position: texture_storage_2d<r32float, write>;
@group(0) @binding(6) var s_normal: texture_storage_2d<rgba16float, write>;
@group(0) @binding(7) var s_albedo: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(8) var s_material: texture_storage_2d<rgba16float, write>;

// The G-buffer pixel of split pixel s (x = −1 when there is none).
fn split_source(s: vec2<u32>, n: u32, tile: vec2<u32>, size: vec2<u32>) -> vec2<i32> {
    let t = s / tile;
    let a = s % tile;
    let p = a * n + t;
    if (p.x >= size.x || p.y >= size.y) {
        return vec2<i32>(-1);
    }
    return vec2<i32>(p);
}

@compute @workgroup_size(TILE, TILE, 1)
fn cs_split(@builtin(global_invocation_id) gid: vec3<u32>) {
    let ssize = textureDimensions(s_position);
    if (gid.x >= ssize.x || gid.y >= ssize.y) {
        return;
    }
    let src = split_source(gid.xy, params.n.x, params.n.yz, textureDimensions(g_position));
    if (src.x < 0) {
        textureStore(s_position, gid.xy, vec4<f32>(0.0));
        textureStore(s_normal, gid.xy, vec4<f32>(0.0));
        textureStore(s_albedo, gid.xy, vec4<f32>(0.0));
        textureStore(s_material, gid.xy, vec4<f32>(0.0));
        return;
    }
    textureStore(s_position, gid.xy, textureLoad(g_position, src, 0));
    textureStore(s_normal, gid.xy, gbuffer_normal(textureLoad(g_normal, src, 0).x));
    textureStore(s_albedo, gid.xy, textureLoad(g_albedo, src, 0));
    textureStore(s_material, gid.xy, textureLoad(g_material, src, 0));
}
