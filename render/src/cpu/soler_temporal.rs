//! CPU twin of Soler et al.'s temporal filtering (004 §4, Eq. 6; GPU:
//! `shaders/soler/temporal.wgsl`): F_i = a·W(H) + (1 − a)·I_i, with the warp through the
//! movement buffer (nearest texel of p + m), rejection where the stored depth at the warped
//! position differs from the point's depth in the previous frame (the movement buffer's z:
//! previous camera, previous object transform) by more than τ_z of it or
//! where n · n_prev < τ_n, and a adapted to motion (× m½ / (m½ + |m|)) and glossiness
//! (÷ (1 + k_g · SI · √SP)). Blended is the radiance, or the irradiance before the albedo
//! multiply as Fig. 4 orders it (⚠[soler.temporal-order]; `BlendParams::irradiance`), the
//! glossy light then blended apart with its own history and the same a.
//!
//! Readings (⚠[soler.temporal-a], ⚠[soler.temporal-history]): the paper gives no value of a nor its adaptation, only that it
//! depends on speed and shininess; it does not say whether H is I_{i−1} (as printed) or
//! F_{i−1}: both are offered (`soler.temporal_history`, default F_{i−1}, whose flicker is
//! lower; measured in tests/soler_temporal.rs).

use glam::{Vec2, Vec3, Vec4};

use crate::buffers::ImageF32;

/// The blend's settings (`passes::soler::temporal::TemporalParams` without the validity).
#[derive(Clone, Copy, Debug)]
pub struct BlendParams {
    pub a: f32,
    pub motion_half_px: f32,
    pub gloss: f32,
    pub reject_depth: f32,
    pub reject_normal: f32,
    /// The history keeps I_i (else F_i).
    pub raw_history: bool,
    /// Blend the irradiance (I_i less the glossy light, over the albedo c·DI/π), else the
    /// radiance.
    pub irradiance: bool,
}

/// One frame's inputs, images of the G-buffer's size.
pub struct BlendInputs<'a> {
    /// I_i (rgb).
    pub current: &'a ImageF32,
    /// xyz world position, w view depth.
    pub position: &'a ImageF32,
    /// xyz normal, w 1 on a surface.
    pub normal: &'a ImageF32,
    /// xy: the pixel's offset to its previous position, z: its depth in the previous frame.
    pub motion: &'a ImageF32,
    /// rgb c, a DI (the irradiance blend's albedo).
    pub albedo: &'a ImageF32,
    /// The glossy light added into `current`, if any.
    pub specular: Option<&'a ImageF32>,
    /// The previous frame's glossy history (irradiance blend); None: black.
    pub specular_history: Option<&'a ImageF32>,
    /// x SI, y SP.
    pub material: &'a ImageF32,
    /// The previous frame's normals.
    pub prev_normal: &'a ImageF32,
    /// The previous frame's history (rgb, depth in a); None: no history yet.
    pub history: Option<&'a ImageF32>,
}

/// The blend's outputs, as the GPU's buffers hold them.
pub struct BlendOutputs {
    /// `soler.temporal`: F_i.
    pub filtered: Vec<Vec3>,
    /// `soler.temporal.history`: rgb F_i or I_i, a depth.
    pub history: Vec<Vec4>,
    /// `soler.temporal.warped`: W(H), a 1 where found.
    pub warped: Vec<Vec4>,
    /// `soler.temporal.rejection`: depth, normal, no history.
    pub rejection: Vec<[bool; 3]>,
    /// `soler.temporal.a`.
    pub a: Vec<f32>,
    /// `soler.temporal.specular_history`: F_S or S.
    pub specular_history: Vec<Vec3>,
}

fn xyz(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// Eq. 6 at every pixel.
pub fn blend(p: BlendParams, x: &BlendInputs) -> BlendOutputs {
    let (w, h) = (x.current.width as i32, x.current.height as i32);
    let n = (w * h) as usize;
    let mut out = BlendOutputs {
        filtered: Vec::with_capacity(n),
        history: Vec::with_capacity(n),
        warped: Vec::with_capacity(n),
        rejection: Vec::with_capacity(n),
        a: Vec::with_capacity(n),
        specular_history: Vec::with_capacity(n),
    };
    for i in 0..n {
        let (px, py) = ((i as i32) % w, (i as i32) / w);
        let (k, s) = match p.irradiance {
            true => {
                let c = x.albedo.data[i];
                (xyz(c) * c[3] / std::f32::consts::PI, x.specular.map_or(Vec3::ZERO, |t| xyz(t.data[i])))
            }
            false => (Vec3::ONE, Vec3::ZERO),
        };
        let r = (xyz(x.current.data[i]) - s).max(Vec3::ZERO);
        let i_new = Vec3::select(k.cmpgt(Vec3::ZERO), r / k, Vec3::ZERO);
        let nrm = x.normal.data[i];
        let pos = x.position.data[i];
        let mut a = 0.0;
        let mut warped = Vec4::ZERO;
        let mut warped_s = Vec3::ZERO;
        let mut mask = [false, false, true];
        if let Some(hist) = x.history.filter(|_| nrm[3] > 0.5) {
            let m = Vec2::new(x.motion.data[i][0], x.motion.data[i][1]);
            let q = (Vec2::new(px as f32, py as f32) + 0.5 + m).floor();
            let (qx, qy) = (q.x as i32, q.y as i32);
            if qx >= 0 && qy >= 0 && qx < w && qy < h {
                let j = (qy * w + qx) as usize;
                let (pn, hv) = (x.prev_normal.data[j], hist.data[j]);
                if pn[3] > 0.5 && hv[3] > 0.0 {
                    warped = Vec4::new(hv[0], hv[1], hv[2], 1.0);
                    warped_s = x.specular_history.map_or(Vec3::ZERO, |t| xyz(t.data[j]));
                    mask[2] = false;
                    let z_prev = x.motion.data[i][2];
                    mask[0] = (hv[3] - z_prev).abs() > p.reject_depth * z_prev.max(1e-6);
                    mask[1] = xyz(nrm).dot(xyz(pn)) < p.reject_normal;
                    if !mask[0] && !mask[1] {
                        let mat = x.material.data[i];
                        let half = p.motion_half_px;
                        a = p.a * half
                            / (half + m.length())
                            / (1.0 + p.gloss * mat[0].max(0.0) * mat[1].max(0.0).sqrt());
                    }
                }
            }
        }
        let f = a * warped.truncate() + (1.0 - a) * i_new;
        let keep = if p.raw_history { i_new } else { f };
        let depth = if nrm[3] > 0.5 { pos[3] } else { 0.0 };
        let f_s = a * warped_s + (1.0 - a) * s;
        out.filtered.push(k * f + f_s);
        out.specular_history.push(if p.raw_history { s } else { f_s });
        out.history.push(keep.extend(depth));
        out.warped.push(warped);
        out.rejection.push(mask);
        out.a.push(a);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, v: [f32; 4]) -> ImageF32 {
        ImageF32 { width: w, height: h, data: vec![v; (w * h) as usize] }
    }

    fn params() -> BlendParams {
        BlendParams {
            a: 0.8,
            motion_half_px: 4.0,
            gloss: 0.0,
            reject_depth: 0.05,
            reject_normal: 0.9,
            raw_history: false,
            irradiance: false,
        }
    }

    /// A still, diffuse surface at depth 2 (also in the previous frame) seen by a camera at the
    /// origin looking down −z; albedo 0.5, DI 1.
    fn still(current: f32, history: f32) -> Vec<ImageF32> {
        vec![
            img(4, 4, [current, current, current, 1.0]),
            img(4, 4, [0.0, 0.0, -2.0, 2.0]),
            img(4, 4, [0.0, 0.0, 1.0, 1.0]),
            img(4, 4, [0.0, 0.0, 2.0, 1.0]),
            img(4, 4, [0.0; 4]),
            img(4, 4, [history, history, history, 2.0]),
            img(4, 4, [0.5, 0.5, 0.5, 1.0]),
        ]
    }

    fn run(p: BlendParams, v: &[ImageF32], with_history: bool) -> BlendOutputs {
        let x = BlendInputs {
            current: &v[0],
            position: &v[1],
            normal: &v[2],
            motion: &v[3],
            material: &v[4],
            prev_normal: &v[2],
            history: with_history.then_some(&v[5]),
            albedo: &v[6],
            specular: None,
            specular_history: None,
        };
        blend(p, &x)
    }

    #[test]
    fn a_still_pixel_blends_by_a_and_the_first_frame_keeps_the_gather() {
        let v = still(1.0, 0.5);
        let o = run(params(), &v, true);
        // F = 0.8 · 0.5 + 0.2 · 1.0 = 0.6.
        assert!((o.filtered[5].x - 0.6).abs() < 1e-6, "{}", o.filtered[5]);
        assert_eq!(o.rejection[5], [false, false, false]);
        assert_eq!(o.history[5].w, 2.0);
        let first = run(params(), &v, false);
        assert_eq!(first.filtered[5].x, 1.0);
        assert_eq!(first.rejection[5], [false, false, true]);
        let raw = run(BlendParams { raw_history: true, ..params() }, &v, true);
        assert_eq!(raw.history[5].x, 1.0, "Eq. 6 as printed keeps I_i");
    }

    #[test]
    fn the_irradiance_blend_demodulates_by_the_albedo_and_leaves_the_glossy_light_out() {
        // Radiance 0.3 of which 0.1 glossy, albedo c·DI/π = 0.5/π: E = 0.2 π / 0.5; the
        // history holds E_h = 0.5. F = k (0.8 E_h + 0.2 E) + 0.1.
        let mut v = still(0.3, 0.5);
        let spec = img(4, 4, [0.1, 0.1, 0.1, 1.0]);
        v.push(spec);
        // The glossy history 0.3: F_S = 0.8 · 0.3 + 0.2 · 0.1.
        v.push(img(4, 4, [0.3, 0.3, 0.3, 1.0]));
        let p = BlendParams { irradiance: true, ..params() };
        let x = BlendInputs {
            current: &v[0],
            position: &v[1],
            normal: &v[2],
            motion: &v[3],
            material: &v[4],
            prev_normal: &v[2],
            history: Some(&v[5]),
            albedo: &v[6],
            specular: Some(&v[7]),
            specular_history: Some(&v[8]),
        };
        let o = blend(p, &x);
        let k = 0.5 / std::f32::consts::PI;
        let e = 0.2 / k;
        let expect = k * (0.8 * 0.5 + 0.2 * e) + (0.8 * 0.3 + 0.2 * 0.1);
        assert!((o.filtered[5].x - expect).abs() < 1e-6, "{} vs {expect}", o.filtered[5].x);
        assert!((o.history[5].x - (0.8 * 0.5 + 0.2 * e)).abs() < 1e-6, "the history keeps the irradiance");
        // A black albedo has no irradiance to blend: the filtered glossy light alone passes.
        assert!((o.specular_history[5].x - 0.26).abs() < 1e-6, "the glossy history keeps F_S");
        let black = img(4, 4, [0.0, 0.0, 0.0, 1.0]);
        let o = blend(p, &BlendInputs { albedo: &black, ..x });
        assert!((o.filtered[5].x - 0.26).abs() < 1e-6, "{}", o.filtered[5].x);
    }

    #[test]
    fn an_object_that_moved_in_depth_keeps_its_history() {
        // The point is at depth 2 now and was at 2.5 in the previous frame (it moved toward
        // the still camera); the history stored 2.5 there: accepted. Projecting the current
        // position with the previous camera (2.0) would have rejected it.
        let mut v = still(1.0, 0.5);
        v[3] = img(4, 4, [0.0, 0.0, 2.5, 1.0]);
        v[5] = img(4, 4, [0.5, 0.5, 0.5, 2.5]);
        let o = run(params(), &v, true);
        assert_eq!(o.rejection[5], [false, false, false]);
        assert!((o.filtered[5].x - 0.6).abs() < 1e-6);
    }

    #[test]
    fn depth_and_normal_disagreement_reject_the_history() {
        let mut v = still(1.0, 0.5);
        // The stored depth 2.2 is 10 % off the point's 2.0 (τ_z 5 %).
        v[5] = img(4, 4, [0.5, 0.5, 0.5, 2.2]);
        let o = run(params(), &v, true);
        assert_eq!((o.rejection[5], o.a[5], o.filtered[5].x), ([true, false, false], 0.0, 1.0));
        let mut v = still(1.0, 0.5);
        // A previous normal 60° away (cos 0.5 < τ_n 0.9).
        v[2] = img(4, 4, [0.0, 0.866, 0.5, 1.0]);
        let x = BlendInputs {
            current: &v[0],
            position: &v[1],
            normal: &img(4, 4, [0.0, 0.0, 1.0, 1.0]),
            motion: &v[3],
            material: &v[4],
            prev_normal: &v[2],
            history: Some(&v[5]),
            albedo: &v[6],
            specular: None,
            specular_history: None,
        };
        let o = blend(params(), &x);
        assert_eq!(o.rejection[5], [false, true, false]);
    }

    #[test]
    fn motion_and_glossiness_lower_a() {
        let mut v = still(1.0, 0.5);
        v[3] = img(4, 4, [-1.0, 0.0, 2.0, 1.0]);
        let o = run(params(), &v, true);
        // m½ = 4 px: a = 0.8 · 4 / 5.
        assert!((o.a[5] - 0.64).abs() < 1e-6, "{}", o.a[5]);
        // Moving 3 px per frame to the right: the previous position is 3 px left, off this
        // 4-pixel-wide image for every column but the last.
        v[3] = img(4, 4, [-3.0, 0.0, 2.0, 1.0]);
        let o = run(params(), &v, true);
        assert_eq!(o.rejection[6], [false, false, true], "warped off screen");
        assert!((o.a[7] - 0.8 * 4.0 / 7.0).abs() < 1e-6, "{}", o.a[7]);
        let mut v = still(1.0, 0.5);
        v[4] = img(4, 4, [0.5, 64.0, 0.0, 0.0]);
        let o = run(BlendParams { gloss: 0.05, ..params() }, &v, true);
        // SI 0.5, SP 64: a = 0.8 / (1 + 0.05 · 0.5 · 8).
        assert!((o.a[5] - 0.8 / 1.2).abs() < 1e-6, "{}", o.a[5]);
    }
}
