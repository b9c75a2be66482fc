//! The app in a real window under Xvfb: it starts, renders frames and saves a screenshot
//! that is not uniform (the Cornell box is visible).

use std::process::Command;

#[test]
fn app_under_xvfb_renders_a_non_uniform_screenshot() {
    let have_xvfb = Command::new("sh").args(["-c", "command -v xvfb-run"]).output().is_ok_and(|o| o.status.success());
    assert!(
        have_xvfb,
        "xvfb-run is missing: install it with `sudo apt-get install -y xvfb xauth` (scripts/test.sh does this)"
    );
    let shot = std::env::temp_dir().join(format!("gi-lab-screenshot-{}.png", std::process::id()));
    let _ = std::fs::remove_file(&shot);
    let o = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(env!("CARGO_BIN_EXE_gi-lab"))
        .arg("--screenshot")
        .arg(&shot)
        .args(["--screenshot-frames", "5"])
        .env("WGPU_BACKEND", std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "vulkan".into()))
        .output()
        .expect("xvfb-run starts");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "the app failed: {err}");
    // The window logs GPU errors instead of panicking on them; none may occur.
    assert!(!err.contains("GPU error"), "the app hit a GPU error: {err}");
    let img = image::open(&shot)
        .unwrap_or_else(|e| panic!("no screenshot at {}: {e}; stderr: {err}", shot.display()))
        .to_rgba8();
    assert!(img.width() >= 640 && img.height() >= 400, "screenshot is {}×{}", img.width(), img.height());
    let first = img.get_pixel(0, 0).0;
    let differing = img.pixels().filter(|p| p.0 != first).count();
    assert!(differing > (img.width() * img.height() / 4) as usize, "screenshot is almost uniform");
    // The Cornell box's red and green walls are visible in the viewport.
    let reddish = img.pixels().filter(|p| p.0[0] > 80 && p.0[1] < 40 && p.0[2] < 40).count();
    let greenish = img.pixels().filter(|p| p.0[1] > 60 && p.0[0] < 50 && p.0[2] < 50).count();
    assert!(reddish > 500 && greenish > 500, "red {reddish} / green {greenish} wall pixels in the screenshot");
}
