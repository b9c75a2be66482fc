// Irradiance splatting (Gautron et al. 003, "From Octree to Splatting": "Principle"): each
// record's sphere of influence (radius a·R_k, inside which the simplified weight
// R_k/‖P − P_k‖ exceeds 1/a) covers the screen-aligned rectangle that bounds its perspective
// image (the tangent planes through the eye in x and in y; the text's TransformVertex is exact
// only on the view axis), the whole screen when the sphere reaches the near plane. At every
// covered pixel Ward's full weight is evaluated at the visible point, kept above 1/a, and
// RGB = w·E_k(extrapolated), A = w are added (target 0 with the gradients as set, target 1
// without any; target 2 the glossy receiver's direction sums, w·dir_k, issue #51). Twin: cpu::gautron::{sphere_ndc_rect, accumulate}.
//
// `gautron.splat`: Blend, the text's way: vs_splat/fs_splat draw one quad per record, added by
// blending (GL_ONE, GL_ONE). Binned, GI Lab's (issue #38: the quads' overdraw into 128-bit
// blended targets is the splat's cost on a GPU): cs_bin marks each record in the squares its
// rectangle overlaps, cs_accumulate adds each pixel's records in increasing index, the order
// in which the blending added the instances, so that the sums are the same
// (common/bins.wgsl). A later round adds its new records to the previous sums (read from the
// other texture of a ping-pong pair).
#import gautron/common.wgsl
#import common/camera.wgsl
#import common/bins.wgsl

@group(0) @binding(0) var<uniform> params: GautronParams;
@group(0) @binding(1) var<uniform> camera: Camera;
@group(0) @binding(2) var<storage, read> records: array<Record>;
@group(0) @binding(3) var g_position: texture_2d<f32>;
@group(0) @binding(4) var g_normal: texture_2d<f32>;
// The draw arguments the creation writes: (6, count, 0, first record).
@group(0) @binding(5) var<storage, read> args: array<u32, 4>;
@group(0) @binding(6) var prev_weighted: texture_2d<f32>;
@group(0) @binding(7) var prev_plain: texture_2d<f32>;
@group(0) @binding(8) var out_weighted: texture_storage_2d<rgba32float, write>;
@group(0) @binding(9) var out_plain: texture_storage_2d<rgba32float, write>;
@group(0) @binding(10) var prev_dir: texture_2d<f32>;
@group(0) @binding(11) var out_dir: texture_storage_2d<rgba32float, write>;

// The record's rectangle in NDC (x0, y0, x1, y1), or an empty one while its hemisphere is
// being computed (gautron/common.wgsl's splat_bound with this frame's camera).
fn splat_rect(rec: Record) -> vec4<f32> {
    return splat_bound(rec, camera.view, camera.params.x, camera.viewport.xy);
}

struct SplatOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) index: u32,
}

// Blend: the record's rectangle as two triangles (nothing while it is being computed).
@vertex
fn vs_splat(@builtin(vertex_index) vi: u32, @builtin(instance_index) index: u32) -> SplatOut {
    var o: SplatOut;
    o.index = index;
    let rect = splat_rect(records[index]);
    if (rect.x > rect.z) {
        o.clip = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return o;
    }
    // two triangles: (0, 0) (1, 0) (0, 1) · (0, 1) (1, 0) (1, 1)
    let corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    let q = corners[vi % 6u];
    o.clip = vec4<f32>(mix(rect.xy, rect.zw, q), 0.0, 1.0);
    return o;
}

struct SplatTargets {
    @location(0) weighted: vec4<f32>,
    @location(1) plain: vec4<f32>,
    @location(2) dir: vec4<f32>,
}

// Blend: Ward's weight at the visible point, discarded below 1/a.
@fragment
fn fs_splat(i: SplatOut) -> SplatTargets {
    let px = vec2<i32>(i.clip.xy);
    let nrm = textureLoad(g_normal, px, 0);
    if (nrm.w < 0.5) {
        discard;
    }
    let p = textureLoad(g_position, px, 0).xyz;
    let n = normalize(nrm.xyz);
    let rec = records[i.index];
    let w = ward_weight(rec, p, n, params.weight.y);
    if (w <= 1.0 / params.weight.x) {
        discard;
    }
    var o: SplatTargets;
    let e = extrapolate(rec, p, n, params.weight.z > 0.5, params.weight.w > 0.5);
    o.weighted = vec4<f32>(w * e, w);
    o.plain = vec4<f32>(w * rec.irradiance.rgb, w);
    o.dir = vec4<f32>(w * rec.dir.xyz, 0.0);
    return o;
}

// Binned: record args[3] + j into the squares of its rectangle.
@compute @workgroup_size(64, 1, 1)
fn cs_bin(@builtin(global_invocation_id) gid: vec3<u32>) {
    let index = args[3] + gid.x;
    if (gid.x >= min(args[1], bins_capacity()) || index >= arrayLength(&records)) {
        return;
    }
    bins_mark(gid.x, splat_rect(records[index]), camera.viewport.xy);
}

// Binned: each pixel adds the records of its square that reach it, in increasing index.
@compute @workgroup_size(16, 16, 1)
fn cs_accumulate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let size = textureDimensions(out_weighted);
    let origin = wg.xy * 16u;
    let words = bins_collect(li, origin, args[1], camera.viewport.zw);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    var weighted = vec4<f32>(0.0);
    var plain = vec4<f32>(0.0);
    var dir = vec4<f32>(0.0);
    if (bin_params.mode.x == 1u) {
        weighted = textureLoad(prev_weighted, px, 0);
        plain = textureLoad(prev_plain, px, 0);
        dir = textureLoad(prev_dir, px, 0);
    }
    let nrm = textureLoad(g_normal, px, 0);
    if (nrm.w >= 0.5) {
        let p = textureLoad(g_position, px, 0).xyz;
        let n = normalize(nrm.xyz);
        let c = bin_centre_ndc(gid.xy, camera.viewport.zw);
        let rotational = params.weight.z > 0.5;
        let translational = params.weight.w > 0.5;
        var cursor = bins_start(words);
        for (var j = bins_next(&cursor, c); j != BIN_NONE; j = bins_next(&cursor, c)) {
            let rec = records[args[3] + j];
            let wk = ward_weight(rec, p, n, params.weight.y);
            if (wk <= 1.0 / params.weight.x) {
                continue;
            }
            let e = extrapolate(rec, p, n, rotational, translational);
            weighted = weighted + vec4<f32>(wk * e, wk);
            plain = plain + vec4<f32>(wk * rec.irradiance.rgb, wk);
            dir = dir + vec4<f32>(wk * rec.dir.xyz, 0.0);
        }
    }
    textureStore(out_weighted, px, weighted);
    textureStore(out_plain, px, plain);
    textureStore(out_dir, px, dir);
}
