//! `gi-lab settings`: every setting with its unit, range and default.

use gi_render::LabSettings;

pub(super) fn settings() {
    for (group, fields) in LabSettings::groups() {
        println!("[{group}]");
        let d = LabSettings::default();
        for m in fields {
            let path = format!("{group}.{}", m.name);
            let default = d.get(&path).map(|v| v.to_string()).unwrap_or_default();
            let range = match m.kind {
                gi_render::settings::FieldKind::F32 | gi_render::settings::FieldKind::U32 => {
                    format!("[{}, {}] {}", m.min, m.max, m.unit)
                }
                gi_render::settings::FieldKind::Bool => "on/off".into(),
                gi_render::settings::FieldKind::Choice(c) => c.join(" | "),
            };
            let doc = m.doc.lines().next().unwrap_or("");
            println!("  {:<26} default {:<10} {:<24} {}", path, default, range, doc);
        }
    }
}
