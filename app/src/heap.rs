//! The `gi-lab` binary's heap, counted: [`CountingAlloc`] forwards to the system allocator
//! and keeps the bytes live. It is the binary's `#[global_allocator]` (app/src/main.rs), so
//! it counts what Rust code allocates (GI Lab, wgpu, egui, naga) and not what C libraries
//! allocate with malloc (the Vulkan driver). The soak judges it where it cannot judge the
//! resident memory (a driver that grows by itself, `cli::soak_memory`).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

static LIVE: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, counted.
pub struct CountingAlloc;

/// Bytes the Rust code of this process holds, if [`CountingAlloc`] is its global allocator
/// (a process that allocates through it always holds some: none counted means not installed).
pub fn live_bytes() -> Option<usize> {
    Some(LIVE.load(Ordering::Relaxed)).filter(|&b| b > 0)
}

// SAFETY: every call is forwarded to `System` with the same arguments; only counters change.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            LIVE.fetch_add(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            LIVE.fetch_add(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_add(new_size, Ordering::Relaxed);
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }
}
