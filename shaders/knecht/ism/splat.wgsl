// Stage 4, imperfect shadow maps (Knecht 002 §2.6.5, Ritschel et al. 2008): every point of
// the point cloud is splatted into the paraboloid map of one VPL of a bounce (point j → VPL
// first + j mod N, so each ISM sees a different N-th of the cloud; bounce b's VPLs start at
// slot first = b·N, §3.6) as a box of texels whose size falls with the
// distance: a disc of radius r_s (the point's share of the surface area, √(A / (π · points
// per ISM))) at distance d has a radius of r = r_s · size / (2 (1 + cos θ) d) texels of a
// paraboloid map (its texel spans 4 cos²(θ/2) / size radians at angle θ from the normal) and
// is splatted as the square of the same area, side round(√π · r) ≥ 1 (even sides too, so
// that coverage does not jump between point counts), at most 2·k_max + 1. WebGPU draws only
// 1-pixel points, so the splat is a compute kernel; the nearest distance wins by atomicMax
// on the inverted f32 bits (positive floats order like their bits; 0 = empty after a clear).
#import common/bounce.wgsl

struct SplatParams {
    // x: points, y: ISMs (VPLs), z: atlas columns, w: map size
    counts: vec4<u32>,
    // x: eye offset along the VPL normal, y: point radius r_s, z: largest splat half-size
    // (texels), w: splat scale
    geom: vec4<f32>,
    // x: first VPL slot of the bounce, y: first map (tile) of the bounce, z: splat depth
    // (0: the point's distance in every texel, Ritschel et al.'s box; 1: its tangent plane's)
    slots: vec4<u32>,
}

@group(0) @binding(0) var<uniform> sp: SplatParams;
@group(0) @binding(1) var<storage, read> points: array<IsmPoint>;
@group(0) @binding(2) var<storage, read> instances: array<Instance>;
@group(0) @binding(3) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(4) var<storage, read_write> depth: array<atomic<u32>>;
// The IRSM baseline's texel owners (point index + 1, 0 = none); a dummy for the ISMs.
@group(0) @binding(5) var<storage, read_write> owner: array<atomic<u32>>;

// Where point j lands: the box of texels (centre ± k) in map `tile`, and its key.
struct Footprint {
    valid: bool,
    // first texel of the box and its side
    start: vec2<i32>,
    side: i32,
    origin: vec2<u32>,
    key: u32,
    // the point relative to the eye and its normal, in the VPL's frame; its distance and the
    // largest depth change across the splat
    local: vec3<f32>,
    normal: vec3<f32>,
    d: f32,
    reach: f32,
}

fn footprint(j: u32) -> Footprint {
    var f: Footprint;
    f.valid = false;
    if (j >= sp.counts.x || sp.counts.y == 0u) {
        return f;
    }
    let local = j % sp.counts.y;
    let vpl = vpls[sp.slots.x + local];
    if (vpl.position.w < 0.5) {
        return f;
    }
    let pt = points[j];
    let world = (instances[pt.draw].model * vec4<f32>(pt.position, 1.0)).xyz;
    let eye = ism_eye(vpl, sp.geom.x);
    let w = world - eye;
    let d = length(w);
    if (d <= 0.0) {
        return f;
    }
    let tbn = vpl_basis(vpl.normal.xyz);
    let q = vec3<f32>(dot(w, tbn[0]), dot(w, tbn[1]), dot(w, tbn[2])) / d;
    if (q.z < 0.0) {
        return f;
    }
    let size = sp.counts.w;
    let c = paraboloid_project(q) * f32(size);
    let r = sp.geom.w * sp.geom.y * f32(size) / (2.0 * (1.0 + q.z) * d);
    f.valid = true;
    // The square of the disc's area, side √π·r rounded (even sides too), at most 2k + 1.
    f.side = clamp(i32(round(1.7724539 * r)), 1, 2 * i32(sp.geom.z) + 1);
    f.origin = vpl_tile_origin(sp.slots.y + local, sp.counts.z, size);
    f.key = ~bitcast<u32>(d);
    let nw = normalize((instances[pt.draw].normal_matrix * vec4<f32>(pt.normal, 0.0)).xyz);
    f.local = q * d;
    f.normal = vec3<f32>(dot(nw, tbn[0]), dot(nw, tbn[1]), dot(nw, tbn[2]));
    f.d = d;
    f.reach = 2.0 * sp.geom.w * sp.geom.y;
    f.start = vec2<i32>(ceil(c - vec2<f32>(0.5 * f32(f.side) + 0.5)));
    return f;
}

// The key of texel t (map-local) of a splat: the point's distance, or with tangent-plane
// splats the distance along the texel's ray to the point's tangent plane, kept within
// ± reach of the point's (a ray that misses the plane in front takes the far end).
// CPU twin: cpu::knecht::splat_distance.
fn texel_key(f: Footprint, t: vec2<i32>, size: i32) -> u32 {
    if (sp.slots.z == 0u) {
        return f.key;
    }
    let uv = (vec2<f32>(t) + 0.5) / f32(size);
    let p = vec2<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let r2 = dot(p, p);
    let z = (1.0 - r2) / (1.0 + r2);
    let ray = vec3<f32>(p * (1.0 + z), z);
    let den = dot(ray, f.normal);
    var s = f.d + f.reach;
    if (abs(den) > 1e-6) {
        let hit = dot(f.local, f.normal) / den;
        if (hit > 0.0) {
            s = hit;
        }
    }
    return ~bitcast<u32>(clamp(s, max(f.d - f.reach, 1e-6), f.d + f.reach));
}

// Visits the texels of point j's box: the splat keeps the nearest distance; the owner pass
// (after the splat) marks the texels whose nearest distance is j's.
fn cover(j: u32, owner_pass: bool) {
    let f = footprint(j);
    if (!f.valid) {
        return;
    }
    let size = i32(sp.counts.w);
    let width = sp.counts.z * sp.counts.w;
    for (var dy = 0; dy < f.side; dy = dy + 1) {
        for (var dx = 0; dx < f.side; dx = dx + 1) {
            let t = f.start + vec2<i32>(dx, dy);
            if (t.x < 0 || t.y < 0 || t.x >= size || t.y >= size) {
                continue;
            }
            let a = f.origin + vec2<u32>(t);
            let i = a.y * width + a.x;
            let key = texel_key(f, t, size);
            if (!owner_pass) {
                atomicMax(&depth[i], key);
            } else if (atomicLoad(&depth[i]) == key) {
                atomicMax(&owner[i], j + 1u);
            }
        }
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_splat(@builtin(global_invocation_id) gid: vec3<u32>) {
    cover(gid.x + gid.y * 65535u * 64u, false);
}

// IRSM baseline (Ritschel et al. 2008, Knecht 002 §3.6): after cs_splat, each texel learns
// which point won it (the nearest; the largest index among equal distances).
@compute @workgroup_size(64, 1, 1)
fn cs_owner(@builtin(global_invocation_id) gid: vec3<u32>) {
    cover(gid.x + gid.y * 65535u * 64u, true);
}
