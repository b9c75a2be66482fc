//! Emissive surfaces as lights (issue #18 point 1): the emitter VPLs' direct light against its
//! CPU twin, the real Cornell box lit only by its ceiling quad against the path tracer in
//! every technique, emitters that only glow, and thousands of emissive triangles.

use gi_lab_tests::images::{exposed_flip, mean, sub};
use gi_lab_tests::{read, real_scene, scene_renderer};
use gi_render::ImageF32;
use gi_render::cpu::knecht;
use gi_render::cpu::pathtrace::{PathTracer, PtSettings};
use gi_render::metrics::scaled;
use gi_render::scene::emitters::{Emitters, add_glowing_sphere};
use gi_render::scene::{LoadOptions, Scene, load_gltf_file};
use glam::Vec3;

/// The classic Cornell box, seen from the front through its open side (the view these
/// tests' bounds were measured from; the framing rule of issue #37 picks a three-quarter
/// view).
fn cornell() -> Scene {
    let mut scene = load_gltf_file(&real_scene("cornell-box/CornellBox-Original.gltf"), &LoadOptions::default())
        .expect("the real Cornell box loads");
    let camera = gi_render::camera::Camera::frame_bounds(scene.bounds(0.0), 1.0);
    scene.view = Some(gi_render::scene::framing::Framing {
        camera,
        kind: gi_render::scene::framing::ViewKind::Exterior,
        reason: "the front view of the tests".into(),
        room: None,
        fit_points: Vec::new(),
    });
    scene
}

#[test]
fn emitter_direct_light_matches_its_cpu_twin() {
    // No visibility: the direct pass's emitter sum against cpu::knecht::vpl_radiance of the
    // same VPLs at every covered pixel.
    let size = 48;
    let mut r = scene_renderer(cornell(), size, |s| {
        gi_render::settings::pipeline::Technique::DirectOnly.apply(s);
        s.apply_override("emitters.visibility=None").expect("valid");
    });
    r.render_frame();
    let stats = r.emitter_stats().expect("the box has an emitter");
    assert_eq!(stats.triangles, 2);
    assert_eq!(stats.vpls, 64, "emitters.vpls VPLs");
    assert_eq!(stats.bounce_share, 0, "no VPL technique runs: no first-bounce share");
    let state = r.scene().evaluate(0.0);
    let emitters = Emitters::collect(r.scene(), &state);
    let d_min = r.settings().emitters.min_distance * emitters.spacing(stats.vpls);
    let vpls: Vec<knecht::Vpl> = emitters
        .vpls(stats.vpls, 0)
        .iter()
        .map(|v| knecht::Vpl {
            position: v.position,
            normal: v.normal,
            flux: v.flux,
            incident: v.normal,
            albedo: Vec3::ONE,
            di: 1.0,
            si: 0.0,
            sp: 1.0,
        })
        .collect();
    let (pos, nrm, alb, mat) = (
        read(&r, "gbuffer.position"),
        read(&r, "gbuffer.normal"),
        read(&r, "gbuffer.albedo"),
        read(&r, "gbuffer.material"),
    );
    let direct = read(&r, "direct.radiance");
    let eye = r.camera.position;
    let (mut worst, mut covered, mut lit) = (0.0f32, 0, 0);
    for i in 0..direct.data.len() {
        if nrm.data[i][3] < 0.5 {
            continue;
        }
        covered += 1;
        let x = knecht::Receiver {
            position: Vec3::from_slice(&pos.data[i][..3]),
            normal: Vec3::from_slice(&nrm.data[i][..3]).normalize(),
            albedo: Vec3::from_slice(&alb.data[i][..3]),
            di: alb.data[i][3],
            si: mat.data[i][0],
            sp: mat.data[i][1],
        };
        let cpu: Vec3 = vpls.iter().map(|v| knecht::vpl_radiance(v, &x, eye, d_min)).sum();
        let gpu = Vec3::from_slice(&direct.data[i][..3]);
        if cpu.max_element() > 0.0 {
            lit += 1;
        }
        worst = worst.max((gpu - cpu).abs().max_element() / cpu.max_element().max(1e-3));
    }
    assert!(covered > 1000 && lit > covered / 2, "{lit} of {covered} pixels lit by the emitter");
    assert!(worst < 1e-3, "largest relative difference GPU vs CPU twin {worst}");
}

#[test]
fn the_shared_cornell_box_lit_only_by_its_ceiling_quad_matches_the_path_tracer() {
    let size = 96;
    let scene = cornell();
    assert!(scene.lights.is_empty(), "no punctual light, no default one");
    let mut pt = PathTracer::new(&scene, 0.0);
    let probe = scene_renderer(scene.clone(), size, |_| {});
    let (view_proj, eye) = (probe.view_proj(), probe.camera.position);
    drop(probe);
    let truth =
        pt.render(view_proj, eye, size, size, PtSettings { bounces: 1, spp: 256, seed: 3, ..Default::default() });
    let truth_indirect = mean(&truth.indirect);
    assert!(mean(&truth.direct) > 0.0 && truth_indirect > 0.0);
    let direct_only_flip = exposed_flip(&truth.direct, &truth.full);
    // (technique, frames, FLIP bound, lowest share of the path tracer's indirect light).
    // Measured on lavapipe at 96² (direct only: FLIP 0.120): knecht 0.0775 with 0.85 of the
    // indirect light, nguyen 0.0803 / 0.81, soler 0.1026 / 0.60 (the screen-space gather sees
    // only the senders on screen), gautron 0.0630 / 0.89; the bounds are those + ~20 %.
    // Issue #51's consistent vote (`soler.vote_consistent`: a coarse texel keeps only the light
    // of the sub-pixels facing as its winner) took Soler's share to 0.474 at the same FLIP
    // (0.1026 → 0.1028): at 24² texels most of this box's blocks mix two walls, and a wall's
    // light no longer leaves along the other's normal. Its lowest share is that − 20 %.
    let cases: [(&str, u32, f64, f64); 4] =
        [("knecht", 8, 0.095, 0.7), ("nguyen", 4, 0.097, 0.65), ("soler", 4, 0.123, 0.38), ("gautron", 6, 0.076, 0.7)];
    for (name, frames, bound, least) in cases {
        let mut r = scene_renderer(scene.clone(), size, |s| {
            let t = match name {
                "knecht" => gi_render::settings::pipeline::Technique::Knecht,
                "nguyen" => gi_render::settings::pipeline::Technique::Nguyen,
                "soler" => gi_render::settings::pipeline::Technique::Soler,
                _ => gi_render::settings::pipeline::Technique::Gautron,
            };
            t.apply(s);
        });
        for _ in 0..frames {
            r.render_frame();
        }
        let (direct, emission, full) =
            (read(&r, "direct.radiance"), read(&r, "gbuffer.emission"), read(&r, "final.hdr"));
        let indirect = sub(&sub(&full, &direct), &emission);
        let direct_flip = exposed_flip(&direct, &truth.direct);
        let ratio = mean(&indirect) / truth_indirect;
        let f = exposed_flip(&full, &truth.full);
        println!(
            "{name}: direct FLIP {direct_flip:.4}, indirect mean {ratio:.3} × the path tracer's, full FLIP {f:.4} (direct only {direct_only_flip:.4})"
        );
        assert!(direct_flip < 0.08, "{name}: the emitter's direct light against the path tracer's: FLIP {direct_flip}");
        assert!((least..1.5).contains(&ratio), "{name}: indirect light {ratio} × the path tracer's");
        assert!(f < bound, "{name}: FLIP {f} against the path tracer (bound {bound})");
        assert!(f < direct_only_flip, "{name}: the indirect light brings it closer ({f} vs {direct_only_flip})");
    }
    // With emitters off the box only glows: nothing is lit, and the path tracer agrees.
    pt.set_emitter_lights(false, &scene, 0.0);
    let dark = pt.render(view_proj, eye, size, size, PtSettings { bounces: 1, spp: 4, seed: 3, ..Default::default() });
    let mut r = scene_renderer(scene, size, |s| s.emitters.enabled = false);
    r.render_frame();
    assert!(r.emitter_stats().is_none());
    let (direct, emission, full) = (read(&r, "direct.radiance"), read(&r, "gbuffer.emission"), read(&r, "final.hdr"));
    assert_eq!(mean(&direct), 0.0, "emitters off: no direct light");
    assert!(mean(&sub(&full, &emission)).abs() < 1e-9, "emitters off: the image is their glow alone");
    assert!(
        mean(&dark.indirect) == 0.0 && (mean(&dark.full) - mean(&emission)).abs() < 1e-3 * mean(&emission).max(1e-3)
    );
}

#[test]
fn thousands_of_emissive_triangles_keep_the_vpl_budget() {
    let mut scene = gi_lab_tests::default_scene();
    let b = scene.bounds(0.0);
    let tris = add_glowing_sphere(&mut scene, b.center(), 0.08 * b.radius(), 48, 64, Vec3::splat(20.0));
    assert!(tris > 5000, "{tris} triangles");
    let mut r = scene_renderer(scene, 64, |_| {});
    r.render_frame();
    r.render_frame();
    let e = r.emitter_stats().expect("the sphere glows");
    assert_eq!(e.triangles, tris);
    let s = r.settings();
    assert_eq!(e.vpls, s.emitters.vpls, "the emitter VPLs do not grow with the triangles");
    assert_eq!(e.bounce_budget, s.vpl.count);
    assert!(e.bounce_share > 0 && e.bounce_share <= s.vpl.count, "{e:?}");
    let vpls = r.vpl_list().expect("VPLs");
    let filled = vpls.iter().filter(|v| v.position.w > 0.5).count() as u32;
    assert!(filled <= s.vpl.count * s.vpl.bounces, "{filled} VPLs in the list");
}

/// An emissive texture shapes the emitter's light (issue #18 point 1: emission = factor ×
/// texture × strength): the real Cornell box's ceiling quad with a texture black on its
/// −x half emits half the power, from its +x half only, and the lab's direct light (emitter
/// VPLs, imperfect shadow maps) matches the path tracer's, which reads the same texels at its
/// hits and light samples. Measured on lavapipe at 64² (PT 256 spp), looking up at the quad:
/// direct light and glow FLIP 0.038 (0.054 when the G-buffer ignores the texture), power
/// 0.50 × the untextured quad's, 40 glowing pixels as in the path tracer (69 without the
/// texture); the FLIP bound is the measure + 20 %.
#[test]
fn an_emissive_texture_shapes_the_emitters_light() {
    let size = 64;
    let plain = cornell();
    let mut scene = plain.clone();
    let light = scene.materials.iter().position(|m| m.emissive.max_element() > 0.0).expect("the quad's material");
    let rgba8: Vec<u8> = (0..16 * 16).flat_map(|i| if i % 16 < 8 { [0, 0, 0, 255] } else { [255; 4] }).collect();
    scene.textures.push(gi_render::scene::TextureImage {
        name: "half".into(),
        width: 16,
        height: 16,
        rgba8: rgba8.into(),
    });
    scene.materials[light].emissive_texture = Some(scene.textures.len() - 1);
    // u runs along x over the quad (its vertices are at the quad's corners).
    let quad: Vec<[f32; 3]> = scene
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .filter(|p| p.material == light)
        .flat_map(|p| p.vertices.iter().map(|v| v.position))
        .collect();
    let (lo, hi) = quad.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[0]), hi.max(p[0])));
    for p in scene.meshes.iter_mut().flat_map(|m| &mut m.primitives).filter(|p| p.material == light) {
        for v in &mut p.vertices {
            v.uv = [(v.position[0] - lo) / (hi - lo), 0.5];
        }
    }
    let mid = 0.5 * (lo + hi);
    let (e_plain, e_tex) =
        (Emitters::collect(&plain, &plain.evaluate(0.0)), Emitters::collect(&scene, &scene.evaluate(0.0)));
    let share = e_tex.luminance_power() / e_plain.luminance_power();
    assert!((share - 0.5).abs() < 0.05, "half the quad is black: {share} of the power");
    // World x of the quad is the node's x (the real box has identity node transforms).
    let vpls = e_tex.vpls(256, 0);
    assert!(vpls.iter().filter(|v| v.flux.max_element() > 0.0).all(|v| v.position.x > mid - 0.07 * (hi - lo)));

    let pt = PathTracer::new(&scene, 0.0);
    let mut r = scene_renderer(scene, size, |s| gi_render::settings::pipeline::Technique::DirectOnly.apply(s));
    // From the middle of the box, looking up at the quad (the file's camera does not see it).
    r.camera.position = r.bounds().center();
    r.camera.pitch = 1.0;
    let truth = pt.render(
        r.view_proj(),
        r.camera.position,
        size,
        size,
        PtSettings { bounces: 0, spp: 256, seed: 9, ..Default::default() },
    );
    for _ in 0..2 {
        r.render_frame();
    }
    let stats = r.emitter_stats().expect("the textured quad still emits");
    assert!((stats.power / e_plain.luminance_power() - share).abs() < 1e-3, "the panel's power is the textured one");
    let emission = read(&r, "gbuffer.emission");
    // The white half glows and the black one does not, on screen as in the path tracer (its
    // direct image is dim but for the glow: the box's lit walls stay under 0.5 here).
    let bright = |img: &ImageF32| img.data.iter().filter(|p| p[0] > 0.5).count();
    let (lab_glow, pt_glow) = (bright(&emission), bright(&truth.direct));
    println!("glowing pixels: {lab_glow} in the lab, {pt_glow} in the path tracer");
    assert!(pt_glow > 20 && lab_glow.abs_diff(pt_glow) * 10 < pt_glow, "{lab_glow} vs {pt_glow} glowing pixels");
    // The path tracer's direct image holds the glow of its first hits; the lab's glow is
    // `gbuffer.emission`, added by the compose.
    let glow_and_direct = sub(&read(&r, "direct.radiance"), &scaled(&emission, -1.0));
    let f = exposed_flip(&glow_and_direct, &truth.direct);
    println!("textured emitter: direct FLIP {f:.4}, power {share:.3} × the plain quad's");
    assert!(f < 0.046, "direct light of the textured emitter against the path tracer's: FLIP {f}");
}
