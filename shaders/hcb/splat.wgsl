// Coherence-weighted splatting of the HCB samples (Nguyen et al. §4.2–4.3). Each sample
// draws a screen quad bounding its sphere (centre a, radius a^w); every pixel b under it
// gets, when b is coherent to a (Eq. 9: the error of Eq. 8 at most 1), the weight of Eq. 10
// times the sample's light in rgb and the weight in alpha, summed by additive blending
// (`hcb.weight_sum`); beside it, the weighted direction sums of the glossy receiver
// (`hcb.weight_sum.direction`: xyz Σ w·Σ lum(E_k) ω_k). cs_normalize then divides (Eq. 11). CPU twin: cpu::hcb::{coherence_errors,
// weight}.
//
// `hcb.splat`: Blend, the paper's way: vs_splat/fs_splat, one quad per sample. Binned, GI
// Lab's (issue #38: the quads' overdraw into a 128-bit blended target is the HCB's cost on a
// GPU): cs_bin marks each sample in the 64-pixel squares its quad overlaps, cs_accumulate adds
// each pixel's samples in increasing index, the blending's order, so that the sums are the
// same (common/bins.wgsl). Samples beyond the bins' 65,536 are drawn as quads after them
// (cs_bin writes their draw's arguments into `rest`).
#import common/camera.wgsl
#import hcb/common.wgsl
#import common/bins.wgsl

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> hp: HcbParams;
@group(0) @binding(2) var<storage, read> samples: array<HcbSample>;
@group(0) @binding(3) var g_position: texture_2d<f32>;
@group(0) @binding(4) var g_normal: texture_2d<f32>;
// the sample counter: word 1 is where the new samples start (§5.2; hp.level.x = 1)
@group(0) @binding(5) var<storage, read> counter: array<u32>;
// Binned only: the splat's draw arguments (hcb_args: word 1 the count of every sample, word 9
// of the new ones), the sums to add to (hp.level.x = 1), the sums, the remainder's draw.
@group(0) @binding(6) var<storage, read> args: array<u32>;
@group(0) @binding(7) var prev_sum: texture_2d<f32>;
@group(0) @binding(8) var out_sum: texture_storage_2d<rgba32float, write>;
@group(0) @binding(9) var<storage, read_write> rest: array<u32, 4>;
@group(0) @binding(10) var prev_dir: texture_2d<f32>;
@group(0) @binding(11) var out_dir: texture_storage_2d<rgba32float, write>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) index: u32,
}

@vertex
fn vs_splat(@builtin(vertex_index) v: u32, @builtin(instance_index) instance: u32) -> VsOut {
    var out: VsOut;
    let i = instance + select(0u, counter[1], hp.level.x == 1u);
    out.index = i;
    let rect = splat_rect(samples[i]);
    out.clip = vec4<f32>(select(rect.xy, rect.zw, quad_corner(v) > vec2<f32>(0.0)), 0.5, 1.0);
    return out;
}

// The sample's quad in NDC (x0, y0, x1, y1): hcb/common.wgsl's splat_quad with this frame's
// camera.
fn splat_rect(s: HcbSample) -> vec4<f32> {
    return splat_quad(s, camera.view, camera.view_proj, camera.position.xyz, camera.viewport.zw, hp.thresholds.w);
}

struct FsOut {
    @location(0) sum: vec4<f32>,
    @location(1) dir: vec4<f32>,
}

@fragment
fn fs_splat(in: VsOut) -> FsOut {
    let px = vec2<i32>(in.clip.xy);
    let nb = textureLoad(g_normal, px, 0);
    if (nb.w < 0.5) {
        discard;
    }
    let s = samples[in.index];
    let v = splat_value(s, textureLoad(g_position, px, 0).xyz, normalize(nb.xyz), hp.thresholds);
    if (v.a < 0.0) {
        discard;
    }
    return FsOut(v, splat_direction(s, v));
}

// The samples of this splat: (first index, count).
fn splat_range() -> vec2<u32> {
    let new_only = hp.level.x == 1u;
    return vec2<u32>(select(0u, counter[1], new_only), args[select(1u, 9u, new_only)]);
}

// Binned: sample first + j into the squares of its quad; the samples beyond the bins'
// capacity into the remainder's draw (first instance: the capacity).
@compute @workgroup_size(64, 1, 1)
fn cs_bin(@builtin(global_invocation_id) gid: vec3<u32>) {
    let range = splat_range();
    let binned = min(range.y, bins_capacity());
    if (gid.x == 0u) {
        rest = array<u32, 4>(6u, range.y - binned, 0u, bins_capacity());
    }
    if (gid.x >= binned) {
        return;
    }
    bins_mark(gid.x, splat_rect(samples[range.x + gid.x]), camera.viewport.xy);
}

// Binned: each pixel adds the samples of its square that reach it, in increasing index.
@compute @workgroup_size(16, 16, 1)
fn cs_accumulate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let size = textureDimensions(out_sum);
    let range = splat_range();
    let origin = wg.xy * 16u;
    let words = bins_collect(li, origin, range.y, camera.viewport.zw);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    var sum = vec4<f32>(0.0);
    var dir = vec4<f32>(0.0);
    if (bin_params.mode.x == 1u) {
        sum = textureLoad(prev_sum, px, 0);
        dir = textureLoad(prev_dir, px, 0);
    }
    let nb = textureLoad(g_normal, px, 0);
    if (nb.w >= 0.5) {
        let b = textureLoad(g_position, px, 0).xyz;
        let n_b = normalize(nb.xyz);
        let c = bin_centre_ndc(gid.xy, camera.viewport.zw);
        var cursor = bins_start(words);
        for (var j = bins_next(&cursor, c); j != BIN_NONE; j = bins_next(&cursor, c)) {
            let s = samples[range.x + j];
            let v = splat_value(s, b, n_b, hp.thresholds);
            if (v.a >= 0.0) {
                sum = sum + v;
                dir = dir + splat_direction(s, v);
            }
        }
    }
    textureStore(out_sum, px, sum);
    textureStore(out_dir, px, dir);
}
