// Gautron, Křivánek et al. 003: the irradiance record, Ward's weight, the extrapolation and
// the splat's bound, shared by the creation, the hemisphere reduction, the splat and the
// pixel's replay (explain.wgsl). CPU twin: cpu::gautron.

// One irradiance record ("Irradiance Caching": position, normal, irradiance, gradients,
// harmonic mean distance). Rust twin: passes::gautron::GpuRecord (160 bytes).
struct Record {
    // xyz: P_k, w: R_k after the clamps (scene units)
    position: vec4<f32>,
    // xyz: n_k, w: the harmonic mean distance H before the clamps
    normal: vec4<f32>,
    // rgb: E_k, w: the frame it was made in
    irradiance: vec4<f32>,
    // ∇_r E_k of the red, green and blue channel (xyz, world space)
    rot: array<vec4<f32>, 3>,
    // ∇_t E_k of the red, green and blue channel (xyz, world space)
    trans: array<vec4<f32>, 3>,
    // xy: the pixel it was made at, z: its linear view depth then, w: 0 while its hemisphere
    // is being computed, 1 once computed, 2 stale (to be computed again: see cs_maintain)
    pixel: vec4<f32>,
    // the scene draws its hemisphere saw, as 128 bits: bit (draw mod 128) (the record
    // cache's invalidation when objects move)
    seen: vec4<u32>,
    // xyz: Σ lum(L) cosθ Ω ω over the hemisphere's texels (world space; the border band not
    // included), the direction sum of the glossy receiver (issue #51, common/receiver.wgsl)
    dir: vec4<f32>,
}

const RECORD_VALID: f32 = 1.0;
const RECORD_STALE: f32 = 2.0;

// The cache's counters. Rust twin: passes::gautron::CacheState.
struct CacheState {
    // records in the cache (computed or being computed this round)
    count: u32,
    // first record of this round's new ones
    new_base: u32,
    // new records this round
    new_count: u32,
    // records made this frame
    made: u32,
    // candidates found this round (before the budget)
    candidates: u32,
    // stale records waiting to be computed again
    stale: u32,
    // where the next round's search for stale records starts (round robin)
    cursor: u32,
    // stale records this round computes again (slots new_count … new_count + refresh − 1)
    refresh: u32,
    // records computed again this frame
    refreshed: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

// Rust twin: passes::gautron::GautronParams.
struct GautronParams {
    // x: accuracy a, y: weight clamp w_max, z: rotational gradient on, w: translational on
    weight: vec4<f32>,
    // x: hemisphere px N, y: tiles per atlas row, z: tan(aperture / 2), w: near plane
    hemisphere: vec4<f32>,
    // x: R_min, y: R_max in scene units; z: R_min, w: R_max in px
    clamps: vec4<f32>,
    // x: creation tile px, y: records per round (slots), z: capacity, w: far plane
    creation: vec4<f32>,
    // x: frame, y: projection's P00, z: P11, w: half the G-buffer's height
    misc: vec4<f32>,
    // x: the "in front" test's tolerance × R_k (f32 max: no test), y: 1 for the glossy
    // receiver (`gautron.receiver`, resolve.wgsl)
    rules: vec4<f32>,
}

// A record's hemisphere camera ("Simple plane sampling"), written by create.wgsl, read by
// the raster and the reduction. Rust twin: passes::gautron::HemisphereCamera.
struct HemisphereCamera {
    view_proj: mat4x4<f32>,
    // xyz: P_k (the viewer), w: 1 when the slot holds a new record
    position: vec4<f32>,
    t: vec4<f32>,
    b: vec4<f32>,
    // xyz: n_k, w: the record's index in the cache
    n: vec4<f32>,
    // the tile in the atlas's NDC: xy offset of its centre, zw scale
    tile: vec4<f32>,
}

// Ward's weight's parts (Gautron et al. 2005, "Radiance cache splatting", "From Octree to
// Splatting": Ward's weight; Ward 1988's "Weighting Function", which the 2005 text prints
// without an equation number): x: ‖P − P_k‖/R_k, y: √(1 − n·n_k), z: (P − P_k)·(n + n_k)/2
// and w: −tol·R_k, the two sides of Ward's "in front" test (tol = params.rules.x). ward_weight
// and the pixel's replay (explain.wgsl) both read them: one implementation.
fn ward_terms(rec: Record, p: vec3<f32>, n: vec3<f32>) -> vec4<f32> {
    let d = p - rec.position.xyz;
    let r = max(rec.position.w, 1e-20);
    return vec4<f32>(
        length(d) / r,
        sqrt(max(0.0, 1.0 - dot(n, rec.normal.xyz))),
        dot(d, n + rec.normal.xyz) * 0.5,
        -params.rules.x * r,
    );
}

// Ward's weight ("Weighting Function", Ward 1988): 1 / (‖P − P_k‖/R_k + √(1 − n·n_k)),
// clamped to w_max (⚠[gautron.weight-clamp] unbounded at P = P_k); 0 when the record lies in
// front of P by Ward's test (P − P_k)·(n + n_k)/2 < −tol·R_k (not in 003; tol =
// params.rules.x, f32 max: no test). Twin: cpu::gautron::weight.
fn ward_weight(rec: Record, p: vec3<f32>, n: vec3<f32>, w_max: f32) -> f32 {
    let t = ward_terms(rec, p, n);
    if (t.z < t.w) {
        return 0.0;
    }
    return 1.0 / max(t.x + t.y, 1.0 / w_max);
}

// The rotational gradient's term (n_k × n)·∇_r E_k per channel (Gautron et al. 2005, "Radiance
// cache splatting", "From Octree to Splatting": E_k extrapolated by its gradients; Ward and
// Heckbert 1992). Twin: the rotational part of cpu::gautron::extrapolate.
fn rotational_term(rec: Record, n: vec3<f32>) -> vec3<f32> {
    let axis = cross(rec.normal.xyz, n);
    return vec3<f32>(dot(axis, rec.rot[0].xyz), dot(axis, rec.rot[1].xyz), dot(axis, rec.rot[2].xyz));
}

// The translational gradient's term (P − P_k)·∇_t E_k per channel (Gautron et al. 2005,
// "Radiance cache splatting", "From Octree to Splatting"; Křivánek et al. 2005). Twin: the
// translational part of cpu::gautron::extrapolate.
fn translational_term(rec: Record, p: vec3<f32>) -> vec3<f32> {
    let d = p - rec.position.xyz;
    return vec3<f32>(dot(d, rec.trans[0].xyz), dot(d, rec.trans[1].xyz), dot(d, rec.trans[2].xyz));
}

// E_k + (n_k × n)·∇_r + (P − P_k)·∇_t per channel ("Irradiance Interpolation"), each gradient
// on or off, clamped at 0. Twin: cpu::gautron::extrapolate.
fn extrapolate(rec: Record, p: vec3<f32>, n: vec3<f32>, rotational: bool, translational: bool) -> vec3<f32> {
    var e = rec.irradiance.rgb;
    if (rotational) {
        e = e + rotational_term(rec, n);
    }
    if (translational) {
        e = e + translational_term(rec, p);
    }
    return max(e, vec3<f32>(0.0));
}

// The NDC interval [lo, hi] of a circle (centre (c, d) with d the distance in front of the
// eye, radius ρ) seen from the eye along one axis; scale is P00 or P11 (Gautron et al. 2005,
// "Radiance cache splatting", "From Octree to Splatting": the quad "tightly enclosing the
// splatted sphere"; twin: cpu::gautron::sphere_ndc_rect).
fn tangent_interval(c: f32, d: f32, rho: f32, scale: f32) -> vec2<f32> {
    let k = d * d - rho * rho;
    let root = sqrt(max(c * c + k, 0.0));
    let lo = (c * d - rho * root) / k;
    let hi = (c * d + rho * root) / k;
    return vec2<f32>(lo, hi) * scale;
}

// A record's splat rectangle in NDC (x0, y0, x1, y1) seen by a camera of `view`, near plane
// `near` and `viewport` (width, height) px: the screen bound of its sphere of radius a·R_k
// (Gautron et al. 2005, "Radiance cache splatting", "From Octree to Splatting", the sphere
// inside which the simplified weight exceeds 1/a); the whole screen when the sphere reaches the
// near plane; an empty one while its hemisphere is being computed. The splat and the pixel's
// replay (explain.wgsl) both call it. Twin: cpu::gautron::sphere_ndc_rect.
fn splat_bound(rec: Record, view: mat4x4<f32>, near: f32, viewport: vec2<f32>) -> vec4<f32> {
    if (rec.pixel.w < 0.5) {
        return vec4<f32>(1.0, 1.0, -1.0, -1.0);
    }
    let rho = params.weight.x * rec.position.w;
    let c = (view * vec4<f32>(rec.position.xyz, 1.0)).xyz;
    let d = -c.z;
    var rect = vec4<f32>(-1.0, -1.0, 1.0, 1.0);
    if (d - rho > near) {
        let x = tangent_interval(c.x, d, rho, params.misc.y);
        let y = tangent_interval(c.y, d, rho, params.misc.z);
        // half a pixel more on every side: a sphere smaller than a pixel (R_k clamped to
        // ~1 px, the brute force of the bench) still reaches its own pixel's centre despite
        // the rounding of its position
        let half_px = vec2<f32>(1.0) / viewport;
        rect = vec4<f32>(x.x - half_px.x, y.x - half_px.y, x.y + half_px.x, y.y + half_px.y);
        rect = vec4<f32>(max(rect.xy, vec2<f32>(-1.0)), min(rect.zw, vec2<f32>(1.0)));
    }
    return rect;
}

// The hemisphere camera's tangent frame (t, b) of a normal, t × b = n. Twin: cpu::gautron::frame.
fn tangent_frame(n: vec3<f32>) -> mat2x3<f32> {
    var t: vec3<f32>;
    if (abs(n.z) < 0.999) {
        t = normalize(cross(vec3<f32>(0.0, 0.0, 1.0), n));
    } else {
        t = normalize(cross(vec3<f32>(1.0, 0.0, 0.0), n));
    }
    return mat2x3<f32>(t, cross(n, t));
}

// Pixels per scene unit at the record's depth when it was made (R_k's clamps in pixels).
fn record_px_per_unit(params: GautronParams, rec: Record) -> f32 {
    return params.misc.z * params.misc.w / max(rec.pixel.z, 1e-6);
}

// R_k from the harmonic mean distance H: clamped in scene units, then its projection at the
// record's depth in pixels (the reduction and the VPL-lit records).
fn clamped_radius(params: GautronParams, h: f32, rec: Record) -> f32 {
    let r = clamp(h, params.clamps.x, params.clamps.y);
    let px_per_unit = record_px_per_unit(params, rec);
    return clamp(r * px_per_unit, params.clamps.z, params.clamps.w) / px_per_unit;
}
