// Explain a pixel (issue #42) for the VPL gather at tiles or at every pixel (Knecht 002
// §3.4.1, §4.5) and what follows it: the geometry-aware filter (§3.4.1, Eq. 4.2) and the
// confidence merge (§3.5, Eq. 3.6). It replays gather.wgsl's sum term by term with the
// frame's own inputs (VPL list, visibility maps, tile offsets, G-buffer), after the frame's
// passes and in its encoder, and writes every term with what made it: the Rust side
// (passes::knecht::explain) turns them into the pixel's contributions and checks their sum
// against the buffers the frame wrote.
//
// Every VPL slot k reached pixel p through one pixel q of the filter's window: the one whose
// interleaving tile holds k (without the filter the window is p alone, and the slots of other
// tiles do not reach p).
#import common/camera.wgsl
#import common/ism.wgsl
#import common/reproject.wgsl
#import common/vpl_explain.wgsl
#import knecht/interleave/params.wgsl
#import common/brdf.wgsl
#import common/split_light.wgsl

struct ExplainParams {
    // x, y: the pixel p; z: the filter's window side (n with the filter, else 1); w: 1 when
    // the confidence merge ran (temporal.confidence and the histories are bound)
    pixel: vec4<u32>,
    // x: α · (z_far − z_near), y: β (knecht/interleave/filter.wgsl); z: 1 when the filter ran
    // demodulated (issue #51); w: 1 when the merge ran demodulated (its history is split_prev)
    thresholds: vec4<f32>,
}

// One pixel of the window (passes::knecht::explain::GpuWindow).
struct WindowPixel {
    // x, y: the pixel (i32 as u32; outside the image: −1); z: flags (EXPLAIN_W_*); w: tile
    pixel: vec4<u32>,
    // rgb: indirect.merged at q (the gather's output); a: q's VPL count N_t
    merged: vec4<f32>,
    // rgb: the history the confidence merge read for q; a: q's confidence c
    history: vec4<f32>,
    // rgb: the temporal history written at q (the merge's output); a: 0
    out: vec4<f32>,
}

// Header: [0] the pixel's final indirect value (rgb; a: 1 when the G-buffer is empty there);
// [1] indirect.filtered at p; [2] N, N_t, n, window.
struct Header {
    final_value: vec4<f32>,
    filtered: vec4<f32>,
    counts: vec4<u32>,
    pad: vec4<u32>,
}

const EXPLAIN_W_INSIDE: u32 = 1u;
const EXPLAIN_W_ACCEPTED: u32 = 2u;
const EXPLAIN_W_SURFACE: u32 = 4u;

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: GatherParams;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(3) var ism_atlas: texture_2d<f32>;
@group(0) @binding(4) var exact_atlas: texture_2d<f32>;
@group(0) @binding(5) var g_position: texture_2d<f32>;
@group(0) @binding(6) var g_normal: texture_2d<f32>;
@group(0) @binding(7) var g_albedo: texture_2d<f32>;
@group(0) @binding(8) var g_material: texture_2d<f32>;
@group(0) @binding(9) var<storage, read> tile_offsets: array<u32>;
@group(0) @binding(10) var<uniform> explain: ExplainParams;
@group(0) @binding(11) var merged: texture_2d<f32>;
@group(0) @binding(12) var filtered: texture_2d<f32>;
@group(0) @binding(13) var confidence: texture_2d<f32>;
@group(0) @binding(14) var history_prev: texture_2d<f32>;
@group(0) @binding(15) var history_out: texture_2d<f32>;
@group(0) @binding(16) var g_motion: texture_2d<f32>;
@group(0) @binding(17) var final_light: texture_2d<f32>;
@group(0) @binding(18) var<storage, read_write> header: Header;
@group(0) @binding(19) var<storage, read_write> window: array<WindowPixel, 64>;
@group(0) @binding(20) var<storage, read_write> terms: array<VplTerm>;
// The demodulated merge's split history (common/split_light.wgsl).
@group(0) @binding(21) var split_prev: texture_2d<u32>;

// The history as the demodulated merge reads it at q: k_q·E_prev + S_prev.
fn split_history(q: vec2<i32>, prev: vec2<i32>) -> vec3<f32> {
    let v = textureLoad(split_prev, prev, 0);
    let alb = textureLoad(g_albedo, q, 0);
    return brdf_diffuse(alb.rgb, alb.a) * unpack_irradiance(v) + unpack_specular(v);
}

fn tile_of(q: vec2<i32>) -> u32 {
    let n = params.split.x;
    return u32(q.x) % n + (u32(q.y) % n) * n;
}

// The pixel of p's window whose tile is t.
fn window_pixel(t: u32) -> vec2<i32> {
    let n = i32(params.split.x);
    let w = i32(explain.pixel.z);
    let lo = -(w / 2);
    let p = vec2<i32>(explain.pixel.xy);
    for (var dy = lo; dy < lo + w; dy = dy + 1) {
        for (var dx = lo; dx < lo + w; dx = dx + 1) {
            let q = p + vec2<i32>(dx, dy);
            // Tiles of negative coordinates wrap as the unsigned ones do not: keep q ≥ 0.
            if (q.x >= 0 && q.y >= 0 && tile_of(q) == t) {
                return q;
            }
        }
    }
    return vec2<i32>(-1, -1);
}

// The filter's test of q against p (knecht/interleave/filter.wgsl).
fn accepted(p: vec2<i32>, q: vec2<i32>) -> bool {
    let size = vec2<i32>(textureDimensions(g_normal));
    if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) {
        return false;
    }
    if (explain.pixel.z <= 1u) {
        return all(p == q);
    }
    let cn = textureLoad(g_normal, p, 0);
    let qn = textureLoad(g_normal, q, 0);
    let cd = textureLoad(g_position, p, 0).w;
    let qd = textureLoad(g_position, q, 0).w;
    return qn.w >= 0.5 && abs(qd - cd) <= explain.thresholds.x && dot(qn.xyz, cn.xyz) >= explain.thresholds.y;
}

// The VPL count of tile t (gather.wgsl's per_tile).
fn per_tile(t: u32) -> u32 {
    let count = params.split.w;
    let stride = params.split.x * params.split.x;
    let blocks = (count + stride - 1u) / stride;
    var k = 0u;
    for (var b = 0u; b < blocks; b = b + 1u) {
        if (b * stride + (t + tile_offsets[b]) % stride < count) {
            k = k + 1u;
        }
    }
    return k;
}

// The pixel's header and its window, one invocation per window pixel.
@compute @workgroup_size(64, 1, 1)
fn cs_explain_pixel(@builtin(local_invocation_index) i: u32) {
    let p = vec2<i32>(explain.pixel.xy);
    let w = explain.pixel.z;
    let size = textureDimensions(g_normal);
    if (i == 0u) {
        let empty = select(0.0, 1.0, textureLoad(g_normal, p, 0).w < 0.5);
        header.final_value = vec4<f32>(textureLoad(final_light, p, 0).rgb, empty);
        header.filtered = textureLoad(filtered, p, 0);
        header.counts = vec4<u32>(params.split.w, per_tile(tile_of(p)), params.split.x, w);
    }
    if (i >= w * w) {
        return;
    }
    let lo = -i32(w / 2u);
    let q = p + vec2<i32>(lo + i32(i % w), lo + i32(i / w));
    var out: WindowPixel;
    out.pixel = vec4<u32>(u32(q.x), u32(q.y), 0u, 0u);
    let inside = q.x >= 0 && q.y >= 0 && q.x < i32(size.x) && q.y < i32(size.y);
    if (inside) {
        let t = tile_of(q);
        var flags = EXPLAIN_W_INSIDE;
        if (accepted(p, q)) {
            flags = flags | EXPLAIN_W_ACCEPTED;
        }
        if (textureLoad(g_normal, q, 0).w >= 0.5) {
            flags = flags | EXPLAIN_W_SURFACE;
        }
        out.pixel.z = flags;
        out.pixel.w = t;
        out.merged = vec4<f32>(textureLoad(merged, q, 0).rgb, f32(per_tile(t)));
        if (explain.pixel.w == 1u) {
            let c = textureLoad(confidence, q, 0).r;
            var h = vec3<f32>(0.0);
            if (c > 0.0) {
                let prev = previous_texel(q, textureLoad(g_motion, q, 0).xy, size);
                if (explain.thresholds.w > 0.5) {
                    h = split_history(q, prev);
                } else {
                    h = textureLoad(history_prev, prev, 0).rgb;
                }
            }
            out.history = vec4<f32>(h, c);
            out.out = vec4<f32>(textureLoad(history_out, q, 0).rgb, 0.0);
        }
    }
    window[i] = out;
}

// Every VPL slot's term at the pixel of the window that its tile reached.
@compute @workgroup_size(64, 1, 1)
fn cs_explain_vpls(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    let count = params.split.w;
    if (k >= count) {
        return;
    }
    let n = params.split.x;
    let stride = n * n;
    let b = k / stride;
    let t = ((k % stride) + stride - tile_offsets[b] % stride) % stride;
    var term: VplTerm;
    term.slot = vec4<u32>(k, 0u, 0xffffffffu, t);
    let vpl = vpls[k];
    let q = window_pixel(t);
    let p = vec2<i32>(explain.pixel.xy);
    var flags = 0u;
    if (vpl.position.w < 0.5) {
        flags = flags | EXPLAIN_EMPTY;
    }
    let size = vec2<i32>(textureDimensions(g_normal));
    if (q.x < 0 || q.x >= size.x || q.y >= size.y) {
        term.slot.y = flags | EXPLAIN_OUTSIDE;
        terms[k] = term;
        return;
    }
    term.slot.z = u32(q.x) | (u32(q.y) << 16u);
    if (!accepted(p, q)) {
        flags = flags | EXPLAIN_FILTERED;
    }
    let nrm = textureLoad(g_normal, q, 0);
    if (nrm.w < 0.5) {
        term.slot.y = flags | EXPLAIN_BACKGROUND;
        terms[k] = term;
        return;
    }
    if ((flags & EXPLAIN_EMPTY) != 0u) {
        term.slot.y = flags;
        terms[k] = term;
        return;
    }
    let x = textureLoad(g_position, q, 0).xyz;
    let nx = normalize(nrm.xyz);
    let alb = textureLoad(g_albedo, q, 0);
    let mat = textureLoad(g_material, q, 0);
    let scale = f32(count) / f32(max(per_tile(t), 1u));
    let m = vec3<f32>(alb.a, select(mat.x, 0.0, params.vis.w == 1u), mat.y);
    let seen = vpl_term(vpl, x, nx, camera.position.xyz, alb.rgb, m, params.shade.x, params.near.x);
    var test = vec3<f32>(1.0, 0.0, 0.0);
    if (max(seen.unshadowed.r, max(seen.unshadowed.g, seen.unshadowed.b)) > 0.0) {
        test = gather_test(params.vis.x, ism_atlas, exact_atlas, k, vpl, x, nx, params.vis.y, params.vis.z, params.shade.yzw);
    }
    let slot = term.slot;
    term = vpl_term_seen(seen, test, scale);
    term.slot = vec4<u32>(slot.x, flags | term.slot.y, slot.z, slot.w);
    // The demodulated filter reflects q's irradiance with p's diffuse colour (filter.wgsl:
    // k_p·E + (L − k_q·E)).
    if (explain.thresholds.z > 0.5) {
        let e = vpl_irradiance(vpl, x, nx, params.shade.x, params.near.x) * test.x * scale;
        let ap = textureLoad(g_albedo, p, 0);
        let k_p = brdf_diffuse(ap.rgb, ap.a);
        let k_q = brdf_diffuse(alb.rgb, alb.a);
        term.reach = vec4<f32>(term.light.rgb + (k_p - k_q) * e, term.light.w);
    }
    terms[k] = term;
}
