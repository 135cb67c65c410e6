// Per-pixel SG shading over the cut (`render::gpu::sg_shade`), second of two passes: each pixel
// sample's indirect radiance is the sum of its (sample, cut node) pairs' values from `sg_shade`
// and `sg_shade_clusters` (its cut's leaves, then its inner nodes), added to what earlier
// lights left. Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> params: GpuShadeParams;
@group(0) @binding(1) var<storage, read> points: array<GpuShadePoint>;
@group(0) @binding(2) var<storage, read> pair_values: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> radiance: array<vec4<f32>>;

@compute @workgroup_size(64)
fn sg_shade_sum(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = params.point_first + gid.x;
    if (i >= params.point_end) {
        return;
    }
    let pt = points[i];
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < pt.cut_count; k = k + 1u) {
        sum += pair_values[pt.pair_start - params.first + k].xyz;
    }
    radiance[i] = radiance[i] + vec4<f32>(sum, 0.0);
}
