// VPL generation's per-triangle weights (`render::gpu::vpl_gen`): one invocation per reflector
// triangle computes the weight VPLs are sampled by, A_t ρ_t Ē_t (0.1 + 0.9 V_t) — area, albedo
// luminance, the light's irradiance on the lit side at the centroid, and the light's visibility
// there from its variance shadow map (the point offset towards the light). Rust twin:
// `precompute::vpl::source_weights` with the map's `light_fraction`. Sampling the 200 VPLs from
// the weights stays on the CPU (`precompute::vpl::generate_weighted`). Prepended with
// shaders/shared/*.wgsl and shaders/parts/shadow_map.wgsl.

@group(0) @binding(0) var<uniform> params: GpuVplGenParams;
@group(0) @binding(1) var<storage, read> sources: array<GpuVplSource>;
@group(0) @binding(2) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(3) var<storage, read> maps: array<GpuShadowMap>;
@group(0) @binding(4) var<storage, read> moments: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read_write> weights: array<f32>;

@compute @workgroup_size(64)
fn vpl_gen(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= params.count) {
        return;
    }
    let s = sources[i];
    let light = lights[0];
    let e1 = s.v1 - s.v0;
    let e2 = s.v2 - s.v0;
    let c = (s.v0 + s.v1 + s.v2) / 3.0;
    let x = cross(e1, e2);
    let len = length(x);
    // `lit_irradiance`: the normal (try_normalize), the light's incidence, the lit side.
    let inc = light_incident(light, c);
    var w = 0.0;
    if (len > 0.0 && inc.wi.w > 0.0) {
        let n = x / len;
        let e = inc.irradiance * abs(dot(n, inc.wi.xyz));
        if (any(e != vec3<f32>(0.0))) {
            var vis = 1.0;
            if (light.map != NONE) {
                vis = variance_shadow_map_lit(maps[light.map], c + inc.wi.xyz * params.eps);
            }
            w = 0.5 * len * luminance(e * s.albedo) * (0.1 + 0.9 * vis);
        }
    }
    weights[i] = w;
}
