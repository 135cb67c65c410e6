// WGSL twins of the Rust math functions. Each function has the name of its Rust twin (a method
// `T::f` becomes `t_f`), and `render::gpu::twins` runs both over the same table of inputs.
// f32 throughout; the Rust twins compute some steps in f64, which the tolerances of the GPU
// tests account for.

const PI: f32 = 3.14159265358979;

// e^x − 1 without cancellation for small |x| (WGSL has no expm1): below 0.1 its Taylor series
// to x⁷ (truncation below 3e-12 relative); above, e^x − 1 loses at most ~10 ulp.
fn expm1(x: f32) -> f32 {
    if (abs(x) < 0.1) {
        return x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0 + x * (1.0 / 120.0
            + x * (1.0 / 720.0 + x * (1.0 / 5040.0)))))));
    }
    return exp(x) - 1.0;
}

// ∫_{S²} exp(λ (ω·p − 1)) dω = 2π (1 − e^{−2λ}) / λ, 4π at λ = 0 (`math::sg::lobe_integral`).
fn lobe_integral(sharpness: f32) -> f32 {
    if (sharpness > 0.0) {
        return -2.0 * PI * expm1(-2.0 * sharpness) / sharpness;
    }
    return 4.0 * PI;
}

// ∫_{S²} G1 G2 dω of two lobes (`math::sg::Sg::inner_product`): with v = λ1 p1 + λ2 p2 and
// λ = |v|, e^{λ − λ1 − λ2} lobe_integral(λ), the exponent in the stable form
// −λ1 λ2 |p1 − p2|² / (λ + λ1 + λ2).
fn sg_inner_product(a: GpuSg, b: GpuSg) -> vec3<f32> {
    let l1 = max(a.sharpness, 0.0);
    let l2 = max(b.sharpness, 0.0);
    let v = a.axis * l1 + b.axis * l2;
    let l = length(v);
    let denom = l + l1 + l2;
    var log_scale = 0.0;
    if (denom > 0.0) {
        let d = a.axis - b.axis;
        log_scale = -(l1 * l2) * dot(d, d) / denom;
    }
    return a.amplitude * b.amplitude * (exp(log_scale) * lobe_integral(l));
}

// Chebyshev's upper bound of the lit fraction P(z ≥ t) from the moments (E[z], E[z²])
// (`visibility::vsm::chebyshev_upper_bound`).
fn chebyshev_upper_bound(moments: vec2<f32>, t: f32, min_variance: f32) -> f32 {
    let mu = moments.x;
    if (!(t > mu)) {
        return 1.0;
    }
    let v = max(moments.y - mu * mu, min_variance);
    let d = t - mu;
    return v / (v + d * d);
}

// Light-bleeding reduction: p rescaled from [b, 1] to [0, 1] (`visibility::vsm::reduce_bleeding`).
fn reduce_bleeding(p: f32, b: f32) -> f32 {
    if (!(b > 0.0)) {
        return p;
    }
    return clamp((p - b) / (1.0 - b), 0.0, 1.0);
}

// erf, Abramowitz & Stegun 7.1.26 (`cut::erf`).
fn erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.3275911 * abs(x));
    let y = 1.0 - (((((1.0614054 * t - 1.4531521) * t) + 1.4214137) * t - 0.28449672) * t
        + 0.2548296) * t * exp(-x * x);
    return select(-y, y, x >= 0.0);
}

// E[max(0, n·ω)] under a lobe whose axis has n·p = c (`cut::clamped_cosine_mean`).
fn clamped_cosine_mean(c: f32, sharpness: f32) -> f32 {
    let v = max(1.0 - c * c, 0.0) / max(sharpness, 1e-6);
    let sigma = min(sqrt(v), 1.0);
    if (!(sigma > 1e-6)) {
        return max(c, 0.0);
    }
    let z = c / sigma;
    let pdf = exp(-0.5 * z * z) * 0.3989423;
    let cdf = 0.5 * (1.0 + erf(z * 0.70710678));
    return clamp(c * cdf + sigma * pdf, 0.0, 1.0);
}
