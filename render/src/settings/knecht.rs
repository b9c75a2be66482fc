//! The settings of Knecht's instant radiosity with imperfect shadow maps and temporal
//! coherence (002): the VPLs by hierarchical warping (§3.2), the ISM atlas and its point cloud
//! (§3.3), interleaved sampling (§3.4) and the confidence merge (§3.5). The passes are in
//! `passes/knecht/`, the CPU twin in `cpu::knecht`.

use crate::settings::pipeline::VplVisibility;
use crate::{settings_enum, settings_group};

settings_enum! {
    /// The shadow test of further bounces (Knecht 002 §3.6.1: a sample is "visible to the
    /// assigned VPL" by "a simple shadow test with the ISM from the assigned VPL").
    pub enum BounceShadowTest {
        /// The splatted distances as they are: no pull-push, no receiver normal offset
        /// (GI Lab before issue #15; light leaks through the maps' holes into the next
        /// bounce's VPLs).
        RawSplats = "raw splats",
        /// The maps after pull-push, tested with the gather's depth bias and receiver normal
        /// offset (`common/ism.wgsl`): one resolve and pull-push of the atlas per bounce.
        PulledMaps = "pulled maps, as the gather",
    }
    default PulledMaps
}

settings_enum! {
    /// Which texels the push phase of pull-push replaces besides holes (§2.6.5: "only those
    /// depth values are replaced that are far from the lower level depth value").
    pub enum PushBehind {
        /// Any texel farther than t_push behind the coarse value (the thesis, after
        /// Marroquim et al.): fills the background seen through holes in an occluder, but
        /// also grows every occluder by up to 2^levels texels at its silhouette.
        Everywhere = "anywhere (thesis)",
        /// Only where the four coarse texels around the texel are valid and agree within
        /// t_push, i.e. inside a surface, not at its silhouette (our reading: the holes in
        /// a dense cloud are filled without dilating the shadows).
        InsideSurfaces = "inside surfaces only",
    }
    default InsideSurfaces
}

settings_enum! {
    /// The distance a point's splat writes into the texels it covers.
    pub enum SplatDepth {
        /// The point's own distance in every texel of its box (Ritschel et al.'s box
        /// kernel): on surfaces seen at a slant the box stands out of the surface and
        /// shadows it.
        PointDistance = "the point's distance (box)",
        /// The distance along each texel's ray to the point's tangent plane, within ±2 r_s
        /// of the point's (a surfel: slanted surfaces stay flat in the map; our addition).
        TangentPlane = "its tangent plane (surfel)",
    }
    default TangentPlane
}

settings_group! {
    /// VPL visibility (stage 4): imperfect shadow maps (Knecht 002 §2.6.5) or a baseline.
    pub struct IsmSettings: "ism" {
        /// Points of the point cloud; each ISM gets points / N of them.
        points: u32 = 131072,
        unit "points", symbol "", range 1024..=262144, cost "one splat of a few texels per point", history false;
        /// Placement of the points on the triangles.
        placement: PointPlacement = PointPlacement::Halton,
        unit "", symbol "", range 0..=1, cost "free (built once)", history false;
        /// Side of each VPL's paraboloid map (a power of two). The default, 64², is for
        /// interactive rates on the software renderer (see `vpl.count`); the thesis uses 128².
        map_size: u32 = 64,
        unit "px", symbol "", range 32..=512, cost "atlas memory 4 B/texel² per VPL; pull-push time", history false;
        /// Pull-push levels (0: none; Ritschel et al. compute two).
        pull_push_levels: u32 = 2,
        unit "levels", symbol "", range 0..=5, cost "one pull and one push pass over the atlas per level", history false;
        /// Pull threshold: children farther than this behind the nearest one are not
        /// averaged, scaled by 2^level (fraction of the scene extent).
        pull_threshold: f32 = 0.05,
        unit "× extent", symbol "t_pull", range 0.0..=1.0, cost "free", history false;
        /// Push threshold: a texel farther than this behind the coarser level's value is
        /// replaced, scaled by 2^level (fraction of the scene extent).
        push_threshold: f32 = 0.05,
        unit "× extent", symbol "t_push", range 0.0..=1.0, cost "free", history false;
        /// Shadow test bias: the receiver counts as lit if its distance less this fraction of
        /// it is at most the stored distance (⚠[knecht.ism-depth-bias] the thesis gives no
        /// bias).
        depth_bias: f32 = 0.05,
        unit "× distance", symbol "", range 0.0..=0.5, cost "free", history false;
        /// Receiver offset along its normal before the shadow test, in texels of the map at the
        /// receiver's distance: a slope-aware bias against the receiving surface's own splats,
        /// which reach k texels around each point and on grazing surfaces are nearer the VPL
        /// than the receiver (⚠[knecht.ism-normal-offset] our addition; the thesis names no
        /// bias).
        normal_offset: f32 = 3.0,
        unit "texels", symbol "", range 0.0..=8.0, cost "free", history false;
        /// Scale of each point's splat (1: the disc of the point's area share).
        splat_scale: f32 = 1.0,
        unit "×", symbol "", range 0.1..=4.0, cost "splat texels grow with its square", history false;
        /// Largest splat half-size in texels (a near point covers at most a (2k+1)² box).
        max_splat_radius: u32 = 4,
        unit "texels", symbol "", range 0..=16, cost "up to (2k+1)² atomics per point", history false;
        /// Lift of each ISM's eye above its VPL along the VPL's normal, as a fraction of the
        /// scene's bounding radius, so that the surface the VPL lies on does not shadow it
        /// (⚠[knecht.ism-eye-offset] our addition; the thesis does not say how self-shadowing
        /// at the VPL is avoided).
        eye_offset: f32 = 0.005,
        unit "× scene radius", symbol "", range 0.0..=0.1, cost "free", history false;
        /// The further bounces' shadow test (§3.6.1, ⚠[knecht.bounce-shadow-test] "a simple
        /// shadow test with the ISM"): the raw splats, or the pulled maps with the gather's
        /// bias and normal offset.
        bounce_test: BounceShadowTest = BounceShadowTest::PulledMaps,
        unit "", symbol "", range 0..=1, cost "pulled maps: one resolve and pull-push of the atlas per extra bounce", history false;
        /// Which texels the push phase replaces besides holes (⚠[knecht.push-inside-surfaces]).
        /// The defaults of this and of `splat_depth` depart from the thesis (issue #15): with
        /// 131,072 points they took the default configuration from mean FLIP 0.097 to 0.064
        /// against the one-bounce path tracer (256², 16 frames), and `knecht-cornell-256` from
        /// 0.062 to 0.047 — the thesis' push grows every indirect shadow by up to 2^levels
        /// texels, and box splats shadow slanted surfaces unless large biases, which leak, are
        /// used. `presets/ritschel-ism.ron` keeps the original ISMs.
        push_behind: PushBehind = PushBehind::InsideSurfaces,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// What a splat writes: the point's distance, or its tangent plane's
        /// (⚠[knecht.splat-tangent-plane]; the thesis splats a box of the point's distance).
        splat_depth: SplatDepth = SplatDepth::TangentPlane,
        unit "", symbol "", range 0..=1, cost "one ray–plane intersection per splatted texel", history false;
    }
    legacy {
        /// Version 1: the VPL visibility; now `pipeline.vpl_visibility`.
        visibility: VplVisibility;
    }
}

settings_group! {
    /// Temporal coherence (stage 7; Knecht 002 §3.5): the confidence merge.
    pub struct TemporalSettings: "temporal" {
        /// Base confidence: the largest weight the previous frame gets (Eq. 3.4).
        c_base: f32 = 0.9,
        unit "", symbol "c_base", range 0.0..=1.0, cost "free", history false;
        /// Weight of the position change (Eq. 3.1; screen movement as a fraction of the image,
        /// depth change in units of z_far − z_near as the thesis' linear depth, Eq. 4.2).
        /// ⚠[knecht.w-pos] The thesis gives no value; 300 drops the confidence to 0 for a
        /// surface that moves 1/300 of the image per frame, and was tuned on the default
        /// scene's sliding sphere (tests/knecht_quality.rs: low on the sphere, high elsewhere).
        w_pos: f32 = 300.0,
        unit "", symbol "w_pos", range 0.0..=1000.0, cost "free", history false;
        /// Weight of the normal change (Eq. 3.2).
        w_normal: f32 = 2.0,
        unit "", symbol "w_normal", range 0.0..=100.0, cost "free", history false;
        /// Weight of the illumination change (Eq. 3.3; relative difference, cubed).
        w_illumination: f32 = 1.0,
        unit "", symbol "w_illumination", range 0.0..=100.0, cost "free", history false;
        /// Whether the geometry-aware filter runs before the merge (GI Lab) or after it (the
        /// thesis, §4 steps 11–12; ⚠[knecht.merge-order]); only with both chosen.
        order: MergeOrder = MergeOrder::FilterThenMerge,
        unit "", symbol "", range 0..=1, cost "free", history true;
        /// Merge the light demodulated (issue #51, ⚠[knecht.demodulated-merge]): the history
        /// keeps the demodulated filter's irradiance E and the specular light S apart, merges
        /// each with its own history and reflects E with the pixel's own colour, so that under
        /// motion a history fetched from a neighbouring texel brings its light, not its texture;
        /// off: the thesis' merge of the reflected light. After the demodulated filter
        /// (`interleave.demodulate`, filter then merge) or the HCB's splat (its `hcb.irradiance`);
        /// elsewhere the merge has no irradiance to keep.
        demodulate: bool = true,
        unit "", symbol "", range 0..=1, cost "a third ping-pong pair (16 B a pixel each) written and read", history true;
    }
    legacy {
        /// Version 1: the confidence merge on or off; now `pipeline.temporal = ConfidenceMerge`.
        enabled: bool;
    }
}

settings_group! {
    /// VPL generation of instant radiosity (stage 3; Knecht 002 §3.3, §4.3–4.4).
    pub struct VplSettings: "vpl" {
        /// Number of VPLs created per frame, over all lights. The default, 128, keeps the
        /// default technique (instant radiosity with ISMs and temporal coherence) near 8 frames
        /// per second on the software renderer at the window's default half resolution
        /// (measured 122 ms at 512×384 on lavapipe, 2 cores); the thesis' §5.2 uses 256
        /// (`presets/knecht-cornell-256.ron`).
        count: u32 = 128,
        unit "VPLs", symbol "N", range 1..=4096, cost "one ISM and one shading term per pixel per n² tiles per VPL", history false;
        /// Draw a new Halton set every frame (§5.2: the thesis changes every VPL each frame
        /// and lets temporal coherence smooth the result); off keeps the same set.
        new_set_each_frame: bool = true,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// Side of each light view's G-buffer and importance map (a power of two).
        light_gbuffer_size: u32 = 256,
        unit "px", symbol "", range 16..=2048, cost "one G-buffer render and one pyramid per light view", history false;
        /// Split the VPL budget over lights by their power; off splits it equally
        /// (⚠[knecht.budget-split]: the thesis samples one light, §4.4, and does not
        /// importance-sample a point light's cube faces, §4.4.3).
        split_by_power: bool = true,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// Distance clamp of the geometry term, 1 / max(d², d_min²) (Eq. 4.7;
        /// ⚠[knecht.distance-clamp] the thesis clamps at 1 scene unit). Larger values remove
        /// the bright spots near VPLs and bias.
        min_distance_m: f32 = 0.1,
        unit "m", symbol "d_min", range 0.0..=10.0, cost "free", history false;
        /// Mip level of the surfaces' colour texture in the light G-buffer (§4.3, render target
        /// 0: ⚠[knecht.albedo-mip] the thesis blurs the colour VPLs carry by a predefined mip
        /// level and gives no value; 4 averages 16×16 texels). Untextured surfaces are
        /// unaffected.
        albedo_mip: f32 = 4.0,
        unit "mip level", symbol "", range 0.0..=12.0, cost "free", history false;
        /// Light bounces (§3.6): 1 is the VPLs on the lit surfaces; each further bounce turns
        /// one point-cloud sample per VPL into a VPL of the next bounce, with its own ISM, and
        /// the gather adds all bounces.
        bounces: u32 = 1,
        unit "bounces", symbol "B", range 1..=6, cost "per extra bounce: N more ISMs (atlas × B), one splat of the cloud, one pass over the cloud, N more shading terms", history false;
        /// Which sample becomes the next bounce's VPL (§3.6.1; proportional is §6.1's future work).
        bounce_selection: BounceSelection = BounceSelection::Strongest,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// How further bounces are made: the thesis' one pass over the point cloud (§3.6.1)
        /// or the imperfect reflective shadow maps of Ritschel et al. it is measured against.
        bounce_method: BounceMethod = BounceMethod::PointCloud,
        unit "", symbol "", range 0..=1, cost "IRSM: a splat, an owner pass and a CDF over N IRSMs per bounce", history false;
        /// Side of each VPL's imperfect reflective shadow map (IRSM baseline; a power of two).
        irsm_size: u32 = 32,
        unit "px", symbol "", range 16..=128, cost "N IRSMs of this size² per bounce: splat fill, 16 B/texel", history false;
        /// How the per-pixel or interleaved gather and the exact-VPL reference reflect the
        /// VPLs' light at the shading point.
        receiver_brdf: ReceiverBrdf = ReceiverBrdf::Full,
        unit "", symbol "f_x", range 0..=1, cost "free", history true;
        /// The constant of Eq. 4.3's glossiness factor (b + SP'): 0.5 in the thesis. Smaller
        /// values send more VPLs to glossy surfaces, larger ones spread them by flux alone.
        importance_bias: f32 = 0.5,
        unit "", symbol "b", range 0.0..=10.0, cost "free", history false;
    }
}

impl VplSettings {
    /// Whether the gathers reflect the VPLs' light with the diffuse term alone
    /// (`vpl.receiver_brdf = DiffuseOnly`), the flag every VPL gather's uniform carries.
    pub fn diffuse_only_receiver(&self) -> bool {
        self.receiver_brdf == ReceiverBrdf::DiffuseOnly
    }
}

settings_group! {
    /// Interleaved sampling and the geometry-aware filter (stages 5–6; Knecht 002 §3.4.1).
    pub struct InterleaveSettings: "interleave" {
        /// Tiles per side: each VPL shades one pixel in n×n (1: every pixel gets every VPL).
        n: u32 = 4,
        unit "tiles", symbol "n", range 1..=8, cost "shading time falls as 1/n²; the filter reads n² pixels", history false;
        /// Depth threshold: neighbours whose depth differs by more than α in the thesis' linear
        /// depth (view depth / (z_far − z_near), Eq. 4.2) are not averaged.
        alpha: f32 = 0.01,
        unit "× (z_far − z_near)", symbol "α", range 0.0..=1.0, cost "free", history false;
        /// Normal threshold: neighbours whose normal's dot product with the centre's is below β are not averaged.
        beta: f32 = 0.8,
        unit "", symbol "β", range -1.0..=1.0, cost "free", history false;
        /// The thesis' three passes (§3.4.1): split the G-buffer into tiles, gather in the
        /// split layout, merge back; off: one pass that gathers each split pixel's tile at its
        /// own pixel, the same light without the split copies (issue #38). On to inspect
        /// `interleave.split.*` and `indirect.accum`.
        split_passes: bool = false,
        unit "", symbol "", range 0..=1, cost "three passes and the split G-buffer's traffic (≈ 3× the fused pass's)", history false;
        /// Filter the light without the albedo (issue #51, ⚠[knecht.demodulated-filter]): the
        /// gather keeps its irradiance apart (`indirect.irradiance`), the filter averages it and
        /// the specular light over the window and reflects the irradiance with each pixel's own
        /// colour, so textures stay sharp; off: the thesis' filter of the reflected light.
        /// With `temporal.order = MergeThenFilter` the filter reads the merged history, which
        /// holds no irradiance, and filters the reflected light.
        demodulate: bool = true,
        unit "", symbol "", range 0..=1, cost "the gather writes a second half-float target; the filter reads it and the albedo", history false;
    }
    legacy {
        /// Version 1: the filter on or off; now `pipeline.reconstruction = GeometryAwareFilter`.
        filter: bool;
    }
}

settings_enum! {
    /// How the point cloud places its samples.
    pub enum PointPlacement {
        /// Independent random samples (Ritschel et al.).
        Random = "random",
        /// Halton low-discrepancy samples (Knecht §6.1's future work).
        Halton = "Halton (quasi-random)",
    }
    default Halton
}

settings_enum! {
    /// How a shading point reflects the light the VPLs send it (stage 6's VPL gather, Knecht
    /// 002 Eq. 4.9 at the receiver).
    pub enum ReceiverBrdf {
        /// The full BRDF, f_x = c·DI/π + SI·(SP + 8)/(8π)·(n·h)^SP (Eq. 4.9, energy-normalised).
        Full = "full BRDF (Eq. 4.9)",
        /// The diffuse term alone, c·DI/π: what the HCB's splatted irradiance gives (Nguyen
        /// §4 reflects it with c·DI/π), so that the HCB and the per-pixel or interleaved
        /// gather compare like for like.
        DiffuseOnly = "diffuse only (as the HCB)",
    }
    default Full
}

settings_enum! {
    /// The order of the geometry-aware filter (stage 6) and the confidence merge (stage 7)
    /// when both run.
    pub enum MergeOrder {
        /// Filter the merged tiles, then merge with the history (GI Lab's default): the
        /// confidence's illumination term (Eq. 3.3) compares an estimate from all N VPLs
        /// with the history, and the history holds filtered light.
        FilterThenMerge = "filter, then merge (GI Lab)",
        /// The thesis' order (§4 steps 11–12): merge each pixel's N/n² VPLs with the
        /// history, then filter; the history holds unfiltered light and Eq. 3.3 sees the
        /// tiles' noise (Fig. 3.5's confidence).
        MergeThenFilter = "merge, then filter (thesis §4)",
    }
    default FilterThenMerge
}

settings_enum! {
    /// Which point-cloud sample becomes the next bounce's VPL (Knecht 002 §3.6.1, §6.1).
    pub enum BounceSelection {
        /// The sample with the largest contribution (the thesis' depth-test selection).
        Strongest = "strongest (thesis)",
        /// A sample drawn with probability proportional to its contribution (the thesis'
        /// future work, §6.1): unbiased, weaker regions get VPLs too.
        Proportional = "proportional to contribution",
    }
    default Strongest
}

settings_enum! {
    /// How the VPLs of further bounces are made (Knecht 002 §3.6).
    pub enum BounceMethod {
        /// One sample per VPL chosen from the point cloud in one pass (§3.6.1).
        PointCloud = "point cloud, one pass (Knecht)",
        /// Imperfect reflective shadow maps, importance-sampled (Ritschel et al. 2008).
        Irsm = "IRSM, importance-sampled (Ritschel)",
    }
    default PointCloud
}
