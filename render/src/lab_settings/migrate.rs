//! Version 1's presets read into version 2 (docs/preset-schema.md): the technique and stage
//! switches of version 1 turned into the stage choices of `crate::settings::pipeline`, and a current
//! preset that still names a replaced field refused with the new name.

use crate::lab_settings::LabSettings;
use crate::settings::FieldError;
use crate::settings::pipeline::*;

/// Migrates a version-1 preset read strictly (the `legacy` fields of the groups) to the
/// stage choices of version 2 and clears the old fields.
pub fn migrate_v1(s: &mut LabSettings) {
    let any = s.indirect.is_some()
        || s.ism.visibility.is_some()
        || s.reference.visibility.is_some()
        || s.interleave.filter.is_some()
        || s.temporal.enabled.is_some()
        || s.hcb.cache.is_some();
    if !any {
        // Nothing of version 1 to carry over (a file without `version` may be a version-2
        // snippet): the stage choices stay as read.
        return;
    }
    let v1 = V1Choices {
        technique: s.indirect.take().map_or(LegacyTechnique::None, |i| i.technique),
        ism_visibility: s.ism.visibility.take().unwrap_or_default(),
        reference_visibility: s.reference.visibility.take().unwrap_or(true),
        filter: s.interleave.filter.take().unwrap_or(true),
        temporal: s.temporal.enabled.take().unwrap_or(true),
        cache: s.hcb.cache.take().unwrap_or(false),
    };
    s.pipeline = v1.choices();
}

/// The version-1 fields still set in a version-2 preset (they were replaced by the stage
/// choices: a current preset naming them is refused with the new name).
pub fn legacy_field_errors(s: &LabSettings) -> Vec<FieldError> {
    let set = [
        s.indirect.is_some(),
        s.ism.visibility.is_some(),
        s.reference.visibility.is_some(),
        s.interleave.filter.is_some(),
        s.temporal.enabled.is_some(),
        s.hcb.cache.is_some(),
    ];
    MOVED
        .into_iter()
        .zip(set)
        .filter(|(_, set)| *set)
        .map(|((field, to), _)| FieldError {
            field: field.into(),
            message: format!("replaced by {to} in preset version 2 (set version: 1 to have it migrated)"),
        })
        .collect()
}
