//! The ring samples one pixel's indirect light comes from (Soler et al. 004 Fig. 3 right:
//! "position of all samples that eventually participate to the indirect light of the
//! central pixel after upsampling and adding mipmap levels"), for the lab's View overlay.
//!
//! For each gathered level k of the last frame's first bounce, the receiver is the level's
//! texel under the pixel; its samples are those the GPU drew (`cpu::soler::receiver_samples`
//! on the receiver's position, normal and material read back from the level, the frame's
//! rotation and the glossy importance sampling), each marked by whether it can light the
//! receiver (`cpu::soler::facing`: on a surface, both cosines positive, inside the near
//! field's cut). The march of the voxel visibility is not replayed.

use glam::{Vec2, Vec3};

use super::Renderer;
use crate::cpu::soler::{self, GatherParams, ScreenCamera, Texel};

/// One ring sample, in G-buffer pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolerSample {
    pub level: u32,
    /// Centre of the sample's texel, in G-buffer pixels.
    pub pixel: Vec2,
    /// On a surface that can light the receiver (before visibility).
    pub lit: bool,
}

/// One level's receiver texel and its samples.
#[derive(Clone, Debug, PartialEq)]
pub struct SolerReceiver {
    pub level: u32,
    /// The receiver texel's footprint in G-buffer pixels (min, max).
    pub footprint: (Vec2, Vec2),
    /// Whether it was importance sampled for its glossy lobe.
    pub glossy: bool,
    pub samples: Vec<SolerSample>,
}

/// Reads texels (name, x, y) for stage 0 (receivers) or 1 (samples); Ok(None): not there yet.
type TexelReader<'a> = dyn FnMut(&[(&str, u32, u32)], usize) -> Result<Option<Vec<[f32; 4]>>, String> + 'a;

impl Renderer {
    /// The ring samples behind G-buffer pixel `pixel` at each gathered level of the last
    /// rendered frame (Fig. 3 right); an error when no screen-space gather runs or nothing has
    /// been rendered. Levels whose receiver texel is background are left out.
    pub fn soler_samples(&self, pixel: (u32, u32)) -> Result<Vec<SolerReceiver>, String> {
        let frame = self.clock.frame.saturating_sub(1);
        let mut read = |points: &[(&str, u32, u32)], _: usize| {
            self.registry.read_texels(&self.ctx, points).map(Some).map_err(|e| e.to_string())
        };
        self.soler_samples_with(pixel, frame, &mut read).map(|r| r.unwrap_or_default())
    }

    /// [`Self::soler_samples`] without waiting (the window's overlay). Its two reads (the
    /// receivers, then the samples their rotation picks) are copied in later frames and taken
    /// in as they arrive: the receivers' read is kept until the samples' read of the same
    /// frame has come (the rings rotate every frame), then the answer is kept and the next
    /// cycle starts. Until the first answer for `pixel`, Ok(None).
    pub fn soler_samples_later(&self, pixel: (u32, u32)) -> Result<Option<Vec<SolerReceiver>>, String> {
        use crate::readback::{Readback, Readout};
        let tag = |points: &[(&str, u32, u32)]| {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            points.hash(&mut h);
            h.finish()
        };
        let mut read = |points: &[(&str, u32, u32)], stage: usize| -> Result<Option<Vec<[f32; 4]>>, String> {
            let key = format!("soler.samples.{stage}");
            let what = || Readback::Texels(points.iter().map(|&(n, x, y)| (n.to_string(), x, y)).collect());
            // The receivers: the arrived read while it is of these points, else ask again.
            let got = match self.read_latest(&key) {
                Some(a) if stage == 0 && a.tag == tag(points) => Some(a),
                _ => self.read_later(&key, what(), tag(points)),
            };
            match got.filter(|a| a.tag == tag(points)).as_deref().map(|a| &a.data) {
                Some(Ok(Readout::Texels(v))) => Ok(Some(v.clone())),
                Some(Err(e)) => Err(e.clone()),
                _ => Ok(None),
            }
        };
        let frame = self.read_latest("soler.samples.0").map_or(self.clock.frame, |a| a.frame);
        let done = self.soler_samples_with(pixel, frame, &mut read)?;
        let mut last = self.soler_overlay.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(r) = done {
            // This cycle is complete: keep its answer, and start the next with fresh receivers.
            *last = Some((pixel, r));
            self.read_forget("soler.samples.0");
        }
        Ok(last.as_ref().filter(|(p, _)| *p == pixel).map(|(_, r)| r.clone()))
    }

    /// The samples behind `pixel` as rendered in `frame`, reading texels with `read` (its
    /// second argument: 0 for the receivers, 1 for their samples; Ok(None): not yet there).
    fn soler_samples_with(
        &self,
        pixel: (u32, u32),
        frame: u64,
        read: &mut TexelReader<'_>,
    ) -> Result<Option<Vec<SolerReceiver>>, String> {
        let s = &self.settings.soler;
        let p = &self.settings.pipeline;
        if !p.uses_soler() || self.stages.soler.is_none() {
            return Err("pick Soler's screen-space gather (or its near field) to see its samples".into());
        }
        if self.clock.frame == 0 {
            return Err("no frame rendered yet".into());
        }
        let frame = frame as u32;
        let (w, h) = self.size();
        let levels: Vec<u32> = s.gathered_levels().collect();
        let size_of = |k: u32| -> (u32, u32) {
            let (mut lw, mut lh) = (w.max(1), h.max(1));
            for _ in 0..k {
                (lw, lh) = (lw.div_ceil(2), lh.div_ceil(2));
            }
            (lw, lh)
        };
        let names = |k: u32| -> [String; 3] {
            if k == 0 {
                ["gbuffer.position".into(), "gbuffer.normal".into(), "gbuffer.material".into()]
            } else {
                ["position", "normal", "material"].map(|n| format!("soler.level.{k}.{n}"))
            }
        };
        let texel_of = |k: u32| {
            let (lw, lh) = size_of(k);
            ((pixel.0 >> k).min(lw - 1), (pixel.1 >> k).min(lh - 1))
        };
        // The receivers: position, normal and material of each level's texel under the pixel.
        let all_names: Vec<[String; 3]> = levels.iter().map(|&k| names(k)).collect();
        let mut points = Vec::new();
        for (i, &k) in levels.iter().enumerate() {
            let (x, y) = texel_of(k);
            points.extend(all_names[i].iter().map(|n| (n.as_str(), x, y)));
        }
        let Some(v) = read(&points, 0)? else { return Ok(None) };
        let texel = |p: [f32; 4], n: [f32; 4], m: [f32; 4]| -> Texel {
            if n[3] < 0.5 {
                return Texel::default();
            }
            Texel {
                position: Vec3::new(p[0], p[1], p[2]),
                depth: p[3],
                normal: Vec3::new(n[0], n[1], n[2]),
                radiance: Vec3::ZERO,
                material: Vec2::new(m[0], m[1]),
            }
        };
        let tan_v = (0.5 * self.camera.yfov).tan();
        let tan_half = Vec2::new(w as f32 / h.max(1) as f32 * tan_v, tan_v);
        let (right, forward) = (self.camera.right(), self.camera.forward());
        let gloss = s.glossy_reflection.then(|| crate::cpu::soler_glossy::Gloss {
            alpha: s.glossy_alpha,
            sharpness: s.glossy_sharpness,
            min_power: s.glossy_min_power,
            importance: s.glossy_sampling,
            axes: [right, right.cross(forward), forward],
        });
        let near_cut = if p.uses_vpls() && p.near_field == crate::settings::pipeline::NearField::ScreenSpace {
            s.near_field_split(self.scale_radius()).max(0.0)
        } else {
            0.0
        };
        struct Pending {
            level: u32,
            /// Index of the level's buffer names.
            names: usize,
            receiver: Texel,
            scale: Vec2,
            footprint: (Vec2, Vec2),
            glossy: bool,
            offsets: Vec<(u32, u32)>,
        }
        let mut pending = Vec::new();
        for (i, &k) in levels.iter().enumerate() {
            let rx = texel(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
            if !rx.valid() {
                continue;
            }
            let (lw, lh) = size_of(k);
            let (x, y) = texel_of(k);
            let cam = ScreenCamera { eye: self.camera.position, tan_half, size: Vec2::new(lw as f32, lh as f32) };
            let params = GatherParams {
                samples: s.samples,
                radius: s.radius_px,
                full_disc: i == 0,
                level: k,
                frame,
                disc: true,
                min_cos_beta: s.min_cos_beta,
                near_cut,
            };
            let glossy = gloss.as_ref().is_some_and(|g| {
                crate::cpu::soler_glossy::receiver_lobe(g, rx.position, rx.normal, cam.eye, rx.material, tan_half)
                    .is_some()
            });
            let offsets = soler::receiver_samples(&rx, x, y, &cam, params, gloss.as_ref())
                .into_iter()
                .filter(|(o, _)| *o != Vec2::ZERO)
                .map(|(o, _)| (x as i64 + o.x as i64, y as i64 + o.y as i64))
                .filter(|&(qx, qy)| qx >= 0 && qy >= 0 && qx < lw as i64 && qy < lh as i64)
                .map(|(qx, qy)| (qx as u32, qy as u32))
                .collect();
            let scale = Vec2::new(w as f32 / lw as f32, h as f32 / lh as f32);
            let footprint = (Vec2::new(x as f32, y as f32) * scale, Vec2::new(x as f32 + 1.0, y as f32 + 1.0) * scale);
            pending.push(Pending { level: k, names: i, receiver: rx, scale, footprint, glossy, offsets });
        }
        // The senders: position, normal of every sample's texel.
        let mut points = Vec::new();
        for pd in &pending {
            for &(qx, qy) in &pd.offsets {
                points.push((all_names[pd.names][0].as_str(), qx, qy));
                points.push((all_names[pd.names][1].as_str(), qx, qy));
            }
        }
        let Some(senders) = read(&points, 1)? else { return Ok(None) };
        let mut at = 0;
        Ok(Some(
            pending
                .into_iter()
                .map(|pd| {
                    let samples = pd
                        .offsets
                        .iter()
                        .map(|&(qx, qy)| {
                            let sender = texel(senders[at], senders[at + 1], [0.0; 4]);
                            at += 2;
                            let lit = sender.valid() && soler::facing(&pd.receiver, &sender, near_cut).is_some();
                            SolerSample {
                                level: pd.level,
                                pixel: (Vec2::new(qx as f32, qy as f32) + 0.5) * pd.scale,
                                lit,
                            }
                        })
                        .collect();
                    SolerReceiver { level: pd.level, footprint: pd.footprint, glossy: pd.glossy, samples }
                })
                .collect(),
        ))
    }
}
