// Log-average luminance L̄w of Reinhard et al. [RSSF02] Eq. 1: exp(mean(log(δ + Lw))).
// Departure: the mean runs over pixels with Lw > 0 only — Reinhard's images have no empty
// background, and counting the black background of a lab scene would drive the automatic
// exposure to white.
// The compose (compose/compose.wgsl) reduces each of its TILE² tiles to (Σ log, count) in
// fixed point as it writes final.hdr, so that nothing reads final.hdr again (issue #38);
// cs_final (one workgroup) sums the tiles in a fixed order and tree: deterministic. The result is the
// exposure of the next frame's compose (and of this frame's tone-mapping pass when it runs).
@group(0) @binding(1) var<storage, read_write> result: array<f32>;
// Per tile: Σ log(δ + Lw) · LOG_SCALE and the count (compose/compose.wgsl).
@group(0) @binding(2) var<storage, read_write> partials: array<i32>;

const LOG_SCALE: f32 = 1048576.0;

const N: u32 = 256u;
var<workgroup> partial: array<vec2<f32>, 256>;

@compute @workgroup_size(256, 1, 1)
fn cs_final(@builtin(local_invocation_index) li: u32) {
    let tiles = arrayLength(&partials) / 2u;
    var acc = vec2<f32>(0.0);
    for (var i = li; i < tiles; i = i + N) {
        acc = acc + vec2<f32>(f32(partials[2u * i]) / LOG_SCALE, f32(partials[2u * i + 1u]));
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
