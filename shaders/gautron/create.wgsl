// Record creation where the coverage is insufficient (Gautron et al. 003, "Algorithm": the
// text scans the image on the CPU; here every round runs on the GPU): `cs_candidates` finds,
// per creation tile, the under-covered pixel nearest the tile's centre (covered: the splatted
// Σ w_k ≥ 1/a, i.e. some record passes Ward's test); `cs_count`, `cs_compact` and
// `cs_scatter` list them in tile order up to the round's budget and the capacity (the same
// set, in the same order, whatever order the GPU ran the tiles in: each chunk of 256 tiles
// counts its candidates, one workgroup turns the counts into the chunks' offsets, and each
// chunk writes its candidates from its offset; issue #38: one workgroup used to scan every
// tile in turn), `cs_compact` then fills the rest of the budget with stale records to
// compute again (round robin from a cursor); `cs_cameras` sets up each slot's
// hemisphere camera. `cs_maintain` runs once per frame before the first splat: the reuse
// policy and the invalidation by moved objects and changed lights. Twin:
// cpu::gautron::candidates.
#import gautron/common.wgsl
#import common/camera.wgsl

const NONE: u32 = 0xffffffffu;
// a slot that computes stale record (slot & ~REFRESH) again instead of making one
const REFRESH: u32 = 0x80000000u;

// What changed since the last frame (stage.rs fills it).
struct MaintainParams {
    // x: drop the records outside the view frustum, y: moved objects, z: every record is
    // invalid (a light changed), w: invalid records are refreshed (1) or dropped (0)
    flags: vec4<u32>,
    // the moved draws as 128 bits (bit draw mod 128), as `Record.seen`
    mask: vec4<u32>,
}

// A moved scene draw: its world bounds last frame and now.
struct MovedObject {
    old_min: vec4<f32>,
    old_max: vec4<f32>,
    new_min: vec4<f32>,
    new_max: vec4<f32>,
}


struct RoundParams {
    // x: round index, y: creation tiles (the candidates; then each chunk of 256 tiles' count
    // and offset follow in `candidates`), z: the round's tile side in pixels, w unused
    round: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: GautronParams;
@group(0) @binding(1) var<uniform> round: RoundParams;
@group(0) @binding(2) var<uniform> camera: Camera;
@group(0) @binding(3) var<storage, read_write> state: CacheState;
@group(0) @binding(4) var<storage, read_write> candidates: array<u32>;
@group(0) @binding(5) var<storage, read_write> slots: array<u32>;
@group(0) @binding(6) var<storage, read_write> records: array<Record>;
@group(0) @binding(7) var<storage, read_write> cameras: array<HemisphereCamera>;
@group(0) @binding(8) var<storage, read_write> viewers: array<vec4<f32>>;
// the hemisphere raster's indirect draws: 5 words per scene draw, word 1 the instance count
@group(0) @binding(9) var<storage, read_write> raster_args: array<u32>;
// the splat's indirect draw: vertex count, instance count, first vertex, first instance
@group(0) @binding(10) var<storage, read_write> splat_args: array<u32, 4>;
@group(0) @binding(11) var<uniform> maintain: MaintainParams;
@group(0) @binding(12) var<storage, read> moved: array<MovedObject>;
@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var g_normal: texture_2d<f32>;
@group(1) @binding(2) var accum: texture_2d<f32>;
@group(1) @binding(3) var candidate_mask: texture_storage_2d<r32float, write>;

var<workgroup> best: atomic<u32>;

// One workgroup per creation tile: the key (distance² to the tile's centre, then the index
// in the tile) of every under-covered pixel, the smallest wins.
@compute @workgroup_size(64, 1, 1)
fn cs_candidates(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(num_workgroups) nwg: vec3<u32>) {
    if (li == 0u) {
        atomicStore(&best, NONE);
    }
    workgroupBarrier();
    let size = textureDimensions(g_normal);
    let tile = round.round.z;
    let origin = wg.xy * tile;
    let centre = vec2<f32>(f32(tile) - 1.0) * 0.5;
    let threshold = 1.0 / params.weight.x;
    for (var k = li; k < tile * tile; k = k + 64u) {
        let local = vec2<u32>(k % tile, k / tile);
        let p = origin + local;
        if (p.x >= size.x || p.y >= size.y) {
            continue;
        }
        let valid = textureLoad(g_normal, vec2<i32>(p), 0).w > 0.5;
        let covered = textureLoad(accum, vec2<i32>(p), 0).a >= threshold;
        if (round.round.x == 0u) {
            textureStore(candidate_mask, vec2<i32>(p), vec4<f32>(0.0));
        }
        if (!valid || covered) {
            continue;
        }
        let d = vec2<f32>(local) - centre;
        // distance² in quarter pixels² (exact for the half-integer offsets), then the index
        let key = (u32(dot(d, d) * 4.0 + 0.5) << 12u) | k;
        atomicMin(&best, key);
    }
    workgroupBarrier();
    if (li == 0u) {
        let key = atomicLoad(&best);
        let t = wg.y * nwg.x + wg.x;
        if (key == NONE) {
            candidates[t] = NONE;
        } else {
            let k = key & 0xfffu;
            let p = origin + vec2<u32>(k % tile, k / tile);
            candidates[t] = p.y * size.x + p.x;
        }
    }
}

var<workgroup> scan: array<u32, 256>;
var<workgroup> taken: u32;
var<workgroup> furthest: atomic<u32>;
var<workgroup> stale_left: atomic<u32>;

// The inclusive prefix sum of the 256 threads' values into `scan` (Hillis–Steele; every
// thread of the workgroup calls it).
fn scan_flags(li: u32, flag: u32) {
    scan[li] = flag;
    workgroupBarrier();
    for (var off = 1u; off < 256u; off = off * 2u) {
        var v = 0u;
        if (li >= off) {
            v = scan[li - off];
        }
        workgroupBarrier();
        scan[li] = scan[li] + v;
        workgroupBarrier();
    }
}

// The candidates of the creation tiles, then per chunk of 256 tiles its count, then its offset.
fn tile_count() -> u32 {
    return round.round.y;
}

fn chunk_count() -> u32 {
    return (tile_count() + 255u) / 256u;
}

var<workgroup> chunk_total: atomic<u32>;

// One workgroup per chunk of 256 tiles: how many of them have a candidate.
@compute @workgroup_size(256, 1, 1)
fn cs_count(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if (li == 0u) {
        atomicStore(&chunk_total, 0u);
    }
    workgroupBarrier();
    let t = wg.x * 256u + li;
    if (t < tile_count() && candidates[t] != NONE) {
        atomicAdd(&chunk_total, 1u);
    }
    workgroupBarrier();
    if (li == 0u) {
        candidates[tile_count() + wg.x] = atomicLoad(&chunk_total);
    }
}

// One workgroup per chunk: its candidates, in tile order, into the slots from the chunk's
// offset, up to the round's new records (`state.new_count`, set by cs_compact).
@compute @workgroup_size(256, 1, 1)
fn cs_scatter(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let t = wg.x * 256u + li;
    var flag = 0u;
    if (t < tile_count() && candidates[t] != NONE) {
        flag = 1u;
    }
    scan_flags(li, flag);
    let slot = candidates[tile_count() + chunk_count() + wg.x] + scan[li] - flag;
    if (flag == 1u && slot < state.new_count) {
        slots[slot] = candidates[t];
    }
}

// One workgroup: the chunks' offsets (a prefix sum of their counts) and the round's new
// records up to the budget and the capacity (cs_scatter writes them); then the stale records
// to compute again, the counters and the indirect draws of the round.
@compute @workgroup_size(256, 1, 1)
fn cs_compact(@builtin(local_invocation_index) li: u32) {
    let chunks = chunk_count();
    let budget = u32(params.creation.y);
    let capacity = u32(params.creation.z);
    let base = state.count;
    let room = min(budget, capacity - min(base, capacity));
    if (li == 0u) {
        taken = 0u;
    }
    workgroupBarrier();
    for (var start = 0u; start < chunks; start = start + 256u) {
        let c = start + li;
        var n = 0u;
        if (c < chunks) {
            n = candidates[tile_count() + c];
        }
        scan_flags(li, n);
        let before = taken;
        if (c < chunks) {
            candidates[tile_count() + chunks + c] = before + scan[li] - n;
        }
        let total = scan[255];
        workgroupBarrier();
        if (li == 0u) {
            taken = before + total;
        }
        workgroupBarrier();
    }
    let new_count = min(taken, room);
    let candidates_found = taken;
    workgroupBarrier();

    // The rest of the budget computes stale records again, in cache order from the cursor
    // (round robin, so that a scene that keeps moving refreshes every record in turn).
    let want = budget - new_count;
    let stale = state.stale;
    let cursor = state.cursor % max(base, 1u);
    if (li == 0u) {
        taken = 0u;
        atomicStore(&furthest, 0u);
    }
    workgroupBarrier();
    if (stale > 0u && want > 0u) {
        for (var start = 0u; start < base; start = start + 256u) {
            let t = start + li;
            var flag = 0u;
            var index = 0u;
            if (t < base) {
                index = (cursor + t) % base;
                if (records[index].pixel.w == RECORD_STALE) {
                    flag = 1u;
                }
            }
            scan_flags(li, flag);
            let before = taken;
            let slot = before + scan[li] - flag;
            if (flag == 1u && slot < want) {
                slots[new_count + slot] = index | REFRESH;
                records[index].pixel.w = 0.0;
                atomicMax(&furthest, t + 1u);
            }
            let total = scan[255];
            workgroupBarrier();
            if (li == 0u) {
                taken = before + total;
            }
            if (workgroupUniformLoad(&taken) >= want) {
                break;
            }
        }
    }
    workgroupBarrier();
    let refresh = min(taken, want);
    if (li == 0u) {
        state.new_base = base;
        state.new_count = new_count;
        state.count = base + new_count;
        state.made = state.made + new_count;
        state.candidates = candidates_found;
        state.refresh = refresh;
        state.refreshed = state.refreshed + refresh;
        state.stale = stale - min(refresh, stale);
        if (refresh > 0u) {
            state.cursor = (cursor + atomicLoad(&furthest)) % max(base, 1u);
        }
        splat_args[0] = 6u;
        splat_args[1] = new_count;
        splat_args[2] = 0u;
        splat_args[3] = base;
    }
    let draws = arrayLength(&raster_args) / 5u;
    for (var d = li; d < draws; d = d + 256u) {
        raster_args[d * 5u + 1u] = new_count + refresh;
    }
}

// One thread per slot: the new record's position and normal from the G-buffer, its
// hemisphere camera (looking along n_k, up b, aperture `params.hemisphere.z` = tan of the
// half angle) and its tile in the atlas; unused slots get a zero matrix (nothing rasterised).
@compute @workgroup_size(64, 1, 1)
fn cs_cameras(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = gid.x;
    let budget = u32(params.creation.y);
    if (s >= budget) {
        return;
    }
    let per_row = u32(params.hemisphere.y);
    let rows = (budget + per_row - 1u) / per_row;
    let scale = vec2<f32>(1.0 / f32(per_row), 1.0 / f32(rows));
    let cell = vec2<f32>(f32(s % per_row), f32(s / per_row));
    var cam: HemisphereCamera;
    cam.tile = vec4<f32>(-1.0 + (2.0 * cell.x + 1.0) * scale.x, 1.0 - (2.0 * cell.y + 1.0) * scale.y, scale);
    if (s >= state.new_count + state.refresh) {
        cam.view_proj = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        cameras[s] = cam;
        viewers[s] = vec4<f32>(0.0);
        return;
    }
    let refresh = s >= state.new_count;
    let width = textureDimensions(g_normal).x;
    var px = vec2<i32>(i32(slots[s] % width), i32(slots[s] / width));
    var index = state.new_base + s;
    var pos: vec4<f32>;
    var n: vec3<f32>;
    var rec: Record;
    if (refresh) {
        // a stale record: the same place, computed again
        index = slots[s] & ~REFRESH;
        rec = records[index];
        pos = vec4<f32>(rec.position.xyz, rec.pixel.z);
        n = rec.normal.xyz;
    } else {
        pos = textureLoad(g_position, px, 0);
        n = normalize(textureLoad(g_normal, px, 0).xyz);
    }
    let f = tangent_frame(n);
    let t = f[0];
    let b = f[1];
    let p = pos.xyz;
    // view: x = t, y = b, looking down −z = n; a right-handed perspective with depth in [0, 1]
    let view = transpose(mat4x4<f32>(
        vec4<f32>(t, -dot(t, p)),
        vec4<f32>(b, -dot(b, p)),
        vec4<f32>(-n, dot(n, p)),
        vec4<f32>(0.0, 0.0, 0.0, 1.0),
    ));
    let inv_tan = 1.0 / params.hemisphere.z;
    let near = params.hemisphere.w;
    let far = params.creation.w;
    let proj = mat4x4<f32>(
        vec4<f32>(inv_tan, 0.0, 0.0, 0.0),
        vec4<f32>(0.0, inv_tan, 0.0, 0.0),
        vec4<f32>(0.0, 0.0, far / (near - far), -1.0),
        vec4<f32>(0.0, 0.0, near * far / (near - far), 0.0),
    );
    cam.view_proj = proj * view;
    cam.position = vec4<f32>(p, 1.0);
    cam.t = vec4<f32>(t, 0.0);
    cam.b = vec4<f32>(b, 0.0);
    cam.n = vec4<f32>(n, f32(index));
    cameras[s] = cam;
    viewers[s] = vec4<f32>(p, 1.0);
    if (refresh) {
        // E_k stays until the reduction overwrites it; the frame says when it was computed
        records[index].irradiance.w = params.misc.x;
        return;
    }
    rec.position = vec4<f32>(p, 0.0);
    rec.normal = vec4<f32>(n, 0.0);
    rec.irradiance = vec4<f32>(0.0, 0.0, 0.0, params.misc.x);
    rec.pixel = vec4<f32>(vec2<f32>(px), pos.w, 0.0);
    rec.seen = vec4<u32>(0u);
    records[index] = rec;
    textureStore(candidate_mask, px, vec4<f32>(f32(round.round.x + 1u)));
}

// Once per frame, before the first splat: every cached record is drawn, the frame's count of
// made records starts at 0.
@compute @workgroup_size(1, 1, 1)
fn cs_begin() {
    state.made = 0u;
    state.refreshed = 0u;
    state.refresh = 0u;
    state.new_base = 0u;
    state.new_count = 0u;
    splat_args[0] = 6u;
    splat_args[1] = state.count;
    splat_args[2] = 0u;
    splat_args[3] = 0u;
}

fn inside(p: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>, margin: f32) -> bool {
    return all(p >= lo - vec3<f32>(margin)) && all(p <= hi + vec3<f32>(margin));
}

// Whether the box [lo, hi] reaches into the half-space in front of the record (its
// hemisphere could see it: a conservative test of the camera's view).
fn in_front(rec: Record, lo: vec3<f32>, hi: vec3<f32>) -> bool {
    let c = (lo + hi) * 0.5;
    let e = (hi - lo) * 0.5;
    let n = rec.normal.xyz;
    return dot(c - rec.position.xyz, n) + dot(e, abs(n)) > 0.0;
}

// What the record cache does with record `rec` this frame: 0 drop, 1 keep, 2 keep stale
// (stage 7): off-screen records go under the "drop off-screen" policy; a record lying on a
// moved object (inside its old or new bounds) goes; a record whose hemisphere saw a moved
// object (its `seen` bits) or could see it now (the new bounds in front of it), and every
// record when a light changed, is invalid: dropped or kept stale by `gautron.invalidation`.
fn fate(rec: Record) -> u32 {
    if (maintain.flags.x == 1u) {
        let clip = camera.view_proj * vec4<f32>(rec.position.xyz, 1.0);
        let visible = clip.w > 0.0 && all(abs(clip.xy) <= vec2<f32>(clip.w)) && clip.z >= 0.0 && clip.z <= clip.w;
        if (!visible) {
            return 0u;
        }
    }
    var invalid = maintain.flags.z == 1u || any((rec.seen & maintain.mask) != vec4<u32>(0u));
    let margin = params.hemisphere.w * 10.0;
    for (var m = 0u; m < maintain.flags.y; m = m + 1u) {
        let o = moved[m];
        let p = rec.position.xyz;
        if (inside(p, o.old_min.xyz, o.old_max.xyz, margin) || inside(p, o.new_min.xyz, o.new_max.xyz, margin)) {
            return 0u;
        }
        invalid = invalid || in_front(rec, o.new_min.xyz, o.new_max.xyz);
    }
    if (!invalid) {
        return select(1u, 2u, rec.pixel.w == RECORD_STALE);
    }
    return select(0u, 2u, maintain.flags.w == 1u);
}

// Once per frame before the first splat, when something changed or the policy drops
// off-screen records: the cache keeps, in order, the records `fate` keeps (one workgroup; a
// record moves only to a lower index, which its chunk has already read) and counts the stale.
@compute @workgroup_size(256, 1, 1)
fn cs_maintain(@builtin(local_invocation_index) li: u32) {
    let count = state.count;
    if (li == 0u) {
        taken = 0u;
        atomicStore(&stale_left, 0u);
    }
    workgroupBarrier();
    for (var start = 0u; start < count; start = start + 256u) {
        let i = start + li;
        var flag = 0u;
        var rec: Record;
        if (i < count) {
            rec = records[i];
            let f = fate(rec);
            if (f == 2u) {
                rec.pixel.w = RECORD_STALE;
                atomicAdd(&stale_left, 1u);
            }
            flag = select(0u, 1u, f > 0u);
        }
        scan_flags(li, flag);
        let before = taken;
        if (flag == 1u) {
            records[before + scan[li] - 1u] = rec;
        }
        let total = scan[255];
        workgroupBarrier();
        if (li == 0u) {
            taken = before + total;
        }
        workgroupBarrier();
    }
    if (li == 0u) {
        state.count = taken;
        state.stale = atomicLoad(&stale_left);
        state.cursor = state.cursor % max(taken, 1u);
    }
}

// R_k's lower clamps (scene units, then pixels at the record's depth), as the reduction
// applies them.
fn lower_clamps(r: f32, rec: Record) -> f32 {
    return max(max(r, params.clamps.x), params.clamps.z / record_px_per_unit(params, rec));
}

// Neighbour clamping (Křivánek et al. 2006, "Making radiance and irradiance caching
// practical"; not in 003): the harmonic mean distance obeys the triangle inequality, so a
// record's R_k is clamped to R_j + ‖P_k − P_j‖ for every neighbour j, here the records whose
// influence spheres (a·R) overlap. The round's fresh records are its new ones and the stale
// ones it computed again. First the other cached records are clamped by the fresh ones (one
// thread per record), then the fresh ones by all (one thread per slot, the result parked in
// its camera's t.w), then the parked values are stored: every pass reads the fresh records'
// unclamped R, so the result does not depend on the records' order. Twin:
// cpu::gautron::neighbour_clamp.

// The record a slot computes this round (a new one, or a stale one again).
fn slot_record(s: u32) -> u32 {
    if (s < state.new_count) {
        return state.new_base + s;
    }
    return slots[s] & ~REFRESH;
}

@compute @workgroup_size(64, 1, 1)
fn cs_clamp_cached(@builtin(global_invocation_id) gid: vec3<u32>) {
    let j = gid.x;
    let base = state.new_base;
    let fresh = state.new_count;
    let slots_used = fresh + state.refresh;
    if (j >= base) {
        return;
    }
    for (var s = fresh; s < slots_used; s = s + 1u) {
        if (slot_record(s) == j) {
            // computed again this round: clamped with the new ones
            return;
        }
    }
    let a = params.weight.x;
    let rj = records[j];
    var r = rj.position.w;
    for (var s = 0u; s < slots_used; s = s + 1u) {
        let rk = records[slot_record(s)];
        let d = distance(rk.position.xyz, rj.position.xyz);
        if (d <= a * (rk.position.w + rj.position.w)) {
            r = min(r, rk.position.w + d);
        }
    }
    if (r < rj.position.w) {
        records[j].position.w = lower_clamps(r, rj);
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_clamp_new(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = gid.x;
    if (s >= state.new_count + state.refresh) {
        return;
    }
    let a = params.weight.x;
    let k = slot_record(s);
    let rk = records[k];
    let own = rk.position.w;
    var r = own;
    for (var j = 0u; j < state.new_base + state.new_count; j = j + 1u) {
        if (j == k) {
            continue;
        }
        let rj = records[j];
        let d = distance(rk.position.xyz, rj.position.xyz);
        if (d <= a * (own + rj.position.w)) {
            r = min(r, rj.position.w + d);
        }
    }
    if (r < own) {
        r = lower_clamps(r, rk);
    }
    cameras[s].t.w = r;
}

@compute @workgroup_size(64, 1, 1)
fn cs_clamp_store(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = gid.x;
    if (s >= state.new_count + state.refresh) {
        return;
    }
    records[slot_record(s)].position.w = cameras[s].t.w;
}
