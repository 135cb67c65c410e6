// Separable Gaussian blur (σ = radius / 2, clamped at the edges) of the faces (one per z) of a
// variance shadow map, one direction per dispatch. Rust twin: `visibility::vsm`'s `blur`.
// Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> params: GpuBlurParams;
@group(0) @binding(1) var<storage, read> src: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read_write> dst: array<vec2<f32>>;

@compute @workgroup_size(8, 8, 1)
fn vsm_blur(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = params.resolution;
    if (gid.x >= n || gid.y >= n) {
        return;
    }
    let base = gid.z * n * n;
    let r = i32(params.radius);
    let sigma = f32(params.radius) * 0.5;
    var total = 0.0;
    var sum = vec2<f32>(0.0);
    for (var k = -r; k <= r; k = k + 1) {
        let w = exp(-f32(k * k) / (2.0 * sigma * sigma));
        var x = i32(gid.x);
        var y = i32(gid.y);
        if (params.vertical == 0u) {
            x = clamp(x + k, 0, i32(n) - 1);
        } else {
            y = clamp(y + k, 0, i32(n) - 1);
        }
        sum += w * src[base + u32(y) * n + u32(x)];
        total += w;
    }
    dst[base + gid.y * n + gid.x] = sum / total;
}
