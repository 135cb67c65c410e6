// The VPL baseline's one-bounce light (`render::gpu::vpl`): one invocation per pixel sample on a
// receiver sums, over a chunk of VPLs, each VPL's light re-emitted through its material's BRDF
// and reflected by the receiver's,
//   f_x(y_k → x → eye) · f_y(light → y_k → x) · Φ_k · cos θ_x cos θ_y / max(d², d_c²) · V(y_k, x),
// with V the VPL's imperfect shadow map. The sums carry over from chunk to chunk
// (`params.accumulate`), so that no invocation loops over more than a chunk (lavapipe's loop
// budget, docs/gpu.md). Rust twin: the indirect part of `render::cpu::vpl`'s `shade` with
// `--visibility approx`. Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> params: GpuVplParams;
@group(0) @binding(1) var<storage, read> points: array<GpuSurfacePoint>;
// This dispatch's chunk of VPLs (a uniform buffer: every invocation reads the same VPL at the
// same time, which lavapipe serves as one load rather than a gather per invocation).
@group(0) @binding(2) var<uniform> vpls: array<GpuVpl, 256>;
@group(0) @binding(3) var<storage, read> materials: array<GpuBrdf>;
@group(0) @binding(4) var<storage, read> atlas: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read_write> sums: array<GpuVplSum>;

// `visibility::vsm::bilinear_moments` over map `m` of the atlas (as in sg_shade.wgsl).
fn bilinear_moments(m: u32, u: f32, v: f32) -> vec2<f32> {
    let n = params.map_res;
    let base = m * n * n;
    let b = bilinear_texels(n, u, v);
    return bilinear_mix(b, atlas[base + b.i00], atlas[base + b.i10], atlas[base + b.i01], atlas[base + b.i11]);
}

// `ImperfectShadowMaps::visibility` of map `m`, whose origin is `o`: 0 below the map's horizon (or at its origin), otherwise
// the Chebyshev bound of the moments at p's direction for p's distance less the bias; 1 where
// no point reached the map.
fn imperfect_shadow_maps_visibility(m: u32, o: GpuMapOrigin, p: vec3<f32>) -> f32 {
    let v = p - o.position;
    let z = length(v);
    if (!(z > 0.0)) {
        return 0.0;
    }
    let w = v / z;
    let d = vec3<f32>(dot(w, o.t), dot(w, o.b), dot(w, o.n));
    if (!(d.z > 0.0)) {
        return 0.0;
    }
    let mo = bilinear_moments(m, d.x / (1.0 + d.z), d.y / (1.0 + d.z));
    if (!(mo.x > 0.0)) {
        return 1.0;
    }
    return chebyshev_upper_bound(mo, z * (1.0 - params.map_bias), o.min_variance);
}

// One VPL's contribution at point x: (radiance, 1 when the pair counts, 1 when clamped, 0).
fn vpl_pair(x: GpuSurfacePoint, mx: GpuBrdf, k: u32) -> array<vec3<f32>, 2> {
    let d = vpls[k].position - x.p;
    let d2 = dot(d, d);
    let to_vpl = d * inverseSqrt(d2);
    let wi_x = vec3<f32>(dot(to_vpl, x.t), dot(to_vpl, x.b), dot(to_vpl, x.n));
    let wo_y = -vec3<f32>(dot(to_vpl, vpls[k].t), dot(to_vpl, vpls[k].b), dot(to_vpl, vpls[k].n));
    // Both ends must face each other (geometric and shading normals).
    let facing = d2 > 0.0 && dot(x.ng, to_vpl) > 0.0 && dot(vpls[k].normal, -to_vpl) > 0.0 && wi_x.z > 0.0 && wo_y.z > 0.0;
    var out = array<vec3<f32>, 2>(vec3<f32>(0.0), vec3<f32>(0.0));
    if (facing) {
        let fx = brdf_eval(mx, x.wo, wi_x);
        let fy = brdf_eval(materials[vpls[k].material], wo_y, vpls[k].wi);
        if (any(fx != vec3<f32>(0.0)) && any(fy != vec3<f32>(0.0))) {
            let g = wi_x.z * wo_y.z / max(d2, params.clamp2);
            var v = 1.0;
            if (vpls[k].map != NONE) {
                v = imperfect_shadow_maps_visibility(vpls[k].map, vpls[k].origin, x.p);
            }
            out[0] = select(vec3<f32>(0.0), fx * fy * vpls[k].power * (g * v), v > 0.0);
            out[1] = vec3<f32>(1.0, select(0.0, 1.0, d2 < params.clamp2), 0.0);
        }
    }
    return out;
}

@compute @workgroup_size(64)
fn vpl(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= params.count) {
        return;
    }
    let i = gid.x;
    let x = points[i];
    var acc = GpuVplSum(vec3<f32>(0.0), 0u, 0u, 0u, 0u, 0u);
    if (params.accumulate != 0u) {
        acc = sums[i];
    }
    let mx = materials[x.material];
    for (var k = 0u; k < params.vpl_count; k++) {
        let r = vpl_pair(x, mx, k);
        acc.radiance += r[0];
        acc.pairs += u32(r[1].x);
        acc.clamped += u32(r[1].y);
    }
    sums[i] = acc;
}
