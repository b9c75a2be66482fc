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
