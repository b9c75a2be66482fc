// Explain a pixel (issue #42) for the hierarchical coherence buffer (Nguyen et al. 000): the
// coherence-weighted splatting of the samples (§4.2–4.3, Eq. 8–10) and Eq. 11's
// normalisation, whatever lit the samples (the VPL gather at the samples, §4.1; GI Lab's mixes:
// Soler's ring gather or Gautron's hemispheres at the samples) and with the sample cache (§5)
// or the confidence merge (Knecht 002 §3.5) after it. It replays, after the frame's passes and
// in its encoder, each sample's splat at the pinned pixel p with the frame's own inputs (the
// sample list, its counter, the G-buffer), calling the splat's own splat_quad and splat_value
// (hcb/common.wgsl), and reads the buffers the frame wrote at p: the splat's sums
// (`hcb.weight_sum`), Eq. 11's `hcb.irradiance`, the stage's output `hcb.indirect` and the
// chain's last output. The Rust side (passes::hcb::explain) turns this into the pixel's
// contributions and checks their sums against those buffers.
//
// cs_explain_args (one invocation) writes the header and the indirect arguments of
// cs_explain_samples: one invocation per sample of the list (the count is counter word 0,
// as the splat's cs_args reads it); the samples whose quad holds p's centre are appended to
// `entries` (at most arrayLength of them; the header counts them all).
#import common/camera.wgsl
#import common/reproject.wgsl
#import hcb/common.wgsl
#import common/receiver.wgsl
#import common/brdf.wgsl
#import common/split_light.wgsl

// Rust twin: passes::hcb::explain::ExplainParams.
struct ExplainParams {
    // x, y: the pixel p; z: 1 with the sample cache (counter words 1–2 are its counts);
    // w: 1 when the confidence merge ran after the splat (its textures are bound), 2 when it ran
    // demodulated (its history is `split_prev`: knecht/temporal/confidence.wgsl)
    pixel: vec4<u32>,
}

// Rust twin: passes::hcb::explain::GpuHeader.
struct Header {
    // x: samples in the list, y: 0 (`tally` counts the samples whose quad holds p), z: the
    // cached samples (counter word 1), w: the re-gathered ones (word 2)
    counts: vec4<u32>,
    // x: 1 when p has a surface; y: 0; z, w: p (the read-back's match with its run)
    state: vec4<u32>,
    // `hcb.weight_sum` at p: rgb Σ w·E, a Σ w (Eq. 10's sums)
    weight_sum: vec4<f32>,
    // `hcb.irradiance` at p (Eq. 11: Σ w·E / Σ w; a = 1 where a sample reached p)
    irradiance: vec4<f32>,
    // `hcb.indirect` at p (the stage's output: c·DI/π × the irradiance)
    indirect: vec4<f32>,
    // rgb: the normalize pass's receiver factor at p (c·DI/π, plus the specular lobe's); a: 0
    factor: vec4<f32>,
    // the confidence merge: rgb the history it read for p, a the confidence c
    history: vec4<f32>,
    // the chain's last output at p (the pixel's indirect value)
    final_value: vec4<f32>,
}

// One sample whose quad holds p (Rust twin: passes::hcb::explain::GpuEntry).
struct Entry {
    // x: its index in the list, y: flags (EXPLAIN_*), z: texel.z (bits 0–7 the level, 8–15
    // the recompute counter), w: its G-buffer pixel x | y << 16
    index: vec4<u32>,
    // xyz: its world position, w: a^w
    position: vec4<f32>,
    // x, y, z: Eq. 8's distance, normal and pose errors at p; w: Eq. 10's weight (−1 when p
    // is not coherent to it, Eq. 9)
    errors: vec4<f32>,
    // rgb: its gathered light E_s (irradiance), a: 1 once gathered
    light: vec4<f32>,
    // its splat's quad in NDC (x0, y0, x1, y1: splat_quad), for the overlay
    quad: vec4<f32>,
}

const EXPLAIN_COHERENT: u32 = 1u;   // p is coherent to it (Eq. 9): it adds to p's sums
const EXPLAIN_CACHED: u32 = 2u;     // a sample kept from the previous frame (§5.1)
const EXPLAIN_REGATHERED: u32 = 4u; // a cached sample whose light was gathered again (§5.3)
const EXPLAIN_NEW: u32 = 8u;        // a sample identified this frame (§5.2)

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> hp: HcbParams;
@group(0) @binding(2) var<uniform> explain: ExplainParams;
@group(0) @binding(3) var<storage, read> samples: array<HcbSample>;
@group(0) @binding(4) var<storage, read> counter: array<u32>;
@group(0) @binding(5) var g_position: texture_2d<f32>;
@group(0) @binding(6) var g_normal: texture_2d<f32>;
@group(0) @binding(7) var g_albedo: texture_2d<f32>;
@group(0) @binding(8) var g_motion: texture_2d<f32>;
@group(0) @binding(9) var weight_sum: texture_2d<f32>;
@group(0) @binding(10) var irradiance: texture_2d<f32>;
@group(0) @binding(11) var indirect: texture_2d<f32>;
@group(0) @binding(12) var final_light: texture_2d<f32>;
@group(0) @binding(13) var confidence: texture_2d<f32>;
@group(0) @binding(14) var history_prev: texture_2d<f32>;
@group(0) @binding(15) var<storage, read_write> header: Header;
// [0]: the samples whose quad holds p (all of them, also those beyond `entries`)
@group(0) @binding(16) var<storage, read_write> tally: array<atomic<u32>, 4>;
@group(0) @binding(17) var<storage, read_write> entries: array<Entry>;
// the glossy receiver's direction sums (`hcb.weight_sum.direction`) and the G-buffer material
@group(0) @binding(18) var weight_dir: texture_2d<f32>;
@group(0) @binding(19) var g_material: texture_2d<f32>;
// the demodulated merge's split history (common/split_light.wgsl)
@group(0) @binding(20) var split_prev: texture_2d<u32>;
// cs_explain_args only: the dispatch-indirect (x, y, 1) of cs_explain_samples
@group(1) @binding(0) var<storage, read_write> args: array<u32>;

fn sample_count() -> u32 {
    return min(counter[0], arrayLength(&samples));
}

@compute @workgroup_size(1, 1, 1)
fn cs_explain_args() {
    let n = sample_count();
    let words = indirect_words(n, n);
    args[0] = words[4];
    args[1] = words[5];
    args[2] = words[6];
    let p = vec2<i32>(explain.pixel.xy);
    var h: Header;
    h.counts = vec4<u32>(n, 0u, 0u, 0u);
    if (explain.pixel.z == 1u) {
        h.counts.z = counter[1];
        h.counts.w = counter[2];
    }
    h.state = vec4<u32>(select(0u, 1u, textureLoad(g_normal, p, 0).w >= 0.5), 0u, explain.pixel.xy);
    h.weight_sum = textureLoad(weight_sum, p, 0);
    h.irradiance = textureLoad(irradiance, p, 0);
    h.indirect = textureLoad(indirect, p, 0);
    // normalize.wgsl's factor, as it computes it (common/receiver.wgsl).
    let alb = textureLoad(g_albedo, p, 0);
    let mat = textureLoad(g_material, p, 0);
    let d = receiver_direction(textureLoad(weight_dir, p, 0).xyz, h.weight_sum.rgb);
    let v = normalize(hp.eye.xyz - textureLoad(g_position, p, 0).xyz);
    let nrm = normalize(textureLoad(g_normal, p, 0).xyz);
    h.factor = vec4<f32>(receiver_factor(d, nrm, v, alb.rgb, alb.a, mat.x, mat.y, hp.cache.y > 0.5), 0.0);
    h.final_value = textureLoad(final_light, p, 0);
    if (explain.pixel.w >= 1u) {
        // The history the confidence merge read for p (knecht/temporal/confidence.wgsl).
        let c = textureLoad(confidence, p, 0).r;
        var prev = vec3<f32>(0.0);
        if (c > 0.0) {
            let size = textureDimensions(g_normal);
            let q = previous_texel(p, textureLoad(g_motion, p, 0).xy, size);
            if (q.x >= 0) {
                if (explain.pixel.w == 2u) {
                    // The demodulated merge's history as p reflects it: k_p·E_prev + S_prev.
                    let v = textureLoad(split_prev, q, 0);
                    prev = brdf_diffuse(alb.rgb, alb.a) * unpack_irradiance(v) + unpack_specular(v);
                } else {
                    prev = textureLoad(history_prev, q, 0).rgb;
                }
            }
        }
        h.history = vec4<f32>(prev, c);
    }
    header = h;
    atomicStore(&tally[0], 0u);
}

// Each sample's splat at p: whether its quad holds p's centre (the test of the binned
// splat, common/bins.wgsl's bins_next at bin_centre_ndc; the quads' rasterization samples the
// same centre), Eq. 8's errors, Eq. 9's verdict and Eq. 10's weight.
@compute @workgroup_size(64, 1, 1)
fn cs_explain_samples(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * 65535u * 64u;
    if (i >= sample_count() || header.state.x == 0u) {
        return;
    }
    let s = samples[i];
    let r = splat_quad(s, camera.view, camera.view_proj, camera.position.xyz, camera.viewport.zw, hp.thresholds.w);
    let inv = camera.viewport.zw;
    let c = vec2<f32>((f32(explain.pixel.x) + 0.5) * inv.x * 2.0 - 1.0, 1.0 - (f32(explain.pixel.y) + 0.5) * inv.y * 2.0);
    if (c.x < r.x || c.x > r.z || c.y < r.y || c.y > r.w) {
        return;
    }
    let p = vec2<i32>(explain.pixel.xy);
    let b = textureLoad(g_position, p, 0).xyz;
    let n_b = normalize(textureLoad(g_normal, p, 0).xyz);
    let e = coherence_errors(s, b, n_b, hp.thresholds);
    let v = splat_value(s, b, n_b, hp.thresholds);
    var flags = select(0u, EXPLAIN_COHERENT, v.a >= 0.0);
    if (explain.pixel.z == 1u) {
        if (i >= counter[1]) {
            flags = flags | EXPLAIN_NEW;
        } else if (((s.texel.z >> 8u) & 0xffu) == 0u) {
            // cache.wgsl's cs_compact restarts the counter of the samples it queues.
            flags = flags | EXPLAIN_REGATHERED;
        } else {
            flags = flags | EXPLAIN_CACHED;
        }
    }
    let slot = atomicAdd(&tally[0], 1u);
    if (slot < arrayLength(&entries)) {
        entries[slot] = Entry(vec4<u32>(i, flags, s.texel.z, s.texel.w), s.position, vec4<f32>(e, v.a), s.light, r);
    }
}
