//! The exact-VPL reference for every kind of light: its indirect light (`indirect.accum`)
//! carries the same energy as the path tracer's one-bounce indirect light. This checks the
//! flux of the VPL sampling per light kind (spot: perspective texels, point: six cube
//! faces, directional: orthographic texels) independently of the direct light.

use gi_lab_tests::{default_scene, gpu};
use gi_render::cpu::pathtrace::{PathTracer, PtSettings};
use gi_render::scene::{LightKind, Scene};
use gi_render::settings::pipeline::Technique;
use gi_render::{ImageF32, LabSettings, Renderer};

const SIZE: u32 = 32;

fn luminance_sum(img: &ImageF32) -> f64 {
    img.data.iter().map(|p| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64).sum()
}

/// (exact-VPL indirect, path-traced indirect) total luminance for `scene` at time 0, after
/// `batches` batches of 128 VPLs.
fn indirect_energy(scene: Scene, batches: u32) -> (f64, f64) {
    let mut s = LabSettings::default();
    Technique::ExactVpl.apply(&mut s);
    s.reference.vpls_per_frame = 128;
    s.reference.total_vpls = 128 * batches;
    s.reference.light_gbuffer_size = 256;
    let mut r = Renderer::new(gpu(), scene.clone(), s, SIZE, SIZE).expect("renderer");
    r.clock.playing = false;
    for _ in 0..batches {
        r.render_frame();
    }
    assert_eq!(r.reference_progress(), Some((128 * batches, 128 * batches)));
    let vpl = r.readback("indirect.accum").expect("indirect.accum");
    let pt = PathTracer::new(&scene, 0.0);
    let img = pt.render(
        r.view_proj(),
        r.camera.position,
        SIZE,
        SIZE,
        PtSettings { bounces: 1, spp: 64, seed: 3, ..Default::default() },
    );
    (luminance_sum(&vpl), luminance_sum(&img.indirect))
}

fn light_node(scene: &Scene) -> usize {
    scene.nodes.iter().position(|n| n.light.is_some()).expect("the default scene has a light")
}

fn check(name: &str, scene: Scene) {
    check_batches(name, scene, 16);
}

fn check_batches(name: &str, scene: Scene, batches: u32) {
    let (vpl, pt) = indirect_energy(scene, batches);
    let ratio = vpl / pt;
    println!("{name}: exact-VPL / path-traced indirect energy = {ratio:.4} ({vpl:.3} / {pt:.3})");
    assert!(pt > 0.0, "{name}: the path tracer finds indirect light");
    // Both are unbiased estimates of the same integral; the bound covers their noise at
    // these sample counts (2048 VPLs, 64 spp at 32×32).
    assert!((0.9..=1.1).contains(&ratio), "{name}: indirect energy ratio {ratio}");
}

#[test]
fn spot_light_vpls_carry_the_path_traced_indirect_energy() {
    check("spot", default_scene());
}

#[test]
fn point_light_vpls_carry_the_path_traced_indirect_energy() {
    let mut scene = default_scene();
    let ni = light_node(&scene);
    let li = scene.nodes[ni].light.expect("light");
    scene.lights[li].kind = LightKind::Point;
    // In the middle of the room: right under the ceiling, the lit spot above the light is so
    // bright and so small that the path tracer's BRDF sampling converges to it only slowly
    // (measured there: exact-VPL / path tracer 1.09 at 64 spp, 1.07 at 512 spp, the VPL side
    // stable within 2 %).
    scene.nodes[ni].transform.translation.y = 1.2;
    check("point", scene);
}

#[test]
fn directional_light_vpls_carry_the_path_traced_indirect_energy() {
    // A directional light shining into the open box along the camera's view direction.
    let mut scene = default_scene();
    let ni = light_node(&scene);
    let li = scene.nodes[ni].light.expect("light");
    let cam = scene.nodes.iter().position(|n| n.camera.is_some()).expect("the default scene has a camera");
    scene.nodes[ni].transform.rotation = scene.nodes[cam].transform.rotation;
    scene.lights[li].kind = LightKind::Directional;
    scene.lights[li].intensity = 2.0;
    check("directional", scene);
}

/// A directional light from above and in front of the open box: most of it falls on the
/// ceiling's back (outer) face, which must stop it as the path tracer's surfaces do. The
/// light G-buffer culled single-sided back faces, so the light passed through the ceiling and
/// its VPLs carried 1.58 × the path tracer's indirect energy (Knecht's importance-warped VPLs
/// 1.45 ×, the same G-buffer).
#[test]
fn directional_light_vpls_stop_at_the_back_of_a_wall() {
    let mut scene = default_scene();
    let ni = light_node(&scene);
    let li = scene.nodes[ni].light.expect("light");
    let travel = glam::Vec3::new(0.3, -0.5, -0.8).normalize();
    scene.nodes[ni].transform.rotation = glam::Quat::from_rotation_arc(glam::Vec3::NEG_Z, travel);
    scene.lights[li].kind = LightKind::Directional;
    scene.lights[li].intensity = 2.0;
    check("directional from above", scene);
}

/// The real Cornell box lit only by its emissive ceiling quad (issue #18): the reference's
/// first bounce comes from `reference.emitter_points` (16) points of the quad, five views
/// each, so 80 batches take every view once.
#[test]
fn emitter_points_carry_the_path_traced_indirect_energy() {
    let scene = gi_render::scene::load_gltf_file(
        &gi_lab_tests::real_scene("cornell-box/CornellBox-Original.gltf"),
        &gi_render::scene::LoadOptions::default(),
    )
    .expect("the real Cornell box loads");
    assert!(scene.lights.is_empty(), "lit by its quad alone");
    check_batches("emitters", scene, 80);
}

/// Stage 3 of the reference on the GPU (`reference/sample.wgsl`) against its CPU twin
/// `cpu::knecht::reference_uv`: VPL i of the first batch sits at the light G-buffer texel
/// under point i of the seed's rotated Halton set (slots whose texel is empty or faces away
/// from the light stay empty, so the filled VPLs are a subsequence of the predicted texels).
#[test]
fn reference_vpls_sit_at_the_texels_of_the_rotated_halton_set() {
    let mut s = LabSettings::default();
    Technique::ExactVpl.apply(&mut s);
    s.reference.vpls_per_frame = 256;
    s.reference.light_gbuffer_size = 128;
    s.reference.seed = 7;
    let mut r = Renderer::new(gpu(), default_scene(), s, SIZE, SIZE).expect("renderer");
    r.clock.playing = false;
    r.render_frame();
    let vpls = r.vpl_list().expect("the reference has a VPL list");
    let lg = r.readback("vpl.light_gbuffer.position").expect("light G-buffer");
    let predicted: Vec<glam::Vec3> = (0..256)
        .map(|i| {
            let uv = gi_render::cpu::knecht::reference_uv(7, i) * lg.width as f32;
            let t = uv.as_uvec2().min(glam::UVec2::splat(lg.width - 1));
            let p = lg.data[(t.y * lg.width + t.x) as usize];
            glam::Vec3::new(p[0], p[1], p[2])
        })
        .collect();
    let mut next = predicted.iter();
    for (k, v) in vpls.iter().enumerate() {
        let p = v.position.truncate();
        assert!(next.any(|q| (*q - p).length() < 1e-4), "VPL {k} at {p} is not at a predicted texel (in order)");
    }
    // Most of the spot light's view is covered and lit: most slots hold a VPL.
    assert!(vpls.len() > 128, "{} of 256 slots filled", vpls.len());
}
