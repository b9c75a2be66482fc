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
                let (texture, base_uv) = match &pbr.base_color_texture {
                    Some(info) => (self.texture(info.index.value())?, Some(uv_use(info))),
                    None => (None, None),
                };
                let (emissive_texture, emissive_uv) = match &m.emissive_texture {
                    Some(info) => (self.texture(info.index.value())?, Some(uv_use(info))),
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
                let strength = m
                    .extensions
                    .as_ref()
                    .and_then(|e| e.emissive_strength.as_ref())
                    .map_or(1.0, |s| s.emissive_strength.0);
                let material = Material {
                    name: m.name.clone().unwrap_or_else(|| format!("material {i}")),
                    base_color: Vec4::from_array(pbr.base_color_factor.0),
                    base_color_texture: texture,
                    metallic: pbr.metallic_factor.0.clamp(0.0, 1.0),
                    roughness: pbr.roughness_factor.0.clamp(0.0, 1.0),
                    emissive: (Vec3::from(m.emissive_factor.0) * strength).max(Vec3::ZERO),
                    emissive_texture,
                    sample_weight: 1.0,
                    double_sided: m.double_sided,
                    specular_override: None,
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
        let rgba = decode_image(&encoded).map_err(|reason| SceneError::Image {
            file: self.file.to_string(),
            image,
            name: name.clone(),
            reason,
        })?;
        self.scene.textures.push(TextureImage {
            name,
            width: rgba.width(),
            height: rgba.height(),
            rgba8: rgba.into_raw().into(),
        });
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

/// Decodes an embedded or external image to RGBA8, after checking the size its header
/// declares against [`MAX_IMAGE_PIXELS`]; the format is sniffed from the data.
fn decode_image(encoded: &[u8]) -> Result<image::RgbaImage, String> {
    let reader =
        || image::ImageReader::new(std::io::Cursor::new(encoded)).with_guessed_format().map_err(|e| e.to_string());
    let (w, h) = reader()?.into_dimensions().map_err(|e| e.to_string())?;
    let pixels = u64::from(w) * u64::from(h);
    if pixels > MAX_IMAGE_PIXELS {
        return Err(format!(
            "its header declares {w} × {h} pixels ({} MiB as RGBA8), more than the 8192 × 8192 pixels \
             ({} MiB) GI Lab loads per image; downscale it",
            (pixels * 4) >> 20,
            (MAX_IMAGE_PIXELS * 4) >> 20
        ));
    }
    // `into_rgba8` keeps an RGBA8 image's buffer instead of copying it.
    Ok(reader()?.decode().map_err(|e| e.to_string())?.into_rgba8())
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
