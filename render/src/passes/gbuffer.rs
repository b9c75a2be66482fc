//! Stage 1, the camera G-buffer (Knecht 002 §4.2, movement buffer §3.5.1).
//! Shader: `shaders/gbuffer/gbuffer.wgsl`.
//!
//! ⚠[knecht.gbuffer-precision] Departure from the thesis' four 32-bit targets: we keep full precision (the linear
//! depth of Eq. 4.2 unnormalised in `R32Float`; normals in `Rgba16Float`, the camera's packed
//! octahedrally in one word each, [`PACKED_NORMAL_FORMAT`]) instead of packing normal.z into
//! the sign of SI (Eq. 4.1), because a lab must show exact values. The camera's
//! target 0 is that depth alone (issue #53; docs/architecture.md "The camera G-buffer's
//! position"): the passes rebuild the point from it, and `gbuffer.position` (world position,
//! depth in w) is filled from it when read (`passes::gbuffer_position`); the light views'
//! G-buffers keep the position in `Rgba32Float`. The thesis
//! has no emitters; `gbuffer.emission` carries glTF emission so that emissive surfaces
//! (the classic Cornell box's light quad) show in the direct light.

use crate::counters::prelude::*;
use crate::gpu::bindings::{Bindings, Kind, binding};

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::scene::SceneState;
use crate::scene::upload::GpuScene;

pub use super::gbuffer_position::POSITION_FORMAT;
/// The camera G-buffer's target 0 (issue #53): the linear view depth alone (Eq. 4.2's depth,
/// unnormalised, scene units), 4 bytes a pixel instead of the position's 16. The passes
/// rebuild the point from it (`shaders/common/camera.wgsl` `world_from_linear_depth`), and
/// `gbuffer.position` is filled from it only when something reads it
/// (`passes::gbuffer_position`).
pub const LINEAR_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The camera G-buffer's normal target (issue #53, docs/architecture.md "The camera
/// G-buffer's normal"): the normal's octahedral coordinates as two 16-bit snorms in one word
/// (`shaders/common/normal.wgsl`, CPU twin `cpu::knecht::pack_normal`), 4 bytes a pixel
/// instead of 8 and under 10⁻⁴ rad from the shaded normal; [`NO_NORMAL`] where no geometry
/// covers the pixel. `gbuffer.normal` ([`NORMAL_FORMAT`]) is unpacked from it when read
/// (`gbuffer_position::normal_pass`).
pub const PACKED_NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// The packed normal of a pixel no geometry covers (`NO_NORMAL` in `shaders/common/normal.wgsl`).
pub use crate::cpu::knecht::NO_NORMAL;
pub const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const MATERIAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The camera G-buffer's material target (issue #53): SI and SP alone, the two values every
/// pass reads, 4 bytes a pixel instead of 8. `gbuffer.material` (SI, SP, metallic, roughness,
/// [`MATERIAL_FORMAT`]) is filled from it and the albedo's DI when read
/// (`gbuffer_position::material_pass`): metallic = 1 − DI, and the roughness that SP shades
/// (SP = 2/α² − 2, α = r², clamped to [1, 4096]: r between 0.149 and 0.904).
pub const SHADING_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// The movement buffer (Knecht 002 §3.5.1) in pixels: half floats (issue #38), a step of
/// 1/256 px below 4 px of motion and 1/32 px at 32–64 px, far below what the histories'
/// bilinear lookups resolve; z: the point's linear depth in the previous frame with the
/// previous object transform (relative step 4.9e-4; Soler et al.'s temporal rejection, 004
/// §4, issue #41), w: 1 on covered pixels.
pub const MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// The camera's movement buffer while no step reads the previous depth (issue #53): Δx and Δy
/// alone, 4 bytes a pixel instead of [`MOTION_FORMAT`]'s 8. Only Soler et al.'s temporal
/// filter reads z (`GBufferPass::ensure_motion_depth`); Knecht's movement buffer (§3.5.1) is
/// the offset alone.
pub const CAMERA_MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
pub const EMISSION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The camera's bind group (group 0 of the G-buffer's raster, read by the screen-space
/// passes too): each G-buffer (the frame's, each light's, Gautron's hemispheres, Soler's
/// voxels) makes its own layout and group from it under its own label.
pub const CAMERA_BINDINGS: Bindings = Bindings {
    label: "gbuffer.camera",
    shader: "gbuffer/gbuffer.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT.union(wgpu::ShaderStages::COMPUTE),
    list: &[binding(0, "camera", Kind::Uniform)],
};
/// The G-buffer textures of one frame.
pub struct GBuffer {
    /// World position (xyz) and linear depth (w): a render target of the light views and the
    /// hemispheres; for the camera, filled from `linear_depth` when read (issue #53).
    pub position: wgpu::Texture,
    /// The camera's target 0, the linear depth ([`LINEAR_DEPTH_FORMAT`]); None for the light
    /// views and the hemispheres, which render the position itself.
    pub linear_depth: Option<wgpu::Texture>,
    /// Unit normal (xyz) and coverage (w): a render target of the light views and the
    /// hemispheres; for the camera, unpacked from `packed_normal` when read (issue #53).
    pub normal: wgpu::Texture,
    /// The camera's target 1, its normals packed ([`PACKED_NORMAL_FORMAT`]); None for the
    /// other G-buffers.
    pub packed_normal: Option<wgpu::Texture>,
    pub albedo: wgpu::Texture,
    /// SI, SP, metallic and roughness ([`MATERIAL_FORMAT`]); the camera's holds SI and SP
    /// alone ([`SHADING_FORMAT`]) and fills `material_view` when read.
    pub material: wgpu::Texture,
    /// The camera's `gbuffer.material` with all four values (None for the other G-buffers).
    pub material_view: Option<wgpu::Texture>,
    pub motion: wgpu::Texture,
    pub emission: wgpu::Texture,
    pub depth: wgpu::Texture,
    pub views: GBufferViews,
}

pub struct GBufferViews {
    pub position: wgpu::TextureView,
    /// The camera's linear depth (see [`GBuffer::linear_depth`]); for the other G-buffers a
    /// view of `position` (whose w is the linear depth: no pass reads it there as depth).
    pub linear_depth: wgpu::TextureView,
    pub normal: wgpu::TextureView,
    /// The camera's packed normals (see [`GBuffer::packed_normal`]), which the direct light
    /// and Knecht's passes read; for the other G-buffers a view of `normal` (no pass reads
    /// it there).
    pub packed_normal: wgpu::TextureView,
    pub albedo: wgpu::TextureView,
    pub material: wgpu::TextureView,
    pub motion: wgpu::TextureView,
    pub emission: wgpu::TextureView,
    pub depth: wgpu::TextureView,
}

pub struct GBufferPass {
    /// Name prefix of every label and registered buffer: `gbuffer` for the camera,
    /// `vpl.light_gbuffer` for the light's view (Knecht 002 §4.3).
    name: String,
    device: wgpu::Device,
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    /// Target 0 is the linear depth (the camera's G-buffer, issue #53).
    linear: bool,
    /// The pipelines by the targets they write ([`Writes`]), made on first use: with the
    /// emission, then without it, each with the movement buffer's z and without (issue #53).
    pipelines: [std::sync::OnceLock<Pipelines>; 4],
    /// Whether the camera's movement buffer keeps z, the previous depth ([`MOTION_FORMAT`];
    /// otherwise [`CAMERA_MOTION_FORMAT`]): only while a step reads it.
    motion_depth: bool,
    /// Whether single-sided materials cull their back faces (the camera's G-buffer, as glTF
    /// asks); light views draw every face (see [`Self::light_view`]).
    cull_single_sided: bool,
    /// The camera's position rebuilt from its linear depth, when something reads it.
    pub position: Option<std::sync::Arc<super::gbuffer_position::PositionPass>>,
    /// The camera's normals unpacked from their packed target, when something reads them.
    pub normal: Option<std::sync::Arc<super::gbuffer_position::Fill>>,
    /// Whether a material emits or has an occlusion texture (`GpuScene::emits`, fixed for a
    /// renderer): otherwise the camera's G-buffer leaves the emission target out, and
    /// `no_emission` fills it when it is read (issue #53).
    emits: bool,
    pub no_emission: Option<std::sync::Arc<super::gbuffer_position::Fill>>,
    /// Fills the camera's `gbuffer.material` from its SI and SP and the albedo's DI when read.
    pub material: Option<std::sync::Arc<super::gbuffer_position::Fill>>,
    pub camera_layout: wgpu::BindGroupLayout,
    pub targets: GBuffer,
    /// What the targets were last rendered for: the camera's G-buffer is kept while the
    /// camera and the objects stay put (issue #53).
    pub last: crate::fingerprint::LastRun,
}

impl GBufferPass {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, width: u32, height: u32) -> Self {
        Self::named(ctx, scene, width, height, "gbuffer")
    }

    /// The same pass under another name: the light G-buffer of stage 3 is this G-buffer
    /// rendered from a light's view (Knecht 002 §4.3 renders the same attributes).
    pub fn named(ctx: &GpuContext, scene: &GpuScene, width: u32, height: u32, name: impl Into<String>) -> Self {
        let name: String = name.into();
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "gbuffer/gbuffer.wgsl");
        let camera_layout = CAMERA_BINDINGS.layout_labelled(device, &format!("{name}.camera"));
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&format!("{name}.layout")),
            bind_group_layouts: &[Some(&camera_layout), Some(&scene.instance_layout), Some(&scene.material_layout)],
            immediate_size: 0,
        });
        // The camera's G-buffer writes the linear depth to target 0 (issue #53).
        let linear = name == "gbuffer";
        let targets = create_targets_with(ctx, width, height, &name, (linear, false));
        let position = linear.then(|| position_pass(ctx, &targets));
        let normal = linear.then(|| normal_pass(ctx, &targets));
        let no_emission = (linear && !scene.emits).then(|| no_emission_pass(ctx, &targets));
        let material = linear.then(|| material_pass(ctx, &targets));
        let last = Default::default();
        Self {
            name,
            device: device.clone(),
            module,
            layout,
            linear,
            pipelines: Default::default(),
            motion_depth: false,
            cull_single_sided: true,
            position,
            normal,
            emits: scene.emits,
            no_emission,
            material,
            camera_layout,
            targets,
            last,
        }
    }

    /// The G-buffer of a light's view (Knecht 002 §4.3): every face is drawn, single-sided
    /// or not, as the shadow maps draw them. A wall's back face seen from the light stops the
    /// light there like the path tracer's two-sided surfaces do; culled, the light would pass
    /// through it and create VPLs on the surfaces behind (the open default box lit by a
    /// directional light from above got 1.5 × the path tracer's first bounce through its
    /// ceiling).
    pub fn light_view(ctx: &GpuContext, scene: &GpuScene, size: u32, name: impl Into<String>) -> Self {
        Self { cull_single_sided: false, ..Self::named(ctx, scene, size, size, name) }
    }

    /// The G-buffer's render pipeline with the vertex and fragment entries `(vs, fs)` of
    /// `module` (`fs_main` or a wrapper of `gbuffer_fragment`: also Gautron's hemisphere
    /// atlas, whose mirrored record views wind front faces clockwise); `textured` false
    /// leaves the texture reads out (materials without textures, issue #53).
    pub(crate) fn pipeline(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
        entries: (&str, &str, wgpu::FrontFace),
        (cull_mode, textured): (Option<wgpu::Face>, bool),
        name: &str,
    ) -> wgpu::RenderPipeline {
        let all = Writes { linear_depth: false, motion: true, motion_depth: true, emission: true };
        Self::pipeline_with(device, layout, module, entries, (cull_mode, textured, all), name)
    }

    /// [`Self::pipeline`] for the targets `writes` names (issue #53).
    fn pipeline_with(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        module: &wgpu::ShaderModule,
        (vs_entry, fs_entry, front_face): (&str, &str, wgpu::FrontFace),
        (cull_mode, textured, writes): (Option<wgpu::Face>, bool, Writes),
        name: &str,
    ) -> wgpu::RenderPipeline {
        let linear = writes.linear_depth;
        let constants =
            [("TEXTURED", if textured { 1.0 } else { 0.0 }), ("LINEAR_DEPTH", if linear { 1.0 } else { 0.0 })];
        let kind = match (textured, writes.emission, writes.motion) {
            (true, true, _) => "",
            (false, true, _) => "_plain",
            (true, false, true) => "_no_emission",
            (false, false, true) => "_plain_no_emission",
            (true, false, false) => "_light",
            (false, false, false) => "_plain_light",
        };
        // The camera's movement buffer without z (issue #53).
        let kind = if linear && !writes.motion_depth { format!("{kind}_motion_xy") } else { kind.to_string() };
        device.counted_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(&if cull_mode.is_some() {
                format!("{name}.pipeline_single_sided{kind}")
            } else {
                format!("{name}.pipeline_double_sided{kind}")
            }),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(vs_entry),
                compilation_options: Default::default(),
                buffers: &[Some(crate::scene::upload::vertex_layout())],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                front_face,
                // glTF: single-sided materials cull back faces; double-sided ones keep them
                // and the shader flips the normal toward the viewer.
                cull_mode,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some(fs_entry),
                compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() },
                targets: &writes.color_targets(),
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// Recreates the targets for a new size.
    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        self.last.invalidate();
        let linear = self.position.is_some();
        self.targets = create_targets_with(ctx, width, height, &self.name, (linear, self.motion_depth));
        if linear {
            self.position = Some(position_pass(ctx, &self.targets));
            self.normal = Some(normal_pass(ctx, &self.targets));
        }
        if self.no_emission.is_some() {
            self.no_emission = Some(no_emission_pass(ctx, &self.targets));
        }
        if self.material.is_some() {
            self.material = Some(material_pass(ctx, &self.targets));
        }
    }

    /// Makes the camera's movement buffer keep z, the previous depth, while `on` (a step reads
    /// it: Soler et al.'s temporal filter) and drop it otherwise (issue #53): the target is
    /// made again in its format and the next frame draws it. True when it changed (the
    /// registry must take the new texture).
    pub fn ensure_motion_depth(&mut self, ctx: &GpuContext, on: bool) -> bool {
        if !self.linear || on == self.motion_depth {
            return false;
        }
        // The pipelines of the movement buffer's other format go (made again on return).
        let old = 2 * (!on) as usize;
        for p in &mut self.pipelines[old..old + 2] {
            p.take();
        }
        self.motion_depth = on;
        let t = &mut self.targets;
        t.motion = motion_target(&ctx.device, &self.name, (t.motion.width(), t.motion.height()), !on);
        t.views.motion = super::view(&t.motion, &format!("{}.motion", self.name));
        self.last.invalidate();
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        let t = &self.targets;
        let name = &self.name;
        let camera = name == "gbuffer";
        match (&self.position, &t.linear_depth) {
            (Some(pass), Some(linear_depth)) => {
                reg.register_derived(
                    "gbuffer.position",
                    BufferKind::Data,
                    "world-space position (xyz) and linear view depth (w), scene units: rebuilt from gbuffer.linear_depth when read (issue #53)",
                    &t.position,
                    pass.clone(),
                );
                reg.register(
                    "gbuffer.linear_depth",
                    BufferKind::Data,
                    "linear view depth (−z in view space, scene units; Knecht §4.2 Eq. 4.2), 0 where no geometry covers the pixel: the camera G-buffer's target 0",
                    linear_depth,
                );
            }
            _ => reg.register(
                &format!("{name}.position"),
                BufferKind::Data,
                "world-space position (xyz) and linear view depth (w), scene units",
                &t.position,
            ),
        }
        let normal = "world-space unit normal (xyz), w = 1 where geometry covers the pixel";
        match &self.normal {
            Some(pass) => reg.register_derived(
                "gbuffer.normal",
                BufferKind::Direction,
                &format!("{normal}: unpacked when read from the G-buffer's normals, packed in one word each (octahedral, two 16-bit snorms; issue #53)"),
                &t.normal,
                pass.clone(),
            ),
            None => reg.register(&format!("{name}.normal"), BufferKind::Direction, normal, &t.normal),
        }
        reg.register(
            &format!("{name}.albedo"),
            BufferKind::Albedo,
            "linear surface colour c (rgb) and diffuse intensity DI (a), Knecht §4.2",
            &t.albedo,
        );
        match (&self.material, &t.material_view) {
            (Some(pass), Some(view)) => reg.register_derived(
                "gbuffer.material",
                BufferKind::Data,
                "specular intensity SI (r), specular power SP (g), metallic (b), roughness (a): filled when read from the G-buffer's SI and SP and the albedo's DI (issue #53); metallic = 1 − DI, the roughness that SP shades (SP clamps below 0.149 and above 0.904)",
                view,
                pass.clone(),
            ),
            _ => reg.register(
                &format!("{name}.material"),
                BufferKind::Data,
                "specular intensity SI (r), specular power SP (g), metallic (b), roughness (a)",
                &t.material,
            ),
        }
        if !camera {
            // The light's view has no previous frame and no viewer for emission.
            reg.register(&format!("{name}.depth"), BufferKind::Depth, "hardware depth in [0, 1]", &t.depth);
            return;
        }
        reg.register(
            "gbuffer.motion",
            BufferKind::Motion,
            if self.motion_depth {
                "movement buffer: xy the offset in pixels from each pixel to its position in the previous frame (Knecht §3.5.1), z its linear depth in the previous frame (Soler's temporal filter reads it)"
            } else {
                "movement buffer: xy the offset in pixels from each pixel to its position in the previous frame (Knecht §3.5.1); z, the previous depth, is kept only while Soler's temporal filter runs (issue #53)"
            },
            &t.motion,
        );
        let emission = (
            "gbuffer.emission",
            BufferKind::Hdr,
            "rgb: emitted radiance L_e of the surface (glTF emissive factor × strength × texture); a: the material's occlusion texture (R; 1 without one), shown only, never applied to computed light. Left out of the raster and filled when read while no material emits nor has an occlusion texture (issue #53)",
            &t.emission,
        );
        match &self.no_emission {
            Some(pass) => reg.register_derived(emission.0, emission.1, emission.2, emission.3, pass.clone()),
            None => reg.register(emission.0, emission.1, emission.2, emission.3),
        }
        reg.register("gbuffer.depth", BufferKind::Depth, "hardware depth in [0, 1]", &t.depth);
    }

    pub fn run(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        camera_group: &wgpu::BindGroup,
        scene: &GpuScene,
        state: &SceneState,
    ) {
        self.run_with(encoder, slot, (true, true), camera_group, scene, state);
    }

    /// [`Self::run`] as one of several passes of a timing scope (`(first, last)`: whether
    /// this pass opens and closes it).
    pub fn run_with(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        (first, last): (bool, bool),
        camera_group: &wgpu::BindGroup,
        scene: &GpuScene,
        state: &SceneState,
    ) {
        let label = format!("{}.pass", self.name);
        let writes = self.writes();
        let p = self.pipelines[!writes.emission as usize + 2 * writes.motion_depth as usize].get_or_init(|| {
            let make = |cull_mode, textured| {
                // The camera's fragment stage packs its normals (issue #53).
                let fs = if self.linear { "fs_camera" } else { "fs_main" };
                let entries = ("vs_main", fs, wgpu::FrontFace::Ccw);
                let (device, layout, module) = (&self.device, &self.layout, &self.module);
                Self::pipeline_with(device, layout, module, entries, (cull_mode, textured, writes), &self.name)
            };
            let [single_sided, double_sided] = [Some(wgpu::Face::Back), None].map(|c| make(c, true));
            let [plain_single_sided, plain_double_sided] = [Some(wgpu::Face::Back), None].map(|c| make(c, false));
            Pipelines { single_sided, double_sided, plain_single_sided, plain_double_sided }
        });
        let ts = slot.and_then(|s| s.render(first, last));
        let mut pass = self.targets.begin_pass(encoder, &label, ts, true, writes);
        pass.set_pipe(&p.double_sided);
        pass.set_group(0, camera_group, &[]);
        pass.set_group(1, &scene.instance_group, &[]);
        let single = if self.cull_single_sided { &p.single_sided } else { &p.double_sided };
        let plain = if self.cull_single_sided { &p.plain_single_sided } else { &p.plain_double_sided };
        let pipelines = ((single, &p.double_sided), (plain, &p.plain_double_sided));
        scene.draw_by_material(&mut pass, state, Some(2), Some(pipelines));
    }

    /// The targets this pass writes for `scene` (issue #53): the camera's all but the
    /// emission when no material emits or has an occlusion texture to show
    /// (`GpuScene::emits`, fixed for a renderer: its scene is uploaded once); a light view's
    /// neither the movement buffer nor the emission, which nothing reads there.
    pub fn writes(&self) -> Writes {
        let camera = self.linear;
        Writes {
            linear_depth: camera,
            motion: camera,
            motion_depth: camera && self.motion_depth,
            emission: camera && self.emits,
        }
    }
}

/// The G-buffer pipelines of one [`Writes`]: single- and double-sided, for materials with
/// textures and without (`TEXTURED` false in the shader, issue #53).
struct Pipelines {
    single_sided: wgpu::RenderPipeline,
    double_sided: wgpu::RenderPipeline,
    plain_single_sided: wgpu::RenderPipeline,
    plain_double_sided: wgpu::RenderPipeline,
}

/// What a G-buffer pass writes (issue #53): target 0 as the linear depth or the position, and
/// whether the movement buffer and the emission targets are attached.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Writes {
    pub linear_depth: bool,
    pub motion: bool,
    /// Whether the movement buffer keeps z (the camera's, when a step reads it; the other
    /// G-buffers' always).
    pub motion_depth: bool,
    pub emission: bool,
}

impl Writes {
    /// The colour targets of a pipeline that writes these (None where a target is left out).
    fn color_targets(self) -> [Option<wgpu::ColorTargetState>; 6] {
        let position = if self.linear_depth { LINEAR_DEPTH_FORMAT } else { POSITION_FORMAT };
        let mut t = color_targets_with(position);
        if self.linear_depth {
            // The camera's packed normals (`fs_camera`), and its SI and SP alone (the
            // shader's vec4 output keeps its first two).
            let target =
                |format| Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL });
            t[1] = target(PACKED_NORMAL_FORMAT);
            t[3] = target(SHADING_FORMAT);
            if !self.motion_depth {
                t[4] = target(CAMERA_MOTION_FORMAT);
            }
        }
        if !self.motion {
            t[4] = None;
        }
        if !self.emission {
            t[5] = None;
        }
        t
    }
}

impl GBuffer {
    /// A render pass into every target, all cleared (colour to 0, depth to 1).
    pub(crate) fn begin_clear_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> wgpu::RenderPass<'e> {
        self.begin_pass(encoder, label, timestamp_writes, true, self.all_targets())
    }

    /// Every target (the hemisphere atlas's passes).
    fn all_targets(&self) -> Writes {
        Writes { linear_depth: self.linear_depth.is_some(), motion: true, motion_depth: true, emission: true }
    }

    /// A render pass over the targets as they are (nothing cleared): the caller clears what
    /// it draws into (Gautron's atlas clears only its round's tiles, issue #53).
    pub(crate) fn begin_load_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) -> wgpu::RenderPass<'e> {
        self.begin_pass(encoder, label, timestamp_writes, false, self.all_targets())
    }

    fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
        clear: bool,
        writes: Writes,
    ) -> wgpu::RenderPass<'e> {
        let v = &self.views;
        let colour_load = if clear { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) } else { wgpu::LoadOp::Load };
        let depth_load = if clear { wgpu::LoadOp::Clear(1.0) } else { wgpu::LoadOp::Load };
        let attach = |view, load| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            })
        };
        // The camera's packed normals clear to the word of no normal.
        let no_normal = wgpu::Color { r: f64::from(NO_NORMAL), g: 0.0, b: 0.0, a: 0.0 };
        let normal_load = if clear { wgpu::LoadOp::Clear(no_normal) } else { wgpu::LoadOp::Load };
        let clear = |view| attach(view, colour_load);
        encoder.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[
                clear(if self.linear_depth.is_some() { &v.linear_depth } else { &v.position }),
                match self.packed_normal {
                    Some(_) => attach(&v.packed_normal, normal_load),
                    None => clear(&v.normal),
                },
                clear(&v.albedo),
                clear(&v.material),
                if writes.motion { clear(&v.motion) } else { None },
                if writes.emission { clear(&v.emission) } else { None },
            ],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &v.depth,
                depth_ops: Some(wgpu::Operations { load: depth_load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }
}

/// The camera's emission when no material emits (issue #53), for these targets.
/// The camera's `gbuffer.material` from its SI and SP and the albedo (issue #53).
fn material_pass(ctx: &GpuContext, t: &GBuffer) -> std::sync::Arc<super::gbuffer_position::Fill> {
    let size = (t.material.width(), t.material.height());
    let view = t.material_view.as_ref().map(|m| super::view(m, "gbuffer.material"));
    let view = view.unwrap_or_else(|| t.views.material.clone());
    super::gbuffer_position::material_pass(ctx, (&t.views.material, &t.views.albedo), &view, size)
}

/// 1×1 stand-ins for a pass that binds both kinds of normals and reads one (issue #53): the
/// unpacked ([`NORMAL_FORMAT`]) and the packed ([`PACKED_NORMAL_FORMAT`]), labelled `{prefix}.no_normal`
/// and `{prefix}.no_packed_normal`.
pub fn normal_stand_ins(device: &wgpu::Device, prefix: &str) -> [wgpu::TextureView; 2] {
    [("no_normal", NORMAL_FORMAT), ("no_packed_normal", PACKED_NORMAL_FORMAT)].map(|(what, format)| {
        let label = format!("{prefix}.{what}");
        let t = super::create_target(device, &label, 1, 1, format, wgpu::TextureUsages::empty());
        super::view(&t, &label)
    })
}

/// The movement buffer: [`CAMERA_MOTION_FORMAT`] when `xy_only`, else [`MOTION_FORMAT`].
fn motion_target(d: &wgpu::Device, name: &str, (width, height): (u32, u32), xy_only: bool) -> wgpu::Texture {
    let format = if xy_only { CAMERA_MOTION_FORMAT } else { MOTION_FORMAT };
    let att = wgpu::TextureUsages::RENDER_ATTACHMENT;
    super::create_target(d, &format!("{name}.motion"), width, height, format, att)
}

/// The camera's normals unpacked from its packed target (issue #53), for these targets.
fn normal_pass(ctx: &GpuContext, t: &GBuffer) -> std::sync::Arc<super::gbuffer_position::Fill> {
    let size = (t.normal.width(), t.normal.height());
    super::gbuffer_position::normal_pass(ctx, &t.views.packed_normal, &t.views.normal, size)
}

fn no_emission_pass(ctx: &GpuContext, t: &GBuffer) -> std::sync::Arc<super::gbuffer_position::Fill> {
    let size = (t.emission.width(), t.emission.height());
    super::gbuffer_position::no_emission_pass(ctx, &t.views.linear_depth, &t.views.emission, size)
}

/// The camera's position from its linear depth (issue #53), for these targets.
fn position_pass(ctx: &GpuContext, t: &GBuffer) -> std::sync::Arc<super::gbuffer_position::PositionPass> {
    let size = (t.position.width(), t.position.height());
    super::gbuffer_position::PositionPass::new(ctx, &t.views.linear_depth, &t.views.position, size)
}

/// The six colour targets of a G-buffer pipeline, in attachment order (position, normal,
/// albedo, material, motion, emission), unblended.
pub(crate) fn color_targets() -> [Option<wgpu::ColorTargetState>; 6] {
    color_targets_with(POSITION_FORMAT)
}

/// [`color_targets`] with target 0 in `position` (the camera's linear depth, issue #53).
fn color_targets_with(position: wgpu::TextureFormat) -> [Option<wgpu::ColorTargetState>; 6] {
    [position, NORMAL_FORMAT, ALBEDO_FORMAT, MATERIAL_FORMAT, MOTION_FORMAT, EMISSION_FORMAT]
        .map(|format| Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL }))
}

/// The G-buffer's textures at `width`×`height` (also the atlas of Gautron's hemispheres).
pub(crate) fn create_targets(ctx: &GpuContext, width: u32, height: u32, name: &str) -> GBuffer {
    create_targets_with(ctx, width, height, name, (false, true))
}

/// [`create_targets`]; `linear`: target 0 is the linear depth and the position a storage
/// texture filled from it (the camera's G-buffer, issue #53).
fn create_targets_with(ctx: &GpuContext, width: u32, height: u32, name: &str, targets: (bool, bool)) -> GBuffer {
    let (linear, motion_depth) = targets;
    let d = &ctx.device;
    let att = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let linear_depth = linear
        .then(|| super::create_target(d, &format!("{name}.linear_depth"), width, height, LINEAR_DEPTH_FORMAT, att));
    let position_usage = if linear { wgpu::TextureUsages::STORAGE_BINDING } else { att };
    let position = super::create_target(d, &format!("{name}.position"), width, height, POSITION_FORMAT, position_usage);
    let normal_usage = if linear { wgpu::TextureUsages::STORAGE_BINDING } else { att };
    let normal = super::create_target(d, &format!("{name}.normal"), width, height, NORMAL_FORMAT, normal_usage);
    let packed_normal = linear
        .then(|| super::create_target(d, &format!("{name}.packed_normal"), width, height, PACKED_NORMAL_FORMAT, att));
    let albedo = super::create_target(d, &format!("{name}.albedo"), width, height, ALBEDO_FORMAT, att);
    let material_format = if linear { SHADING_FORMAT } else { MATERIAL_FORMAT };
    let material = super::create_target(d, &format!("{name}.material"), width, height, material_format, att);
    let storage = wgpu::TextureUsages::STORAGE_BINDING;
    let material_view = linear
        .then(|| super::create_target(d, &format!("{name}.material_view"), width, height, MATERIAL_FORMAT, storage));
    let motion = motion_target(d, name, (width, height), linear && !motion_depth);
    // The camera's may be filled in compute when no material emits (`gbuffer_position::no_emission_pass`).
    let emission_usage = if linear { att | wgpu::TextureUsages::STORAGE_BINDING } else { att };
    let emission = super::create_target(d, &format!("{name}.emission"), width, height, EMISSION_FORMAT, emission_usage);
    let depth = super::create_target(d, &format!("{name}.depth"), width, height, DEPTH_FORMAT, att);
    let views = GBufferViews {
        position: super::view(&position, &format!("{name}.position")),
        linear_depth: match &linear_depth {
            Some(t) => super::view(t, &format!("{name}.linear_depth")),
            None => super::view(&position, &format!("{name}.position")),
        },
        normal: super::view(&normal, &format!("{name}.normal")),
        packed_normal: match &packed_normal {
            Some(t) => super::view(t, &format!("{name}.packed_normal")),
            None => super::view(&normal, &format!("{name}.normal")),
        },
        albedo: super::view(&albedo, &format!("{name}.albedo")),
        material: super::view(&material, &format!("{name}.material")),
        motion: super::view(&motion, &format!("{name}.motion")),
        emission: super::view(&emission, &format!("{name}.emission")),
        depth: super::view(&depth, &format!("{name}.depth")),
    };
    GBuffer {
        position,
        linear_depth,
        normal,
        packed_normal,
        albedo,
        material,
        material_view,
        motion,
        emission,
        depth,
        views,
    }
}
