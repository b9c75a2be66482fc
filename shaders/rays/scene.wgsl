// The scene for rays on the GPU (issue #56 point 1; docs/architecture.md "Rays on the GPU"):
// the two-level bounding volume hierarchy of `scene::two_level` in storage buffers (group 1),
// closest-hit and any-hit queries that honour alpha cutouts (glTF alphaMode MASK, §3.9.4),
// and what shading needs at a hit (position, interpolated normal, texture coordinates,
// tangent, material). Plain compute, no ray-tracing extension: it runs on every wgpu backend.
// CPU twin of the walk: `TwoLevel::intersect`; of the whole caster, the path tracer's own
// traversal (`scene::bvh::SceneBvh`), checked on every shipped scene by `tests/pathtrace/rays.rs`.

// WGSL twin of `scene::sah::BvhNode`: an inner node (count 0) has its children at `first`
// and `first + 1`; a bottom-level leaf holds triangles `first … first + count − 1`; a
// top-level leaf holds one instance, `first`.
struct BvhNode {
    lo: vec3<f32>,
    first: u32,
    hi: vec3<f32>,
    count: u32,
}

// `scene::two_level::RayVertex`.
struct RayVertex {
    normal: vec3<f32>,
    u: f32,
    tangent: vec4<f32>,
    v: f32,
}

// `scene::two_level::RayInstance`; flags: 1 double-sided, 2 mirrored, 4 in the top level.
struct RayInstance {
    world_to_object: mat4x4<f32>,
    object_to_world: mat4x4<f32>,
    normal_matrix: mat4x4<f32>,
    blas_root: u32,
    index_base: u32,
    material: u32,
    flags: u32,
}

// `scene::two_level::RayMaterial`.
struct RayMaterial {
    base_color: vec4<f32>,
    // Emitted radiance, normal texture scale.
    emissive: vec4<f32>,
    // Metallic, roughness, alpha cutoff (< 0: opaque), specular override (< 0: none).
    factors: vec4<f32>,
    // Texture entries of base colour, emissive, normal, metallic-roughness (RAY_NO_TEXTURE).
    textures: vec4<u32>,
}

// `scene::two_level::RayTexture`: one mip level; a texture's levels follow each other.
struct RayTexture {
    offset: u32,
    width: u32,
    height: u32,
    levels: u32,
}

// `passes::rays::RaySceneInfo`.
struct RaySceneInfo {
    // The top level's root node and its node count (0: every ray misses).
    tlas_root: u32,
    tlas_nodes: u32,
    instances: u32,
    materials: u32,
}

@group(1) @binding(0) var<uniform> ray_scene: RaySceneInfo;
@group(1) @binding(1) var<storage, read> ray_nodes: array<BvhNode>;
// Three per triangle in leaf order: the vertices in the primitive's space; the first's w
// holds the triangle's index in its primitive (bits of a u32).
@group(1) @binding(2) var<storage, read> ray_tris: array<vec4<f32>>;
@group(1) @binding(3) var<storage, read> ray_vertices: array<RayVertex>;
@group(1) @binding(4) var<storage, read> ray_indices: array<u32>;
@group(1) @binding(5) var<storage, read> ray_instances: array<RayInstance>;
@group(1) @binding(6) var<storage, read> ray_materials: array<RayMaterial>;
@group(1) @binding(7) var<storage, read> ray_textures: array<RayTexture>;
@group(1) @binding(8) var<storage, read> ray_texels: array<u32>;

// One entry per level of the walk (the builder keeps every leaf shallower: `sah::max_depth`,
// checked at upload).
const RAY_STACK: u32 = 64u;
const RAY_NO_TEXTURE: u32 = 0xffffffffu;
const RAY_DOUBLE_SIDED: u32 = 1u;
const RAY_MIRRORED: u32 = 2u;

// Queries (`scene::two_level::Query`): the closest hit on any face, the closest as a camera
// sees it (back faces of single-sided materials skipped), any hit (a shadow ray).
const RAY_CLOSEST: u32 = 0u;
const RAY_CAMERA: u32 = 1u;
const RAY_ANY: u32 = 2u;

struct RayHit {
    t: f32,
    instance: u32,
    // The triangle's index in its primitive.
    triangle: u32,
    // Barycentrics of the second and third vertices.
    bary: vec2<f32>,
    front: bool,
    hit: bool,
    // The triangle's record in `ray_tris` (its vertices at 3·slot …).
    slot: u32,
}

// Whether both components are finite numbers.
fn ray_finite2(v: vec2<f32>) -> bool {
    let e = vec2<u32>(0x7f800000u);
    return all((bitcast<vec2<u32>>(v) & e) != e);
}

// 1/d with each zero component replaced by a tiny number of its sign (`two_level::safe_inverse`).
fn ray_safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let negative = (bitcast<vec3<u32>>(d) & vec3<u32>(0x80000000u)) != vec3<u32>(0u);
    let tiny = select(vec3<f32>(1e-30), vec3<f32>(-1e-30), negative);
    return 1.0 / select(d, tiny, abs(d) < vec3<f32>(1e-30));
}

// Entry distance into a node's box within [0, t_max], or −1 (`two_level::slab`).
fn ray_slab(n: BvhNode, o: vec3<f32>, inv: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (n.lo - o) * inv;
    let t1 = (n.hi - o) * inv;
    let a = min(t0, t1);
    let b = max(t0, t1);
    let lo = max(max(max(a.x, a.y), a.z), 0.0);
    let hi = min(min(b.x, b.y), min(b.z, t_max));
    return select(-1.0, lo, lo <= hi);
}

// Barycentric slack of the triangle test: the walk transforms rays into each instance's
// space, and where two triangles share an edge (or two quads meet at a corner) the rounding
// of that transform could let a ray through both (a crack the world-space CPU walk does not
// have); each triangle reaches 10⁻⁵ of its size past its edges instead.
const RAY_EDGE_SLACK: f32 = 1e-5;

// Möller & Trumbore (1997), as `scene::raycast::moller_trumbore`, its bounds widened by
// RAY_EDGE_SLACK (`two_level::triangle_hit`): (t, u, v, 1) or w = 0.
fn ray_triangle(o: vec3<f32>, d: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec4<f32> {
    let e1 = b - a;
    let e2 = c - a;
    let p = cross(d, e2);
    let det = dot(e1, p);
    if (abs(det) < 1e-12) {
        return vec4<f32>(0.0);
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = dot(s, p) * inv;
    if (u < -RAY_EDGE_SLACK || u > 1.0 + RAY_EDGE_SLACK) {
        return vec4<f32>(0.0);
    }
    let q = cross(s, e1);
    let v = dot(d, q) * inv;
    if (v < -RAY_EDGE_SLACK || u + v > 1.0 + RAY_EDGE_SLACK) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(dot(e2, q) * inv, u, v, 1.0);
}

// The three vertex indices of triangle `tri` of the primitive whose indices start at `base`.
fn ray_triangle_indices(base: u32, tri: u32) -> vec3<u32> {
    let k = base + 3u * tri;
    return vec3<u32>(ray_indices[k], ray_indices[k + 1u], ray_indices[k + 2u]);
}

// Texture coordinates at barycentrics `b` of a triangle.
fn ray_uv(base: u32, tri: u32, b: vec2<f32>) -> vec2<f32> {
    let i = ray_triangle_indices(base, tri);
    let v0 = ray_vertices[i.x];
    let v1 = ray_vertices[i.y];
    let v2 = ray_vertices[i.z];
    let w = 1.0 - b.x - b.y;
    return vec2<f32>(v0.u, v0.v) * w + vec2<f32>(v1.u, v1.v) * b.x + vec2<f32>(v2.u, v2.v) * b.y;
}

// sRGB → linear (IEC 61966-2-1), as `scene::texture`'s table.
fn ray_srgb(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

// Texel (x, y) of a level, repeat wrap; RGB decoded from sRGB when `srgb`, alpha linear.
fn ray_texel(e: RayTexture, x: i32, y: i32, srgb: bool) -> vec4<f32> {
    let w = i32(e.width);
    let h = i32(e.height);
    let xi = ((x % w) + w) % w;
    let yi = ((y % h) + h) % h;
    let c = unpack4x8unorm(ray_texels[e.offset + u32(yi * w + xi)]);
    if (srgb) {
        return vec4<f32>(ray_srgb(c.rgb), c.a);
    }
    return c;
}

// A level at `uv`, bilinear with repeat wrap and texel centres at (i + ½) / size, as the
// G-buffer's sampler reads it (`TextureImage::sample_rgba`); non-finite coordinates read 0.
fn ray_sample_level(entry: u32, uv: vec2<f32>, srgb: bool) -> vec4<f32> {
    if (!ray_finite2(uv)) {
        return vec4<f32>(0.0);
    }
    let e = ray_textures[entry];
    let p = fract(uv) * vec2<f32>(f32(e.width), f32(e.height)) - 0.5;
    let f = floor(p);
    let t = p - f;
    let x = i32(f.x);
    let y = i32(f.y);
    let top = mix(ray_texel(e, x, y, srgb), ray_texel(e, x + 1, y, srgb), t.x);
    let bottom = mix(ray_texel(e, x, y + 1, srgb), ray_texel(e, x + 1, y + 1, srgb), t.x);
    return mix(top, bottom, t.y);
}

// A texture at `uv` filtered trilinearly at level of detail `lod` (clamped to its levels;
// `TextureImage::sample_trilinear`).
fn ray_sample(entry: u32, uv: vec2<f32>, lod: f32, srgb: bool) -> vec4<f32> {
    let top = f32(ray_textures[entry].levels - 1u);
    let d = clamp(lod, 0.0, top);
    let lo = floor(d);
    let a = ray_sample_level(entry + u32(lo), uv, srgb);
    if (d > lo) {
        return mix(a, ray_sample_level(entry + u32(lo) + 1u, uv, srgb), d - lo);
    }
    return a;
}

// Whether a hit survives its material's alpha cutout: base colour alpha, factor × texture
// at mip 0, at least the cutoff (as the path tracer's `intersect` and the depth-only views).
fn ray_alpha_passes(inst: RayInstance, tri: u32, bary: vec2<f32>) -> bool {
    let m = ray_materials[inst.material];
    if (m.factors.z < 0.0) {
        return true;
    }
    var a = m.base_color.a;
    if (m.textures.x != RAY_NO_TEXTURE) {
        a = a * ray_sample_level(m.textures.x, ray_uv(inst.index_base, tri, bary), true).a;
    }
    return a >= m.factors.z;
}

// The hit of the ray o + t·d, t in (tmin, tmax), for `query`. The top level's leaves take the
// ray into their instance's space (t is the same there: d is transformed, not normalised).
fn ray_trace(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32, query: u32) -> RayHit {
    var hit = RayHit(tmax, 0u, 0u, vec2<f32>(0.0), false, false, 0u);
    if (ray_scene.tlas_nodes == 0u) {
        return hit;
    }
    let inv = ray_safe_inverse(d);
    var top: array<u32, RAY_STACK>;
    var bottom: array<u32, RAY_STACK>;
    top[0] = ray_scene.tlas_root;
    var sp = 1u;
    while (sp > 0u) {
        sp = sp - 1u;
        let n = ray_nodes[top[sp]];
        if (ray_slab(n, o, inv, hit.t) < 0.0) {
            continue;
        }
        if (n.count == 0u) {
            if (sp + 2u <= RAY_STACK) {
                top[sp] = n.first + 1u;
                top[sp + 1u] = n.first;
                sp = sp + 2u;
            }
            continue;
        }
        let inst = ray_instances[n.first];
        let ol = (inst.world_to_object * vec4<f32>(o, 1.0)).xyz;
        let dl = (inst.world_to_object * vec4<f32>(d, 0.0)).xyz;
        let inv_l = ray_safe_inverse(dl);
        let mirrored = (inst.flags & RAY_MIRRORED) != 0u;
        let cull = query == RAY_CAMERA && (inst.flags & RAY_DOUBLE_SIDED) == 0u;
        bottom[0] = inst.blas_root;
        var bp = 1u;
        while (bp > 0u) {
            bp = bp - 1u;
            let m = ray_nodes[bottom[bp]];
            if (ray_slab(m, ol, inv_l, hit.t) < 0.0) {
                continue;
            }
            if (m.count == 0u) {
                if (bp + 2u <= RAY_STACK) {
                    bottom[bp] = m.first + 1u;
                    bottom[bp + 1u] = m.first;
                    bp = bp + 2u;
                }
                continue;
            }
            for (var k = m.first; k < m.first + m.count; k = k + 1u) {
                let a = ray_tris[3u * k];
                let b = ray_tris[3u * k + 1u].xyz;
                let c = ray_tris[3u * k + 2u].xyz;
                let r = ray_triangle(ol, dl, a.xyz, b, c);
                if (r.w == 0.0 || !(r.x > tmin && r.x < hit.t)) {
                    continue;
                }
                let facing = dot(cross(b - a.xyz, c - a.xyz), dl) < 0.0;
                let front = facing != mirrored;
                if (cull && !front) {
                    continue;
                }
                let tri = bitcast<u32>(a.w);
                if (!ray_alpha_passes(inst, tri, r.yz)) {
                    continue;
                }
                hit = RayHit(r.x, n.first, tri, r.yz, front, true, k);
                if (query == RAY_ANY) {
                    return hit;
                }
            }
        }
    }
    return hit;
}

// Whether anything (alpha cutouts passed through) lies on the ray within (tmin, tmax).
fn ray_occluded(o: vec3<f32>, d: vec3<f32>, tmin: f32, tmax: f32) -> bool {
    return ray_trace(o, d, tmin, tmax, RAY_ANY).hit;
}

// What shading needs at a hit.
struct RaySurface {
    p: vec3<f32>,
    // The interpolated vertex normal facing the ray's origin (the geometric one where the
    // vertex normals cancel), as `SceneBvh::intersect_where` gives it.
    n: vec3<f32>,
    // The geometric normal (world, unit, counter-clockwise side).
    geometric: vec3<f32>,
    // The interpolated vertex normal as it is (unit, or zero where the normals cancel).
    vertex_normal: vec3<f32>,
    uv: vec2<f32>,
    // Interpolated world tangent (xyz) and the first vertex's bitangent sign (w; 0: none).
    tangent: vec4<f32>,
    material: u32,
}

fn ray_surface(o: vec3<f32>, d: vec3<f32>, h: RayHit) -> RaySurface {
    let inst = ray_instances[h.instance];
    let i = ray_triangle_indices(inst.index_base, h.triangle);
    let vs = array<RayVertex, 3>(ray_vertices[i.x], ray_vertices[i.y], ray_vertices[i.z]);
    let w = vec3<f32>(1.0 - h.bary.x - h.bary.y, h.bary.x, h.bary.y);
    var n = vec3<f32>(0.0);
    var t = vec3<f32>(0.0);
    var uv = vec2<f32>(0.0);
    let flip = select(1.0, -1.0, (inst.flags & RAY_MIRRORED) != 0u);
    for (var j = 0u; j < 3u; j = j + 1u) {
        let nj = (inst.normal_matrix * vec4<f32>(vs[j].normal, 0.0)).xyz;
        n = n + ray_normalize_or_zero(nj) * w[j];
        let tj = (inst.object_to_world * vec4<f32>(vs[j].tangent.xyz, 0.0)).xyz;
        t = t + ray_normalize_or_zero(tj) * w[j];
        uv = uv + vec2<f32>(vs[j].u, vs[j].v) * w[j];
    }
    let geometric = ray_geometric_normal(inst, h.slot);
    n = ray_normalize_or_zero(n);
    let vertex_normal = n;
    if (all(n == vec3<f32>(0.0))) {
        n = geometric;
    }
    if (dot(n, d) > 0.0) {
        n = -n;
    }
    let material = inst.material;
    return RaySurface(o + d * h.t, n, geometric, vertex_normal, uv, vec4<f32>(t, vs[0].tangent.w * flip), material);
}

fn ray_normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    return select(vec3<f32>(0.0), v / l, l > 0.0 && l < 1e30);
}

// The unit geometric normal in the world of the triangle record `slot` (counter-clockwise
// side; +Y when degenerate, as `SceneBvh`'s `normalize_or(Vec3::Y)`).
fn ray_geometric_normal(inst: RayInstance, slot: u32) -> vec3<f32> {
    let a = (inst.object_to_world * vec4<f32>(ray_tris[3u * slot].xyz, 1.0)).xyz;
    let b = (inst.object_to_world * vec4<f32>(ray_tris[3u * slot + 1u].xyz, 1.0)).xyz;
    let c = (inst.object_to_world * vec4<f32>(ray_tris[3u * slot + 2u].xyz, 1.0)).xyz;
    let g = ray_normalize_or_zero(cross(b - a, c - a));
    return select(g, vec3<f32>(0.0, 1.0, 0.0), all(g == vec3<f32>(0.0)));
}
