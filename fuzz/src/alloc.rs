//! A counting global allocator with a cap on the live heap, for the fuzzer's memory cap.
//!
//! [`CountingAlloc`] wraps the system allocator and keeps the number of live bytes and their
//! peak. It is installed as the `#[global_allocator]` of the `gi-lab-fuzz` binary (and of the
//! test that measures the 2³¹-element accessors), never of the library, so the CI tests and
//! other crates are unaffected. With a cap set ([`set_cap`]), an allocation that would take
//! the live total over it is not made: the input being run ([`set_current_input`]) is
//! written to the crashes folder and the process exits with status 3 and a message naming
//! the allocation. The handler itself may allocate (a guard lets those through), but it
//! formats the crash file's name on the stack.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write as _;
use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicUsize, Ordering};

/// Live bytes allocated through [`CountingAlloc`].
static LIVE: AtomicUsize = AtomicUsize::new(0);
/// The largest value [`LIVE`] has had since the last [`reset_peak`].
static PEAK: AtomicUsize = AtomicUsize::new(0);
/// The cap on [`LIVE`] (usize::MAX: no cap).
static CAP: AtomicUsize = AtomicUsize::new(usize::MAX);
/// Set while the over-cap handler runs: its own allocations are let through.
static IN_HANDLER: AtomicBool = AtomicBool::new(false);
/// The input being executed (pointer and length), for the over-cap handler.
static INPUT_PTR: AtomicPtr<u8> = AtomicPtr::new(std::ptr::null_mut());
static INPUT_LEN: AtomicUsize = AtomicUsize::new(0);
/// The crash file prefix (`<crashes>/<target>-`), leaked once at start-up.
static PREFIX_PTR: AtomicPtr<u8> = AtomicPtr::new(std::ptr::null_mut());
static PREFIX_LEN: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, counted.
pub struct CountingAlloc;

/// Bytes currently allocated.
pub fn live() -> usize {
    LIVE.load(Ordering::Relaxed)
}

/// The peak of [`live`] since the last [`reset_peak`].
pub fn peak() -> usize {
    PEAK.load(Ordering::Relaxed)
}

/// Restarts the peak at the current live total.
pub fn reset_peak() {
    PEAK.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
}

/// Sets the cap on live bytes (None: no cap).
pub fn set_cap(bytes: Option<usize>) {
    CAP.store(bytes.unwrap_or(usize::MAX), Ordering::Relaxed);
}

/// Where the over-cap handler writes the input: `<prefix><hash>.bin`, for example
/// `fuzz/crashes/gltf-` (leaked: set once per process).
pub fn set_crash_prefix(prefix: String) {
    let leaked: &'static mut str = prefix.leak();
    PREFIX_LEN.store(leaked.len(), Ordering::Relaxed);
    PREFIX_PTR.store(leaked.as_mut_ptr(), Ordering::Release);
}

/// Records the input being executed (the caller keeps it alive until [`clear_current_input`]).
pub fn set_current_input(input: &[u8]) {
    INPUT_LEN.store(input.len(), Ordering::Relaxed);
    INPUT_PTR.store(input.as_ptr().cast_mut(), Ordering::Release);
}

/// Forgets the input recorded by [`set_current_input`].
pub fn clear_current_input() {
    INPUT_PTR.store(std::ptr::null_mut(), Ordering::Release);
    INPUT_LEN.store(0, Ordering::Relaxed);
}

/// FNV-1a (64-bit) of `bytes`: the name of a crash file.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01B3))
}

/// Counts `n` more live bytes; false when that would pass the cap (nothing counted then).
fn reserve(n: usize) -> bool {
    let cap = CAP.load(Ordering::Relaxed);
    let before = LIVE.fetch_add(n, Ordering::Relaxed);
    let after = before.saturating_add(n);
    if after > cap && !IN_HANDLER.load(Ordering::Relaxed) {
        LIVE.fetch_sub(n, Ordering::Relaxed);
        return false;
    }
    PEAK.fetch_max(after, Ordering::Relaxed);
    true
}

/// The allocation of `size` bytes would pass the cap: saves the input and exits (status 3).
#[cold]
fn over_cap(size: usize) -> ! {
    if IN_HANDLER.swap(true, Ordering::SeqCst) {
        std::process::abort();
    }
    let live = LIVE.load(Ordering::Relaxed);
    let cap = CAP.load(Ordering::Relaxed);
    let mut name = [0u8; 1024];
    let saved = save_input(&mut name);
    let mut err = std::io::stderr().lock();
    let _ = writeln!(
        err,
        "\nOVER THE MEMORY CAP: an allocation of {size} bytes would take the live heap from {live} to {} bytes, over the cap of {cap} bytes ({} MiB)",
        live.saturating_add(size),
        cap >> 20
    );
    match saved {
        Some(path) => {
            let _ = err.write_all(b"the input was saved to ");
            let _ = err.write_all(path);
            let _ = err.write_all(b"\n");
        }
        None => {
            let _ = writeln!(err, "(no input was being run, or it could not be saved)");
        }
    }
    let _ = err.flush();
    std::process::exit(3);
}

/// Writes the current input to `<prefix><hash>.bin`, formatting the name into `buf`;
/// returns the name written.
fn save_input(buf: &mut [u8; 1024]) -> Option<&[u8]> {
    let ptr = INPUT_PTR.load(Ordering::Acquire);
    let prefix_ptr = PREFIX_PTR.load(Ordering::Acquire);
    if ptr.is_null() || prefix_ptr.is_null() {
        return None;
    }
    // SAFETY: both were recorded from live slices: the prefix is leaked, and the runner keeps
    // the input alive until it clears it (it is blocked in this allocation meanwhile).
    let (input, prefix) = unsafe {
        (
            std::slice::from_raw_parts(ptr, INPUT_LEN.load(Ordering::Relaxed)),
            std::slice::from_raw_parts(prefix_ptr, PREFIX_LEN.load(Ordering::Relaxed)),
        )
    };
    let len = {
        let mut cursor = std::io::Cursor::new(&mut buf[..]);
        cursor.write_all(prefix).ok()?;
        write!(cursor, "{:016x}.bin", fnv1a(input)).ok()?;
        cursor.position() as usize
    };
    let name = &buf[..len];
    #[cfg(unix)]
    let path = std::path::Path::new(<std::ffi::OsStr as std::os::unix::ffi::OsStrExt>::from_bytes(name));
    #[cfg(not(unix))]
    let path = std::path::Path::new(std::str::from_utf8(name).ok()?);
    std::fs::File::create(path).and_then(|mut f| f.write_all(input)).ok()?;
    Some(name)
}

// SAFETY: every call is forwarded to `System` with the same arguments; only counters change.
unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if !reserve(layout.size()) {
            over_cap(layout.size());
        }
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.alloc(layout) };
        if p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if !reserve(layout.size()) {
            over_cap(layout.size());
        }
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.alloc_zeroed(layout) };
        if p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let old = layout.size();
        if new_size > old && !reserve(new_size - old) {
            over_cap(new_size - old);
        }
        // SAFETY: forwarded unchanged.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if p.is_null() {
            if new_size > old {
                LIVE.fetch_sub(new_size - old, Ordering::Relaxed);
            }
        } else if new_size < old {
            LIVE.fetch_sub(old - new_size, Ordering::Relaxed);
        }
        p
    }
}
