//! A small CPU chart renderer for the CLI's plots (the sweep's Pareto plot): lines, dots and
//! text into an `image::RgbaImage`. Text is laid out and rasterised by egui's own font
//! machinery (`epaint::text::Fonts`, the fonts the app shows), so no extra font dependency.

use egui::epaint::text::{FontDefinitions, Fonts, TextOptions};
use egui::{Color32, FontId};
use image::{Rgba, RgbaImage};

pub struct Canvas {
    pub img: RgbaImage,
    fonts: Fonts,
}

/// Where a text's anchor point is on its box.
#[derive(Clone, Copy)]
pub enum Anchor {
    LeftTop,
    LeftCenter,
    CenterTop,
    RightCenter,
    CenterBottom,
}

fn blend(img: &mut RgbaImage, x: i64, y: i64, c: [u8; 3], a: f32) {
    if x < 0 || y < 0 || x >= img.width() as i64 || y >= img.height() as i64 || a <= 0.0 {
        return;
    }
    let p = img.get_pixel_mut(x as u32, y as u32);
    let a = a.min(1.0);
    for (dst, src) in p.0.iter_mut().zip(c) {
        *dst = (*dst as f32 * (1.0 - a) + src as f32 * a).round() as u8;
    }
}

impl Canvas {
    pub fn new(width: u32, height: u32) -> Self {
        let img = RgbaImage::from_pixel(width, height, Rgba([255, 255, 255, 255]));
        Self { img, fonts: Fonts::new(TextOptions::default(), FontDefinitions::default()) }
    }

    /// A line of width `w` pixels (anti-aliased by distance to the segment).
    pub fn line(&mut self, a: (f32, f32), b: (f32, f32), w: f32, c: [u8; 3]) {
        let (x0, x1) = (a.0.min(b.0) - w, a.0.max(b.0) + w);
        let (y0, y1) = (a.1.min(b.1) - w, a.1.max(b.1) + w);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len2 = (dx * dx + dy * dy).max(1e-6);
        for y in y0.floor() as i64..=y1.ceil() as i64 {
            for x in x0.floor() as i64..=x1.ceil() as i64 {
                let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                let t = (((px - a.0) * dx + (py - a.1) * dy) / len2).clamp(0.0, 1.0);
                let (qx, qy) = (a.0 + t * dx - px, a.1 + t * dy - py);
                let d = (qx * qx + qy * qy).sqrt();
                blend(&mut self.img, x, y, c, w * 0.5 + 0.5 - d);
            }
        }
    }

    /// A filled disc of radius `r`.
    pub fn disc(&mut self, center: (f32, f32), r: f32, c: [u8; 3]) {
        for y in (center.1 - r - 1.0).floor() as i64..=(center.1 + r + 1.0).ceil() as i64 {
            for x in (center.0 - r - 1.0).floor() as i64..=(center.0 + r + 1.0).ceil() as i64 {
                let d = ((x as f32 + 0.5 - center.0).powi(2) + (y as f32 + 0.5 - center.1).powi(2)).sqrt();
                blend(&mut self.img, x, y, c, r + 0.5 - d);
            }
        }
    }

    /// A ring of radius `r`.
    pub fn ring(&mut self, center: (f32, f32), r: f32, w: f32, c: [u8; 3]) {
        for y in (center.1 - r - w).floor() as i64..=(center.1 + r + w).ceil() as i64 {
            for x in (center.0 - r - w).floor() as i64..=(center.0 + r + w).ceil() as i64 {
                let d = ((x as f32 + 0.5 - center.0).powi(2) + (y as f32 + 0.5 - center.1).powi(2)).sqrt();
                blend(&mut self.img, x, y, c, w * 0.5 + 0.5 - (d - r).abs());
            }
        }
    }

    /// Text of `size` pixels; returns its width.
    pub fn text(&mut self, at: (f32, f32), s: &str, size: f32, c: [u8; 3], anchor: Anchor) -> f32 {
        let galley = self.fonts.with_pixels_per_point(1.0).layout_no_wrap(
            s.to_string(),
            FontId::proportional(size),
            Color32::WHITE,
        );
        let atlas = self.fonts.image();
        let (w, h) = (galley.size().x, galley.size().y);
        let origin = match anchor {
            Anchor::LeftTop => (at.0, at.1),
            Anchor::LeftCenter => (at.0, at.1 - h * 0.5),
            Anchor::CenterTop => (at.0 - w * 0.5, at.1),
            Anchor::RightCenter => (at.0 - w, at.1 - h * 0.5),
            Anchor::CenterBottom => (at.0 - w * 0.5, at.1 - h),
        };
        let (origin_x, origin_y) = (origin.0.round(), origin.1.round());
        for row in &galley.rows {
            let mesh = &row.row.visuals.mesh;
            // Glyphs are axis-aligned quads of four vertices (pos in points, uv in atlas texels).
            for quad in mesh.vertices.chunks_exact(4) {
                let (mut p0, mut p1) = ((f32::MAX, f32::MAX), (f32::MIN, f32::MIN));
                let (mut u0, mut u1) = ((f32::MAX, f32::MAX), (f32::MIN, f32::MIN));
                for v in quad {
                    p0 = (p0.0.min(v.pos.x), p0.1.min(v.pos.y));
                    p1 = (p1.0.max(v.pos.x), p1.1.max(v.pos.y));
                    u0 = (u0.0.min(v.uv.x), u0.1.min(v.uv.y));
                    u1 = (u1.0.max(v.uv.x), u1.1.max(v.uv.y));
                }
                let gw = (p1.0 - p0.0).round() as i64;
                let gh = (p1.1 - p0.1).round() as i64;
                for j in 0..gh.max(0) {
                    for i in 0..gw.max(0) {
                        let u = (u0.0 + (i as f32 + 0.5) / gw as f32 * (u1.0 - u0.0)) as usize;
                        let v = (u0.1 + (j as f32 + 0.5) / gh as f32 * (u1.1 - u0.1)) as usize;
                        if u >= atlas.size[0] || v >= atlas.size[1] {
                            continue;
                        }
                        let coverage = atlas.pixels[v * atlas.size[0] + u].a() as f32 / 255.0;
                        let x = (origin_x + row.pos.x + p0.0).round() as i64 + i;
                        let y = (origin_y + row.pos.y + p0.1).round() as i64 + j;
                        blend(&mut self.img, x, y, c, coverage);
                    }
                }
            }
        }
        w
    }
}

/// "Nice" tick values covering [lo, hi] (1, 2, 5 × 10^k steps), about `count` of them.
pub fn ticks(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    if hi <= lo || !lo.is_finite() || !hi.is_finite() {
        return vec![lo];
    }
    let raw = (hi - lo) / count.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|i| i as f64 * step).collect()
}

/// Formats a tick value with as many decimals as its step needs.
pub fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 { 0 } else { (-step.log10()).ceil() as usize };
    format!("{v:.decimals$}")
}
