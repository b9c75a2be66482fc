//! The scene- and image-relative settings of an export, as set and as resolved (issue #54
//! point 4). The papers and GI Lab give several settings against "the scene" or the image:
//! the HCB's d_max from the scene when 0, Gautron's radius clamps and Soler's near-field split
//! as fractions of the scene's scale L (docs/architecture.md, "Scene scale"), the imperfect
//! shadow maps' eye offset and pull-push thresholds against the model's radius, pixel radii
//! against the image. An engine that takes the preset to another scene or resolution needs
//! the value GI Lab used and the formula to get it again; each entry gives both.
//!
//! The formulas here are the passes' own: they call the same functions (`HcbSettings::d_max`,
//! `SolerSettings::near_field_split`, `voxels::depth_range`) or repeat one product, and
//! `resolved_values_are_the_passes_own` checks them against those functions.

use serde::{Deserialize, Serialize};

use super::Provenance;
use crate::LabSettings;

/// One relative setting: its dotted path, the value as set with its unit, the value resolved
/// for the export's scene and image with its unit, and how to resolve it again.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Resolved {
    pub path: String,
    pub set: f64,
    pub set_unit: String,
    pub resolved: f64,
    pub resolved_unit: String,
    pub formula: String,
}

/// `x` (an `f32` setting or a product of them) as the shortest decimal that reads back as the
/// same `f32`, so that 0.005 is written 0.005 and not 0.004999999888241291.
fn tidy(x: f64) -> f64 {
    (x as f32).to_string().parse().unwrap_or(x)
}

/// The relative settings of the groups in use (`PipelineSettings::group_in_use`) resolved for
/// `p`'s scene, camera and resolution. Empty when `p` has no bounds (a schema 1 file).
pub fn resolve(s: &LabSettings, p: &Provenance) -> Vec<Resolved> {
    let Some(bounds) = &p.bounds else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let used = |g: &str| s.pipeline.group_in_use(g);
    let mut push = |path: &str, set: f64, set_unit: &str, resolved: f64, resolved_unit: &str, formula: String| {
        out.push(Resolved {
            path: path.into(),
            set: tidy(set),
            set_unit: set_unit.into(),
            resolved: tidy(resolved),
            resolved_unit: resolved_unit.into(),
            formula,
        })
    };
    let l = p.scale.as_ref().map(|s| s.length).unwrap_or(bounds.radius);
    let l_is = match p.scale.as_ref().map(|s| s.source.as_str()) {
        Some("room") => "L = half the diagonal of the room the camera is in (provenance.scale)",
        _ => "L = the model's bounding radius (provenance.scale)",
    };
    let r = bounds.radius.max(1e-3);
    let r_is = "R = the model's bounding radius (provenance.bounds.radius)";
    let h = p.resolution[1].max(1) as f64;
    let per_height = |px: f64| px / h;
    let height_formula = |name: &str| format!("{name} ÷ H, H = {} px; an image of height H' uses resolved × H'", h);

    if used("hcb") {
        let d = s.hcb.d_max(l);
        let formula = if s.hcb.d_max_m > 0.0 {
            "d_max = d_max_m (set > 0: an absolute length)".to_string()
        } else {
            format!("d_max = {} × L when d_max_m = 0; {l_is}", crate::settings::hcb::D_MAX_PER_RADIUS)
        };
        push("hcb.d_max_m", s.hcb.d_max_m as f64, "m", d as f64, "m", formula);
        let q = s.hcb.surplus_quad_px as f64;
        push("hcb.surplus_quad_px", q, "px", per_height(q), "× image height", height_formula("surplus_quad_px"));
    }
    if used("gautron") {
        let g = &s.gautron;
        for (name, v) in [("r_min_scene", g.r_min_scene), ("r_max_scene", g.r_max_scene)] {
            let formula = format!("{name} × L; {l_is}");
            push(&format!("gautron.{name}"), v as f64, "× L", (v * l) as f64, "m", formula);
        }
        for (name, v) in
            [("r_min_px", g.r_min_px), ("r_max_px", g.r_max_px), ("creation_tile_px", g.creation_tile_px as f32)]
        {
            let v = v as f64;
            push(&format!("gautron.{name}"), v, "px", per_height(v), "× image height", height_formula(name));
        }
    }
    if used("soler") {
        let so = &s.soler;
        let split = so.near_field_split(l);
        push(
            "soler.near_field_distance",
            so.near_field_distance as f64,
            "× L",
            split as f64,
            "m",
            format!("near_field_distance × L; {l_is}"),
        );
        // The ring's radius is in texels of each gathered level; the first gathered level is
        // the image divided by 2^start.
        let start = so.start_resolution.level();
        let h0 = (p.resolution[1].max(1) >> start).max(1) as f64;
        push(
            "soler.radius_px",
            so.radius_px as f64,
            "texels of each gathered level",
            so.radius_px as f64 / h0,
            "× height of the first gathered level",
            format!(
                "radius_px ÷ H₀, H₀ = H ÷ 2^{start} = {h0} texels (start_resolution); a level k below it keeps r texels, 2^k × as far"
            ),
        );
        let m = so.temporal_motion_px as f64;
        push(
            "soler.temporal_motion_px",
            m,
            "px/frame",
            per_height(m),
            "× image height per frame",
            height_formula("temporal_motion_px"),
        );
        let c = bounds.min.iter().zip(&bounds.max).map(|(a, b)| 0.5 * (a + b)).collect::<Vec<_>>();
        let center = glam::Vec3::new(c[0], c[1], c[2]);
        let cam = &p.camera;
        let (z0, z1) = crate::passes::soler::voxels::depth_range(
            cam.position,
            cam.forward(),
            center,
            bounds.radius,
            cam.znear,
            so.voxel_depth_from,
            so.voxel_depth_to,
        );
        let depth_formula = "the view depths the scene's bounding sphere spans from the camera, \
                             [max(c − R, z_near), c + R] with c the bounds' centre's depth, cut at this fraction";
        push(
            "soler.voxel_depth_from",
            so.voxel_depth_from as f64,
            "× extent",
            z0 as f64,
            "m (view depth)",
            depth_formula.into(),
        );
        push(
            "soler.voxel_depth_to",
            so.voxel_depth_to as f64,
            "× extent",
            z1 as f64,
            "m (view depth)",
            depth_formula.into(),
        );
    }
    if used("ism") {
        let i = &s.ism;
        push(
            "ism.eye_offset",
            i.eye_offset as f64,
            "× R",
            (i.eye_offset * r) as f64,
            "m",
            format!("eye_offset × R; {r_is}"),
        );
        for (name, t) in [("pull_threshold", i.pull_threshold), ("push_threshold", i.push_threshold)] {
            push(
                &format!("ism.{name}"),
                t as f64,
                "× extent",
                (t * 2.0 * r) as f64,
                "m at level 0",
                format!("{name} × 2R at level 0, doubling each pull-push level; {r_is}"),
            );
        }
    }
    if used("interleave") {
        let a = s.interleave.alpha;
        let range = p.camera.zfar - p.camera.znear;
        push(
            "interleave.alpha",
            a as f64,
            "× (z_far − z_near)",
            (a * range) as f64,
            "m",
            "alpha × (z_far − z_near) of the camera (provenance.camera)".into(),
        );
    }
    out
}
