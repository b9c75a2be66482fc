//! Gautron et al.'s record cache across frames (003, "Results": records reused while the scene
//! is static; stage 7): a moved object or a changed light invalidates the records it changes
//! and no other (GPU = CPU twin `cpu::gautron::fate`); invalid records are dropped or
//! computed again in place (`gautron.invalidation`); the popping while the scene animates is
//! measured with the flicker metric.

use gi_lab_tests::{paused_renderer, read};
use gi_render::Renderer;
use gi_render::cpu::gautron::{Changes, Fate, fate};
use gi_render::passes::gautron::{GpuRecord, Invalidation};
use gi_render::settings::pipeline::Technique;
use glam::Vec3;

fn renderer(invalidation: Invalidation) -> Renderer {
    let mut r = paused_renderer(96, Technique::Gautron, |s| s.gautron.invalidation = invalidation);
    // Only the test moves things.
    r.scene_mut().animations.clear();
    r
}

fn state(r: &Renderer) -> gi_render::passes::gautron::CacheState {
    r.gautron().unwrap().read_state(&r.ctx).unwrap()
}

fn records(r: &Renderer) -> Vec<GpuRecord> {
    let count = state(r).count;
    r.gautron().unwrap().read_records(&r.ctx, count).unwrap()
}

/// Frames until a frame makes no record and leaves no stale one, at most `max`.
fn settle(r: &mut Renderer, max: u32) -> u32 {
    for frame in 1..=max {
        r.render_frame();
        let st = state(r);
        if st.made == 0 && st.stale == 0 && st.refreshed == 0 {
            return frame;
        }
    }
    panic!("the cache had not settled after {max} frames: {:?}", state(r));
}

/// Pixels with geometry whose coverage is below 1/a (no record passes Ward's test).
fn uncovered(r: &Renderer) -> usize {
    let a = r.settings().gautron.accuracy;
    let (accum, normal) = (read(r, "gautron.accum"), read(r, "gbuffer.normal"));
    (0..accum.data.len()).filter(|&k| normal.data[k][3] > 0.5 && accum.data[k][3] < 1.0 / a).count()
}

/// The world bounds of scene draw `d` now.
fn draw_bounds(r: &Renderer, d: usize) -> (Vec3, Vec3) {
    let b = r.scene().draw_bounds(&r.scene().evaluate(0.0).draws[d]);
    (b.min, b.max)
}

/// Moves the node of the draw named `name` by `by`; returns the draw's index and the
/// changes the invalidation should see.
fn move_draw(r: &mut Renderer, name: &str, by: Vec3, refresh: bool) -> Changes {
    let draws = r.scene().evaluate(0.0).draws;
    let d = draws.iter().position(|d| r.scene().nodes[d.node].name == name).expect("the draw");
    let old = draw_bounds(r, d);
    let node = draws[d].node;
    r.scene_mut().nodes[node].transform.translation += by;
    let new = draw_bounds(r, d);
    Changes { moved: vec![d], bounds: vec![(old, new)], margin: r.bounds().radius() * 1e-3, lights: false, refresh }
}

/// Dropping: after the tall box moves, the cache holds exactly the records the CPU twin keeps,
/// in their order, unchanged, followed by the frame's new records; some records go (those
/// that saw the box or face it), others stay (those facing away from it).
#[test]
fn a_moved_object_drops_only_the_records_it_changes() {
    let mut r = renderer(Invalidation::Drop);
    settle(&mut r, 24);
    let before = records(&r);
    let changes = move_draw(&mut r, "tall_box", Vec3::new(0.0, 0.0, 0.08), false);
    r.render_frame();
    let st = state(&r);
    let after = records(&r);
    let kept: Vec<&GpuRecord> = before
        .iter()
        .filter(|g| {
            let f = fate(g.position.truncate(), g.normal.truncate(), g.seen, false, &changes);
            assert_ne!(f, Fate::Stale, "dropping never keeps a stale record");
            f == Fate::Keep
        })
        .collect();
    let saw = before.iter().filter(|g| g.saw(changes.moved[0])).count();
    eprintln!("{} records, {} saw the box, {} kept, {} made after the move", before.len(), saw, kept.len(), st.made);
    assert!(!kept.is_empty() && kept.len() < before.len() && saw < before.len(), "{} of {}", kept.len(), before.len());
    assert_eq!(after.len(), kept.len() + st.made as usize, "{st:?}");
    for (i, (g, k)) in after.iter().zip(&kept).enumerate() {
        assert_eq!(g, *k, "record {i}");
    }
}

/// Refreshing: after the tall box moves, the records the CPU twin invalidates stay (no holes:
/// every pixel is covered at the end of the frame, where dropping left some uncovered) and are
/// computed again in place over the next frames; the others are untouched.
#[test]
fn refreshing_keeps_the_coverage_and_computes_invalid_records_again() {
    let mut r = renderer(Invalidation::Refresh);
    let mut drop = renderer(Invalidation::Drop);
    settle(&mut r, 24);
    settle(&mut drop, 24);
    let before = records(&r);
    let changes = move_draw(&mut r, "tall_box", Vec3::new(0.0, 0.0, 0.08), true);
    move_draw(&mut drop, "tall_box", Vec3::new(0.0, 0.0, 0.08), false);
    let frame = r.clock.frame as f32;
    r.render_frame();
    drop.render_frame();
    let (holes, drop_holes) = (uncovered(&r), uncovered(&drop));
    let st = state(&r);
    let after = records(&r);
    let fates: Vec<Fate> =
        before.iter().map(|g| fate(g.position.truncate(), g.normal.truncate(), g.seen, false, &changes)).collect();
    let kept: Vec<(&GpuRecord, Fate)> = before.iter().zip(fates).filter(|(_, f)| *f != Fate::Drop).collect();
    let stale = kept.iter().filter(|(_, f)| *f == Fate::Stale).count();
    eprintln!(
        "{} records, {} kept ({stale} invalid), {} refreshed and {} made the first frame; uncovered pixels {holes} (dropping: {drop_holes})",
        before.len(),
        kept.len(),
        st.refreshed,
        st.made
    );
    assert!(stale > 0 && stale < kept.len(), "{stale} of {}", kept.len());
    assert_eq!(holes, 0, "refreshing leaves no pixel uncovered");
    assert!(drop_holes > 0, "the move is large enough that dropping leaves holes");
    assert_eq!(after.len(), kept.len() + st.made as usize);
    assert_eq!(st.stale as usize + st.refreshed as usize, stale, "{st:?}");
    for (i, (g, (k, f))) in after.iter().zip(&kept).enumerate() {
        assert_eq!(
            (g.position.truncate(), g.normal.truncate()),
            (k.position.truncate(), k.normal.truncate()),
            "record {i} stays in place"
        );
        match f {
            Fate::Keep => assert_eq!(g, *k, "record {i} is untouched"),
            _ if g.pixel.w == 2.0 => assert_eq!(g.irradiance, k.irradiance, "stale record {i} keeps its value"),
            _ => assert_eq!((g.pixel.w, g.irradiance.w), (1.0, frame), "record {i} computed again this frame"),
        }
    }
    let frames = settle(&mut r, 24);
    // A record computed again has a new R_k (what it sees moved): the coverage shifts a little.
    assert_eq!(uncovered(&r), 0);
    eprintln!("every invalid record computed again after {frames} frames; {} records then", state(&r).count);
}

/// A light change (here the direct light's intensity, doubled) invalidates every record;
/// refreshed in place, every record's irradiance and gradients double (the direct light is
/// linear in the intensity and the default scene emits nothing), positions unchanged.
#[test]
fn a_light_change_computes_every_record_again() {
    let mut r = renderer(Invalidation::Refresh);
    settle(&mut r, 24);
    let before = records(&r);
    let mut s = r.settings().clone();
    s.direct.intensity_scale *= 2.0;
    r.set_settings(s).unwrap();
    r.render_frame();
    let st = state(&r);
    assert_eq!((st.made, st.stale + st.refreshed), (0, before.len() as u32), "{st:?}");
    settle(&mut r, 24);
    // Neighbour clamping shrinks some refreshed R_k more than the first time (all the
    // neighbours are fresh at once now), which can leave a pixel for a new record.
    let after = records(&r);
    assert!(after.len() >= before.len() && after.len() <= before.len() + 4, "{} vs {}", after.len(), before.len());
    let mut worst = (0.0f32, 0.0f32, 0.0f32);
    for (i, (a, b)) in after.iter().zip(&before).enumerate() {
        assert_eq!(
            (a.position.truncate(), a.normal.truncate()),
            (b.position.truncate(), b.normal.truncate()),
            "record {i}"
        );
        // The hemisphere is rasterized into another tile of the atlas this time: its texels
        // see the scene from positions that differ in the last bits (measured: 5.8e-5 in a
        // release build, 1.2e-4 in a debug one with neighbour clamping's records).
        let scale = b.irradiance.truncate().max_element().max(1e-12);
        // H before the clamps (R_k after them depends on the neighbours computed with it)
        worst.0 = worst.0.max((a.normal.w / b.normal.w - 1.0).abs());
        worst.1 = worst.1.max((a.irradiance.truncate() - 2.0 * b.irradiance.truncate()).abs().max_element() / scale);
        assert!(
            (a.irradiance.truncate() - 2.0 * b.irradiance.truncate()).abs().max_element() <= 3e-4 * scale,
            "record {i}: {:?} vs 2 × {:?}",
            a.irradiance,
            b.irradiance
        );
        // ∇t relative to the value compared (twice the old one), whose edge terms depend on
        // which texels see an edge: measured 7.4e-4 for a record 1.3 cm from a wall.
        for c in 0..3 {
            let want = 2.0 * b.trans[c];
            let t = (a.trans[c] - want).abs().max_element();
            worst.2 = worst.2.max(t / want.abs().max_element().max(2.0 * scale));
            assert!(
                t <= 1e-3 * want.abs().max_element().max(2.0 * scale),
                "record {i}: ∇t {c}: {:?} vs 2 × {:?} (H {})",
                a.trans[c],
                b.trans[c],
                b.normal.w
            );
        }
    }
    eprintln!(
        "refreshed records: H within {:.2e}, E within {:.2e} and ∇t within {:.2e} of twice the old",
        worst.0, worst.1, worst.2
    );
    // H as well, from the same texels: its grazing texels' distances are the most sensitive
    // (measured 1.6e-4 for a record 8 mm above the floor with H = 4 cm, at the normals of the
    // packed G-buffer, issue #53: the record's hemisphere is oriented by the unpacked normal).
    assert!(worst.0 < 2e-4, "H within {:.2e}", worst.0);

    // Dropping instead: a light change empties the cache.
    let mut s = r.settings().clone();
    s.gautron.invalidation = Invalidation::Drop;
    s.direct.intensity_scale *= 0.5;
    r.set_settings(s).unwrap();
    r.render_frame();
    let st = state(&r);
    assert_eq!(st.made, st.count, "{st:?}");
}

/// Popping while the scene's animations play (the sphere slides, the short box turns): the
/// flicker of the final images over consecutive frames with the cache refreshing invalid
/// records, dropping them, and without a cache (every frame cold). Refreshing flickers least
/// and leaves almost no pixel uncovered.
#[test]
fn popping_while_the_scene_animates() {
    let run = |temporal: gi_render::settings::pipeline::Temporal, invalidation: Invalidation| {
        let mut r = paused_renderer(96, Technique::Gautron, |s| {
            s.pipeline.temporal = temporal;
            s.gautron.invalidation = invalidation;
        });
        if temporal == gi_render::settings::pipeline::Temporal::RecordCache {
            settle(&mut r, 24);
        }
        r.clock.playing = true;
        let mut frames = Vec::new();
        let mut holes = 0;
        for _ in 0..12 {
            r.render_frame();
            frames.push(read(&r, "gautron.indirect"));
            holes += uncovered(&r);
        }
        (gi_render::metrics::flicker(&frames).unwrap(), holes)
    };
    use gi_render::settings::pipeline::Temporal;
    let (refresh, refresh_holes) = run(Temporal::RecordCache, Invalidation::Refresh);
    let (drop, drop_holes) = run(Temporal::RecordCache, Invalidation::Drop);
    let (cold, cold_holes) = run(Temporal::None, Invalidation::Refresh);
    eprintln!(
        "flicker over 12 animated frames: refresh {refresh:.4} ({refresh_holes} uncovered pixel-frames), drop {drop:.4} ({drop_holes}), cold {cold:.4} ({cold_holes})"
    );
    // Measured (96², neighbour clamping on, refreshed records clamped again): refresh 0.0183
    // with 2 uncovered pixel-frames, drop 0.0333 with 2,195, cold 0.0295 with 2,425 (without
    // clamping: 0 holes when refreshing; the last round's clamp of cached records can uncover
    // a pixel that only the next frame's first round fills).
    assert!(refresh_holes * 100 <= drop_holes, "refresh {refresh_holes} vs drop {drop_holes} uncovered");
    assert!(refresh < drop, "refresh {refresh} vs drop {drop}");
}
