//! Explain a pixel (issue #42): every technique's GPU replay against the buffers the frame
//! wrote and against its CPU twin, and the window's key, menu, pane and overlay. One test
//! binary for all of them (one link instead of five).

mod gautron;
mod hcb;
mod soler;
mod vpl;
mod window;

/// The byte size of WGSL struct `name` in shader `entry` (as `gi_render::shaders` resolves it).
fn wgsl_size(entry: &str, name: &str) -> usize {
    let src = gi_render::shaders::resolve(entry).expect("resolves");
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    module
        .types
        .iter()
        .find_map(|(_, t)| match (&t.name, &t.inner) {
            (Some(n), naga::TypeInner::Struct { span, .. }) if n == name => Some(*span as usize),
            _ => None,
        })
        .unwrap_or_else(|| panic!("{entry}: struct {name} not found"))
}

/// Every replay's output structs have their WGSL twins' sizes (the decode reads them by size).
#[test]
fn the_replays_structs_have_the_sizes_of_their_wgsl_twins() {
    use gi_render::passes::{gautron, knecht, reference, soler};
    use std::mem::size_of;
    let pairs = [
        ("knecht/interleave/explain.wgsl", "VplTerm", size_of::<reference::explain::GpuTerm>()),
        ("knecht/interleave/explain.wgsl", "WindowPixel", size_of::<knecht::explain::GpuWindow>()),
        ("knecht/interleave/explain.wgsl", "Header", size_of::<knecht::explain::GpuHeader>()),
        ("soler/explain.wgsl", "Entry", size_of::<soler::explain::GpuEntry>()),
        ("soler/explain.wgsl", "Header", size_of::<soler::explain::GpuHeader>()),
        ("soler/explain_ring.wgsl", "RingOut", size_of::<soler::explain::GpuRingTerm>()),
        ("reference/explain.wgsl", "VplTerm", size_of::<reference::explain::GpuTerm>()),
        ("reference/explain.wgsl", "Header", size_of::<reference::explain::GpuHeader>()),
        ("gautron/explain.wgsl", "Entry", size_of::<gautron::explain::GpuEntry>()),
        ("gautron/explain.wgsl", "Header", size_of::<gautron::explain::GpuHeader>()),
    ];
    for (entry, name, rust) in pairs {
        assert_eq!(wgsl_size(entry, name), rust, "{entry}: {name}");
    }
}
