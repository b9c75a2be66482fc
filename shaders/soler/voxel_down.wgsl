// The visibility grid of the next coarser level (Soler et al. 004 §4 "Visibility"): a coarse
// column is the AND of the (up to) four fine columns of its 2×2 block, slice by slice — a
// coarse voxel is solid only where all its sub-voxels are. Also writes the viewer's image of
// the fine grid (`soler.voxels.k`): the chosen slice's bit, or the column's filled fraction.
// CPU twin: cpu::soler::and_down.
#import soler/voxel_common.wgsl

@group(0) @binding(0) var<uniform> params: VoxelParams;
@group(0) @binding(1) var<storage, read> fine: array<u32>;
// The coarse grid (`params.grid` is the fine one's; the coarse size is ⌈W/2⌉ × ⌈H/2⌉).
@group(0) @binding(2) var<storage, read_write> coarse: array<u32>;

@compute @workgroup_size(8, 8, 1)
fn cs_down(@builtin(global_invocation_id) gid: vec3<u32>) {
    let cw = (params.grid.x + 1u) / 2u;
    let ch = (params.grid.y + 1u) / 2u;
    if (gid.x >= cw || gid.y >= ch) {
        return;
    }
    let words = params.grid.z;
    for (var w = 0u; w < words; w = w + 1u) {
        var m = 0xffffffffu;
        for (var i = 0u; i < 4u; i = i + 1u) {
            let fx = 2u * gid.x + (i & 1u);
            let fy = 2u * gid.y + (i >> 1u);
            if (fx < params.grid.x && fy < params.grid.y) {
                m = m & fine[(fy * params.grid.x + fx) * words + w];
            }
        }
        coarse[(gid.y * cw + gid.x) * words + w] = m;
    }
}
