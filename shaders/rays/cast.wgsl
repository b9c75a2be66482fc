// A batch of rays through the GPU ray caster (issue #56 point 1): one invocation per ray,
// its hit and the surface there written out. What `tests/pathtrace/rays.rs` compares with the path
// tracer's traversal and `gi-lab bench --suite rays` times; `passes::rays::RayCastPass`.

#import rays/scene.wgsl

// `passes::rays::CastRay`: origin and tmin, direction and tmax.
struct CastRay {
    origin: vec4<f32>,
    dir: vec4<f32>,
}

// `passes::rays::CastHit`.
struct CastHit {
    // Position and t.
    p: vec4<f32>,
    // Normal facing the ray (xyz), material (w, bits of a u32).
    n: vec4<f32>,
    // Barycentrics (xy), texture coordinates (zw).
    bary_uv: vec4<f32>,
    // Instance, triangle, front face, hit.
    ids: vec4<u32>,
}

// `passes::rays::CastParams`.
struct CastParams {
    count: u32,
    // RAY_CLOSEST, RAY_CAMERA or RAY_ANY.
    query: u32,
    // Invocations per row of the dispatch (its x size × 64).
    row: u32,
    _pad: u32,
}

@group(0) @binding(0) var<storage, read> cast_params: CastParams;
@group(0) @binding(1) var<storage, read> cast_rays: array<CastRay>;
@group(0) @binding(2) var<storage, read_write> cast_hits: array<CastHit>;

@compute @workgroup_size(64)
fn cs_cast(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * cast_params.row + id.x;
    if (i >= cast_params.count) {
        return;
    }
    let ray = cast_rays[i];
    let h = ray_trace(ray.origin.xyz, ray.dir.xyz, ray.origin.w, ray.dir.w, cast_params.query);
    var out = CastHit(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<u32>(0u));
    if (h.hit) {
        let s = ray_surface(ray.origin.xyz, ray.dir.xyz, h);
        out.p = vec4<f32>(s.p, h.t);
        out.n = vec4<f32>(s.n, bitcast<f32>(s.material));
        out.bary_uv = vec4<f32>(h.bary, s.uv);
        out.ids = vec4<u32>(h.instance, h.triangle, select(0u, 1u, h.front), 1u);
    }
    cast_hits[i] = out;
}
