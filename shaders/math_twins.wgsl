// Runs one WGSL math function (shared/math.wgsl) over a table of inputs, for the GPU tests that
// compare each with its Rust twin (`render::gpu::twins`). Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> params: TwinParams;
@group(0) @binding(1) var<storage, read> queries: array<TwinQuery>;
@group(0) @binding(2) var<storage, read_write> results: array<vec4<f32>>;
// The node-bound twin's rows: a node and a receiver each, the point in `queries[i].a.xyz`.
@group(0) @binding(3) var<storage, read> nodes: array<GpuNodeBound>;
@group(0) @binding(4) var<storage, read> receivers: array<GpuReceiver>;
// The transport twins' rows: a lit triangle or a lit node each, the point in `queries[i].a.xyz`,
// the receiver's direction across its plane of incidence in `b.xyz`, the light in `c.xyz`.
@group(0) @binding(5) var<storage, read> leaves: array<GpuLeaf>;
@group(0) @binding(6) var<storage, read> lit_nodes: array<GpuLitNode>;

@compute @workgroup_size(64)
fn math_twins(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= params.count) {
        return;
    }
    let q = queries[i];
    var r = vec4<f32>(0.0);
    switch params.function {
        case 0u: {
            r.x = lobe_integral(q.a.x);
        }
        case 1u: {
            let a = GpuSg(q.a.xyz, q.a.w, q.b.xyz, 0.0);
            let b = GpuSg(q.c.xyz, q.c.w, q.d.xyz, 0.0);
            r = vec4<f32>(sg_inner_product(a, b), 0.0);
        }
        case 2u: {
            r.x = chebyshev_upper_bound(q.a.xy, q.a.z, q.a.w);
        }
        case 3u: {
            r.x = reduce_bleeding(q.a.x, q.a.y);
        }
        case 4u: {
            r.x = clamped_cosine_mean(q.a.x, q.a.y);
        }
        case 5u: {
            r.x = integrate_sg(q.a.xyz, q.a.w, q.b.xyz, q.c.xyz, q.d.xyz);
        }
        case 6u: {
            r = vec4<f32>(node_bound(nodes[i], q.a.xyz, receivers[i]), 0.0);
        }
        case 9u: {
            r.x = cosine_weighted(GpuSg(q.a.xyz, q.a.w, vec3<f32>(1.0), 0.0), vec3<f32>(q.b.w, q.c.w, q.d.w), q.b.xyz, q.c.xyz, q.d.xyz);
        }
        case 10u: {
            let m = GpuBrdf(q.c.xyz, u32(q.a.w), q.d.xyz, q.b.w, u32(q.c.w), 0u, 0u, 0u);
            r = vec4<f32>(brdf_eval(m, q.a.xyz, q.b.xyz), 0.0);
        }
        case 7u: {
            r = vec4<f32>(lit_triangle_shade(leaves[i], q.a.xyz, receivers[i], q.b.xyz), 0.0);
        }
        case 8u: {
            r = vec4<f32>(lit_scene_cluster(lit_nodes[i], q.c.xyz, q.a.xyz, receivers[i], q.b.xyz), 0.0);
        }
        default: {
            r = vec4<f32>(-1.0);
        }
    }
    results[i] = r;
}
