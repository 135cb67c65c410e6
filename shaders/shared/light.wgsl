// Lights, shared by every pass: `Light::incident` and the spot's falloff (`GpuLight`).

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
