// Stage 4: pull-push hole filling of the ISM atlas (Knecht 002 §2.6.5 after Marroquim et al.
// 2008): pull averages the valid children within t_pull · 2^l of the nearest one into level
// l+1; push fills level l from the bilinear interpolation of the valid coarse texels of the
// same map where the fine texel is a hole or lies more than t_push · 2^l behind it — anywhere
// (the thesis), or only where the four coarse texels are valid and agree within t_push · 2^l
// (inside a surface; at a silhouette the background stays).
// CPU twin: cpu::knecht::pull_push (the readings are documented there).
const ISM_EMPTY: f32 = 1.0e30;

struct LevelParams {
    // x: threshold of this level (t · 2^l, scene units); y (push): 1 to replace texels behind
    // only inside a surface
    threshold: vec4<f32>,
    // x: side of one map at the coarse level (texels); y: the first texel row this dispatch
    // writes at its level (only the rows of some maps, `IsmPass::finish_maps`)
    tile: vec4<u32>,
}

@group(0) @binding(0) var<uniform> lp: LevelParams;
@group(0) @binding(1) var src: texture_2d<f32>;
@group(0) @binding(2) var dst: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_pull(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(dst);
    let gid = vec2<u32>(id.x, id.y + lp.tile.y);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let c = vec2<i32>(gid.xy) * 2;
    let v = array<f32, 4>(
        textureLoad(src, c, 0).r,
        textureLoad(src, c + vec2<i32>(1, 0), 0).r,
        textureLoad(src, c + vec2<i32>(0, 1), 0).r,
        textureLoad(src, c + vec2<i32>(1, 1), 0).r,
    );
    let nearest = min(min(v[0], v[1]), min(v[2], v[3]));
    var out = ISM_EMPTY;
    if (nearest < ISM_EMPTY) {
        var sum = 0.0;
        var n = 0.0;
        for (var k = 0; k < 4; k = k + 1) {
            if (v[k] < ISM_EMPTY && v[k] - nearest <= lp.threshold.x) {
                sum = sum + v[k];
                n = n + 1.0;
            }
        }
        out = sum / n;
    }
    textureStore(dst, gid.xy, vec4<f32>(out, 0.0, 0.0, 0.0));
}

@group(0) @binding(3) var fine: texture_storage_2d<r32float, read_write>;

// The bilinear value of the valid coarse texels around fine texel (x, y) in its map (x; empty
// if none), and whether all four are valid and agree within `threshold` (y: 1 or 0).
fn coarse_at(x: u32, y: u32, threshold: f32) -> vec2<f32> {
    let ct = lp.tile.x;
    let px = (f32(x) + 0.5) * 0.5 - 0.5;
    let py = (f32(y) + 0.5) * 0.5 - 0.5;
    let x0 = floor(px);
    let y0 = floor(py);
    let fx = px - x0;
    let fy = py - y0;
    let tx = i32((x / 2u) / ct * ct);
    let ty = i32((y / 2u) / ct * ct);
    let offsets = array<vec2<i32>, 4>(vec2<i32>(0, 0), vec2<i32>(1, 0), vec2<i32>(0, 1), vec2<i32>(1, 1));
    let weights = array<f32, 4>((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
    var sum = 0.0;
    var wsum = 0.0;
    var lo = ISM_EMPTY;
    var hi = 0.0;
    var taps = 0u;
    for (var k = 0; k < 4; k = k + 1) {
        let cx = clamp(i32(x0) + offsets[k].x, tx, tx + i32(ct) - 1);
        let cy = clamp(i32(y0) + offsets[k].y, ty, ty + i32(ct) - 1);
        let v = textureLoad(src, vec2<i32>(cx, cy), 0).r;
        if (v < ISM_EMPTY) {
            lo = min(lo, v);
            hi = max(hi, v);
            taps = taps + 1u;
        }
        if (v < ISM_EMPTY && weights[k] > 0.0) {
            sum = sum + weights[k] * v;
            wsum = wsum + weights[k];
        }
    }
    let agree = select(0.0, 1.0, taps == 4u && hi - lo <= threshold);
    if (wsum > 0.0) {
        return vec2<f32>(sum / wsum, agree);
    }
    return vec2<f32>(ISM_EMPTY, 0.0);
}

@compute @workgroup_size(8, 8, 1)
fn cs_push(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(fine);
    let gid = vec2<u32>(id.x, id.y + lp.tile.y);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let c = coarse_at(gid.x, gid.y, lp.threshold.x);
    let f = textureLoad(fine, gid.xy).r;
    let may_replace = lp.threshold.y < 0.5 || c.y > 0.5;
    if (c.x < ISM_EMPTY && (f >= ISM_EMPTY || (may_replace && f - c.x > lp.threshold.x))) {
        textureStore(fine, gid.xy, vec4<f32>(c.x, 0.0, 0.0, 0.0));
    }
}
