// Log-average luminance L̄w of Reinhard et al. [RSSF02] Eq. 1: exp(mean(log(δ + Lw))).
// Departure: the mean runs over pixels with Lw > 0 only — Reinhard's images have no empty
// background, and counting the black background of a lab scene would drive the automatic
// exposure to white. One workgroup strides over all pixels in a fixed order so the result
// is deterministic.
#import common/fullscreen.wgsl

@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> result: array<f32>;

const N: u32 = 256u;
var<workgroup> partial: array<vec2<f32>, 256>;

@compute @workgroup_size(256, 1, 1)
fn cs_main(@builtin(local_invocation_index) li: u32) {
    let size = textureDimensions(hdr);
    let total = size.x * size.y;
    var acc = vec2<f32>(0.0);
    for (var i = li; i < total; i = i + N) {
        let c = textureLoad(hdr, vec2<u32>(i % size.x, i / size.x), 0).rgb;
        let lw = dot(max(c, vec3<f32>(0.0)), vec3<f32>(0.2126, 0.7152, 0.0722));
        if (lw > 0.0) {
            acc = acc + vec2<f32>(log(1e-4 + lw), 1.0);
        }
    }
    partial[li] = acc;
    workgroupBarrier();
    var stride = N / 2u;
    while (stride > 0u) {
        if (li < stride) {
            partial[li] = partial[li] + partial[li + stride];
        }
        workgroupBarrier();
        stride = stride / 2u;
    }
    if (li == 0u) {
        if (partial[0].y > 0.0) {
            result[0] = exp(partial[0].x / partial[0].y);
        } else {
            result[0] = 1.0;
        }
    }
}
