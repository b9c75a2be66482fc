// Soler et al.'s visibility grid (004 §4 "Visibility", after Eisemann & Décoret's solid
// voxelization): one column of `slices` bits per texel of a level, words of 32 bits, bit s of
// a column set where the slice s of view depth lies inside a solid. Slice s covers view
// depths z0 + (z1 − z0)·[s, s + 1)/slices. CPU twin: cpu::soler::{slice_of, column_mask}.

// Rust twin: passes::soler::voxels::VoxelParams.
struct VoxelParams {
    // x: W, y: H (the grid's columns), z: 32-bit words per column, w: slices
    grid: vec4<u32>,
    // x: z0, y: z1 (view depths of the grid's front and back), z: G-buffer pixels per grid
    // texel (2^k), w: the viewer's slice (< 0: the column's filled fraction)
    depth: vec4<f32>,
    // x: the toggles' slope bias b (× the fragment's depth change across one texel), y: its
    // cap (slices); z, w unused
    toggle: vec4<f32>,
}

// The slice of view depth z: 0 in front of the grid, `slices` behind it.
fn voxel_slice(z: f32, p: VoxelParams) -> i32 {
    let s = floor((z - p.depth.x) / max(p.depth.y - p.depth.x, 1e-12) * f32(p.grid.w));
    return i32(clamp(s, 0.0, f32(p.grid.w)));
}

// The depth a surface crossing toggles its column at (cpu::soler::toggle_depth): its depth z
// at the texel's centre, moved back by b·(|∂z/∂x| + |∂z/∂y|) (b = ½: to the texel's farthest
// corner), at most the cap, where the surface faces the viewer (it enters a solid: the column
// turns solid only behind the whole texel's surface, as the coarser grids' AND keeps only what
// all four finer columns hold). b = 0 is the paper's toggle at the centre's depth, which hides
// paths that pass a grazing surface's texel in front of the surface. A surface facing away
// (it leaves a solid) stays at its centre's depth: moved forward, near a silhouette it would
// cross its entry and the XOR would fill the space in front of the object; the paths the
// march tests run between visible surfaces, in front of the solids they pass.
fn voxel_toggle_depth(z: f32, slope: f32, facing: bool, p: VoxelParams) -> f32 {
    let cap = p.toggle.y * (p.depth.y - p.depth.x) / f32(max(p.grid.w, 1u));
    let push = min(p.toggle.x * slope, cap);
    return select(z, z + push, facing);
}

// Word w's bits of the slices first … slices − 1 (what one surface at slice `first` toggles).
fn voxel_mask_from(first: i32, w: u32, slices: u32) -> u32 {
    let lo = i32(w * 32u);
    let hi = min(lo + 32, i32(slices));
    if (first >= hi) {
        return 0u;
    }
    var mask = 0xffffffffu;
    if (first > lo) {
        mask = mask << u32(first - lo);
    }
    if (hi - lo < 32) {
        mask = mask & ((1u << u32(hi - lo)) - 1u);
    }
    return mask;
}
