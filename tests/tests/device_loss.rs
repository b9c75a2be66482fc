//! Device loss (issue #19 point 3): when the device is lost (a driver reset; here
//! `device.destroy()`), the renderer says so, nothing panics, and `Renderer::move_to` rebuilds
//! it on a new device — scene upload, textures and every pass — with the same settings, size,
//! camera and clock, rendering what a renderer made there from scratch renders.

use gi_lab_tests::{default_scene, gpu};
use gi_render::{LabSettings, Renderer};

#[test]
fn a_lost_device_is_reported_and_the_renderer_moves_to_a_new_one() {
    let ctx = gpu();
    let mut settings = LabSettings::default();
    settings.direct.pcf_radius = 2;
    let mut r = Renderer::new(ctx.clone(), default_scene(), settings.clone(), 48, 40).expect("renderer");
    r.clock.playing = false;
    r.camera.yaw += 0.2;
    for _ in 0..3 {
        r.render_frame();
    }
    assert_eq!(ctx.lost_reason(), None);
    let (camera, clock) = (r.camera, r.clock);

    ctx.device.destroy();
    ctx.wait_idle();
    let why = ctx.lost_reason().expect("the loss is reported");
    assert!(why.contains("Destroyed"), "{why}");
    // Work on the lost device fails quietly (no panic); reading back says it failed.
    r.render_frame();
    assert!(r.readback("final.hdr").is_err(), "a lost device has no image to read");

    let fresh_ctx = gpu();
    r.move_to(fresh_ctx.clone()).expect("the renderer moves to the new device");
    assert_eq!((r.settings(), r.camera, r.size()), (&settings, camera, (48, 40)));
    assert_eq!(r.clock.frame, clock.frame + 1, "the clock goes on (the lost frame counted)");
    let moved_clock = r.clock;
    r.render_frame();
    let moved = r.readback("final.hdr").expect("renders on the new device");

    let mut twin = Renderer::new(fresh_ctx, default_scene(), settings, 48, 40).expect("twin");
    twin.camera = camera;
    twin.clock = moved_clock;
    twin.render_frame();
    let expected = twin.readback("final.hdr").expect("twin renders");
    assert!(moved.data.iter().flatten().any(|x| *x > 0.0), "the moved renderer's image is black");
    assert_eq!(moved.data, expected.data, "the moved renderer renders as a new one in its state does");
}
