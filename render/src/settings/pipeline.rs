//! The stage choices: one setting per stage of the pipeline table of docs/principles.md
//! (stages 3–7), and the named techniques that are only sets of these choices.
//!
//! A paper is a preset of choices ([`Technique`]); after the technique picker has set them,
//! every stage's choice can be changed on its own, and `lab_settings`'s rules refuse the
//! mixes that cannot work with a message naming the stage and what it needs.
//! `docs/architecture.md` lists every choice with the pass it runs; `frame.rs` runs them.

use crate::{settings_enum, settings_group};

settings_enum! {
    /// Stage 3: where the virtual point lights come from.
    pub enum VplSource {
        /// No VPLs (a gather that needs none, or direct light only).
        None = "none",
        /// Importance-driven VPLs by hierarchical warping of a Halton set over the light
        /// G-buffers of every light view, with multiple bounces (Knecht 002 §3.3, §3.6, §4.4).
        ImportanceWarping = "importance warping (Knecht)",
        /// Uniformly sampled batches from one light view per frame, each VPL's flux divided by
        /// its density (the exact-VPL reference's unbiased VPLs, Knecht 002 §5.2).
        UniformBatches = "uniform reference batches",
    }
    default ImportanceWarping
}

settings_enum! {
    /// Stage 4: how the VPLs' visibility is computed.
    pub enum VplVisibility {
        /// No visibility: every VPL lights everything in front of it.
        None = "none (unshadowed)",
        /// Imperfect shadow maps from the point cloud with pull-push (Knecht §2.6.5).
        Imperfect = "imperfect shadow maps",
        /// Exact cube-face depth maps from the triangles (the baseline and the reference).
        Exact = "exact shadow maps",
    }
    default Imperfect
}

settings_enum! {
    /// Stage 5: where the indirect light is gathered.
    pub enum ShadingPoints {
        /// Every pixel of the G-buffer gathers every VPL.
        EveryPixel = "every pixel",
        /// Interleaved n×n tiles: each pixel gathers one VPL subset in n² (Knecht 002 §3.4.1;
        /// n is `interleave.n`).
        InterleavedTiles = "interleaved tiles (Knecht)",
        /// The samples of the hierarchical coherence buffer (Nguyen et al. 000 §3), a few
        /// percent of the pixels.
        HcbSamples = "HCB samples (Nguyen)",
        /// Every texel of the G-buffer's mip levels, made by voting among sub-pixels (Soler
        /// et al. 004 §4, Eq. 5), from the start resolution down `soler.levels` levels.
        MipLevels = "mip levels (Soler)",
        /// Irradiance records where the splatted coverage is insufficient, made in rounds on
        /// the GPU and kept in a cache (Gautron et al. 003, "Irradiance Caching",
        /// "Algorithm"; settings in `gautron`).
        IrradianceRecords = "irradiance records (Gautron)",
    }
    default InterleavedTiles
}

settings_enum! {
    /// Stage 6: how the shading points gather indirect light.
    pub enum Gather {
        /// No indirect light: the image is the direct light.
        None = "none (direct light only)",
        /// Sum over the VPLs with the chosen visibility (Knecht 002 §4.5, Eq. 4.6–4.7).
        Vpl = "VPL gather",
        /// Screen-space samples on a ring around each texel of each mip level: the visible
        /// surfaces' direct light as small emitters (Soler et al. 004 §3–4, Eq. 1–4).
        ScreenSpace = "screen-space ring gather (Soler)",
        /// Each record's hemisphere rasterized through one wide camera, lit by the direct light
        /// and its shadow maps, reduced to irradiance, gradients and the harmonic mean
        /// distance (Gautron et al. 003, "Simple plane sampling").
        Hemispheres = "hemisphere rasterization (Gautron)",
        /// A grid of probes, each tracing rays through the scene every frame and keeping
        /// octahedral irradiance and distance moments with a hysteresis; every pixel reads its
        /// cell's eight probes weighted by trilinear, backface and Chebyshev visibility weights
        /// (Majercik et al. 2019 §3, 2021 §4–5; settings in `ddgi`). Today's engines' answer,
        /// beside the papers.
        Probes = "DDGI probes (Majercik et al.)",
    }
    default Vpl
}

settings_enum! {
    /// Stage 6: how the gathered light becomes a full image.
    pub enum Reconstruction {
        /// None: the gather's image as it is (every pixel, or the interleaved tiles merged).
        None = "none",
        /// Geometry-aware n×n box filter over the merged tiles (Knecht 002 §3.4.1, Eq. 4.2).
        GeometryAwareFilter = "geometry-aware filter (Knecht)",
        /// Coherence-weighted splatting of the HCB samples and normalisation (Nguyen et al.
        /// §4.2–4.3, Eq. 8–11).
        CoherenceSplatting = "coherence splatting (Nguyen)",
        /// Joint bilateral upsampling of every mip level's light, coarse to fine, added
        /// level by level (Soler et al. 004 §4, "Continuous combination of all levels").
        BilateralUpsampling = "joint bilateral upsampling (Soler)",
        /// Each record's bounding quad splatted with Ward's weight, Σ w·E and Σ w added by the
        /// blending, divided in a resolve (Gautron et al. 003, "From Octree to Splatting").
        WeightSplatting = "Ward-weight splatting (Gautron)",
    }
    default GeometryAwareFilter
}

settings_enum! {
    /// Stage 7: how the indirect light uses earlier frames.
    pub enum Temporal {
        /// None: a new image every frame.
        None = "none",
        /// Reprojection through the movement buffer and the confidence merge (Knecht 002 §3.5,
        /// Eq. 3.1–3.6; settings in `temporal`).
        ConfidenceMerge = "confidence merge (Knecht)",
        /// The HCB's sample cache: valid samples of the last frame are kept, a share is
        /// re-gathered each frame (Nguyen et al. §5; settings in `hcb`).
        HcbSampleCache = "HCB sample cache (Nguyen)",
        /// Running average of the reference's batches until `reference.total_vpls` are in.
        RunningAverage = "running average (reference)",
        /// The previous result warped through the movement buffer, rejected on depth and
        /// normal disagreement, blended by a (Soler et al. 004 §4, Eq. 6; settings
        /// `soler.temporal_*`, `soler.reject_*`): the screen-space gather's filter.
        WarpedBlend = "warped blend (Soler Eq. 6)",
        /// The irradiance records are kept across frames while the scene, its lights and the
        /// record settings stay (Gautron et al. 003, "Results": "the irradiance cache is
        /// reused across frames"); new records only where the coverage is insufficient.
        RecordCache = "irradiance record cache (Gautron)",
    }
    default ConfidenceMerge
}

settings_enum! {
    /// Stage 6, near field: a second gather that takes the light arriving from closer than a
    /// split distance, the VPL gather then taking only what arrives from farther (no light
    /// is counted twice: the two gathers split one integral by the distance to the sender).
    pub enum NearField {
        /// The main gather takes light from every distance.
        None = "none",
        /// Soler et al.'s screen-space gather (004 §3–4, settings in `soler`) within
        /// `soler.near_field_distance`; VPLs beyond it. Screen-space gathering is strongest
        /// where VPLs lose light to their distance clamp (corners, contacts), VPLs see what
        /// the screen does not.
        ScreenSpace = "screen-space (Soler) near, VPLs far",
    }
    default None
}

settings_group! {
    /// The stage choices (the pipeline table of docs/principles.md, stages 3–7): which pass
    /// each stage runs. The technique picker sets them all; each can then be changed on its
    /// own.
    pub struct PipelineSettings: "pipeline" {
        /// Stage 3, VPL source (Knecht 002 §3.3/§4.4 or the reference's uniform batches).
        vpl_source: VplSource = VplSource::ImportanceWarping,
        unit "", symbol "", range 0..=2, cost "importance warping: light G-buffers of every view and a warp per VPL; uniform: one light G-buffer per frame", history true;
        /// Stage 4, VPL visibility (Knecht §2.6.5; exact: the reference's cube-face maps).
        vpl_visibility: VplVisibility = VplVisibility::Imperfect,
        unit "", symbol "V", range 0..=2, cost "ISM: one splat per point; exact: five depth renders of the scene per VPL", history true;
        /// Stage 5, shading points (every pixel; Knecht §3.4.1's tiles; Nguyen §3's samples).
        shading_points: ShadingPoints = ShadingPoints::InterleavedTiles,
        unit "", symbol "", range 0..=4, cost "every pixel: N VPLs per pixel; tiles: N/n²; HCB: N at 2–5 % of the pixels plus the HCB build; records: one hemisphere each", history true;
        /// Stage 6, gather (Knecht §4.5's VPL gather; none: direct light only).
        gather: Gather = Gather::Vpl,
        unit "", symbol "", range 0..=4, cost "one term per VPL and shading point; probes: rays per probe and frame, eight probe reads per pixel", history true;
        /// Stage 6, reconstruction (Knecht §3.4.1's filter; Nguyen §4's splatting).
        reconstruction: Reconstruction = Reconstruction::GeometryAwareFilter,
        unit "", symbol "", range 0..=4, cost "filter: n² reads per pixel; splatting: one quad per sample or record", history true;
        /// Stage 7, temporal (Knecht §3.5's confidence merge; Nguyen §5's sample cache; the
        /// reference's running average).
        temporal: Temporal = Temporal::ConfidenceMerge,
        unit "", symbol "", range 0..=5, cost "merge, warped blend: one pass and two copies; cache: validation and removal quads", history true;
        /// Stage 6, near field: Soler's screen-space gather for the light from closer than
        /// `soler.near_field_distance`, the VPL gather for the rest.
        near_field: NearField = NearField::None,
        unit "", symbol "", range 0..=1, cost "screen-space: the mip levels, one ring gather per level and the upsampling", history true;
    }
}

settings_enum! {
    /// A named set of stage choices: what the technique picker and `gi-lab --technique`
    /// apply. Only the stage choices change; every other setting stays.
    pub enum Technique {
        /// Direct light only.
        DirectOnly = "direct light only",
        /// Instant radiosity with imperfect shadow maps, interleaved sampling and temporal
        /// coherence (Knecht 002).
        Knecht = "instant radiosity (Knecht)",
        /// The hierarchical coherence buffer gathering instant radiosity's VPLs at its
        /// samples (Nguyen et al. §3–4).
        Nguyen = "hierarchical coherence buffer (Nguyen)",
        /// The HCB with its sample cache (Nguyen et al. §5).
        NguyenCached = "HCB with the sample cache (Nguyen §5)",
        /// Many uniformly sampled VPLs with exact visibility, averaged over frames.
        ExactVpl = "exact-VPL reference",
        /// Multi-resolution screen-space indirect illumination (Soler et al. 004): no VPLs,
        /// the mip levels gather the visible direct light.
        Soler = "screen-space mip levels (Soler)",
        /// Soler's screen-space gather for the near field, Knecht's instant radiosity for the
        /// far field (`pipeline.near_field`; split at `soler.near_field_distance`).
        SolerNearKnechtFar = "near field Soler, far field Knecht",
        /// Soler's screen-space gather evaluated at the HCB's samples and spread by coherence
        /// splatting (GI Lab's mix of Nguyen et al. and Soler et al.).
        SolerAtHcbSamples = "screen-space gather at HCB samples (Nguyen + Soler)",
        /// Irradiance cache splatting (Gautron et al. 003): records made where the coverage
        /// is insufficient, their hemispheres rasterized, Ward's weights splatted, the records
        /// kept across frames.
        Gautron = "irradiance cache splatting (Gautron)",
        /// Gautron's irradiance records and splatting, the records lit by Knecht's VPLs
        /// (instant radiosity at the records) instead of their hemispheres (GI Lab's mix).
        GautronVplRecords = "irradiance records lit by VPLs (Gautron + Knecht)",
        /// Gautron's hemispheres computed at the HCB's samples and spread by coherence
        /// splatting (GI Lab's mix of Nguyen et al. and Gautron et al.); the HCB's sample
        /// cache keeps the samples and their hemispheres' light across frames (Nguyen §5).
        GautronAtHcbSamples = "hemispheres at HCB samples (Nguyen + Gautron)",
        /// Dynamic diffuse global illumination (Majercik et al. 2019, 2021): ray-traced
        /// probes with octahedral irradiance and visibility, read at every pixel.
        Ddgi = "DDGI probes (Majercik et al.)",
    }
    default DirectOnly
}

impl Technique {
    pub const ALL: [Technique; 12] = [
        Self::DirectOnly,
        Self::Knecht,
        Self::Nguyen,
        Self::NguyenCached,
        Self::ExactVpl,
        Self::Soler,
        Self::SolerNearKnechtFar,
        Self::SolerAtHcbSamples,
        Self::Gautron,
        Self::GautronVplRecords,
        Self::GautronAtHcbSamples,
        Self::Ddgi,
    ];

    /// The technique's stage choices. `base` gives the choices the technique leaves open
    /// (the visibility of instant radiosity and the HCB, direct light's unused stages).
    pub fn choices(self, base: &PipelineSettings) -> PipelineSettings {
        let ir = |points, reconstruction, temporal| PipelineSettings {
            vpl_source: VplSource::ImportanceWarping,
            vpl_visibility: match base.vpl_source {
                VplSource::ImportanceWarping => base.vpl_visibility,
                _ => VplVisibility::Imperfect,
            },
            shading_points: points,
            gather: Gather::Vpl,
            reconstruction,
            temporal,
            near_field: NearField::None,
        };
        match self {
            Self::DirectOnly => PipelineSettings { gather: Gather::None, ..base.clone() },
            Self::Knecht => PipelineSettings {
                vpl_visibility: VplVisibility::Imperfect,
                ..ir(ShadingPoints::InterleavedTiles, Reconstruction::GeometryAwareFilter, Temporal::ConfidenceMerge)
            },
            Self::Nguyen => ir(ShadingPoints::HcbSamples, Reconstruction::CoherenceSplatting, Temporal::None),
            Self::NguyenCached => {
                ir(ShadingPoints::HcbSamples, Reconstruction::CoherenceSplatting, Temporal::HcbSampleCache)
            }
            Self::ExactVpl => PipelineSettings {
                vpl_source: VplSource::UniformBatches,
                vpl_visibility: VplVisibility::Exact,
                shading_points: ShadingPoints::EveryPixel,
                gather: Gather::Vpl,
                reconstruction: Reconstruction::None,
                temporal: Temporal::RunningAverage,
                near_field: NearField::None,
            },
            Self::Soler => PipelineSettings {
                vpl_source: VplSource::None,
                vpl_visibility: VplVisibility::None,
                shading_points: ShadingPoints::MipLevels,
                gather: Gather::ScreenSpace,
                reconstruction: Reconstruction::BilateralUpsampling,
                temporal: Temporal::WarpedBlend,
                near_field: NearField::None,
            },
            Self::SolerNearKnechtFar => {
                PipelineSettings { near_field: NearField::ScreenSpace, ..Self::Knecht.choices(base) }
            }
            Self::SolerAtHcbSamples => PipelineSettings {
                shading_points: ShadingPoints::HcbSamples,
                reconstruction: Reconstruction::CoherenceSplatting,
                temporal: Temporal::None,
                ..Self::Soler.choices(base)
            },
            Self::Gautron => PipelineSettings {
                vpl_source: VplSource::None,
                vpl_visibility: VplVisibility::None,
                shading_points: ShadingPoints::IrradianceRecords,
                gather: Gather::Hemispheres,
                reconstruction: Reconstruction::WeightSplatting,
                temporal: Temporal::RecordCache,
                near_field: NearField::None,
            },
            Self::GautronVplRecords => {
                ir(ShadingPoints::IrradianceRecords, Reconstruction::WeightSplatting, Temporal::RecordCache)
            }
            Self::GautronAtHcbSamples => PipelineSettings {
                shading_points: ShadingPoints::HcbSamples,
                reconstruction: Reconstruction::CoherenceSplatting,
                temporal: Temporal::HcbSampleCache,
                ..Self::Gautron.choices(base)
            },
            Self::Ddgi => PipelineSettings {
                vpl_source: VplSource::None,
                vpl_visibility: VplVisibility::None,
                shading_points: ShadingPoints::EveryPixel,
                gather: Gather::Probes,
                reconstruction: Reconstruction::None,
                temporal: Temporal::None,
                near_field: NearField::None,
            },
        }
    }

    /// The technique a version-1 `indirect.technique` name selected (`--set` of old scripts).
    pub fn from_v1_name(name: &str) -> Option<Technique> {
        Some(match name {
            "None" => Self::DirectOnly,
            "ExactVpl" => Self::ExactVpl,
            "InstantRadiosity" => Self::Knecht,
            "Hcb" => Self::Nguyen,
            _ => return None,
        })
    }

    /// The technique in words (as the picker shows it).
    pub fn label(self) -> &'static str {
        Self::LABELS[Self::ALL.iter().position(|x| *x == self).unwrap_or(0)]
    }

    /// The technique whose choices `p` are, if any (a mix of stages is none of them).
    pub fn of(p: &PipelineSettings) -> Option<Technique> {
        if p.gather == Gather::None {
            return Some(Self::DirectOnly);
        }
        Self::ALL.into_iter().skip(1).find(|t| t.choices(p) == *p)
    }
}

impl PipelineSettings {
    /// Whether stage 3 runs (a gather consumes VPLs).
    pub fn uses_vpls(&self) -> bool {
        self.gather == Gather::Vpl && self.vpl_source != VplSource::None
    }

    /// Whether Soler et al.'s passes run: as the gather, or as the near field of a VPL gather.
    pub fn uses_soler(&self) -> bool {
        self.gather == Gather::ScreenSpace || (self.uses_vpls() && self.near_field == NearField::ScreenSpace)
    }

    /// Whether Eq. 6's warped blend filters Soler's light: stage 7's choice with the
    /// screen-space gather; as a near field, whenever stage 7 filters the far field (the
    /// near field's own filter, since the far field's choice acts on the VPL gather).
    pub fn soler_temporal(&self) -> bool {
        match self.gather {
            Gather::ScreenSpace => self.temporal == Temporal::WarpedBlend,
            _ => self.uses_soler() && self.temporal != Temporal::None,
        }
    }

    /// Whether Gautron et al.'s passes run: the hemisphere gather (at irradiance records or,
    /// GI Lab's mix, at the HCB's samples), or irradiance records lit by the VPL gather.
    pub fn uses_gautron(&self) -> bool {
        self.gather == Gather::Hemispheres
            || (self.gather == Gather::Vpl && self.shading_points == ShadingPoints::IrradianceRecords)
    }

    /// Whether DDGI's probes are the indirect light (Majercik et al.).
    pub fn uses_ddgi(&self) -> bool {
        self.gather == Gather::Probes
    }

    /// Whether instant radiosity's VPLs (stages 3–4 of Knecht) are in use.
    pub fn uses_knecht_vpls(&self) -> bool {
        self.gather == Gather::Vpl && self.vpl_source == VplSource::ImportanceWarping
    }

    /// Whether the exact-VPL reference is the indirect light.
    pub fn is_reference(&self) -> bool {
        self.gather == Gather::Vpl && self.vpl_source == VplSource::UniformBatches
    }

    /// Whether the HCB's passes run (its samples are the shading points).
    pub fn uses_hcb(&self) -> bool {
        (self.uses_knecht_vpls() || matches!(self.gather, Gather::ScreenSpace | Gather::Hemispheres))
            && self.shading_points == ShadingPoints::HcbSamples
    }

    /// Whether the settings group `group` acts on the image with these choices (the panel
    /// folds the others under "not in use").
    pub fn group_in_use(&self, group: &str) -> bool {
        let knecht = self.uses_knecht_vpls();
        match group {
            "vpl" => knecht,
            "ism" => knecht && (self.vpl_visibility != VplVisibility::None),
            "interleave" => {
                knecht
                    && (self.shading_points == ShadingPoints::InterleavedTiles
                        || self.reconstruction == Reconstruction::GeometryAwareFilter)
            }
            "temporal" => knecht && self.temporal == Temporal::ConfidenceMerge,
            "hcb" => self.uses_hcb(),
            "reference" => self.is_reference(),
            "soler" => self.uses_soler(),
            "gautron" => self.uses_gautron(),
            "ddgi" => self.uses_ddgi(),
            _ => true,
        }
    }
}

/// The settings of version-1 presets that the stage choices replaced; read on load only
/// (`settings_group!`'s `legacy` fields) and turned into choices by `lab_settings`'s migration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum LegacyTechnique {
    None,
    ExactVpl,
    InstantRadiosity,
    Hcb,
}

/// Version 1's `indirect` group.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LegacyIndirect {
    pub technique: LegacyTechnique,
}

/// Version 1's technique and stage switches as they were set (absent fields at their
/// version-1 defaults).
pub struct V1Choices {
    pub technique: LegacyTechnique,
    pub ism_visibility: VplVisibility,
    pub reference_visibility: bool,
    pub filter: bool,
    pub temporal: bool,
    pub cache: bool,
}

impl V1Choices {
    /// The stage choices of version 2 that render what version 1 rendered.
    pub fn choices(&self) -> PipelineSettings {
        let reconstruction = if self.filter { Reconstruction::GeometryAwareFilter } else { Reconstruction::None };
        let temporal = if self.temporal { Temporal::ConfidenceMerge } else { Temporal::None };
        let ir = PipelineSettings {
            vpl_source: VplSource::ImportanceWarping,
            vpl_visibility: self.ism_visibility,
            shading_points: ShadingPoints::InterleavedTiles,
            gather: Gather::Vpl,
            reconstruction,
            temporal,
            near_field: NearField::None,
        };
        match self.technique {
            LegacyTechnique::None => PipelineSettings { gather: Gather::None, ..ir },
            LegacyTechnique::InstantRadiosity => ir,
            LegacyTechnique::Hcb => PipelineSettings {
                shading_points: ShadingPoints::HcbSamples,
                reconstruction: Reconstruction::CoherenceSplatting,
                temporal: if self.cache { Temporal::HcbSampleCache } else { Temporal::None },
                ..ir
            },
            LegacyTechnique::ExactVpl => PipelineSettings {
                vpl_visibility: if self.reference_visibility { VplVisibility::Exact } else { VplVisibility::None },
                ..Technique::ExactVpl.choices(&ir)
            },
        }
    }
}

/// Migrates a version-1 preset read leniently (`preset::load_lenient`, identifiers quoted as
/// names): the old fields are removed and a `pipeline` group of the same choices is added
/// (returns the old values it could not read, as (field, problem)).
pub fn migrate_v1_map(top: &mut ron::Map) -> Vec<(String, String)> {
    use crate::settings::SettingType;
    use ron::Value;
    fn take(top: &mut ron::Map, group: &str, field: &str) -> Option<Value> {
        match top.get_mut(&Value::String(group.into()))? {
            Value::Map(m) => m.remove(&Value::String(field.into())),
            _ => None,
        }
    }
    let flag = |v: Option<Value>, default: bool| match v {
        Some(Value::Bool(b)) => b,
        _ => default,
    };
    let mut problems = Vec::new();
    let legacy = [
        ("indirect", "technique"),
        ("ism", "visibility"),
        ("reference", "visibility"),
        ("interleave", "filter"),
        ("temporal", "enabled"),
        ("hcb", "cache"),
    ];
    let any = legacy.iter().any(|(g, f)| match top.get(&Value::String((*g).into())) {
        Some(Value::Map(m)) => m.get(&Value::String((*f).into())).is_some(),
        _ => false,
    });
    if !any {
        return problems;
    }
    let technique = match take(top, "indirect", "technique") {
        Some(Value::String(t)) => match t.as_str() {
            "None" => LegacyTechnique::None,
            "ExactVpl" => LegacyTechnique::ExactVpl,
            "InstantRadiosity" => LegacyTechnique::InstantRadiosity,
            "Hcb" => LegacyTechnique::Hcb,
            other => {
                problems.push((
                    "indirect.technique".to_string(),
                    format!("'{other}' is not one of None, ExactVpl, InstantRadiosity, Hcb; read as None"),
                ));
                LegacyTechnique::None
            }
        },
        // `None` is RON's empty option, not a quoted name.
        None | Some(Value::Option(None)) | Some(Value::Unit) => LegacyTechnique::None,
        Some(_) => {
            problems.push(("indirect.technique".to_string(), "expected a technique name; read as None".to_string()));
            LegacyTechnique::None
        }
    };
    if matches!(top.get(&Value::String("indirect".into())), Some(Value::Map(m)) if m.is_empty()) {
        top.remove(&Value::String("indirect".into()));
    }
    let ism_visibility = match take(top, "ism", "visibility") {
        Some(Value::Option(None)) | Some(Value::Unit) => VplVisibility::None,
        Some(Value::String(v)) => VplVisibility::NAMES
            .iter()
            .position(|n| *n == v)
            .and_then(|i| VplVisibility::from_value(&crate::settings::Value::Choice(VplVisibility::NAMES[i])))
            .unwrap_or_default(),
        _ => VplVisibility::default(),
    };
    let v1 = V1Choices {
        technique,
        ism_visibility,
        reference_visibility: flag(take(top, "reference", "visibility"), true),
        filter: flag(take(top, "interleave", "filter"), true),
        temporal: flag(take(top, "temporal", "enabled"), true),
        cache: flag(take(top, "hcb", "cache"), false),
    };
    let p = v1.choices();
    let mut pipeline = ron::Map::new();
    for m in <PipelineSettings as crate::settings::SettingsGroup>::fields() {
        if let Some(v) = crate::settings::SettingsGroup::get(&p, m.name) {
            pipeline.insert(Value::String(m.name.into()), Value::String(v.to_string()));
        }
    }
    top.insert(Value::String("pipeline".into()), Value::Map(pipeline));
    problems
}

/// Version 1's settings that the stage choices replaced, with what replaced them.
pub(crate) const MOVED: [(&str, &str); 6] = [
    ("indirect.technique", "the pipeline.* stage choices (a technique sets them all)"),
    ("ism.visibility", "pipeline.vpl_visibility"),
    ("reference.visibility", "pipeline.vpl_visibility"),
    ("interleave.filter", "pipeline.reconstruction"),
    ("temporal.enabled", "pipeline.temporal"),
    ("hcb.cache", "pipeline.temporal = HcbSampleCache"),
];

/// What replaced a version-1 setting (for `--set` and sweeps written before version 2).
pub fn moved_setting(path: &str) -> Option<&'static str> {
    MOVED.iter().find(|(p, _)| *p == path).map(|(_, to)| *to)
}
