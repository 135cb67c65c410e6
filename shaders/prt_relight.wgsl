// PRT relighting: one dot product per vertex and colour channel.
//
// radiance[v].c = Σ_i transfer[v][i].c · lighting[i].c, over the n = order² SH coefficients.
// Rust twin: `precompute::prt::relight_cpu` (and `render::gpu::prt::relight`, which dispatches
// this shader over chunks of vertices so that no binding exceeds the device's limit).
// Layouts (plain f32 arrays, no vec3 padding):
//   transfer: [coefficient][rgb][vertex] (structure of arrays: the invocations of a workgroup
//             read consecutive addresses, which lavapipe's SIMD lanes load as vectors)
//   lighting: [coefficient][rgb]   radiance: [vertex][rgb]

struct Params {
    vertex_count: u32,
    coefficients: u32,
    // Invocations per row of the dispatch grid (workgroups in x × 64).
    row_stride: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> transfer: array<f32>;
@group(0) @binding(2) var<storage, read> lighting: array<f32>;
@group(0) @binding(3) var<storage, read_write> radiance: array<f32>;

@compute @workgroup_size(64)
fn prt_relight(@builtin(global_invocation_id) gid: vec3<u32>) {
    let v = gid.y * params.row_stride + gid.x;
    if (v >= params.vertex_count) {
        return;
    }
    let n = params.coefficients;
    let count = params.vertex_count;
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < n; i = i + 1u) {
        let base = 3u * i * count + v;
        let t = vec3<f32>(transfer[base], transfer[base + count], transfer[base + 2u * count]);
        let l = vec3<f32>(lighting[3u * i], lighting[3u * i + 1u], lighting[3u * i + 2u]);
        sum = sum + t * l;
    }
    radiance[3u * v] = sum.x;
    radiance[3u * v + 1u] = sum.y;
    radiance[3u * v + 2u] = sum.z;
}
