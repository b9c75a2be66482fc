// Irradiance splatting (Gautron et al. 003, "From Octree to Splatting": "Principle"): each
// record's sphere of influence (radius a·R_k, inside which the simplified weight
// R_k/‖P − P_k‖ exceeds 1/a) covers the screen-aligned rectangle that bounds its perspective
// image (the tangent planes through the eye in x and in y; the text's TransformVertex is exact
// only on the view axis), the whole screen when the sphere reaches the near plane. At every
// covered pixel Ward's full weight is evaluated at the visible point, kept above 1/a, and
// RGB = w·E_k(extrapolated), A = w are added (target 0 with the gradients as set, target 1
// without any). Twin: cpu::gautron::{sphere_ndc_rect, accumulate}.
//
// `gautron.splat`: Blend, the text's way: vs_splat/fs_splat draw one quad per record, added by
// blending (GL_ONE, GL_ONE). Binned, GI Lab's (issue #38: the quads' overdraw into 128-bit
// blended targets is the splat's cost on a GPU): cs_bin marks each record in a bit mask of every BIN² pixel square its rectangle overlaps;
// cs_accumulate (an 8×8 workgroup inside one square) keeps the records whose rectangle
// overlaps its pixels, then each pixel adds them in increasing record index, the order in
// which the blending added the instances, so that the sums are the same. A later round adds
// its new records to the previous sums (read from the other texture of a ping-pong pair).
#import gautron/common.wgsl
#import common/camera.wgsl

// Rust twin: passes::gautron::splat::TileParams.
struct TileParams {
    // x: squares across, y: squares down, z: mask words per square (capacity / 32), w: BIN
    bins: vec4<u32>,
    // x: 1 to add to the sums read from prev_* (a later round), 0 to start from zero
    mode: vec4<u32>,
}

// Most mask words per square: `gautron.capacity` ≤ 65,536 records.
const MAX_WORDS: u32 = 2048u;

@group(0) @binding(0) var<uniform> params: GautronParams;
@group(0) @binding(1) var<uniform> camera: Camera;
@group(0) @binding(2) var<storage, read> records: array<Record>;
@group(0) @binding(3) var g_position: texture_2d<f32>;
@group(0) @binding(4) var g_normal: texture_2d<f32>;
@group(0) @binding(5) var<uniform> tiles: TileParams;
// The draw arguments the creation writes: (6, count, 0, first record).
@group(0) @binding(6) var<storage, read> args: array<u32, 4>;
// Per square, one bit per record: bit k of word k / 32.
@group(0) @binding(7) var<storage, read_write> mask: array<atomic<u32>>;
// Per record, its rectangle in NDC (x0, y0, x1, y1; empty when x0 > x1).
@group(0) @binding(8) var<storage, read_write> rects: array<vec4<f32>>;
@group(0) @binding(9) var prev_weighted: texture_2d<f32>;
@group(0) @binding(10) var prev_plain: texture_2d<f32>;
@group(0) @binding(11) var out_weighted: texture_storage_2d<rgba32float, write>;
@group(0) @binding(12) var out_plain: texture_storage_2d<rgba32float, write>;

// The NDC interval [lo, hi] of a circle (centre (c, d) with d the distance in front of the
// eye, radius ρ) seen from the eye along one axis; scale is P00 or P11.
fn tangent_interval(c: f32, d: f32, rho: f32, scale: f32) -> vec2<f32> {
    let k = d * d - rho * rho;
    let root = sqrt(max(c * c + k, 0.0));
    let lo = (c * d - rho * root) / k;
    let hi = (c * d + rho * root) / k;
    return vec2<f32>(lo, hi) * scale;
}

// The record's rectangle in NDC (x0, y0, x1, y1), or an empty one while its hemisphere is
// being computed.
fn splat_rect(rec: Record) -> vec4<f32> {
    if (rec.pixel.w < 0.5) {
        return vec4<f32>(1.0, 1.0, -1.0, -1.0);
    }
    let rho = params.weight.x * rec.position.w;
    let c = (camera.view * vec4<f32>(rec.position.xyz, 1.0)).xyz;
    let d = -c.z;
    var rect = vec4<f32>(-1.0, -1.0, 1.0, 1.0);
    if (d - rho > camera.params.x) {
        let x = tangent_interval(c.x, d, rho, params.misc.y);
        let y = tangent_interval(c.y, d, rho, params.misc.z);
        // half a pixel more on every side: a sphere smaller than a pixel (R_k clamped to
        // ~1 px, the brute force of the bench) still reaches its own pixel's centre despite
        // the rounding of its position
        let half_px = vec2<f32>(1.0) / camera.viewport.xy;
        rect = vec4<f32>(x.x - half_px.x, y.x - half_px.y, x.y + half_px.x, y.y + half_px.y);
        rect = vec4<f32>(max(rect.xy, vec2<f32>(-1.0)), min(rect.zw, vec2<f32>(1.0)));
    }
    return rect;
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
    return o;
}

// NDC of pixel centre (x, y) (y down in pixels, up in NDC).
fn centre_ndc(x: f32, y: f32) -> vec2<f32> {
    return vec2<f32>((x + 0.5) * camera.viewport.z * 2.0 - 1.0, 1.0 - (y + 0.5) * camera.viewport.w * 2.0);
}

@compute @workgroup_size(64, 1, 1)
fn cs_bin(@builtin(global_invocation_id) gid: vec3<u32>) {
    let index = args[3] + gid.x;
    if (gid.x >= args[1] || index >= arrayLength(&records)) {
        return;
    }
    let r = splat_rect(records[index]);
    rects[index] = r;
    if (r.x > r.z || r.y > r.w) {
        return;
    }
    // The pixels whose centres may lie inside, one pixel wider on each side (conservative).
    let size = camera.viewport.xy;
    let x0 = (r.x + 1.0) * 0.5 * size.x - 1.5;
    let x1 = (r.z + 1.0) * 0.5 * size.x + 0.5;
    let y0 = (1.0 - r.w) * 0.5 * size.y - 1.5;
    let y1 = (1.0 - r.y) * 0.5 * size.y + 0.5;
    let last = vec2<f32>(size - 1.0);
    let lo = vec2<u32>(clamp(vec2<f32>(x0, y0), vec2<f32>(0.0), last)) / tiles.bins.w;
    let hi = vec2<u32>(clamp(vec2<f32>(x1, y1), vec2<f32>(0.0), last)) / tiles.bins.w;
    let word = index / 32u;
    let bit = 1u << (index % 32u);
    for (var by = lo.y; by <= min(hi.y, tiles.bins.y - 1u); by = by + 1u) {
        for (var bx = lo.x; bx <= min(hi.x, tiles.bins.x - 1u); bx = bx + 1u) {
            atomicOr(&mask[(by * tiles.bins.x + bx) * tiles.bins.z + word], bit);
        }
    }
}

// The square's records that overlap this workgroup's pixels, and which of those words are
// not empty (one bit per word).
var<workgroup> kept: array<u32, MAX_WORDS>;
var<workgroup> summary: array<atomic<u32>, 64>;

@compute @workgroup_size(16, 16, 1)
fn cs_accumulate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let size = textureDimensions(out_weighted);
    let origin = wg.xy * 16u;
    let square = (origin.y / tiles.bins.w) * tiles.bins.x + origin.x / tiles.bins.w;
    // Only the words of this splat's records (the creation's arguments: first + count).
    let words = min(min(tiles.bins.z, MAX_WORDS), (args[3] + args[1] + 31u) / 32u);
    // The NDC range of the workgroup's pixel centres (y: top is the larger).
    let a = centre_ndc(f32(origin.x), f32(origin.y));
    let b = centre_ndc(f32(origin.x + 15u), f32(origin.y + 15u));
    if (li < 64u) {
        atomicStore(&summary[li], 0u);
    }
    workgroupBarrier();
    for (var w = li; w < words; w = w + 256u) {
        var m = atomicLoad(&mask[square * tiles.bins.z + w]);
        var keep = 0u;
        while (m != 0u) {
            let j = firstTrailingBit(m);
            m = m & (m - 1u);
            let r = rects[w * 32u + j];
            if (r.x <= b.x && r.z >= a.x && r.y <= a.y && r.w >= b.y) {
                keep = keep | (1u << j);
            }
        }
        kept[w] = keep;
        if (keep != 0u) {
            atomicOr(&summary[w / 32u], 1u << (w % 32u));
        }
    }
    workgroupBarrier();
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    var weighted = vec4<f32>(0.0);
    var plain = vec4<f32>(0.0);
    if (tiles.mode.x == 1u) {
        weighted = textureLoad(prev_weighted, px, 0);
        plain = textureLoad(prev_plain, px, 0);
    }
    let nrm = textureLoad(g_normal, px, 0);
    if (nrm.w >= 0.5) {
        let p = textureLoad(g_position, px, 0).xyz;
        let n = normalize(nrm.xyz);
        let c = centre_ndc(f32(gid.x), f32(gid.y));
        let rotational = params.weight.z > 0.5;
        let translational = params.weight.w > 0.5;
        for (var s = 0u; s < (words + 31u) / 32u; s = s + 1u) {
            var sw = atomicLoad(&summary[s]);
            while (sw != 0u) {
                let w = s * 32u + firstTrailingBit(sw);
                sw = sw & (sw - 1u);
                var m = kept[w];
                while (m != 0u) {
                    let index = w * 32u + firstTrailingBit(m);
                    m = m & (m - 1u);
                    let r = rects[index];
                    if (c.x < r.x || c.x > r.z || c.y < r.y || c.y > r.w) {
                        continue;
                    }
                    let rec = records[index];
                    let wk = ward_weight(rec, p, n, params.weight.y);
                    if (wk <= 1.0 / params.weight.x) {
                        continue;
                    }
                    let e = extrapolate(rec, p, n, rotational, translational);
                    weighted = weighted + vec4<f32>(wk * e, wk);
                    plain = plain + vec4<f32>(wk * rec.irradiance.rgb, wk);
                }
            }
        }
    }
    textureStore(out_weighted, px, weighted);
    textureStore(out_plain, px, plain);
}
