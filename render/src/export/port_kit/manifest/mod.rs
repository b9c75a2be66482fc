//! The port kit's `manifest.json` (docs/port-kit.md): the frame as the ordered list of its
//! passes, each pass as its steps (a dispatch, a draw or a copy with the pipeline, shader
//! entry points and every binding in force), the resources with their formats, sizes and
//! lifetimes, and each shader module's declarations. Built from a [`capture`] of frames the
//! renderer really drew and from naga's reading of the modules ([`super::reflect`]).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::hash::{Hash, Hasher};

mod schema;
pub use schema::*;

use super::reflect::{BindingDecl, ModuleDecl, reflect};
use crate::counters::capture::{Bound, Capture, Command, PassCommands};

/// Names for the captured objects: the label, with `#2`, `#3` … where labels repeat, in the
/// order the frame first uses them.
struct Names {
    by_key: HashMap<(u8, u64), String>,
    seen: HashMap<String, u32>,
}

impl Names {
    fn name(&mut self, kind: u8, key: u64, label: &str) -> String {
        if let Some(n) = self.by_key.get(&(kind, key)) {
            return n.clone();
        }
        let count = self.seen.entry(label.to_string()).or_insert(0);
        *count += 1;
        let n = if *count == 1 { label.to_string() } else { format!("{label}#{count}") };
        self.by_key.insert((kind, key), n.clone());
        n
    }
}

/// What a pass of a captured frame read and wrote (the goldens' files).
#[derive(Clone, Debug)]
pub struct PassAccess {
    /// The pass's index in the frame's [`PassCommands`] (its snapshots) and in the listed frame.
    pub source: usize,
    pub index: usize,
    pub name: String,
    pub written: Vec<String>,
    pub read: Vec<String>,
}

/// A manifest with what the goldens need: each frame's passes' accesses, and each resource's
/// capture key (texture or not, key).
pub struct Built {
    pub manifest: Manifest,
    pub frames: Vec<Vec<PassAccess>>,
    pub keys: HashMap<String, (bool, u64)>,
    /// The uploads' files (kit path, bytes).
    pub uploads: Vec<(std::path::PathBuf, Vec<u8>)>,
}

/// Builds the manifest of the captured `frames` (at least two, from a fresh start) with the
/// objects of `objects`.
///
/// Uploads into `input` buffers are left out (the goldens' `inputs/` hold those buffers as the
/// passes read them); which buffers are inputs is known once every frame is read, so the
/// manifest is built twice, the second time without them.
pub fn build(preset: &str, size: (u32, u32), frames: &[Vec<PassCommands>], objects: &Capture) -> Result<Built, String> {
    if frames.len() < 2 {
        return Err(format!("a kit needs two frames or more, {} were drawn", frames.len()));
    }
    let first = build_with(preset, size, frames, objects, HashSet::new())?;
    let inputs = first
        .manifest
        .resources
        .iter()
        .filter(|r| r.lifetime == "input" && r.kind == "buffer")
        .filter_map(|r| first.keys.get(&r.name).map(|k| k.1))
        .collect();
    build_with(preset, size, frames, objects, inputs)
}

fn build_with(
    preset: &str,
    size: (u32, u32),
    frames: &[Vec<PassCommands>],
    objects: &Capture,
    skip_uploads: HashSet<u64>,
) -> Result<Built, String> {
    let mut b = Builder {
        skip_uploads,
        upload_files: HashMap::new(),
        uploads: Vec::new(),
        objects,
        names: Names { by_key: HashMap::new(), seen: HashMap::new() },
        modules: BTreeMap::new(),
        access: BTreeMap::new(),
        order: Vec::new(),
        frame: 0,
        pass_access: Vec::new(),
        pipelines_used: Vec::new(),
    };
    let mut lists = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        b.frame = k;
        b.pass_access.push(Vec::new());
        lists.push(b.frame_passes(f)?);
    }
    let out = lists.last().cloned().unwrap_or_default();
    let resources = b.resources();
    let pipelines = b.used_pipelines();
    let keys = b
        .names
        .by_key
        .iter()
        .filter(|((kind, _), _)| *kind != SAM)
        .map(|((kind, key), name)| (name.clone(), (*kind == TEX, *key)))
        .collect();
    let access = std::mem::take(&mut b.pass_access);
    let shaders = b
        .modules
        .into_iter()
        .map(|(module, decl)| Shader { file: format!("shaders/{module}"), module, decl })
        .collect();
    let manifest = Manifest {
        schema: SCHEMA_NAME,
        schema_version: SCHEMA_VERSION,
        preset: preset.into(),
        size: [size.0, size.1],
        frames: frames.len() as u32,
        preset_file: "preset.json",
        device: DeviceNeeds::of_gi_lab(),
        passes: out,
        frame_passes: lists,
        pipelines,
        resources,
        shaders,
        translations: Vec::new(),
        golden: Vec::new(),
        expressions: None,
        repeated_passes: Vec::new(),
        not_yet: NOT_YET.to_vec(),
    };
    Ok(Built { manifest, frames: access, keys, uploads: std::mem::take(&mut b.uploads) })
}

/// A resource's name as a file name.
pub fn file_name(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '_' || c == '-' { c } else { '_' }).collect()
}

const TEX: u8 = 0;
const BUF: u8 = 1;
const SAM: u8 = 2;

struct Builder<'a> {
    objects: &'a Capture,
    names: Names,
    modules: BTreeMap<String, ModuleDecl>,
    /// Resource name → its accesses in order: (frame, pass name, wrote).
    access: BTreeMap<String, Vec<(usize, String, bool)>>,
    /// The frame being read.
    frame: usize,
    /// Per frame, the accesses of its listed passes.
    pass_access: Vec<Vec<PassAccess>>,
    /// Pipeline keys in order of first use.
    pipelines_used: Vec<u64>,
    /// Resource names in order of first use, with their kind and key.
    order: Vec<(String, u8, u64)>,
    /// Buffers whose uploads are left out (inputs), by key.
    skip_uploads: HashSet<u64>,
    /// Upload contents already written: their file, by hash and length.
    upload_files: HashMap<(u64, usize), String>,
    uploads: Vec<(std::path::PathBuf, Vec<u8>)>,
}

impl Builder<'_> {
    fn module(&mut self, path: &str) -> Result<&ModuleDecl, String> {
        if !self.modules.contains_key(path) {
            let source = crate::shaders::resolve(path).map_err(|e| format!("{path}: {e}"))?;
            let decl = reflect(&source).map_err(|e| format!("{path}: {e}"))?;
            self.modules.insert(path.to_string(), decl);
        }
        Ok(&self.modules[path])
    }

    fn resource(&mut self, kind: u8, key: u64) -> String {
        let label = match kind {
            TEX => self.objects.textures.get(&key).map(|t| t.label.clone()),
            BUF => self.objects.buffers.get(&key).map(|b| b.label.clone()),
            _ => self.objects.samplers.get(&key).map(|s| s.label.clone()),
        }
        .unwrap_or_else(|| format!("(unknown {key:x})"));
        let fresh = !self.names.by_key.contains_key(&(kind, key));
        let name = self.names.name(kind, key, &label);
        if fresh {
            self.order.push((name.clone(), kind, key));
        }
        name
    }

    /// The pipelines the steps set, once each, in order of first use.
    fn used_pipelines(&self) -> Vec<crate::counters::capture::PipelineInfo> {
        let mut out: Vec<crate::counters::capture::PipelineInfo> = Vec::new();
        for k in &self.pipelines_used {
            if let Some(p) = self.objects.pipelines.get(k)
                && !out.iter().any(|o| o.label == p.label)
            {
                out.push(p.clone());
            }
        }
        out
    }

    fn touch(&mut self, name: &str, pass: &str, wrote: bool) {
        self.access.entry(name.to_string()).or_default().push((self.frame, pass.to_string(), wrote));
        if let Some(a) = self.pass_access.last_mut().and_then(|f| f.last_mut()) {
            let list = if wrote { &mut a.written } else { &mut a.read };
            if !list.iter().any(|n| n == name) {
                list.push(name.to_string());
            }
        }
    }

    /// One frame's passes, without GI Lab's own instrumentation (the timestamp read-back).
    fn frame_passes(&mut self, passes: &[PassCommands]) -> Result<Vec<Pass>, String> {
        let mut out = Vec::new();
        for (source, p) in passes.iter().enumerate().filter(|(_, p)| !p.commands.is_empty()) {
            let access =
                PassAccess { source, index: out.len(), name: p.name.clone(), written: Vec::new(), read: Vec::new() };
            if let Some(f) = self.pass_access.last_mut() {
                f.push(access);
            }
            let mut steps = self.steps(p)?;
            steps.retain(|s| !s.copy.as_ref().is_some_and(|c| c.to_string().contains("\"timing.")));
            if steps.is_empty() {
                if let Some(f) = self.pass_access.last_mut() {
                    f.pop();
                }
                continue;
            }
            let runs = runs_of(&steps, false);
            out.push(Pass { index: out.len(), name: p.name.clone(), role: role_of(&p.name), steps, runs });
        }
        Ok(out)
    }

    /// The resource, view range, offset and size of a bound object.
    fn bound(&mut self, b: &Bound) -> (String, Option<ViewRange>, Option<u64>, Option<u64>) {
        match b {
            Bound::View { texture, base_mip, mips, base_layer, layers, dimension } => (
                self.resource(TEX, *texture),
                Some(ViewRange {
                    base_mip: *base_mip,
                    mips: *mips,
                    base_layer: *base_layer,
                    layers: *layers,
                    dimension: dimension.clone(),
                }),
                None,
                None,
            ),
            Bound::Buffer { buffer, offset, size } => (self.resource(BUF, *buffer), None, Some(*offset), Some(*size)),
            Bound::Sampler { sampler } => (self.resource(SAM, *sampler), None, None, None),
            Bound::Unknown => ("(unknown)".into(), None, None, None),
        }
    }

    fn steps(&mut self, p: &PassCommands) -> Result<Vec<Step>, String> {
        let mut steps = Vec::new();
        let mut pipeline: Option<u64> = None;
        let mut groups: BTreeMap<u32, (u64, Vec<u32>)> = BTreeMap::new();
        let mut targets: Vec<Target> = Vec::new();
        let mut depth: Option<Target> = None;
        let mut vertex: Vec<(u32, String)> = Vec::new();
        let mut index: Option<(String, String)> = None;
        let mut render_passes = 0u32;
        for c in &p.commands {
            match c {
                Command::ComputePass => {}
                Command::RenderPass { colors, depth: d } => {
                    render_passes += 1;
                    (pipeline, targets, vertex, index) = (None, Vec::new(), Vec::new(), None);
                    groups.clear();
                    for a in colors {
                        let (resource, view, ..) = self.bound(&a.bound);
                        targets.push(Target { resource, view, load: a.load, clear: a.clear });
                    }
                    depth = d.as_ref().map(|a| {
                        let (resource, view, ..) = self.bound(&a.bound);
                        Target { resource, view, load: a.load, clear: a.clear }
                    });
                }
                Command::Pipeline { pipeline: k } => pipeline = Some(*k),
                Command::Group { index: i, group, offsets } => {
                    groups.insert(*i, (*group, offsets.clone()));
                }
                Command::VertexBuffer { slot, buffer } => {
                    let n = self.resource(BUF, *buffer);
                    vertex.retain(|(s, _)| s != slot);
                    vertex.push((*slot, n));
                }
                Command::IndexBuffer { buffer, format } => index = Some((self.resource(BUF, *buffer), format.clone())),
                Command::CopyTexture { src, src_mip, src_origin, dst, dst_mip, dst_origin, size } => {
                    let (s, d) = (self.resource(TEX, *src), self.resource(TEX, *dst));
                    self.touch(&s, &p.name, false);
                    self.touch(&d, &p.name, true);
                    steps.push(copy_step(serde_json::json!({
                        "src": s, "src_mip": src_mip, "src_origin": src_origin,
                        "dst": d, "dst_mip": dst_mip, "dst_origin": dst_origin, "texels": size
                    })));
                }
                Command::ClearBuffer { buffer, offset, size } => {
                    let b = self.resource(BUF, *buffer);
                    self.touch(&b, &p.name, true);
                    steps.push(Step { clear: Some((b, *offset, *size)), ..blank_step("clear") });
                }
                Command::Upload { buffer, offset, data } => {
                    if self.skip_uploads.contains(buffer) {
                        continue;
                    }
                    let name = self.resource(BUF, *buffer);
                    let mut h = std::collections::hash_map::DefaultHasher::new();
                    data.hash(&mut h);
                    let id = (h.finish(), data.len());
                    let file = match self.upload_files.get(&id) {
                        Some(f) => f.clone(),
                        None => {
                            let f = format!(
                                "golden/frame-{}/uploads/{}.{}.bin",
                                self.frame,
                                file_name(&name),
                                self.uploads.len()
                            );
                            self.uploads.push((std::path::PathBuf::from(&f), data.clone()));
                            self.upload_files.insert(id, f.clone());
                            f
                        }
                    };
                    let upload = UploadStep { buffer: name, offset: *offset, bytes: data.len() as u64, file };
                    steps.push(Step { upload: Some(upload), ..blank_step("upload") });
                }
                Command::CopyBuffer { src, src_offset, dst, dst_offset, size } => {
                    let (s, d) = (self.resource(BUF, *src), self.resource(BUF, *dst));
                    self.touch(&s, &p.name, false);
                    self.touch(&d, &p.name, true);
                    steps.push(copy_step(serde_json::json!({
                        "src": s, "src_offset": src_offset, "dst": d, "dst_offset": dst_offset, "bytes": size
                    })));
                }
                Command::Dispatch { .. }
                | Command::DispatchIndirect { .. }
                | Command::Draw { .. }
                | Command::DrawIndexed { .. }
                | Command::DrawIndirect { .. } => {
                    let mut step = self.work(p, c, pipeline, &groups)?;
                    if step.kind.starts_with("draw") {
                        for t in targets.iter().chain(depth.as_ref()) {
                            if t.load {
                                self.touch(&t.resource, &p.name, false);
                            }
                            self.touch(&t.resource, &p.name, true);
                        }
                        let mut inputs: Vec<String> = vertex.iter().map(|(_, v)| v.clone()).collect();
                        inputs.extend(index.iter().map(|(n, _)| n.clone()));
                        for v in inputs {
                            self.touch(&v, &p.name, false);
                        }
                        step.render_pass = Some(render_passes.saturating_sub(1));
                        step.targets = targets.clone();
                        step.depth_target = depth.clone();
                        step.vertex_buffers = vertex.clone();
                        step.index_buffer = index.clone();
                    }
                    steps.push(step);
                }
            }
        }
        Ok(steps)
    }

    /// A dispatch or draw with everything in force.
    fn work(
        &mut self,
        p: &PassCommands,
        c: &Command,
        pipeline: Option<u64>,
        groups: &BTreeMap<u32, (u64, Vec<u32>)>,
    ) -> Result<Step, String> {
        if let Some(k) = pipeline
            && !self.pipelines_used.contains(&k)
        {
            self.pipelines_used.push(k);
        }
        let info = pipeline.and_then(|k| self.objects.pipelines.get(&k)).cloned();
        let mut decls: Vec<BindingDecl> = Vec::new();
        if let Some(info) = &info {
            for s in &info.stages {
                for d in &self.module(&s.module)?.bindings {
                    if !decls.iter().any(|x| x.group == d.group && x.binding == d.binding) {
                        decls.push(d.clone());
                    }
                }
            }
        }
        let mut bindings = Vec::new();
        for (&gi, (gk, offsets)) in groups {
            let Some(g) = self.objects.groups.get(gk) else { continue };
            for (binding, bound) in &g.entries {
                let decl = decls.iter().find(|d| d.group == gi && d.binding == *binding);
                let Some(decl) = decl else { continue };
                let (resource, view, mut offset, size) = self.bound(bound);
                // The dynamic offsets go, in order, to the bindings the layout gives one.
                let dynamic = g.dynamic.iter().position(|b| b == binding).and_then(|i| offsets.get(i));
                if let (Some(o), Some(extra)) = (offset.as_mut(), dynamic) {
                    *o += *extra as u64;
                }
                let wrote = decl.access != "read";
                if decl.access != "write" {
                    self.touch(&resource, &p.name, false);
                }
                if wrote {
                    self.touch(&resource, &p.name, true);
                }
                bindings.push(BindingUse {
                    group: gi,
                    binding: *binding,
                    name: decl.name.clone(),
                    kind: decl.kind.into(),
                    access: decl.access.into(),
                    resource,
                    view,
                    offset,
                    size,
                    values: Vec::new(),
                });
            }
        }
        let (kind, workgroups, draw, indirect) = match c {
            Command::Dispatch { workgroups } => ("dispatch", Some(*workgroups), None, None),
            Command::DispatchIndirect { buffer, offset } => {
                let b = self.resource(BUF, *buffer);
                self.touch(&b, &p.name, false);
                ("dispatch_indirect", None, None, Some((b, *offset)))
            }
            Command::Draw { vertices, instances } => {
                ("draw", None, Some(serde_json::json!({"vertices": vertices, "instances": instances})), None)
            }
            Command::DrawIndexed { indices, base_vertex, instances } => (
                "draw_indexed",
                None,
                Some(serde_json::json!({"indices": indices, "base_vertex": base_vertex, "instances": instances})),
                None,
            ),
            Command::DrawIndirect { buffer, offset, indexed } => {
                let b = self.resource(BUF, *buffer);
                self.touch(&b, &p.name, false);
                (if *indexed { "draw_indexed_indirect" } else { "draw_indirect" }, None, None, Some((b, *offset)))
            }
            _ => unreachable!("work() is called for dispatches and draws"),
        };
        Ok(Step {
            pipeline: info.as_ref().map(|i| i.label.clone()),
            entry_points: info
                .as_ref()
                .map(|i| i.stages.iter().map(|s| (s.module.clone(), s.entry.clone())).collect())
                .unwrap_or_default(),
            constants: info.as_ref().map(|i| i.constants.clone()).unwrap_or_default(),
            bindings,
            workgroups,
            draw,
            indirect,
            ..blank_step(kind)
        })
    }

    fn resources(&self) -> Vec<Resource> {
        let o = self.objects;
        self.order
            .iter()
            .filter(|(name, ..)| !name.starts_with("timing."))
            .map(|(name, kind, key)| {
                let acc = self.access.get(name).cloned().unwrap_or_default();
                // History: some frame reads it before that frame writes it, and it is written.
                let written = acc.iter().any(|a| a.2);
                let read_first = (0..=self.frame).any(|f| {
                    let w = acc.iter().position(|a| a.0 == f && a.2);
                    let r = acc.iter().position(|a| a.0 == f && !a.2);
                    matches!((r, w), (Some(r), Some(w)) if r < w) || matches!((r, w), (Some(_), None))
                });
                let lifetime = match (written, read_first) {
                    (false, _) => "input",
                    (true, true) => "history",
                    (true, false) => "frame",
                };
                let mut written_by: Vec<String> = Vec::new();
                let mut read_by: Vec<String> = Vec::new();
                for (_, pass, wrote) in acc.iter().filter(|a| a.0 == self.frame) {
                    let list = if *wrote { &mut written_by } else { &mut read_by };
                    if !list.contains(pass) {
                        list.push(pass.clone());
                    }
                }
                let mut r = Resource {
                    name: name.clone(),
                    kind: "sampler",
                    format: None,
                    size: Vec::new(),
                    size_expr: Vec::new(),
                    depends_on: Vec::new(),
                    mips: None,
                    dimension: None,
                    usage: None,
                    sampler: None,
                    unordered_records: None,
                    lifetime,
                    written_by,
                    read_by,
                };
                match *kind {
                    TEX => {
                        if let Some(t) = o.textures.get(key) {
                            r.kind = "texture";
                            r.format = Some(t.format.clone());
                            r.size = t.size.iter().map(|&x| x as u64).collect();
                            r.mips = Some(t.mips);
                            r.dimension = Some(t.dimension.clone());
                            r.usage = Some(t.usage.clone());
                        }
                    }
                    BUF => {
                        if let Some(b) = o.buffers.get(key) {
                            r.kind = "buffer";
                            r.size = vec![b.size];
                            r.unordered_records = o.unordered.get(key).copied();
                            r.usage = Some(b.usage.clone());
                        }
                    }
                    _ => {
                        if let Some(s) = o.samplers.get(key) {
                            r.sampler = Some(serde_json::json!({
                                "address_mode": s.address_mode, "filter": s.filter, "compare": s.compare
                            }));
                        }
                    }
                }
                r
            })
            .collect()
    }
}

fn copy_step(copy: serde_json::Value) -> Step {
    Step { copy: Some(copy), ..blank_step("copy") }
}

/// A step of `kind` with nothing else set.
fn blank_step(kind: &str) -> Step {
    Step {
        kind: kind.into(),
        pipeline: None,
        entry_points: Vec::new(),
        constants: Vec::new(),
        bindings: Vec::new(),
        workgroups: None,
        draw: None,
        indirect: None,
        counts_expr: Vec::new(),
        counts_depend_on: Vec::new(),
        render_pass: None,
        targets: Vec::new(),
        depth_target: None,
        vertex_buffers: Vec::new(),
        index_buffer: None,
        copy: None,
        clear: None,
        upload: None,
    }
}
