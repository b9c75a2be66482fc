// DDGI's probes (issue #56 point 3; Majercik et al. 2019, 2021; CPU twin `cpu::ddgi`,
// documented there): the update's parameters, octahedral directions, the atlases' layout.

// `passes::ddgi::DdgiUpdateParams`.
struct DdgiUpdate {
    // The frame's rotation of every probe's rays (columns), 2019 §3.1.
    rotation: mat3x3<f32>,
    // Probes, rays per probe, irradiance interior texels, distance interior texels.
    counts: vec4<u32>,
    // Tiles per atlas row (irradiance, distance), whether the old values count (0: the first
    // update), the frame's seed (the trace's shading samples).
    tiles: vec4<u32>,
    // Hysteresis α, distance sharpness, max distance (world units), 0.
    blend: vec4<f32>,
}

// Octahedral coordinates ∈ [−1, 1]² → unit direction (`cpu::ddgi::oct_decode`).
fn ddgi_sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}

fn ddgi_oct_decode(e: vec2<f32>) -> vec3<f32> {
    let z = 1.0 - abs(e.x) - abs(e.y);
    var xy = e;
    if (z < 0.0) {
        xy = (vec2<f32>(1.0) - abs(e.yx)) * ddgi_sign_not_zero(e);
    }
    let v = vec3<f32>(xy, z);
    let l = length(v);
    return select(vec3<f32>(0.0, 0.0, 1.0), v / l, l > 0.0);
}

// Unit direction → octahedral coordinates (`cpu::ddgi::oct_encode`).
fn ddgi_oct_encode(d: vec3<f32>) -> vec2<f32> {
    let l1 = abs(d.x) + abs(d.y) + abs(d.z);
    if (l1 <= 0.0) {
        return vec2<f32>(0.0);
    }
    let p = d.xy / l1;
    if (d.z < 0.0) {
        return (vec2<f32>(1.0) - abs(p.yx)) * ddgi_sign_not_zero(p);
    }
    return p;
}

// Ray `i` of `n` on the spherical Fibonacci lattice (`cpu::ddgi::spherical_fibonacci`).
fn ddgi_fibonacci(i: u32, n: u32) -> vec3<f32> {
    let golden = (sqrt(5.0) - 1.0) * 0.5;
    let s = f32(i) * golden;
    let phi = 6.28318530718 * (s - floor(s));
    let cos_theta = 1.0 - (2.0 * f32(i) + 1.0) / f32(max(n, 1u));
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    return vec3<f32>(cos(phi) * sin_theta, sin(phi) * sin_theta, cos_theta);
}

// The atlas texel of a probe's tile texel (tx, ty) (`cpu::ddgi::Atlas::texel`): tiles of
// interior + 2 texels, `columns` a row.
fn ddgi_texel(probe: u32, tx: u32, ty: u32, interior: u32, columns: u32) -> vec2<u32> {
    let t = interior + 2u;
    return vec2<u32>((probe % columns) * t + tx, (probe / columns) * t + ty);
}

// The direction of interior texel (i, j) (`Atlas::direction`).
fn ddgi_texel_direction(i: u32, j: u32, interior: u32) -> vec3<f32> {
    let n = f32(interior);
    return ddgi_oct_decode(vec2<f32>((f32(i) + 0.5) / n * 2.0 - 1.0, (f32(j) + 0.5) / n * 2.0 - 1.0));
}

// `passes::ddgi::DdgiGridParams`: the grid and what the frame does with it.
struct DdgiGrid {
    // The first probe's place (xyz), the normal bias in world units (w).
    origin: vec4<f32>,
    // The spacing (xyz), the view bias in world units (w).
    spacing: vec4<f32>,
    // Probes along x, y, z; flags (DDGI_*).
    counts: vec4<u32>,
    // Irradiance interior texels and tiles a row, distance interior texels and tiles a row.
    atlas: vec4<u32>,
    // Classification's back-face share, relocation's least front-face distance (world), 1 for
    // the glossy receiver (`ddgi.receiver`).
    state: vec4<f32>,
}

const DDGI_CLASSIFY: u32 = 1u;
const DDGI_RELOCATE: u32 = 2u;
const DDGI_BOUNCES: u32 = 4u;
const DDGI_SKIP_INACTIVE: u32 = 8u;
// A probe record's w: 0 active, 1 inactive (`cpu::ddgi::ProbeState`).
const DDGI_INACTIVE: f32 = 1.0;
// The rays an inactive probe still casts a frame, on a lattice of their own, and the distance
// its other rays record (`cpu::ddgi::{INACTIVE_RAYS, UNTRACED}`; 2021 §5.2).
const DDGI_INACTIVE_RAYS: u32 = 32u;
const DDGI_UNTRACED: f32 = 3.0e38;
