//! Explain a pixel (issue #42) for Soler et al.'s screen-space gather (004 §4, Fig. 4, Eq. 6):
//! the replay's level contributions sum to `soler.indirect` and, with the warped history, to
//! `soler.temporal`; each reached texel's upsampling weight equals the CPU twin's chain
//! (`cpu::soler::upsample`, applied to a unit light at that texel) and its E the level's own
//! gathered light.

use std::collections::HashMap;

use gi_lab_tests::{paused_renderer, read, soler_level, v3};
use gi_render::cpu::soler::{Level, UpsampleSigmas, upsample};
use gi_render::explain::{Explanation, luminance};
use gi_render::settings::pipeline::Technique;
use glam::Vec3;

/// The sums are of f32 terms; `soler.temporal` is a half float (a step of 2⁻¹¹ relative) and
/// so is the warped history it blends: two half steps.
const SUM_TOLERANCE: f32 = 2.0 * 4.9e-4;

fn field(c: &gi_render::explain::Contribution, name: &str) -> f32 {
    c.fields.iter().find(|(k, _)| *k == name).map(|(_, v)| *v).unwrap_or_else(|| panic!("{}: no {name}", c.name))
}

/// The CPU twin's weight of every texel of levels 1 … top to fine pixel `p`: the upsampling of
/// level k + 1 into level k applied to a unit light at each of the four coarse texels.
fn cpu_chain(levels: &[Level], p: (u32, u32), s: UpsampleSigmas) -> Vec<HashMap<(u32, u32), f32>> {
    let mut chain = vec![HashMap::from([(p, 1.0f32)])];
    for k in 0..levels.len() - 1 {
        let (fine, coarse) = (&levels[k], &levels[k + 1]);
        let mut next: HashMap<(u32, u32), f32> = HashMap::new();
        for (&(x, y), &w) in &chain[k] {
            let Some(t) = fine.at(x as i64, y as i64) else { continue };
            for ((cx, cy), _) in gi_render::cpu::soler::coarse_footprint(x, y) {
                if coarse.at(cx, cy).is_none() {
                    continue;
                }
                let mut light = vec![Vec3::ZERO; coarse.texels.len()];
                light[(cy as u64 * coarse.width as u64 + cx as u64) as usize] = Vec3::ONE;
                let up = upsample(coarse, &light, t, x, y, s).x;
                if up > 0.0 {
                    *next.entry((cx as u32, cy as u32)).or_default() += w * up;
                }
            }
        }
        chain.push(next);
    }
    chain
}

fn check(r: &gi_render::Renderer, e: &Explanation) {
    let total = e.total_check();
    assert!(total.relative_error() <= SUM_TOLERANCE, "{}", e.to_text(6));
    for c in &e.checks {
        assert!(c.relative_error() <= 1e-5, "{}: {}\n{}", c.what, c.relative_error(), e.to_text(6));
    }
    assert!(luminance(e.value) > 0.0, "{}", e.to_text(6));
    let s = &r.settings().soler;
    let top = s.gathered_levels().end - 1;
    let levels: Vec<Level> = (0..=top).map(|k| soler_level(r, k, "direct.radiance")).collect();
    let sigmas = UpsampleSigmas { depth: s.upsample_sigma_depth, normal: s.upsample_sigma_normal };
    let chain = cpu_chain(&levels, e.pixel, sigmas);
    let mut compared = 0;
    // A texel's row ("level k (x, y)"), or one of its ring samples' ("level k (x, y) #i"): the
    // heaviest texel of each level is listed sample by sample.
    let texel_of = |c: &gi_render::explain::Contribution| {
        let coords = c.name.split(['(', ')', ',']).filter_map(|t| t.trim().parse::<u32>().ok()).collect::<Vec<_>>();
        (field(c, "level") as u32, (coords[0], coords[1]))
    };
    let mut rings = std::collections::BTreeSet::new();
    for c in e.contributions.iter().filter(|c| c.name.starts_with("level ") && c.name.contains('#')) {
        let (k, t) = texel_of(c);
        let cpu = chain[k as usize].get(&t).copied().unwrap_or(0.0);
        assert!((field(c, "w (upsampling)") - cpu).abs() <= 1e-4 * cpu.max(1e-3), "ring of level {k} texel {t:?}");
        rings.insert((k, t));
    }
    for c in e.contributions.iter().filter(|c| c.name.starts_with("level ") && !c.name.contains('#')) {
        let (k, t) = texel_of(c);
        let cpu = chain[k as usize].get(&t).copied().unwrap_or(0.0);
        let gpu = field(c, "w (upsampling)");
        assert!((gpu - cpu).abs() <= 1e-4 * cpu.max(1e-3), "level {k} texel {t:?}: GPU weight {gpu}, CPU twin {cpu}");
        let own = read(r, &format!("soler.level.{k}.indirect"));
        let e_k = luminance(v3(own.at(t.0, t.1)));
        assert!((field(c, "E (lum)") - e_k).abs() <= 1e-6 * e_k.max(1.0), "level {k} texel {t:?}: E");
        compared += 1;
    }
    // Every texel the CPU chain reaches on a gathered level is listed, alone or by its ring's
    // samples (those with lit samples: a ring with none lists no sample).
    for k in s.gathered_levels() {
        let prefix = format!("level {k} ");
        let alone = e.contributions.iter().filter(|c| c.name.starts_with(&prefix) && !c.name.contains('#')).count();
        let by_ring = rings.iter().filter(|(l, _)| *l == k).count();
        let reached = chain[k as usize].values().filter(|&&w| w > 0.0).count();
        assert_eq!(alone + by_ring, reached, "level {k}: {alone} texels and {by_ring} rings listed");
    }
    // The heaviest texels' rings: their visible samples sum to the texel's own light.
    let ring_checks: Vec<_> = e.checks.iter().filter(|c| c.what.starts_with("Σ visible ring samples")).collect();
    assert!(!ring_checks.is_empty(), "{}", e.to_text(0));
    assert!(compared > 0);
}

#[test]
fn levels_sum_to_the_upsampled_light_and_their_weights_are_the_cpu_twins() {
    let presets = [
        include_str!("../../../presets/soler-quarter-4-64.ron"),
        include_str!("../../../presets/soler-as-printed.ron"),
    ];
    for (i, text) in presets.into_iter().enumerate() {
        let s = gi_render::preset::load_lenient(text, "soler").expect("loads").settings;
        let mut r = paused_renderer(64, Technique::Soler, |x| *x = s.clone());
        for p in [(32, 56), (32, 20), (6, 30), (24, 36)] {
            r.set_explain(Some(p));
            for _ in 0..3 {
                r.render_frame();
            }
            let e = r.explanation().unwrap_or_else(|e| panic!("preset {i} pixel {p:?}: {e}"));
            check(&r, &e);
            if r.settings().pipeline.temporal == gi_render::settings::pipeline::Temporal::WarpedBlend {
                assert_eq!(e.buffer, "soler.temporal");
                let h = e.contributions.iter().find(|c| c.name == "history").expect("the history's share");
                assert!(field(h, "a") > 0.0, "{}", e.to_text(4));
            }
        }
    }
}

/// 004 §4 "Multi-bounce": the stage replays each bounce right after gathering it, so every
/// bounce's levels are listed and their sum is `soler.indirect`; with alternating bounces the
/// bounces this frame did not gather are read from what was kept.
#[test]
fn every_bounce_is_listed_and_the_kept_ones_with_alternating_bounces() {
    for alternate in [false, true] {
        let text = include_str!("../../../presets/soler-quarter-4-64.ron");
        let s = gi_render::preset::load_lenient(text, "soler").expect("loads").settings;
        let mut r = paused_renderer(64, Technique::Soler, |x| {
            *x = s.clone();
            x.soler.bounces = 3;
            x.soler.alternate_bounces = alternate;
        });
        for p in [(32, 56), (6, 30)] {
            r.set_explain(Some(p));
            for _ in 0..4 {
                r.render_frame();
            }
            let e = r.explanation().unwrap_or_else(|e| panic!("pixel {p:?}: {e}"));
            let total = e.total_check();
            assert!(total.relative_error() <= SUM_TOLERANCE, "{}", e.to_text(6));
            for c in &e.checks {
                assert!(c.relative_error() <= 1e-5, "{}: {}\n{}", c.what, c.relative_error(), e.to_text(6));
            }
            let bounce = |b: u32| {
                e.contributions
                    .iter()
                    .filter(|c| c.fields.iter().any(|(k, v)| *k == "bounce" && *v == b as f32))
                    .count()
            };
            assert!((1..=3).all(|b| bounce(b) > 0), "every bounce is listed:\n{}", e.to_text(0));
            let kept = e.contributions.iter().filter(|c| c.name.ends_with("(kept)")).count();
            assert_eq!(kept, if alternate { 2 } else { 0 }, "{}", e.to_text(0));
        }
    }
}
