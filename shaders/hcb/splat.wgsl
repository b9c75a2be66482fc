// Coherence-weighted splatting of the HCB samples (Nguyen et al. §4.2–4.3). Each sample
// draws a screen quad bounding its sphere (centre a, radius a^w); every pixel b under it
// gets, when b is coherent to a (Eq. 9: the error of Eq. 8 at most 1), the weight of Eq. 10
// times the sample's light in rgb and the weight in alpha, summed by additive blending
// (`hcb.weight_sum`). cs_normalize then divides (Eq. 11). CPU twin: cpu::hcb::{coherence_errors,
// weight}.
#import common/camera.wgsl
#import hcb/common.wgsl

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> hp: HcbParams;
@group(0) @binding(2) var<storage, read> samples: array<HcbSample>;
@group(0) @binding(3) var g_position: texture_2d<f32>;
@group(0) @binding(4) var g_normal: texture_2d<f32>;
// the sample counter: word 1 is where the new samples start (§5.2; hp.level.x = 1)
@group(0) @binding(5) var<storage, read> counter: array<u32>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) index: u32,
}

@vertex
fn vs_splat(@builtin(vertex_index) v: u32, @builtin(instance_index) instance: u32) -> VsOut {
    var out: VsOut;
    let i = instance + select(0u, counter[1], hp.level.x == 1u);
    out.index = i;
    let s = samples[i];
    let corner = quad_corner(v);
    let depth = -(camera.view * vec4<f32>(s.position.xyz, 1.0)).z;
    let c = camera.view_proj * vec4<f32>(s.position.xyz, 1.0);
    if (depth <= s.position.w || c.w <= 0.0) {
        // The sphere holds the eye: the whole screen.
        out.clip = vec4<f32>(corner, 0.5, 1.0);
        return out;
    }
    // Half-size: the tangent of the sphere's angular radius at its view depth (r / √(d² − r²),
    // larger than at its distance), stretched by distance / depth for its off-axis ellipse,
    // in pixels, plus one.
    let r = s.position.w / sqrt(depth * depth - s.position.w * s.position.w);
    let stretch = length(s.position.xyz - camera.position.xyz) / depth;
    let half_px = r * stretch / hp.thresholds.w + 1.0;
    let half = vec2<f32>(half_px * 2.0 * camera.viewport.z, half_px * 2.0 * camera.viewport.w);
    out.clip = vec4<f32>(c.xy / c.w + corner * half, 0.5, 1.0);
    return out;
}

@fragment
fn fs_splat(in: VsOut) -> @location(0) vec4<f32> {
    let px = vec2<i32>(in.clip.xy);
    let nb = textureLoad(g_normal, px, 0);
    if (nb.w < 0.5) {
        discard;
    }
    let b = textureLoad(g_position, px, 0).xyz;
    let n_b = normalize(nb.xyz);
    let s = samples[in.index];
    let a = s.position.xyz;
    let n_a = s.normal.xyz;
    let d = b - a;
    let len = length(d);
    let e1 = len / max(s.position.w, 1e-12);
    // 1 − n_a·n_b as ½‖n_a − n_b‖² (unit normals): exact 0 for equal normals.
    let dn = n_a - n_b;
    let e2 = sqrt(0.5 * dot(dn, dn)) / sqrt(max(1.0 - hp.thresholds.x, 1e-12));
    var e3 = 0.0;
    if (len > 0.0) {
        let ab = d / len;
        if (dot(ab, n_a) <= 0.0 || dot(-ab, n_b) <= 0.0) {
            e3 = sqrt(abs(dot(ab, n_a))) / sqrt(max(hp.thresholds.y, 1e-12));
        }
    }
    if (max(e1, max(e2, e3)) > 1.0) {
        discard;
    }
    let w = (1.0 - e1) * (1.0 - e2) * (1.0 - e3);
    return vec4<f32>(w * s.light.rgb, w);
}
