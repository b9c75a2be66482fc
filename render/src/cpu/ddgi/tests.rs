//! The CPU twin's own tests (`cpu::ddgi`).
use super::*;

#[test]
fn octahedral_coordinates_round_trip_and_fibonacci_covers_the_sphere() {
    for i in 0..256 {
        let d = spherical_fibonacci(i, 256);
        assert!((d.length() - 1.0).abs() < 1e-5);
        let back = oct_decode(oct_encode(d));
        assert!((back - d).length() < 1e-5, "{d} → {back}");
    }
    // Even cover: the mean direction vanishes, the mean of max(0, z) is 1/4.
    let dirs: Vec<Vec3> = (0..1024).map(|i| spherical_fibonacci(i, 1024)).collect();
    let mean = dirs.iter().copied().sum::<Vec3>() / 1024.0;
    assert!(mean.length() < 2e-3, "{mean}");
    let cos = dirs.iter().map(|d| d.z.max(0.0)).sum::<f32>() / 1024.0;
    assert!((cos - 0.25).abs() < 2e-3, "{cos}");
    // A random rotation keeps lengths and angles.
    let r = random_rotation([0.3, 0.7, 0.1]);
    assert!((r.determinant() - 1.0).abs() < 1e-5);
    assert!(((r * dirs[3]).dot(r * dirs[9]) - dirs[3].dot(dirs[9])).abs() < 1e-5);
}

#[test]
fn a_constant_sky_fills_every_texel_with_its_radiance_and_samples_to_pi_l() {
    // A probe seeing radiance L in every direction: every texel holds L (E / π), the
    // borders too, and the sample is π L whatever the weights.
    let grid = ProbeGrid::fit(Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) }, UVec3::splat(2), 64).0;
    let l = Vec3::new(0.5, 1.0, 2.0);
    let rays: Vec<ProbeRay> = (0..256)
        .map(|i| ProbeRay { dir: spherical_fibonacci(i, 256), radiance: l, distance: f32::INFINITY, backface: false })
        .collect();
    let mut irr = Atlas::new(6, grid.len(), Vec3::ZERO);
    let mut dist = Atlas::new(14, grid.len(), Vec3::ZERO);
    for probe in 0..grid.len() {
        update_irradiance(&mut irr, probe, &rays, 0.0);
        update_distance(&mut dist, probe, &rays, 0.0, 50.0, 3.0);
    }
    for probe in 0..grid.len() {
        for (y, x) in (0..irr.tile()).flat_map(|y| (0..irr.tile()).map(move |x| (y, x))) {
            assert!((irr.get(probe, x, y) - l).length() < 1e-4, "every texel, borders too");
        }
        for (y, x) in (0..dist.tile()).flat_map(|y| (0..dist.tile()).map(move |x| (y, x))) {
            let t = dist.get(probe, x, y);
            assert!((t.x - 3.0).abs() < 1e-4 && (t.y - 9.0).abs() < 1e-3, "{t}");
        }
    }
    let states = vec![ProbeState::Active; grid.len()];
    let offsets = vec![Vec3::ZERO; grid.len()];
    let probes = Probes { grid: &grid, irradiance: &irr, distance: &dist, offsets: &offsets, states: &states };
    let (e, w) = sample(&probes, Vec3::new(0.1, -0.2, 0.3), Vec3::Y, Vec3::Z, &DdgiParams::default());
    assert!((e - l * std::f32::consts::PI).length() < 1e-3, "{e}");
    let tri: f32 = w.iter().map(|p| p.trilinear).sum();
    assert!((tri - 1.0).abs() < 1e-5, "trilinear weights sum to 1: {tri}");
}

#[test]
fn a_texel_sees_the_light_of_its_hemisphere_and_hysteresis_keeps_the_old() {
    // Light only from +Y: the texel toward +Y holds the cosine-weighted mean of L over its
    // hemisphere (the lit half's mean of cos over all of it: ½), −Y none.
    let rays: Vec<ProbeRay> = (0..2048)
        .map(|i| {
            let d = spherical_fibonacci(i, 2048);
            ProbeRay {
                dir: d,
                radiance: if d.y > 0.0 { Vec3::ONE } else { Vec3::ZERO },
                distance: 1.0,
                backface: false,
            }
        })
        .collect();
    let mut irr = Atlas::new(8, 1, Vec3::ZERO);
    update_irradiance(&mut irr, 0, &rays, 0.0);
    let up = irr.lookup(0, Vec3::Y);
    let down = irr.lookup(0, Vec3::NEG_Y);
    assert!((up.x - 1.0).abs() < 0.05 && down.x < 0.05, "up {up} down {down}");
    let side = irr.lookup(0, Vec3::X);
    assert!((side.x - 0.5).abs() < 0.05, "sideways: half the cosine lobe is lit: {side}");
    // α = 0.9: one update moves a tenth of the way.
    let mut slow = Atlas::new(8, 1, Vec3::splat(2.0));
    update_irradiance(&mut slow, 0, &rays, 0.9);
    let v = slow.lookup(0, Vec3::Y);
    assert!((v.x - (0.1 * up.x + 0.9 * 2.0)).abs() < 0.02, "{v}");
}

#[test]
fn a_cold_start_averages_its_frames_evenly_then_keeps_alpha() {
    // Frame k's rays all carry radiance k + 1: with the running mean each texel holds the
    // mean of the frames so far until k/(k+1) reaches α; as printed, the first frame's
    // value keeps weight α^k.
    let frame = |k: u32| -> Vec<ProbeRay> {
        (0..64)
            .map(|i| ProbeRay {
                dir: spherical_fibonacci(i, 64),
                radiance: Vec3::splat(k as f32 + 1.0),
                distance: 1.0,
                backface: false,
            })
            .collect()
    };
    let alpha = 0.9;
    let (mut even, mut printed) = (Atlas::new(4, 1, Vec3::ZERO), Atlas::new(4, 1, Vec3::ZERO));
    for k in 0..9 {
        update_irradiance(&mut even, 0, &frame(k), blend_share(alpha, true, k));
        update_irradiance(&mut printed, 0, &frame(k), blend_share(alpha, false, k).min(if k == 0 { 0.0 } else { 1.0 }));
        let mean = (1..=k + 1).sum::<u32>() as f32 / (k + 1) as f32;
        let got = even.lookup(0, Vec3::Y).x;
        assert!((got - mean).abs() < 1e-4, "frame {k}: {got} vs the mean {mean}");
    }
    // Nine frames as printed: 1·0.9^8 + Σ 0.1·0.9^(8−k)(k+1) is well below the mean, 5.
    let p = printed.lookup(0, Vec3::Y).x;
    assert!(p < 4.0, "as printed the first frames keep their weight: {p}");
    assert_eq!(blend_share(alpha, true, 9), alpha, "from k/(k+1) ≥ α on, α");
    assert_eq!(blend_share(alpha, true, 1000), alpha);
    assert_eq!(blend_share(alpha, true, 0), 0.0);
}

#[test]
fn the_borders_make_lookups_continuous_across_the_octahedrons_seams() {
    // Radiance varying smoothly over the sphere: the stored field is smooth too, and two
    // directions a hair apart on either side of a fold (z = 0, where the lower half is
    // unfolded to the corners) read nearly the same value through the borders.
    let rays: Vec<ProbeRay> = (0..4096)
        .map(|i| {
            let d = spherical_fibonacci(i, 4096);
            ProbeRay { dir: d, radiance: d * 0.5 + Vec3::splat(0.5), distance: 1.0, backface: false }
        })
        .collect();
    let mut irr = Atlas::new(8, 1, Vec3::ZERO);
    update_irradiance(&mut irr, 0, &rays, 0.0);
    let mut worst = 0f32;
    for k in 0..360 {
        let phi = (k as f32 + 0.5).to_radians();
        let (a, b) =
            (Vec3::new(phi.cos(), phi.sin(), 2e-3).normalize(), Vec3::new(phi.cos(), phi.sin(), -2e-3).normalize());
        worst = worst.max((irr.lookup(0, a) - irr.lookup(0, b)).abs().max_element());
    }
    assert!(worst < 0.02, "a jump of {worst} across the fold");
    // Without the borders the lookup at the edge reads whatever the border held (zero).
    let mut bare = irr.clone();
    let n = bare.interior;
    for k in 0..n + 2 {
        for (x, y) in [(k, 0), (k, n + 1), (0, k), (n + 1, k)] {
            bare.set(0, x, y, Vec3::ZERO);
        }
    }
    let edge = Vec3::new(1.0, 0.0, 1e-4).normalize();
    assert!((bare.lookup(0, edge) - irr.lookup(0, edge)).length() > 0.1, "the border matters at the edge");
}

#[test]
fn a_wall_between_probe_and_point_hides_the_probe() {
    // One probe's distance tile says a wall 0.3 away in every direction: a point 0.9 away
    // gets Chebyshev's weight near 0; a point 0.2 away full weight.
    let grid = ProbeGrid { origin: Vec3::ZERO, spacing: Vec3::ONE, counts: UVec3::splat(2) };
    let rays: Vec<ProbeRay> = (0..256)
        .map(|i| ProbeRay { dir: spherical_fibonacci(i, 256), radiance: Vec3::ONE, distance: 0.3, backface: false })
        .collect();
    let mut irr = Atlas::new(6, 8, Vec3::ZERO);
    let mut dist = Atlas::new(14, 8, Vec3::splat(10.0));
    for p in 0..8 {
        update_irradiance(&mut irr, p, &rays, 0.0);
    }
    update_distance(&mut dist, 0, &rays, 0.0, 50.0, 1.5);
    // The other probes' tiles keep their fill (mean 10): nothing in the way.
    let params = DdgiParams { normal_bias: 0.0, view_bias: 0.0, ..DdgiParams::default() };
    let states = vec![ProbeState::Active; 8];
    let offsets = vec![Vec3::ZERO; 8];
    let near = sample(
        &Probes { grid: &grid, irradiance: &irr, distance: &dist, offsets: &offsets, states: &states },
        Vec3::splat(0.1),
        Vec3::Y,
        Vec3::Y,
        &params,
    )
    .1;
    let far = sample(
        &Probes { grid: &grid, irradiance: &irr, distance: &dist, offsets: &offsets, states: &states },
        Vec3::splat(0.55),
        Vec3::Y,
        Vec3::Y,
        &params,
    )
    .1;
    assert_eq!(near[0].probe, 0);
    assert!(near[0].visibility > 0.99, "{:?}", near[0]);
    assert!(far[0].visibility < 0.05, "{:?}", far[0]);
    // An inactive probe weighs nothing.
    let mut off = states.clone();
    off[0] = ProbeState::Inactive;
    let w = sample(
        &Probes { grid: &grid, irradiance: &irr, distance: &dist, offsets: &offsets, states: &off },
        Vec3::splat(0.1),
        Vec3::Y,
        Vec3::Y,
        &params,
    )
    .1;
    assert_eq!(w[0].weight, 0.0);
}

#[test]
fn probes_in_walls_are_classified_and_moved_out() {
    let spacing = Vec3::ONE;
    // Inside a wall: every ray meets a back face 0.1 away, the nearest along +X.
    let inside: Vec<ProbeRay> = (0..64)
        .map(|i| {
            let d = spherical_fibonacci(i, 64);
            ProbeRay { dir: d, radiance: Vec3::ZERO, distance: if d.x > 0.9 { 0.05 } else { 0.1 }, backface: true }
        })
        .collect();
    assert_eq!(classify(&inside, spacing, 0.25), ProbeState::Inactive);
    let moved = relocate(Vec3::ZERO, &inside, spacing, 0.25, 0.1);
    assert!(moved.x > 0.05 && moved.length() <= 0.45 * 3f32.sqrt(), "{moved}");
    // In a room: front faces half a spacing away: active, not moved.
    let room: Vec<ProbeRay> = (0..64)
        .map(|i| ProbeRay { dir: spherical_fibonacci(i, 64), radiance: Vec3::ONE, distance: 0.5, backface: false })
        .collect();
    assert_eq!(classify(&room, spacing, 0.25), ProbeState::Active);
    assert_eq!(relocate(Vec3::ZERO, &room, spacing, 0.25, 0.1), Vec3::ZERO);
    // In the void: nothing within the cell.
    let void: Vec<ProbeRay> = (0..64)
        .map(|i| ProbeRay {
            dir: spherical_fibonacci(i, 64),
            radiance: Vec3::ONE,
            distance: f32::INFINITY,
            backface: false,
        })
        .collect();
    assert_eq!(classify(&void, spacing, 0.25), ProbeState::Inactive);
}

#[test]
fn grids_fit_flat_boxes_and_clamp_to_the_device() {
    let flat = Aabb { min: Vec3::new(-5.0, 0.0, -5.0), max: Vec3::new(5.0, 0.0, 5.0) };
    let (g, clamp) = ProbeGrid::fit(flat, UVec3::new(8, 4, 8), 4096);
    assert!(clamp.is_none());
    assert!(g.spacing.y > 0.0 && g.spacing.is_finite(), "{g:?}");
    assert!(g.origin.y > 0.0, "the probes hover over the plane: {g:?}");
    let (big, clamp) = ProbeGrid::fit(flat, UVec3::new(64, 64, 64), 4096);
    assert!(big.len() <= 4096, "{big:?}");
    assert!(clamp.is_some_and(|c| c.reason.contains("4096")));
    let (empty, _) = ProbeGrid::fit(Aabb::EMPTY, UVec3::splat(4), 64);
    assert!(empty.origin.is_finite() && empty.spacing.is_finite());
    // Cell lookups clamp to the grid.
    let (base, a) = g.cell(Vec3::splat(1e9));
    assert!(base.cmplt(g.counts).all() && a.cmple(Vec3::ONE).all());
}
