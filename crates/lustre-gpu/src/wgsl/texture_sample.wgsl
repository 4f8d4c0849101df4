// module texture_sample: the CPU's texture lookup (lustre_scene::Texture::sample, and
// `scalar_at`, TexturedScalar::at), for the passes that read textures: the raster G-buffer, the
// light-map and view-dependent shading, and the passes that evaluate textured records
// (measured::material_eval_source). The texels of every uploaded texture are RGBA f32
// (lustre_gpu::gbuffer::pack_textures).
// Requires (the pass defines): fn texture_texel(i: u32) -> vec4<f32>.
// Requires (the pass defines): fn texture_info(t: u32) -> vec4<u32>.

fn wrap(i: f32, n: u32) -> u32 {
    let m = i32(n);
    return u32(((i32(i) % m) + m) % m);
}

// `lustre_scene::Texture::sample`: bilinear, repeat, texel centres at ((x + ½)/W, (y + ½)/H).
fn texture_sample(t: u32, uv: vec2<f32>) -> vec4<f32> {
    let info = texture_info(t);
    let w = info.y;
    let h = info.z;
    let x = uv.x * f32(w) - 0.5;
    let y = uv.y * f32(h) - 0.5;
    let x0 = floor(x);
    let y0 = floor(y);
    let fx = x - x0;
    let fy = y - y0;
    let xa = wrap(x0, w);
    let xb = wrap(x0 + 1.0, w);
    let ya = wrap(y0, h);
    let yb = wrap(y0 + 1.0, h);
    let t00 = texture_texel(info.x + ya * w + xa);
    let t10 = texture_texel(info.x + ya * w + xb);
    let t01 = texture_texel(info.x + yb * w + xa);
    let t11 = texture_texel(info.x + yb * w + xb);
    let top = t00 + (t10 - t00) * fx;
    let bottom = t01 + (t11 - t01) * fx;
    return top + (bottom - top) * fy;
}

// `TexturedScalar::at`: factor × the texture's channel at the uv set it names.
fn scalar_at(q: vec4<f32>, uv0: vec2<f32>, uv1: vec2<f32>) -> f32 {
    let t = bitcast<i32>(q.y);
    if t < 0 {
        return q.x;
    }
    var uv = uv0;
    if bitcast<u32>(q.z) == 1u {
        uv = uv1;
    }
    return q.x * texture_sample(u32(t), uv)[bitcast<u32>(q.w)];
}
