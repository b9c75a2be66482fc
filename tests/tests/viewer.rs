//! The buffer viewer's colour mapping (`passes::view`) against its CPU twin
//! (`cpu::view`), and the pixel probe against full readbacks.

use gi_lab_tests::{default_renderer, gpu};
use gi_render::buffers::{BufferEntry, BufferKind, read_texture};
use gi_render::cpu::view::{INF_COLOUR, NAN_COLOUR, NEGATIVE_COLOUR, map_texel};
use gi_render::passes::view::{BufferView, Colormap, ViewMode, ViewPipeline, ViewSettings};
use gi_render::{GpuContext, ImageF32};

/// Renders the view of `entry` and checks every texel against the CPU twin applied to a
/// readback of the source; returns the number of texels compared.
fn check_view(ctx: &GpuContext, view: &mut BufferView, entry: &BufferEntry, s: &ViewSettings) -> usize {
    view.render(ctx, entry, s, false).unwrap_or_else(|e| panic!("{}: {e}", entry.name));
    let out = read_texture(ctx, "view.output", view.output().expect("output exists"), 0, 0).expect("readback");
    let src = read_texture(ctx, &entry.name, &entry.texture, s.layer, s.level).expect("source readback");
    assert_eq!((out.width, out.height), (src.width, src.height), "{}: output has the level's size", entry.name);
    let mut worst = 0.0f32;
    for (i, (o, v)) in out.data.iter().zip(&src.data).enumerate() {
        let want = map_texel(s, *v);
        for c in 0..3 {
            let e = (o[c] - want[c]).abs();
            if e > worst {
                worst = e;
            }
            assert!(
                e <= 1.5 / 255.0,
                "{} {:?} texel {i}: GPU {:?} vs CPU {want:?} for raw {v:?}",
                entry.name,
                s.mode,
                &o[..3]
            );
        }
    }
    out.data.len()
}

#[test]
fn view_of_every_kind_of_buffer_matches_the_cpu_twin() {
    let mut r = default_renderer(64, 48);
    for _ in 0..3 {
        r.render_frame();
    }
    let ctx = r.ctx.clone();
    let shared = ViewPipeline::new(&ctx);
    let mut view = BufferView::new(&ctx, shared);
    let cases: Vec<(&str, ViewSettings)> = vec![
        ("gbuffer.normal", ViewSettings::for_kind(BufferKind::Direction)),
        (
            "gbuffer.position",
            ViewSettings { mode: ViewMode::Channel, channel: 3, range: [0.0, 6.0], ..Default::default() },
        ),
        ("gbuffer.depth", ViewSettings::for_kind(BufferKind::Depth)),
        ("direct.shadow_map", ViewSettings { layer: 0, ..ViewSettings::for_kind(BufferKind::Depth) }),
        ("gbuffer.motion", ViewSettings::for_kind(BufferKind::Motion)),
        ("final.hdr", ViewSettings { exposure_ev: 1.0, log: true, range: [0.01, 4.0], ..Default::default() }),
        (
            "direct.radiance",
            ViewSettings {
                mode: ViewMode::Length,
                colormap: Colormap::Inferno,
                range: [0.0, 2.0],
                ..Default::default()
            },
        ),
        ("final.ldr", ViewSettings::for_kind(BufferKind::Ldr)),
    ];
    for (name, s) in cases {
        let entry = r.buffers().get(name).expect("registered").clone();
        assert!(check_view(&ctx, &mut view, &entry, &s) > 0);
    }
}

/// The auto-range reduced on the GPU (the view pass's min, max and histogram) gives the CPU's
/// `auto_range` of a read-back of the same buffer: min–max exactly, a percentile range within
/// one histogram bin (never narrower), in every mode and for float, depth and array buffers,
/// non-finite values left out.
#[test]
fn the_gpu_auto_range_matches_the_cpu() {
    use gi_render::cpu::view::{auto_range, order_key, range_from_stats};
    use gi_render::maths::colormap::RANGE_STATS_BYTES;
    let mut r = default_renderer(64, 48);
    for _ in 0..3 {
        r.render_frame();
    }
    let ctx = r.ctx.clone();
    let mut view = BufferView::new(&ctx, ViewPipeline::new(&ctx));
    let texels: Vec<[f32; 4]> = (0..40)
        .map(|i| [i as f32 * 0.25 - 2.0, if i == 7 { f32::NAN } else { 1.0 / (i as f32 + 1.0) }, 3.0, 1.0])
        .collect();
    let bytes: Vec<u8> = texels.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    let synthetic = BufferEntry {
        name: "tests.values".into(),
        description: String::new(),
        kind: BufferKind::Data,
        texture: texture_with(&ctx, wgpu::TextureFormat::Rgba32Float, &bytes, 40),
    };
    let entry = |name: &str| r.buffers().get(name).expect("registered").clone();
    let cases: Vec<(BufferEntry, ViewSettings)> = vec![
        (entry("final.hdr"), ViewSettings { exposure_ev: 1.0, ..Default::default() }),
        (entry("gbuffer.position"), ViewSettings { mode: ViewMode::Channel, channel: 3, ..Default::default() }),
        (entry("gbuffer.normal"), ViewSettings { mode: ViewMode::Length, ..Default::default() }),
        (entry("gbuffer.depth"), ViewSettings::for_kind(BufferKind::Depth)),
        (entry("direct.shadow_map"), ViewSettings { layer: 0, ..ViewSettings::for_kind(BufferKind::Depth) }),
        (synthetic.clone(), ViewSettings { mode: ViewMode::Channel, channel: 1, ..Default::default() }),
        (synthetic, ViewSettings::default()),
    ];
    for (e, s) in cases {
        view.render(&ctx, &e, &s, true).unwrap_or_else(|err| panic!("{}: {err}", e.name));
        let bytes = gi_render::buffers::read_storage(&ctx, view.range_stats(), RANGE_STATS_BYTES).expect("stats");
        let words: Vec<u32> = bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect();
        let img = read_texture(&ctx, &e.name, &e.texture, s.layer, s.level).expect("readback");
        // Min–max exactly, but a length, which the GPU's length() may round differently by
        // an ulp or two.
        let ulps = if s.mode == ViewMode::Length { 4 } else { 0 };
        let (got, want) = (range_from_stats(&words, s.exposure_ev, 0.0), auto_range(&s, &img, 0.0));
        let (got, want) = (got.expect("finite values"), want.expect("finite values"));
        for i in 0..2 {
            let d = order_key(got[i]).abs_diff(order_key(want[i]));
            assert!(d <= ulps, "{} {:?} min–max: GPU {got:?} vs CPU {want:?}", e.name, s.mode);
        }
        let bin = 1u32 << (32 - (words[1] - words[0]).leading_zeros()).saturating_sub(12);
        for p in [1.0, 5.0] {
            let scale = s.exposure_ev.exp2();
            let [lo, hi] = auto_range(&s, &img, p).expect("finite values").map(|v| v / scale);
            let [glo, ghi] = range_from_stats(&words, s.exposure_ev, p).expect("stats").map(|v| v / scale);
            let (k, gk) = ([order_key(lo), order_key(hi)], [order_key(glo), order_key(ghi)]);
            assert!(gk[0] <= k[0] && k[0] - gk[0] < bin, "{} {:?} {p} %: low {glo} vs {lo}", e.name, s.mode);
            assert!(gk[1] >= k[1] && gk[1] - k[1] < bin, "{} {:?} {p} %: high {ghi} vs {hi}", e.name, s.mode);
        }
    }
}

/// A texture of the given format filled with `texels` (one row).
fn texture_with(ctx: &GpuContext, format: wgpu::TextureFormat, bytes: &[u8], width: u32) -> wgpu::Texture {
    gi_lab_tests::texture_from_bytes(ctx, "tests.view_source", format, (width, 1), bytes)
}

#[test]
fn nan_inf_and_negative_values_are_flagged_and_uint_buffers_display() {
    let ctx = gpu();
    let mut view = BufferView::new(&ctx, ViewPipeline::new(&ctx));
    let texels: [[f32; 4]; 5] = [
        [f32::NAN, 0.5, 0.5, 1.0],
        [0.5, f32::INFINITY, 0.5, 1.0],
        [0.5, 0.5, -0.25, 1.0],
        [0.25, 0.5, 1.0, 1.0],
        [f32::NEG_INFINITY, 0.0, 0.0, 1.0],
    ];
    let bytes: Vec<u8> = texels.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    let t = texture_with(&ctx, wgpu::TextureFormat::Rgba32Float, &bytes, 5);
    let entry =
        BufferEntry { name: "tests.bad".into(), description: String::new(), kind: BufferKind::Data, texture: t };
    let s = ViewSettings { srgb: false, ..Default::default() };
    check_view(&ctx, &mut view, &entry, &s);
    let out = read_texture(&ctx, "out", view.output().expect("output"), 0, 0).expect("readback");
    let rgb = |i: usize| [out.data[i][0], out.data[i][1], out.data[i][2]];
    let is = |got: [f32; 3], want: [f32; 3]| got.iter().zip(want).all(|(a, b)| (a - b).abs() <= 1.0 / 255.0);
    assert!(is(rgb(0), NAN_COLOUR), "{:?}", rgb(0));
    assert!(is(rgb(1), INF_COLOUR), "{:?}", rgb(1));
    assert!(is(rgb(2), NEGATIVE_COLOUR), "{:?}", rgb(2));
    assert!(is(rgb(4), INF_COLOUR), "{:?}", rgb(4));
    assert!((rgb(3)[0] - 0.25).abs() < 1.0 / 255.0 && (rgb(3)[2] - 1.0).abs() < 1.0 / 255.0);
    // Overlay off: the values map through the range like any other.
    let quiet = ViewSettings { flag_nan_inf: false, flag_negative: false, srgb: false, ..Default::default() };
    check_view(&ctx, &mut view, &entry, &quiet);

    // A uint buffer (HCB masks, ISM depth keys) through a colour map.
    let ids: Vec<u8> = [0u32, 7, 15, 3].iter().flat_map(|v| v.to_le_bytes()).collect();
    let t = texture_with(&ctx, wgpu::TextureFormat::R32Uint, &ids, 4);
    let entry =
        BufferEntry { name: "tests.uint".into(), description: String::new(), kind: BufferKind::Data, texture: t };
    let s =
        ViewSettings { mode: ViewMode::Channel, colormap: Colormap::Turbo, range: [0.0, 15.0], ..Default::default() };
    assert_eq!(check_view(&ctx, &mut view, &entry, &s), 4);
}

#[test]
fn probe_reads_the_same_values_as_a_full_readback() {
    let mut r = default_renderer(40, 30);
    for _ in 0..2 {
        r.render_frame();
    }
    let pixels = [(0, 0), (20, 15), (39, 29), (7, 22)];
    let probes = r.probe(&pixels).expect("probe");
    assert_eq!(probes.len(), pixels.len());
    let names = r.buffers().names();
    for (values, &(x, y)) in probes.iter().zip(&pixels) {
        assert_eq!(values.len(), names.len(), "every registered buffer is probed");
        for v in values {
            let img: ImageF32 = r.readback(&v.name).expect("readback");
            let e = r.buffers().get(&v.name).expect("entry");
            let want_texel = (x * e.texture.width() / 40, y * e.texture.height() / 30);
            assert_eq!(v.texel, want_texel, "{}", v.name);
            let want = img.at(want_texel.0, want_texel.1);
            let same = v.value.iter().zip(want).all(|(a, b)| a == &b || (a.is_nan() && b.is_nan()));
            assert!(same, "{} at ({x}, {y}): probe {:?} vs readback {want:?}", v.name, v.value);
        }
    }
}
