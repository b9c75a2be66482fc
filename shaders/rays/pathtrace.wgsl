// Path-traced ground truth on the GPU (issue #56 point 2): the CPU path tracer's estimator
// (`cpu::pathtrace`, documented there) step for step over the GPU ray caster
// (`rays/scene.wgsl`): a ray through the pixel centre whose footprint picks the textures' mip
// level, punctual lights, one emitter point and one sky direction by next-event estimation at
// every vertex, the BRDF mixture sampled for each bounce. One invocation per pixel adds
// `size.w` samples to its sums (direct, indirect). Its random numbers are its own (PCG per
// pixel and sample), so the two tracers agree in expectation, not sample by sample:
// `tests/pathtrace/rays.rs` compares them at equal spp by FLIP.

#import rays/shade.wgsl

// `passes::rays::pathtrace::PtParams`: the camera and the run.
struct PtParams {
    inv_view_proj: mat4x4<f32>,
    // Eye (xyz), ray offset ε (w).
    eye: vec4<f32>,
    // Width, height, index of the pass's first sample, samples this pass.
    size: vec4<u32>,
    // Bounces, seed, 0, flags (PT_SKY_*).
    config: vec4<u32>,
}

@group(0) @binding(5) var<storage, read> pt: PtParams;
// Per pixel: the sum of direct light, then of indirect light.
@group(0) @binding(6) var<storage, read_write> pt_sums: array<vec4<f32>>;

// The primary ray through the centre of pixel (x, y) (`raycast::primary_ray`).
struct PtRay {
    o: vec3<f32>,
    d: vec3<f32>,
}

fn pt_primary(x: f32, y: f32) -> PtRay {
    let ndc = vec2<f32>((x + 0.5) / f32(pt.size.x) * 2.0 - 1.0, 1.0 - (y + 0.5) / f32(pt.size.y) * 2.0);
    let near = pt.inv_view_proj * vec4<f32>(ndc, 0.0, 1.0);
    let far = pt.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    let a = near.xyz / near.w;
    let b = far.xyz / far.w;
    return PtRay(a, normalize(b - a));
}

// ∂uv/∂x and ∂uv/∂y where the neighbours' rays meet the hit triangle's plane (the path
// tracer's `Footprint::uv_derivatives`); zero when a ray is parallel to it.
fn pt_uv_derivatives(h: RayHit, uv: vec2<f32>, right: PtRay, below: PtRay) -> vec4<f32> {
    let inst = ray_instances[h.instance];
    let a = (inst.object_to_world * vec4<f32>(ray_tris[3u * h.slot].xyz, 1.0)).xyz;
    let b = (inst.object_to_world * vec4<f32>(ray_tris[3u * h.slot + 1u].xyz, 1.0)).xyz;
    let c = (inst.object_to_world * vec4<f32>(ray_tris[3u * h.slot + 2u].xyz, 1.0)).xyz;
    let i = ray_triangle_indices(inst.index_base, h.triangle);
    let uv0 = vec2<f32>(ray_vertices[i.x].u, ray_vertices[i.x].v);
    let uv1 = vec2<f32>(ray_vertices[i.y].u, ray_vertices[i.y].v);
    let uv2 = vec2<f32>(ray_vertices[i.z].u, ray_vertices[i.z].v);
    let e1 = b - a;
    let e2 = c - a;
    let plane = cross(e1, e2);
    let d00 = dot(e1, e1);
    let d01 = dot(e1, e2);
    let d11 = dot(e2, e2);
    let det = d00 * d11 - d01 * d01;
    var out = vec4<f32>(0.0);
    for (var k = 0u; k < 2u; k = k + 1u) {
        var r = right;
        if (k == 1u) {
            r = below;
        }
        let den = dot(plane, r.d);
        if (abs(den) <= 1e-30 || abs(det) <= 1e-30) {
            return vec4<f32>(0.0);
        }
        let w = r.o + r.d * (dot(plane, a - r.o) / den) - a;
        let d20 = dot(w, e1);
        let d21 = dot(w, e2);
        let b1 = (d11 * d20 - d01 * d21) / det;
        let b2 = (d00 * d21 - d01 * d20) / det;
        let q = uv0 * (1.0 - b1 - b2) + uv1 * b1 + uv2 * b2 - uv;
        if (!ray_finite2(q)) {
            return vec4<f32>(0.0);
        }
        if (k == 0u) {
            out = vec4<f32>(q, out.zw);
        } else {
            out = vec4<f32>(out.xy, q);
        }
    }
    return out;
}

@compute @workgroup_size(8, 8)
fn cs_pathtrace(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= pt.size.x || id.y >= pt.size.y) {
        return;
    }
    let x = f32(id.x);
    let y = f32(id.y);
    var ray = pt_primary(x, y);
    if (!all((bitcast<vec3<u32>>(ray.o) & vec3<u32>(0x7f800000u)) != vec3<u32>(0x7f800000u))) {
        ray.o = pt.eye.xyz;
    }
    let right = pt_primary(x + 1.0, y);
    let below = pt_primary(x, y + 1.0);
    let pixel = id.y * pt.size.x + id.x;
    var direct_sum = vec3<f32>(0.0);
    var indirect_sum = vec3<f32>(0.0);
    // The camera's hit and its material do not depend on the sample: read once.
    let first = ray_trace(ray.o, ray.d, 0.0, 3.4e38, RAY_CLOSEST);
    var first_surface: PtSurface;
    var emission = vec3<f32>(0.0);
    if (first.hit) {
        let s0 = ray_surface(ray.o, ray.d, first);
        first_surface = pt_surface(s0, pt_uv_derivatives(first, s0.uv, right, below));
        emission = pt_emission(first_surface);
    }
    for (var k = 0u; k < pt.size.w; k = k + 1u) {
        var rng = pt_hash(pt.config.y ^ pt_hash(pixel * 0x9E3779B9u ^ pt_hash(pt.size.z + k)));
        if (!first.hit) {
            if ((pt.config.w & PT_SKY_BACKGROUND) != 0u && (pt.config.w & PT_SKY_LIT) != 0u) {
                direct_sum = direct_sum + pt_sky_radiance(ray.d);
            }
            continue;
        }
        var h = first_surface;
        var v = -ray.d;
        var throughput = vec3<f32>(1.0);
        // Vertex 0 is the camera's hit (its emission and direct light), vertices 1 … bounces
        // the path's (their direct light is the indirect light): one call of pt_direct.
        for (var b = 0u; b <= pt.config.x; b = b + 1u) {
            let d = pt_direct(h, v, &rng);
            if (b == 0u) {
                direct_sum = direct_sum + emission + d;
            } else {
                indirect_sum = indirect_sum + throughput * d;
            }
            if (b == pt.config.x) {
                break;
            }
            let bounce = pt_sample_brdf(h, v, &rng);
            if (!bounce.ok) {
                break;
            }
            throughput = throughput * bounce.weight;
            if (max(max(throughput.x, throughput.y), throughput.z) <= 0.0) {
                break;
            }
            let o = h.p + h.n * pt.eye.w;
            let next = ray_trace(o, bounce.l, 0.0, 3.4e38, RAY_CLOSEST);
            if (!next.hit) {
                break;
            }
            v = -bounce.l;
            h = pt_surface(ray_surface(o, bounce.l, next), vec4<f32>(0.0));
        }
    }
    pt_sums[2u * pixel] = pt_sums[2u * pixel] + vec4<f32>(direct_sum, 0.0);
    pt_sums[2u * pixel + 1u] = pt_sums[2u * pixel + 1u] + vec4<f32>(indirect_sum, 0.0);
}
