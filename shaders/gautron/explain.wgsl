// Explain a pixel (issue #42) for Gautron et al.'s irradiance cache splatting (Gautron,
// Křivánek, Bouatouch and Pattanaik 2005, "Radiance cache splatting"; the course notes 003,
// "From Octree to Splatting": "Principle"). It replays gautron/splat.wgsl at the pinned pixel p
// record by record, after the frame's passes and in its encoder, with the frame's own records,
// G-buffer and camera, through the splat's own functions (gautron/common.wgsl: splat_bound,
// ward_terms, ward_weight, rotational_term, translational_term, extrapolate): one invocation per
// record of the cache decides whether its bound holds p's centre, Ward's weight there before and
// after the clamp, whether the splat keeps it (w > 1/a), E_k extrapolated to p with each
// gradient's term apart, and lists it when its bound holds p or p lies within 2·a·R_k of it.
// One invocation reads what the frame wrote at p: the splat's sums (gautron.accum), the
// resolve's output (gautron.indirect, gautron.irradiance) and c·DI. The Rust side
// (passes::gautron::explain) turns the list into contributions and checks their sums.
#import gautron/common.wgsl
#import common/camera.wgsl
#import common/bins.wgsl
#import common/receiver.wgsl

struct ExplainParams {
    // x, y: the pixel p; z: the splats' snapshots (0: none, the records as the frame left them)
    pixel: vec4<u32>,
}

// What the frame wrote at p (passes::gautron::explain::GpuHeader).
struct Header {
    // x, y: the pixel; z: the records the cache can hold; w: the records in it
    pixel: vec4<u32>,
    // gautron.accum at p: rgb Σ w·E, a Σ w
    accum: vec4<f32>,
    // gautron.indirect at p (the resolve's f·E)
    indirect: vec4<f32>,
    // gautron.irradiance at p (E = RGB / A; a: Σ w)
    irradiance: vec4<f32>,
    // rgb: the resolve's receiver factor f (c·DI/π, plus the specular lobe's; its light is f·E);
    // a: 1 when the G-buffer is empty at p
    albedo: vec4<f32>,
    // xyz: P, the visible point; w: 0
    point: vec4<f32>,
    // xyz: n, normalized as the splat does
    normal: vec4<f32>,
    // the cache's counters after the frame: records made this frame, records computed again
    // this frame, stale records waiting, records
    state: vec4<u32>,
    // xy: p's centre in NDC (bin_centre_ndc, as the binned splat tests it)
    ndc: vec4<f32>,
}

// One listed record (passes::gautron::explain::GpuEntry).
struct Entry {
    // x: the record's index k; y: flags (EXPLAIN_*)
    index: vec4<u32>,
    // x: Ward's weight clamped at w_max (what the splat adds); y: before the clamp;
    // z: ‖P − P_k‖/R_k; w: √(1 − n·n_k)
    weight: vec4<f32>,
    // rgb: E_k extrapolated to P with the gradients as set, clamped at 0 (what the splat
    // multiplies by w); a: (P − P_k)·(n + n_k)/2 + tol·R_k (< 0: in front)
    e: vec4<f32>,
    // rgb: the rotational gradient's term (n_k × n)·∇_r E_k
    rot: vec4<f32>,
    // rgb: the translational gradient's term (P − P_k)·∇_t E_k
    trans: vec4<f32>,
    // the record's position (xyz: P_k, w: R_k), normal (w: H), irradiance (w: the frame it was
    // computed in) and pixel (xy: where it was made, w: its state)
    position: vec4<f32>,
    normal: vec4<f32>,
    irradiance: vec4<f32>,
    pixel: vec4<f32>,
}

const EXPLAIN_COVERS: u32 = 1u;   // its splat's bound holds p's centre
const EXPLAIN_PENDING: u32 = 2u;  // its hemisphere is being computed (an empty bound)
const EXPLAIN_IN_FRONT: u32 = 4u; // Ward's "in front" test: w = 0
const EXPLAIN_BELOW: u32 = 8u;    // w ≤ 1/a: the splat discards it
// A clamp no weight reaches: Ward's weight before the clamp.
const EXPLAIN_NO_CLAMP: f32 = 1e30;

@group(0) @binding(0) var<uniform> params: GautronParams;
@group(0) @binding(1) var<uniform> camera: Camera;
@group(0) @binding(2) var<storage, read> records: array<Record>;
@group(0) @binding(3) var<storage, read> state: CacheState;
@group(0) @binding(4) var g_position: texture_2d<f32>;
@group(0) @binding(5) var g_normal: texture_2d<f32>;
@group(0) @binding(6) var g_albedo: texture_2d<f32>;
@group(0) @binding(7) var accum: texture_2d<f32>;
@group(0) @binding(8) var indirect: texture_2d<f32>;
@group(0) @binding(9) var irradiance: texture_2d<f32>;
@group(0) @binding(10) var<uniform> explain: ExplainParams;
@group(0) @binding(11) var<storage, read_write> header: Header;
// x: records listed, y: records whose bound holds p, z: records the splat added at p
@group(0) @binding(12) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(13) var<storage, read_write> listed: array<Entry>;
// The records as each splat of the frame read them (passes::gautron::explain::Snapshots):
// snapshot s holds the whole cache right after splat s (the cached records' splat, then each
// round's), and the cache's counters then (word 0 of each 256-byte slot: the record count).
@group(0) @binding(14) var<storage, read> snap_records: array<Record>;
@group(0) @binding(15) var<storage, read> snap_states: array<vec4<u32>>;
// the glossy receiver's direction sums, the plain sums that weigh them, the G-buffer material
@group(0) @binding(16) var accum_dir: texture_2d<f32>;
@group(0) @binding(17) var accum_plain: texture_2d<f32>;
@group(0) @binding(18) var g_material: texture_2d<f32>;

// Record k as the splat that added it read it: the first snapshot whose count holds k (a
// cached record computed again in a round, or clamped by a later round's neighbours, was
// splatted before that); without snapshots, the record as the frame left it.
fn splatted_record(k: u32) -> Record {
    let n = explain.pixel.z;
    let capacity = arrayLength(&records);
    for (var s = 0u; s < n; s = s + 1u) {
        if (k < snap_states[s * 16u].x) {
            return snap_records[s * capacity + k];
        }
    }
    return records[k];
}

// What the frame wrote at p (Gautron et al. 2005, "Radiance cache splatting", "From Octree to
// Splatting": the sums RGB, A and the resolve's RGB / A).
@compute @workgroup_size(1, 1, 1)
fn cs_explain_pixel() {
    let p = vec2<i32>(explain.pixel.xy);
    let nrm = textureLoad(g_normal, p, 0);
    let alb = textureLoad(g_albedo, p, 0);
    header.pixel = vec4<u32>(explain.pixel.xy, arrayLength(&records), state.count);
    header.accum = textureLoad(accum, p, 0);
    header.indirect = textureLoad(indirect, p, 0);
    header.irradiance = textureLoad(irradiance, p, 0);
    // The resolve's receiver factor, as it computes it (common/receiver.wgsl).
    let mat = textureLoad(g_material, p, 0);
    let d = receiver_direction(textureLoad(accum_dir, p, 0).xyz, textureLoad(accum_plain, p, 0).rgb);
    let v = normalize(camera.position.xyz - textureLoad(g_position, p, 0).xyz);
    let f = receiver_factor(d, normalize(nrm.xyz), v, alb.rgb, alb.a, mat.x, mat.y, params.rules.y > 0.5);
    header.albedo = vec4<f32>(f, select(0.0, 1.0, nrm.w < 0.5));
    header.point = vec4<f32>(textureLoad(g_position, p, 0).xyz, 0.0);
    header.normal = vec4<f32>(normalize(nrm.xyz), 0.0);
    header.state = vec4<u32>(state.made, state.refreshed, state.stale, state.count);
    header.ndc = vec4<f32>(bin_centre_ndc(explain.pixel.xy, camera.viewport.zw), 0.0, 0.0);
}

// Record k at p, as the splat weighs it (Gautron et al. 2005, "Radiance cache splatting",
// "From Octree to Splatting": the sphere a·R_k's screen bound, Ward's weight w_k > 1/a, RGB +=
// w_k·E_k(P) with the gradients, A += w_k).
@compute @workgroup_size(64, 1, 1)
fn cs_explain_records(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if (k >= state.count || k >= arrayLength(&records)) {
        return;
    }
    let px = vec2<i32>(explain.pixel.xy);
    let nrm = textureLoad(g_normal, px, 0);
    // the splat adds nothing where the G-buffer is empty
    if (nrm.w < 0.5) {
        return;
    }
    let p = textureLoad(g_position, px, 0).xyz;
    let n = normalize(nrm.xyz);
    let rec = splatted_record(k);
    let a = params.weight.x;
    let rect = splat_bound(rec, camera.view, camera.params.x, camera.viewport.xy);
    let c = bin_centre_ndc(explain.pixel.xy, camera.viewport.zw);
    // the binned splat's test (bins_next); the blended quads cover the same centres but on
    // their edges
    let covers = !(c.x < rect.x || c.x > rect.z || c.y < rect.y || c.y > rect.w);
    let near = length(p - rec.position.xyz) < 2.0 * a * rec.position.w;
    if (!covers && !near) {
        return;
    }
    var flags = 0u;
    if (covers) {
        flags = flags | EXPLAIN_COVERS;
    }
    if (rec.pixel.w < 0.5) {
        flags = flags | EXPLAIN_PENDING;
    }
    let terms = ward_terms(rec, p, n);
    let w = ward_weight(rec, p, n, params.weight.y);
    if (terms.z < terms.w) {
        flags = flags | EXPLAIN_IN_FRONT;
    } else if (w <= 1.0 / a) {
        flags = flags | EXPLAIN_BELOW;
    }
    var entry: Entry;
    entry.index = vec4<u32>(k, flags, 0u, 0u);
    entry.weight = vec4<f32>(w, ward_weight(rec, p, n, EXPLAIN_NO_CLAMP), terms.x, terms.y);
    entry.e = vec4<f32>(extrapolate(rec, p, n, params.weight.z > 0.5, params.weight.w > 0.5), terms.z - terms.w);
    entry.rot = vec4<f32>(rotational_term(rec, n), 0.0);
    entry.trans = vec4<f32>(translational_term(rec, p), 0.0);
    entry.position = rec.position;
    entry.normal = rec.normal;
    entry.irradiance = rec.irradiance;
    entry.pixel = rec.pixel;
    if (covers) {
        atomicAdd(&counters[1], 1u);
        if ((flags & (EXPLAIN_PENDING | EXPLAIN_IN_FRONT | EXPLAIN_BELOW)) == 0u) {
            atomicAdd(&counters[2], 1u);
        }
    }
    let slot = atomicAdd(&counters[0], 1u);
    if (slot < arrayLength(&listed)) {
        listed[slot] = entry;
    }
}
