// Direct light (`render::gpu::direct`): one invocation per pixel sample sums, over the lights,
// the light reflected towards the eye, f(wo, ωl) cos θl E_l V, with V the light's variance
// shadow map looked up at the point offset off the surface and towards the light. Rust twin:
// `render::cpu::sg::direct_light` with a shadow map per light (`reflected_light_with`,
// `Light::incident`, `VarianceShadowMap::lit`). Prepended with shaders/shared/*.wgsl and
// shaders/parts/shadow_map.wgsl.

@group(0) @binding(0) var<uniform> params: GpuDirectParams;
@group(0) @binding(1) var<storage, read> points: array<GpuSurfacePoint>;
@group(0) @binding(2) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(3) var<storage, read> maps: array<GpuShadowMap>;
@group(0) @binding(4) var<storage, read> moments: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read> materials: array<GpuBrdf>;
@group(0) @binding(6) var<storage, read_write> radiance: array<vec4<f32>>;

@compute @workgroup_size(64)
fn direct(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= params.count) {
        return;
    }
    let x = points[i];
    let brdf = materials[x.material];
    var l = vec3<f32>(0.0);
    for (var k = 0u; k < params.light_count; k++) {
        let light = lights[k];
        let inc = light_incident(light, x.p);
        let wi = inc.wi.xyz;
        // `reflected_light_with`: both directions on the oriented side, both local z > 0.
        let wi_l = vec3<f32>(dot(wi, x.t), dot(wi, x.b), dot(wi, x.n));
        if (inc.wi.w > 0.0 && dot(x.ng, wi) > 0.0 && wi_l.z > 0.0) {
            let f = brdf_eval(brdf, x.wo, wi_l);
            if (any(f != vec3<f32>(0.0)) && any(inc.irradiance != vec3<f32>(0.0))) {
                var vis = 1.0;
                if (light.map != NONE) {
                    vis = variance_shadow_map_lit(maps[light.map], x.p + x.ng * params.eps + wi * params.eps);
                }
                if (vis > 0.0) {
                    l += f * wi_l.z * inc.irradiance * vis;
                }
            }
        }
    }
    radiance[i] = vec4<f32>(l, 0.0);
}
