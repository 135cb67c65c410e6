// The five BRDF models (`brdf::models::eval` and the microfacet terms of `brdf::microfacet`), in
// f32: what the VPL baseline's pass evaluates at both ends of every VPL–receiver pair. Each
// function is named after its Rust twin (`Brdf::eval` is `brdf_eval`); `render::gpu::twins`
// runs `brdf_eval` against it. The Rust twins compute the half vector, 1 − a·b and the
// Beckmann Λ in f64; here 1 − a·b is |a − b|²/2 of the normalised vectors, which keeps the
// cancellation-free form and loses only f32's rounding of the inputs.
//
// A material is a `GpuBrdf`: `model` 0 Lambert, 1 Phong, 2 Blinn-Phong, 3 Ward, 4 Cook-Torrance
// (`distribution` 0 Beckmann, 1 GGX); `param` is the exponent (Phong, Blinn-Phong) or α.

// `brdf::microfacet::COS_EPS`, `brdf::models::COUPLED_DIFFUSE_NORM`.
const COS_EPS: f32 = 1e-7;
const COUPLED_DIFFUSE_NORM: f32 = 0.841188;

// sin²θ of a unit vector from its tangent components (`microfacet::sin2`).
fn sin2(w: vec3<f32>) -> f32 {
    return min(w.x * w.x + w.y * w.y, 1.0);
}

// ln(1 + x) for x > −1 (Rust's `ln_1p`). Vulkan lets `log` be off by 2^-21 absolute near 1,
// which would be 8 % of ln(1 − 6e-6), so small |x| take the series of
// 2 atanh(z), z = x / (2 + x) (|z| < 1/7 here; the first omitted term is below 1e-10 of it).
fn ln_1p(x: f32) -> f32 {
    if (abs(x) < 0.25) {
        let z = x / (2.0 + x);
        let z2 = z * z;
        return 2.0 * z * (1.0 + z2 * (1.0 / 3.0 + z2 * (0.2 + z2 * (1.0 / 7.0 + z2 * (1.0 / 9.0)))));
    }
    return log(1.0 + x);
}

// `microfacet::pow_one_minus`: (1 − d)^n as exp(n ln(1 − d)); 0^0 = 1.
fn pow_one_minus(d: f32, n: f32) -> f32 {
    if (n == 0.0) {
        return 1.0;
    }
    let c = clamp(d, 0.0, 1.0);
    if (c >= 1.0) {
        return 0.0;
    }
    return exp(n * ln_1p(-c));
}

// `microfacet::one_minus_dot`: 1 − a·b = |â − b̂|² / 2; 1 when either is degenerate.
fn one_minus_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let la = length(a);
    let lb = length(b);
    if (!(la > 0.0 && lb > 0.0 && la < 3.0e38 && lb < 3.0e38)) {
        return 1.0;
    }
    let d = a / la - b / lb;
    return 0.5 * dot(d, d);
}

// `microfacet::half_vector`: (h, wo·h), wo·h = |ŵo + ŵi| / 2; w < 0 when degenerate.
fn half_vector(wo: vec3<f32>, wi: vec3<f32>) -> vec4<f32> {
    let lo = length(wo);
    let li = length(wi);
    if (!(lo > 0.0 && li > 0.0 && lo < 3.0e38 && li < 3.0e38)) {
        return vec4<f32>(0.0, 0.0, 1.0, -1.0);
    }
    let s = wo / lo + wi / li;
    let l = length(s);
    if (!(l > 0.0 && l < 3.0e38)) {
        return vec4<f32>(0.0, 0.0, 1.0, -1.0);
    }
    return vec4<f32>(s / l, 0.5 * l);
}

// `microfacet::schlick_fresnel`.
fn schlick_fresnel(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let m = max(1.0 - clamp(c, 0.0, 1.0), 0.0);
    let m2 = m * m;
    return f0 + (vec3<f32>(1.0) - f0) * (m2 * m2 * m);
}

// `microfacet::blinn_phong_d`: (n + 2)/(2π) cos^n θh.
fn blinn_phong_d(h: vec3<f32>, n: f32) -> f32 {
    if (!(h.z > 0.0)) {
        return 0.0;
    }
    let one_minus_cos = sin2(h) / (1.0 + min(h.z, 1.0));
    return (n + 2.0) / (2.0 * PI) * pow_one_minus(one_minus_cos, n);
}

// `microfacet::v_cavity_visibility`: G_V / (4 cos θi cos θo).
fn v_cavity_visibility(wo: vec3<f32>, wi: vec3<f32>, h: vec3<f32>, oh_in: f32) -> f32 {
    let co = max(wo.z, COS_EPS);
    let ci = max(wi.z, COS_EPS);
    let oh = max(oh_in, COS_EPS);
    let ch = max(h.z, 0.0);
    return min(min(1.0 / (4.0 * ci * co), ch / (2.0 * oh * ci)), ch / (2.0 * oh * co));
}

// `microfacet::beckmann_d`.
fn beckmann_d(h: vec3<f32>, alpha: f32) -> f32 {
    if (!(h.z > 0.0)) {
        return 0.0;
    }
    let c2 = h.z * h.z;
    let a2 = alpha * alpha;
    let e = sin2(h) / (c2 * a2);
    if (!(e < 80.0)) {
        return 0.0;
    }
    return exp(-e) / (PI * a2 * c2 * c2);
}

// `microfacet::erfc`, Numerical Recipes' erfcc (fractional error < 1.2e-7).
fn erfc(x: f32) -> f32 {
    let z = abs(x);
    let t = 1.0 / (1.0 + 0.5 * z);
    let p = -1.26551223 + t * (1.00002368 + t * (0.37409196 + t * (0.09678418 + t * (-0.18628806
        + t * (0.27886807 + t * (-1.13520398 + t * (1.48851587 + t * (-0.82215223
        + t * 0.17087277))))))));
    let ans = t * exp(-z * z + p);
    return select(2.0 - ans, ans, x >= 0.0);
}

// `microfacet::beckmann_lambda`: Smith Λ of Beckmann; 0 beyond a = 6 (Λ ≈ 1e-18 there).
fn beckmann_lambda(w: vec3<f32>, alpha: f32) -> f32 {
    let c = max(w.z, COS_EPS);
    let s = sqrt(sin2(w));
    if (s <= 0.0) {
        return 0.0;
    }
    let a = c / (alpha * s);
    if (a > 6.0) {
        return 0.0;
    }
    let l = 0.5 * (exp(-a * a) / (a * 1.7724539) - erfc(a));
    return max(l, 0.0);
}

// `microfacet::ggx_d`: α² / (π (sin²θh + α² cos²θh)²).
fn ggx_d(h: vec3<f32>, alpha: f32) -> f32 {
    if (!(h.z > 0.0)) {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = sin2(h) + a2 * h.z * h.z;
    return a2 / (PI * d * d);
}

// `microfacet::ggx_s`: √(cos²θ + α² sin²θ).
fn ggx_s(w: vec3<f32>, alpha: f32) -> f32 {
    let c = max(w.z, COS_EPS);
    return sqrt(c * c + alpha * alpha * sin2(w));
}

// `microfacet::ggx_visibility`: height-correlated Smith G2 / (4 cos θi cos θo).
fn ggx_visibility(wo: vec3<f32>, wi: vec3<f32>, alpha: f32) -> f32 {
    let co = max(wo.z, COS_EPS);
    let ci = max(wi.z, COS_EPS);
    return 1.0 / (2.0 * (ci * ggx_s(wo, alpha) + co * ggx_s(wi, alpha)));
}

// `models::coupled_diffuse_weight`: 1 − (1 − cos(θ/2 + π/4))^5.
fn coupled_diffuse_weight(w: vec3<f32>) -> f32 {
    let mu = max(w.z, 0.0);
    let s = sqrt(min(w.x * w.x + w.y * w.y, 1.0));
    let m = mu / sqrt(2.0 * (1.0 + s));
    let x = 1.0 - m;
    let x2 = x * x;
    return clamp(1.0 - x2 * x2 * x, 0.0, 1.0);
}

// `models::phong_lobe`: (n + 2)/(2π) max(0, r·wi)^n about the mirror direction r of wo.
fn phong_lobe(wo: vec3<f32>, wi: vec3<f32>, n: f32) -> f32 {
    let d = one_minus_dot(vec3<f32>(-wo.x, -wo.y, wo.z), wi);
    if (!(d <= 1.0)) {
        return 0.0;
    }
    return (n + 2.0) / (2.0 * PI) * pow_one_minus(d, n);
}

// The models a pipeline compiles (`render::gpu::layout::brdf_models`): bit i for model i, bits 5
// and 6 for Cook-Torrance's Beckmann and GGX distributions; all by default. A pass that knows
// its scene's materials sets it when its pipeline is built, so that the models no material
// uses are not compiled in at all — lavapipe runs all the code a shader can reach, taken or
// not (docs/gpu.md). A material whose model is left out evaluates to its diffuse term only.
override BRDF_MODELS: u32 = 0xffffffffu;

fn brdf_has(bit: u32) -> bool {
    return (BRDF_MODELS & (1u << bit)) != 0u;
}

// `Brdf::eval`: f(wo, wi) in 1/sr without the cosine, in the local frame (z the normal); zero
// when either direction is below the horizon, and zero rather than a non-finite value.
fn brdf_eval(m: GpuBrdf, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0) || !(wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    var f = m.diffuse / PI;
    let hv = half_vector(wo, wi);
    let h = hv.xyz;
    let ok = hv.w >= 0.0;
    switch m.model {
        case 1u: {
            if (brdf_has(1u)) {
                f += m.specular * phong_lobe(wo, wi, m.param);
            }
        }
        case 2u: {
            if (brdf_has(2u) && ok) {
                f += m.specular * (blinn_phong_d(h, m.param) * v_cavity_visibility(wo, wi, h, hv.w));
            }
        }
        case 3u: {
            if (brdf_has(3u) && ok) {
                let oh = max(hv.w, COS_EPS);
                f += m.specular * (beckmann_d(h, m.param) / (4.0 * oh * oh));
            }
        }
        case 4u: {
            var spec = vec3<f32>(0.0);
            if (brdf_has(4u) && ok) {
                var dv = 0.0;
                if (m.distribution == 1u) {
                    if (brdf_has(6u)) {
                        dv = ggx_d(h, m.param) * ggx_visibility(wo, wi, m.param);
                    }
                } else if (brdf_has(5u)) {
                    let d = beckmann_d(h, m.param);
                    if (d > 0.0) {
                        let g2 = 1.0 / (1.0 + beckmann_lambda(wo, m.param) + beckmann_lambda(wi, m.param));
                        dv = d * g2 / (4.0 * max(wi.z, COS_EPS) * max(wo.z, COS_EPS));
                    }
                }
                spec = schlick_fresnel(m.specular, hv.w) * dv;
            }
            let wd = coupled_diffuse_weight(wo) * coupled_diffuse_weight(wi) / (PI * COUPLED_DIFFUSE_NORM);
            f = m.diffuse * wd + spec;
        }
        default: {}
    }
    // Non-finite (NaN or ±∞) parts become zero, as the Rust wrapper does for the whole value.
    let finite = all(abs(f) < vec3<f32>(3.0e38));
    return select(vec3<f32>(0.0), max(f, vec3<f32>(0.0)), finite);
}
