// Splats summed in compute instead of quads added by blending (issue #38; docs/architecture.md,
// "Read-backs, waits and the frame's traffic"): shared by Gautron's records (003, "From Octree
// to Splatting") and the HCB's samples (Nguyen §4.3). The items of one splat are numbered
// j = 0, 1, … in the order the blending would draw them.
// - bins_mark (one invocation per item): its rectangle in NDC into `bin_rects[j]`, and bit j
//   into the mask of every BIN × BIN pixel square the rectangle overlaps;
// - bins_collect (a 16 × 16 workgroup inside one square): the items whose rectangle overlaps
//   the workgroup's pixels;
// - bins_next: those items in increasing j, so that each pixel adds them in the blending's
//   order and gets the same sums, bit for bit.
// Rust twin: passes::bins.

// Rust twin: passes::bins::BinParams.
struct BinParams {
    // x: squares across, y: squares down, z: mask words per square (items / 32), w: BIN (px)
    bins: vec4<u32>,
    // x: 1 to add to the previous sums, 0 to start from zero
    mode: vec4<u32>,
}

// Most mask words per square: 65,536 items (passes::bins::MAX_ITEMS).
const BIN_MAX_WORDS: u32 = 2048u;
// bins_next's end.
const BIN_NONE: u32 = 0xffffffffu;

@group(1) @binding(0) var<uniform> bin_params: BinParams;
// Per square, one bit per item: bit j of word j / 32.
@group(1) @binding(1) var<storage, read_write> bin_mask: array<atomic<u32>>;
// Per item, its rectangle in NDC (x0, y0, x1, y1; empty when x0 > x1).
@group(1) @binding(2) var<storage, read_write> bin_rects: array<vec4<f32>>;

// Items the bins hold (the remainder of a larger splat is left to the caller).
fn bins_capacity() -> u32 {
    return bin_params.bins.z * 32u;
}

// Item j's rectangle r (NDC) on a `size`-pixel screen into the squares it overlaps.
fn bins_mark(j: u32, r: vec4<f32>, size: vec2<f32>) {
    bin_rects[j] = r;
    if (r.x > r.z || r.y > r.w) {
        return;
    }
    // The pixels whose centres may lie inside, one pixel wider on each side (conservative).
    let x0 = (r.x + 1.0) * 0.5 * size.x - 1.5;
    let x1 = (r.z + 1.0) * 0.5 * size.x + 0.5;
    let y0 = (1.0 - r.w) * 0.5 * size.y - 1.5;
    let y1 = (1.0 - r.y) * 0.5 * size.y + 0.5;
    let last = vec2<f32>(size - 1.0);
    let lo = vec2<u32>(clamp(vec2<f32>(x0, y0), vec2<f32>(0.0), last)) / bin_params.bins.w;
    let hi = vec2<u32>(clamp(vec2<f32>(x1, y1), vec2<f32>(0.0), last)) / bin_params.bins.w;
    let word = j / 32u;
    let bit = 1u << (j % 32u);
    for (var by = lo.y; by <= min(hi.y, bin_params.bins.y - 1u); by = by + 1u) {
        for (var bx = lo.x; bx <= min(hi.x, bin_params.bins.x - 1u); bx = bx + 1u) {
            atomicOr(&bin_mask[(by * bin_params.bins.x + bx) * bin_params.bins.z + word], bit);
        }
    }
}

// The square's items that overlap this workgroup's pixels, and which of those words are not
// empty (one bit per word).
var<workgroup> bin_kept: array<u32, BIN_MAX_WORDS>;
var<workgroup> bin_summary: array<atomic<u32>, 64>;

// NDC of the centre of pixel p (y down in pixels, up in NDC) on a screen of 1 / `inv_size`
// pixels (the camera's viewport.zw).
fn bin_centre_ndc(p: vec2<u32>, inv_size: vec2<f32>) -> vec2<f32> {
    return vec2<f32>((f32(p.x) + 0.5) * inv_size.x * 2.0 - 1.0, 1.0 - (f32(p.y) + 0.5) * inv_size.y * 2.0);
}

// Collects the items j < `end` of the square holding pixel `origin` whose rectangle overlaps
// the 16 × 16 pixels from `origin` (their centres' NDC box; `inv_size` as bin_centre_ndc's).
// Every invocation of the workgroup calls it (it has barriers); it returns the words to walk.
fn bins_collect(li: u32, origin: vec2<u32>, end: u32, inv_size: vec2<f32>) -> u32 {
    // The NDC range of the workgroup's pixel centres (y: top is the larger).
    let a = bin_centre_ndc(origin, inv_size);
    let b = bin_centre_ndc(origin + vec2<u32>(15u), inv_size);
    let square = (origin.y / bin_params.bins.w) * bin_params.bins.x + origin.x / bin_params.bins.w;
    let words = min(min(bin_params.bins.z, BIN_MAX_WORDS), (end + 31u) / 32u);
    if (li < 64u) {
        atomicStore(&bin_summary[li], 0u);
    }
    workgroupBarrier();
    for (var w = li; w < words; w = w + 256u) {
        var m = atomicLoad(&bin_mask[square * bin_params.bins.z + w]);
        var keep = 0u;
        while (m != 0u) {
            let j = firstTrailingBit(m);
            m = m & (m - 1u);
            let r = bin_rects[w * 32u + j];
            if (r.x <= b.x && r.z >= a.x && r.y <= a.y && r.w >= b.y) {
                keep = keep | (1u << j);
            }
        }
        bin_kept[w] = keep;
        if (keep != 0u) {
            atomicOr(&bin_summary[w / 32u], 1u << (w % 32u));
        }
    }
    workgroupBarrier();
    return words;
}

// A walk over the collected items in increasing j.
struct BinCursor {
    // the summary word, its remaining bits, the mask word, its remaining bits, the words
    s: u32,
    sw: u32,
    w: u32,
    m: u32,
    words: u32,
}

fn bins_start(words: u32) -> BinCursor {
    var c = BinCursor(0u, 0u, 0u, 0u, words);
    if (words > 0u) {
        c.sw = atomicLoad(&bin_summary[0]);
    }
    return c;
}

// The next collected item whose rectangle holds the NDC point `p`, or BIN_NONE.
fn bins_next(c: ptr<function, BinCursor>, p: vec2<f32>) -> u32 {
    loop {
        if ((*c).m != 0u) {
            let j = (*c).w * 32u + firstTrailingBit((*c).m);
            (*c).m = (*c).m & ((*c).m - 1u);
            let r = bin_rects[j];
            if (p.x < r.x || p.x > r.z || p.y < r.y || p.y > r.w) {
                continue;
            }
            return j;
        }
        if ((*c).sw != 0u) {
            (*c).w = (*c).s * 32u + firstTrailingBit((*c).sw);
            (*c).sw = (*c).sw & ((*c).sw - 1u);
            (*c).m = bin_kept[(*c).w];
            continue;
        }
        (*c).s = (*c).s + 1u;
        if ((*c).s >= ((*c).words + 31u) / 32u) {
            return BIN_NONE;
        }
        (*c).sw = atomicLoad(&bin_summary[(*c).s]);
    }
    return BIN_NONE;
}
