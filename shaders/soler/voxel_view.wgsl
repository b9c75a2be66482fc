// The viewer's image of one level's visibility grid (`soler.voxels.k`, Soler et al. 004 §4
// "Visibility"): r the bit of the slice `params.depth.w` (< 0: the column's filled fraction),
// g 1 where the column ends inside a solid (parity left open: a mesh that is not closed, or a
// room's wall seen from inside, whose back half-space counts as solid).
#import soler/voxel_common.wgsl

@group(0) @binding(0) var<uniform> params: VoxelParams;
@group(0) @binding(1) var<storage, read> grid: array<u32>;
@group(0) @binding(2) var out_view: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_view(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.grid.x || gid.y >= params.grid.y) {
        return;
    }
    let words = params.grid.z;
    let base = (gid.y * params.grid.x + gid.x) * words;
    var filled = 0u;
    for (var w = 0u; w < words; w = w + 1u) {
        filled = filled + countOneBits(grid[base + w]);
    }
    var r = f32(filled) / f32(max(params.grid.w, 1u));
    let s = i32(params.depth.w);
    if (params.depth.w >= 0.0 && s < i32(params.grid.w)) {
        r = f32((grid[base + u32(s) / 32u] >> (u32(s) % 32u)) & 1u);
    }
    let last = params.grid.w - 1u;
    let open = f32((grid[base + last / 32u] >> (last % 32u)) & 1u);
    textureStore(out_view, gid.xy, vec4<f32>(r, open, 0.0, 1.0));
}
