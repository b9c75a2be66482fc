// The movement buffer's reprojection (Knecht 002 §3.5.1; W of Soler et al. 004 Eq. 6): pixel
// p of this frame was at the nearest texel of p + m(p) in the previous frame. Returns
// (−1, −1) when that texel lies outside the `size` image.
fn previous_texel(p: vec2<i32>, motion: vec2<f32>, size: vec2<u32>) -> vec2<i32> {
    let q = vec2<i32>(floor(vec2<f32>(p) + 0.5 + motion));
    if (q.x < 0 || q.y < 0 || q.x >= i32(size.x) || q.y >= i32(size.y)) {
        return vec2<i32>(-1, -1);
    }
    return q;
}
