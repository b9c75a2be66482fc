//! Animations (§3.11): node translation, rotation and scale channels.

use glam::{Quat, Vec3};
use json::accessor::Type as AccessorType;
use json::validation::Checked;

use super::{Loader, SceneError, json};
use crate::scene::{Animation, Channel, ChannelTarget, Interpolation};

impl Loader<'_> {
    // -----------------------------------------------------------------------------------
    // Animations (§3.11)
    // -----------------------------------------------------------------------------------

    /// Loads translation, rotation and scale channels; morph target weights are ignored with
    /// a warning. Key times must be finite and non-decreasing, and the output count must be
    /// the key count (STEP, LINEAR) or three times it (CUBICSPLINE: in-tangent, value, out-tangent).
    pub(super) fn load_animations(&mut self) -> Result<(), SceneError> {
        use json::animation::{Interpolation as JInterp, Property};
        let (root, file) = (self.root, self.file);
        for (ai, a) in root.animations.iter().enumerate() {
            let name = a.name.clone().unwrap_or_else(|| format!("animation {ai}"));
            let bad =
                |reason: String| SceneError::BadAnimation { file: file.to_string(), animation: name.clone(), reason };
            let mut channels = Vec::new();
            for (ci, ch) in a.channels.iter().enumerate() {
                let s = ch.sampler.value();
                let sampler = a
                    .samplers
                    .get(s)
                    .ok_or_else(|| bad(format!("channel {ci} refers to sampler {s}, which does not exist")))?;
                let node = ch.target.node.value();
                if node >= root.nodes.len() {
                    return Err(bad(format!("channel {ci} targets node {node}, which does not exist")));
                }
                let path = match ch.target.path {
                    Checked::Valid(Property::MorphTargetWeights) => {
                        self.warn("morph target weight animations are not supported and are ignored".to_string());
                        continue;
                    }
                    Checked::Valid(p) => p,
                    Checked::Invalid => return Err(bad(format!("channel {ci} animates an unknown property"))),
                };
                let interpolation = match sampler.interpolation {
                    Checked::Valid(JInterp::Linear) => Interpolation::Linear,
                    Checked::Valid(JInterp::Step) => Interpolation::Step,
                    Checked::Valid(JInterp::CubicSpline) => Interpolation::CubicSpline,
                    Checked::Invalid => return Err(bad(format!("sampler {s} has an unknown interpolation"))),
                };
                let times = self.read_floats(
                    sampler.input.value(),
                    &format!("key times of animation '{name}' channel {ci}"),
                    &[AccessorType::Scalar],
                )?;
                if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| matches!(w, [a, b] if b < a)) {
                    return Err(bad(format!("channel {ci} has key times that are not finite and increasing")));
                }
                if times.is_empty() {
                    self.warn(format!("animation '{name}' channel {ci} has no keys and is ignored"));
                    continue;
                }
                let ty = if path == Property::Rotation { AccessorType::Vec4 } else { AccessorType::Vec3 };
                let out = self.read_floats(
                    sampler.output.value(),
                    &format!("values of animation '{name}' channel {ci}"),
                    &[ty],
                )?;
                let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
                let values = out.len() / ty.multiplicity();
                if values != times.len() * per_key {
                    return Err(bad(format!(
                        "channel {ci} has {} key times but {values} output values; {interpolation:?} interpolation needs {}",
                        times.len(),
                        times.len() * per_key
                    )));
                }
                let target = match path {
                    Property::Rotation => {
                        let (quads, _) = out.as_chunks::<4>();
                        ChannelTarget::Rotation(
                            quads
                                .iter()
                                .map(|&q| {
                                    let q = Quat::from_array(q);
                                    // Cubic-spline tangents are not unit quaternions; values and
                                    // linear/step keys are renormalised.
                                    if interpolation == Interpolation::CubicSpline || q.length_squared() == 0.0 {
                                        q
                                    } else {
                                        q.normalize()
                                    }
                                })
                                .collect(),
                        )
                    }
                    _ => {
                        let (triples, _) = out.as_chunks::<3>();
                        let v = triples.iter().map(|&t| Vec3::from_array(t)).collect();
                        if path == Property::Translation {
                            ChannelTarget::Translation(v)
                        } else {
                            ChannelTarget::Scale(v)
                        }
                    }
                };
                channels.push(Channel { node, interpolation, times, target });
            }
            if !channels.is_empty() {
                self.scene.animations.push(Animation { name, channels });
            }
        }
        Ok(())
    }
}
