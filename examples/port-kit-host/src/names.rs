//! The manifest names wgpu's enums and flags as wgpu spells them (`Rgba16Float`,
//! `ClampToEdge`, `TEXTURE_BINDING`); these tables turn the names back into values. A name
//! the table does not know is an error that names it, never a guess.

use std::fmt::Debug;

use wgpu::TextureFormat as F;

fn by_name<T: Debug + Copy>(what: &str, name: &str, all: &[T]) -> Result<T, String> {
    all.iter().copied().find(|v| format!("{v:?}") == name).ok_or_else(|| format!("unknown {what} `{name}`"))
}

/// The uncompressed texture formats a kit can use.
const FORMATS: &[F] = &[
    F::R8Unorm,
    F::R8Snorm,
    F::R8Uint,
    F::R8Sint,
    F::R16Uint,
    F::R16Sint,
    F::R16Unorm,
    F::R16Snorm,
    F::R16Float,
    F::Rg8Unorm,
    F::Rg8Snorm,
    F::Rg8Uint,
    F::Rg8Sint,
    F::R32Uint,
    F::R32Sint,
    F::R32Float,
    F::Rg16Uint,
    F::Rg16Sint,
    F::Rg16Unorm,
    F::Rg16Snorm,
    F::Rg16Float,
    F::Rgba8Unorm,
    F::Rgba8UnormSrgb,
    F::Rgba8Snorm,
    F::Rgba8Uint,
    F::Rgba8Sint,
    F::Bgra8Unorm,
    F::Bgra8UnormSrgb,
    F::Rgb9e5Ufloat,
    F::Rgb10a2Uint,
    F::Rgb10a2Unorm,
    F::Rg11b10Ufloat,
    F::R64Uint,
    F::Rg32Uint,
    F::Rg32Sint,
    F::Rg32Float,
    F::Rgba16Uint,
    F::Rgba16Sint,
    F::Rgba16Unorm,
    F::Rgba16Snorm,
    F::Rgba16Float,
    F::Rgba32Uint,
    F::Rgba32Sint,
    F::Rgba32Float,
    F::Stencil8,
    F::Depth16Unorm,
    F::Depth24Plus,
    F::Depth24PlusStencil8,
    F::Depth32Float,
    F::Depth32FloatStencil8,
];

pub fn format(name: &str) -> Result<F, String> {
    by_name("texture format", name, FORMATS)
}

pub fn texture_dimension(name: &str) -> Result<wgpu::TextureDimension, String> {
    use wgpu::TextureDimension as D;
    by_name("texture dimension", name, &[D::D1, D::D2, D::D3])
}

pub fn view_dimension(name: &str) -> Result<wgpu::TextureViewDimension, String> {
    use wgpu::TextureViewDimension as V;
    by_name("view dimension", name, &[V::D1, V::D2, V::D2Array, V::Cube, V::CubeArray, V::D3])
}

/// A shader's declared dimension (`2d`, `2d_array`, `cube`, …; docs/port-kit.md).
pub fn declared_dimension(name: &str) -> Result<wgpu::TextureViewDimension, String> {
    use wgpu::TextureViewDimension as V;
    Ok(match name {
        "1d" => V::D1,
        "2d" => V::D2,
        "2d_array" => V::D2Array,
        "cube" => V::Cube,
        "cube_array" => V::CubeArray,
        "3d" => V::D3,
        other => return Err(format!("unknown declared dimension `{other}`")),
    })
}

pub fn texture_usages(names: &[String]) -> Result<wgpu::TextureUsages, String> {
    names.iter().try_fold(wgpu::TextureUsages::empty(), |u, n| {
        wgpu::TextureUsages::from_name(n).map(|f| u | f).ok_or_else(|| format!("unknown texture usage `{n}`"))
    })
}

pub fn buffer_usages(names: &[String]) -> Result<wgpu::BufferUsages, String> {
    names.iter().try_fold(wgpu::BufferUsages::empty(), |u, n| {
        wgpu::BufferUsages::from_name(n).map(|f| u | f).ok_or_else(|| format!("unknown buffer usage `{n}`"))
    })
}

pub fn features(names: &[String]) -> Result<wgpu::Features, String> {
    names.iter().try_fold(wgpu::Features::empty(), |u, n| {
        wgpu::Features::from_name(n).map(|f| u | f).ok_or_else(|| format!("unknown feature `{n}`"))
    })
}

pub fn address_mode(name: &str) -> Result<wgpu::AddressMode, String> {
    use wgpu::AddressMode as A;
    by_name("address mode", name, &[A::ClampToEdge, A::Repeat, A::MirrorRepeat, A::ClampToBorder])
}

pub fn filter(name: &str) -> Result<wgpu::FilterMode, String> {
    by_name("filter", name, &[wgpu::FilterMode::Nearest, wgpu::FilterMode::Linear])
}

pub fn mipmap_filter(name: &str) -> Result<wgpu::MipmapFilterMode, String> {
    by_name("mipmap filter", name, &[wgpu::MipmapFilterMode::Nearest, wgpu::MipmapFilterMode::Linear])
}

pub fn compare(name: &str) -> Result<wgpu::CompareFunction, String> {
    use wgpu::CompareFunction as C;
    by_name(
        "comparison",
        name,
        &[C::Never, C::Less, C::Equal, C::LessEqual, C::Greater, C::NotEqual, C::GreaterEqual, C::Always],
    )
}

pub fn blend_factor(name: &str) -> Result<wgpu::BlendFactor, String> {
    use wgpu::BlendFactor as B;
    by_name(
        "blend factor",
        name,
        &[
            B::Zero,
            B::One,
            B::Src,
            B::OneMinusSrc,
            B::SrcAlpha,
            B::OneMinusSrcAlpha,
            B::Dst,
            B::OneMinusDst,
            B::DstAlpha,
            B::OneMinusDstAlpha,
            B::SrcAlphaSaturated,
            B::Constant,
            B::OneMinusConstant,
        ],
    )
}

pub fn blend_operation(name: &str) -> Result<wgpu::BlendOperation, String> {
    use wgpu::BlendOperation as O;
    by_name("blend operation", name, &[O::Add, O::Subtract, O::ReverseSubtract, O::Min, O::Max])
}

pub fn topology(name: &str) -> Result<wgpu::PrimitiveTopology, String> {
    use wgpu::PrimitiveTopology as T;
    by_name("topology", name, &[T::PointList, T::LineList, T::LineStrip, T::TriangleList, T::TriangleStrip])
}

pub fn index_format(name: &str) -> Result<wgpu::IndexFormat, String> {
    by_name("index format", name, &[wgpu::IndexFormat::Uint16, wgpu::IndexFormat::Uint32])
}

pub fn face(name: &str) -> Result<wgpu::Face, String> {
    by_name("face", name, &[wgpu::Face::Front, wgpu::Face::Back])
}

pub fn front_face(name: &str) -> Result<wgpu::FrontFace, String> {
    by_name("front face", name, &[wgpu::FrontFace::Ccw, wgpu::FrontFace::Cw])
}

pub fn polygon_mode(name: &str) -> Result<wgpu::PolygonMode, String> {
    use wgpu::PolygonMode as P;
    by_name("polygon mode", name, &[P::Fill, P::Line, P::Point])
}

pub fn step_mode(name: &str) -> Result<wgpu::VertexStepMode, String> {
    by_name("step mode", name, &[wgpu::VertexStepMode::Vertex, wgpu::VertexStepMode::Instance])
}

pub fn vertex_format(name: &str) -> Result<wgpu::VertexFormat, String> {
    use wgpu::VertexFormat as V;
    by_name(
        "vertex format",
        name,
        &[
            V::Uint8x2,
            V::Uint8x4,
            V::Unorm8x2,
            V::Unorm8x4,
            V::Uint16x2,
            V::Uint16x4,
            V::Unorm16x2,
            V::Unorm16x4,
            V::Float16x2,
            V::Float16x4,
            V::Float32,
            V::Float32x2,
            V::Float32x3,
            V::Float32x4,
            V::Uint32,
            V::Uint32x2,
            V::Uint32x3,
            V::Uint32x4,
            V::Sint32,
            V::Sint32x2,
            V::Sint32x3,
            V::Sint32x4,
        ],
    )
}

/// A storage texture's access as the shader declares it.
pub fn storage_access(name: &str) -> Result<wgpu::StorageTextureAccess, String> {
    use wgpu::StorageTextureAccess as A;
    Ok(match name {
        "read" => A::ReadOnly,
        "write" => A::WriteOnly,
        "read_write" => A::ReadWrite,
        other => return Err(format!("unknown access `{other}`")),
    })
}

/// Bytes of one texel of `format` as a copy packs it (the depth aspect of depth formats).
pub fn texel_bytes(format: F) -> Result<u32, String> {
    format
        .block_copy_size(None)
        .or_else(|| format.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)))
        .ok_or_else(|| format!("{format:?} cannot be copied"))
}
