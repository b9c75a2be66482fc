//! Settings: the single source of truth for every tunable (docs/principles.md principle 2).
//!
//! Each pass declares its `Settings` struct with [`settings_group!`]: every field carries
//! its documentation, unit, paper symbol, valid range and cost next to it. The macro
//! derives serde (with `#[serde(default)]`, unknown fields refused so that a typo in a
//! preset is reported), the defaults, and a table of [`FieldMeta`] that drives the UI
//! sliders, preset validation and CLI overrides (`--set direct.pcf_radius=2`) — ranges
//! are never repeated elsewhere.

pub mod compose;
pub mod ddgi;
pub mod direct;
pub mod emitters;
pub mod gautron;
pub mod hcb;
pub mod knecht;
pub mod pipeline;
pub mod reference;
pub mod scale;
pub mod sky;
pub mod soler;
pub mod splat;
pub mod view;

/// A setting's value, type-erased for the UI, CLI overrides and validation.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    F32(f32),
    U32(u32),
    Bool(bool),
    /// One of the field's named choices.
    Choice(&'static str),
}

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::F32(v) => write!(f, "{v}"),
            Value::U32(v) => write!(f, "{v}"),
            Value::Bool(v) => write!(f, "{v}"),
            Value::Choice(v) => write!(f, "{v}"),
        }
    }
}

/// What kind of widget / parsing a field needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldKind {
    F32,
    U32,
    Bool,
    Choice(&'static [&'static str]),
}

/// Everything known about one field, declared next to it.
#[derive(Clone, Copy, Debug)]
pub struct FieldMeta {
    /// Field name as in the RON preset.
    pub name: &'static str,
    /// The doc comment: meaning, paper reference.
    pub doc: &'static str,
    /// Unit ("px", "m", "EV", "" for none).
    pub unit: &'static str,
    /// The paper's symbol (θmax, c_base, …) or "".
    pub symbol: &'static str,
    /// What raising the value costs.
    pub cost: &'static str,
    pub kind: FieldKind,
    /// Human-readable labels of a choice's names (same order), empty for other kinds.
    pub labels: &'static [&'static str],
    /// Inclusive range for numbers (ignored for bool and choices).
    pub min: f64,
    pub max: f64,
    /// Whether a change invalidates temporal history (docs/principles.md principle 5).
    pub resets_history: bool,
}

/// A field whose value is invalid.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldError {
    /// Dotted path: `group.field`.
    pub field: String,
    pub message: String,
}

impl std::fmt::Display for FieldError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

/// A type a setting field may have.
pub trait SettingType: Sized {
    const KIND: FieldKind;
    /// Labels of a choice's names for the UI.
    const LABELS: &'static [&'static str] = &[];
    fn to_value(&self) -> Value;
    fn from_value(v: &Value) -> Option<Self>;
}

impl SettingType for f32 {
    const KIND: FieldKind = FieldKind::F32;
    fn to_value(&self) -> Value {
        Value::F32(*self)
    }
    fn from_value(v: &Value) -> Option<Self> {
        match v {
            Value::F32(x) => Some(*x),
            Value::U32(x) => Some(*x as f32),
            _ => None,
        }
    }
}

impl SettingType for u32 {
    const KIND: FieldKind = FieldKind::U32;
    fn to_value(&self) -> Value {
        Value::U32(*self)
    }
    fn from_value(v: &Value) -> Option<Self> {
        match v {
            Value::U32(x) => Some(*x),
            Value::F32(x) if x.fract() == 0.0 && *x >= 0.0 && *x <= u32::MAX as f32 => Some(*x as u32),
            _ => None,
        }
    }
}

impl SettingType for bool {
    const KIND: FieldKind = FieldKind::Bool;
    fn to_value(&self) -> Value {
        Value::Bool(*self)
    }
    fn from_value(v: &Value) -> Option<Self> {
        match v {
            Value::Bool(b) => Some(*b),
            _ => None,
        }
    }
}

/// Parses a textual value (CLI override, UI text box) for a field of `kind`.
pub fn parse_value(kind: FieldKind, text: &str) -> Result<Value, String> {
    let t = text.trim();
    match kind {
        FieldKind::F32 => t.parse::<f32>().map(Value::F32).map_err(|_| format!("'{t}' is not a number")),
        FieldKind::U32 => t.parse::<u32>().map(Value::U32).map_err(|_| format!("'{t}' is not a whole number ≥ 0")),
        FieldKind::Bool => match t {
            "true" | "on" | "1" => Ok(Value::Bool(true)),
            "false" | "off" | "0" => Ok(Value::Bool(false)),
            _ => Err(format!("'{t}' is not true/false")),
        },
        FieldKind::Choice(names) => names
            .iter()
            .find(|n| n.eq_ignore_ascii_case(t))
            .map(|n| Value::Choice(n))
            .ok_or_else(|| format!("'{t}' is not one of {}", names.join(", "))),
    }
}

/// Checks a value against the field's declared range.
pub fn check_range(meta: &FieldMeta, v: &Value) -> Result<(), String> {
    // Compared in the field's own precision: the f64 range 0.01 is not below the f32 0.01.
    let (x, lo, hi) = match v {
        Value::F32(x) => {
            if !x.is_finite() {
                return Err(format!("{x} is not a finite number"));
            }
            (*x as f64, meta.min as f32 as f64, meta.max as f32 as f64)
        }
        Value::U32(x) => (*x as f64, meta.min, meta.max),
        Value::Bool(_) | Value::Choice(_) => return Ok(()),
    };
    if x < lo || x > hi {
        let unit = if meta.unit.is_empty() { String::new() } else { format!(" {}", meta.unit) };
        return Err(format!("{} is outside [{}, {}]{unit}", v, meta.min, meta.max));
    }
    Ok(())
}

/// Clamps a numeric value into the field's range (used when a preset is loaded with an
/// out-of-range value: the problem is reported and the clamped value kept).
pub fn clamp_value(meta: &FieldMeta, v: &Value) -> Value {
    match v {
        Value::F32(x) if !x.is_finite() => Value::F32(meta.min.max(0.0).min(meta.max) as f32),
        Value::F32(x) => Value::F32((*x as f64).clamp(meta.min, meta.max) as f32),
        Value::U32(x) => Value::U32((*x as f64).clamp(meta.min, meta.max) as u32),
        other => other.clone(),
    }
}

/// A settings struct of one pass / stage.
pub trait SettingsGroup: Default + Clone + PartialEq {
    /// The group's name in presets and dotted paths (`direct`, `tonemap`).
    const GROUP: &'static str;
    fn fields() -> &'static [FieldMeta];
    fn get(&self, field: &str) -> Option<Value>;
    /// Sets a field; errors name the field and why.
    fn set(&mut self, field: &str, v: &Value) -> Result<(), String>;

    /// Every invalid field, with its dotted path.
    fn validate(&self) -> Vec<FieldError> {
        let mut errors = Vec::new();
        for m in Self::fields() {
            if let Some(v) = self.get(m.name)
                && let Err(message) = check_range(m, &v)
            {
                errors.push(FieldError { field: format!("{}.{}", Self::GROUP, m.name), message });
            }
        }
        errors
    }

    /// Clamps every out-of-range field and returns what was changed.
    fn clamp_all(&mut self) -> Vec<FieldError> {
        let mut changed = Vec::new();
        for m in Self::fields() {
            if let Some(v) = self.get(m.name)
                && let Err(message) = check_range(m, &v)
            {
                let c = clamp_value(m, &v);
                let _ = self.set(m.name, &c);
                changed.push(FieldError {
                    field: format!("{}.{}", Self::GROUP, m.name),
                    message: format!("{message}; clamped to {c}"),
                });
            }
        }
        changed
    }

    /// Whether any field that `resets_history` differs between `self` and `other`.
    fn history_invalidated_by(&self, other: &Self) -> bool {
        Self::fields().iter().any(|m| m.resets_history && self.get(m.name) != other.get(m.name))
    }
}

/// Declares an enum usable as a setting (a combo box in the UI, a name in presets).
#[macro_export]
macro_rules! settings_enum {
    (
        $(#[$meta:meta])*
        pub enum $name:ident { $( $(#[doc = $doc:literal])* $variant:ident = $label:literal ),+ $(,)? }
        default $default:ident
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
        pub enum $name { $( $(#[doc = $doc])* $variant ),+ }
        impl Default for $name { fn default() -> Self { Self::$default } }
        impl $name {
            /// Names of the choices as presets and the UI spell them.
            pub const NAMES: &'static [&'static str] = &[ $( stringify!($variant) ),+ ];
            /// Human-readable labels in the order of [`Self::NAMES`].
            pub const LABELS: &'static [&'static str] = &[ $( $label ),+ ];
        }
        impl $crate::settings::SettingType for $name {
            const KIND: $crate::settings::FieldKind = $crate::settings::FieldKind::Choice(Self::NAMES);
            const LABELS: &'static [&'static str] = $name::LABELS;
            fn to_value(&self) -> $crate::settings::Value {
                match self { $( Self::$variant => $crate::settings::Value::Choice(stringify!($variant)) ),+ }
            }
            fn from_value(v: &$crate::settings::Value) -> Option<Self> {
                match v {
                    $crate::settings::Value::Choice(n) => match *n { $( stringify!($variant) => Some(Self::$variant), )+ _ => None },
                    _ => None,
                }
            }
        }
    };
}

/// Declares a pass's settings struct with its field metadata (see the module docs).
///
/// ```text
/// settings_group! {
///     /// Direct light (stage 2).
///     pub struct DirectSettings: "direct" {
///         /// PCF kernel radius in shadow-map texels.
///         pcf_radius: u32 = 1, unit "texels", symbol "", range 0..=4, cost "(2r+1)² lookups per light", history false;
///     }
/// }
/// ```
///
/// An optional `legacy { /// doc\n name: Type; }` block after the fields declares fields of
/// older preset versions: read on load (`Option`, absent by default), never written, not
/// settings; the migration turns them into current fields.
#[macro_export]
macro_rules! settings_group {
    (
        $(#[doc = $sdoc:literal])*
        pub struct $name:ident : $group:literal {
            $(
                $(#[doc = $doc:literal])+
                $field:ident : $ty:ty = $default:expr ,
                unit $unit:literal , symbol $symbol:literal , range $min:literal ..= $max:literal ,
                cost $cost:literal , history $hist:literal ;
            )+
        }
        $( legacy { $( $(#[doc = $ldoc:literal])+ $lfield:ident : $lty:ty ; )+ } )?
    ) => {
        $(#[doc = $sdoc])*
        #[derive(Clone, PartialEq, Debug, serde::Serialize, serde::Deserialize)]
        #[serde(default, deny_unknown_fields)]
        pub struct $name {
            $( $(#[doc = $doc])+ pub $field: $ty, )+
            $($(
                $(#[doc = $ldoc])+
                #[serde(skip_serializing, deserialize_with = "crate::settings::legacy_field")]
                pub $lfield: Option<$lty>,
            )+)?
        }
        impl Default for $name {
            fn default() -> Self { Self { $( $field: $default, )+ $($( $lfield: None, )+)? } }
        }
        impl $crate::settings::SettingsGroup for $name {
            const GROUP: &'static str = $group;
            fn fields() -> &'static [$crate::settings::FieldMeta] {
                const FIELDS: &[$crate::settings::FieldMeta] = &[ $(
                    $crate::settings::FieldMeta {
                        name: stringify!($field),
                        doc: concat!($($doc, "\n"),+),
                        unit: $unit,
                        symbol: $symbol,
                        cost: $cost,
                        kind: <$ty as $crate::settings::SettingType>::KIND,
                        labels: <$ty as $crate::settings::SettingType>::LABELS,
                        min: $min as f64,
                        max: $max as f64,
                        resets_history: $hist,
                    }
                ),+ ];
                FIELDS
            }
            fn get(&self, field: &str) -> Option<$crate::settings::Value> {
                match field {
                    $( stringify!($field) => Some($crate::settings::SettingType::to_value(&self.$field)), )+
                    _ => None,
                }
            }
            fn set(&mut self, field: &str, v: &$crate::settings::Value) -> Result<(), String> {
                match field {
                    $( stringify!($field) => {
                        self.$field = <$ty as $crate::settings::SettingType>::from_value(v)
                            .ok_or_else(|| format!("{}.{}: {v} has the wrong type", $group, field))?;
                        Ok(())
                    } )+
                    _ => Err(format!("{} has no field '{}'", $group, field)),
                }
            }
        }
    };
}

/// A typed error of preset parsing (RON syntax or types).
#[derive(Debug, thiserror::Error)]
pub enum PresetError {
    #[error("cannot read preset {path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error("preset {path} is not valid: {message}")]
    Parse { path: String, message: String },
    #[error("preset {path} has invalid values:\n{}", list(.errors))]
    Invalid { path: String, errors: Vec<FieldError> },
}

fn list(errors: &[FieldError]) -> String {
    errors.iter().map(|e| format!("  - {e}")).collect::<Vec<_>>().join("\n")
}

/// Current preset format version (see [`LabSettings::version`]). Version 2 replaced
/// `indirect.technique` and the stage switches of the groups by the stage choices
/// (`pipeline.*`, see `crate::settings::pipeline::migrate_v1`).
pub const PRESET_VERSION: u32 = 2;

/// Reads a field of an older preset version (a `legacy` field of [`settings_group!`]),
/// written without `Some(..)`.
pub fn legacy_field<'de, D: serde::Deserializer<'de>, T: serde::Deserialize<'de>>(d: D) -> Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
}

/// Whether a value is the default, for `skip_serializing_if`.
pub fn is_default<T: Default + PartialEq>(t: &T) -> bool {
    *t == T::default()
}
