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
    view.render(ctx, entry, s).unwrap_or_else(|e| panic!("{}: {e}", entry.name));
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
