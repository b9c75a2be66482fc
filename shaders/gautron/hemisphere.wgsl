enable clip_distances;
// The records' hemispheres by rasterization (Gautron et al. 003, "Simple plane sampling"):
// each new record's wide camera (aperture 126.87° by default, Larsen et al.) renders the scene
// into its tile of one atlas, every tile in the same draws: instance i·S + s is scene draw i
// seen by slot s, the vertex is moved into slot s's tile and clipped to it by four clip
// distances (the record's own frustum sides), so no triangle reaches a neighbour's tile.
// The fragment stage is the G-buffer's (stage 1), so that the direct pass lights the atlas
// exactly as it lights the screen (`direct.wgsl`'s cs_atlas, viewed from each record); it
// writes the scene draw's index where the screen writes its motion (the atlas has none), so
// that the reduction knows which objects a record saw (the record cache's invalidation).
#import gbuffer/gbuffer.wgsl
#import gautron/common.wgsl


@group(0) @binding(1) var<storage, read> hemispheres: array<HemisphereCamera>;
@group(0) @binding(2) var<uniform> params: GautronParams;

struct HemiOut {
    @builtin(position) clip: vec4<f32>,
    @builtin(clip_distances) clip_distances: array<f32, 4>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) cur_clip: vec4<f32>,
    @location(4) prev_clip: vec4<f32>,
    @location(5) @interpolate(flat) object: u32,
}

@vertex
fn vs_hemisphere(v: VsIn, @builtin(instance_index) instance: u32) -> HemiOut {
    let slots = u32(params.creation.y);
    let object = instance / slots;
    let cam = hemispheres[instance % slots];
    let inst = instances[object];
    let world = inst.model * vec4<f32>(v.position, 1.0);
    let clip = cam.view_proj * world;
    var o: HemiOut;
    o.clip_distances[0] = clip.w - clip.x;
    o.clip_distances[1] = clip.w + clip.x;
    o.clip_distances[2] = clip.w - clip.y;
    o.clip_distances[3] = clip.w + clip.y;
    o.clip = vec4<f32>(clip.xy * cam.tile.zw + cam.tile.xy * clip.w, clip.zw);
    o.world = world.xyz;
    o.normal = (inst.normal_matrix * vec4<f32>(v.normal, 0.0)).xyz;
    o.uv = v.uv;
    o.cur_clip = o.clip;
    o.prev_clip = o.clip;
    o.object = object;
    return o;
}

// The tiles of a round's records cleared by one quad each (instance s: slot s's tile, at the
// far depth), drawn first in a pass that loads the atlas, instead of clearing the whole atlas:
// a round of few records, or none (the HCB mix's chunks past its sample count), then costs
// what its tiles cost (issue #53). The same values as the G-buffer's clear: zero, depth 1.
struct TileClearOut {
    @builtin(position) clip: vec4<f32>,
}

@vertex
fn vs_tile_clear(@builtin(vertex_index) v: u32, @builtin(instance_index) s: u32) -> TileClearOut {
    var corners = array<vec2<f32>, 6>(
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(-1.0, -1.0), vec2<f32>(1.0, 1.0), vec2<f32>(-1.0, 1.0),
    );
    let tile = hemispheres[s].tile;
    var o: TileClearOut;
    o.clip = vec4<f32>(corners[v % 6u] * tile.zw + tile.xy, 1.0, 1.0);
    return o;
}

@fragment
fn fs_tile_clear() -> FsOut {
    let zero = vec4<f32>(0.0);
    return FsOut(zero, zero, zero, zero, zero, zero);
}

// HemiOut without the clip distances (a vertex output only).
struct HemiIn {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) cur_clip: vec4<f32>,
    @location(4) prev_clip: vec4<f32>,
    @location(5) @interpolate(flat) object: u32,
}

@fragment
fn fs_hemisphere(i: HemiIn, @builtin(front_facing) front: bool) -> FsOut {
    var v: VsOut;
    v.clip = i.clip;
    v.world = i.world;
    v.normal = i.normal;
    v.uv = i.uv;
    v.cur_clip = i.cur_clip;
    v.prev_clip = i.prev_clip;
    var o = gbuffer_fragment(v, front);
    // x: the scene draw's index (exact in f32 below 2²⁴)
    o.motion = vec4<f32>(f32(i.object), 0.0, 0.0, 0.0);
    return o;
}
