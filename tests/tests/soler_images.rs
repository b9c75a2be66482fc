//! Soler et al.'s screen-space indirect light (issue #16) against the path tracer: more
//! bounces bring the default scene closer to the path-traced three bounces; the hotel room;
//! visibility against the path tracer restricted to screen-visible senders.

use gi_lab_tests::{default_scene, gpu, stored_reference};
use gi_render::settings::pipeline::Technique;
use gi_render::{ImageF32, LabSettings, Renderer};

fn renderer(size: u32, edit: impl FnOnce(&mut LabSettings)) -> Renderer {
    let mut s = LabSettings::default();
    Technique::Soler.apply(&mut s);
    edit(&mut s);
    assert!(s.validate().is_empty(), "{:?}", s.validate());
    let mut r = Renderer::new(gpu(), default_scene(), s, size, size).expect("renderer");
    r.clock.playing = false;
    r
}

fn last_frame(r: &mut Renderer, n: usize) -> ImageF32 {
    for _ in 0..n {
        r.render_frame();
    }
    r.readback("final.hdr").expect("final.hdr")
}

fn flip(a: &ImageF32, b: &ImageF32) -> f64 {
    use gi_render::image_io::hdr_display;
    gi_render::metrics::flip(&hdr_display(a), &hdr_display(b)).expect("flip").0
}

fn mean_luminance(img: &ImageF32) -> f64 {
    img.data.iter().map(|p| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64).sum::<f64>() / img.data.len() as f64
}

#[test]
fn more_bounces_bring_the_image_closer_to_three_path_traced_bounces() {
    let reference = stored_reference("cornell_3bounce_128.exr");
    let run = |bounces: u32, alternate: bool| {
        let mut r = renderer(128, |s| {
            s.soler.radius_px = 20.0;
            s.soler.bounces = bounces;
            s.soler.alternate_bounces = alternate;
        });
        let img = last_frame(&mut r, 16);
        (flip(&img, &reference), mean_luminance(&img))
    };
    let ((f1, l1), (f2, l2), (f3, l3), (fa, la)) = (run(1, false), run(2, false), run(3, false), run(2, true));
    let l_ref = mean_luminance(&reference);
    println!(
        "Soler vs the path-traced 3 bounces at 128², 16 frames (reference mean {l_ref:.4}): 1 bounce FLIP {f1:.4} \
         (mean {l1:.4}), 2: {f2:.4} ({l2:.4}), 3: {f3:.4} ({l3:.4}), 2 alternating: {fa:.4} ({la:.4})"
    );
    // Measured on lavapipe with the power-preserving vote: 1 bounce FLIP 0.4105 (mean 0.0859
    // of the reference's 0.1519), 2: 0.3633 (0.0932), 3: 0.3487 (0.0955), 2 alternating:
    // 0.3654 (0.0928); with the block's plain mean 0.4408, 0.4088, 0.3998, 0.4105; diffuse
    // only they were 0.4485, 0.4181, 0.4096, 0.4196. Each bounce
    // adds light, less than the one before, and the screen-space image stays far below the
    // truth: it misses every sender off screen or hidden (the issue note's darkness finding).
    assert!(l1 < l2 && l2 < l3 && l3 < l_ref, "mean luminance {l1} {l2} {l3} (reference {l_ref})");
    assert!(l3 - l2 < l2 - l1, "bounce 3 must add less than bounce 2");
    assert!(f2 < f1 - 0.02 && f3 < f2, "FLIP 1 bounce {f1}, 2 {f2}, 3 {f3}");
    // Alternating bounces over the frames come close to both bounces every frame.
    assert!((fa - f2).abs() < 0.01 && (la - l2).abs() < 0.02 * l2, "alternating: FLIP {fa} mean {la}");
}

/// One bounce on the hotel room (a real scene: 99k triangles, furniture, no lights of its own)
/// against the path tracer, from inside the room, lit by a spot looking down from under the
/// ceiling at the room's middle (the lab's default light before issue #37, kept here so that
/// the measured bound keeps its meaning). Textures are left out on both sides.
#[test]
fn one_bounce_on_the_hotel_room_against_the_path_tracer() {
    use gi_render::cpu::pathtrace::{PathTracer, PtSettings};
    const SIZE: u32 = 128;
    let opts = gi_render::scene::LoadOptions { unit_scale: 0.001, add_default_light: false, detect_units: false };
    let path = gi_lab_tests::real_scene("hotel-room/hotel-room.glb");
    let mut scene = gi_render::scene::load_gltf_file(&path, &opts).expect("the hotel room loads");
    for m in &mut scene.materials {
        m.base_color_texture = None;
        m.normal_texture = None;
        m.metallic_roughness_texture = None;
    }
    {
        use gi_render::scene::{Light, LightKind, Node, Transform};
        let b = scene.bounds(0.0);
        let (c, ext) = (b.center(), b.extent());
        let pos = glam::Vec3::new(c.x, b.min.y + 0.85 * ext.y, c.z);
        let height = pos.y - b.min.y;
        let outer = (1.5 * 0.5 * ext.x.max(ext.z) / height).atan().clamp(0.5, 1.35);
        scene.lights.push(Light {
            name: "spot".into(),
            kind: LightKind::Spot { inner_cone: outer * 0.6, outer_cone: outer },
            color: glam::Vec3::ONE,
            intensity: std::f32::consts::PI * height * height,
            range: None,
        });
        let rotation = glam::Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
        scene.nodes.push(Node {
            name: "spot".into(),
            transform: Transform { translation: pos, rotation, scale: glam::Vec3::ONE },
            children: vec![],
            mesh: None,
            light: Some(scene.lights.len() - 1),
            camera: None,
        });
        scene.roots.push(scene.nodes.len() - 1);
    }
    let image = |t: Technique| {
        let mut s = LabSettings::default();
        t.apply(&mut s);
        let mut r = Renderer::new(gpu(), scene.clone(), s, SIZE, SIZE).expect("renderer");
        r.clock.playing = false;
        let b = r.bounds();
        let e = b.extent();
        let eye = b.min + glam::Vec3::new(0.2 * e.x, 0.45 * e.y, 0.2 * e.z);
        let target = b.min + glam::Vec3::new(0.8 * e.x, 0.35 * e.y, 0.8 * e.z);
        r.camera = gi_render::camera::Camera::look_at(eye, target, 60f32.to_radians(), b);
        (last_frame(&mut r, 16), r.camera)
    };
    let (soler, camera) = image(Technique::Soler);
    let (direct, _) = image(Technique::DirectOnly);
    let pt = PathTracer::new(&scene, 0.0);
    let settings = PtSettings { bounces: 1, spp: 128, seed: 11, ..Default::default() };
    let truth = pt.render(camera.view_proj(1.0), camera.position, SIZE, SIZE, settings).full;
    let (f_soler, f_direct) = (flip(&soler, &truth), flip(&direct, &truth));
    let (l_soler, l_direct, l_truth) = (mean_luminance(&soler), mean_luminance(&direct), mean_luminance(&truth));
    println!(
        "hotel room {SIZE}², 16 frames, against 128 spp of one bounce: Soler FLIP {f_soler:.4} (mean {l_soler:.4}), \
         direct only {f_direct:.4} ({l_direct:.4}), truth mean {l_truth:.4}"
    );
    for (name, img) in [("soler", &soler), ("truth", &truth)] {
        let file = std::env::temp_dir().join(format!("gi_lab_hotel_{name}.png"));
        let _ = gi_render::image_io::save_png(&file, img, gi_render::buffers::BufferKind::Hdr);
    }
    // Measured on lavapipe: Soler FLIP 0.1439 (mean 0.3124; 0.1604 and 0.3019 with the
    // pyramid's plain mean radiance), direct only 0.4000 (0.2330),
    // the truth's mean 0.3385: the room's walls are mostly on screen, so the screen-space
    // gather misses less than in the open Cornell box.
    assert!(f_soler < f_direct, "Soler {f_soler} vs direct only {f_direct}");
    assert!(f_soler <= 0.18, "Soler on the hotel room: FLIP {f_soler}");
    assert!(l_direct < l_soler && l_soler < l_truth * 1.1, "mean luminance {l_direct} {l_soler} (truth {l_truth})");
}

/// Visibility (004 §4) against the path tracer where the boxes occlude: the truth counts only
/// light whose first bounce lands on a surface the camera sees (`Senders::ScreenVisible`),
/// what a screen-space gather can know; on the pixels where the voxel march removes a tenth
/// or more of the light, the image with visibility is the closer. Started at full resolution:
/// a coarse first level misses the light from within its receiver's own texel and carries
/// each block's power at its winner's position and normal (the level's screen sum at a
/// quarter of 128² is 81 % of the full resolution's, with `vote_power`), so that the image is
/// already too dark where the boxes occlude and only gets darker when visibility removes the
/// occluded light (quarter: RMSE 0.0131 without, 0.0158 with, measured).
#[test]
fn visibility_brings_the_occluded_pixels_closer_to_the_screen_visible_path_tracer() {
    use gi_render::cpu::pathtrace::{PathTracer, PtSettings, Senders};
    use gi_render::passes::soler::StartResolution;
    const SIZE: u32 = 128;
    let image = |visibility: bool| {
        let mut r = renderer(SIZE, |s| {
            s.soler.start_resolution = StartResolution::Full;
            s.soler.levels = 4;
            s.soler.samples = 64;
            s.soler.radius_px = 40.0;
            s.soler.visibility = visibility;
        });
        (last_frame(&mut r, 16), r.view_proj(), r.camera.position)
    };
    let ((open, view_proj, eye), (marched, _, _)) = (image(false), image(true));
    let pt = PathTracer::new(&default_scene(), 0.0);
    let settings = PtSettings { bounces: 1, spp: 128, seed: 5, senders: Senders::ScreenVisible };
    let truth = pt.render(view_proj, eye, SIZE, SIZE, settings).full;
    let lum = |p: [f32; 4]| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64;
    let (mut n, mut err_open, mut err_marched) = (0usize, 0.0f64, 0.0f64);
    for ((o, m), t) in open.data.iter().zip(&marched.data).zip(&truth.data) {
        let (o, m, t) = (lum(*o), lum(*m), lum(*t));
        if o - m >= 0.1 * o && o > 0.0 {
            n += 1;
            err_open += (o - t).powi(2);
            err_marched += (m - t).powi(2);
        }
    }
    let (rmse_open, rmse_marched) = ((err_open / n as f64).sqrt(), (err_marched / n as f64).sqrt());
    let (l_open, l_truth) = (mean_luminance(&open), mean_luminance(&truth));
    println!(
        "{n} pixels where the march removes ≥ 10 %: RMSE against the screen-visible truth without visibility \
         {rmse_open:.4}, with {rmse_marched:.4}; mean luminance without visibility {l_open:.4}, truth {l_truth:.4}"
    );
    assert!(n as u32 > SIZE * SIZE / 10, "{n} pixels lose light to the march");
    // Measured on lavapipe: 6907 pixels, RMSE 0.0128 → 0.0109 (÷1.17); means 0.0914 and 0.0918
    // (with the pyramid's plain mean radiance 0.0124 → 0.0108, 0.0898).
    assert!(rmse_marched < rmse_open, "with visibility {rmse_marched}, without {rmse_open}");
    assert!((l_open - l_truth).abs() < 0.1 * l_truth, "mean luminance {l_open} vs the truth's {l_truth}");
}
