// DDGI's probe update (Majercik et al. 2019 §3.3, Eq. 3–4; 2021 §5.2–5.3; CPU twins
// `cpu::ddgi::{update_irradiance, update_distance}`, `Atlas::fill_borders`, `classify` and
// `relocate`): each interior texel of a probe's tiles blends the probe's rays of this frame
// about its direction into its old value with the hysteresis; then the borders copy the
// interior as the octahedron folds; then each probe is classified and relocated from the same
// rays. `passes::ddgi::blend`.

#import ddgi/probes.wgsl

@group(0) @binding(0) var<storage, read> ddgi: DdgiUpdate;
// Per probe and ray: radiance (rgb), distance (w; negative: a back face at −w; ≥ 1e30: none).
@group(0) @binding(1) var<storage, read> ddgi_rays: array<vec4<f32>>;
// The atlases, row-major, irradiance / π (rgb) and distance moments (mean, mean²).
@group(0) @binding(2) var<storage, read_write> ddgi_irradiance: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> ddgi_distance: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> ddgi_grid: DdgiGrid;
// Per probe: relocation offset (xyz), state (w: 0 active, 1 inactive).
@group(0) @binding(5) var<storage, read_write> ddgi_probes: array<vec4<f32>>;

// The probe and tile texel of atlas texel `p` (tiles of interior + 2, `columns` a row);
// probe ≥ the probe count: none.
fn ddgi_tile_of(p: vec2<u32>, interior: u32, columns: u32) -> vec3<u32> {
    let t = interior + 2u;
    return vec3<u32>((p.y / t) * columns + p.x / t, p.x % t, p.y % t);
}

// The interior texel of atlas texel `p`: (probe, i, j, 1), or w = 0 for a border texel, a
// texel past the atlas's width or of a tile past the probes.
fn ddgi_interior(p: vec2<u32>, n: u32, columns: u32) -> vec4<u32> {
    let c = ddgi_tile_of(p, n, columns);
    let inside = p.x < columns * (n + 2u) && c.x < ddgi.counts.x && c.y >= 1u && c.z >= 1u && c.y <= n && c.z <= n;
    return vec4<u32>(c.x, c.y - 1u, c.z - 1u, select(0u, 1u, inside));
}

fn ddgi_ray_dir(r: u32) -> vec3<f32> {
    return normalize(ddgi.rotation * ddgi_fibonacci(r, ddgi.counts.y));
}

// Whether probe `p` traced only an inactive probe's few rays this frame (its state is still
// the one the trace read; the state kernel runs last) with `ddgi.skip_inactive`: its tiles
// are not blended, since it shades nothing (2021 §5.2).
fn ddgi_skipped(p: u32) -> bool {
    let skip = DDGI_CLASSIFY | DDGI_SKIP_INACTIVE;
    return (ddgi_grid.counts.w & skip) == skip && ddgi_probes[p].w == DDGI_INACTIVE;
}

// The frame's ray directions, a chunk at a time: every invocation of a workgroup reads the
// same rays, so each direction is computed once per workgroup rather than once per texel.
var<workgroup> ddgi_dirs: array<vec3<f32>, 64>;

// Loads rays `base`.. `base + 63` of the frame's lattice into `ddgi_dirs` (`lane`: the
// invocation's index in its workgroup) and returns how many of them exist.
fn ddgi_load_dirs(base: u32, lane: u32) -> u32 {
    workgroupBarrier();
    if (base + lane < ddgi.counts.y) {
        ddgi_dirs[lane] = ddgi_ray_dir(base + lane);
    }
    workgroupBarrier();
    return min(64u, ddgi.counts.y - base);
}

@compute @workgroup_size(8, 8)
fn cs_irradiance(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let n = ddgi.counts.z;
    let width = ddgi.tiles.x * (n + 2u);
    let c = ddgi_interior(id.xy, n, ddgi.tiles.x);
    // Every invocation takes part in loading the directions (barriers in uniform control
    // flow); a border texel, one past the atlas or one of a skipped probe writes nothing.
    let updated = c.w != 0u && !ddgi_skipped(c.x);
    let d = ddgi_texel_direction(c.y, c.z, n);
    var sum = vec3<f32>(0.0);
    var w = 0.0;
    for (var base = 0u; base < ddgi.counts.y; base = base + 64u) {
        let m = ddgi_load_dirs(base, lane);
        if (updated) {
            for (var k = 0u; k < m; k = k + 1u) {
                let c_k = max(dot(d, ddgi_dirs[k]), 0.0);
                if (c_k > 0.0) {
                    let ray = ddgi_rays[c.x * ddgi.counts.y + base + k];
                    // Back faces carry no light (they are inside geometry, 2021 §5.2).
                    sum = sum + select(ray.rgb, vec3<f32>(0.0), ray.w < 0.0) * c_k;
                    w = w + c_k;
                }
            }
        }
    }
    let i = id.y * width + id.x;
    if (updated && w > 0.0) {
        var v = sum / w;
        if (ddgi.tiles.z != 0u) {
            v = mix(v, ddgi_irradiance[i].rgb, clamp(ddgi.blend.x, 0.0, 1.0));
        }
        ddgi_irradiance[i] = vec4<f32>(v, 1.0);
    }
}

@compute @workgroup_size(8, 8)
fn cs_distance(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let n = ddgi.counts.w;
    let width = ddgi.tiles.y * (n + 2u);
    let c = ddgi_interior(id.xy, n, ddgi.tiles.y);
    let updated = c.w != 0u && !ddgi_skipped(c.x);
    let d = ddgi_texel_direction(c.y, c.z, n);
    var sum = vec2<f32>(0.0);
    var w = 0.0;
    for (var base = 0u; base < ddgi.counts.y; base = base + 64u) {
        let m = ddgi_load_dirs(base, lane);
        if (updated) {
            for (var k = 0u; k < m; k = k + 1u) {
                let cosine = dot(d, ddgi_dirs[k]);
                if (cosine > 0.0) {
                    let weight = pow(cosine, ddgi.blend.y);
                    let ray = ddgi_rays[c.x * ddgi.counts.y + base + k];
                    var t = min(abs(ray.w), ddgi.blend.z);
                    // A back face counts a fifth of its distance (2021 §5.3).
                    if (ray.w < 0.0) {
                        t = t * 0.2;
                    }
                    sum = sum + vec2<f32>(t, t * t) * weight;
                    w = w + weight;
                }
            }
        }
    }
    let i = id.y * width + id.x;
    if (updated && w > 0.0) {
        var v = sum / w;
        if (ddgi.tiles.z != 0u) {
            v = mix(v, ddgi_distance[i].xy, clamp(ddgi.blend.x, 0.0, 1.0));
        }
        ddgi_distance[i] = vec4<f32>(v, 0.0, 1.0);
    }
}

// The interior texel a border texel (tx, ty) of a tile of `n` copies (`Atlas::fill_borders`);
// (0, 0) for an interior texel.
fn ddgi_border_source(tx: u32, ty: u32, n: u32) -> vec2<u32> {
    let last = n + 1u;
    let x_edge = tx == 0u || tx == last;
    let y_edge = ty == 0u || ty == last;
    if (x_edge && y_edge) {
        return vec2<u32>(select(n, 1u, tx == last), select(n, 1u, ty == last));
    }
    if (y_edge) {
        return vec2<u32>(n + 1u - tx, select(1u, n, ty == last));
    }
    if (x_edge) {
        return vec2<u32>(select(1u, n, tx == last), n + 1u - ty);
    }
    return vec2<u32>(0u);
}

// The atlas index a border texel `p` copies to and the interior index it copies from
// (x = y: `p` is no border texel of a probe's tile).
fn ddgi_border_copy(p: vec2<u32>, n: u32, columns: u32) -> vec2<u32> {
    let c = ddgi_tile_of(p, n, columns);
    let width = columns * (n + 2u);
    let s = ddgi_border_source(c.y, c.z, n);
    if (p.x >= width || c.x >= ddgi.counts.x || s.x == 0u) {
        return vec2<u32>(0u);
    }
    let src = ddgi_texel(c.x, s.x, s.y, n, columns);
    return vec2<u32>(p.y * width + p.x, src.y * width + src.x);
}

// Both atlases' borders, dispatched over the larger (the distance atlas, whose tiles are the
// larger, is at least as wide and as tall for the same probes).
@compute @workgroup_size(8, 8)
fn cs_borders(@builtin(global_invocation_id) id: vec3<u32>) {
    let a = ddgi_border_copy(id.xy, ddgi.counts.z, ddgi.tiles.x);
    if (a.x != a.y) {
        ddgi_irradiance[a.x] = ddgi_irradiance[a.y];
    }
    let b = ddgi_border_copy(id.xy, ddgi.counts.w, ddgi.tiles.y);
    if (b.x != b.y) {
        ddgi_distance[b.x] = ddgi_distance[b.y];
    }
}

// A probe's state and place from its rays (2021 §5.2–5.3; `cpu::ddgi::classify` and
// `relocate`): inside geometry when more than the back-face share of its rays meet back faces;
// idle when no front face lies within its cell; moved through the nearest back face when
// inside, away from a front face closer than the least distance otherwise, within ±0.45 of a
// spacing.
@compute @workgroup_size(64)
fn cs_probe_state(@builtin(global_invocation_id) id: vec3<u32>) {
    let probe = id.x;
    if (probe >= ddgi.counts.x) {
        return;
    }
    // An inactive probe's rays of the frame: the first DDGI_INACTIVE_RAYS, on their own
    // lattice (`cpu::ddgi::lattice`).
    let stride = ddgi.counts.y;
    let n = select(stride, min(stride, DDGI_INACTIVE_RAYS), ddgi_skipped(probe));
    let spacing = ddgi_grid.spacing.xyz;
    var back = 0u;
    var near = false;
    var nearest_back = 3.4e38;
    var back_dir = vec3<f32>(0.0);
    var nearest_front = 3.4e38;
    var front_dir = vec3<f32>(0.0);
    for (var r = 0u; r < n; r = r + 1u) {
        let w = ddgi_rays[probe * stride + r].w;
        if (abs(w) >= 1e30) {
            continue;
        }
        let d = normalize(ddgi.rotation * ddgi_fibonacci(r, n));
        let t = abs(w);
        if (w < 0.0) {
            back = back + 1u;
            if (t < nearest_back) {
                nearest_back = t;
                back_dir = d;
            }
        } else {
            if (all(abs(d * t) <= spacing)) {
                near = true;
            }
            if (t < nearest_front) {
                nearest_front = t;
                front_dir = d;
            }
        }
    }
    let inside = f32(back) / f32(max(n, 1u)) > ddgi_grid.state.x;
    var o = ddgi_probes[probe].xyz;
    if ((ddgi_grid.counts.w & DDGI_RELOCATE) != 0u) {
        let scale = min(min(spacing.x, spacing.y), spacing.z);
        if (inside) {
            if (nearest_back < 3.4e38) {
                o = o + back_dir * (nearest_back + 0.05 * scale);
            }
        } else if (nearest_front < ddgi_grid.state.y) {
            o = o - front_dir * (ddgi_grid.state.y - nearest_front);
        }
        o = clamp(o, -0.45 * spacing, 0.45 * spacing);
    }
    var state = 0.0;
    if ((ddgi_grid.counts.w & DDGI_CLASSIFY) != 0u && (inside || !near)) {
        state = DDGI_INACTIVE;
    }
    ddgi_probes[probe] = vec4<f32>(o, state);
}
