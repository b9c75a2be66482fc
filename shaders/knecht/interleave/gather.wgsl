// Stages 5–6 (Knecht 002 §3.4.1–3.4.2, §4.5): all VPLs shaded in one dispatch over the split
// G-buffer. Slots are cut into blocks of n² consecutive slots and tile t (= i + j·n) takes
// slot b·n² + (t + o_b) mod n² of block b, with per-frame offsets o_b that are a permutation
// of 0…n² over every n² blocks (CPU twin and why: cpu::knecht::tile_offsets). Each split pixel
// gathers its tile's N_t VPLs, scaled by N / N_t so that each tile is an unbiased estimate of
// all N (the n×n filter averages the tiles). Each VPL: Eq. 4.7–4.9 (common/vpl.wgsl) times
// its visibility — the ISM (common/ism.wgsl), the exact cube-face maps, or none. Beside the
// light it writes the irradiance the same VPLs give (Σ E_k · V_k · N/N_t, out_irradiance): the
// demodulated filter reflects it with each pixel's own colour (filter.wgsl, issue #51).
#import common/camera.wgsl
#import common/ism.wgsl
#import common/fullscreen.wgsl
#import knecht/interleave/params.wgsl
#import common/normal.wgsl

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: GatherParams;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(3) var ism_atlas: texture_2d<f32>;
@group(0) @binding(4) var exact_atlas: texture_2d<f32>;
// Linear depth (the camera G-buffer's or the split one, issue #53): the point is rebuilt at the
// source pixel (common/camera.wgsl world_from_linear_depth).
@group(0) @binding(5) var s_position: texture_2d<f32>;
// The camera G-buffer's packed normals (the fused gather, common/normal.wgsl, issue #53), or a
// 1×1 stand-in beside the split G-buffer's unpacked ones (`s_normal_split`, the thesis' layout).
@group(0) @binding(6) var s_normal: texture_2d<u32>;
@group(0) @binding(7) var s_albedo: texture_2d<f32>;
@group(0) @binding(8) var s_material: texture_2d<f32>;
@group(0) @binding(9) var out_accum: texture_storage_2d<rgba16float, write>;
@group(0) @binding(10) var<storage, read> tile_offsets: array<u32>;
@group(0) @binding(11) var out_irradiance: texture_storage_2d<rgba16float, write>;
@group(0) @binding(12) var s_normal_split: texture_2d<f32>;

// A split pixel's gathered light and the irradiance it came from.
struct Gathered {
    light: vec3<f32>,
    irradiance: vec3<f32>,
}

// The light of split pixel `sp`'s tile's VPLs at the pixel `px` of the bound textures (the
// split G-buffer at sp itself, or the G-buffer at sp's source pixel), whose G-buffer pixel is
// `src`, and whose normal is `nrm` (w: coverage).
fn gather_at(px: vec2<i32>, sp: vec2<u32>, src: vec2<i32>, nrm: vec4<f32>) -> Gathered {
    var sum = vec3<f32>(0.0);
    var irr = vec3<f32>(0.0);
    let n = params.split.x;
    let count = params.split.w;
    let t2 = sp / params.split.yz;
    let tile = t2.x + t2.y * n;
    let stride = n * n;
    if (nrm.w > 0.5) {
        let x = world_from_linear_depth(camera, src, textureLoad(s_position, px, 0).x);
        let nx = normalize(nrm.xyz);
        let alb = textureLoad(s_albedo, px, 0);
        let mat = textureLoad(s_material, px, 0);
        let m = vec3<f32>(alb.a, select(mat.x, 0.0, params.vis.w == 1u), mat.y);
        let blocks = (count + stride - 1u) / stride;
        var per_tile = 0u;
        for (var b = 0u; b < blocks; b = b + 1u) {
            let k = b * stride + (tile + tile_offsets[b]) % stride;
            if (k >= count) {
                continue;
            }
            per_tile = per_tile + 1u;
            let vpl = vpls[k];
            if (vpl.position.w < 0.5) {
                continue;
            }
            // vpl_radiance's two factors, the irradiance kept apart.
            let e = vpl_irradiance(vpl, x, nx, params.shade.x, params.near.x);
            if (max(e.r, max(e.g, e.b)) <= 0.0) {
                continue;
            }
            let l = e * vpl_receiver_brdf(vpl, x, nx, camera.position.xyz, alb.rgb, m);
            let vis = gather_visibility(params.vis.x, ism_atlas, exact_atlas, k, vpl, x, nx, params.vis.y, params.vis.z, params.shade.yzw);
            sum = sum + l * vis;
            irr = irr + e * vis;
        }
        if (per_tile > 0u) {
            let scale = f32(count) / f32(per_tile);
            sum = sum * scale;
            irr = irr * scale;
        }
    }
    return Gathered(sum, irr);
}

// The thesis' layout: s_* are the split G-buffer, out_accum the split accumulation buffer.
@compute @workgroup_size(TILE, TILE, 1)
fn cs_gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_accum);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    // The G-buffer pixel of split pixel s: (s mod tile)·n + s / tile (split.wgsl).
    let tile = params.split.yz;
    let src = (gid.xy % tile) * params.split.x + gid.xy / tile;
    let g = gather_at(vec2<i32>(gid.xy), gid.xy, vec2<i32>(src), textureLoad(s_normal_split, gid.xy, 0));
    textureStore(out_accum, vec2<i32>(gid.xy), vec4<f32>(g.light, 1.0));
    textureStore(out_irradiance, vec2<i32>(gid.xy), vec4<f32>(g.irradiance, 1.0));
}

// Fused (issue #38): s_* are the G-buffer and out_accum the merged light; each split pixel
// (the same dispatch and tiles as cs_gather, so a workgroup still shares its tile's VPLs)
// reads and writes its source pixel (a·n + i, b·n + j), which is what split, gather and
// merge give, without the split copies.
@compute @workgroup_size(TILE, TILE, 1)
fn cs_gather_fused(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = params.split.x;
    let tile = params.split.yz;
    if (gid.x >= tile.x * n || gid.y >= tile.y * n) {
        return;
    }
    let a = gid.xy % tile;
    let p = a * n + gid.xy / tile;
    let size = textureDimensions(out_accum);
    if (p.x >= size.x || p.y >= size.y) {
        return;
    }
    let g = gather_at(vec2<i32>(p), gid.xy, vec2<i32>(p), gbuffer_normal(textureLoad(s_normal, p, 0).x));
    textureStore(out_accum, vec2<i32>(p), vec4<f32>(g.light, 1.0));
    textureStore(out_irradiance, vec2<i32>(p), vec4<f32>(g.irradiance, 1.0));
}
