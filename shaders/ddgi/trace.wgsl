// DDGI's probe rays (Majercik et al. 2019 §3.1; 2021 §5): each probe casts `counts.y` rays on a
// spherical Fibonacci lattice under the frame's random rotation from its relocated place. A
// hit is lit as the GPU truth lights a path's vertex (`rays/shade.wgsl`: every punctual
// light, one emitter point and one sky direction with shadow rays), plus, with
// infinite bounces, its diffuse albedo times the probes' irradiance of the previous frame
// (2019 §3.3). Each ray writes vec4(radiance toward the probe, distance):
// a negative distance is a back face at −w (2021 §5.2), 1e30 a miss, DDGI_UNTRACED a ray an
// inactive probe did not cast. `passes::ddgi::trace`.

#import rays/shade.wgsl
#import ddgi/lookup.wgsl

@group(0) @binding(5) var<storage, read> ddgi: DdgiUpdate;
@group(0) @binding(6) var<storage, read> ddgi_grid: DdgiGrid;
@group(0) @binding(7) var<storage, read> ddgi_probes: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> ddgi_irradiance: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> ddgi_distance: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> ddgi_rays: array<vec4<f32>>;

@compute @workgroup_size(64)
fn cs_trace(@builtin(global_invocation_id) id: vec3<u32>) {
    let rays = ddgi.counts.y;
    let i = id.x;
    if (i >= ddgi.counts.x * rays) {
        return;
    }
    let probe = i / rays;
    let r = i % rays;
    // An inactive probe shades nothing (2021 §5.2): with `ddgi.skip_inactive` it casts only the first
    // DDGI_INACTIVE_RAYS rays, on a lattice of that many, enough to see a surface come near
    // and wake it; its other records say they were not traced (`cpu::ddgi::lattice`).
    var lattice = rays;
    let skip = DDGI_CLASSIFY | DDGI_SKIP_INACTIVE;
    if ((ddgi_grid.counts.w & skip) == skip && ddgi_probes[probe].w == DDGI_INACTIVE) {
        lattice = min(rays, DDGI_INACTIVE_RAYS);
        if (r >= lattice) {
            ddgi_rays[i] = vec4<f32>(0.0, 0.0, 0.0, DDGI_UNTRACED);
            return;
        }
    }
    let o = ddgi_probe_position(probe);
    let d = normalize(ddgi.rotation * ddgi_fibonacci(r, lattice));
    let h = ray_trace(o, d, 0.0, 3.4e38, RAY_CLOSEST);
    if (!h.hit) {
        // The sky seen directly is stage 2's light (its directions light every pixel), as
        // the emitters are: a miss carries none.
        ddgi_rays[i] = vec4<f32>(0.0, 0.0, 0.0, 1e30);
        return;
    }
    let inst = ray_instances[h.instance];
    if (!h.front && (inst.flags & RAY_DOUBLE_SIDED) == 0u) {
        // Inside geometry: no light, the distance marked (2021 §5.2).
        ddgi_rays[i] = vec4<f32>(0.0, 0.0, 0.0, -h.t);
        return;
    }
    let s = pt_surface(ray_surface(o, d, h), vec4<f32>(0.0));
    var rng = pt_hash(ddgi.tiles.w ^ pt_hash(i * 0x9E3779B9u));
    var l = pt_direct(s, -d, &rng);
    if ((ddgi_grid.counts.w & DDGI_BOUNCES) != 0u) {
        l = l + s.c * s.di / PI * ddgi_sample(s.p, s.n, -d);
    }
    ddgi_rays[i] = vec4<f32>(l, h.t);
}
