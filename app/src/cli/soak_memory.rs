//! The soak's memory checks (issue #19): what it counts at each return to the starting
//! state, how it judges the counts, and a probe of the driver's own growth.
//!
//! GPU memory is judged on every driver: wgpu's live buffers, textures, bind groups and
//! pipelines (its hub report) and the bytes its allocator holds (its allocator report) may not
//! rise above what they were in the first half of the run. The heap of the process's Rust
//! code (`crate::heap`: GI Lab, wgpu, naga) must level off on every driver. The process's
//! resident memory is judged too, except where the driver is seen to keep memory per
//! dispatch by itself:
//! Mesa 22.3's lavapipe compiles a new shader variant whenever it binds a pipeline whose
//! uniforms it can inline into branch and loop conditions (`update_inline_shader_state` in
//! lvp_execute.c), and never frees the variant it replaces. GI Lab's frame binds about a dozen
//! such pipelines (any pass whose uniform chooses a branch: the light kind in
//! `knecht/vpl/importance.wgsl`, the sky mode in `compose/compose.wgsl`, the window size in
//! `knecht/interleave/filter.wgsl`), which made one live renderer's resident memory rise by about
//! 1.6 MiB a frame at 64×64 on lavapipe while wgpu's objects and allocator bytes stayed flat.
//! The probe below runs a pipeline of that kind and measures the driver's growth directly.

use gi_render::GpuContext;

/// Resources at a return to the starting state.
#[derive(Clone, Copy, Debug)]
pub struct Checkpoint {
    pub frame: u64,
    pub buffers: usize,
    pub textures: usize,
    pub bind_groups: usize,
    pub pipelines: usize,
    /// Bytes wgpu's allocator holds for buffers and textures (None where the backend has no
    /// allocator report).
    pub allocated_bytes: Option<u64>,
    /// What the process's Rust code holds on the heap (the `gi-lab` binary counts it,
    /// `crate::heap`; None elsewhere): GI Lab's, wgpu's and naga's memory without the
    /// driver's.
    pub heap_mib: Option<f64>,
    pub rss_mib: f64,
}

/// Whether the resident memory takes part in the verdict, and why not when it does not.
#[derive(Clone, Debug, PartialEq)]
pub enum RssJudged {
    Yes,
    /// Reported only, for the reason given (`--no-rss-check`, or the driver's own growth).
    No(String),
}

/// The verdict on the checkpoints: its text, whether memory is flat, and whether the GPU
/// memory alone is.
pub struct MemoryVerdict {
    pub text: String,
    pub flat: bool,
    pub gpu_flat: bool,
}

/// One quantity of a checkpoint.
type Measure = fn(&Checkpoint) -> u64;

/// Growth of the allocator's bytes at the starting state that is not a leak (see
/// `memory_verdict`).
const ALLOCATOR_SLACK_BYTES: u64 = 1 << 20;

/// "memory flat (…)" or "memory GROWS (…)". The device's live buffers, textures, bind groups
/// and pipelines and its allocator's bytes (give or take 1 MiB of staging) at the starting
/// state may not rise above what they were in the first half of the run (a renderer makes a few objects on first use, such as a
/// probe's readback, and keeps them; a leak keeps adding). The resident memory (after glibc's
/// trim) rises for a while as caches fill, then must level off: from the middle checkpoint to
/// the last it may rise by at most 64 MiB or 15 %, whichever is more.
pub fn memory_verdict(c: &[Checkpoint], rss: &RssJudged) -> MemoryVerdict {
    if c.len() < 2 {
        return MemoryVerdict {
            text: "memory not checked (fewer than 2 checkpoints; raise --frames or lower --check-every)".into(),
            flat: true,
            gpu_flat: true,
        };
    }
    let (a, m, z) = (c[1], c[c.len() / 2], c[c.len() - 1]);
    let peak = c.iter().map(|x| x.rss_mib).fold(0.0, f64::max);
    let first_half = &c[..=c.len() / 2];
    let most = |f: fn(&Checkpoint) -> u64| first_half.iter().map(f).max().unwrap_or(0);
    let counts: [(&str, Measure); 5] = [
        ("buffers", |k| k.buffers as u64),
        ("textures", |k| k.textures as u64),
        ("bind groups", |k| k.bind_groups as u64),
        ("pipelines", |k| k.pipelines as u64),
        ("allocated bytes", |k| k.allocated_bytes.unwrap_or(0)),
    ];
    // Writes queued after the frame's last submission keep wgpu staging memory whose size
    // varies by a few bytes between returns; a leak adds more than this in a few returns.
    let slack = |name: &str| if name == "allocated bytes" { ALLOCATOR_SLACK_BYTES } else { 0 };
    let grown: Vec<&str> = counts
        .iter()
        .filter(|(name, f)| c[c.len() / 2..].iter().any(|x| f(x) > most(*f) + slack(name)))
        .map(|(name, _)| *name)
        .collect();
    let gpu_flat = grown.is_empty();
    let rss_flat = z.rss_mib <= m.rss_mib + (m.rss_mib * 0.15).max(64.0);
    let rss_counts = *rss == RssJudged::Yes;
    // The heap of the Rust code is judged on every driver, as the resident memory: it may
    // fill caches, then must level off (16 MiB or 15 % from the middle to the end).
    let heap_flat = match (m.heap_mib, z.heap_mib) {
        (Some(hm), Some(hz)) => hz <= hm + (hm * 0.15).max(16.0),
        _ => true,
    };
    let flat = gpu_flat && heap_flat && (rss_flat || !rss_counts);
    let heap = match (a.heap_mib, m.heap_mib, z.heap_mib) {
        (Some(ha), Some(hm), Some(hz)) => format!(
            "; heap {ha:.1} MiB at frame {}, {hm:.1} at {}, {hz:.1} at {}{}",
            a.frame,
            m.frame,
            z.frame,
            if heap_flat { "" } else { ": heap GROWS" }
        ),
        _ => String::new(),
    };
    let bytes = match (a.allocated_bytes, z.allocated_bytes) {
        (Some(x), Some(y)) => format!(", allocator {:.1}→{:.1} MiB", mib(x), mib(y)),
        _ => String::new(),
    };
    let rss_note = match (rss, rss_flat) {
        (RssJudged::Yes, true) => String::new(),
        (RssJudged::Yes, false) => ": resident memory GROWS".into(),
        (RssJudged::No(why), _) => format!("; not judged: {why}"),
    };
    let text = format!(
        "memory {} over {} checkpoints (frames {}–{}: buffers {}→{}, textures {}→{}, bind groups {}→{}, pipelines {}→{}{bytes}{}{heap}; resident {:.0} MiB at frame {}, {:.0} at {}, {:.0} at {}, peak {:.0}{rss_note})",
        if flat { "flat" } else { "GROWS" },
        c.len(),
        a.frame,
        z.frame,
        a.buffers,
        z.buffers,
        a.textures,
        z.textures,
        a.bind_groups,
        z.bind_groups,
        a.pipelines,
        z.pipelines,
        if gpu_flat { String::new() } else { format!(": GPU memory LEAKS ({})", grown.join(", ")) },
        a.rss_mib,
        a.frame,
        m.rss_mib,
        m.frame,
        z.rss_mib,
        z.frame,
        peak,
    );
    MemoryVerdict { text, flat, gpu_flat }
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// The process's resident memory in MiB (Linux; 0 elsewhere), after glibc has handed back
/// the free memory it keeps (what is left is memory in use, not the allocator's reserve).
pub fn rss_mib() -> f64 {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        unsafe extern "C" {
            fn malloc_trim(pad: usize) -> i32;
        }
        // SAFETY: malloc_trim only returns free heap memory to the system.
        unsafe {
            malloc_trim(0);
        }
    }
    let pages = std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1).and_then(|x| x.parse::<f64>().ok()))
        .unwrap_or(0.0);
    pages * 4096.0 / (1024.0 * 1024.0)
}

/// Dispatches the driver probe makes; lavapipe 22.3 keeps about 0.9 MiB per dispatch of the
/// probe, so the growth it measures is ~30 MiB there and under 1 MiB on a driver without
/// the problem.
const PROBE_DISPATCHES: u32 = 32;
/// Growth over the probe's dispatches above which the driver is taken to keep memory per
/// dispatch (64 KiB a dispatch: far above the noise of a trimmed heap, far below lavapipe's).
const PROBE_THRESHOLD_MIB: f64 = 2.0;

/// A compute kernel shaped like the passes in which lavapipe's growth was found: a window
/// whose size and thresholds come from a uniform. Inlining the uniform unrolls the loops and
/// drops the rejected branch, so the driver keeps inlining (and compiling) at every bind.
const PROBE_WGSL: &str = "
struct Params { n: vec4<u32>, t: vec4<f32> }
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var src: texture_2d<f32>;
@group(0) @binding(2) var aux: texture_2d<f32>;
@group(0) @binding(3) var dst: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn probe(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(dst);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let centre = textureLoad(aux, p, 0);
    let n = i32(params.n.x);
    let lo = -(n / 2);
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    for (var dy = lo; dy < lo + n; dy = dy + 1) {
        for (var dx = lo; dx < lo + n; dx = dx + 1) {
            let q = clamp(p + vec2<i32>(dx, dy), vec2<i32>(0), vec2<i32>(size) - 1);
            let a = textureLoad(aux, q, 0);
            if (a.w < 0.5 || abs(a.x - centre.x) > params.t.x || dot(a.yz, centre.yz) < params.t.y) {
                continue;
            }
            sum = sum + textureLoad(src, q, 0).rgb;
            count = count + 1.0;
        }
    }
    textureStore(dst, p, vec4<f32>(sum / max(count, 1.0), 1.0));
}
";

/// Measures how much resident memory the driver keeps per dispatch of a pipeline whose
/// uniform decides its loops and branches (see the module's text): the growth in MiB over
/// [`PROBE_DISPATCHES`] dispatches, each bound and submitted on its own. Everything the probe
/// makes is dropped before it returns.
pub fn driver_growth_mib(ctx: &GpuContext) -> f64 {
    let d = &ctx.device;
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("soak.driver_probe"),
        source: wgpu::ShaderSource::Wgsl(PROBE_WGSL.into()),
    });
    let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("soak.driver_probe"),
        layout: None,
        module: &module,
        entry_point: Some("probe"),
        compilation_options: Default::default(),
        cache: None,
    });
    use gi_render::passes::{create_target, uniform_buffer, view};
    let texture = |label: &str, usage| create_target(d, label, 16, 16, wgpu::TextureFormat::Rgba32Float, usage);
    let src = texture("soak.driver_probe.src", wgpu::TextureUsages::empty());
    let aux = texture("soak.driver_probe.aux", wgpu::TextureUsages::empty());
    let dst = texture("soak.driver_probe.dst", wgpu::TextureUsages::STORAGE_BINDING);
    let params = uniform_buffer(d, "soak.driver_probe.params", 32);
    // A 4×4 window, as the interleaved filter's default.
    let values: [u32; 8] = [4, 0, 0, 0, 0.1f32.to_bits(), 0.5f32.to_bits(), 0, 0];
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    ctx.queue.write_buffer(&params, 0, &bytes);
    let (src_v, aux_v, dst_v) =
        (view(&src, "soak.driver_probe.src"), view(&aux, "soak.driver_probe.aux"), view(&dst, "soak.driver_probe.dst"));
    let tv = wgpu::BindingResource::TextureView;
    let resources = [params.as_entire_binding(), tv(&src_v), tv(&aux_v), tv(&dst_v)];
    let entries: Vec<wgpu::BindGroupEntry> = resources
        .into_iter()
        .enumerate()
        .map(|(k, resource)| wgpu::BindGroupEntry { binding: k as u32, resource })
        .collect();
    let group = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("soak.driver_probe"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    let dispatch = || {
        let mut e = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("soak.driver_probe") });
        {
            let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("soak.driver_probe"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(2, 2, 1);
        }
        ctx.submit([e.finish()]);
        ctx.wait_idle();
    };
    // The first dispatches compile what any driver compiles once.
    for _ in 0..4 {
        dispatch();
    }
    let before = rss_mib();
    for _ in 0..PROBE_DISPATCHES {
        dispatch();
    }
    (rss_mib() - before).max(0.0)
}

/// Whether the resident memory can be judged on this device: not with `--no-rss-check`, and
/// not where the driver probe shows the driver keeping memory per dispatch.
pub fn rss_judged(ctx: &GpuContext, no_rss_check: bool) -> RssJudged {
    if no_rss_check {
        return RssJudged::No("--no-rss-check".into());
    }
    let growth = driver_growth_mib(ctx);
    if growth > PROBE_THRESHOLD_MIB {
        let info = &ctx.adapter_info;
        RssJudged::No(format!(
            "{} ({}) kept {growth:.0} MiB over {PROBE_DISPATCHES} dispatches of a pipeline whose uniform decides its branches: \
             a driver that compiles a new shader at each bind and keeps it (Mesa 22.3's lavapipe does)",
            info.name, info.driver_info
        ))
    } else {
        RssJudged::Yes
    }
}

#[cfg(test)]
mod tests {
    use super::{Checkpoint, RssJudged, memory_verdict};

    fn at(frame: u64, buffers: usize, rss_mib: f64) -> Checkpoint {
        Checkpoint {
            frame,
            buffers,
            textures: 10,
            bind_groups: 5,
            pipelines: 20,
            allocated_bytes: Some(1 << 24),
            heap_mib: Some(40.0),
            rss_mib,
        }
    }

    #[test]
    fn memory_that_levels_off_is_flat_and_a_leak_is_not() {
        let yes = RssJudged::Yes;
        let levelling: Vec<_> = (1..=20).map(|i| at(i * 100, 30, 400.0 - 200.0 / i as f64)).collect();
        let v = memory_verdict(&levelling, &yes);
        assert!(v.flat, "{}", v.text);
        let leaking: Vec<_> = (1..=20).map(|i| at(i * 100, 30, 200.0 + 20.0 * i as f64)).collect();
        let v = memory_verdict(&leaking, &yes);
        assert!(!v.flat && v.gpu_flat, "20 MiB per 100 frames is a leak, of resident memory only: {}", v.text);
        let mut first_use = levelling.clone();
        first_use[3].buffers += 2;
        assert!(memory_verdict(&first_use, &yes).flat, "objects made once and kept are not a leak");
        let adding: Vec<_> = (1..=20).map(|i| at(i * 100, 30 + i as usize, 300.0)).collect();
        let v = memory_verdict(&adding, &yes);
        assert!(!v.flat && !v.gpu_flat && v.text.contains("(buffers)"), "a buffer more at every return: {}", v.text);
        assert!(memory_verdict(&levelling[..1], &yes).text.contains("not checked"));
    }

    #[test]
    fn allocator_bytes_and_pipelines_are_gpu_memory() {
        let yes = RssJudged::Yes;
        let mut bytes: Vec<_> = (1..=10).map(|i| at(i * 100, 30, 300.0)).collect();
        for (i, c) in bytes.iter_mut().enumerate() {
            c.allocated_bytes = Some((1 << 24) + i as u64 * (1 << 19));
        }
        let v = memory_verdict(&bytes, &yes);
        assert!(!v.gpu_flat && v.text.contains("allocated bytes"), "512 KiB more at every return: {}", v.text);
        let mut jitter: Vec<_> = (1..=10).map(|i| at(i * 100, 30, 300.0)).collect();
        for (i, c) in jitter.iter_mut().enumerate() {
            c.allocated_bytes = Some((1 << 24) + (i as u64 * 7919) % 300);
        }
        assert!(memory_verdict(&jitter, &yes).gpu_flat, "staging that varies by bytes is not a leak");
        let mut pipes: Vec<_> = (1..=10).map(|i| at(i * 100, 30, 300.0)).collect();
        pipes[9].pipelines += 1;
        let v = memory_verdict(&pipes, &yes);
        assert!(!v.gpu_flat && v.text.contains("pipelines"), "{}", v.text);
    }

    #[test]
    fn resident_memory_not_judged_is_reported_with_its_reason_and_gpu_memory_still_decides() {
        let why = RssJudged::No("the driver keeps what it compiles".into());
        let leaking: Vec<_> = (1..=20).map(|i| at(i * 100, 30, 200.0 + 20.0 * i as f64)).collect();
        let v = memory_verdict(&leaking, &why);
        assert!(v.flat, "{}", v.text);
        assert!(
            v.text.contains("not judged: the driver keeps what it compiles") && v.text.contains("600 at 2000"),
            "{}",
            v.text
        );
        let adding: Vec<_> = (1..=20).map(|i| at(i * 100, 30 + i as usize, 300.0)).collect();
        assert!(!memory_verdict(&adding, &why).flat, "a GPU leak fails whatever the driver");
        let mut heap = leaking.clone();
        for (i, c) in heap.iter_mut().enumerate() {
            c.heap_mib = Some(40.0 + 2.0 * i as f64);
        }
        let v = memory_verdict(&heap, &why);
        assert!(!v.flat && v.gpu_flat && v.text.contains("heap GROWS"), "2 MiB of heap per return: {}", v.text);
        for (i, c) in heap.iter_mut().enumerate() {
            c.heap_mib = Some(60.0 - 20.0 / (i + 1) as f64);
        }
        assert!(memory_verdict(&heap, &why).flat, "a heap that levels off is flat");
    }
}
