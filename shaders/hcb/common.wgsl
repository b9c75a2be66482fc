// The hierarchical coherence buffer (Nguyen et al., 000 §3). Each level is two rgba32float
// textures: position (xyz world, w = a^w, the radius of the sphere the texel stands for)
// and normal (xyz, w = n^w, the group coherence; 0 = incoherent or background). Level k has
// ⌈w/2⌉ × ⌈h/2⌉ texels of level k − 1; texel (x, y) covers the 3×3 block centred at (2x, 2y).
// Also a sample's splat (§4.2–4.3: its rectangle, Eq. 8's errors, Eq. 9–10's weight), shared
// by the splat (splat.wgsl) and the pixel's replay (explain.wgsl): one implementation.
// CPU twin: render/src/cpu/hcb.rs (the readings of the paper are documented there).

// Rust twin: passes::hcb::HcbParams.
struct HcbParams {
    // x: cos θ_max, y: cos γ_max, z: d_max (scene units), w: pixel scale 2 tan(fov_y/2) / height
    thresholds: vec4<f32>,
    // xyz: eye position
    eye: vec4<f32>,
    // x: 1 when this is the top level (sample pass), y: level index, z: 1 for the cache's
    // supplementary G-buffer (§5.2: n^w = ±1 from the splatted weight), w: 1 to spread the
    // sign of incomplete texels upward (Fig. 7d)
    level: vec4<u32>,
    // x: incomplete weight threshold (§5.2), y: 1 for the glossy receiver (`hcb.receiver`,
    // normalize.wgsl), z: the footprint's clamp of |cos| (`hcb.footprint_min_cos`, base.wgsl)
    cache: vec4<f32>,
    // §5.3's 4×4 index pattern: the recompute phase of a new sample at texel (x, y) of its level
    pattern: array<vec4<u32>, 4>,
}

// One sample of the compact list (Rust twin: passes::hcb::GpuHcbSample).
struct HcbSample {
    // xyz: world position (the level texel's), w: a^w, the radius of the sphere it stands for
    position: vec4<f32>,
    // xyz: normal, w: n^w
    normal: vec4<f32>,
    // x, y: texel at its level; z: bits 0–7 the level, 8–15 the recompute counter (§5.3),
    // 16–23 the cache status while the cache is updated; w: G-buffer pixel x | y << 16
    texel: vec4<u32>,
    // rgb: the light gathered at the sample (irradiance), a: 1 once gathered, 0 until then
    // (new, or due for recomputation)
    light: vec4<f32>,
    // xyz: Σ lum(E_k) ω_k over the VPLs' irradiance E_k from directions ω_k (issue #51: the
    // receiver's specular lobe is lit from its direction; common/receiver.wgsl), 0 when the
    // gather that lit the sample keeps no direction
    dir: vec4<f32>,
}

// Indirect arguments of a quad draw over `instances` samples (6 vertices) and of a dispatch
// of 64-wide workgroups over `items` (x, y within the 65535 limit), in 8 words.
fn indirect_words(instances: u32, items: u32) -> array<u32, 8> {
    let groups = (items + 63u) / 64u;
    return array<u32, 8>(6u, instances, 0u, 0u, min(groups, 65535u), max((groups + 65534u) / 65535u, 1u), 1u, 0u);
}

// The 12 words of the HCB's indirect arguments: the splat draw over `n` samples, the gather
// dispatch over `items`, a spare word, and the draw over the samples after the `cached`
// first ones (§5.2).
fn hcb_args(n: u32, items: u32, cached: u32) -> array<u32, 12> {
    let w = indirect_words(n, items);
    return array<u32, 12>(w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7], 6u, n - min(cached, n), 0u, 0u);
}

// Corner of vertex `v` of a quad drawn as two triangles (6 vertices), in [−1, 1]².
fn quad_corner(v: u32) -> vec2<f32> {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    return corners[v % 6u];
}

fn sample_level(s: HcbSample) -> u32 {
    return s.texel.z & 0xffu;
}

fn pack_pixel(p: vec2<u32>) -> u32 {
    return (p.x & 0xffffu) | (p.y << 16u);
}

fn unpack_pixel(v: u32) -> vec2<u32> {
    return vec2<u32>(v & 0xffffu, v >> 16u);
}

// Parameters of the cache update (§5.1, §5.3); Rust twin: passes::hcb_cache::CacheParams.
struct CacheParams {
    // x: distance threshold (scene units), y: cos of the normal threshold, z: removal quad
    // side (pixels), w: recompute period
    limits: vec4<f32>,
}

// A cached sample's status during the update (texel.z bits 16–23).
const DROPPED: u32 = 0u;
const VALID: u32 = 1u;
const INVALID: u32 = 2u;

fn status(s: HcbSample) -> u32 {
    return (s.texel.z >> 16u) & 0xffu;
}

// Eq. 8 of Nguyen et al. (§4.2): the errors of the point b (normal n_b) toward sample s:
// x the distance error ‖b − a‖ / a^w, y the normal error √(1 − n_a·n_b) / √(1 − cos θ_max),
// z the pose error ρ √|âb·n_a| / √cos γ_max (ρ = 1 when a and b do not face each other, the
// first line of Eq. 3; else 0). `thresholds` is HcbParams.thresholds (x cos θ_max, y cos
// γ_max). CPU twin: cpu::hcb::coherence_errors.
fn coherence_errors(s: HcbSample, b: vec3<f32>, n_b: vec3<f32>, thresholds: vec4<f32>) -> vec3<f32> {
    let a = s.position.xyz;
    let n_a = s.normal.xyz;
    let d = b - a;
    let len = length(d);
    let e1 = len / max(s.position.w, 1e-12);
    // 1 − n_a·n_b as ½‖n_a − n_b‖² (unit normals): exact 0 for equal normals.
    let dn = n_a - n_b;
    let e2 = sqrt(0.5 * dot(dn, dn)) / sqrt(max(1.0 - thresholds.x, 1e-12));
    var e3 = 0.0;
    if (len > 0.0) {
        let ab = d / len;
        if (dot(ab, n_a) <= 0.0 || dot(-ab, n_b) <= 0.0) {
            e3 = sqrt(abs(dot(ab, n_a))) / sqrt(max(thresholds.y, 1e-12));
        }
    }
    return vec3<f32>(e1, e2, e3);
}

// Sample s's splat at the point b with normal n_b (§4.3): rgb w·E, a w, the weight of Eq. 10
// w = (1 − e_d)(1 − e_n)(1 − e_p) of Eq. 8's errors; a = −1 where b is not coherent to s
// (Eq. 9: an error above 1). CPU twin: cpu::hcb::weight.
fn splat_value(s: HcbSample, b: vec3<f32>, n_b: vec3<f32>, thresholds: vec4<f32>) -> vec4<f32> {
    let e = coherence_errors(s, b, n_b, thresholds);
    if (max(e.x, max(e.y, e.z)) > 1.0) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let w = (1.0 - e.x) * (1.0 - e.y) * (1.0 - e.z);
    return vec4<f32>(w * s.light.rgb, w);
}

// What sample s adds to the direction sums with its splat `v` (splat_value's): w·Σ lum(E_k) ω_k.
fn splat_direction(s: HcbSample, v: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(max(v.a, 0.0) * s.dir.xyz, 0.0);
}

// Sample s's splat quad in NDC (x0, y0, x1, y1) (§4.3: a screen quad bounding its sphere of
// centre a, radius a^w), seen by a camera of `view`, `view_proj` and eye `eye`, on a screen
// of 1 / `inv_size` pixels, with the pixel scale 2 tan(fov_y / 2) / height: the whole screen
// when its sphere holds the eye. Half-size: the tangent of the sphere's angular radius at its
// view depth (r / √(d² − r²), larger than at its distance), stretched by distance / depth for
// its off-axis ellipse, in pixels, plus one.
fn splat_quad(s: HcbSample, view: mat4x4<f32>, view_proj: mat4x4<f32>, eye: vec3<f32>, inv_size: vec2<f32>, pixel_scale: f32) -> vec4<f32> {
    let depth = -(view * vec4<f32>(s.position.xyz, 1.0)).z;
    let c = view_proj * vec4<f32>(s.position.xyz, 1.0);
    if (depth <= s.position.w || c.w <= 0.0) {
        return vec4<f32>(-1.0, -1.0, 1.0, 1.0);
    }
    let r = s.position.w / sqrt(depth * depth - s.position.w * s.position.w);
    let stretch = length(s.position.xyz - eye) / depth;
    let half_px = r * stretch / pixel_scale + 1.0;
    let half = vec2<f32>(half_px * 2.0 * inv_size.x, half_px * 2.0 * inv_size.y);
    let centre = c.xy / c.w;
    return vec4<f32>(centre - half, centre + half);
}
