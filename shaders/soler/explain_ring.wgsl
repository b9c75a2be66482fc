// Explain a pixel (issue #42), Soler et al.'s ring samples (004 §3–4, Eq. 1–4, Fig. 3; §4
// "Visibility"): after a bounce's levels were replayed (soler/explain.wgsl), the heaviest
// texel of each gathered level's list gathers its ring again, sample by sample, through the
// gather's own functions (soler/ring_texel.wgsl) with the gather's own uniform, so that each
// sample's light and the voxel march's verdict are the gather's. Rust side:
// passes::soler::explain.
#import soler/common.wgsl
#import soler/voxel_common.wgsl
#import soler/glossy.wgsl
#import common/random.wgsl
#import soler/ring.wgsl
#import soler/ring_texel.wgsl

// Rust twin: passes::soler::explain::RingParams.
struct RingParams {
    // x: the list (bounce · 16 + level) whose heaviest texel is replayed; y: 1 when the level
    // is gathered; z, w: 0
    list: vec4<u32>,
}

// One sample (passes::soler::explain::GpuRingTerm).
struct RingOut {
    // xy: its sender texel, z: 1 lit (it counts), w: 1 visible (the voxel march lets it through)
    sender: vec4<f32>,
    // rgb: its light L·K (what the gather adds when lit and visible), a: 0
    light: vec4<f32>,
    // xyz: the sender's world position
    position: vec4<f32>,
    // rgb: its light through the receiver's specular lobe (with the glossy reflection)
    spec: vec4<f32>,
}

const MAX_RING: u32 = 256u;

struct RingSlot {
    // xy: the texel, z: 1 when one was found, w: the samples N
    texel: vec4<u32>,
    terms: array<RingOut, 256>,
}

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var level_position: texture_2d<f32>;
@group(0) @binding(2) var level_normal: texture_2d<f32>;
@group(0) @binding(3) var level_radiance: texture_2d<f32>;
@group(0) @binding(4) var<storage, read> grid: array<u32>;
@group(0) @binding(5) var level_material: texture_2d<f32>;
@group(0) @binding(6) var<uniform> ring: RingParams;
// soler/explain.wgsl's header (u32 words: pixel, then the counts per list) and entries (six
// vec4 each: texel, weight, own, occlusion, position, spec).
@group(0) @binding(7) var<storage, read> header_words: array<u32>;
@group(0) @binding(8) var<storage, read> entries: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> slots: array<RingSlot>;

const MAX_PER_LEVEL: u32 = 64u;

@compute @workgroup_size(64, 1, 1)
fn cs_explain_ring(@builtin(local_invocation_index) li: u32) {
    let list = ring.list.x;
    let n = header_words[4u + list];
    // The list's heaviest texel (every invocation finds the same).
    var best = -1.0;
    var texel = vec2<u32>(0u);
    for (var i = 0u; i < n; i = i + 1u) {
        let base = (list * MAX_PER_LEVEL + i) * 6u;
        let w = entries[base + 1u].x;
        if (w > best) {
            best = w;
            texel = bitcast<vec4<u32>>(entries[base]).xy;
        }
    }
    let count = min(params.counts.x, MAX_RING);
    let found = best > 0.0 && ring.list.y == 1u;
    if (li == 0u) {
        slots[list].texel = vec4<u32>(texel, select(0u, 1u, found), params.counts.x);
    }
    if (!found) {
        return;
    }
    let x = vec2<i32>(texel);
    let r = ring_receiver(x);
    for (var i = li; i < count; i = i + 64u) {
        let t = ring_term(x, r, i);
        var out: RingOut;
        out.sender = vec4<f32>(vec2<f32>(t.q), select(0.0, 1.0, t.lit), select(0.0, 1.0, t.visible));
        out.light = vec4<f32>(t.light, 0.0);
        out.position = vec4<f32>(0.0);
        out.spec = vec4<f32>(t.spec, 0.0);
        if (t.lit) {
            out.position = textureLoad(level_position, t.q, 0);
        }
        slots[list].terms[i] = out;
    }
}
