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

// Coarse texel (x, y) clamped into the coarse map whose first texel is t (side lp.tile.x).
fn coarse_tap(x: i32, y: i32, t: vec2<i32>) -> f32 {
    let last = t + vec2<i32>(i32(lp.tile.x) - 1);
    return textureLoad(src, clamp(vec2<i32>(x, y), t, last), 0).r;
}

// The bilinear value of the valid coarse texels among a (x0, y0), b (x0 + 1, y0), c (x0, y0 + 1)
// and d (x0 + 1, y0 + 1) at fractions (fx, fy) (x; empty if none), and whether all four are
// valid and agree within `threshold` (y: 1 or 0). The fractions of a fine texel are 1/4 or
// 3/4, so every weight is above 0.
fn bilinear(a: f32, b: f32, c: f32, d: f32, fx: f32, fy: f32, threshold: f32) -> vec2<f32> {
    let v = vec4<f32>(a, b, c, d);
    let w = vec4<f32>((1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy);
    var sum = 0.0;
    var wsum = 0.0;
    var lo = ISM_EMPTY;
    var hi = 0.0;
    var taps = 0u;
    for (var k = 0; k < 4; k = k + 1) {
        if (v[k] < ISM_EMPTY) {
            lo = min(lo, v[k]);
            hi = max(hi, v[k]);
            taps = taps + 1u;
            sum = sum + w[k] * v[k];
            wsum = wsum + w[k];
        }
    }
    let agree = select(0.0, 1.0, taps == 4u && hi - lo <= threshold);
    if (wsum > 0.0) {
        return vec2<f32>(sum / wsum, agree);
    }
    return vec2<f32>(ISM_EMPTY, 0.0);
}

// The push of fine texel p from its bilinear coarse value cv.
fn push_texel(p: vec2<u32>, cv: vec2<f32>) {
    let f = textureLoad(fine, p).r;
    let may_replace = lp.threshold.y < 0.5 || cv.y > 0.5;
    if (cv.x < ISM_EMPTY && (f >= ISM_EMPTY || (may_replace && f - cv.x > lp.threshold.x))) {
        textureStore(fine, p, vec4<f32>(cv.x, 0.0, 0.0, 0.0));
    }
}

// One 2×2 quad of fine texels (2i … 2i + 1, 2j … 2j + 1) per invocation (issue #53): fine texel
// 2i + a sits at coarse x = i − 1/4 + a/2, so the quad's four bilinear lookups read the 3×3
// coarse texels around (i, j) once, 9 loads instead of 16 (docs/architecture.md "The ISM's
// pull-push in fewer passes"). The same values and sums, texel by texel, as the CPU twin's
// `coarse_at`.
@compute @workgroup_size(8, 8, 1)
fn cs_push(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(fine);
    let q = vec2<u32>(id.x, id.y + lp.tile.y / 2u);
    if (q.x * 2u >= size.x || q.y * 2u >= size.y) {
        return;
    }
    let ct = lp.tile.x;
    let t = vec2<i32>(q / ct * ct);
    let i = i32(q.x);
    let j = i32(q.y);
    // Rows j − 1, j, j + 1 (clamped into the coarse map), columns i − 1, i, i + 1.
    let a0 = coarse_tap(i - 1, j - 1, t);
    let a1 = coarse_tap(i, j - 1, t);
    let a2 = coarse_tap(i + 1, j - 1, t);
    let b0 = coarse_tap(i - 1, j, t);
    let b1 = coarse_tap(i, j, t);
    let b2 = coarse_tap(i + 1, j, t);
    let c0 = coarse_tap(i - 1, j + 1, t);
    let c1 = coarse_tap(i, j + 1, t);
    let c2 = coarse_tap(i + 1, j + 1, t);
    let th = lp.threshold.x;
    let p = q * 2u;
    push_texel(p, bilinear(a0, a1, b0, b1, 0.75, 0.75, th));
    push_texel(p + vec2<u32>(1u, 0u), bilinear(a1, a2, b1, b2, 0.25, 0.75, th));
    push_texel(p + vec2<u32>(0u, 1u), bilinear(b0, b1, c0, c1, 0.75, 0.25, th));
    push_texel(p + vec2<u32>(1u, 1u), bilinear(b1, b2, c1, c2, 0.25, 0.25, th));
}
