// Explain a pixel (issue #42) for Soler et al.'s screen-space gather (004 §4, Fig. 4): which
// texels of which mip level gave pixel p its irradiance, and with what weight. The joint
// bilateral upsampling is linear in the coarse light, so the light of p is Σ over levels k and
// texels t of w_k(t) · E_k(t), with w_k(t) the product of the upsampling weights along every
// path from t down to p (soler/jbu.wgsl, the same function the upsampling runs) and E_k(t)
// the level's own gathered irradiance (the ring samples' sum, soler/gather.wgsl), beside the
// light the voxel visibility removed there. Replayed after each bounce's passes (004 §4
// "Multi-bounce": the levels' light is the bounce's until the next one gathers), level by level
// from the G-buffer up: each dispatch takes level k's texels and weights, reads their own
// light and spreads the weights to level k + 1; every bounce has its own region of texels.
// Rust side: passes::soler::explain.
#import soler/common.wgsl
#import soler/jbu.wgsl
#import common/reproject.wgsl

// Rust twin: passes::soler::explain::StepParams.
struct StepParams {
    // x: level k; y: 1 when level k has its own gathered light (cs_explain_kept: 1 when the
    // kept bounce has a glossy part); z: 1 for the top level (no coarser level to spread to);
    // w: the bounce (0 … 3)
    level: vec4<u32>,
    // x: σ depth, y: σ normal (soler.upsample_sigma_*)
    sigma: vec4<f32>,
}

// One texel of a level reaching p (passes::soler::explain::GpuEntry).
struct Entry {
    // x, y: the texel; z: its level; w: 1 once read
    texel: vec4<u32>,
    // x: its weight to p (the upsampling chain's product)
    weight: vec4<f32>,
    // rgb: its own gathered irradiance E_k(t) (0 on levels not gathered)
    own: vec4<f32>,
    // rgb: the light the voxel visibility removed there; a: the visible fraction of its lit
    // samples (soler.level.k.occlusion)
    occlusion: vec4<f32>,
    // xyz: its world position; w: its view depth
    position: vec4<f32>,
    // rgb: its own glossy light S_k(t) (soler.level.k.specular; 0 without the glossy
    // reflection)
    spec: vec4<f32>,
}

struct Header {
    // x, y: the pixel
    pixel: vec4<u32>,
    // Texels per bounce and level (4 bounces × 16 levels at most).
    counts: array<u32, 64>,
    // soler.indirect at p (the resolved radiance before the temporal filter)
    indirect: vec4<f32>,
    // the stage's output at p (soler.temporal with the filter, else soler.indirect)
    last: vec4<f32>,
    // rgb: W(H) at p (soler.temporal.warped), a: Eq. 6's effective a (soler.temporal.a)
    history: vec4<f32>,
    // rgb: c·DI/π at p; a: 1 when p has a surface
    albedo: vec4<f32>,
    // rgb: the glossy light's warped history W_S at p (0 where the history was not taken)
    spec_history: vec4<f32>,
    // Per bounce: rgb its kept light at p (soler.bounce.b, with its glossy part), when this
    // frame did not gather it (alternating bounces)
    kept: array<vec4<f32>, 4>,
}

const MAX_PER_LEVEL: u32 = 64u;
const MAX_LEVELS: u32 = 16u;
const INV_PI: f32 = 0.318309886183791;

@group(0) @binding(0) var<uniform> step: StepParams;
@group(0) @binding(1) var fine_position: texture_2d<f32>;
@group(0) @binding(2) var fine_normal: texture_2d<f32>;
@group(0) @binding(3) var fine_light: texture_2d<f32>;
@group(0) @binding(4) var fine_occlusion: texture_2d<f32>;
@group(0) @binding(5) var coarse_position: texture_2d<f32>;
@group(0) @binding(6) var coarse_normal: texture_2d<f32>;
@group(0) @binding(7) var indirect: texture_2d<f32>;
@group(0) @binding(8) var last: texture_2d<f32>;
@group(0) @binding(9) var warped: texture_2d<f32>;
@group(0) @binding(10) var blend_a: texture_2d<f32>;
@group(0) @binding(11) var g_albedo: texture_2d<f32>;
@group(0) @binding(12) var<storage, read_write> header: Header;
@group(0) @binding(13) var<storage, read_write> entries: array<Entry>;
@group(0) @binding(14) var fine_specular: texture_2d<f32>;
@group(0) @binding(15) var g_motion: texture_2d<f32>;
@group(0) @binding(16) var spec_history_prev: texture_2d<f32>;

// The list of bounce b's level k: its count's index, and its first entry's.
fn list(b: u32, k: u32) -> u32 {
    return b * MAX_LEVELS + k;
}

// Adds weight w of texel q to level k's list of bounce b (one entry per texel).
fn spread(b: u32, k: u32, q: vec2<i32>, w: f32) {
    let base = list(b, k) * MAX_PER_LEVEL;
    let n = header.counts[list(b, k)];
    let t = vec2<u32>(q);
    for (var i = 0u; i < n; i = i + 1u) {
        if (all(entries[base + i].texel.xy == t)) {
            entries[base + i].weight.x = entries[base + i].weight.x + w;
            return;
        }
    }
    if (n < MAX_PER_LEVEL) {
        var e: Entry;
        e.texel = vec4<u32>(t, k, 0u);
        e.weight = vec4<f32>(w, 0.0, 0.0, 0.0);
        entries[base + n] = e;
        header.counts[list(b, k)] = n + 1u;
    }
}

// The pixel's buffers (once, before the steps).
@compute @workgroup_size(1, 1, 1)
fn cs_explain_pixel() {
    let p = vec2<i32>(header.pixel.xy);
    header.indirect = textureLoad(indirect, p, 0);
    header.last = textureLoad(last, p, 0);
    header.history = vec4<f32>(textureLoad(warped, p, 0).rgb, textureLoad(blend_a, p, 0).r);
    let alb = textureLoad(g_albedo, p, 0);
    header.albedo = vec4<f32>(alb.rgb * alb.a * INV_PI, textureLoad(fine_normal, p, 0).w);
    // soler/temporal.wgsl reads the glossy history at the warped texel wherever it takes W.
    header.spec_history = vec4<f32>(0.0);
    if (textureLoad(warped, p, 0).a > 0.5) {
        let q = previous_texel(p, textureLoad(g_motion, p, 0).xy, textureDimensions(g_albedo));
        if (q.x >= 0) {
            header.spec_history = vec4<f32>(textureLoad(spec_history_prev, q, 0).rgb, 0.0);
        }
    }
}

// Level k's texels: their own light, then their weights spread to level k + 1 as the
// upsampling of level k + 1 into level k weighs them.
@compute @workgroup_size(1, 1, 1)
fn cs_explain_step() {
    let k = step.level.x;
    let b = step.level.w;
    let base = list(b, k) * MAX_PER_LEVEL;
    let n = header.counts[list(b, k)];
    for (var i = 0u; i < n; i = i + 1u) {
        var e = entries[base + i];
        let t = vec2<i32>(e.texel.xy);
        e.position = textureLoad(fine_position, t, 0);
        if (step.level.y == 1u) {
            e.own = textureLoad(fine_light, t, 0);
            e.occlusion = textureLoad(fine_occlusion, t, 0);
            e.spec = textureLoad(fine_specular, t, 0);
        }
        e.texel.w = 1u;
        entries[base + i] = e;
        let nf = textureLoad(fine_normal, t, 0);
        if (step.level.z == 1u || nf.w < 0.5 || e.weight.x == 0.0) {
            continue;
        }
        var j = jbu_weights(e.texel.xy, e.position.w, nf.xyz, coarse_position, coarse_normal, step.sigma.xy);
        if (j.wsum > 1e-6) {
            for (var c = 0; c < 4; c = c + 1) {
                if (j.w[c] > 0.0) {
                    spread(b, k + 1u, j.q[c], e.weight.x * j.w[c] / j.wsum);
                }
            }
        } else if (j.best >= 0) {
            spread(b, k + 1u, j.q[j.best], e.weight.x);
        }
    }
}

// A bounce this frame did not gather (alternating bounces): its kept light at p, with its
// glossy part (soler/bounces.wgsl adds both), bound as fine_light and fine_specular.
@compute @workgroup_size(1, 1, 1)
fn cs_explain_kept() {
    let p = vec2<i32>(header.pixel.xy);
    var kept = textureLoad(fine_light, p, 0).rgb;
    if (step.level.y == 1u) {
        kept = kept + textureLoad(fine_specular, p, 0).rgb;
    }
    header.kept[step.level.w] = vec4<f32>(kept, 1.0);
}
