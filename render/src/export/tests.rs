use super::*;
use crate::settings::pipeline::Technique;

fn camera() -> Camera {
    Camera {
        position: glam::Vec3::new(0.1, 1.7, 3.3),
        yaw: 0.3,
        pitch: -0.1,
        yfov: 0.9,
        znear: 0.01,
        zfar: 100.0,
        orbit_distance: 2.5,
    }
}

/// A 4 × 2 × 6 m scene seen from a 3 × 2 × 4 m room, at 1280×720.
fn view(scale: ScaleSource) -> ExportView<'static> {
    ExportView {
        scene_name: "test",
        camera: camera(),
        size: (1280, 720),
        bounds: Aabb { min: glam::Vec3::new(-2.0, 0.0, -3.0), max: glam::Vec3::new(2.0, 2.0, 3.0) },
        scale: (if matches!(scale, ScaleSource::Room(_)) { 0.5 * 29f32.sqrt() } else { 14f32.sqrt() }, scale),
        units: None,
    }
}

fn room() -> ScaleSource {
    ScaleSource::Room(Aabb { min: glam::Vec3::new(-1.5, 0.0, -2.0), max: glam::Vec3::new(1.5, 2.0, 2.0) })
}

#[test]
fn export_round_trips_in_both_formats_with_every_group() {
    let mut s = LabSettings::default();
    s.tonemap.exposure_ev = 0.1 + 0.2;
    s.direct.depth_bias = 1.0 / 3.0;
    s.soler.radius_px = 17.0;
    Technique::ExactVpl.apply(&mut s);
    let e = Export::new(s, Provenance::now(&view(room()))).with_all_groups(true);
    for f in [ExportFormat::Json, ExportFormat::Ron] {
        let back = Export::parse(&e.to_text(f), "t").unwrap_or_else(|err| panic!("{f:?}: {err}"));
        assert_eq!(back.with_all_groups(true), e, "{f:?}");
    }
    let bad = e.to_text(ExportFormat::Json).replace("gi-lab-preset", "other");
    assert!(Export::parse(&bad, "t").is_err());
}

#[test]
fn every_group_is_written_with_all_groups() {
    let e = Export::new(LabSettings::default(), Provenance::now(&view(room()))).with_all_groups(true);
    let v: serde_json::Value = serde_json::from_str(&e.to_text(ExportFormat::Json)).expect("json");
    for (group, _) in LabSettings::groups() {
        assert!(v["settings"].get(group).is_some(), "group {group} missing from an --all-groups export");
    }
}

#[test]
fn only_the_groups_in_use_are_written_and_the_rest_load_at_defaults() {
    for t in [Technique::Knecht, Technique::Nguyen, Technique::Gautron, Technique::Soler, Technique::ExactVpl] {
        let mut s = LabSettings::default();
        t.apply(&mut s);
        // Every group off the technique's path set away from its default: it must not travel.
        s.soler.radius_px = 33.0;
        s.gautron.r_min_px = 11.0;
        s.hcb.theta_max_deg = 21.0;
        s.reference.min_distance_m = 0.2;
        s.ism.map_size = 128;
        let e = Export::new(s.clone(), Provenance::now(&view(room())));
        for f in [ExportFormat::Json, ExportFormat::Ron] {
            let text = e.to_text(f);
            let back = Export::parse(&text, "t").unwrap_or_else(|err| panic!("{t:?} {f:?}: {err}"));
            for (group, fields) in LabSettings::groups() {
                let in_use = s.pipeline.group_in_use(group);
                for m in fields {
                    let path = format!("{group}.{}", m.name);
                    let expected = if in_use { s.get(&path) } else { LabSettings::default().get(&path) };
                    assert_eq!(back.settings.get(&path), expected, "{t:?} {f:?} {path}");
                }
            }
            if f == ExportFormat::Json {
                let v: serde_json::Value = serde_json::from_str(&text).expect("json");
                let written: Vec<&str> =
                    v["settings"].as_object().expect("settings").keys().map(|k| k.as_str()).collect();
                for (group, _) in LabSettings::groups() {
                    assert_eq!(written.contains(&group), s.pipeline.group_in_use(group), "{t:?}: group {group}");
                }
            }
        }
    }
}

#[test]
fn schema_1_files_still_load() {
    let v1 = r#"{"schema": "gi-lab-preset", "schema_version": 1,
        "provenance": {"gi_lab_version": "0.1.0", "scene": "default",
            "camera": {"position": [0, 1, 3], "yaw": 0, "pitch": 0, "yfov": 0.8, "znear": 0.01, "zfar": 50, "orbit_distance": 3},
            "date": "2026-11-01T00:00:00Z"},
        "settings": {"hcb": {"theta_max_deg": 20.0}}}"#;
    let e = Export::parse(v1, "v1").expect("a schema 1 export loads");
    assert_eq!(e.settings.hcb.theta_max_deg, 20.0);
    assert_eq!(e.provenance.resolution, [0, 0]);
    assert!(e.provenance.bounds.is_none() && e.resolved.is_empty());
}

#[test]
fn resolved_values_are_the_passes_own() {
    // Values are written as the shortest decimals of their f32: compare as f32.
    let get = |e: &Export, path: &str| {
        let r = e.resolved.iter().find(|r| r.path == path).unwrap_or_else(|| panic!("{path} not resolved"));
        Resolved { set: r.set as f32 as f64, resolved: r.resolved as f32 as f64, ..r.clone() }
    };
    // The HCB with d_max from the scene: 0.1 × L, L the room's half diagonal.
    let mut s = LabSettings::default();
    Technique::Nguyen.apply(&mut s);
    s.hcb.d_max_m = 0.0;
    let p = Provenance::now(&view(room()));
    let l = p.scale.as_ref().expect("scale").length;
    assert_eq!(p.scale.as_ref().map(|s| s.source.as_str()), Some("room"));
    let e = Export::new(s.clone(), p.clone());
    let d = get(&e, "hcb.d_max_m");
    assert_eq!((d.set, d.resolved), (0.0, s.hcb.d_max(l) as f64));
    assert!((d.resolved - 0.1 * 0.5 * 29f64.sqrt()).abs() < 1e-6, "{d:?}");
    // Set: the value itself.
    s.hcb.d_max_m = 0.7;
    assert_eq!(get(&Export::new(s.clone(), p.clone()), "hcb.d_max_m").resolved, 0.7f32 as f64);
    assert!(e.resolved.iter().all(|r| !r.path.starts_with("gautron.") && !r.path.starts_with("soler.")));

    // Gautron: the radius clamps × L, pixel radii as fractions of the image's 720 rows.
    let mut s = LabSettings::default();
    Technique::Gautron.apply(&mut s);
    let e = Export::new(s.clone(), p.clone());
    assert_eq!(get(&e, "gautron.r_max_scene").resolved, (s.gautron.r_max_scene * l) as f64);
    assert_eq!(get(&e, "gautron.r_min_px").resolved, (s.gautron.r_min_px / 720.0) as f64);

    // Soler: the split as the near field computes it, the voxel depths as the voxelizer's.
    let mut s = LabSettings::default();
    Technique::Soler.apply(&mut s);
    let e = Export::new(s.clone(), p.clone());
    assert_eq!(get(&e, "soler.near_field_distance").resolved, s.soler.near_field_split(l) as f64);
    let (z0, z1) = crate::passes::soler::voxels::depth_range(
        camera().position,
        camera().forward(),
        glam::Vec3::new(0.0, 1.0, 0.0),
        14f32.sqrt(),
        camera().znear,
        s.soler.voxel_depth_from,
        s.soler.voxel_depth_to,
    );
    assert_eq!(
        (get(&e, "soler.voxel_depth_from").resolved, get(&e, "soler.voxel_depth_to").resolved),
        (z0 as f64, z1 as f64)
    );
    let h0 = (720 >> s.soler.start_resolution.level()) as f64;
    assert_eq!(get(&e, "soler.radius_px").resolved, (s.soler.radius_px as f64 / h0) as f32 as f64);

    // Knecht: the ISM's offsets against the model's radius, whatever the scale's source.
    let mut s = LabSettings::default();
    Technique::Knecht.apply(&mut s);
    let e = Export::new(s.clone(), Provenance::now(&view(ScaleSource::Model)));
    let r = 14f32.sqrt();
    assert_eq!(get(&e, "ism.eye_offset").resolved, (s.ism.eye_offset * r) as f64);
    assert_eq!(get(&e, "ism.pull_threshold").resolved, (s.ism.pull_threshold * 2.0 * r) as f64);
    assert_eq!(get(&e, "interleave.alpha").resolved, (s.interleave.alpha * (100.0 - 0.01)) as f64);
    assert_eq!(e.provenance.scale.as_ref().map(|s| s.source.as_str()), Some("model"));
    for r in &e.resolved {
        assert!(r.resolved.is_finite() && !r.formula.is_empty(), "{r:?}");
    }
}
