// Per-pixel SG shading over the cut (`render::gpu::sg_shade`), first of two passes: one
// invocation per (pixel sample, cut node) pair computes that node's one-bounce radiance at the
// sample — a leaf's exact SG transport over the triangle's solid angle, an inner node's
// clustered approximation clamped to its error bound — times the node's visibility from its map
// at a tree node; `sg_shade_sum` then adds up each sample's pairs. One invocation per pair
// rather than per sample because lavapipe ends every loop of an invocation once all its loops
// together have run 65,535 iterations (llvmpipe's LP_MAX_TGSI_LOOP_ITERATIONS; docs/gpu.md),
// and one leaf takes about a thousand. Two entry points, dispatched one after the other over
// the same points: `sg_shade` for the (sample, leaf) pairs, `sg_shade_clusters` for the
// (sample, inner node) pairs — each sample's cut lists its leaves first — because lavapipe runs
// all the code an entry point can reach, taken or not, so an inner node in a shader that also
// holds the leaf transport pays for the transport. Rust twin: the shading stage of
// `render::cpu::sg` with `--visibility approx` and `--cut vertex` (`LitScene::evaluate`,
// `LitTriangle::shade`, `LitScene::cluster`, `NodeMaps::visibility`); the transport functions
// are in shaders/shared/transport.wgsl. Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> params: GpuShadeParams;
@group(0) @binding(1) var<storage, read> points: array<GpuShadePoint>;
@group(0) @binding(2) var<storage, read> cut_nodes: array<u32>;
@group(0) @binding(3) var<storage, read> nodes: array<GpuLitNode>;
@group(0) @binding(4) var<storage, read> leaves: array<GpuLeaf>;
@group(0) @binding(5) var<storage, read> map_origins: array<GpuMapOrigin>;
@group(0) @binding(6) var<storage, read> atlas: array<vec2<f32>>;
@group(0) @binding(7) var<storage, read_write> pair_values: array<vec4<f32>>;

// `visibility::vsm::bilinear_moments` over map `m` of the atlas.
fn bilinear_moments(m: u32, u: f32, v: f32) -> vec2<f32> {
    let n = params.map_res;
    let base = m * n * n;
    let b = bilinear_texels(n, u, v);
    return bilinear_mix(b, atlas[base + b.i00], atlas[base + b.i10], atlas[base + b.i01], atlas[base + b.i11]);
}

// `NodeMaps::visibility`: the Chebyshev bound of map `m` (paraboloid about its origin's normal)
// at p; 1 where the map knows nothing (no map, p below its horizon, no depth there).
fn node_maps_visibility(m: u32, p: vec3<f32>) -> f32 {
    if (m == NONE) {
        return 1.0;
    }
    let o = map_origins[m];
    let v = p - o.position;
    let z = length(v);
    if (!(z > 0.0)) {
        return 1.0;
    }
    let w = v / z;
    let d = vec3<f32>(dot(w, o.t), dot(w, o.b), dot(w, o.n));
    if (!(d.z > 0.0)) {
        return 1.0;
    }
    let mo = bilinear_moments(m, d.x / (1.0 + d.z), d.y / (1.0 + d.z));
    if (!(mo.x > 0.0)) {
        return 1.0;
    }
    return chebyshev_upper_bound(mo, z * (1.0 - params.map_bias), o.min_variance);
}

// The point among params.point_first..point_end holding pair `pair` of a kind whose pairs
// start, per point, at `leaf_pair_start` (leaves) or `pair_start − leaf_pair_start` (inner
// nodes): the last point starting at or before it (a point without such pairs shares its
// start with the next).
fn point_of(pair: u32, leaves: bool) -> u32 {
    var lo = params.point_first;
    var hi = params.point_end;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        var start = points[mid].leaf_pair_start;
        if (!leaves) {
            start = points[mid].pair_start - start;
        }
        if (start <= pair) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

@compute @workgroup_size(64)
fn sg_shade(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.count) {
        return;
    }
    let pair = params.leaf_first + gid.x;
    let pt = points[point_of(pair, true)];
    let k = pair - pt.leaf_pair_start;
    let node = nodes[cut_nodes[pt.cut_start + k]];
    var value = lit_triangle_shade(leaves[node.leaf], pt.x, pt.receiver, pt.across);
    if (any(value != vec3<f32>(0.0))) {
        value *= node_maps_visibility(node.map, pt.xo);
    }
    pair_values[pt.pair_start + k - params.first] = vec4<f32>(value, 0.0);
}

@compute @workgroup_size(64)
fn sg_shade_clusters(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.cluster_count) {
        return;
    }
    let pair = params.cluster_first + gid.x;
    let pt = points[point_of(pair, false)];
    let k = pt.leaf_count + pair - (pt.pair_start - pt.leaf_pair_start);
    let node = nodes[cut_nodes[pt.cut_start + k]];
    var value = vec3<f32>(0.0);
    if (node.weight > 0.0) {
        let bound = node_bound(node.bound, pt.x, pt.receiver);
        value = min(lit_scene_cluster(node, params.light_pos, pt.x, pt.receiver, pt.across), bound);
    }
    if (any(value != vec3<f32>(0.0))) {
        value *= node_maps_visibility(node.map, pt.xo);
    }
    pair_values[pt.pair_start + k - params.first] = vec4<f32>(value, 0.0);
}
