// Random and quasi-random numbers shared by the VPL passes.
// CPU twins: cpu::knecht::{pcg_hash, halton}.

// PCG hash (Jarzynski & Olano, JCGT 2020).
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Element `index_in` of the Halton sequence in base `base`, in [0, 1) (the radical inverse;
// Halton 1964).
fn halton(index_in: u32, base: u32) -> f32 {
    var index = index_in;
    var f = 1.0;
    var r = 0.0;
    while (index > 0u) {
        f = f / f32(base);
        r = r + f * f32(index % base);
        index = index / base;
    }
    return r;
}
