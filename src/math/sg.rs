//! Spherical Gaussians: G(ω; p, λ, μ) = μ · exp(λ (ω·p − 1)).
//!
//! Conventions follow Wang et al., "All-Frequency Rendering of Dynamic, Spatially-Varying
//! Reflectance" (SIGGRAPH Asia 2009) and Xu et al., "A Practical Algorithm for Rendering
//! Interreflections with All-Frequency BRDFs" (TOG 2014): unit axis p, sharpness λ ≥ 0, RGB
//! amplitude μ. Every function here is valid for λ ∈ [0, 1e5] (and beyond): the exponents
//! are always ≤ 0, the λ → 0 limits are taken with `exp_m1`, and no result is NaN for finite
//! inputs. Derivations: `docs/sg-math.md`.

use glam::{DVec3, Vec3};

use super::spherical_triangle;

/// Sharpness of the clamped-cosine fit max(0, n·ω) ≈ 1.17 · exp(2.133 (n·ω − 1))
/// (Xu et al. 2014, §4; the constants of Wang et al. 2009).
pub const CLAMPED_COSINE_SHARPNESS: f32 = 2.133;
/// Amplitude of the clamped-cosine fit, see [`CLAMPED_COSINE_SHARPNESS`].
pub const CLAMPED_COSINE_AMPLITUDE: f32 = 1.17;
/// Largest overshoot of the clamped-cosine fit over max(0, n·ω): 0.17 (at ω = n, where the
/// fit is 1.17 and the cosine 1). Measured by `sg_tests::clamped_cosine_fit_errors`.
pub const CLAMPED_COSINE_MAX_OVERSHOOT: f32 = 0.17;
/// Largest undershoot of the clamped-cosine fit: the fit is 0.1024 below n·ω at n·ω ≈ 0.571.
pub const CLAMPED_COSINE_MAX_UNDERSHOOT: f32 = 0.1024;
/// Value of the clamped-cosine fit on the horizon (n·ω = 0), where the cosine is 0:
/// 1.17 e^{−2.133} ≈ 0.1387; below the horizon the fit decays further to 1.17 e^{−4.266}.
pub const CLAMPED_COSINE_HORIZON_VALUE: f32 = 0.1387;

/// A spherical Gaussian with unit `axis` p, `sharpness` λ ≥ 0 and RGB `amplitude` μ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sg {
    pub axis: Vec3,
    pub sharpness: f32,
    pub amplitude: Vec3,
}

/// Largest sharpness used internally (larger values, including +∞, are clamped to it), so
/// that sums of two sharpnesses stay finite in f32.
pub const MAX_SHARPNESS: f32 = 1e30;

/// λ sanitised: NaN and negative values become 0, values above [`MAX_SHARPNESS`] are clamped.
#[inline]
fn clean_sharpness(l: f32) -> f32 {
    if l > 0.0 { l.min(MAX_SHARPNESS) } else { 0.0 }
}

/// ∫_{S²} exp(λ (ω·p − 1)) dω = 2π (1 − e^{−2λ}) / λ, computed as −2π expm1(−2λ) / λ;
/// the limit at λ → 0 is 4π (Wang et al. 2009, eq. 5). Never NaN; λ < 0 or NaN counts as 0.
#[inline]
pub fn lobe_integral(sharpness: f32) -> f32 {
    lobe_integral_f64(f64::from(clean_sharpness(sharpness))) as f32
}

/// f64 version of [`lobe_integral`]: 2π (1 − e^{−2λ}) / λ with the λ → 0 limit 4π.
#[inline]
pub fn lobe_integral_f64(l: f64) -> f64 {
    if l > 0.0 {
        -2.0 * std::f64::consts::PI * (-2.0 * l).exp_m1() / l
    } else {
        4.0 * std::f64::consts::PI
    }
}

/// The product lobe of two unit-amplitude SGs, in f64:
/// G(ω; p1, λ1) G(ω; p2, λ2) = s · G(ω; p, λ) with v = λ1 p1 + λ2 p2, λ = |v|, p = v / λ and
/// ln s = λ − λ1 − λ2 = −λ1 λ2 |p1 − p2|² / (λ + λ1 + λ2) (the stable form of the exponent,
/// from λ² = (λ1 + λ2)² − λ1 λ2 |p1 − p2|²; Wang et al. 2009, eq. 4).
/// Returns (p, λ, ln s); when λ = 0 (opposite lobes of equal sharpness, or both λi = 0) p is p1.
pub fn product_lobe_f64(p1: DVec3, l1: f64, p2: DVec3, l2: f64) -> (DVec3, f64, f64) {
    let v = p1 * l1 + p2 * l2;
    let l = v.length();
    let denom = l + l1 + l2;
    let log_scale = if denom > 0.0 {
        -(l1 * l2) * (p1 - p2).length_squared() / denom
    } else {
        0.0
    };
    let p = if l > 0.0 { v / l } else { p1 };
    (p, l, log_scale)
}

/// ∫_{S²} G(ω; p1, λ1) G(ω; p2, λ2) dω for unit amplitudes, in the stable form
/// 2π e^{λ − λ1 − λ2} (1 − e^{−2λ}) / λ with λ = |λ1 p1 + λ2 p2| and the exponent of
/// [`product_lobe_f64`] (Wang et al. 2009, eq. 6). Always in [0, 4π].
pub fn inner_product_f64(p1: DVec3, l1: f64, p2: DVec3, l2: f64) -> f64 {
    let (_, l, log_scale) = product_lobe_f64(p1, l1, p2, l2);
    log_scale.exp() * lobe_integral_f64(l)
}

impl Sg {
    /// A lobe with the axis normalised (a zero or non-finite axis becomes +Z) and λ clamped
    /// to [0, [`MAX_SHARPNESS`]] (NaN → 0).
    pub fn new(axis: Vec3, sharpness: f32, amplitude: Vec3) -> Sg {
        Sg {
            axis: axis.try_normalize().unwrap_or(Vec3::Z),
            sharpness: clean_sharpness(sharpness),
            amplitude,
        }
    }

    /// The clamped-cosine fit max(0, n·ω) ≈ 1.17 exp(2.133 (n·ω − 1)) (Xu et al. 2014, §4,
    /// after Wang et al. 2009). Errors against the cosine (measured, see
    /// [`CLAMPED_COSINE_MAX_OVERSHOOT`]): +0.17 at ω = n, −0.102 at n·ω ≈ 0.571, 0.139 on the
    /// horizon; its sphere integral is 3.398 against π for the cosine (+8.2 %).
    pub fn clamped_cosine(n: Vec3) -> Sg {
        Sg::new(
            n,
            CLAMPED_COSINE_SHARPNESS,
            Vec3::splat(CLAMPED_COSINE_AMPLITUDE),
        )
    }

    /// G(ω) = μ exp(λ (ω·p − 1)).
    #[inline]
    pub fn eval(&self, w: Vec3) -> Vec3 {
        self.amplitude * (self.sharpness * (w.dot(self.axis) - 1.0)).exp()
    }

    /// The unit-amplitude lobe exp(λ (ω·p − 1)), in (0, 1] for unit ω.
    #[inline]
    pub fn lobe(&self, w: Vec3) -> f32 {
        (self.sharpness * (w.dot(self.axis) - 1.0)).exp()
    }

    /// The product G1 G2 as one SG: axis p = v/|v|, λ = |v| with v = λ1 p1 + λ2 p2, and
    /// μ = μ1 μ2 exp(−λ1 λ2 |p1 − p2|² / (λ + λ1 + λ2)) (Wang et al. 2009, eq. 4, with the
    /// exponent λ − λ1 − λ2 written without cancellation). Exact, commutative up to rounding.
    pub fn product(&self, other: &Sg) -> Sg {
        let (p, l, log_scale) = product_lobe_f64(
            self.axis.as_dvec3(),
            f64::from(clean_sharpness(self.sharpness)),
            other.axis.as_dvec3(),
            f64::from(clean_sharpness(other.sharpness)),
        );
        Sg {
            axis: p.as_vec3(),
            sharpness: l as f32,
            amplitude: self.amplitude * other.amplitude * (log_scale.exp() as f32),
        }
    }

    /// ∫_{S²} G(ω) dω = 2π μ (1 − e^{−2λ}) / λ, in the expm1 form with the limit 4π μ at
    /// λ → 0 (Wang et al. 2009, eq. 5).
    pub fn integral(&self) -> Vec3 {
        self.amplitude * lobe_integral(self.sharpness)
    }

    /// ⟨G1, G2⟩ = ∫_{S²} G1 G2 dω = μ1 μ2 · 2π e^{λ − λ1 − λ2} (1 − e^{−2λ}) / λ with
    /// λ = |λ1 p1 + λ2 p2| (the integral of [`Sg::product`]; Wang et al. 2009, eq. 6). The
    /// scalar factor is computed in f64, is in [0, 4π] and never overflows.
    pub fn inner_product(&self, other: &Sg) -> Vec3 {
        let s = inner_product_f64(
            self.axis.as_dvec3(),
            f64::from(clean_sharpness(self.sharpness)),
            other.axis.as_dvec3(),
            f64::from(clean_sharpness(other.sharpness)),
        );
        self.amplitude * other.amplitude * (s as f32)
    }

    /// ∫ G(ω) dω over the spherical triangle with vertices a, b, c (directions, any length,
    /// either winding): μ · [`spherical_triangle::integrate_sg`] (Xu et al. 2014, §5).
    pub fn integrate_triangle(&self, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
        self.amplitude * spherical_triangle::integrate_sg(self.axis, self.sharpness, a, b, c)
    }
}

#[cfg(test)]
#[path = "sg_tests.rs"]
mod tests;
