// Shared by the bounce passes (Knecht 002 §3.6): the point cloud as the bounce kernels see it
// and the light one VPL sends to one of its samples. CPU twin: cpu::knecht::bounce_incident.
#import common/ism.wgsl
#import common/random.wgsl

struct Instance {
    model: mat4x4<f32>,
    prev_model: mat4x4<f32>,
    normal_matrix: mat4x4<f32>,
}

// Rust twin: passes::ism::GpuPoint.
struct IsmPoint {
    position: vec3<f32>,
    draw: u32,
    normal: vec3<f32>,
    material: u32,
}

// Rust twin: passes::ism::GpuPointSurface.
struct PointSurface {
    // rgb: base colour c; a: W / w_s (area of the whole cloud over the sample's weight)
    albedo: vec4<f32>,
    // x: DI, y: SI, z: SP
    material: vec4<f32>,
}

// Rust twin: passes::vpl_bounce::BounceParams.
struct BounceParams {
    // x: points P, y: VPLs per bounce N, z: atlas columns, w: map size
    counts: vec4<u32>,
    // x: first slot of the source bounce, y: first slot of the new bounce,
    // z: selection (0 strongest, 1 proportional), w: shadow test: none (0), raw splats (1),
    // pulled maps (2); the IRSM baseline uses x and y only
    slots: vec4<u32>,
    // x: ISM eye offset, y: depth bias (point cloud only), z: d_min², w: receiver normal
    // offset in texels (pulled maps)
    geom: vec4<f32>,
    // x: random seed of this frame and bounce
    seed: vec4<u32>,
}

struct BouncePoint {
    x: vec3<f32>,
    n: vec3<f32>,
}

// World position and normal of a cloud point (it follows its instance's animation).
fn bounce_point(pt: IsmPoint, inst: Instance) -> BouncePoint {
    let x = (inst.model * vec4<f32>(pt.position, 1.0)).xyz;
    let n = normalize((inst.normal_matrix * vec4<f32>(pt.normal, 0.0)).xyz);
    return BouncePoint(x, n);
}

// Uniform in (0, 1) for sample j (CPU twin: cpu::knecht::bounce_uniform).
fn bounce_uniform(seed: u32, j: u32) -> f32 {
    let h = pcg_hash(j ^ pcg_hash(seed));
    return (f32(h >> 8u) + 0.5) / 16777216.0;
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Incident flux on sample p from `vpl` (rgb) and its contribution C (a), visibility not
// included: Φ_s = Φ_v · f_v(ω_in, v→s) · cos θ_v · cos θ_s / max(d², d_min²) · W / (w_s · P_v)
// (Eq. 4.7–4.8) and C_s = lum(Φ_s ⊙ (c_s·DI_s + SI_s)): Φ_s already holds the source's BRDF
// f_v, so the sample reflects it with its own material alone (see bounce_vpl).
fn bounce_light(vpl: Vpl, p: BouncePoint, surf: PointSurface, per_vpl: u32, dmin2: f32) -> vec4<f32> {
    let w = p.x - vpl.position.xyz;
    let d2 = dot(w, w);
    let l = w * inverseSqrt(max(d2, 1e-12));
    let cos_v = dot(vpl.normal.xyz, l);
    let cos_s = -dot(p.n, l);
    if (cos_v <= 0.0 || cos_s <= 0.0 || per_vpl == 0u) {
        return vec4<f32>(0.0);
    }
    let f_v = brdf_eval(vpl.normal.xyz, vpl.incident.xyz, l, vpl.albedo.rgb, vpl.normal.w, vpl.flux.a, vpl.incident.w);
    let area = surf.albedo.a / f32(per_vpl);
    let flux = vpl.flux.rgb * f_v * cos_v * cos_s / max(d2, dmin2) * area;
    let reflect = surf.albedo.rgb * surf.material.x + vec3<f32>(surf.material.y);
    return vec4<f32>(flux, luminance(flux * reflect));
}

// The VPL a sample becomes (§3.6.1): its position and normal, incident flux `flux` scaled by
// `scale`, ω_in toward the source VPL, and the sample's own material: DI_s, SP_s and
// SI = SI_s. The thesis writes SI = SI_s · SI_v ("necessary to get correct specular light
// bounces"); that product is right only for VPLs that carry the diffuse colour alone. Our Φ_s
// already went through the source's full BRDF f_v (glossy lobe included, Eq. 4.8), so the
// product would apply the source's specular intensity a second time (CPU twin and test:
// cpu::knecht::bounce_vpl, bounce_vpl_reflects_with_the_samples_own_brdf).
fn bounce_vpl(source: Vpl, p: BouncePoint, surf: PointSurface, flux: vec3<f32>, scale: f32) -> Vpl {
    return Vpl(
        vec4<f32>(p.x, 1.0),
        vec4<f32>(p.n, surf.material.x),
        vec4<f32>(flux * scale, surf.material.y),
        vec4<f32>(normalize(source.position.xyz - p.x), surf.material.z),
        vec4<f32>(surf.albedo.rgb, 0.0),
    );
}

fn empty_vpl() -> Vpl {
    return Vpl(vec4<f32>(0.0), vec4<f32>(0.0, 0.0, 1.0, 0.0), vec4<f32>(0.0), vec4<f32>(0.0, 0.0, 1.0, 0.0), vec4<f32>(0.0));
}
