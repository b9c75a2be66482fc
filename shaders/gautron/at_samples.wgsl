// GI Lab's mix of Nguyen et al. 000 and Gautron et al. 003 (issue #17 "Mixes"): a record's
// hemisphere ("Simple plane sampling") computed at each of the HCB's samples (000 §3)
// instead of where Gautron's coverage test asks for one, and the samples' irradiance then
// spread by the HCB's coherence splatting (000 §4.2–4.3, hcb/splat.wgsl). The samples are
// taken in chunks of the round's slots: `cs_samples_begin` turns chunk k's samples into
// records in slots 0…m−1 of the record buffer (as stale records computed again in place, so
// that cs_cameras sets their cameras at the sample's own position and normal), the
// hemisphere raster and reduction compute them, `cs_samples_store` writes each E into its
// sample's light (irradiance, as the HCB's VPL gather: the splat reflects it with c·DI/π).
// With the HCB's sample cache (Nguyen §5, issue #53) the chunks run after the build over the
// cached samples due for recomputation (§5.3, their slots in `queue`) followed by the new
// samples after the cached ones (§5.2); the other cached samples keep their hemisphere's
// irradiance. (The HCB's VPL gather lights the due ones before the cached splat; that splat
// only decides where the build adds samples, by the weights, and the mix splats every sample
// again at the end, so one set after the build does.)
#import gautron/common.wgsl
#import hcb/common.wgsl
#import common/fullscreen.wgsl

const REFRESH: u32 = 0x80000000u;

struct RoundParams {
    // x: the chunk's index; y: which samples (0 every sample of the list, 1 the cached ones
    // due for recomputation, listed in `queue`, then the new ones after the cached ones); zw
    // unused
    round: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: GautronParams;
@group(0) @binding(1) var<uniform> round: RoundParams;
@group(0) @binding(2) var<storage, read_write> state: CacheState;
@group(0) @binding(3) var<storage, read_write> slots: array<u32>;
@group(0) @binding(4) var<storage, read_write> records: array<Record>;
// the hemisphere raster's indirect draws: 5 words per scene draw, word 1 the instance count
@group(0) @binding(5) var<storage, read_write> raster_args: array<u32>;
@group(0) @binding(6) var<storage, read> counter: array<u32>;
@group(0) @binding(7) var<storage, read_write> list: array<HcbSample>;
// the HCB splat's indirect arguments (as hcb/gather.wgsl's cs_args writes them)
@group(0) @binding(8) var<storage, read_write> args: array<u32>;
// the list slots of the cached samples due for recomputation (counter word 2 of them)
@group(0) @binding(9) var<storage, read> queue: array<u32>;
// the chunk's round arguments (passes::gautron::hemisphere::RoundArgs): the tile clears' draw,
// the direct light's dispatch over the rows of tiles in use, the reduction's dispatch
@group(0) @binding(10) var<storage, read_write> round_args: array<u32>;

fn sample_count() -> u32 {
    return min(counter[0], arrayLength(&list));
}

// The cached samples due for recomputation (mode 1; §5.3).
fn due_count() -> u32 {
    return min(counter[2], min(sample_count(), arrayLength(&queue)));
}

// How many samples this dispatch computes, and where the i-th of them is in the list (as
// hcb/gather.wgsl's gather_count and gather_slot, modes 1 and 2 in one).
fn item_count() -> u32 {
    let n = sample_count();
    if (round.round.y == 1u) {
        return due_count() + n - min(counter[1], n);
    }
    return n;
}

fn item_slot(i: u32) -> u32 {
    if (round.round.y == 1u) {
        let due = due_count();
        if (i < due) {
            return queue[i];
        }
        return counter[1] + i - due;
    }
    return i;
}

// The first item of this chunk and how many it takes.
fn chunk() -> vec2<u32> {
    let n = item_count();
    let per = u32(params.creation.y);
    let base = min(round.round.x * per, n);
    return vec2<u32>(base, min(per, n - base));
}

@compute @workgroup_size(64, 1, 1)
fn cs_samples_begin(@builtin(local_invocation_index) li: u32) {
    let c = chunk();
    for (var s = li; s < c.y; s = s + 64u) {
        let smp = list[item_slot(c.x + s)];
        var rec: Record;
        rec.position = vec4<f32>(smp.position.xyz, 0.0);
        rec.normal = vec4<f32>(normalize(smp.normal.xyz), 0.0);
        rec.irradiance = vec4<f32>(0.0, 0.0, 0.0, params.misc.x);
        // the pixel; its depth 1 (R_k's pixel clamps are unused: the HCB splats)
        rec.pixel = vec4<f32>(f32(smp.texel.w & 0xffffu), f32(smp.texel.w >> 16u), 1.0, RECORD_STALE);
        records[s] = rec;
        slots[s] = s | REFRESH;
    }
    if (li == 0u) {
        // Only this chunk's tiles are cleared, lit and reduced (issue #53): a chunk past the
        // set's size costs almost nothing.
        let n_px = u32(params.hemisphere.x);
        let per_row = max(u32(params.hemisphere.y), 1u);
        let rows = (c.y + per_row - 1u) / per_row;
        round_args[0] = 6u;
        round_args[1] = c.y;
        round_args[2] = 0u;
        round_args[3] = 0u;
        round_args[4] = (per_row * n_px + TILE - 1u) / TILE;
        round_args[5] = (rows * n_px + TILE - 1u) / TILE;
        round_args[6] = 1u;
        round_args[7] = 0u;
        round_args[8] = c.y;
        round_args[9] = 1u;
        round_args[10] = 1u;
        round_args[11] = 0u;
        state.count = c.y;
        state.new_base = 0u;
        state.new_count = 0u;
        state.refresh = c.y;
        state.made = state.made + c.y;
        if (round.round.x == 0u) {
            let n = sample_count();
            var cached = 0u;
            if (round.round.y != 0u) {
                cached = counter[1];
            }
            let words = hcb_args(n, item_count(), cached);
            for (var i = 0u; i < 12u; i = i + 1u) {
                args[i] = words[i];
            }
        }
    }
    let draws = arrayLength(&raster_args) / 5u;
    for (var d = li; d < draws; d = d + 64u) {
        raster_args[d * 5u + 1u] = c.y;
    }
}

// With the cache, between its update and the build: the splat's arguments over the cached
// samples (their light from earlier frames), for the splat that tells the build where the
// weights fall short (as hcb/gather.wgsl's cs_args writes them before that splat).
@compute @workgroup_size(1, 1, 1)
fn cs_cached_args() {
    let n = sample_count();
    let words = hcb_args(n, 0u, counter[1]);
    for (var i = 0u; i < 12u; i = i + 1u) {
        args[i] = words[i];
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_samples_store(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = gid.x;
    let c = chunk();
    if (s >= c.y) {
        return;
    }
    let slot = item_slot(c.x + s);
    list[slot].light = vec4<f32>(records[s].irradiance.rgb, 1.0);
    list[slot].dir = records[s].dir;
}
