//! GPU passes against CPU references on the default scene (lavapipe in CI).

use gi_lab_tests::{default_renderer, default_scene, gpu, real_scene};
use gi_render::cpu::brdf;
use gi_render::scene::raycast::{Hit, TriangleSoup, primary_ray};
use gi_render::scene::{Light, LightKind, LoadOptions, Node, Scene, SceneState, Transform};
use gi_render::{LabSettings, Renderer};
use glam::{Quat, Vec3, Vec4Swizzles};

const N: u32 = 128;

fn cast(r: &Renderer, soup: &TriangleSoup, x: u32, y: u32) -> Option<Hit> {
    let (o, d) = primary_ray(r.view_proj().inverse(), x, y, N, N);
    soup.intersect_camera(o, d)
}

/// A pixel is "interior" when the rays through its four neighbours hit the same draw with
/// the same normal: no silhouette or crease where rasterisation and ray casting may
/// legitimately pick different triangles.
fn interior(r: &Renderer, soup: &TriangleSoup, x: u32, y: u32, h: &Hit) -> bool {
    if x == 0 || y == 0 || x + 1 >= N || y + 1 >= N {
        return false;
    }
    [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)]
        .iter()
        .all(|&(a, b)| cast(r, soup, a, b).is_some_and(|n| n.draw == h.draw && n.normal.dot(h.normal) > 0.98))
}

fn node_name(scene: &Scene, state: &SceneState, draw: usize) -> String {
    scene.nodes[state.draws[draw].node].name.to_lowercase()
}

#[test]
fn gbuffer_matches_cpu_ray_cast() {
    let mut r = default_renderer(N, N);
    // The default preset's passes read the linear depth (issue #53): the frame does not fill
    // the position, which is rebuilt from the depth when it is read below.
    let passes: Vec<String> = r.render_frame().into_iter().map(|t| t.name).collect();
    assert!(!passes.iter().any(|p| p == "gbuffer.position" || p == "gbuffer.normal"), "{passes:?}");
    // What the G-buffer pass binds: the linear depth (4 bytes), the packed normal (4), albedo
    // (4), SI and SP (4), movement buffer (4: no step reads its z) and depth (4) a pixel, and
    // the camera, instance and material buffers (a few KB); no emission target (8 bytes a
    // pixel, 128 KB here), since no material of the default box emits, and no metallic and
    // roughness nor unpacked normals, filled when read (issue #53).
    let bound = r.traffic().iter().find(|(p, _)| p == "gbuffer").map_or(0, |(_, b)| *b);
    let targets = 24 * (N * N) as u64;
    assert!((targets..targets + 16 * 1024).contains(&bound), "{bound} bytes: {:?}", r.traffic());
    let pos = r.readback("gbuffer.position").expect("position");
    let depth = r.readback("gbuffer.linear_depth").expect("linear depth");
    let (eye, forward) = (r.camera.position, r.camera.forward());
    let nrm = r.readback("gbuffer.normal").expect("normal");
    let alb = r.readback("gbuffer.albedo").expect("albedo");
    let mat = r.readback("gbuffer.material").expect("material");
    let emi = r.readback("gbuffer.emission").expect("emission");
    let state = r.scene().evaluate(0.0);
    let soup = TriangleSoup::new(r.scene(), &state);
    let mut compared = 0;
    let mut background = 0;
    for y in (2..N - 2).step_by(5) {
        for x in (2..N - 2).step_by(5) {
            let gp = pos.at(x, y);
            let gn = nrm.at(x, y);
            match cast(&r, &soup, x, y) {
                None => {
                    assert_eq!(gn[3], 0.0, "pixel ({x},{y}): CPU ray misses, G-buffer has geometry");
                    background += 1;
                }
                Some(h) if interior(&r, &soup, x, y, &h) => {
                    assert_eq!(gn[3], 1.0, "pixel ({x},{y}): CPU ray hits, G-buffer is empty");
                    let dp = Vec3::new(gp[0], gp[1], gp[2]).distance(h.position);
                    assert!(dp < 2e-3, "pixel ({x},{y}): position off by {dp} m ({gp:?} vs {})", h.position);
                    // w and the linear depth: the distance along the view axis (Eq. 4.2).
                    let d = (h.position - eye).dot(forward);
                    assert!((gp[3] - d).abs() < 2e-3, "pixel ({x},{y}): depth {} vs {d}", gp[3]);
                    assert_eq!(gp[3], depth.at(x, y)[0], "pixel ({x},{y}): w is the linear depth");
                    let n = Vec3::new(gn[0], gn[1], gn[2]);
                    assert!(n.dot(h.normal) > 0.999, "pixel ({x},{y}): normal {n} vs {}", h.normal);
                    let m = &r.scene().materials[h.material];
                    let a = alb.at(x, y);
                    for c in 0..3 {
                        assert!(
                            (a[c] - m.base_color[c]).abs() < 3.0 / 255.0,
                            "pixel ({x},{y}): albedo {a:?} vs {}",
                            m.base_color
                        );
                    }
                    assert!((a[3] - m.diffuse_intensity()).abs() < 3.0 / 255.0);
                    let e = emi.at(x, y);
                    assert!(
                        Vec3::new(e[0], e[1], e[2]).distance(m.emissive) < 1e-3,
                        "emission {e:?} vs {}",
                        m.emissive
                    );
                    let g = mat.at(x, y);
                    assert!((g[0] - m.specular_intensity()).abs() < 1e-3, "SI {} vs {}", g[0], m.specular_intensity());
                    assert!(
                        (g[1] - m.specular_power()).abs() / m.specular_power() < 1e-3,
                        "SP {} vs {}",
                        g[1],
                        m.specular_power()
                    );
                    // Filled when read from SI, SP and DI (issue #53): metallic = 1 − DI, and
                    // the roughness SP shades (the material's own where SP does not clamp).
                    assert!((g[2] - m.metallic).abs() < 3.0 / 255.0, "metallic {} vs {}", g[2], m.metallic);
                    let shaded = (2.0 / (m.specular_power() + 2.0)).powf(0.25);
                    assert!((g[3] - shaded).abs() < 1e-3, "roughness {} vs {shaded}", g[3]);
                    if (0.16..0.9).contains(&m.roughness) {
                        assert!((g[3] - m.roughness).abs() < 1e-3, "roughness {} vs {}", g[3], m.roughness);
                    }
                    compared += 1;
                }
                Some(_) => {}
            }
        }
    }
    assert!(compared >= 50, "only {compared} interior pixels compared");
    println!("G-buffer: {compared} pixels match the CPU ray cast, {background} background pixels agree");
}

/// The camera's movement buffer keeps z, each pixel's linear depth in the previous frame, only
/// while Soler et al.'s temporal filter runs, the one step that reads it (issue #53): the
/// default preset's is Δx, Δy alone (4 bytes a pixel less in the G-buffer and in Knecht's
/// merge); choosing Soler makes it again with z, and leaving Soler drops z again.
#[test]
fn the_movement_buffer_keeps_the_previous_depth_only_while_a_step_reads_it() {
    use gi_render::settings::pipeline::Technique;
    let mut r = default_renderer(N, N);
    let format = |r: &Renderer| r.buffers().get("gbuffer.motion").expect("motion").texture.format();
    let gbuffer_bytes = |r: &Renderer| r.traffic().iter().find(|(p, _)| p == "gbuffer").map_or(0, |(_, b)| *b);
    r.render_frame();
    assert_eq!(format(&r), wgpu::TextureFormat::Rg16Float);
    let without = gbuffer_bytes(&r);
    let mut s = r.settings().clone();
    Technique::Soler.apply(&mut s);
    assert!(s.pipeline.soler_temporal(), "Soler's technique filters in time");
    r.set_settings(s).expect("Soler");
    r.render_frame();
    r.render_frame();
    assert_eq!(format(&r), wgpu::TextureFormat::Rgba16Float);
    assert_eq!(gbuffer_bytes(&r), without + 4 * (N * N) as u64, "{:?}", r.traffic());
    // Nothing moved: z is this frame's depth, as a half float.
    let (motion, depth) =
        (r.readback("gbuffer.motion").expect("motion"), r.readback("gbuffer.linear_depth").expect("depth"));
    let mut covered = 0;
    for (m, d) in motion.data.iter().zip(&depth.data) {
        if d[0] > 0.0 {
            covered += 1;
            assert!((m[2] - d[0]).abs() <= gi_render::buffers::half_step(d[0]), "z {} vs depth {}", m[2], d[0]);
        }
    }
    assert!(covered > (N * N) as usize / 2, "{covered} covered pixels");
    r.set_settings(LabSettings::default()).expect("default");
    r.render_frame();
    assert_eq!(format(&r), wgpu::TextureFormat::Rg16Float);
    assert_eq!(gbuffer_bytes(&r), without);
}

#[test]
fn movement_buffer_reprojects_static_pixels_and_flags_moving_ones() {
    // Part 1: camera move, scene frozen. Offsets must equal the CPU reprojection.
    let mut r = default_renderer(N, N);
    r.render_frame();
    let prev_vp = r.view_proj();
    r.camera.orbit(0.06, 0.03);
    r.render_frame();
    let motion = r.readback("gbuffer.motion").expect("motion");
    let state = r.scene().evaluate(0.0);
    let soup = TriangleSoup::new(r.scene(), &state);
    let mut compared = 0;
    let mut max_motion = 0.0f32;
    for y in (2..N - 2).step_by(5) {
        for x in (2..N - 2).step_by(5) {
            let Some(h) = cast(&r, &soup, x, y) else { continue };
            if !interior(&r, &soup, x, y, &h) {
                continue;
            }
            let clip = prev_vp * h.position.extend(1.0);
            let ndc = clip.xy() / clip.w;
            let prev_px = glam::Vec2::new((ndc.x * 0.5 + 0.5) * N as f32, (0.5 - ndc.y * 0.5) * N as f32);
            let expect = prev_px - glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let m = motion.at(x, y);
            let got = glam::Vec2::new(m[0], m[1]);
            assert!((got - expect).length() < 0.02, "pixel ({x},{y}): motion {got} vs CPU {expect}");
            max_motion = max_motion.max(expect.length());
            compared += 1;
        }
    }
    assert!(compared >= 50, "only {compared} pixels compared");
    assert!(max_motion > 1.0, "the camera move should displace pixels (max {max_motion} px)");

    // Part 2: camera still, animation playing with a large step: the moving sphere's pixels
    // differ from the static prediction (zero), static pixels do not move. Soler's technique,
    // whose temporal filter reads the previous depth z (kept only then, issue #53).
    let mut settings = LabSettings::default();
    gi_render::settings::pipeline::Technique::Soler.apply(&mut settings);
    settings.animation.time_step_s = 0.1;
    let mut r = Renderer::new(gpu(), default_scene(), settings, N, N).expect("renderer");
    r.clock.playing = true;
    r.render_frame();
    let t = r.clock.time_s();
    r.render_frame();
    let motion = r.readback("gbuffer.motion").expect("motion");
    let position = r.readback("gbuffer.position").expect("position");
    let state = r.scene().evaluate(t);
    let soup = TriangleSoup::new(r.scene(), &state);
    let (mut moving, mut moving_ok, mut still) = (0, 0, 0);
    for y in 1..N - 1 {
        for x in 1..N - 1 {
            let Some(h) = cast(&r, &soup, x, y) else { continue };
            if !interior(&r, &soup, x, y, &h) {
                continue;
            }
            let m = motion.at(x, y);
            let len = glam::Vec2::new(m[0], m[1]).length();
            let name = node_name(r.scene(), &state, h.draw);
            if name.contains("sphere") {
                moving += 1;
                if len > 0.5 {
                    moving_ok += 1;
                }
            } else if !name.contains("short") {
                assert!(len < 1e-3, "static pixel ({x},{y}) on '{name}' moved by {len} px");
                // z: the depth in the previous frame, the current one where nothing moved.
                let (z_prev, z) = (m[2], position.at(x, y)[3]);
                assert!((z_prev - z).abs() <= 1e-3 * z, "static pixel ({x},{y}): previous depth {z_prev} vs {z}");
                still += 1;
            }
        }
    }
    assert!(moving >= 10, "the sphere covers only {moving} interior pixels");
    assert_eq!(moving_ok, moving, "{moving_ok} of {moving} sphere pixels have motion > 0.5 px");
    assert!(still >= 100);
}

/// What [`check_direct`] compared.
struct DirectCheck {
    lit: usize,
    shadowed: usize,
    shadowed_by_tall_box: usize,
    worst_rel: f32,
}

/// Renders one frame and compares `direct.radiance` with the analytic sum over the scene's
/// lights: floor pixels that every light reaches unoccluded (also 4 cm around, away from
/// penumbrae) within 2 %, and pixels that no light reaches (robustly occluded, though
/// unshadowed they would be bright) below 2 % of their unshadowed value.
fn check_direct(r: Renderer) -> DirectCheck {
    check_direct_buffer(r, "direct.radiance", false)
}

/// [`check_direct`] on `buffer`, which holds the whole reflected light or (`diffuse`) only its
/// diffuse part c·DI/π · E (the analytic sum then with SI = 0).
fn check_direct_buffer(mut r: Renderer, buffer: &str, diffuse: bool) -> DirectCheck {
    r.render_frame();
    let radiance = r.readback(buffer).unwrap_or_else(|e| panic!("{buffer}: {e}"));
    let state = r.scene().evaluate(0.0);
    let soup = TriangleSoup::new(r.scene(), &state);
    let far = r.bounds().radius() * 10.0;
    let eye = r.camera.position;
    let mut c = DirectCheck { lit: 0, shadowed: 0, shadowed_by_tall_box: 0, worst_rel: 0.0 };
    for y in 1..N - 1 {
        for x in 1..N - 1 {
            let Some(h) = cast(&r, &soup, x, y) else { continue };
            if !interior(&r, &soup, x, y, &h) {
                continue;
            }
            let floor = h.normal.y > 0.999 && h.position.y.abs() < 1e-3;
            let m = &r.scene().materials[h.material];
            let si = if diffuse { 0.0 } else { m.specular_intensity() };
            let m = (m.base_color.truncate(), m.diffuse_intensity(), si, m.specular_power());
            let t1 = h.normal.any_orthonormal_vector() * 0.04;
            let t2 = h.normal.cross(t1);
            let around = [Vec3::ZERO, t1, -t1, t2, -t2];
            let (mut visible_sum, mut unshadowed_sum) = (Vec3::ZERO, Vec3::ZERO);
            let (mut all_clear, mut all_blocked, mut tall) = (true, true, true);
            for wl in &state.lights {
                let (rad, target) =
                    brdf::punctual_radiance(wl, h.position, h.normal, (eye - h.position).normalize(), m, far);
                if rad.length() < 1e-6 {
                    continue; // this light does not reach the pixel at all
                }
                let occluded: Vec<bool> =
                    around.iter().map(|o| soup.occluded(h.position + *o + h.normal * 1e-3, target, 1e-3)).collect();
                unshadowed_sum += rad;
                if occluded.iter().all(|o| !o) {
                    visible_sum += rad;
                    all_blocked = false;
                } else if occluded.iter().all(|o| *o) {
                    all_clear = false;
                    let d = target - h.position;
                    let blocker = soup.intersect(h.position + h.normal * 1e-3, d.normalize(), 1e-3, d.length());
                    tall &= blocker.is_some_and(|b| node_name(r.scene(), &state, b.draw).contains("tall"));
                } else {
                    (all_clear, all_blocked) = (false, false); // penumbra
                }
            }
            let g = radiance.at(x, y);
            let got = Vec3::new(g[0], g[1], g[2]);
            if unshadowed_sum.length() < 0.05 * 0.3 {
                continue; // too dark to compare meaningfully
            }
            if floor && all_clear {
                let rel = (got - visible_sum).length() / visible_sum.length();
                c.worst_rel = c.worst_rel.max(rel);
                assert!(
                    rel < 0.02,
                    "lit floor pixel ({x},{y}) at {}: GPU {got} vs analytic {visible_sum} ({:.2} %)",
                    h.position,
                    rel * 100.0
                );
                c.lit += 1;
            } else if all_blocked {
                assert!(
                    got.length() < 0.02 * unshadowed_sum.length(),
                    "pixel ({x},{y}) at {} is occluded from every light but lit: {got} (unshadowed {unshadowed_sum})",
                    h.position
                );
                c.shadowed += 1;
                if tall {
                    c.shadowed_by_tall_box += 1;
                }
            }
        }
    }
    c
}

/// Soler et al.'s senders under 004 §5.3's diffuse approximation (`soler.sender`, issue #41):
/// `direct.diffuse` is the analytic direct light with the specular term left out, within
/// 2 % on the lit floor, dark where every light is occluded.
#[test]
fn the_diffuse_direct_light_matches_the_analytic_diffuse_part() {
    let mut s = LabSettings::default();
    gi_render::settings::pipeline::Technique::Soler.apply(&mut s);
    let r = Renderer::new(gpu(), default_scene(), s, N, N).expect("renderer");
    let c = check_direct_buffer(r, "direct.diffuse", true);
    println!("diffuse part: {} lit floor pixels within {:.3} %, {} shadowed", c.lit, c.worst_rel * 100.0, c.shadowed);
    assert!(c.lit > 50 && c.shadowed > 10, "{} lit, {} shadowed", c.lit, c.shadowed);
}

#[test]
fn direct_light_matches_analytic_spot_radiance_and_shadows() {
    let c = check_direct(default_renderer(N, N));
    println!(
        "spot: {} lit floor pixels within {:.3} %, {} shadowed pixels ({} behind the tall box)",
        c.lit,
        c.worst_rel * 100.0,
        c.shadowed,
        c.shadowed_by_tall_box
    );
    assert!(c.lit >= 50, "only {} lit floor pixels compared", c.lit);
    assert!(c.shadowed_by_tall_box >= 5, "only {} pixels behind the tall box", c.shadowed_by_tall_box);
}

#[test]
fn point_light_with_cube_shadow_map_matches_analytic_radiance() {
    let mut scene = default_scene();
    for l in &mut scene.lights {
        l.kind = LightKind::Point;
    }
    let mut r = Renderer::new(gpu(), scene, LabSettings::default(), N, N).expect("renderer");
    r.clock.playing = false;
    let c = check_direct(r);
    println!("point: {} lit floor pixels within {:.3} %, {} shadowed", c.lit, c.worst_rel * 100.0, c.shadowed);
    assert!(c.lit >= 50, "only {} lit floor pixels compared", c.lit);
    assert!(c.shadowed >= 5, "only {} shadowed pixels", c.shadowed);
}

#[test]
fn directional_and_spot_lights_add_up() {
    let mut scene = default_scene();
    scene.lights.push(Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        color: Vec3::new(1.0, 0.9, 0.8),
        intensity: 1.5,
        range: None,
    });
    // Shining down and toward −Z, a little from the left, through the open front.
    let dir = Vec3::new(0.3, -0.8, -0.5).normalize();
    scene.nodes.push(Node {
        name: "sun".into(),
        transform: Transform { rotation: Quat::from_rotation_arc(Vec3::NEG_Z, dir), ..Transform::default() },
        children: vec![],
        mesh: None,
        light: Some(scene.lights.len() - 1),
        camera: None,
    });
    scene.roots.push(scene.nodes.len() - 1);
    let mut r = Renderer::new(gpu(), scene, LabSettings::default(), N, N).expect("renderer");
    r.clock.playing = false;
    let c = check_direct(r);
    println!("spot + sun: {} lit floor pixels within {:.3} %, {} shadowed", c.lit, c.worst_rel * 100.0, c.shadowed);
    assert!(c.lit >= 50, "only {} lit floor pixels compared", c.lit);
    assert!(c.shadowed >= 5, "only {} pixels shadowed from both lights", c.shadowed);
}

#[test]
fn ten_frames_are_bit_identical() {
    let run = || {
        let mut r = Renderer::new(gpu(), default_scene(), LabSettings::default(), 96, 96).expect("renderer");
        for _ in 0..10 {
            r.render_frame();
        }
        r.readback("final.hdr").expect("final.hdr")
    };
    let a = run();
    let b = run();
    let bits = |i: &gi_render::ImageF32| i.data.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert!(a.data.iter().flatten().any(|x| *x > 0.0), "the image is black");
    assert!(bits(&a) == bits(&b), "two runs of 10 frames differ");
}

#[test]
fn every_registered_buffer_reads_back() {
    let mut r = default_renderer(64, 48);
    let timings = r.render_frame();
    let names: Vec<_> = timings.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(names, gi_lab_tests::first_frame(gi_lab_tests::DEFAULT_PASSES));
    for t in &timings {
        assert!(t.ms.is_finite() && t.ms >= 0.0, "{}: {} ms", t.name, t.ms);
    }
    for name in r.buffers().names() {
        let img = r.readback(&name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(img.width > 0 && img.height > 0);
        assert!(img.data.iter().flatten().all(|x| !x.is_nan()), "{name} has NaN");
    }
    for name in [
        "gbuffer.position",
        "gbuffer.normal",
        "gbuffer.albedo",
        "gbuffer.material",
        "gbuffer.motion",
        "gbuffer.depth",
        "direct.shadow_map",
        "direct.radiance",
        "final.hdr",
        "final.ldr",
    ] {
        r.buffers().get(name).unwrap_or_else(|e| panic!("{e}"));
    }
    let depth = r.readback("gbuffer.depth").expect("depth");
    assert!(depth.data.iter().all(|p| (0.0..=1.0).contains(&p[0])));
    assert!(r.readback("no.such.buffer").unwrap_err().to_string().contains("gbuffer.normal"));
}

#[test]
fn bad_sizes_and_settings_are_refused_without_change() {
    let mut r = default_renderer(32, 32);
    assert!(r.resize(0, 10).is_err());
    assert!(r.resize(10, 0).is_err());
    assert!(r.resize(1 << 20, 8).is_err());
    assert_eq!(r.size(), (32, 32));
    let mut bad = LabSettings::default();
    bad.direct.pcf_radius = 100;
    let e = r.set_settings(bad).unwrap_err().to_string();
    assert!(e.contains("direct.pcf_radius"), "{e}");
    assert_eq!(r.settings(), &LabSettings::default());
    let mut huge = LabSettings::default();
    huge.direct.shadow_map_size = 8192;
    huge.direct.shadow_map_size = r.ctx.limits.max_texture_dimension_2d + 1;
    assert!(r.set_settings(huge).is_err());
    r.resize(40, 20).expect("valid resize");
    r.render_frame();
    assert_eq!(r.readback("final.ldr").expect("ldr").width, 40);
}

fn render_shared(rel: &str, unit_scale: f32, tris: usize) {
    let opts = LoadOptions { unit_scale, ..LoadOptions::default() };
    let scene = gi_render::scene::load_gltf_file(&real_scene(rel), &opts).unwrap_or_else(|e| panic!("{rel}: {e}"));
    assert_eq!(scene.triangle_count(), tris, "{rel}");
    let mut r = Renderer::new(gpu(), scene, LabSettings::default(), 96, 96).expect("renderer");
    r.render_frame();
    let img = r.readback("final.ldr").expect("ldr");
    let coverage = r.readback("gbuffer.normal").expect("normal").data.iter().filter(|p| p[3] > 0.5).count();
    assert!(coverage > img.data.len() / 20, "{rel}: geometry covers only {coverage} pixels");
    // Direct light only: interiors lit by one default spot are mostly in shadow (the hotel
    // room's lit floor is a few percent of the view), so "non-empty" means some lit pixels.
    let lit = img.data.iter().filter(|p| p[0] + p[1] + p[2] > 0.05).count();
    let first = img.data[0];
    assert!(lit >= 20, "{rel}: only {lit} lit pixels");
    assert!(img.data.iter().any(|p| *p != first), "{rel}: uniform image");
}

#[test]
fn shared_cornell_box_renders() {
    render_shared("cornell-box/CornellBox-Original.gltf", 1.0, 32);
}

#[test]
fn emissive_surfaces_show_their_emission() {
    // The classic Cornell box's light is an emissive quad (factor 1) under the ceiling.
    let scene =
        gi_render::scene::load_gltf_file(&real_scene("cornell-box/CornellBox-Original.gltf"), &LoadOptions::default())
            .expect("loads");
    let mut r = Renderer::new(gpu(), scene, LabSettings::default(), 96, 96).expect("renderer");
    r.camera.orbit(0.0, 0.3); // look a little upward so that the ceiling light is in view
    r.render_frame();
    let emission = r.readback("gbuffer.emission").expect("emission");
    // The compose adds the emission (direct.radiance holds only the light reflected there).
    let radiance = r.readback("final.hdr").expect("radiance");
    let mut emitting = 0;
    for (e, l) in emission.data.iter().zip(&radiance.data) {
        if e[0] > 0.5 {
            assert!((0..3).all(|c| l[c] >= e[c] - 1e-3), "radiance {l:?} below emission {e:?}");
            emitting += 1;
        }
    }
    assert!(emitting >= 10, "only {emitting} pixels of the light quad are visible");
}

#[test]
fn shared_chair_on_floor_renders() {
    render_shared("chair-on-floor/MixedLightingExample.gltf", 1.0, 40_898);
}

#[test]
fn shared_hotel_room_renders() {
    render_shared("hotel-room/hotel-room.glb", 0.001, 99_029);
}

#[test]
fn tone_mapping_matches_the_cpu_reference() {
    for auto_exposure in [true, false] {
        let mut settings = LabSettings::default();
        settings.tonemap.auto_exposure = auto_exposure;
        settings.tonemap.exposure_ev = if auto_exposure { 0.5 } else { 1.5 };
        let mut r = Renderer::new(gpu(), default_scene(), settings.clone(), 100, 70).expect("renderer");
        r.render_frame();
        let hdr = r.readback("final.hdr").expect("hdr");
        let ldr = r.readback("final.ldr").expect("ldr");
        let avg = gi_render::cpu::tonemap::log_average(&hdr);
        let mut max_err = 0.0f32;
        for (h, l) in hdr.data.iter().zip(&ldr.data) {
            let want = gi_render::cpu::tonemap::reinhard([h[0], h[1], h[2]], &settings.tonemap, avg);
            for c in 0..3 {
                max_err = max_err.max((want[c] - l[c]).abs());
            }
        }
        // 8-bit output: half a step of rounding plus float noise in L̄w.
        assert!(max_err <= 1.5 / 255.0, "auto {auto_exposure}: final.ldr differs from the CPU reference by {max_err}");
    }
}

#[test]
fn interactive_mode_reports_timings_without_waiting_for_each_frame() {
    let mut r = default_renderer(48, 32);
    r.set_interactive(true);
    let mut seen = 0;
    for _ in 0..12 {
        let t = r.render_frame();
        if !t.is_empty() {
            let names: Vec<_> = t.iter().map(|p| p.name.as_str()).collect();
            // The first frame's timings (when they are the newest) have its own tone mapping
            // and the passes the later, still frames keep (the second redraws the G-buffer).
            let first = gi_lab_tests::first_frame(gi_lab_tests::DEFAULT_PASSES);
            let second = gi_lab_tests::second_frame(gi_lab_tests::DEFAULT_PASSES);
            let still = gi_lab_tests::still(gi_lab_tests::DEFAULT_PASSES);
            assert!(names == still || names == second || names == first, "{names:?}");
            seen += 1;
        }
    }
    assert!(seen >= 8, "timings arrived for only {seen} of 12 frames");
    r.set_interactive(false);
    assert_eq!(
        r.render_frame().len(),
        gi_lab_tests::still(gi_lab_tests::DEFAULT_PASSES).len(),
        "blocking mode returns this frame's timings"
    );
}

#[test]
fn a_flip_map_is_published_as_the_metrics_flip_buffer() {
    let mut r = default_renderer(16, 8);
    r.render_frame();
    assert!(r.readback("metrics.flip").is_err(), "no comparison yet");
    let hdr = r.readback("final.hdr").expect("hdr");
    let mut other = hdr.clone();
    for p in other.data.iter_mut().take(40) {
        *p = [1.0, 0.0, 1.0, 1.0];
    }
    let (mean, map) =
        gi_render::metrics::flip(&gi_render::image_io::hdr_display(&hdr), &gi_render::image_io::hdr_display(&other))
            .expect("flip");
    assert!(mean > 0.0);
    r.set_flip_map(&map);
    let back = r.readback("metrics.flip").expect("metrics.flip is registered");
    assert_eq!((back.width, back.height), (16, 8));
    assert_eq!(back.data, map.data, "the buffer holds the error map exactly");
}

#[test]
fn an_exact_vpl_atlas_larger_than_the_device_is_refused_with_the_largest_valid_batch() {
    let mut r = default_renderer(16, 16);
    let before = r.settings().clone();
    let mut s = before.clone();
    gi_render::settings::pipeline::Technique::ExactVpl.apply(&mut s);
    s.reference.vpls_per_frame = 1024;
    s.reference.shadow_map_size = 1024;
    let e = r.set_settings(s.clone()).expect_err("a 73728-texel-wide atlas cannot exist").to_string();
    let max = r.ctx.limits.max_texture_dimension_2d;
    let largest = gi_render::passes::reference::vpl_visibility::AtlasLayout::largest_batch(1024, max);
    assert!(e.contains(&format!("at most {largest} VPLs per frame")), "{e}");
    assert_eq!(r.settings(), &before, "a refused change leaves the settings as they were");
    // The largest batch the message names fits; one more does not.
    assert!(gi_render::passes::reference::vpl_visibility::AtlasLayout::new(largest, 1024).fits(max));
    assert!(!gi_render::passes::reference::vpl_visibility::AtlasLayout::new(largest + 1, 1024).fits(max));
}

/// The hotel room (a closed room without lights or cameras) with a glTF camera added inside
/// it, from near one corner toward the opposite one, and optionally a copy of its first
/// mesh far above its roof (so that the bounds' top lies above the ceiling).
fn hotel_room_with_camera_inside(roof_object: bool) -> gi_render::scene::Scene {
    use gi_render::scene::{CameraDef, Node, Projection, Transform};
    let opts = LoadOptions { unit_scale: 0.001, add_default_light: false, detect_units: false };
    let mut scene = gi_render::scene::load_gltf_file(&real_scene("hotel-room/hotel-room.glb"), &opts)
        .expect("the hotel room loads");
    assert!(scene.lights.is_empty());
    let b = scene.bounds(0.0);
    let e = b.extent();
    let eye = b.min + glam::Vec3::new(0.2 * e.x, 0.45 * e.y, 0.2 * e.z);
    let target = b.min + glam::Vec3::new(0.8 * e.x, 0.35 * e.y, 0.8 * e.z);
    scene.cameras.push(CameraDef {
        name: "inside".into(),
        projection: Projection::Perspective { yfov: 60f32.to_radians(), znear: 0.05, zfar: None },
    });
    let rotation = glam::Quat::from_rotation_arc(-glam::Vec3::Z, (target - eye).normalize());
    scene.nodes.push(Node {
        name: "inside".into(),
        transform: Transform { translation: eye, rotation, scale: glam::Vec3::ONE },
        children: vec![],
        mesh: None,
        light: None,
        camera: Some(scene.cameras.len() - 1),
    });
    scene.roots.push(scene.nodes.len() - 1);
    if roof_object {
        // A copy of the first draw, at its world transform (the unit scale sits on a root),
        // lifted ten room heights (the default spot at 85 % of the bounds then hangs between it
        // and the room).
        let d = scene.evaluate(0.0).draws[0];
        let (scale, rotation, translation) = d.world.to_scale_rotation_translation();
        let mut copy = scene.nodes[d.node].clone();
        copy.children.clear();
        copy.transform = Transform { translation: translation + glam::Vec3::Y * (10.0 * e.y), rotation, scale };
        scene.nodes.push(copy);
        scene.roots.push(scene.nodes.len() - 1);
    }
    scene
}

/// Lit share of the covered pixels of stage 2's direct light at the scene's camera.
fn lit_share(scene: gi_render::scene::Scene) -> f64 {
    let mut r = Renderer::new(gpu(), scene, LabSettings::default(), 96, 96).expect("renderer");
    r.clock.playing = false;
    if r.scene().cameras.is_empty() {
        // the inside view of `hotel_room_with_camera_inside`
        let b = r.bounds();
        let e = hotel_room_with_camera_inside(false).bounds(0.0);
        let x = e.extent();
        let eye = e.min + glam::Vec3::new(0.2 * x.x, 0.45 * x.y, 0.2 * x.z);
        let target = e.min + glam::Vec3::new(0.8 * x.x, 0.35 * x.y, 0.8 * x.z);
        r.camera = gi_render::camera::Camera::look_at(eye, target, 60f32.to_radians(), b);
    }
    r.render_frame();
    let direct = r.readback("direct.radiance").expect("direct");
    let normal = r.readback("gbuffer.normal").expect("normal");
    let covered: Vec<_> = direct.data.iter().zip(&normal.data).filter(|(_, n)| n[3] > 0.5).collect();
    assert!(covered.len() > direct.data.len() / 2, "the camera sees geometry");
    covered.iter().filter(|(d, _)| d[0] + d[1] + d[2] > 1e-3).count() as f64 / covered.len() as f64
}

/// Issue #18 (3): a closed room without lights, its camera inside, gets a point light in
/// the camera's view: the image is not black, and says why.
#[test]
fn a_closed_room_without_lights_is_lit_where_its_camera_looks() {
    let mut scene = hotel_room_with_camera_inside(false);
    scene.ensure_light();
    assert_eq!(scene.lights.len(), 1);
    assert_eq!(scene.lights[0].name, "default point");
    let note = scene.default_light_note().expect("a note on the added light").to_string();
    assert!(note.contains("camera"), "{note}");
    let lit = lit_share(scene);
    eprintln!("{note}; lit share of the view {lit:.3}");
    assert!(lit > 0.4, "only {lit:.3} of the view is lit");
}

/// Issues #18 (3) and #37 (1, 3): with something far above the roof (the bounds' top above
/// the ceiling) and no camera, the room is still found: the view stands inside it and the
/// default point light hangs under its ceiling — the room's floor, seen from inside, is lit.
#[test]
fn an_object_above_the_roof_does_not_move_the_light_out_of_the_room() {
    let mut scene = hotel_room_with_camera_inside(true);
    scene.cameras.clear();
    scene.nodes.iter_mut().for_each(|n| n.camera = None);
    let view = gi_render::scene::framing::choose_view(&scene, 1.0, Default::default());
    assert_eq!(view.kind, gi_render::scene::framing::ViewKind::Interior, "{}", view.reason);
    scene.ensure_light();
    let note = scene.default_light_note().expect("a note").to_string();
    assert!(note.contains("under the ceiling"), "{note}");
    assert_eq!(scene.lights[0].name, "default point");
    let ceiling_room = hotel_room_with_camera_inside(false).bounds(0.0).max.y;
    let spot = scene.nodes.iter().find(|n| n.light.is_some()).expect("light node").transform.translation;
    assert!(spot.y < ceiling_room, "the spot at {spot} is above the room's top {ceiling_room}");
    let lit = lit_share(scene);
    eprintln!("{note}; lit share of the inside view {lit:.3}");
    assert!(lit > 0.1, "only {lit:.3} of the inside view is lit");
}

/// `final.hdr` is stored only when a read-back of the frame copies it (issue #53): otherwise
/// the compose binds a 1×1 stand-in (8 bytes a pixel less) and a read after the frame composes
/// it again from the frame's inputs, bit for bit what the frame would have stored, while
/// `final.ldr` is the frame's own. The camera moves, so every frame's inputs are new.
#[test]
fn final_hdr_is_composed_when_read_bit_for_bit_what_the_frame_stores() {
    use gi_render::readback::Readback;
    let (w, h) = (64u32, 48u32);
    let mut lazy = default_renderer(w, h);
    let mut stored = default_renderer(w, h);
    for frame in 0..4u64 {
        let step = Vec3::new(0.003, 0.001, 0.0) * lazy.bounds().radius();
        lazy.camera.fly(step);
        stored.camera.fly(step);
        stored.read_later("test.hdr", Readback::Image { name: "final.hdr".into(), layer: 0, mip: 0 }, frame);
        lazy.render_frame();
        stored.render_frame();
        let compose = |r: &Renderer| r.traffic().iter().find(|(p, _)| p == "compose").map_or(0, |(_, b)| *b);
        let (l, s) = (compose(&lazy), compose(&stored));
        // The first frame of automatic exposure tone maps in a pass of its own, which reads
        // final.hdr: stored then.
        let saved = if frame == 0 { 0 } else { 8 * (w * h) as u64 - 8 };
        assert_eq!(s - l, saved, "frame {frame}: the compose bound {l} bytes, {s} storing final.hdr");
        let (a, b) =
            (lazy.readback("final.hdr").expect("composed when read"), stored.readback("final.hdr").expect("hdr"));
        assert!(a.data.iter().any(|p| p[0] > 0.0), "frame {frame}: a lit image");
        assert_eq!(a.data, b.data, "frame {frame}: final.hdr composed when read");
        assert_eq!(
            lazy.readback("final.ldr").expect("ldr").data,
            stored.readback("final.ldr").expect("ldr").data,
            "frame {frame}: final.ldr"
        );
    }
}
