// Log-average luminance L̄w of Reinhard et al. [RSSF02] Eq. 1: exp(mean(log(δ + Lw))).
// Departure: the mean runs over pixels with Lw > 0 only — Reinhard's images have no empty
// background, and counting the black background of a lab scene would drive the automatic
// exposure to white.
// Two passes: cs_partial reduces each 64×16 tile to (Σ log, count) — each of 64 threads
// walks one column of 16 pixels, then a tree in workgroup memory (few barriers: they are
// what costs on a CPU rasteriser such as lavapipe); cs_final (one workgroup) sums the
// tiles. Fixed orders and trees: deterministic.

@group(0) @binding(0) var hdr: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> result: array<f32>;
@group(0) @binding(2) var<storage, read_write> partials: array<vec2<f32>>;

const N: u32 = 256u;
const TILE_W: u32 = 64u;
const TILE_H: u32 = 16u;
var<workgroup> partial: array<vec2<f32>, 256>;

// Tree reduction of partial[0..n] into partial[0] (n a power of two).
fn reduce(li: u32, n: u32) {
    workgroupBarrier();
    var stride = n / 2u;
    while (stride > 0u) {
        if (li < stride) {
            partial[li] = partial[li] + partial[li + stride];
        }
        workgroupBarrier();
        stride = stride / 2u;
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_partial(
    @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let size = textureDimensions(hdr);
    var acc = vec2<f32>(0.0);
    let x = wg.x * TILE_W + li;
    for (var r = 0u; r < TILE_H; r = r + 1u) {
        let y = wg.y * TILE_H + r;
        if (x < size.x && y < size.y) {
            let c = textureLoad(hdr, vec2<u32>(x, y), 0).rgb;
            let lw = dot(max(c, vec3<f32>(0.0)), vec3<f32>(0.2126, 0.7152, 0.0722));
            if (lw > 0.0) {
                acc = acc + vec2<f32>(log(1e-4 + lw), 1.0);
            }
        }
    }
    partial[li] = acc;
    reduce(li, TILE_W);
    if (li == 0u) {
        partials[wg.y * groups.x + wg.x] = partial[0];
    }
}

@compute @workgroup_size(256, 1, 1)
fn cs_final(@builtin(local_invocation_index) li: u32) {
    let size = textureDimensions(hdr);
    let tiles = ((size.x + TILE_W - 1u) / TILE_W) * ((size.y + TILE_H - 1u) / TILE_H);
    var acc = vec2<f32>(0.0);
    for (var i = li; i < tiles; i = i + N) {
        acc = acc + partials[i];
    }
    partial[li] = acc;
    reduce(li, N);
    if (li == 0u) {
        if (partial[0].y > 0.0) {
            result[0] = exp(partial[0].x / partial[0].y);
        } else {
            result[0] = 1.0;
        }
    }
}
