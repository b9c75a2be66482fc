//! The engine export (`gi-lab export`, File → Export; `docs/preset-schema.md`): the settings a
//! preset's stage choices use, where they were tuned (the scene's bounds, unit and scale, the
//! camera, the resolution), and every scene- or image-relative value both as set and as
//! resolved for that scene and image, with the formula that resolves it again (issue #54
//! point 4; [`resolved`]).

use serde::{Deserialize, Serialize};

use crate::LabSettings;
use crate::camera::Camera;
use crate::maths::Aabb;
use crate::scale::ScaleSource;
use crate::settings::PresetError;

pub mod port_kit;
pub mod resolved;

pub use resolved::Resolved;

/// The scene's bounding box as exported, in scene units, with its bounding radius.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    pub min: [f32; 3],
    pub max: [f32; 3],
    /// Half the box's diagonal: the "scene radius" of the settings in `× scene radius`.
    pub radius: f32,
}

/// The length scene-relative settings were fractions of (`scale.reference`; docs/
/// architecture.md, "Scene scale").
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScaleProvenance {
    /// L in scene units.
    pub length: f32,
    /// Where L came from: `room` (half the diagonal of the room the camera stood in, whose box
    /// is `room_min`/`room_max`) or `model` (the model's bounding radius).
    pub source: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub room_min: Option<[f32; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub room_max: Option<[f32; 3]>,
}

/// Where a preset was tuned: stamped on every engine export.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The GI Lab version that wrote the file.
    pub gi_lab_version: String,
    /// The scene file, or the name of the embedded default scene.
    pub scene: String,
    /// The camera at export time.
    pub camera: Camera,
    /// UTC date and time of the export, ISO 8601.
    pub date: String,
    /// The image the pixel-relative values were tuned at, [width, height] in pixels
    /// (schema 2; [0, 0] in older files).
    #[serde(default)]
    pub resolution: [u32; 2],
    /// The unit of scene lengths: "m" (glTF's metre; the loader converts scenes it finds in
    /// millimetres or centimetres, see `unit_conversion`). Empty in schema 1 files.
    #[serde(default)]
    pub unit: String,
    /// The loader's conversion to metres, when it made one (the factor and its sentence).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_conversion: Option<(f32, String)>,
    /// The scene's bounds (schema 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounds: Option<Bounds>,
    /// The scene's scale L (schema 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<ScaleProvenance>,
}

/// What an export is made from: the scene as the lab sees it at export time.
pub struct ExportView<'a> {
    /// The scene file, or the embedded scene's name.
    pub scene_name: &'a str,
    pub camera: Camera,
    /// The image's width and height in pixels.
    pub size: (u32, u32),
    /// The scene's bounds in scene units (the renderer's: animated objects included).
    pub bounds: Aabb,
    /// `scale::scale_radius` for these settings, camera and scene.
    pub scale: (f32, ScaleSource),
    /// The loader's conversion to metres (`Scene::units`).
    pub units: Option<(f32, String)>,
}

impl<'a> ExportView<'a> {
    /// The view of `scene` with these bounds, camera, image size and settings (the scale as
    /// `scale::scale_radius` measures it for the camera's position).
    pub fn of_scene(
        scene_name: &'a str,
        scene: &crate::scene::Scene,
        bounds: Aabb,
        camera: Camera,
        size: (u32, u32),
        settings: &LabSettings,
    ) -> Self {
        let room = scene.view.as_ref().and_then(|v| v.room.as_ref());
        let scale = crate::scale::scale_radius(settings.scale.reference, room, camera.position, bounds);
        Self { scene_name, camera, size, bounds, scale, units: scene.units.clone() }
    }
}

impl Provenance {
    /// The provenance of an export made now from `v`.
    pub fn now(v: &ExportView) -> Self {
        let finite = v.bounds.min.is_finite() && v.bounds.max.is_finite();
        let bounds = finite.then(|| Bounds {
            min: v.bounds.min.to_array(),
            max: v.bounds.max.to_array(),
            radius: v.bounds.radius(),
        });
        let (length, source) = v.scale;
        let (source, room) = match source {
            ScaleSource::Room(b) => ("room", Some(b)),
            ScaleSource::Model => ("model", None),
        };
        Self {
            gi_lab_version: env!("CARGO_PKG_VERSION").into(),
            scene: v.scene_name.into(),
            camera: v.camera,
            date: utc_now(),
            resolution: [v.size.0, v.size.1],
            unit: "m".into(),
            unit_conversion: v.units.clone(),
            bounds,
            scale: Some(ScaleProvenance {
                length,
                source: source.into(),
                room_min: room.map(|b| b.min.to_array()),
                room_max: room.map(|b| b.max.to_array()),
            }),
        }
    }
}

/// Name and version of the export schema (`docs/preset-schema.md`). Version 2 added the
/// provenance's resolution, unit, bounds and scale, the `resolved` values, and writes only
/// the groups in use; version 1 files still load.
pub const SCHEMA_NAME: &str = "gi-lab-preset";
pub const SCHEMA_VERSION: u32 = 2;

/// The engine export: schema id, provenance, the settings and the resolved values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Export {
    pub schema: String,
    pub schema_version: u32,
    pub provenance: Provenance,
    /// The settings; a file written without `--all-groups` holds only the groups the stage
    /// choices use, and the others load at their defaults.
    pub settings: LabSettings,
    /// Every scene- or image-relative setting of the groups in use, as set and as resolved
    /// for the provenance's scene and image (schema 2; [`resolved::resolve`]).
    #[serde(default)]
    pub resolved: Vec<Resolved>,
    /// Whether [`Export::to_text`] writes every group, in use or not.
    #[serde(skip)]
    pub all_groups: bool,
}

/// Export file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFormat {
    Json,
    Ron,
}

impl ExportFormat {
    pub fn extension(self) -> &'static str {
        match self {
            Self::Json => "json",
            Self::Ron => "ron",
        }
    }
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "json" => Some(Self::Json),
            "ron" => Some(Self::Ron),
            _ => None,
        }
    }
}

/// The settings as written: the groups that act with these stage choices
/// (`PipelineSettings::group_in_use`), or all of them. A group added to [`LabSettings`]
/// must be added here too (`every_group_is_written_with_all_groups` checks it).
#[derive(Serialize)]
struct WrittenSettings<'a> {
    version: u32,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    animation: Option<&'a crate::lab_settings::AnimationSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    direct: Option<&'a crate::settings::direct::DirectSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    emitters: Option<&'a crate::settings::emitters::EmitterSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    sky: Option<&'a crate::settings::sky::SkySettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    pipeline: Option<&'a crate::settings::pipeline::PipelineSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    scale: Option<&'a crate::settings::scale::ScaleSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    vpl: Option<&'a crate::settings::knecht::VplSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    ism: Option<&'a crate::settings::knecht::IsmSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    interleave: Option<&'a crate::settings::knecht::InterleaveSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    temporal: Option<&'a crate::settings::knecht::TemporalSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    hcb: Option<&'a crate::settings::hcb::HcbSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    soler: Option<&'a crate::settings::soler::SolerSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    gautron: Option<&'a crate::settings::gautron::GautronSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    ddgi: Option<&'a crate::settings::ddgi::DdgiSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    reference: Option<&'a crate::settings::reference::ReferenceSettings>,
    #[serde(skip_serializing_if = "Option::is_none", serialize_with = "group")]
    tonemap: Option<&'a crate::settings::compose::TonemapSettings>,
}

/// A written group as itself (RON would write an `Option` as `Some(..)`).
fn group<S: serde::Serializer, T: Serialize>(v: &Option<&T>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(t) => t.serialize(s),
        None => s.serialize_unit(),
    }
}

impl<'a> WrittenSettings<'a> {
    fn of(s: &'a LabSettings, all: bool) -> Self {
        let p = &s.pipeline;
        let used = |group: &str| all || p.group_in_use(group);
        Self {
            version: s.version,
            animation: used("animation").then_some(&s.animation),
            direct: used("direct").then_some(&s.direct),
            emitters: used("emitters").then_some(&s.emitters),
            sky: used("sky").then_some(&s.sky),
            pipeline: used("pipeline").then_some(&s.pipeline),
            scale: used("scale").then_some(&s.scale),
            vpl: used("vpl").then_some(&s.vpl),
            ism: used("ism").then_some(&s.ism),
            interleave: used("interleave").then_some(&s.interleave),
            temporal: used("temporal").then_some(&s.temporal),
            hcb: used("hcb").then_some(&s.hcb),
            soler: used("soler").then_some(&s.soler),
            gautron: used("gautron").then_some(&s.gautron),
            ddgi: used("ddgi").then_some(&s.ddgi),
            reference: used("reference").then_some(&s.reference),
            tonemap: used("tonemap").then_some(&s.tonemap),
        }
    }
}

/// [`Export`] as written.
#[derive(Serialize)]
struct Written<'a> {
    schema: &'a str,
    schema_version: u32,
    provenance: &'a Provenance,
    settings: WrittenSettings<'a>,
    resolved: &'a [Resolved],
}

impl Export {
    /// The export of `settings` tuned where `provenance` says, with its resolved values.
    pub fn new(settings: LabSettings, provenance: Provenance) -> Self {
        let resolved = resolved::resolve(&settings, &provenance);
        Self {
            schema: SCHEMA_NAME.into(),
            schema_version: SCHEMA_VERSION,
            provenance,
            settings,
            resolved,
            all_groups: false,
        }
    }

    /// The same export writing every settings group (`--all-groups`).
    pub fn with_all_groups(mut self, all: bool) -> Self {
        self.all_groups = all;
        self
    }

    pub fn to_text(&self, format: ExportFormat) -> String {
        let w = Written {
            schema: &self.schema,
            schema_version: self.schema_version,
            provenance: &self.provenance,
            settings: WrittenSettings::of(&self.settings, self.all_groups),
            resolved: &self.resolved,
        };
        match format {
            ExportFormat::Json => {
                serde_json::to_string_pretty(&w).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
            }
            ExportFormat::Ron => {
                let cfg = ron::ser::PrettyConfig::new().struct_names(false);
                ron::ser::to_string_pretty(&w, cfg).unwrap_or_else(|e| format!("// serialisation failed: {e}"))
            }
        }
    }

    /// Parses an export (JSON or RON, told apart by the first non-space character) and
    /// checks its schema and settings. Groups a file leaves out take their defaults.
    pub fn parse(text: &str, origin: &str) -> Result<Self, PresetError> {
        let parse_err = |message: String| PresetError::Parse { path: origin.into(), message };
        let e: Self = if text.trim_start().starts_with('{') {
            serde_json::from_str(text).map_err(|e| parse_err(e.to_string()))?
        } else {
            ron::from_str(text).map_err(|e| parse_err(e.to_string()))?
        };
        if e.schema != SCHEMA_NAME {
            return Err(parse_err(format!("schema '{}' is not '{SCHEMA_NAME}'", e.schema)));
        }
        if e.schema_version > SCHEMA_VERSION {
            return Err(parse_err(format!(
                "schema version {} is newer than this GI Lab understands ({SCHEMA_VERSION})",
                e.schema_version
            )));
        }
        let errors = e.settings.validate();
        if !errors.is_empty() {
            return Err(PresetError::Invalid { path: origin.into(), errors });
        }
        Ok(e)
    }
}

/// The current UTC time as `YYYY-MM-DDTHH:MM:SSZ`.
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    utc_from_unix(secs)
}

/// Unix seconds → ISO 8601 UTC (the civil-from-days conversion of Howard Hinnant's
/// date algorithms).
pub fn utc_from_unix(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z", rem / 3600, rem % 3600 / 60, rem % 60)
}

#[cfg(test)]
mod tests;
