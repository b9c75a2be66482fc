//! `LabSettings`: every pass's settings in one aggregate, saved as a RON preset
//! (docs/principles.md principle 3). Unknown fields, wrong types and out-of-range values are
//! reported by name; out-of-range values can be clamped on load.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::settings::compose::TonemapSettings;
use crate::settings::ddgi::DdgiSettings;
use crate::settings::direct::DirectSettings;
use crate::settings::emitters::EmitterSettings;
use crate::settings::gautron::GautronSettings;
use crate::settings::hcb::HcbSettings;
use crate::settings::knecht::InterleaveSettings;
use crate::settings::knecht::IsmSettings;
use crate::settings::knecht::TemporalSettings;
use crate::settings::knecht::VplSettings;
use crate::settings::pipeline::{LegacyIndirect, PipelineSettings};
use crate::settings::reference::ReferenceSettings;
use crate::settings::scale::ScaleSettings;
use crate::settings::sky::SkySettings;
use crate::settings::soler::SolerSettings;
use crate::settings::{FieldError, FieldMeta, PRESET_VERSION, PresetError, SettingsGroup, Value};
use crate::settings_group;

mod migrate;
mod rules;

impl crate::settings::pipeline::Technique {
    /// Sets the technique's choices in `s`.
    pub fn apply(self, s: &mut LabSettings) {
        s.pipeline = self.choices(&s.pipeline);
    }
}

settings_group! {
    /// The deterministic clock (see `clock.rs`).
    pub struct AnimationSettings: "animation" {
        /// Fixed time step of one frame; animation time = animated frames × step.
        time_step_s: f32 = 1.0 / 60.0,
        unit "s", symbol "Δt", range 0.001..=1.0, cost "free", history true;
    }
}

/// Fields that must be powers of two (mip pyramids and pull-push halve them down to one
/// texel); the UI steps them by doublings.
pub const POWER_OF_TWO_FIELDS: &[&str] = &["vpl.light_gbuffer_size", "ism.map_size"];

/// All settings of the lab. A preset file is this struct in RON.
#[derive(Clone, PartialEq, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LabSettings {
    /// Preset format version; older versions are migrated on load (a file without it is
    /// version 0).
    #[serde(default)]
    pub version: u32,
    pub animation: AnimationSettings,
    pub direct: DirectSettings,
    /// Emissive surfaces as lights (stage 2).
    pub emitters: EmitterSettings,
    /// The sky light's sampling (stage 2; the sky itself belongs to the scene).
    pub sky: SkySettings,
    /// The stage choices (stages 3–7): which pass each stage runs.
    pub pipeline: PipelineSettings,
    pub scale: ScaleSettings,
    /// Version 1's technique, read from old presets only (see `pipeline::migrate_v1`), never
    /// written (it is read without `Some(..)`, so a written `Some(..)` could not be read back).
    #[serde(skip_serializing, deserialize_with = "crate::settings::legacy_field")]
    pub indirect: Option<LegacyIndirect>,
    pub vpl: VplSettings,
    pub ism: IsmSettings,
    pub interleave: InterleaveSettings,
    pub temporal: TemporalSettings,
    pub hcb: HcbSettings,
    pub soler: SolerSettings,
    pub gautron: GautronSettings,
    /// DDGI's probes (issue #56; Majercik et al. 2019, 2021).
    pub ddgi: DdgiSettings,
    pub reference: ReferenceSettings,
    pub tonemap: TonemapSettings,
}

impl Default for LabSettings {
    fn default() -> Self {
        Self {
            version: PRESET_VERSION,
            animation: Default::default(),
            direct: Default::default(),
            emitters: Default::default(),
            sky: Default::default(),
            pipeline: Default::default(),
            scale: Default::default(),
            indirect: None,
            vpl: Default::default(),
            ism: Default::default(),
            interleave: Default::default(),
            temporal: Default::default(),
            hcb: Default::default(),
            soler: Default::default(),
            gautron: Default::default(),
            ddgi: Default::default(),
            reference: Default::default(),
            tonemap: Default::default(),
        }
    }
}

/// Calls `$m!(field, Type)` for every group, so that adding a group is one line here.
macro_rules! for_each_group {
    ($m:ident) => {
        $m!(animation, AnimationSettings);
        $m!(direct, DirectSettings);
        $m!(emitters, EmitterSettings);
        $m!(sky, SkySettings);
        $m!(pipeline, PipelineSettings);
        $m!(scale, ScaleSettings);
        $m!(vpl, VplSettings);
        $m!(ism, IsmSettings);
        $m!(interleave, InterleaveSettings);
        $m!(temporal, TemporalSettings);
        $m!(hcb, HcbSettings);
        $m!(soler, SolerSettings);
        $m!(gautron, GautronSettings);
        $m!(ddgi, DdgiSettings);
        $m!(reference, ReferenceSettings);
        $m!(tonemap, TonemapSettings);
    };
}

/// Visits every settings group of a [`LabSettings`] with its counterpart in another one
/// (the UI: the live settings and the loaded preset).
pub trait GroupVisitor {
    fn visit<S: SettingsGroup>(&mut self, settings: &mut S, other: &S);
}

impl LabSettings {
    /// Calls `v` for every group in declaration order, with the same group of `other`.
    pub fn visit_groups<V: GroupVisitor>(&mut self, other: &Self, v: &mut V) {
        macro_rules! visit {
            ($f:ident, $t:ty) => {
                v.visit(&mut self.$f, &other.$f);
            };
        }
        for_each_group!(visit);
    }

    /// Every group name with its field table, in pipeline order.
    pub fn groups() -> Vec<(&'static str, &'static [FieldMeta])> {
        let mut v = Vec::new();
        macro_rules! push {
            ($f:ident, $t:ty) => {
                v.push((<$t>::GROUP, <$t>::fields()));
            };
        }
        for_each_group!(push);
        v
    }

    /// Value at a dotted path (`direct.pcf_radius`).
    pub fn get(&self, path: &str) -> Option<Value> {
        let (group, field) = path.split_once('.')?;
        macro_rules! get {
            ($f:ident, $t:ty) => {
                if group == <$t>::GROUP {
                    return self.$f.get(field);
                }
            };
        }
        for_each_group!(get);
        None
    }

    /// Sets the value at a dotted path after checking its range.
    pub fn set(&mut self, path: &str, value: &Value) -> Result<(), String> {
        let meta = Self::field(path).ok_or_else(|| format!("no setting named '{path}'"))?;
        crate::settings::check_range(meta, value).map_err(|e| format!("{path}: {e}"))?;
        let (group, field) = path.split_once('.').ok_or_else(|| format!("no setting named '{path}'"))?;
        macro_rules! set {
            ($f:ident, $t:ty) => {
                if group == <$t>::GROUP {
                    return self.$f.set(field, value);
                }
            };
        }
        for_each_group!(set);
        Err(format!("no setting named '{path}'"))
    }

    /// Parses `path=value` (CLI `--set`) and applies it.
    pub fn apply_override(&mut self, assignment: &str) -> Result<(), String> {
        let (path, text) =
            assignment.split_once('=').ok_or_else(|| format!("'{assignment}' is not of the form group.field=value"))?;
        if path.trim() == "indirect.technique" {
            // Version 1's technique, kept for scripts written before the stage choices.
            let t = crate::settings::pipeline::Technique::from_v1_name(text.trim()).ok_or_else(|| {
                format!("indirect.technique: '{}' is not one of None, ExactVpl, InstantRadiosity, Hcb", text.trim())
            })?;
            t.apply(self);
            return Ok(());
        }
        let meta =
            Self::field(path.trim()).ok_or_else(|| match crate::settings::pipeline::moved_setting(path.trim()) {
                Some(to) => format!("{} was replaced by {to} (preset version 2)", path.trim()),
                None => format!("no setting named '{}'; known: {}", path.trim(), Self::all_paths().join(", ")),
            })?;
        let v = crate::settings::parse_value(meta.kind, text).map_err(|e| format!("{}: {e}", path.trim()))?;
        self.set(path.trim(), &v)
    }

    /// The metadata of a dotted path.
    pub fn field(path: &str) -> Option<&'static FieldMeta> {
        let (group, field) = path.split_once('.')?;
        Self::groups().into_iter().find(|(g, _)| *g == group)?.1.iter().find(|m| m.name == field)
    }

    /// Every setting whose value differs from `base`'s: (path, value here, value in `base`).
    pub fn differences(&self, base: &LabSettings) -> Vec<(String, Value, Value)> {
        Self::all_paths()
            .into_iter()
            .filter_map(|p| {
                let (a, b) = (self.get(&p)?, base.get(&p)?);
                (a != b).then_some((p, a, b))
            })
            .collect()
    }

    pub fn all_paths() -> Vec<String> {
        Self::groups()
            .into_iter()
            .flat_map(|(g, fields)| fields.iter().map(move |m| format!("{g}.{}", m.name)))
            .collect()
    }

    /// Every invalid field.
    pub fn validate(&self) -> Vec<FieldError> {
        let mut errors = Vec::new();
        if self.version > PRESET_VERSION {
            errors.push(FieldError {
                field: "version".into(),
                message: format!("{} is newer than this GI Lab understands ({PRESET_VERSION})", self.version),
            });
        }
        macro_rules! validate {
            ($f:ident, $t:ty) => {
                errors.extend(self.$f.validate());
            };
        }
        for_each_group!(validate);
        let in_range = errors.iter().all(|e| e.field == "version");
        errors.extend(self.combination_errors(in_range));
        errors
    }

    /// Settings that are valid one by one but not together, or not for the GPU's layouts
    /// (docs/principles.md, the pipeline table: combinations are refused with a reason, never
    /// by a crash). The stage choices' rules (`pipeline::combination_errors`) are checked when
    /// every field is in its range (`in_range`) only: they are rules about valid values, and
    /// their arithmetic assumes them (an `interleave.n` of 65536 overflowed n², found by the
    /// fuzzer, issue #19); until the fields are fixed, the range errors say what is wrong.
    fn combination_errors(&self, in_range: bool) -> Vec<FieldError> {
        let mut errors = Vec::new();
        let mut err = |field: &str, message: String| errors.push(FieldError { field: field.into(), message });
        for field in POWER_OF_TWO_FIELDS {
            let Some(Value::U32(v)) = self.get(field) else { continue };
            if !v.is_power_of_two() {
                // The powers of two around v, in u64: 0 has none below, and above 2³¹ the next
                // one does not fit in a u32 (found by the fuzzer, issue #19: both panicked).
                let nearest = match v.checked_ilog2() {
                    Some(l) => format!("use {} or {}", 1u64 << l, 2u64 << l),
                    None => "use 1 or a larger power of two".to_string(),
                };
                err(field, format!("{v} is not a power of two (the pyramid halves it down to 1 texel); {nearest}"));
            }
        }
        if in_range {
            // Gautron et al. 003 "Irradiance Interpolation": a record contributes where w_k >
            // 1/a; clamped to w_max ≤ 1/a none ever does, no pixel is covered and the creation
            // fills the cache (issue #41).
            let (a, w_max) = (self.gautron.accuracy, self.gautron.weight_clamp);
            if w_max <= 1.0 / a {
                let least = 1.0 / a;
                err(
                    "gautron.weight_clamp",
                    format!(
                        "{w_max} ≤ 1/a = {least:.3} (a = gautron.accuracy = {a}): no record's clamped weight passes w > 1/a, so no pixel is ever covered; use more than {least:.3}"
                    ),
                );
            }
            errors.extend(rules::combination_errors(self));
        }
        errors.extend(migrate::legacy_field_errors(self));
        errors
    }

    /// Clamps every out-of-range field; returns what was changed.
    pub fn clamp_all(&mut self) -> Vec<FieldError> {
        let mut changed = Vec::new();
        macro_rules! clamp {
            ($f:ident, $t:ty) => {
                changed.extend(self.$f.clamp_all());
            };
        }
        for_each_group!(clamp);
        changed
    }

    /// Whether switching from `self` to `other` invalidates temporal history.
    pub fn history_invalidated_by(&self, other: &Self) -> bool {
        let mut any = false;
        macro_rules! hist {
            ($f:ident, $t:ty) => {
                any |= self.$f.history_invalidated_by(&other.$f);
            };
        }
        for_each_group!(hist);
        any
    }

    /// Parses a preset; the value is returned only when every field is valid.
    pub fn from_ron(text: &str, origin: &str) -> Result<Self, PresetError> {
        let s: Self =
            ron::from_str(text).map_err(|e| PresetError::Parse { path: origin.into(), message: e.to_string() })?;
        let s = s.migrate();
        let errors = s.validate();
        if errors.is_empty() { Ok(s) } else { Err(PresetError::Invalid { path: origin.into(), errors }) }
    }

    /// Upgrades an older preset version (version 0 = files written before versioning):
    /// version 1's technique and stage switches become the stage choices of version 2.
    pub fn migrate(mut self) -> Self {
        if self.version < 2 {
            migrate::migrate_v1(&mut self);
        }
        if self.version < PRESET_VERSION {
            self.version = PRESET_VERSION;
        }
        self
    }

    pub fn load(path: &Path) -> Result<Self, PresetError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| PresetError::Io { path: path.display().to_string(), source })?;
        Self::from_ron(&text, &path.display().to_string())
    }

    /// The preset as RON, each choice field preceded by a comment with its options (name:
    /// label), so that a preset read in an editor says what else may go there.
    pub fn to_ron(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new().depth_limit(3).struct_names(false);
        let text = match ron::ser::to_string_pretty(self, cfg) {
            Ok(t) => t,
            Err(e) => return format!("// serialisation failed: {e}"),
        };
        let groups = Self::groups();
        let mut out = String::with_capacity(text.len() * 2);
        let mut group: Option<&str> = None;
        for line in text.lines() {
            let trimmed = line.trim_start();
            let indent = &line[..line.len() - trimmed.len()];
            if let Some(name) = trimmed.strip_suffix(": (") {
                group = groups.iter().find(|(g, _)| *g == name).map(|(g, _)| *g);
            } else if trimmed == ")," {
                group = None;
            } else if let (Some(g), Some((field, _))) = (group, trimmed.split_once(':')) {
                let meta = groups.iter().find(|(n, _)| *n == g).and_then(|(_, f)| f.iter().find(|m| m.name == field));
                if let Some(m) = meta
                    && let crate::settings::FieldKind::Choice(names) = m.kind
                {
                    let options: Vec<String> = names.iter().zip(m.labels).map(|(n, l)| format!("{n}: {l}")).collect();
                    out.push_str(&format!("{indent}// {}\n", options.join("; ")));
                }
            }
            out.push_str(line);
            out.push('\n');
        }
        out
    }

    /// Writes the preset atomically (`crate::files::write_atomic`): a temporary file, then
    /// a rename; the replaced file is kept as `<name>.bak`.
    pub fn save(&self, path: &Path) -> Result<(), PresetError> {
        crate::files::write_atomic(path, &self.to_ron())
            .map_err(|source| PresetError::Io { path: path.display().to_string(), source })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_preset_round_trips_and_is_valid() {
        let s = LabSettings::default();
        assert!(s.validate().is_empty());
        let back = LabSettings::from_ron(&s.to_ron(), "test").expect("round trip");
        assert_eq!(back, s);
    }

    #[test]
    fn checked_in_default_preset_matches_defaults() {
        let text = include_str!("../../../presets/default.ron");
        let s = LabSettings::from_ron(text, "presets/default.ron").expect("presets/default.ron loads");
        assert_eq!(s, LabSettings::default(), "presets/default.ron differs from LabSettings::default()");
    }

    #[test]
    fn validation_names_every_bad_field() {
        let mut s = LabSettings::default();
        s.direct.pcf_radius = 99;
        s.tonemap.key = -1.0;
        s.animation.time_step_s = f32::NAN;
        let errors = s.validate();
        let fields: Vec<_> = errors.iter().map(|e| e.field.as_str()).collect();
        assert_eq!(fields, ["animation.time_step_s", "direct.pcf_radius", "tonemap.key"], "{errors:?}");
        let changed = s.clamp_all();
        assert_eq!(changed.len(), 3);
        assert_eq!(s.direct.pcf_radius, 4);
        assert!(s.validate().is_empty(), "{:?}", s.validate());
    }

    #[test]
    fn a_weight_clamp_no_record_can_pass_is_refused() {
        let mut s = LabSettings::default();
        s.gautron.accuracy = 0.5;
        s.gautron.weight_clamp = 2.0;
        let errors = s.validate();
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert_eq!(errors[0].field, "gautron.weight_clamp");
        assert!(errors[0].message.contains("1/a = 2.000"), "{}", errors[0].message);
        s.gautron.weight_clamp = 2.01;
        assert!(s.validate().is_empty(), "{:?}", s.validate());
    }

    #[test]
    fn unknown_fields_and_wrong_types_are_errors() {
        let unknown = "(direct: (pcf_radiuss: 2))";
        let e = LabSettings::from_ron(unknown, "x").unwrap_err().to_string();
        assert!(e.contains("pcf_radiuss"), "{e}");
        let wrong = "(direct: (pcf_radius: \"two\"))";
        assert!(LabSettings::from_ron(wrong, "x").is_err());
        let range = "(direct: (pcf_radius: 9))";
        let e = LabSettings::from_ron(range, "x").unwrap_err().to_string();
        assert!(e.contains("direct.pcf_radius"), "{e}");
    }

    #[test]
    fn overrides_parse_and_check_ranges() {
        let mut s = LabSettings::default();
        s.apply_override("direct.pcf_radius=3").expect("valid");
        assert_eq!(s.direct.pcf_radius, 3);
        s.apply_override("tonemap.auto_exposure=on").expect("valid");
        assert!(s.tonemap.auto_exposure);
        assert!(s.apply_override("direct.pcf_radius=30").is_err());
        assert!(s.apply_override("direct.nope=1").is_err());
        assert!(s.apply_override("garbage").is_err());
        assert_eq!(s.get("direct.pcf_radius"), Some(Value::U32(3)));
    }

    /// Found by the fuzzer (issue #19): `validate` took the logarithm of a power-of-two field
    /// before its range was checked, and panicked on 0 (and overflowed past 2³¹).
    #[test]
    fn power_of_two_check_takes_any_value() {
        for v in [0, 3, 3_000_000_000, u32::MAX] {
            let mut s = LabSettings::default();
            s.vpl.light_gbuffer_size = v;
            s.ism.map_size = v;
            let errors = s.validate();
            for field in POWER_OF_TWO_FIELDS {
                assert!(
                    errors.iter().any(|e| e.field == *field && e.message.contains("power of two")),
                    "{v}: {errors:?}"
                );
            }
        }
        let mut s = LabSettings::default();
        s.vpl.light_gbuffer_size = 3_000_000_000;
        let e = s.validate().into_iter().find(|e| e.message.contains("power of two")).expect("power-of-two error");
        assert!(e.message.contains("2147483648 or 4294967296"), "{}", e.message);
        let e = LabSettings::from_ron("(vpl: (light_gbuffer_size: 0))", "t").expect_err("0 is refused").to_string();
        assert!(e.contains("vpl.light_gbuffer_size"), "{e}");
    }

    /// Found by the fuzzer (issue #19, in a debug build): `interleave.n` = 65536 with
    /// interleaved tiles overflowed n² in the stage choices' rules. They run on in-range
    /// values only; the range error names the field.
    #[test]
    fn combination_rules_wait_for_valid_fields() {
        let mut s = LabSettings::default();
        crate::settings::pipeline::Technique::Knecht.apply(&mut s);
        assert_eq!(s.pipeline.shading_points, crate::settings::pipeline::ShadingPoints::InterleavedTiles);
        s.vpl.count = 4;
        let fields = |s: &LabSettings| s.validate().into_iter().map(|e| e.field).collect::<Vec<_>>();
        assert!(fields(&s).contains(&"vpl.count".to_string()), "4 VPLs for 4×4 tiles: {:?}", s.validate());
        s.interleave.n = 65536;
        assert_eq!(fields(&s), ["interleave.n"]);
        let text = s.to_ron();
        let err = LabSettings::from_ron(&text, "t").expect_err("out of range").to_string();
        assert!(err.contains("interleave.n") && !err.contains("vpl.count"), "{err}");
    }

    /// Found by the fuzzer (issue #19): a preset newer than version 2 keeps its version-1
    /// fields (no migration), and `to_ron` wrote them as `Some(..)`, which the reader (legacy
    /// fields are read without `Some`) refused. They are never written now.
    #[test]
    fn legacy_fields_are_never_written() {
        let text = "(version: 4294967295, indirect: (technique: Hcb), ism: (visibility: Exact), \
                    reference: (visibility: false), interleave: (filter: false), temporal: (enabled: false), \
                    hcb: (cache: true))";
        let s: LabSettings = ron::from_str(text).expect("the raw preset parses");
        let s = s.migrate();
        assert!(s.indirect.is_some() && s.hcb.cache == Some(true), "a newer version is not migrated");
        let written = s.to_ron();
        assert!(!written.contains("technique") && !written.contains("Some("), "{written}");
        let back: LabSettings = ron::from_str(&written).expect("to_ron's output parses again");
        assert_eq!(back.version, s.version);
        assert!(back.indirect.is_none() && back.hcb.cache.is_none());
    }

    #[test]
    fn history_reset_follows_field_flags() {
        let a = LabSettings::default();
        let mut b = a.clone();
        b.tonemap.exposure_ev = 2.0;
        assert!(!a.history_invalidated_by(&b), "exposure does not touch history");
        b.direct.intensity_scale = 2.0;
        assert!(a.history_invalidated_by(&b));
    }
}
