//! Materials (§3.9) and textures (§3.8), with KHR_texture_transform.

use glam::{Mat3, Vec2, Vec3, Vec4};

use super::container::{decode_data_uri, is_data_uri};
use super::{Loader, SceneError, UvUse};
use crate::scene::{Material, TextureImage};

impl Loader<'_> {
    // -----------------------------------------------------------------------------------
    // Materials and textures (§3.9, §3.8)
    // -----------------------------------------------------------------------------------

    /// Loads glTF material `index` (None: the default material of §3.9.6) as a scene material.
    pub(super) fn material(&mut self, index: Option<usize>) -> Result<usize, SceneError> {
        if let Some(&m) = self.material_map.get(&index) {
            return Ok(m);
        }
        let (material, uv) = match index {
            None => (Material::default(), UvUse::default()),
            Some(i) => {
                let root = self.root;
                let m = root
                    .materials
                    .get(i)
                    .ok_or_else(|| self.invalid(format!("a primitive refers to material {i}, which does not exist")))?;
                let pbr = &m.pbr_metallic_roughness;
                let mname = m.name.clone().unwrap_or_else(|| format!("material {i}"));
                let (texture, base_uv) = match &pbr.base_color_texture {
                    Some(info) => {
                        (self.texture_or_factor(info.index.value(), &mname, "base colour")?, Some(uv_use(info)))
                    }
                    None => (None, None),
                };
                let (emissive_texture, emissive_uv) = match &m.emissive_texture {
                    Some(info) => (self.texture_or_factor(info.index.value(), &mname, "emissive")?, Some(uv_use(info))),
                    None => (None, None),
                };
                // One UV set per vertex (`Vertex::uv`): the base colour's, else the emissive
                // texture's. An emissive texture on other UVs is read with the base colour's.
                let uv = match (base_uv, emissive_uv) {
                    (Some(b), Some(e)) if texture.is_some() && emissive_texture.is_some() && b != e => {
                        self.warn(format!(
                            "material {i}: the emissive texture uses other texture coordinates than the base colour \
                             texture (TEXCOORD_{} vs TEXCOORD_{}, or another KHR_texture_transform); it is read with \
                             the base colour's",
                            e.set, b.set
                        ));
                        b
                    }
                    (Some(b), _) if texture.is_some() => b,
                    (_, Some(e)) if emissive_texture.is_some() => e,
                    _ => UvUse::default(),
                };
                // The other maps read the same texture coordinates (one UV set per vertex).
                let mut other_map = |index: usize, used: UvUse, role: &str| {
                    let t = self.texture_or_factor(index, &mname, role)?;
                    if t.is_some() && used != uv && (texture.is_some() || emissive_texture.is_some()) {
                        self.warn(format!(
                            "material '{mname}': the {role} texture uses other texture coordinates than the base colour \
                             texture; it is read with the base colour's"
                        ));
                    }
                    Ok::<_, SceneError>(t)
                };
                let normal = m.normal_texture.as_ref();
                let normal_texture = match normal {
                    Some(n) => {
                        let t = n.extensions.as_ref().and_then(|e| e.others.get("KHR_texture_transform"));
                        other_map(n.index.value(), json_uv_use(n.tex_coord, t), "normal")?
                    }
                    None => None,
                };
                let metallic_roughness_texture = match &pbr.metallic_roughness_texture {
                    Some(info) => other_map(info.index.value(), uv_use(info), "metallic-roughness")?,
                    None => None,
                };
                let occlusion = m.occlusion_texture.as_ref();
                let occlusion_texture = match occlusion {
                    Some(o) => {
                        let t = o.extensions.as_ref().and_then(|e| e.others.get("KHR_texture_transform"));
                        other_map(o.index.value(), json_uv_use(o.tex_coord, t), "occlusion")?
                    }
                    None => None,
                };
                let mut normal_scale = normal.map_or(1.0, |n| n.scale);
                if !normal_scale.is_finite() {
                    self.warn(format!(
                        "material '{mname}': normalTexture.scale {normal_scale} is not a number; 1 is used"
                    ));
                    normal_scale = 1.0;
                }
                let alpha_cutoff = match m.alpha_mode {
                    gltf::json::validation::Checked::Valid(gltf::json::material::AlphaMode::Mask) => {
                        let c = m.alpha_cutoff.map_or(0.5, |c| c.0);
                        if !(0.0..=1.0).contains(&c) {
                            let used = if c.is_finite() { c.clamp(0.0, 1.0) } else { 0.5 };
                            self.warn(format!("material '{mname}': alphaCutoff {c} is outside [0, 1]; {used} is used"));
                            Some(used)
                        } else {
                            Some(c)
                        }
                    }
                    gltf::json::validation::Checked::Valid(gltf::json::material::AlphaMode::Blend) => {
                        self.warn(format!(
                            "material '{mname}': alphaMode BLEND is drawn as MASK at alpha 0.5 (GI Lab has no \
                             transparency)"
                        ));
                        Some(0.5)
                    }
                    _ => None,
                };
                let strength = m
                    .extensions
                    .as_ref()
                    .and_then(|e| e.emissive_strength.as_ref())
                    .map_or(1.0, |s| s.emissive_strength.0);
                let material = Material {
                    name: mname.clone(),
                    base_color: Vec4::from_array(pbr.base_color_factor.0),
                    base_color_texture: texture,
                    metallic: pbr.metallic_factor.0.clamp(0.0, 1.0),
                    roughness: pbr.roughness_factor.0.clamp(0.0, 1.0),
                    emissive: (Vec3::from(m.emissive_factor.0) * strength).max(Vec3::ZERO),
                    emissive_texture,
                    sample_weight: 1.0,
                    double_sided: m.double_sided,
                    specular_override: None,
                    alpha_cutoff,
                    normal_texture,
                    normal_scale,
                    metallic_roughness_texture,
                    occlusion_texture,
                };
                (material, uv)
            }
        };
        self.scene.materials.push(material);
        self.material_uv.push(uv);
        let id = self.scene.materials.len() - 1;
        self.material_map.insert(index, id);
        Ok(id)
    }

    /// [`Self::texture`], but an image that cannot be read or decoded (missing file, broken
    /// data, too large) leaves the material on its factor, with a warning naming the image,
    /// the material and the map. A reference outside the scene's folder stays an error.
    fn texture_or_factor(&mut self, index: usize, material: &str, role: &str) -> Result<Option<usize>, SceneError> {
        match self.texture(index) {
            Err(e @ (SceneError::MissingImage { .. } | SceneError::Image { .. } | SceneError::BadDataUri { .. })) => {
                self.warn(format!("material '{material}': its {role} texture is not used, the factor is: {e}"));
                Ok(None)
            }
            r => r,
        }
    }

    /// Loads the image of texture `index` (decoded to RGBA8; shared between textures that
    /// use the same image). A texture without an image (extension-only source) is skipped.
    fn texture(&mut self, index: usize) -> Result<Option<usize>, SceneError> {
        let root = self.root;
        let tex = root
            .textures
            .get(index)
            .ok_or_else(|| self.invalid(format!("a material refers to texture {index}, which does not exist")))?;
        let image = tex.source.value();
        if image == u32::MAX as usize {
            self.warn(format!("texture {index} has no image in a supported format and is ignored"));
            return Ok(None);
        }
        if let Some(&t) = self.image_map.get(&image) {
            return Ok(Some(t));
        }
        let img = root
            .images
            .get(image)
            .ok_or_else(|| self.invalid(format!("texture {index} refers to image {image}, which does not exist")))?;
        let name = img.name.clone().unwrap_or_else(|| format!("image {image}"));
        let missing = |uri: &str, reason: String| SceneError::MissingImage {
            file: self.file.to_string(),
            image,
            uri: uri.to_string(),
            reason,
        };
        let encoded: Vec<u8> =
            match (img.buffer_view, img.uri.as_deref()) {
                (Some(view), _) => self.view_bytes(view.value()).map_err(|r| missing("bufferView", r))?.to_vec(),
                (None, Some(uri)) if is_data_uri(uri) => decode_data_uri(uri).map_err(|reason| {
                    SceneError::BadDataUri { file: self.file.to_string(), what: format!("image {image}"), reason }
                })?,
                (None, Some(uri)) => self.read_external(uri, &format!("image {image}"), |r| missing(uri, r))?,
                (None, None) => return Err(self.invalid(format!("image {image} has neither a uri nor a bufferView"))),
            };
        let (width, height, rgba8) = decode_image(&encoded).map_err(|reason| SceneError::Image {
            file: self.file.to_string(),
            image,
            name: name.clone(),
            reason,
        })?;
        self.scene.textures.push(TextureImage { name, width, height, rgba8 });
        let id = self.scene.textures.len() - 1;
        self.image_map.insert(image, id);
        Ok(Some(id))
    }
}

/// The most pixels the loader decodes per image: 8192 × 8192 (64 megapixels, 256 MiB as
/// RGBA8). An image's header states its size, so without a limit a kilobyte-sized JPEG that
/// declares 12800 × 12800 pixels made the loader allocate and fill 1.7 GB (found with the
/// fuzzer's texture seeds, issue #19).
pub(super) const MAX_IMAGE_PIXELS: u64 = 8192 * 8192;

/// The most bytes the decoder may produce for one image, in its own format (256 MiB): an
/// OpenEXR image of 8 × 5,373,956 pixels (within [`MAX_IMAGE_PIXELS`]) decodes to 12-byte
/// float pixels, 516 MB (found by the fuzzer, issue #19).
pub(super) const MAX_DECODED_IMAGE_BYTES: u64 = 256 << 20;

/// Decodes an embedded or external image to RGBA8 (width, height, pixels), after checking
/// the size its header declares against [`MAX_IMAGE_PIXELS`] and [`MAX_DECODED_IMAGE_BYTES`];
/// the format is sniffed from the data. The RGBA8 pixels are written straight into the
/// texture's shared buffer (no intermediate RGBA image to copy).
fn decode_image(encoded: &[u8]) -> Result<(u32, u32, std::sync::Arc<[u8]>), String> {
    use image::{DynamicImage, GenericImageView as _, ImageDecoder as _};
    let reader =
        image::ImageReader::new(std::io::Cursor::new(encoded)).with_guessed_format().map_err(|e| e.to_string())?;
    let decoder = reader.into_decoder().map_err(|e| e.to_string())?;
    let (w, h) = decoder.dimensions();
    let pixels = u64::from(w) * u64::from(h);
    let decoded = decoder.total_bytes();
    if pixels > MAX_IMAGE_PIXELS || decoded > MAX_DECODED_IMAGE_BYTES {
        return Err(format!(
            "its header declares {w} × {h} pixels ({} MiB decoded), more than the 8192 × 8192 pixels and {} MiB \
             GI Lab loads per image; downscale it",
            decoded >> 20,
            MAX_DECODED_IMAGE_BYTES >> 20
        ));
    }
    let img = DynamicImage::from_decoder(decoder).map_err(|e| e.to_string())?;
    let len = usize::try_from(pixels * 4).map_err(|_| "the image is too large for this machine".to_string())?;
    // One allocation of the final size (`repeat_n` has an exact length), then filled.
    let mut rgba8: std::sync::Arc<[u8]> = std::iter::repeat_n(0u8, len).collect();
    let out = std::sync::Arc::get_mut(&mut rgba8).ok_or("the texture buffer is shared")?;
    match &img {
        DynamicImage::ImageRgba8(src) => out.copy_from_slice(src.as_raw()),
        DynamicImage::ImageRgb8(src) => {
            for (o, i) in out.chunks_exact_mut(4).zip(src.as_raw().chunks_exact(3)) {
                o[..3].copy_from_slice(i);
                o[3] = 255;
            }
        }
        // Other formats (grey, 16-bit, float) through the same per-pixel conversion as `to_rgba8`.
        other => {
            for (o, (_, _, p)) in out.chunks_exact_mut(4).zip(other.pixels()) {
                o.copy_from_slice(&p.0);
            }
        }
    }
    Ok((w, h, rgba8))
}

/// The texture coordinates a texture reference reads: its set and KHR_texture_transform.
fn uv_use(info: &gltf::json::texture::Info) -> UvUse {
    let transform = info.extensions.as_ref().and_then(|e| e.texture_transform.as_ref());
    UvUse {
        set: transform.and_then(|t| t.tex_coord).unwrap_or(info.tex_coord),
        transform: transform.map(|t| uv_transform(t.offset.0, t.rotation.0, t.scale.0)),
    }
}

/// KHR_texture_transform's UV matrix: translation × rotation × scale, with the rotation
/// matrix of the ratified extension text (columns (cos, −sin), (sin, cos)).
pub(super) fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Mat3 {
    let (s, c) = rotation.sin_cos();
    let t = Mat3::from_translation(Vec2::from(offset));
    let r = Mat3::from_cols(Vec3::new(c, -s, 0.0), Vec3::new(s, c, 0.0), Vec3::Z);
    t * r * Mat3::from_scale(Vec2::from(scale))
}

/// The texture coordinates of a normal or occlusion texture reference, whose
/// KHR_texture_transform gltf-json keeps untyped.
fn json_uv_use(tex_coord: u32, transform: Option<&serde_json::Value>) -> UvUse {
    let set = transform.and_then(|t| t.get("texCoord")).and_then(|x| x.as_u64()).map_or(tex_coord, |x| x as u32);
    UvUse { set, transform: transform.and_then(transform_of_json) }
}

/// KHR_texture_transform's matrix from its JSON.
fn transform_of_json(v: &serde_json::Value) -> Option<Mat3> {
    let pair = |key: &str, default: [f32; 2]| {
        v.get(key).and_then(|a| a.as_array()).map_or(default, |a| {
            let x = |i: usize, d: f32| a.get(i).and_then(|x| x.as_f64()).map_or(d, |x| x as f32);
            [x(0, default[0]), x(1, default[1])]
        })
    };
    let rotation = v.get("rotation").and_then(|r| r.as_f64()).unwrap_or(0.0) as f32;
    Some(uv_transform(pair("offset", [0.0, 0.0]), rotation, pair("scale", [1.0, 1.0])))
}
