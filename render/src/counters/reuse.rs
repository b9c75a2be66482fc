//! Views and bind groups made again for the same resources are the same objects (issue #38
//! point 2: "bind groups and views cached and rebuilt on change only").
//!
//! The passes describe their views and bind groups where they record, every frame; the first
//! request makes the object and later requests with the same description get it back. A
//! description is the label, the layout or texture, and the identity of every resource
//! (wgpu compares and hashes its handles by identity), so a resize or a settings change that
//! makes new textures or buffers makes new views and groups by itself, and nothing has to
//! be invalidated by hand. An entry that no request has asked for in
//! [`DROP_AFTER_FRAMES`] frames is dropped (a resize's old textures are freed then); the
//! cache holds what it made alive, so a handle's identity is never reused while it is cached.

use std::cell::RefCell;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};

/// Frames an unused view or bind group stays cached.
pub const DROP_AFTER_FRAMES: u64 = 3;

#[derive(Default)]
struct Cache {
    frame: u64,
    views: Table<wgpu::TextureView>,
    groups: Table<wgpu::BindGroup>,
}

thread_local! {
    static CACHE: RefCell<Cache> = RefCell::new(Cache::default());
}

/// A hasher seeded with the current context (handles of two instances share ids).
fn hasher() -> std::collections::hash_map::DefaultHasher {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    super::context().hash(&mut h);
    h
}

pub(crate) fn view_key(t: &wgpu::Texture, d: &wgpu::TextureViewDescriptor) -> u64 {
    let mut h = hasher();
    t.hash(&mut h);
    d.label.hash(&mut h);
    d.format.hash(&mut h);
    d.dimension.hash(&mut h);
    d.usage.hash(&mut h);
    d.aspect.hash(&mut h);
    d.base_mip_level.hash(&mut h);
    d.mip_level_count.hash(&mut h);
    d.base_array_layer.hash(&mut h);
    d.array_layer_count.hash(&mut h);
    h.finish()
}

fn hash_buffer(b: &wgpu::BufferBinding, h: &mut impl Hasher) {
    b.buffer.hash(h);
    b.offset.hash(h);
    b.size.hash(h);
}

/// The key of a bind group's description; None when it holds a resource kind this cache
/// does not know (such groups are always made anew).
pub(crate) fn group_key(d: &wgpu::BindGroupDescriptor) -> Option<u64> {
    let mut h = hasher();
    d.label.hash(&mut h);
    d.layout.hash(&mut h);
    for e in d.entries {
        e.binding.hash(&mut h);
        match &e.resource {
            wgpu::BindingResource::Buffer(b) => {
                0u8.hash(&mut h);
                hash_buffer(b, &mut h);
            }
            wgpu::BindingResource::BufferArray(bs) => {
                1u8.hash(&mut h);
                bs.iter().for_each(|b| hash_buffer(b, &mut h));
            }
            wgpu::BindingResource::Sampler(s) => {
                2u8.hash(&mut h);
                s.hash(&mut h);
            }
            wgpu::BindingResource::SamplerArray(ss) => {
                3u8.hash(&mut h);
                ss.iter().for_each(|s| s.hash(&mut h));
            }
            wgpu::BindingResource::TextureView(v) => {
                4u8.hash(&mut h);
                v.hash(&mut h);
            }
            wgpu::BindingResource::TextureViewArray(vs) => {
                5u8.hash(&mut h);
                vs.iter().for_each(|v| v.hash(&mut h));
            }
            _ => return None,
        }
    }
    Some(h.finish())
}

type Table<T> = HashMap<u64, (T, u64)>;

/// The object cached under `key` in the table `pick` chooses, marked as used this frame.
fn lookup<T: Clone>(key: u64, pick: fn(&mut Cache) -> &mut Table<T>) -> Option<T> {
    CACHE.with(|c| {
        let mut c = c.borrow_mut();
        let frame = c.frame;
        pick(&mut c).get_mut(&key).map(|(v, used)| {
            *used = frame;
            v.clone()
        })
    })
}

/// Caches `v` under `key` in the table `pick` chooses.
fn keep<T: Clone>(key: u64, v: &T, pick: fn(&mut Cache) -> &mut Table<T>) {
    CACHE.with(|c| {
        let mut c = c.borrow_mut();
        let frame = c.frame;
        pick(&mut c).insert(key, (v.clone(), frame));
    });
}

/// The cached view for `key`, if any (marked as used this frame).
pub(crate) fn cached_view(key: u64) -> Option<wgpu::TextureView> {
    lookup(key, |c| &mut c.views)
}

pub(crate) fn keep_view(key: u64, v: &wgpu::TextureView) {
    keep(key, v, |c| &mut c.views)
}

/// The cached bind group for `key`, if any (marked as used this frame).
pub(crate) fn cached_group(key: u64) -> Option<wgpu::BindGroup> {
    lookup(key, |c| &mut c.groups)
}

pub(crate) fn keep_group(key: u64, g: &wgpu::BindGroup) {
    keep(key, g, |c| &mut c.groups)
}

/// Ends a frame: drops what no request used for [`DROP_AFTER_FRAMES`] frames.
pub(crate) fn end_frame() {
    CACHE.with(|c| {
        let mut c = c.borrow_mut();
        c.frame += 1;
        let frame = c.frame;
        let fresh = |used: &u64| frame.saturating_sub(*used) <= DROP_AFTER_FRAMES;
        c.groups.retain(|_, (_, used)| fresh(used));
        c.views.retain(|_, (_, used)| fresh(used));
    });
}

/// Views and bind groups cached now.
pub fn cached() -> (usize, usize) {
    CACHE.with(|c| {
        let c = c.borrow();
        (c.views.len(), c.groups.len())
    })
}

/// Drops every cached view and bind group of this thread (memory checkpoints: what stays
/// alive then is what the renderers hold themselves).
pub fn clear() {
    CACHE.with(|c| {
        let mut c = c.borrow_mut();
        c.views.clear();
        c.groups.clear();
    });
}
