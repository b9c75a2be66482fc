// Reading DDGI's probes at a surface point (Majercik et al. 2019 §3.4, Eq. 5–6; 2021 §4.2;
// CPU twin `cpu::ddgi::sample`, documented there): the point moved by the normal and view
// bias, the eight probes of its cell weighted by trilinear, the smooth backface term and
// Chebyshev's visibility from the distance moments, the weighted mean of their irradiance
// toward n, times π. The including module declares `ddgi_grid` (DdgiGrid), `ddgi_probes`
// (per probe: relocation offset xyz, state w), `ddgi_irradiance` and `ddgi_distance` (the
// atlases, row-major).

#import ddgi/probes.wgsl

fn ddgi_probe_coords(i: u32) -> vec3<u32> {
    let c = ddgi_grid.counts;
    return vec3<u32>(i % c.x, (i / c.x) % c.y, i / (c.x * c.y));
}

// A probe's place: on the grid, moved by its relocation offset.
fn ddgi_probe_position(i: u32) -> vec3<f32> {
    return ddgi_grid.origin.xyz + ddgi_grid.spacing.xyz * vec3<f32>(ddgi_probe_coords(i)) + ddgi_probes[i].xyz;
}

// Tile coordinates of direction d in a tile of `n` interior texels, texel centres at k + 0.5
// (`Atlas::lookup`): the lower texel and the bilinear fractions.
struct DdgiTap {
    lo: vec2<u32>,
    t: vec2<f32>,
}

fn ddgi_tap(d: vec3<f32>, n: u32) -> DdgiTap {
    let e = ddgi_oct_encode(d);
    let p = (e * 0.5 + vec2<f32>(0.5)) * f32(n) + vec2<f32>(0.5);
    let f = floor(p);
    return DdgiTap(vec2<u32>(f), p - f);
}

fn ddgi_irradiance_texel(probe: u32, x: u32, y: u32) -> vec3<f32> {
    let n = ddgi_grid.atlas.x;
    let p = ddgi_texel(probe, min(x, n + 1u), min(y, n + 1u), n, ddgi_grid.atlas.y);
    return ddgi_irradiance[p.y * ddgi_grid.atlas.y * (n + 2u) + p.x].rgb;
}

fn ddgi_distance_texel(probe: u32, x: u32, y: u32) -> vec2<f32> {
    let n = ddgi_grid.atlas.z;
    let p = ddgi_texel(probe, min(x, n + 1u), min(y, n + 1u), n, ddgi_grid.atlas.w);
    return ddgi_distance[p.y * ddgi_grid.atlas.w * (n + 2u) + p.x].xy;
}

// The probe's irradiance / π toward d, bilinear (`Atlas::lookup`).
fn ddgi_lookup_irradiance(probe: u32, d: vec3<f32>) -> vec3<f32> {
    let a = ddgi_tap(d, ddgi_grid.atlas.x);
    let top = mix(ddgi_irradiance_texel(probe, a.lo.x, a.lo.y), ddgi_irradiance_texel(probe, a.lo.x + 1u, a.lo.y), a.t.x);
    let bottom = mix(ddgi_irradiance_texel(probe, a.lo.x, a.lo.y + 1u), ddgi_irradiance_texel(probe, a.lo.x + 1u, a.lo.y + 1u), a.t.x);
    return mix(top, bottom, a.t.y);
}

// The probe's distance moments (mean, mean²) toward d, bilinear.
fn ddgi_lookup_distance(probe: u32, d: vec3<f32>) -> vec2<f32> {
    let a = ddgi_tap(d, ddgi_grid.atlas.z);
    let top = mix(ddgi_distance_texel(probe, a.lo.x, a.lo.y), ddgi_distance_texel(probe, a.lo.x + 1u, a.lo.y), a.t.x);
    let bottom = mix(ddgi_distance_texel(probe, a.lo.x, a.lo.y + 1u), ddgi_distance_texel(probe, a.lo.x + 1u, a.lo.y + 1u), a.t.x);
    return mix(top, bottom, a.t.y);
}

fn ddgi_normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    return select(fallback, v / l, l > 0.0 && l < 3.4e38);
}

// One of the eight probes a point reads, with its weights (`cpu::ddgi::ProbeWeight`).
struct DdgiTerm {
    probe: u32,
    trilinear: f32,
    // The smooth backface term ((dir·n + 1)/2)² + 0.2 (2019 §3.4).
    normal: f32,
    // Chebyshev's bound from the distance moments, cubed (2019 Eq. 6).
    visibility: f32,
    // The product, small weights crushed, times trilinear; 0 for an inactive probe.
    weight: f32,
}

// The cell of a point moved by the bias: its lowest probe's coordinates and the position in it.
struct DdgiCell {
    biased: vec3<f32>,
    base: vec3<u32>,
    alpha: vec3<f32>,
}

fn ddgi_cell(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>) -> DdgiCell {
    let counts = ddgi_grid.counts.xyz;
    let biased = p + n * ddgi_grid.origin.w + v * ddgi_grid.spacing.w;
    let g = (biased - ddgi_grid.origin.xyz) / ddgi_grid.spacing.xyz;
    let hi = max(vec3<f32>(counts) - vec3<f32>(2.0), vec3<f32>(0.0));
    let base_f = clamp(floor(g), vec3<f32>(0.0), hi);
    return DdgiCell(biased, vec3<u32>(base_f), clamp(g - base_f, vec3<f32>(0.0), vec3<f32>(1.0)));
}

// Corner k ∈ [0, 8) of the cell, read from the point p of normal n.
fn ddgi_term(cell: DdgiCell, k: u32, p: vec3<f32>, n: vec3<f32>) -> DdgiTerm {
    let counts = ddgi_grid.counts.xyz;
    let corner = vec3<u32>(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u);
    let c = min(cell.base + corner, counts - vec3<u32>(1u));
    let probe = c.x + counts.x * (c.y + counts.y * c.z);
    let at = ddgi_probe_position(probe);
    let t = select(vec3<f32>(1.0) - cell.alpha, cell.alpha, corner == vec3<u32>(1u));
    let trilinear = t.x * t.y * t.z;
    let to_probe = ddgi_normalize_or(at - p, vec3<f32>(0.0));
    let nb = (dot(to_probe, n) + 1.0) * 0.5;
    let normal = nb * nb + 0.2;
    let from_probe = cell.biased - at;
    let r = length(from_probe);
    let moments = ddgi_lookup_distance(probe, ddgi_normalize_or(from_probe, vec3<f32>(0.0, 0.0, 1.0)));
    var visibility = 1.0;
    if (r > moments.x) {
        let variance = abs(moments.y - moments.x * moments.x);
        let d = r - moments.x;
        let q = variance / max(variance + d * d, 1e-12);
        visibility = q * q * q;
    }
    var w = max(normal * visibility, 1e-6);
    if (w < 0.2) {
        w = w * w * w / 0.04;
    }
    w = w * trilinear;
    if (ddgi_probes[probe].w == DDGI_INACTIVE) {
        w = 0.0;
    }
    return DdgiTerm(probe, trilinear, normal, visibility, w);
}

// The irradiance at p (normal n, unit v toward the eye) from the probes toward n and toward
// `dir`, with the same eight weights (`cpu::ddgi::sample`, `irradiance_toward`).
struct DdgiPair {
    n: vec3<f32>,
    dir: vec3<f32>,
}

fn ddgi_sample_pair(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, dir: vec3<f32>) -> DdgiPair {
    let cell = ddgi_cell(p, n, v);
    var sum = vec3<f32>(0.0);
    var sum_dir = vec3<f32>(0.0);
    var total = 0.0;
    for (var k = 0u; k < 8u; k = k + 1u) {
        let term = ddgi_term(cell, k, p, n);
        sum = sum + ddgi_lookup_irradiance(term.probe, n) * term.weight;
        sum_dir = sum_dir + ddgi_lookup_irradiance(term.probe, dir) * term.weight;
        total = total + term.weight;
    }
    if (total <= 0.0) {
        return DdgiPair(vec3<f32>(0.0), vec3<f32>(0.0));
    }
    let k = 3.14159265358979 / total;
    return DdgiPair(sum * k, sum_dir * k);
}

// The irradiance E at p toward n (`cpu::ddgi::sample`).
fn ddgi_sample(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let cell = ddgi_cell(p, n, v);
    var sum = vec3<f32>(0.0);
    var total = 0.0;
    for (var k = 0u; k < 8u; k = k + 1u) {
        let term = ddgi_term(cell, k, p, n);
        sum = sum + ddgi_lookup_irradiance(term.probe, n) * term.weight;
        total = total + term.weight;
    }
    if (total <= 0.0) {
        return vec3<f32>(0.0);
    }
    return sum / total * 3.14159265358979;
}
