// The SG transport of a reflector triangle or a cluster of them to a receiver point
// (`transport`, `cut::LitScene::cluster`), in f32: the functions the SG shading pass sums over a
// cut. Each is named after its Rust twin (a method `T::f` is `t_f`); `render::gpu::twins` runs
// `lit_triangle_shade` and `lit_scene_cluster` against theirs. lavapipe inlines every call, so
// the heavy functions (the SG integral above all) are called from one site each, in loops over
// the terms.

const NONE: u32 = 0xffffffffu;
// `transport::receiver::MAX_STRETCH`, `ANISOTROPY_FADE`.
const MAX_STRETCH: f32 = 10.0;
const ANISOTROPY_FADE: f32 = 1.0;

// glam's `try_normalize`, with the fallback for a zero or non-finite length.
fn try_normalize(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    if (l > 0.0 && l < 3.0e38) {
        return v / l;
    }
    return fallback;
}

fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    return try_normalize(v, vec3<f32>(0.0));
}

// `cut::luminance`.
fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

// `Sg::new`: the axis normalised (+Z when zero), the sharpness cleaned.
fn sg_new(axis: vec3<f32>, sharpness: f32, amplitude: vec3<f32>) -> GpuSg {
    return GpuSg(try_normalize(axis, vec3<f32>(0.0, 0.0, 1.0)), clean_sharpness(sharpness), amplitude, 0.0);
}

// The tangent of `Frame::from_normal` (Duff et al. 2017; the sign of −0 counts as negative).
fn frame_from_normal_t(n: vec3<f32>) -> vec3<f32> {
    let sign = select(1.0, -1.0, (bitcast<u32>(n.z) >> 31u) != 0u);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

// `transport::receiver::Anisotropic`: the isotropic lobe (axis, amplitude, geometric-mean
// sharpness), the unit direction t it is narrow across and the stretch k ≥ 1.
struct Anisotropic {
    iso: GpuSg,
    t: vec3<f32>,
    k: f32,
}

fn anisotropic_isotropic(lobe: GpuSg) -> Anisotropic {
    return Anisotropic(lobe, frame_from_normal_t(lobe.axis), 1.0);
}

fn anisotropic_new(lobe: GpuSg, t: vec3<f32>, k_in: f32) -> Anisotropic {
    let s = max(lobe.sharpness, 0.0);
    let k = clamp(k_in, 1.0, MAX_STRETCH);
    let fade = min(s / k / ANISOTROPY_FADE, 1.0);
    return Anisotropic(lobe, t, 1.0 + (k - 1.0) * fade);
}

// `Anisotropic::precision_in`: the 2×2 precision [xx, xy, yy] in the tangent basis (e1, e2).
fn anisotropic_precision_in(s: Anisotropic, e1: vec3<f32>, e2: vec3<f32>) -> vec3<f32> {
    let lam = max(s.iso.sharpness, 0.0);
    let a = s.iso.axis;
    let lo = lam / s.k;
    let hi = lam * s.k;
    let xx = lo * (dot(e1, e1) - dot(e1, a) * dot(e1, a) - dot(e1, s.t) * dot(e1, s.t)) + hi * dot(e1, s.t) * dot(e1, s.t);
    let xy = lo * (dot(e1, e2) - dot(e1, a) * dot(e2, a) - dot(e1, s.t) * dot(e2, s.t)) + hi * dot(e1, s.t) * dot(e2, s.t);
    let yy = lo * (dot(e2, e2) - dot(e2, a) * dot(e2, a) - dot(e2, s.t) * dot(e2, s.t)) + hi * dot(e2, s.t) * dot(e2, s.t);
    return vec3<f32>(xx, xy, yy);
}

// `transport::receiver::TangentProduct`; `ok` false where the Rust twin returns None.
struct TangentProduct {
    ok: bool,
    det: f32,
    centre: vec2<f32>,
    attenuation: f32,
    stretch: f32,
    widest_across: vec2<f32>,
}

fn sym_mul(m: vec3<f32>, v: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(m.x * v.x + m.y * v.y, m.y * v.x + m.z * v.y);
}

fn tangent_product_new(pa: vec3<f32>, pb: vec3<f32>, b: vec2<f32>) -> TangentProduct {
    var out = TangentProduct(false, 0.0, vec2<f32>(0.0), 0.0, 1.0, vec2<f32>(0.0));
    let p = pa + pb;
    let det = p.x * p.z - p.y * p.y;
    if (!(det > 0.0)) {
        return out;
    }
    let inv = vec3<f32>(p.z / det, -p.y / det, p.x / det);
    let pb_b = sym_mul(pb, b);
    let centre = sym_mul(inv, pb_b);
    let attenuation = max(b.x * pb_b.x + b.y * pb_b.y - (pb_b.x * centre.x + pb_b.y * centre.y), 0.0);
    let mean = 0.5 * (p.x + p.z);
    let d = sqrt(0.25 * (p.x - p.z) * (p.x - p.z) + p.y * p.y);
    let hi = mean + d;
    let lo = max(mean - d, 1e-20);
    var widest = vec2<f32>(p.y, hi - p.x);
    if (p.x >= p.z) {
        widest = vec2<f32>(hi - p.z, p.y);
    }
    out.ok = true;
    out.det = det;
    out.centre = centre;
    out.attenuation = attenuation;
    out.stretch = sqrt(hi / lo);
    out.widest_across = widest;
    return out;
}

// `Anisotropic::product`.
fn anisotropic_product(s: Anisotropic, o: Anisotropic) -> Anisotropic {
    let g = s.iso;
    let h = o.iso;
    let p0 = sg_product(g, h);
    let lam = max(g.sharpness, 0.0);
    let kap = max(h.sharpness, 0.0);
    if ((s.k <= 1.0 && o.k <= 1.0) || !(lam + kap > 0.0)) {
        return anisotropic_isotropic(p0);
    }
    let e2 = try_normalize(s.t - dot(s.t, g.axis) * g.axis, frame_from_normal_t(g.axis));
    let e1 = cross(e2, g.axis);
    let b = vec2<f32>(dot(h.axis, e1), dot(h.axis, e2));
    let aniso = tangent_product_new(anisotropic_precision_in(s, e1, e2), anisotropic_precision_in(o, e1, e2), b);
    let iso = tangent_product_new(
        anisotropic_precision_in(anisotropic_isotropic(g), e1, e2),
        anisotropic_precision_in(anisotropic_isotropic(h), e1, e2),
        b,
    );
    if (!aniso.ok || !iso.ok) {
        return anisotropic_isotropic(p0);
    }
    var amplitude = p0.amplitude;
    if (iso.attenuation > 1e-12 && dot(h.axis, g.axis) > 0.0) {
        let kk = s.k * o.k;
        let ratio = clamp(aniso.attenuation / iso.attenuation, 1.0 / kk, kk);
        let d = g.axis - h.axis;
        let log_iso = -(lam * kap) * dot(d, d) / (p0.sharpness + lam + kap);
        amplitude = g.amplitude * h.amplitude * exp(min(log_iso * ratio, 0.0));
    }
    let axis = try_normalize(
        p0.axis + (aniso.centre.x - iso.centre.x) * e1 + (aniso.centre.y - iso.centre.y) * e2,
        p0.axis,
    );
    var t = try_normalize(aniso.widest_across.x * e1 + aniso.widest_across.y * e2, e2);
    t = try_normalize(t - dot(t, axis) * axis, e2);
    return Anisotropic(
        sg_new(axis, p0.sharpness * sqrt(sqrt(aniso.det / iso.det)), amplitude),
        t,
        min(aniso.stretch, MAX_STRETCH),
    );
}

// `transport::receiver::cosine_weighted`: ∫_T exp(λ(p·ω − 1)) (n·ω) dω, by the cosine at the
// axis where the lobe sits well above the horizon, otherwise a central difference of the SG
// integral along n (the Rust twin differences in f64). lavapipe inlines every call, so the
// SG integral has one call site here, in a loop over the one or two evaluations.
fn cosine_weighted(s: GpuSg, n: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let lam = max(s.sharpness, 0.0);
    let np = dot(n, s.axis);
    let v_var = max(1.0 - np * np, 0.0) / max(lam, 1e-6);
    let at_axis = np > 0.0 && np * np >= 9.0 * v_var;
    let v = s.axis * lam;
    let h = 0.1 * sqrt(max(lam, 1.0));
    var value = array<f32, 2>(0.0, 0.0);
    let evaluations = select(2u, 1u, at_axis);
    for (var e = 0u; e < evaluations; e = e + 1u) {
        var axis = s.axis;
        var sharp = lam;
        var scale = np;
        if (!at_axis) {
            let w = v + select(-h, h, e == 0u) * n;
            let len = length(w);
            axis = select(vec3<f32>(0.0, 0.0, 1.0), w / len, len > 0.0);
            sharp = len;
            scale = exp(len - lam);
        }
        value[e] = integrate_sg(axis, sharp, a, b, c) * scale;
    }
    if (at_axis) {
        return value[0];
    }
    return max((value[0] - value[1]) / (2.0 * h), 0.0);
}

// `Anisotropic::integrate` with `CosineMode::Moment` (`lobe_with_cosine`): an anisotropic lobe
// is integrated in the whitened directions, where it is isotropic.
fn anisotropic_integrate(s: Anisotropic, n: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    var lobe = s.iso;
    var nn = n;
    var n_len = 1.0;
    var fa = a;
    var fb = b;
    var fc = c;
    if (s.k > 1.0 + 1e-4) {
        let t = s.t;
        let k = s.k;
        let n_w = n + (1.0 / k - 1.0) * dot(t, n) * t;
        n_len = length(n_w);
        nn = n_w / n_len;
        lobe = sg_new(s.iso.axis, s.iso.sharpness / k, s.iso.amplitude / k);
        fa = a + (k - 1.0) * dot(t, a) * t;
        fb = b + (k - 1.0) * dot(t, b) * t;
        fc = c + (k - 1.0) * dot(t, c) * t;
    }
    return lobe.amplitude * cosine_weighted(lobe, nn, fa, fb, fc) * n_len;
}

// `transport::receiver::projected_solid_angle`.
fn projected_solid_angle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, n: vec3<f32>) -> f32 {
    var v = array<vec3<f32>, 3>(normalize_or_zero(a), normalize_or_zero(b), normalize_or_zero(c));
    var s = 0.0;
    for (var i = 0u; i < 3u; i = i + 1u) {
        let p = v[i];
        let q = v[(i + 1u) % 3u];
        let cr = cross(p, q);
        let len = length(cr);
        if (len > 0.0) {
            s += atan2(len, dot(p, q)) * dot(n, cr / len);
        }
    }
    return abs(0.5 * s);
}

// `transport::receiver::clip_to_horizon`: up to 4 vertices.
struct Polygon {
    v: array<vec3<f32>, 4>,
    count: u32,
}

fn clip_to_horizon(t0: vec3<f32>, t1: vec3<f32>, t2: vec3<f32>, n: vec3<f32>) -> Polygon {
    var tri = array<vec3<f32>, 3>(t0, t1, t2);
    var out = Polygon(array<vec3<f32>, 4>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0)), 0u);
    var k = 0u;
    for (var i = 0u; i < 3u; i = i + 1u) {
        let j = (i + 1u) % 3u;
        let p = tri[i];
        let q = tri[j];
        let dp = dot(p, n);
        let dq = dot(q, n);
        if (dp >= 0.0) {
            if (k < 4u) {
                out.v[k] = p;
                k += 1u;
            }
            if (dq < 0.0 && k < 4u) {
                out.v[k] = p + (q - p) * (dp / (dp - dq));
                k += 1u;
            }
        } else if (dq >= 0.0 && k < 4u) {
            out.v[k] = p + (q - p) * (dp / (dp - dq));
            k += 1u;
        }
    }
    out.count = k;
    return out;
}

// `ReflectedSg::light_cosine`.
fn reflected_sg_light_cosine(s: GpuLeaf) -> f32 {
    return dot(normalize_or_zero(s.light - s.origin), s.normal);
}

// `transport::reflector::aim_at_receiver`: the lobes re-aimed at x through the light's mirror
// image, sharpened by the distances, with their anisotropy at the specular point.
fn aim_at_receiver(s: GpuLeaf, x: vec3<f32>) -> GpuLeaf {
    let n = s.normal;
    let h_l = dot(s.light - s.origin, n);
    let h_x = dot(x - s.origin, n);
    if (!(h_l > 0.0 && h_x > 0.0)) {
        return s;
    }
    let image = s.light - 2.0 * h_l * n;
    let to_x = x - image;
    let d = length(to_x);
    if (!(d > 0.0 && d < 3.0e38)) {
        return s;
    }
    let axis = to_x / d;
    let d_l = d * h_l / (h_l + h_x);
    let d_x = d - d_l;
    let f = 1.0 + d_x / d_l;
    var scale = f * f;
    var out = s;
    if (s.half_vector != 0u) {
        let cos_c = reflected_sg_light_cosine(s);
        let cos_s = max(dot(axis, n), 1.0 / MAX_STRETCH);
        if (cos_c > 0.0) {
            scale *= cos_c / cos_s;
        }
        out.stretch = 1.0 / cos_s;
    }
    for (var i = 0u; i < out.lobe_count; i = i + 1u) {
        out.lobes[i].axis = axis;
        out.lobes[i].sharpness *= scale;
    }
    return out;
}

// `transport::receiver::one_bounce_with` (the default `ReceiverOptions`: moment cosine, clipped
// to the horizon, anisotropic lobes) for the reflector `refl` and the receiver `rx` at x.
fn one_bounce_with(refl: GpuLeaf, x: vec3<f32>, rx: GpuReceiver, across: vec3<f32>) -> vec3<f32> {
    let n_x = rx.normal;
    let centroid = (refl.v0 + refl.v1 + refl.v2) / 3.0;
    let to_x = x - centroid;
    // The margin counts the triangle's size too: a receiver point inside the triangle itself
    // must not pass on rounding.
    let reach = length(to_x) + length(refl.v0 - centroid);
    if (!(dot(to_x, refl.geometric_normal) > 1e-4 * reach)
        || (rx.lobe_count == 0u && all(rx.diffuse == vec3<f32>(0.0)))) {
        return vec3<f32>(0.0);
    }
    let poly = clip_to_horizon(refl.v0 - x, refl.v1 - x, refl.v2 - x, n_x);
    if (poly.count < 3u) {
        return vec3<f32>(0.0);
    }
    var g: array<Anisotropic, 4>;
    for (var i = 0u; i < refl.lobe_count; i = i + 1u) {
        let l = refl.lobes[i];
        let flipped = sg_new(-l.axis, l.sharpness, l.amplitude);
        let c = cross(flipped.axis, refl.normal);
        let cl = length(c);
        if (cl > 0.0 && cl < 3.0e38) {
            g[i] = anisotropic_new(flipped, c / cl, refl.stretch);
        } else {
            g[i] = anisotropic_isotropic(flipped);
        }
    }
    var h: array<Anisotropic, 4>;
    for (var j = 0u; j < rx.lobe_count; j = j + 1u) {
        h[j] = anisotropic_new(rx.lobes[j], across, rx.stretch);
    }
    // The terms: diffuse × diffuse (the projected solid angle), then diffuse × lobe, lobe ×
    // diffuse and lobe × lobe, numbered so that one loop with one call site integrates them
    // all (lavapipe inlines every call).
    let nh = rx.lobe_count;
    let ng = refl.lobe_count;
    let terms = nh + ng * (1u + nh);
    var sum = vec3<f32>(0.0);
    for (var k = 1u; k + 1u < poly.count; k = k + 1u) {
        let a = poly.v[0];
        let b = poly.v[k];
        let c = poly.v[k + 1u];
        sum += refl.diffuse * rx.diffuse * projected_solid_angle(a, b, c, n_x);
        for (var q = 0u; q < terms; q = q + 1u) {
            var lobe: Anisotropic;
            var factor = vec3<f32>(1.0);
            if (q < nh) {
                lobe = h[q];
                factor = refl.diffuse;
            } else {
                let r = q - nh;
                let i = r / (1u + nh);
                let j = r % (1u + nh);
                if (j == 0u) {
                    lobe = g[i];
                    factor = rx.diffuse;
                } else {
                    lobe = anisotropic_product(g[i], h[j - 1u]);
                }
            }
            sum += factor * anisotropic_integrate(lobe, n_x, a, b, c);
        }
    }
    return sum;
}

// `LitTriangle::shade`: the triangle's lobes re-aimed at x, integrated over its solid angle.
fn lit_triangle_shade(t: GpuLeaf, x: vec3<f32>, rx: GpuReceiver, across: vec3<f32>) -> vec3<f32> {
    if (t.has_sg == 0u) {
        return vec3<f32>(0.0);
    }
    return one_bounce_with(aim_at_receiver(t, x), x, rx, across);
}

// `LitScene::cluster`: a node shaded as one reflector — a unit-height SG cap of its solid angle
// times its diffuse part and merged lobes, aimed through the light's image in its mean plane.
fn lit_scene_cluster(lit: GpuLitNode, light_pos: vec3<f32>, x: vec3<f32>, rx: GpuReceiver, across: vec3<f32>) -> vec3<f32> {
    if (!(lit.weight > 0.0 && lit.area > 0.0)) {
        return vec3<f32>(0.0);
    }
    let c = lit.centroid;
    let v = x - c;
    let d2 = dot(v, v);
    if (!(d2 > 0.0)) {
        return vec3<f32>(0.0);
    }
    let r = v / sqrt(d2);
    let proj = dot(lit.normal_sum, r) / lit.area;
    if (!(proj > 0.0)) {
        return vec3<f32>(0.0);
    }
    let omega = clamp(lit.area * proj / d2, 1e-12, TAU);
    let cap_sharp = TAU / omega;
    let cap = sg_new(-r, cap_sharp, vec3<f32>(omega / lobe_integral(cap_sharp)));
    let inv_area = 1.0 / lit.area;
    let cap_a = anisotropic_isotropic(cap);
    var incoming: array<Anisotropic, 5>;
    var count = 0u;
    if (any(lit.diffuse != vec3<f32>(0.0))) {
        var d = cap;
        d.amplitude *= lit.diffuse * inv_area;
        incoming[0] = anisotropic_isotropic(d);
        count = 1u;
    }
    let nbar = normalize_or_zero(lit.normal_sum);
    let h_l = dot(light_pos - c, nbar);
    let h_x = dot(v, nbar);
    var aimed = false;
    var aim_axis = vec3<f32>(0.0);
    var aim_scale = 1.0;
    var aim_stretch = 1.0;
    if (h_l > 0.0 && h_x > 0.0) {
        let image = light_pos - 2.0 * h_l * nbar;
        let to_x = x - image;
        let d = length(to_x);
        if (d > 0.0 && d < 3.0e38) {
            aimed = true;
            aim_axis = to_x / d;
            let d_l = d * h_l / (h_l + h_x);
            let f = 1.0 + (d - d_l) / d_l;
            aim_scale = f * f;
            if (lit.half_vector != 0u) {
                let cos_c = h_l / length(light_pos - c);
                let cos_s = max(dot(aim_axis, nbar), 1.0 / MAX_STRETCH);
                aim_scale *= cos_c / cos_s;
                aim_stretch = 1.0 / cos_s;
            }
        }
    }
    for (var i = 0u; i < 4u; i = i + 1u) {
        let l = lit.lobes[i];
        let weight = luminance(l.energy);
        if (!(weight > 0.0)) {
            continue;
        }
        let mean_axis = l.axis_sum / weight;
        let rlen = min(length(mean_axis), 1.0);
        let own = l.inv_sharpness_sum / weight;
        let spread = 1.0 - rlen;
        var axis = normalize_or_zero(mean_axis);
        var scale = 1.0;
        var stretch = 1.0;
        if (aimed) {
            axis = aim_axis;
            scale = aim_scale;
            stretch = aim_stretch;
        }
        if (all(axis == vec3<f32>(0.0))) {
            continue;
        }
        let var_ = max(own + spread, 1e-12);
        let lobe = sg_new(-axis, scale / var_, l.energy * (inv_area / var_));
        var lobe_a = anisotropic_isotropic(lobe);
        let tc = cross(-axis, nbar);
        let tl = length(tc);
        if (tl > 0.0 && tl < 3.0e38 && stretch > 1.0) {
            lobe_a = anisotropic_new(lobe, tc / tl, stretch);
        }
        incoming[count] = anisotropic_product(lobe_a, cap_a);
        count += 1u;
    }
    let n_x = rx.normal;
    var sum = vec3<f32>(0.0);
    // Each incoming lobe against the receiver's diffuse part (j = 0) and each of its lobes.
    let per = 1u + rx.lobe_count;
    for (var q = 0u; q < count * per; q = q + 1u) {
        let s = incoming[q / per];
        let j = q % per;
        var p = s.iso;
        var factor = vec3<f32>(1.0);
        if (j == 0u) {
            factor = rx.diffuse;
        } else {
            p = anisotropic_product(s, anisotropic_new(rx.lobes[j - 1u], across, rx.stretch)).iso;
        }
        sum += factor * sg_integral(p) * clamped_cosine_mean(dot(n_x, p.axis), p.sharpness);
    }
    return sum;
}

