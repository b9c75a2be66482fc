//! A bind group from one description (issue #52 point 3; CONTRIBUTING.md, "Files and
//! modules"): a pass declares each of its bind groups once, as a [`Bindings`] constant that
//! names the shader and group it serves and lists every binding (number, name, kind). The
//! layout is made from it ([`Bindings::layout`]) and the group from it and the resources, in
//! the description's order ([`Bindings::group`]): adding a binding is one line of the
//! description and one resource where the group is made. `passes::BINDINGS` lists every
//! description, and `tests/tests/shaders.rs` checks each against its shader's declarations
//! (every binding of the group there, of the same kind), so that a description cannot drift
//! from the WGSL; it is also what a port kit's manifest can read.

use crate::counters::prelude::*;

use super::bgl;

/// What a binding holds (the layout entry's type).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Uniform,
    /// A uniform read at a dynamic offset (one slot of a strided buffer per dispatch).
    UniformDynamic,
    /// A read-only storage buffer read at a dynamic offset: per-dispatch parameters that
    /// change from frame to frame, which lavapipe would otherwise inline into a new shader
    /// variant for each new value (docs/performance.md, "Shader variants on lavapipe").
    StorageDynamic,
    Storage {
        read_only: bool,
    },
    /// A 2D float texture, sampled or loaded.
    Texture {
        filterable: bool,
    },
    /// A 2D float texture array.
    TextureArray {
        filterable: bool,
    },
    /// A 2D unsigned-integer texture.
    UintTexture,
    /// A 2D unsigned-integer texture array.
    UintTextureArray,
    /// A 2D depth texture.
    Depth,
    /// A depth texture array.
    DepthArray,
    /// A write-only 2D storage texture of this format.
    StorageTexture(wgpu::TextureFormat),
    /// A write-only 2D storage texture array of this format.
    StorageTextureArray(wgpu::TextureFormat),
    /// A read-write 2D storage texture of this format.
    StorageTextureReadWrite(wgpu::TextureFormat),
    Sampler(wgpu::SamplerBindingType),
}

/// One binding: its number in the group, the name of its variable in the shader, its kind.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub binding: u32,
    pub name: &'static str,
    pub kind: Kind,
}

/// A binding of [`Bindings::list`].
pub const fn binding(binding: u32, name: &'static str, kind: Kind) -> Binding {
    Binding { binding, name, kind }
}

/// One bind group of a pass: its label (the group's and the layout's), the shader entry
/// module and group number it serves, the stages that see it, and its bindings.
#[derive(Clone, Copy, Debug)]
pub struct Bindings {
    pub label: &'static str,
    pub shader: &'static str,
    pub group: u32,
    /// The entry point the group serves, where the shader's entry points bind different
    /// subsets of one group number (the direct light's group 2, the ISM's pull and push;
    /// `vs_x+fs_x` for a raster pipeline's two stages); None: the group is every binding the
    /// shader declares under its number.
    pub entry: Option<&'static str>,
    pub visibility: wgpu::ShaderStages,
    pub list: &'static [Binding],
}

impl Bindings {
    /// The layout entries, in the description's order.
    pub fn layout_entries(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        let vis = self.visibility;
        self.list
            .iter()
            .map(|b| match b.kind {
                Kind::Uniform => bgl::uniform(b.binding, vis),
                Kind::UniformDynamic => bgl::uniform_dynamic(b.binding, vis),
                Kind::StorageDynamic => bgl::storage_dynamic(b.binding, vis),
                Kind::Storage { read_only } => bgl::storage(b.binding, vis, read_only),
                Kind::Texture { filterable } => bgl::texture(b.binding, vis, filterable),
                Kind::TextureArray { filterable } => bgl::texture_array(b.binding, vis, filterable),
                Kind::UintTexture => bgl::uint_texture(b.binding, vis),
                Kind::UintTextureArray => bgl::uint_texture_array(b.binding, vis),
                Kind::Depth => bgl::depth(b.binding, vis),
                Kind::DepthArray => bgl::depth_array(b.binding, vis),
                Kind::StorageTexture(format) => {
                    wgpu::BindGroupLayoutEntry { visibility: vis, ..bgl::storage_texture(b.binding, format) }
                }
                Kind::StorageTextureArray(format) => {
                    wgpu::BindGroupLayoutEntry { visibility: vis, ..bgl::storage_texture_array(b.binding, format) }
                }
                Kind::StorageTextureReadWrite(format) => {
                    wgpu::BindGroupLayoutEntry { visibility: vis, ..bgl::storage_texture_read_write(b.binding, format) }
                }
                Kind::Sampler(ty) => bgl::sampler(b.binding, vis, ty),
            })
            .collect()
    }

    /// The bind group layout of the description.
    pub fn layout(&self, device: &wgpu::Device) -> wgpu::BindGroupLayout {
        self.layout_labelled(device, self.label)
    }

    /// The layout under another label: a pass that binds an equal group of its own (the
    /// G-buffer's camera in each light's G-buffer; WebGPU: groups of equal layouts are
    /// interchangeable).
    pub fn layout_labelled(&self, device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
        let entries = self.layout_entries();
        let layout =
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries });
        crate::counters::capture::remember_layout(&layout, &entries);
        layout
    }

    /// The bind group of `layout` (made by [`Self::layout`]) with `resources` in the
    /// description's order. Panics when their number differs from the description's: a
    /// programming error, found by the first frame of any test that runs the pass.
    pub fn group<'a>(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        resources: impl IntoIterator<Item = wgpu::BindingResource<'a>>,
    ) -> wgpu::BindGroup {
        self.group_labelled(device, self.label, layout, resources)
    }

    /// [`Self::group`] under another label (one group per material, per light, per level).
    pub fn group_labelled<'a>(
        &self,
        device: &wgpu::Device,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        resources: impl IntoIterator<Item = wgpu::BindingResource<'a>>,
    ) -> wgpu::BindGroup {
        let resources: Vec<wgpu::BindingResource> = resources.into_iter().collect();
        let n = (resources.len(), self.list.len());
        assert_eq!(n.0, n.1, "{}: {} resources for {} bindings", self.label, n.0, n.1);
        let entries: Vec<wgpu::BindGroupEntry> = self
            .list
            .iter()
            .zip(resources)
            .map(|(b, resource)| wgpu::BindGroupEntry { binding: b.binding, resource })
            .collect();
        device.counted_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
    }
}
