//! `LabSettings`: every pass's settings in one aggregate, saved as a RON preset
//! (DESIGN.md principle 3). Unknown fields, wrong types and out-of-range values are
//! reported by name; out-of-range values can be clamped on load.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::passes::compose::TonemapSettings;
use crate::passes::direct::DirectSettings;
use crate::passes::hcb::HcbSettings;
use crate::passes::interleave::InterleaveSettings;
use crate::passes::ism::{IsmSettings, VplVisibility};
use crate::passes::temporal::TemporalSettings;
use crate::passes::vpl::ReferenceSettings;
use crate::passes::vpl_importance::VplSettings;
use crate::settings::{FieldError, FieldMeta, PRESET_VERSION, PresetError, SettingsGroup, Value};
use crate::{settings_enum, settings_group};

settings_group! {
    /// The deterministic clock (see `clock.rs`).
    pub struct AnimationSettings: "animation" {
        /// Fixed time step of one frame; animation time = animated frames × step.
        time_step_s: f32 = 1.0 / 60.0,
        unit "s", symbol "Δt", range 0.001..=1.0, cost "free", history true;
    }
}

settings_enum! {
    /// How stages 3–6 compute indirect light (DESIGN.md's pipeline table). The techniques of
    /// issues #5 and #6 add their choices here.
    pub enum IndirectTechnique {
        /// No indirect light: the image is the direct light.
        None = "none (direct light only)",
        /// Many VPLs with exact visibility maps, accumulated over frames: the reference the
        /// techniques are measured against (Knecht 002 §5.2).
        ExactVpl = "exact-VPL reference",
        /// Instant radiosity with imperfect shadow maps, interleaved sampling and temporal
        /// coherence (Knecht 002): stages 3–7 as the `vpl`, `ism`, `interleave` and
        /// `temporal` settings choose.
        InstantRadiosity = "instant radiosity (Knecht)",
        /// The hierarchical coherence buffer (Nguyen et al.): the VPLs and visibility of
        /// instant radiosity gathered at a few percent of the pixels, chosen by the `hcb`
        /// settings, and splatted to the coherent pixels around them.
        Hcb = "hierarchical coherence buffer (Nguyen)",
    }
    default None
}

impl IndirectTechnique {
    /// Whether the technique lights the scene with instant radiosity's VPLs (stages 3–4).
    pub fn uses_vpls(self) -> bool {
        matches!(self, Self::InstantRadiosity | Self::Hcb)
    }
}

settings_group! {
    /// Indirect light (stages 3–6): which technique computes it.
    pub struct IndirectSettings: "indirect" {
        /// The technique of stages 3–6.
        technique: IndirectTechnique = IndirectTechnique::None,
        unit "", symbol "", range 0..=2, cost "see the technique's own settings", history true;
    }
}

/// Fields that must be powers of two (mip pyramids and pull-push halve them down to one
/// texel); the UI steps them by doublings.
pub const POWER_OF_TWO_FIELDS: &[&str] = &["vpl.light_gbuffer_size", "ism.map_size"];

/// All settings of the lab. A preset file is this struct in RON.
#[derive(Clone, PartialEq, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LabSettings {
    /// Preset format version; older versions are migrated on load.
    pub version: u32,
    pub animation: AnimationSettings,
    pub direct: DirectSettings,
    pub indirect: IndirectSettings,
    pub vpl: VplSettings,
    pub ism: IsmSettings,
    pub interleave: InterleaveSettings,
    pub temporal: TemporalSettings,
    pub hcb: HcbSettings,
    pub reference: ReferenceSettings,
    pub tonemap: TonemapSettings,
}

impl Default for LabSettings {
    fn default() -> Self {
        Self {
            version: PRESET_VERSION,
            animation: Default::default(),
            direct: Default::default(),
            indirect: Default::default(),
            vpl: Default::default(),
            ism: Default::default(),
            interleave: Default::default(),
            temporal: Default::default(),
            hcb: Default::default(),
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
        $m!(indirect, IndirectSettings);
        $m!(vpl, VplSettings);
        $m!(ism, IsmSettings);
        $m!(interleave, InterleaveSettings);
        $m!(temporal, TemporalSettings);
        $m!(hcb, HcbSettings);
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
        let meta = Self::field(path.trim())
            .ok_or_else(|| format!("no setting named '{}'; known: {}", path.trim(), Self::all_paths().join(", ")))?;
        let v = crate::settings::parse_value(meta.kind, text).map_err(|e| format!("{}: {e}", path.trim()))?;
        self.set(path.trim(), &v)
    }

    /// The metadata of a dotted path.
    pub fn field(path: &str) -> Option<&'static FieldMeta> {
        let (group, field) = path.split_once('.')?;
        Self::groups().into_iter().find(|(g, _)| *g == group)?.1.iter().find(|m| m.name == field)
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
        errors.extend(self.combination_errors());
        errors
    }

    /// Settings that are valid one by one but not together, or not for the GPU's layouts
    /// (DESIGN.md: combinations are refused with a reason, never by a crash).
    fn combination_errors(&self) -> Vec<FieldError> {
        let mut errors = Vec::new();
        let mut err = |field: &str, message: String| errors.push(FieldError { field: field.into(), message });
        for field in POWER_OF_TWO_FIELDS {
            let Some(Value::U32(v)) = self.get(field) else { continue };
            if !v.is_power_of_two() {
                let (lo, hi) = (1u32 << v.ilog2(), 1u32 << (v.ilog2() + 1));
                err(
                    field,
                    format!("{v} is not a power of two (the pyramid halves it down to 1 texel); use {lo} or {hi}"),
                );
            }
        }
        if self.indirect.technique == IndirectTechnique::InstantRadiosity {
            let n = self.interleave.n;
            if self.vpl.count < n * n {
                err(
                    "vpl.count",
                    format!(
                        "{} VPLs cannot cover {n}×{n} interleaved tiles (each tile needs at least one VPL): use at least {} VPLs or interleave.n ≤ {}",
                        self.vpl.count,
                        n * n,
                        (self.vpl.count as f64).sqrt().floor() as u32
                    ),
                );
            }
            if self.ism.visibility == VplVisibility::Imperfect && self.ism.points < self.vpl.count {
                err(
                    "ism.points",
                    format!(
                        "{} points cannot give each of {} ISMs a point: use at least as many points as VPLs",
                        self.ism.points, self.vpl.count
                    ),
                );
            }
        }
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

    /// Upgrades an older preset version (version 0 = files written before versioning).
    fn migrate(mut self) -> Self {
        if self.version == 0 {
            self.version = PRESET_VERSION;
        }
        self
    }

    pub fn load(path: &Path) -> Result<Self, PresetError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| PresetError::Io { path: path.display().to_string(), source })?;
        Self::from_ron(&text, &path.display().to_string())
    }

    pub fn to_ron(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new().depth_limit(3).struct_names(false);
        ron::ser::to_string_pretty(self, cfg).unwrap_or_else(|e| format!("// serialisation failed: {e}"))
    }

    /// Writes the preset atomically (`crate::preset::write_atomic`): a temporary file, then
    /// a rename; the replaced file is kept as `<name>.bak`.
    pub fn save(&self, path: &Path) -> Result<(), PresetError> {
        crate::preset::write_atomic(path, &self.to_ron())
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
        let text = include_str!("../../presets/default.ron");
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
