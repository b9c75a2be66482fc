//! Soler et al.'s screen-space indirect light (issue #16) against the path tracer: more
//! bounces bring the default scene closer to the path-traced three bounces.

use gi_lab_tests::{default_scene, gpu, stored_reference};
use gi_render::pipeline::Technique;
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
    // Measured on lavapipe with the glossy reflection: 1 bounce FLIP 0.4408 (mean 0.0811 of
    // the reference's 0.1519), 2: 0.4088 (0.0857), 3: 0.3998 (0.0870), 2 alternating: 0.4105
    // (0.0854); diffuse only they were 0.4485, 0.4181, 0.4096, 0.4196. Each bounce
    // adds light, less than the one before, and the screen-space image stays far below the
    // truth: it misses every sender off screen or hidden (the issue note's darkness finding).
    assert!(l1 < l2 && l2 < l3 && l3 < l_ref, "mean luminance {l1} {l2} {l3} (reference {l_ref})");
    assert!(l3 - l2 < l2 - l1, "bounce 3 must add less than bounce 2");
    assert!(f2 < f1 - 0.02 && f3 < f2, "FLIP 1 bounce {f1}, 2 {f2}, 3 {f3}");
    // Alternating bounces over the frames come close to both bounces every frame.
    assert!((fa - f2).abs() < 0.01 && (la - l2).abs() < 0.02 * l2, "alternating: FLIP {fa} mean {la}");
}

/// One bounce on the hotel room (a real scene: 99k triangles, furniture, no lights but the
/// lab's default spot) against the path tracer, from inside the room. Textures are left out
/// on both sides (the path tracer reads the base colour factors only).
#[test]
fn one_bounce_on_the_hotel_room_against_the_path_tracer() {
    use gi_render::cpu::pathtrace::{PathTracer, PtSettings};
    const SIZE: u32 = 128;
    let opts = gi_render::scene::LoadOptions { unit_scale: 0.001, ..Default::default() };
    let path = gi_lab_tests::shared_scene("hotel-room/hotel-room.glb");
    let mut scene = gi_render::scene::load_gltf_file(&path, &opts).expect("the hotel room loads");
    for m in &mut scene.materials {
        m.base_color_texture = None;
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
    let settings = PtSettings { bounces: 1, spp: 128, seed: 11 };
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
    // Measured on lavapipe: Soler FLIP 0.1604 (mean 0.3019), direct only 0.4000 (0.2330),
    // the truth's mean 0.3385: the room's walls are mostly on screen, so the screen-space
    // gather misses less than in the open Cornell box.
    assert!(f_soler < f_direct, "Soler {f_soler} vs direct only {f_direct}");
    assert!(f_soler <= 0.18, "Soler on the hotel room: FLIP {f_soler}");
    assert!(l_direct < l_soler && l_soler < l_truth * 1.1, "mean luminance {l_direct} {l_soler} (truth {l_truth})");
}
