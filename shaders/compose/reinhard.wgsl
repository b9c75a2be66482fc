// Reinhard et al. [RSSF02]'s global photographic operator, shared by the compose (which tone
// maps as it composes, issue #38) and compose/tonemap.wgsl (the first frame's exact pass):
//   L = s · Lw with s = 2^EV (manual) or s = 2^EV · a / L̄w (automatic, key a; Eq. 2),
//   Ld = L (1 + L / L²white) / (1 + L) (Eq. 4),
// applied to the colour by the ratio Ld / Lw, then sRGB-encoded. CPU twin: cpu::tonemap.

fn srgb_encode(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

// Rec. 709 luminance of a linear colour.
fn luminance_of(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// The display value of HDR colour `hdr`: tone = (2^EV, a, L_white, automatic (> 0.5) or
// manual), log_avg = L̄w.
fn reinhard(hdr: vec3<f32>, tone: vec4<f32>, log_avg: f32) -> vec3<f32> {
    let c = max(hdr, vec3<f32>(0.0));
    let lw = luminance_of(c);
    var s = tone.x;
    if (tone.w > 0.5) {
        s = s * tone.y / max(log_avg, 1e-6);
    }
    let l = s * lw;
    let lwhite2 = tone.z * tone.z;
    let ld = l * (1.0 + l / lwhite2) / (1.0 + l);
    var mapped = vec3<f32>(0.0);
    if (lw > 0.0) {
        mapped = c * (ld / lw);
    }
    return srgb_encode(clamp(mapped, vec3<f32>(0.0), vec3<f32>(1.0)));
}
