//! Which stage choices work together (`combination_errors`, called by
//! `LabSettings::validate`): the rules of docs/architecture.md's "What works with what".

use super::LabSettings;
use crate::settings::FieldError;
use crate::settings::pipeline::{Gather, NearField, Reconstruction, ShadingPoints, Temporal, VplSource, VplVisibility};

/// The stage choices that cannot work together, each with the stage that needs what
/// (docs/principles.md, the pipeline table: refused with a reason, never by a crash or a
/// black image).
pub fn combination_errors(s: &LabSettings) -> Vec<FieldError> {
    let p = &s.pipeline;
    let mut errors = Vec::new();
    let mut err =
        |field: &str, message: String| errors.push(FieldError { field: format!("pipeline.{field}"), message });
    if p.gather == Gather::None {
        return errors;
    }
    if p.gather == Gather::Probes {
        // DDGI: the probes hold the light over time (the hysteresis) and every pixel reads
        // them; no VPLs, no other shading points, reconstruction or history.
        if p.shading_points != ShadingPoints::EveryPixel {
            err(
                "shading_points",
                "DDGI's probes are read at every pixel: set pipeline.shading_points = EveryPixel".into(),
            );
        }
        if p.reconstruction != Reconstruction::None {
            err(
                "reconstruction",
                "every pixel reads DDGI's probes and needs no reconstruction: set pipeline.reconstruction = None"
                    .into(),
            );
        }
        if p.temporal != Temporal::None {
            err(
                "temporal",
                "DDGI's probes keep their own history (the hysteresis ddgi.hysteresis): set pipeline.temporal = None"
                    .into(),
            );
        }
        if p.near_field != NearField::None {
            err("near_field", "DDGI's probes already take the light from every distance; a near field splits a VPL gather: set pipeline.near_field = None".into());
        }
        return errors;
    }
    if p.gather == Gather::Hemispheres {
        // Gautron et al.'s records: their own shading points, splatting and cache; no VPLs.
        // GI Lab's mix with Nguyen et al.: the hemispheres at the HCB's samples, splatted by
        // coherence.
        if p.shading_points == ShadingPoints::HcbSamples {
            if p.reconstruction != Reconstruction::CoherenceSplatting {
                err("reconstruction", "hemispheres at HCB samples are spread by coherence splatting: set pipeline.reconstruction = CoherenceSplatting".into());
            }
            if !matches!(p.temporal, Temporal::None | Temporal::HcbSampleCache) {
                err("temporal", "hemispheres at HCB samples are computed every frame (None) or kept with their samples by the HCB sample cache (HcbSampleCache); the record cache keeps Gautron's own records".into());
            }
        } else {
            if p.shading_points != ShadingPoints::IrradianceRecords {
                err(
                    "shading_points",
                    "the hemisphere gather computes irradiance records (IrradianceRecords) or the HCB's samples (HcbSamples)".into(),
                );
            }
            if p.reconstruction != Reconstruction::WeightSplatting {
                err("reconstruction", "irradiance records are interpolated by splatting Ward's weights: set pipeline.reconstruction = WeightSplatting".into());
            }
            if !matches!(p.temporal, Temporal::None | Temporal::RecordCache) {
                err(
                    "temporal",
                    "irradiance records are kept by the record cache (RecordCache) or made anew every frame (None)"
                        .into(),
                );
            }
        }
        if p.near_field != NearField::None {
            err("near_field", "the hemispheres already take the light from every distance; a near field splits a VPL gather: set pipeline.near_field = None".into());
        }
        return errors;
    }
    let records = p.shading_points == ShadingPoints::IrradianceRecords;
    if !records && (p.reconstruction == Reconstruction::WeightSplatting || p.temporal == Temporal::RecordCache) {
        err("shading_points", "Ward-weight splatting and the record cache act on irradiance records: set pipeline.shading_points = IrradianceRecords".into());
    }
    if records && p.gather != Gather::Vpl {
        err("gather", "irradiance records are lit by their hemispheres (Hemispheres) or by the VPLs (Vpl)".into());
    }
    if records && p.gather == Gather::Vpl {
        // GI Lab's mix with Knecht: the records lit by the VPL gather.
        if p.reconstruction != Reconstruction::WeightSplatting {
            err("reconstruction", "irradiance records are interpolated by splatting Ward's weights: set pipeline.reconstruction = WeightSplatting".into());
        }
        if !matches!(p.temporal, Temporal::None | Temporal::RecordCache) {
            err(
                "temporal",
                "irradiance records are kept by the record cache (RecordCache) or made anew every frame (None)".into(),
            );
        }
        if p.vpl_source != VplSource::ImportanceWarping {
            err("vpl_source", "irradiance records are lit by instant radiosity's VPLs: set pipeline.vpl_source = ImportanceWarping (the reference's batches are averaged at every pixel)".into());
        }
        return errors;
    }
    if p.gather == Gather::ScreenSpace {
        // Soler et al.'s gather runs on the mip levels and is combined by the upsampling, or
        // (GI Lab's mix with Nguyen et al.) at the HCB's samples, splatted by coherence; it
        // reads the direct light, not VPLs (stages 3–4 are idle).
        if p.shading_points == ShadingPoints::HcbSamples {
            if p.reconstruction != Reconstruction::CoherenceSplatting {
                err("reconstruction", "the screen-space gather at HCB samples is spread by coherence splatting: set pipeline.reconstruction = CoherenceSplatting".into());
            }
            if p.temporal != Temporal::None {
                err("temporal", "the screen-space gather at HCB samples has no temporal choice yet (the sample cache re-gathers with VPLs, Eq. 6 filters the per-pixel gather): set pipeline.temporal = None".into());
            }
            if s.soler.bounces > 1 {
                err("gather", "the screen-space gather at HCB samples gathers one bounce (a second bounce needs the first one at every pixel): set soler.bounces = 1".into());
            }
        } else {
            if p.shading_points != ShadingPoints::MipLevels {
                err("shading_points", "the screen-space gather samples rings on the mip levels (MipLevels) or at the HCB's samples (HcbSamples)".into());
            }
            if p.reconstruction != Reconstruction::BilateralUpsampling {
                err("reconstruction", "the screen-space gather's levels are combined by joint bilateral upsampling: set pipeline.reconstruction = BilateralUpsampling".into());
            }
            if !matches!(p.temporal, Temporal::None | Temporal::WarpedBlend) {
                err("temporal", "the screen-space gather is filtered by Eq. 6's warped blend (WarpedBlend) or not at all (None); the other temporal choices belong to VPL gathers".into());
            }
        }
        if p.near_field != NearField::None {
            err("near_field", "the screen-space gather already takes the light from every distance; a near field splits a VPL gather: set pipeline.near_field = None or pipeline.gather = Vpl".into());
        }
        return errors;
    }
    if p.shading_points == ShadingPoints::MipLevels {
        err(
            "shading_points",
            "mip levels are gathered by the screen-space gather: set pipeline.gather = ScreenSpace".into(),
        );
    }
    if p.reconstruction == Reconstruction::BilateralUpsampling {
        err("reconstruction", "joint bilateral upsampling combines the screen-space gather's mip levels: set pipeline.gather = ScreenSpace".into());
    }
    if p.vpl_source == VplSource::None {
        err(
            "gather",
            "the VPL gather needs VPLs: set pipeline.vpl_source to ImportanceWarping or UniformBatches".into(),
        );
        return errors;
    }
    if p.vpl_source == VplSource::UniformBatches {
        // The reference's gather folds each batch into its running average at every pixel
        // (`passes::reference::gather`): its other stages are fixed.
        if p.vpl_visibility == VplVisibility::Imperfect {
            err("vpl_visibility", "the reference's uniform batches have exact visibility or none, not imperfect shadow maps (no point cloud is splatted for them)".into());
        }
        if p.shading_points != ShadingPoints::EveryPixel {
            err(
                "shading_points",
                "the reference's uniform batches are gathered at every pixel: set pipeline.shading_points = EveryPixel"
                    .into(),
            );
        }
        if p.reconstruction != Reconstruction::None {
            err(
                "reconstruction",
                "the reference gathers every pixel and needs no reconstruction: set pipeline.reconstruction = None"
                    .into(),
            );
        }
        if p.temporal != Temporal::RunningAverage {
            err(
                "temporal",
                "the reference's batches are averaged over frames: set pipeline.temporal = RunningAverage".into(),
            );
        }
        return errors;
    }
    // Importance-warped VPLs (Knecht).
    if p.temporal == Temporal::RunningAverage {
        err("temporal", "the running average accumulates the reference's uniform batches (pipeline.vpl_source = UniformBatches); with importance-warped VPLs use None, ConfidenceMerge or (with HCB samples) HcbSampleCache".into());
    }
    if p.temporal == Temporal::WarpedBlend {
        err("temporal", "Eq. 6's warped blend filters the screen-space gather (pipeline.gather = ScreenSpace); a VPL gather's near field gets it whenever stage 7 filters the far field: use None or ConfidenceMerge here".into());
    }
    match p.shading_points {
        ShadingPoints::HcbSamples => {
            if p.reconstruction != Reconstruction::CoherenceSplatting {
                err("reconstruction", "HCB samples cover a few percent of the pixels: only coherence splatting (CoherenceSplatting) fills the image from them".into());
            }
        }
        ShadingPoints::EveryPixel
        | ShadingPoints::InterleavedTiles
        | ShadingPoints::MipLevels
        | ShadingPoints::IrradianceRecords => {
            if p.reconstruction == Reconstruction::CoherenceSplatting {
                err(
                    "reconstruction",
                    "coherence splatting spreads HCB samples: it needs pipeline.shading_points = HcbSamples".into(),
                );
            }
            if p.temporal == Temporal::HcbSampleCache {
                err(
                    "temporal",
                    "the HCB sample cache keeps HCB samples: it needs pipeline.shading_points = HcbSamples".into(),
                );
            }
        }
    }
    if p.shading_points == ShadingPoints::EveryPixel && p.reconstruction == Reconstruction::GeometryAwareFilter {
        err("reconstruction", "the geometry-aware filter removes the interleaved tiles' pattern; every pixel has none: use pipeline.reconstruction = None or InterleavedTiles".into());
    }
    if p.shading_points == ShadingPoints::InterleavedTiles {
        let n = s.interleave.n;
        if s.vpl.count < n * n {
            errors.push(FieldError {
                field: "vpl.count".into(),
                message: format!(
                    "{} VPLs cannot cover {n}×{n} interleaved tiles (each tile needs at least one VPL): use at least {} VPLs or interleave.n ≤ {}",
                    s.vpl.count,
                    n * n,
                    (s.vpl.count as f64).sqrt().floor() as u32
                ),
            });
        }
    }
    // Every ISM needs points, whoever gathers (the HCB with imperfect maps too).
    if p.vpl_visibility == VplVisibility::Imperfect && s.ism.points < s.vpl.count {
        errors.push(FieldError {
            field: "ism.points".into(),
            message: format!(
                "{} points cannot give each of {} ISMs a point: use at least as many points as VPLs",
                s.ism.points, s.vpl.count
            ),
        });
    }
    errors
}
