//! Microfacet building blocks: normal distributions, Smith and V-cavity masking-shadowing,
//! Schlick's Fresnel approximation and half-vector sampling.
//!
//! Every function takes directions in the local shading frame (z = macro-surface normal) and is
//! written so that it returns finite values for every unit input: cosines that appear in
//! denominators are clamped below by [`COS_EPS`], exponentials are cut off before they underflow
//! into `0 / 0`.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Smallest cosine used in a denominator (and in the Smith Λ). It only changes f within 1e-7 of
/// the horizon (a band of solid angle ≈ 2π·1e-7), where the clamped values stay bounded.
pub const COS_EPS: f32 = 1e-7;

/// Mirror reflection of `w` about the unit vector `m`: 2 (w·m) m − w.
#[inline]
pub fn reflect(w: Vec3, m: Vec3) -> Vec3 {
    2.0 * w.dot(m) * m - w
}

/// Normalised half vector h = (wo + wi) / |wo + wi| (Cook & Torrance 1982) and wo·h = wi·h,
/// computed in f64 from the re-normalised inputs, with wo·h = |ŵo + ŵi| / 2 (exact for unit
/// vectors). The symmetric form makes every h-based model exactly reciprocal, and f64 keeps
/// h's tangent components — from which sin²θh is taken — accurate when wo and wi are nearly
/// opposite (grazing), where the f32 sum loses most of its bits. `None` if degenerate.
#[inline]
pub fn half_vector(wo: Vec3, wi: Vec3) -> Option<(Vec3, f32)> {
    let o = wo.as_dvec3().try_normalize()?;
    let i = wi.as_dvec3().try_normalize()?;
    let s = o + i;
    let l = s.length();
    // f64 resolves |wo + wi| down to the f32 subnormals, so only exactly opposite inputs fail.
    if l > 0.0 && l.is_finite() {
        Some(((s / l).as_vec3(), (0.5 * l) as f32))
    } else {
        None
    }
}

/// 1 − a·b = |a − b|² / 2 for directions a, b, in f64 after re-normalisation: full relative
/// precision even when a and b are within 1e-4 rad, where 1 − a·b in f32 is dominated by the
/// ~1e-7 length error of f32 unit vectors.
#[inline]
pub fn one_minus_dot(a: Vec3, b: Vec3) -> f32 {
    match (a.as_dvec3().try_normalize(), b.as_dvec3().try_normalize()) {
        (Some(a), Some(b)) => (0.5 * (a - b).length_squared()) as f32,
        _ => 1.0,
    }
}

/// sin²θ of a unit vector from its tangent components (no cancellation near the pole).
#[inline]
fn sin2(w: Vec3) -> f32 {
    (w.x * w.x + w.y * w.y).min(1.0)
}

/// (1 − d)^n for d ∈ [0, 1], as exp(n ln(1 − d)) with `ln_1p`, so that cosines close to 1 are
/// handled through their small complement d (exact to f32 relative precision even when
/// n = 1e6 and d ≈ 1e-6, where cos^n via `powf` would lose ~10 % to the rounding of cos).
/// Convention 0^0 = 1.
#[inline]
pub fn pow_one_minus(d: f32, n: f32) -> f32 {
    if n == 0.0 {
        return 1.0;
    }
    let d = d.clamp(0.0, 1.0);
    if d >= 1.0 {
        return 0.0;
    }
    (n * (-d).ln_1p()).exp()
}

/// Schlick's approximation (Schlick 1994): F = F0 + (1 − F0)(1 − cos)^5, per channel.
#[inline]
pub fn schlick_fresnel(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).max(0.0);
    let m2 = m * m;
    f0 + (Vec3::ONE - f0) * (m2 * m2 * m)
}

/// Blinn's normalised cosine-power NDF (Blinn 1977; normalisation as in Walter et al. 2007):
/// D(h) = (n + 2)/(2π) cos^n θh, so that ∫ D(h) cos θh dωh = 1.
#[inline]
pub fn blinn_phong_d(h: Vec3, n: f32) -> f32 {
    if !(h.z > 0.0) {
        return 0.0;
    }
    // 1 − cos θh = sin²θh / (1 + cos θh), free of cancellation near the pole.
    let one_minus_cos = sin2(h) / (1.0 + h.z.min(1.0));
    (n + 2.0) / (2.0 * PI) * pow_one_minus(one_minus_cos, n)
}

/// Samples h ∝ D_BlinnPhong(h) cos θh: cos θh = u1^(1/(n+2)), φ = 2π u2 (inverse CDF of the
/// density (n + 2) μ^(n+1) on μ = cos θh). sin²θh is computed as −expm1(2 ln u1 / (n + 2)) so
/// that exponents up to 1e6 keep full precision.
pub fn blinn_phong_sample(n: f32, u: Vec2) -> Vec3 {
    power_cosine_sample(n + 1.0, u)
}

/// pdf (solid angle, in h) of [`blinn_phong_sample`]: D(h) cos θh = (n + 2)/(2π) cos^(n+1) θh.
#[inline]
pub fn blinn_phong_pdf_h(h: Vec3, n: f32) -> f32 {
    blinn_phong_d(h, n) * h.z.max(0.0)
}

/// Samples a direction about +z with density (e + 1)/(2π) cos^e θ (Lafortune & Willems 1994):
/// cos θ = u1^(1/(e+1)), φ = 2π u2.
pub fn power_cosine_sample(e: f32, u: Vec2) -> Vec3 {
    let ln_u = u.x.max(f32::MIN_POSITIVE).ln();
    let k = 1.0 / (e + 1.0);
    let cos = (ln_u * k).exp();
    let sin = (-(2.0 * ln_u * k).exp_m1()).clamp(0.0, 1.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)
}

/// Beckmann NDF (Beckmann & Spizzichino 1963; Walter et al. 2007):
/// D(h) = exp(−tan²θh / α²) / (π α² cos⁴θh).
#[inline]
pub fn beckmann_d(h: Vec3, alpha: f32) -> f32 {
    if !(h.z > 0.0) {
        return 0.0;
    }
    let c2 = h.z * h.z;
    let a2 = alpha * alpha;
    let e = sin2(h) / (c2 * a2);
    // exp(-80) ≈ 2e-35: beyond this D is negligible, and cutting here keeps c2² away from 0.
    if !(e < 80.0) {
        return 0.0;
    }
    (-e).exp() / (PI * a2 * c2 * c2)
}

/// Samples h ∝ D_Beckmann(h) cos θh (Walter et al. 2007):
/// tan²θh = −α² ln(1 − u1), φ = 2π u2.
pub fn beckmann_sample(alpha: f32, u: Vec2) -> Vec3 {
    let tan2 = -alpha * alpha * (1.0 - u.x).max(f32::MIN_POSITIVE).ln();
    let cos = 1.0 / (1.0 + tan2).sqrt();
    let sin = (tan2 / (1.0 + tan2)).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)
}

/// Complementary error function, Numerical Recipes' `erfcc` (Press et al. 1992, §6.2,
/// a Chebyshev-based fit): fractional error < 1.2e-7 everywhere.
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let p = -1.26551223
        + t * (1.00002368
            + t * (0.37409196
                + t * (0.09678418
                    + t * (-0.18628806
                        + t * (0.27886807
                            + t * (-1.13520398
                                + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277))))))));
    let ans = t * (-z * z + p).exp();
    if x >= 0.0 { ans } else { 2.0 - ans }
}

/// Smith Λ of the Beckmann distribution (Walter et al. 2007; Heitz 2014):
/// Λ(w) = (erf(a) − 1)/2 + exp(−a²)/(2a√π), a = 1/(α tan θ) = cos θ / (α sin θ).
pub fn beckmann_lambda(w: Vec3, alpha: f32) -> f32 {
    let c = w.z.max(COS_EPS) as f64;
    let s = (sin2(w) as f64).sqrt();
    if s <= 0.0 {
        return 0.0;
    }
    let a = c / (alpha as f64 * s);
    // Λ(6) ≈ 1e-18: zero within f32 next to the 1 in 1 + Λ.
    if a > 6.0 {
        return 0.0;
    }
    let l = 0.5 * ((-a * a).exp() / (a * std::f64::consts::PI.sqrt()) - erfc(a));
    l.max(0.0) as f32
}

/// Smith Λ of GGX (Walter et al. 2007; Heitz 2014):
/// Λ(w) = (−1 + √(1 + α² tan²θ)) / 2, written as (√(cos² + α² sin²) − cos) / (2 cos).
pub fn ggx_lambda(w: Vec3, alpha: f32) -> f32 {
    let c = w.z.max(COS_EPS);
    let s = (c * c + alpha * alpha * sin2(w)).sqrt();
    ((s - c) / (2.0 * c)).max(0.0)
}

/// GGX (Trowbridge–Reitz) NDF (Walter et al. 2007):
/// D(h) = α² / (π (cos²θh (α² − 1) + 1)²), evaluated as α² / (π (sin²θh + α² cos²θh)²).
#[inline]
pub fn ggx_d(h: Vec3, alpha: f32) -> f32 {
    if !(h.z > 0.0) {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = sin2(h) + a2 * h.z * h.z;
    a2 / (PI * d * d)
}

/// √(cos²θ + α² sin²θ) = cos θ (1 + 2 Λ_GGX), the building block of the GGX Smith terms.
#[inline]
fn ggx_s(w: Vec3, alpha: f32) -> f32 {
    let c = w.z.max(COS_EPS);
    (c * c + alpha * alpha * sin2(w)).sqrt()
}

/// GGX height-correlated Smith visibility V = G2 / (4 cos θi cos θo) with
/// G2 = 1 / (1 + Λ(wo) + Λ(wi)) (Heitz 2014, height-correlated Smith), in the closed form
/// V = 1 / (2 (cos θi √(cos²θo + α² sin²θo) + cos θo √(cos²θi + α² sin²θi))).
#[inline]
pub fn ggx_visibility(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    let co = wo.z.max(COS_EPS);
    let ci = wi.z.max(COS_EPS);
    1.0 / (2.0 * (ci * ggx_s(wo, alpha) + co * ggx_s(wi, alpha)))
}

/// Solid-angle pdf (in h) of GGX visible-normal sampling (Heitz 2018, JCGT 7(4)):
/// D_wo(h) = G1(wo) max(0, wo·h) D(h) / cos θo, with G1 = 1 / (1 + Λ(wo)).
#[inline]
pub fn ggx_visible_pdf_h(wo: Vec3, h: Vec3, alpha: f32) -> f32 {
    let oh = wo.dot(h);
    if !(oh > 0.0) {
        return 0.0;
    }
    // G1 / cos θo = 2 / (cos θo + √(cos²θo + α² sin²θo)).
    let co = wo.z.max(COS_EPS);
    2.0 * oh * ggx_d(h, alpha) / (co + ggx_s(wo, alpha))
}

/// Solid-angle pdf (in wi) of reflecting wo about a GGX visible normal:
/// D_wo(h) / (4 wo·h) = G1(wo) D(h) / (4 cos θo) (Heitz 2018, with the Jacobian
/// dωh/dωi = 1 / (4 wo·h) of Walter et al. 2007). `h` must satisfy wo·h > 0, which holds
/// for the half vector of two above-horizon directions.
#[inline]
pub fn ggx_visible_pdf_wi(wo: Vec3, h: Vec3, alpha: f32) -> f32 {
    let co = wo.z.max(COS_EPS);
    ggx_d(h, alpha) / (2.0 * (co + ggx_s(wo, alpha)))
}

/// Samples a GGX visible normal for `wo` with the spherical-cap method of Dupuy & Benyoub,
/// "Sampling Visible GGX Normals with Spherical Caps" (HPG 2023). `None` on the
/// measure-zero degenerate case.
pub fn ggx_sample_visible(wo: Vec3, alpha: f32, u: Vec2) -> Option<Vec3> {
    // Stretch wo into the configuration where the distribution is the unit hemisphere.
    let v = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z.max(0.0)).try_normalize()?;
    let phi = 2.0 * PI * u.x;
    let z = (1.0 - u.y) * (1.0 + v.z) - v.z;
    let sin = (1.0 - z * z).clamp(0.0, 1.0).sqrt();
    let c = Vec3::new(sin * phi.cos(), sin * phi.sin(), z);
    let hs = c + v;
    let h = Vec3::new(alpha * hs.x, alpha * hs.y, hs.z.max(0.0)).try_normalize()?;
    if h.z > 0.0 { Some(h) } else { None }
}

/// V-cavity masking-shadowing of Torrance & Sparrow 1967 / Cook & Torrance 1982 (the form Blinn
/// 1977 used with the cos^n distribution): G2 = min(1, 2 cos θh cos θo / (wo·h),
/// 2 cos θh cos θi / (wo·h)). Returned already divided by 4 cos θi cos θo:
/// G2 / (4 ci co) = min(1 / (4 ci co), cos θh / (2 (wo·h) ci), cos θh / (2 (wo·h) co)),
/// with `oh` = wo·h.
#[inline]
pub fn v_cavity_visibility(wo: Vec3, wi: Vec3, h: Vec3, oh: f32) -> f32 {
    let co = wo.z.max(COS_EPS);
    let ci = wi.z.max(COS_EPS);
    let oh = oh.max(COS_EPS);
    let ch = h.z.max(0.0);
    (1.0 / (4.0 * ci * co))
        .min(ch / (2.0 * oh * ci))
        .min(ch / (2.0 * oh * co))
}

/// V-cavity masking G1(w, h) = min(1, 2 cos θh cos θw / (w·h)) (zero for back-facing h);
/// used by the tests to check the projected-area normalisation behind the energy argument.
pub fn v_cavity_g1(w: Vec3, h: Vec3) -> f32 {
    let wh = w.dot(h);
    if !(wh > 0.0) || !(w.z > 0.0) {
        return 0.0;
    }
    (2.0 * h.z.max(0.0) * w.z / wh).min(1.0)
}
