// Variance shadow-map lookups, for the passes that bind the maps' texels as
// `moments: array<vec2<f32>>` (a part, not shared: `render::gpu::shaders::parts`). The maps
// themselves are `GpuShadowMap` (origin, projection, faces), `VarianceShadowMap::parts`.

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
