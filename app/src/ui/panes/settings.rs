//! The settings pane, with the HCB's Table 1 and Soler's ring reach per level.

use crate::ui::ERROR;
use crate::ui::state::State;

pub(super) fn settings_ui(st: &mut State, ui: &mut egui::Ui) {
    let Ok(l) = &mut st.lab else { return };
    ui.horizontal(|ui| {
        ui.add(
            egui::TextEdit::singleline(&mut st.settings_search)
                .hint_text("search: name, symbol (θ_max), paper (Nguyen)…")
                .desired_width(ui.available_width() - 30.0),
        )
        .accessible_name("settings search");
        if !st.settings_search.is_empty() && ui.small_button("×").on_hover_text("clear the search").clicked() {
            st.settings_search.clear();
        }
    });
    let cx = crate::ui::settings_ui::PanelContext {
        search: st.settings_search.clone(),
        idle_groups: idle_groups(&l.renderer),
    };
    let changed = crate::ui::settings_ui::lab_settings_ui(ui, &mut l.settings, &st.preset.baseline, &cx);
    if changed {
        l.apply_settings();
    }
    if let Some((done, target)) = l.renderer.reference_progress() {
        ui.add(
            egui::ProgressBar::new(done as f32 / target.max(1) as f32)
                .text(format!("{done} / {target} VPLs accumulated")),
        );
        if l.renderer.clock.playing {
            ui.small("The accumulation restarts whenever the camera, a light or an animated object moves: pause the animation (Space) to let it converge.");
        }
    }
    if let Some(note) = l.renderer.shadow_note() {
        ui.colored_label(ui.visuals().warn_fg_color, note);
    }
    if let Some(e) = &l.settings_error {
        // A clamped value was applied (a warning); a refused one was not (an error).
        let colour = if e.starts_with("clamped:") { ui.visuals().warn_fg_color } else { ERROR };
        ui.colored_label(colour, e);
    }
    ui.small(scale_note(&l.renderer));
    if l.settings.pipeline.uses_soler() {
        ui.separator();
        egui::CollapsingHeader::new("Soler rings and reach (Fig. 3)")
            .id_salt("soler_reach")
            .default_open(true)
            .show(ui, |ui| soler_reach_ui(ui, &l.settings.soler, l.renderer.size()));
    }
    if l.settings.pipeline.uses_gautron() {
        ui.separator();
        egui::CollapsingHeader::new("Gautron record cache")
            .id_salt("gautron_cache")
            .default_open(true)
            .show(ui, |ui| gautron_cache_ui(ui, &l.renderer, &l.settings));
    }
    if l.settings.pipeline.uses_ddgi() {
        ui.separator();
        egui::CollapsingHeader::new("DDGI probe grid")
            .id_salt("ddgi_grid")
            .default_open(true)
            .show(ui, |ui| ddgi_grid_ui(ui, &l.renderer));
    }
    if l.settings.pipeline.uses_hcb() {
        ui.separator();
        egui::CollapsingHeader::new("HCB statistics (Nguyen Table 1)").id_salt("hcb_stats").default_open(true).show(
            ui,
            |ui| match l.renderer.hcb_stats_later() {
                Some(stats) => hcb_stats_ui(ui, &stats, l.renderer.size()),
                None => {
                    ui.small("no HCB frame rendered yet");
                }
            },
        );
    }
}

/// DDGI's grid as fitted (issue #56): its probes, spacing and box, and why it is smaller than
/// asked when the device holds fewer probes (a warning: the clamped grid runs).
fn ddgi_grid_ui(ui: &mut egui::Ui, r: &gi_render::Renderer) {
    if let Some(e) = r.ddgi_error() {
        ui.colored_label(ERROR, format!("DDGI cannot run on this scene: {e}"));
        return;
    }
    let Some(stage) = r.ddgi() else {
        ui.small("no DDGI frame rendered yet");
        return;
    };
    if let Some(g) = stage.grid() {
        let (c, s) = (g.counts, g.spacing);
        ui.small(format!(
            "{}×{}×{} = {} probes, {:.2} × {:.2} × {:.2} m apart, the first at ({:.2}, {:.2}, {:.2})",
            c.x,
            c.y,
            c.z,
            g.len(),
            s.x,
            s.y,
            s.z,
            g.origin.x,
            g.origin.y,
            g.origin.z
        ));
    }
    if let Some(c) = &stage.clamp {
        ui.colored_label(ui.visuals().warn_fg_color, format!("clamped: {}", c.reason));
    }
}

/// What the scene-relative settings scale with (`scale.reference`, issue #51 point 4).
pub fn scale_note(r: &gi_render::Renderer) -> String {
    use gi_render::scale::ScaleSource;
    match r.scale() {
        (s, ScaleSource::Room(b)) => {
            let e = b.extent();
            format!("scene scale {s:.2} m: the room the camera is in ({:.1} × {:.1} × {:.1} m)", e.x, e.y, e.z)
        }
        (s, ScaleSource::Model) => format!("scene scale {s:.2} m: the model's bounding radius"),
    }
}

/// The groups that cannot act on the open scene, with why (issue #39 point 4).
fn idle_groups(r: &gi_render::Renderer) -> Vec<(&'static str, String)> {
    let scene = r.scene();
    let mut idle = Vec::new();
    if !scene.has_emitters() {
        idle.push(("emitters", "none in this scene".to_string()));
    }
    if !scene.sky.enabled {
        idle.push(("sky", "off (Scene panel)".to_string()));
    } else if !scene.sky.is_lit() {
        idle.push(("sky", "dark (Scene panel)".to_string()));
    }
    idle
}

/// Table 1 of Nguyen et al. for the last frame: per level its resolution, the samples and
/// their share of the level's texels and of the G-buffer's pixels; the total; the covered
/// pixels no sample reached; with the cache (§5), the reused, new and recomputed samples.
pub fn hcb_stats_ui(ui: &mut egui::Ui, stats: &gi_render::passes::hcb::stage::HcbStats, size: (u32, u32)) {
    let pixels = (size.0 * size.1).max(1) as f64;
    let (mut w, mut h) = size;
    egui::Grid::new("hcb_table_1").num_columns(4).striped(true).show(ui, |ui| {
        for head in ["level (resolution)", "samples", "% of level", "% of G-buffer"] {
            ui.strong(head);
        }
        ui.end_row();
        for (k, (&n, &t)) in stats.samples_per_level.iter().zip(&stats.texels_per_level).enumerate() {
            ui.label(format!("{k} ({w}×{h})"));
            ui.label(n.to_string());
            ui.label(format!("{:.2} %", 100.0 * n as f64 / t.max(1) as f64));
            ui.label(format!("{:.2} %", 100.0 * n as f64 / pixels));
            ui.end_row();
            (w, h) = (w.div_ceil(2), h.div_ceil(2));
        }
        ui.strong("total");
        ui.strong(stats.samples().to_string());
        ui.label("");
        ui.strong(format!("{:.2} %", 100.0 * stats.samples() as f64 / pixels));
        ui.end_row();
    });
    ui.small(format!(
        "the paper: 1.9–4.4 % of the G-buffer; {} covered pixels no sample reached; d_max in use {:.3} scene units",
        stats.uncovered, stats.d_max
    ));
    if let Some(c) = &stats.cache {
        egui::Grid::new("hcb_cache_counts").num_columns(2).show(ui, |ui| {
            for (label, n, tip) in [
                ("cached (reused)", c.cached, "samples of the last frame still valid here (§5.1)"),
                ("new", c.new_samples(), "identified on the incomplete texels this frame (§5.2)"),
                ("recomputed", c.recomputed, "cached samples whose light was gathered again (§5.3)"),
                ("removed: invalid", c.invalid, "the G-buffer moved or turned under them (§5.1)"),
                ("removed: surplus", c.surplus, "valid, but inside an invalid sample's quad (§5.1)"),
                ("left the view", c.dropped, "reprojected outside the image"),
            ] {
                ui.label(label).on_hover_text(tip);
                ui.label(n.to_string());
                ui.end_row();
            }
        });
    }
}

/// Soler et al.'s rings (004 §4, Fig. 3) for the settings and the render size: per gathered
/// level its resolution and the ring it samples, in its own texels and in G-buffer pixels, and
/// the reach of the coarsest ring against the image (⚠[soler.ring-reach] the paper's "r so that
/// the whole screen is sampled" does not hold for every setting: 4 levels of r = 40 from a
/// quarter reach 1280 px, but the first level only from a full start).
pub fn soler_reach_ui(ui: &mut egui::Ui, s: &gi_render::passes::soler::SolerSettings, size: (u32, u32)) {
    let r = s.radius_px;
    let off = s.levels_off_image(size);
    egui::Grid::new("soler_rings").num_columns(4).striped(true).show(ui, |ui| {
        for head in ["level (resolution)", "ring (level texels)", "ring (G-buffer px)", "texels"] {
            ui.strong(head);
        }
        ui.end_row();
        for (i, k) in s.gathered_levels().enumerate() {
            let scale = (1u64 << k) as f32;
            let (w, h) = (size.0.div_ceil(1 << k).max(1), size.1.div_ceil(1 << k).max(1));
            let inner = if i == 0 { 0.0 } else { 0.5 * r };
            ui.label(format!("{k} ({w}×{h})"));
            ui.label(if i == 0 { format!("disc 0 … {r:.0}") } else { format!("{inner:.0} … {r:.0}") });
            // A ring that starts beyond the image's diagonal samples nothing on screen.
            if off.contains(&k) {
                ui.colored_label(
                    ui.visuals().warn_fg_color,
                    format!("{:.0} … {:.0}: off the image", inner * scale, r * scale),
                )
                .on_hover_text("this level's ring starts beyond the image's diagonal: it adds no light at this size");
            } else {
                ui.label(format!("{:.0} … {:.0}", inner * scale, r * scale));
            }
            ui.label((w as u64 * h as u64).to_string());
            ui.end_row();
        }
    });
    let reach = s.reach_px();
    let diagonal = (size.0 as f32).hypot(size.1 as f32);
    let verdict =
        if reach >= diagonal { "every pixel reaches every other" } else { "pixels farther apart exchange no light" };
    ui.label(format!(
        "reach {reach:.0} px = {:.0} % of the image diagonal ({diagonal:.0} px): {verdict}",
        100.0 * reach / diagonal.max(1.0)
    ));
}

/// The record cache's counters of the last frame (Gautron et al. 003, "Results"), and a
/// warning when it is full while pixels still lack a record.
pub fn gautron_cache_ui(ui: &mut egui::Ui, r: &gi_render::Renderer, s: &gi_render::LabSettings) {
    let Some((st, _)) = r.gautron_state_later(false) else {
        ui.small("no Gautron frame rendered yet");
        return;
    };
    if s.pipeline.shading_points == gi_render::settings::pipeline::ShadingPoints::HcbSamples {
        ui.label(format!("{} hemispheres this frame, one per HCB sample (no cache)", st.made));
        return;
    }
    let g = &s.gautron;
    egui::Grid::new("gautron_cache_counts").num_columns(2).striped(true).show(ui, |ui| {
        let mut row = |name: &str, value: String| {
            ui.label(name);
            ui.label(value);
            ui.end_row();
        };
        row(
            "records",
            format!("{} of {} ({:.1} %)", st.count, g.capacity, 100.0 * st.count as f64 / g.capacity.max(1) as f64),
        );
        row("made this frame", st.made.to_string());
        row("computed again this frame", st.refreshed.to_string());
        row("stale, waiting", st.stale.to_string());
        row("candidates, last round", st.candidates.to_string());
    });
    if st.count >= g.capacity && st.candidates > 0 {
        ui.colored_label(
            ERROR,
            format!(
                "The cache is full: {} under-covered pixels found no room for a record (they stay without indirect light). \
                 Raise gautron.capacity, use a larger accuracy a, or drop off-screen records (gautron.reuse).",
                st.candidates
            ),
        );
    } else if st.candidates > 0 && st.made >= g.records_per_round * g.rounds {
        ui.small("still covering the image: every round used its whole budget (records per round × rounds)");
    }
}
