// Virtual point lights (stage 3) and their exact visibility maps (stage 4).
// Rust twin: passes::vpl::GpuVpl (size checked by the shader test).
//
// A VPL stands for the light that reached a small patch of surface y: it carries the
// incident flux Φ (W) and the direction ω_in toward the light it came from, so that its
// radiant intensity toward x is I(y→x) = Φ · f(y; ω_in, y→x) · max(0, n_y·(y→x)), with the one
// BRDF f of common/brdf.wgsl (the glossy VPL of Knecht 002 Eq. 4.8 is this with the
// specular lobe of f; a diffuse VPL is f = c·DI/π).
#import common/brdf.wgsl
struct Vpl {
    // xyz: position on the surface; w: 1 for a VPL, 0 for an empty slot.
    position: vec4<f32>,
    // xyz: unit surface normal; w: diffuse intensity DI.
    normal: vec4<f32>,
    // rgb: incident flux Φ in W; a: specular intensity SI.
    flux: vec4<f32>,
    // xyz: unit direction from the surface toward the light; w: specular power SP.
    incident: vec4<f32>,
    // rgb: surface colour c; a: unused.
    albedo: vec4<f32>,
}

// Faces of a VPL's visibility map: the hemisphere around n is covered by five 90° faces
// of a cube oriented on the normal: +n, +t, −t, +b, −b (the −n face sees nothing a VPL lights).
const VPL_FACES: u32 = 5u;

// Orthonormal basis (t, b, n) around a unit n (Duff et al., JCGT 2017, "Building an
// orthonormal basis, revisited").
fn vpl_basis(n: vec3<f32>) -> mat3x3<f32> {
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return mat3x3<f32>(t, bt, n);
}

// (right, up, forward) of face `face` of the cube on basis `tbn`.
fn vpl_face_axes(tbn: mat3x3<f32>, face: u32) -> mat3x3<f32> {
    let t = tbn[0];
    let b = tbn[1];
    let n = tbn[2];
    switch face {
        case 0u: { return mat3x3<f32>(t, b, n); }
        case 1u: { return mat3x3<f32>(-n, b, t); }
        case 2u: { return mat3x3<f32>(n, b, -t); }
        case 3u: { return mat3x3<f32>(t, -n, b); }
        default: { return mat3x3<f32>(t, n, -b); }
    }
}

// The face that sees direction q (in world space) from the VPL, for q in the upper hemisphere.
fn vpl_face_of(tbn: mat3x3<f32>, q: vec3<f32>) -> u32 {
    let l = vec3<f32>(dot(q, tbn[0]), dot(q, tbn[1]), dot(q, tbn[2]));
    let a = abs(l);
    if (l.z >= a.x && l.z >= a.y) {
        return 0u;
    }
    if (a.x >= a.y) {
        return select(2u, 1u, l.x > 0.0);
    }
    return select(4u, 3u, l.y > 0.0);
}

// Clip coordinates of p in a 90° perspective face (depth in [0, 1] from near to far, as the
// D3D-style projection of the primary shadow maps).
fn vpl_face_clip(eye: vec3<f32>, axes: mat3x3<f32>, p: vec3<f32>, near: f32, far: f32) -> vec4<f32> {
    let q = p - eye;
    let z = dot(q, axes[2]);
    let a = far / (far - near);
    return vec4<f32>(dot(q, axes[0]), dot(q, axes[1]), a * z - a * near, z);
}

// Top-left texel of tile `tile` in an atlas of `cols` columns of `size`² tiles.
fn vpl_tile_origin(tile: u32, cols: u32, size: u32) -> vec2<u32> {
    return vec2<u32>(tile % cols, tile / cols) * size;
}

// Irradiance at x (normal nx) from one VPL, visibility not included: Φ · f_y(ω_in, y→x) ·
// cos θ_y · cos θ_x / max(d², d_min²) (Knecht 002 Eq. 4.7–4.8; dmin2 = d_min²). A VPL closer
// than the near field's cut (near2 = cut², 0: none; `pipeline.near_field`) sends nothing:
// the screen-space gather takes that light.
fn vpl_irradiance(vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, dmin2: f32, near2: f32) -> vec3<f32> {
    let w = vpl.position.xyz - x;
    let d2 = dot(w, w);
    if (d2 < near2) {
        return vec3<f32>(0.0);
    }
    let l = w * inverseSqrt(max(d2, 1e-12));
    let cos_x = dot(nx, l);
    let cos_y = -dot(vpl.normal.xyz, l);
    if (cos_x <= 0.0 || cos_y <= 0.0) {
        return vec3<f32>(0.0);
    }
    let f_y = brdf_eval(vpl.normal.xyz, vpl.incident.xyz, -l, vpl.albedo.rgb, vpl.normal.w, vpl.flux.a, vpl.incident.w);
    return vpl.flux.rgb * f_y * cos_y * cos_x / max(d2, dmin2);
}

// Radiance toward the eye at `eye` that one VPL sends to x (normal nx, colour c, DI, SI, SP),
// visibility not included: Knecht 002 Eq. 4.7–4.9 with the one BRDF at both ends — the
// irradiance times f_x (CPU twin: cpu::knecht::vpl_radiance, where the reading is documented).
fn vpl_radiance(vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, eye: vec3<f32>, c: vec3<f32>, mat: vec3<f32>, dmin2: f32, near2: f32) -> vec3<f32> {
    let e = vpl_irradiance(vpl, x, nx, dmin2, near2);
    if (max(e.r, max(e.g, e.b)) <= 0.0) {
        return vec3<f32>(0.0);
    }
    return e * vpl_receiver_brdf(vpl, x, nx, eye, c, mat);
}

// f_x of Eq. 4.9: the receiver's BRDF from the VPL toward the eye (vpl_radiance's factor; the
// gather at tiles also keeps the irradiance apart for the demodulated filter, issue #51).
fn vpl_receiver_brdf(vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, eye: vec3<f32>, c: vec3<f32>, mat: vec3<f32>) -> vec3<f32> {
    let l = normalize(vpl.position.xyz - x);
    return brdf_eval(nx, l, normalize(eye - x), c, mat.x, mat.y, mat.z);
}

// Exact visibility of x (receiver normal nx) from VPL i in a cube-face atlas (stage 4's
// exact maps): one depth comparison in the face that sees x. Biases are world offsets of the
// receiver in texels of that face at the receiver's distance. clip = (near, far, eye offset).
fn vpl_exact_visibility(atlas: texture_2d<f32>, i: u32, vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, clip: vec3<f32>, cols: u32, size: u32, depth_bias: f32, normal_offset: f32) -> f32 {
    let t = vpl_exact_depths(atlas, i, vpl, x, nx, clip, cols, size, depth_bias, normal_offset);
    return select(0.0, 1.0, t.x >= 0.0 && t.y <= t.x);
}

// The comparison behind vpl_exact_visibility: (the depth stored in the face's texel, the
// receiver's biased depth), both in the face's [0, 1] depth; (−1, 1) when x lies behind the
// face's eye. Explaining a pixel (knecht/interleave/explain.wgsl) shows both.
fn vpl_exact_depths(atlas: texture_2d<f32>, i: u32, vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, clip: vec3<f32>, cols: u32, size: u32, depth_bias: f32, normal_offset: f32) -> vec2<f32> {
    let n = vpl.normal.xyz;
    let eye = vpl.position.xyz + n * clip.z;
    let d = distance(x, eye);
    let texel = 2.0 * d / f32(size);
    let to_eye = (eye - x) / max(d, 1e-6);
    let p = x + nx * texel * normal_offset + to_eye * texel * depth_bias;
    let tbn = vpl_basis(n);
    let face = vpl_face_of(tbn, p - eye);
    let c = vpl_face_clip(eye, vpl_face_axes(tbn, face), p, clip.x, clip.y);
    if (c.w <= 0.0) {
        return vec2<f32>(-1.0, 1.0);
    }
    let ndc = c.xyz / c.w;
    let origin = vpl_tile_origin(i * VPL_FACES + face, cols, size);
    let uv = clamp(vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5), vec2<f32>(0.0), vec2<f32>(1.0));
    let t = min(vec2<u32>(uv * f32(size)), vec2<u32>(size - 1u));
    return vec2<f32>(textureLoad(atlas, origin + t, 0).x, ndc.z);
}
