//! The window never waits for the GPU (issue #38 point 1): with the probe hovering, pinned
//! probes, the statistics panes, every overlay, an auto-ranging viewer and the A/B metrics on,
//! no frame of any technique makes a blocking wait (`gi_render::counters`), and every one of
//! those features still gets its data, a frame or two late.

use egui_kittest::Harness;
use gi_lab::ui::app::GiLabApp;
use gi_lab::ui::session::PinnedProbe;
use gi_lab_tests::ui_harness::{arrived, harness, pause, run_until, show_in_viewer};
use gi_render::settings::pipeline::Technique;

fn waits_over(h: &mut Harness<'static, GiLabApp>, steps: usize) -> u64 {
    let before = gi_render::counters::now();
    for _ in 0..steps {
        h.run_steps(1);
    }
    (gi_render::counters::now() - before).blocking_waits
}

#[test]
fn no_frame_of_the_window_waits_for_the_gpu_with_every_readback_on() {
    let (mut h, _dir) = harness("no_wait");
    // Small frames (about 100×90 pixels, the probes and the explained pixel inside): the test
    // asks whether a frame waits, not what it shows.
    h.state_mut().state.session.render_scale = 0.1;
    pause(&mut h);
    h.run_steps(2);
    // An auto-ranging viewer.
    show_in_viewer(&mut h, "gbuffer.position");
    if let Some(v) = h.state_mut().state.viewers.open.values_mut().next() {
        v.state.range_mode = gi_lab::ui::viewer::RangeMode::MinMax;
    }
    // The hovered pixel and two pinned probes.
    let vp = h.state().state.viewport_rect;
    h.hover_at(vp.center());
    {
        let st = &mut h.state_mut().state;
        st.probes.pinned.push(PinnedProbe { pixel: (20, 30), buffer: "final.hdr".into(), channel: 0 });
        st.probes.pinned.push(PinnedProbe { pixel: (60, 40), buffer: "gbuffer.normal".into(), channel: 0 });
        st.probes.history.resize_with(2, Default::default);
        // Every overlay.
        st.overlays.vpls = true;
        st.overlays.hcb_samples = true;
        st.overlays.soler_samples = true;
        st.overlays.gautron_records = true;
        // A pixel explained (issue #42).
        st.explain = Some(gi_lab::ui::explain::ExplainView::new((30, 40)));
        // A/B with its FLIP view.
        st.start_ab(gi_lab::ui::ab::AbSource::Frozen);
        st.ab.as_mut().expect("A/B starts").view = gi_lab::ui::ab::AbView::Flip;
    }
    for t in [
        Technique::Knecht,
        Technique::NguyenCached,
        Technique::Soler,
        Technique::Gautron,
        Technique::GautronVplRecords,
        Technique::ExactVpl,
    ] {
        if let Ok(l) = &mut h.state_mut().state.lab {
            t.apply(&mut l.settings);
            l.apply_settings();
        }
        if let Some(v) = &mut h.state_mut().state.explain {
            v.latest = None;
        }
        // Warm-up: the technique's passes are made, its first read-backs arrive (a few frames
        // late, more under load).
        let overlay = match t {
            Technique::Knecht | Technique::ExactVpl => "vpl.list",
            Technique::NguyenCached => "hcb.stats",
            Technique::Soler => "soler.samples.1",
            _ => "gautron.records",
        };
        run_until(&mut h, 40, |a| {
            arrived(a, overlay)
                && arrived(a, "ab.final.ldr")
                && a.state.viewers.open.values().next().is_some_and(|v| v.auto_range_frame().is_some())
                && !a.state.probes.values.is_empty()
                && a.state.ab.as_ref().is_some_and(|ab| ab.metrics.is_some())
                && a.state.explain.as_ref().is_some_and(|v| v.latest.is_some())
        });
        let waits = waits_over(&mut h, 8);
        assert_eq!(waits, 0, "{t:?}: the window waited for the GPU {waits} times in 8 frames");

        // Every feature got data without waiting.
        let st = &h.state().state;
        assert!(!st.probes.values.is_empty(), "{t:?}: the hovered probe has no values");
        assert!(st.probes.history.iter().all(|p| !p.is_empty()), "{t:?}: a pinned probe has no history");
        let r = &st.lab.as_ref().expect("lab").renderer;
        let arrived = |key: &str| r.read_latest(key).is_some_and(|a| a.data.is_ok());
        // The GPU's statistics arrived and set the range (positions span more than [0, 1]).
        assert!(
            st.viewers.open.values().next().is_some_and(|v| v.auto_range_frame().is_some()
                && v.state.view.range[1] > v.state.view.range[0]
                && v.state.view.range != [0.0, 1.0]),
            "{t:?}: the viewer's auto-range"
        );
        assert!(arrived("ab.final.hdr") && arrived("ab.final.ldr"), "{t:?}: A/B's images");
        match st.explain.as_ref().and_then(|v| v.latest.as_ref()) {
            Some(Ok(e)) => assert!(!e.contributions.is_empty(), "{t:?}: the explanation lists nothing"),
            // The reference's average may complete within the frames: nothing left to replay.
            Some(Err(e)) if t == Technique::ExactVpl && e.contains("complete") => {}
            other => panic!("{t:?}: the pixel's explanation did not arrive: {other:?}"),
        }
        assert!(st.ab.as_ref().is_some_and(|a| a.metrics.is_some()), "{t:?}: A/B's FLIP and RMSE");
        match t {
            Technique::Knecht | Technique::ExactVpl => assert!(arrived("vpl.list"), "{t:?}: the VPL overlay"),
            Technique::NguyenCached => assert!(arrived("hcb.stats"), "{t:?}: the HCB pane and overlay"),
            Technique::Soler => {
                assert!(arrived("soler.samples.1"), "{t:?}: the Soler samples overlay");
            }
            _ => assert!(arrived("gautron.records"), "{t:?}: the records overlay"),
        }
    }
}
