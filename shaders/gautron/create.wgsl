// Record creation where the coverage is insufficient (Gautron et al. 003, "Algorithm": the
// text scans the image on the CPU; here every round runs on the GPU): `cs_candidates` finds,
// per creation tile, the under-covered pixel nearest the tile's centre (covered: the splatted
// Σ w_k ≥ 1/a, i.e. some record passes Ward's test); `cs_compact` lists them in tile order up
// to the round's budget and the capacity (one workgroup: the same set, in the same order,
// whatever order the GPU ran the tiles in); `cs_cameras` sets up each new record's
// hemisphere camera. Twin: cpu::gautron::candidates.
#import gautron/common.wgsl
#import common/camera.wgsl

const NONE: u32 = 0xffffffffu;


struct RoundParams {
    // x: round index, yzw unused
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
    let tile = u32(params.creation.x);
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

// The inclusive prefix sum of the 256 threads' flags into `scan` (Hillis–Steele; every
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

// One workgroup: the candidates in tile order (a prefix sum per chunk of 256 tiles) up to
// the budget and the capacity; then the counters and the indirect draws of the round.
@compute @workgroup_size(256, 1, 1)
fn cs_compact(@builtin(local_invocation_index) li: u32) {
    let tiles = arrayLength(&candidates);
    let budget = u32(params.creation.y);
    let capacity = u32(params.creation.z);
    let base = state.count;
    let room = min(budget, capacity - min(base, capacity));
    if (li == 0u) {
        taken = 0u;
    }
    workgroupBarrier();
    for (var start = 0u; start < tiles; start = start + 256u) {
        let t = start + li;
        var flag = 0u;
        if (t < tiles && candidates[t] != NONE) {
            flag = 1u;
        }
        scan_flags(li, flag);
        let before = taken;
        let slot = before + scan[li] - flag;
        if (flag == 1u && slot < room) {
            slots[slot] = candidates[t];
        }
        let total = scan[255];
        workgroupBarrier();
        if (li == 0u) {
            taken = before + total;
        }
        workgroupBarrier();
    }
    let new_count = min(taken, room);
    if (li == 0u) {
        state.new_base = base;
        state.new_count = new_count;
        state.count = base + new_count;
        state.made = state.made + new_count;
        state.candidates = taken;
        splat_args[0] = 6u;
        splat_args[1] = new_count;
        splat_args[2] = 0u;
        splat_args[3] = base;
    }
    let draws = arrayLength(&raster_args) / 5u;
    for (var d = li; d < draws; d = d + 256u) {
        raster_args[d * 5u + 1u] = new_count;
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
    if (s >= state.new_count) {
        cam.view_proj = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
        cameras[s] = cam;
        viewers[s] = vec4<f32>(0.0);
        return;
    }
    let width = textureDimensions(g_normal).x;
    let px = vec2<i32>(i32(slots[s] % width), i32(slots[s] / width));
    let pos = textureLoad(g_position, px, 0);
    let n = normalize(textureLoad(g_normal, px, 0).xyz);
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
    let index = state.new_base + s;
    cam.view_proj = proj * view;
    cam.position = vec4<f32>(p, 1.0);
    cam.t = vec4<f32>(t, 0.0);
    cam.b = vec4<f32>(b, 0.0);
    cam.n = vec4<f32>(n, f32(index));
    cameras[s] = cam;
    viewers[s] = vec4<f32>(p, 1.0);
    var rec: Record;
    rec.position = vec4<f32>(p, 0.0);
    rec.normal = vec4<f32>(n, 0.0);
    rec.irradiance = vec4<f32>(0.0, 0.0, 0.0, params.misc.x);
    rec.pixel = vec4<f32>(vec2<f32>(px), pos.w, 0.0);
    records[index] = rec;
    textureStore(candidate_mask, px, vec4<f32>(f32(round.round.x + 1u)));
}

// Once per frame, before the first splat: every cached record is drawn, the frame's count of
// made records starts at 0.
@compute @workgroup_size(1, 1, 1)
fn cs_begin() {
    state.made = 0u;
    state.new_base = 0u;
    state.new_count = 0u;
    splat_args[0] = 6u;
    splat_args[1] = state.count;
    splat_args[2] = 0u;
    splat_args[3] = 0u;
}

// The reuse policy "drop off-screen": the cache keeps, in order, only the records whose
// position is inside the view frustum (one workgroup; a record moves only to a lower index,
// which its chunk has already read).
@compute @workgroup_size(256, 1, 1)
fn cs_cull(@builtin(local_invocation_index) li: u32) {
    let count = state.count;
    if (li == 0u) {
        taken = 0u;
    }
    workgroupBarrier();
    for (var start = 0u; start < count; start = start + 256u) {
        let i = start + li;
        var flag = 0u;
        var rec: Record;
        if (i < count) {
            rec = records[i];
            let clip = camera.view_proj * vec4<f32>(rec.position.xyz, 1.0);
            let inside = clip.w > 0.0 && all(abs(clip.xy) <= vec2<f32>(clip.w)) && clip.z >= 0.0 && clip.z <= clip.w;
            flag = select(0u, 1u, inside);
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
    }
}
