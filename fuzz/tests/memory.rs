//! Issue #19: "a 2³¹-element accessor must be refused before it allocates". This test binary
//! installs the fuzzer's counting allocator (it has this one test, so nothing else allocates
//! meanwhile) and checks that every 2³¹-element accessor of [`huge_accessor_cases`] is
//! refused with an error naming the accessor or view while the live heap grows by less than
//! 16 MiB, and that no glTF regression input takes the fuzzer's default cap (512 MiB).

use std::path::Path;

use gi_lab_fuzz::alloc::{self, CountingAlloc};
use gi_lab_fuzz::hostile::huge_accessor_cases;
use gi_render::scene::{LoadOptions, load_gltf_bytes};

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

/// The most a 2³¹-element accessor may add to the live heap before it is refused.
const BUDGET: usize = 16 << 20;
/// The fuzzer's default memory cap, which no regression input may reach.
const CAP: usize = 512 << 20;

/// Loads `bytes`; returns the result's message (None when it loaded) and how much the live
/// heap grew at its peak.
fn load_measured(bytes: &[u8]) -> (Option<String>, usize) {
    let before = alloc::live();
    alloc::reset_peak();
    let result = load_gltf_bytes(bytes, None, &LoadOptions::default());
    let grew = alloc::peak().saturating_sub(before);
    (result.err().map(|e| e.to_string()), grew)
}

#[test]
fn huge_counts_are_refused_before_they_allocate() {
    let cases = huge_accessor_cases();
    assert!(cases.len() >= 5);
    for case in &cases {
        let (error, grew) = load_measured(&case.bytes);
        let message = error.unwrap_or_else(|| panic!("{}: loaded", case.name));
        assert!(grew < BUDGET, "{}: the heap grew by {grew} bytes before the refusal: {message}", case.name);
        assert!(
            message.contains("accessor") || message.contains("buffer view"),
            "{}: the error does not name the accessor or view: {message}",
            case.name
        );
        println!("{}: +{grew} bytes: {message}", case.name);
    }
    // The glTF regressions stay under the fuzzer's default cap, loaded or refused (one
    // declared 2²⁶ vertices of a 37-byte meshopt stream and allocated 768 MiB before the
    // decoder refused it; one read a zero-filled accessor of 2²² vertices in four primitives,
    // 1.3 GB; a JPEG header declared 12800 × 12800 pixels, 1.7 GB).
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("regressions/gltf");
    let mut files = 0;
    for entry in std::fs::read_dir(&dir).expect("fuzz/regressions/gltf").filter_map(Result::ok) {
        let bytes = std::fs::read(entry.path()).expect("read");
        let (error, grew) = load_measured(&bytes);
        assert!(grew < CAP, "{}: the heap grew by {grew} bytes ({error:?})", entry.path().display());
        files += 1;
    }
    assert!(files >= 2, "{files} glTF regression files");
}
