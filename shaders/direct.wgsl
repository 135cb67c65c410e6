// Direct light (`render::gpu::direct`): one invocation per pixel sample sums, over the lights,
// the light reflected towards the eye, f(wo, ωl) cos θl E_l V, with V the light's variance
// shadow map looked up at the point offset off the surface and towards the light. Rust twin:
// `render::cpu::sg::direct_light` with a shadow map per light (`reflected_light_with`,
// `Light::incident`, `VarianceShadowMap::lit`). Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> params: GpuDirectParams;
@group(0) @binding(1) var<storage, read> points: array<GpuSurfacePoint>;
@group(0) @binding(2) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(3) var<storage, read> maps: array<GpuShadowMap>;
@group(0) @binding(4) var<storage, read> moments: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read> materials: array<GpuBrdf>;
@group(0) @binding(6) var<storage, read_write> radiance: array<vec4<f32>>;

// `scene::light::spot_falloff`: 1 inside the falloff cone, smoothstep to 0 at the cone.
fn spot_falloff(cos_theta: f32, cos_cone: f32, cos_falloff: f32) -> f32 {
    if (cos_theta >= cos_falloff) {
        return 1.0;
    }
    if (cos_theta <= cos_cone) {
        return 0.0;
    }
    let t = clamp((cos_theta - cos_cone) / (cos_falloff - cos_cone), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// `Light::incident` at p: (wi, 1) and the irradiance on a surface facing the light; w = 0 when
// the light cannot reach p.
struct Incident {
    wi: vec4<f32>,
    irradiance: vec3<f32>,
}

fn light_incident(l: GpuLight, p: vec3<f32>) -> Incident {
    let none = Incident(vec4<f32>(0.0), vec3<f32>(0.0));
    if (l.kind == 2u) {
        return Incident(vec4<f32>(-l.direction, 1.0), l.intensity);
    }
    let d = l.position - p;
    let d2 = dot(d, d);
    if (!(d2 > 0.0)) {
        return none;
    }
    let wi = d / sqrt(d2);
    var f = 1.0;
    if (l.kind == 1u) {
        f = spot_falloff(dot(-wi, l.direction), l.cos_cone, l.cos_falloff);
        if (f <= 0.0) {
            return none;
        }
    }
    return Incident(vec4<f32>(wi, 1.0), l.intensity * (f / d2));
}

// `visibility::vsm::bilinear_moments` over face `face` of map `m`, whose texels span
// [−margin, margin]² of face coordinates.
fn shadow_map_bilinear(m: GpuShadowMap, face: u32, u_in: f32, v_in: f32) -> vec2<f32> {
    let n = m.res;
    let base = m.first_texel + face * n * n;
    let b = bilinear_texels(n, u_in / m.margin, v_in / m.margin);
    return bilinear_mix(b, moments[base + b.i00], moments[base + b.i10], moments[base + b.i01], moments[base + b.i11]);
}

// `VarianceShadowMap::lit`: the lit fraction at p, 1 outside the map.
fn variance_shadow_map_lit(m: GpuShadowMap, p: vec3<f32>) -> f32 {
    let d = p - m.origin;
    var face = 0u;
    var u = 0.0;
    var v = 0.0;
    var t = 0.0;
    if (m.projection == 0u) {
        let a = abs(d);
        if (a.x >= a.y && a.x >= a.z) {
            face = select(1u, 0u, d.x > 0.0);
        } else if (a.y >= a.z) {
            face = select(3u, 2u, d.y > 0.0);
        } else {
            face = select(5u, 4u, d.z > 0.0);
        }
        let w = dot(d, m.forward[face].xyz);
        if (!(w > 0.0)) {
            return 1.0;
        }
        u = dot(d, m.right[face].xyz) / w;
        v = dot(d, m.up[face].xyz) / w;
        t = length(d);
    } else if (m.projection == 1u) {
        let w = dot(d, m.forward[0].xyz);
        if (!(w > 0.0)) {
            return 1.0;
        }
        u = dot(d, m.right[0].xyz) / (w * m.scale);
        v = dot(d, m.up[0].xyz) / (w * m.scale);
        if (!(abs(u) <= 1.0 && abs(v) <= 1.0)) {
            return 1.0;
        }
        t = length(d);
    } else {
        u = dot(d, m.right[0].xyz) / m.scale;
        v = dot(d, m.up[0].xyz) / m.scale;
        if (!(abs(u) <= 1.0 && abs(v) <= 1.0)) {
            return 1.0;
        }
        t = dot(d, m.forward[0].xyz);
    }
    let mo = shadow_map_bilinear(m, face, u, v);
    return reduce_bleeding(chebyshev_upper_bound(mo, t, m.min_variance), m.bleeding);
}

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
