// Linear RGB to 8-bit sRGB: v ↦ round(255 · OETF(operator(2^exposure · v))) per channel, one
// pixel per invocation, packed as RGBA8 (alpha 255). Rust twin: `image::tonemap::to_srgb8`.
// Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> params: GpuTonemapParams;
@group(0) @binding(1) var<storage, read> linear: array<f32>;
@group(0) @binding(2) var<storage, read_write> display: array<u32>;

fn quantize8(v: f32) -> u32 {
    return u32(round(clamp(v, 0.0, 1.0) * 255.0));
}

@compute @workgroup_size(64)
fn tonemap(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.y * params.row_stride + gid.x;
    if (i >= params.count) {
        return;
    }
    var out = 0xff000000u;
    for (var c = 0u; c < 3u; c = c + 1u) {
        let v = linear[3u * i + c] * params.scale;
        let d = srgb_oetf(tone_operator_apply(params.tone_operator, v));
        out = out | (quantize8(d) << (8u * c));
    }
    display[i] = out;
}
