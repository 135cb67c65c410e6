//! Spherical-Gaussian (SG) fits of the BRDF models, warped into the light domain
//! (Xu et al. 2014, §3; Wang et al. 2009, §4). See `docs/sg-brdf-fits.md`.
//!
//! Every model becomes a constant diffuse term plus 1..[`MAX_LOBES`] SG lobes over the incident
//! direction wi, for a fixed view direction wo:
//!
//! f(wo, wi) ≈ `diffuse` + Σ_k G(wi; p, λ_k, μ_k).
//!
//! - Phong: the lobe (n+2)/(2π) (r·wi)^n is already an SG around the mirror direction r, with
//!   (r·wi)^n ≈ exp(n (r·wi − 1)): λ = n, μ = ks (n+2)/(2π). No warp.
//! - Microfacet models: the NDF is an SG (or a sum of SGs for GGX) in the half-vector domain
//!   around the normal, D(h) ≈ Σ_k μ_k exp(λ_k (h·n − 1)):
//!   Blinn-Phong λ = n, μ = (n+2)/(2π); Beckmann (Ward and Cook-Torrance) λ = 2/α²,
//!   μ = 1/(π α²); GGX K ∈ 1..=4 lobes fitted by energy-preserving least squares and
//!   tabulated over α
//!   ([`ggx`], `ggx_table.rs`). The lobes are warped into the wi domain about wo (spherical warp
//!   of Wang et al. 2009): axis r = 2 (wo·n) n − wo, sharpness λ / (4 |wo·n|), and the remaining
//!   factors of the BRDF (Fresnel, masking-shadowing, 1/(4 cos θi cos θo), ks) are evaluated once
//!   at wi = r and folded into the amplitudes ("smooth factors").
//!
//! The lobes do **not** include the cosine max(0, wi·n): a renderer multiplies by it (or by its
//! own SG fit of it). Lobes are not cut at the horizon either: they are meant to be multiplied
//! by the cosine clamped at zero.

// `!(x > 0.0)` is deliberate (NaN goes to the safe branch), as in the rest of `brdf`.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod ggx;
mod ggx_table;
pub(crate) mod quadrature;
pub mod report;

#[cfg(test)]
mod tests;

use super::microfacet::{COS_EPS, beckmann_lambda, ggx_visibility, schlick_fresnel};
use super::models::coupled_diffuse_weight;
use super::{Brdf, Distribution};
use crate::math::sg::Sg;
use glam::{DVec3, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

pub use quadrature::integrate_hemisphere;

/// Largest number of SG lobes of one BRDF fit.
pub const MAX_LOBES: usize = 4;

/// Number of SG lobes used for the GGX NDF by [`warped_lobes`]: the relative L2 error of the
/// (energy-preserving) NDF fit is ≤ 23.3 % with 1 lobe, 4.5 % with 2, 1.2 % with 3 and 0.36 %
/// with 4 over the table's α ∈ [1e-3, 1]; with 3 lobes it is well below the other errors of
/// the warped fit at every view angle (see `results/brdf-fits.md`). Use [`warped_lobes_k`] to
/// choose.
pub const GGX_DEFAULT_LOBES: usize = 3;

/// An SG lobe of an NDF (in the half-vector domain, axis n) or of the Phong lobe (axis r),
/// before warping: sharpness λ and scalar amplitude μ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NdfLobe {
    pub sharpness: f32,
    pub amplitude: f32,
}

/// The SG approximation of a BRDF for one view direction:
/// f(wo, wi) ≈ `diffuse` + Σ `lobes()`(wi).
///
/// The lobes are in the local shading frame (z = normal), over the incident direction wi, with
/// the smooth factors (Fresnel, masking-shadowing, 1/(4 cos θi cos θo), ks) already multiplied
/// into the amplitudes. The cosine max(0, wi.z) is **not** included.
///
/// Fixed capacity, no allocation: `lobes[..len]` are the lobes; the unused entries are
/// [`Sg`]s with zero amplitude (and sharpness 0, axis +z), so summing all [`MAX_LOBES`] entries
/// is also correct.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrdfSg {
    /// The constant diffuse term (1/sr), kd/π for every model except Cook-Torrance, where it is
    /// kd · w(cos θo) / π: the exact diffuse kd w(μi) w(μo)/(π S̄) with w(μi) replaced by its
    /// cosine-weighted hemispherical mean S̄, so the diffuse albedo is preserved (up to the
    /// rounding of S̄ in `COUPLED_DIFFUSE_NORM`, 6e-8 relative).
    pub diffuse: Vec3,
    /// The lobes; only the first `len` are meaningful, the rest have zero amplitude.
    pub lobes: [Sg; MAX_LOBES],
    /// Number of lobes in use (0 for Lambert and for wo below the horizon).
    pub len: usize,
}

/// An SG that evaluates to zero everywhere.
const ZERO_SG: Sg = Sg {
    axis: Vec3::Z,
    sharpness: 0.0,
    amplitude: Vec3::ZERO,
};

impl BrdfSg {
    /// Zero BRDF: no diffuse, no lobes.
    pub const ZERO: BrdfSg = BrdfSg {
        diffuse: Vec3::ZERO,
        lobes: [ZERO_SG; MAX_LOBES],
        len: 0,
    };

    /// The lobes in use.
    #[inline]
    pub fn lobes(&self) -> &[Sg] {
        &self.lobes[..self.len]
    }

    /// diffuse + Σ lobes(wi), in 1/sr, without the cosine; zero for wi below the horizon
    /// (like [`Brdf::eval`]).
    ///
    /// Each lobe is μ exp(min(0, λ (wi·p − 1))): the clamp matters for the sharpest warped
    /// lobes (λ up to ~1e13 at wo.z = 1e-7), where f32 rounding can make wi·p exceed 1 by
    /// ~1e-7 and the unclamped exponential overflows.
    pub fn eval(&self, wi: Vec3) -> Vec3 {
        if !(wi.z > 0.0) {
            return Vec3::ZERO;
        }
        self.lobes().iter().fold(self.diffuse, |a, l| {
            a + l.amplitude * (l.sharpness * (wi.dot(l.axis) - 1.0)).min(0.0).exp()
        })
    }

    /// As [`BrdfSg::eval`] but in f64 with 1 − wi·p computed as |wi − p|²/2, which keeps full
    /// relative precision for very sharp lobes (used by [`fit_error`] and the report).
    pub fn eval_f64(&self, wi: DVec3) -> DVec3 {
        if !(wi.z > 0.0) {
            return DVec3::ZERO;
        }
        let mut s = self.diffuse.as_dvec3();
        for l in self.lobes() {
            let d = 0.5 * (wi - l.axis.as_dvec3()).length_squared();
            s += l.amplitude.as_dvec3() * (-(l.sharpness as f64) * d).exp();
        }
        s
    }

    fn push(&mut self, sg: Sg) {
        if self.len < MAX_LOBES {
            self.lobes[self.len] = sg;
            self.len += 1;
        }
    }
}

/// The unwarped lobes of a model's NDF (half-vector domain; for Phong the lobe around r) and
/// their count: Blinn-Phong / Phong λ = n, μ = (n+2)/(2π); Beckmann λ = 2/α², μ = 1/(π α²);
/// GGX `ggx_lobes` lobes (clamped to 1..=[`MAX_LOBES`]) from the fitted table. Lambert: none.
/// Amplitudes do not include ks / F0.
pub fn ndf_lobes(brdf: &Brdf, ggx_lobes: usize) -> ([NdfLobe; MAX_LOBES], usize) {
    let mut out = [NdfLobe {
        sharpness: 0.0,
        amplitude: 0.0,
    }; MAX_LOBES];
    let n = match *brdf {
        Brdf::Lambert { .. } => 0,
        Brdf::Phong { exponent, .. } | Brdf::BlinnPhong { exponent, .. } => {
            let e = exponent.max(0.0);
            out[0] = NdfLobe {
                sharpness: e,
                amplitude: (e + 2.0) / (2.0 * PI),
            };
            1
        }
        Brdf::Ward { roughness, .. }
        | Brdf::CookTorrance {
            roughness,
            distribution: Distribution::Beckmann,
            ..
        } => {
            let a2 = roughness * roughness;
            out[0] = NdfLobe {
                sharpness: 2.0 / a2,
                amplitude: 1.0 / (PI * a2),
            };
            1
        }
        Brdf::CookTorrance {
            roughness,
            distribution: Distribution::Ggx,
            ..
        } => {
            let k = ggx_lobes.clamp(1, MAX_LOBES);
            let lobes = ggx::ggx_ndf_lobes(roughness, k);
            out[..k].copy_from_slice(&lobes[..k]);
            k
        }
    };
    (out, n)
}

/// [`warped_lobes_k`] with [`GGX_DEFAULT_LOBES`] lobes for GGX.
pub fn warped_lobes(brdf: &Brdf, wo_local: Vec3) -> BrdfSg {
    warped_lobes_k(brdf, wo_local, GGX_DEFAULT_LOBES)
}

/// The SG approximation of `brdf` for the view direction `wo_local` (local frame, unit,
/// z = normal), with `ggx_lobes` (1..=4) lobes for a GGX NDF (ignored by the other models).
///
/// With co = max(wo.z, 1e-7) and r = 2 co n − wo = (−wo.x, −wo.y, wo.z), every lobe has axis r
/// and, per model (ks = `specular`, NDF lobes (λ, μ) from [`ndf_lobes`]):
///
/// | model | sharpness | amplitude |
/// |---|---|---|
/// | Phong | n | ks (n+2)/(2π) |
/// | Blinn-Phong | n / (4 co) | ks (n+2)/(2π) · 1/(4 co²)  (V-cavity G = 1 at wi = r) |
/// | Ward | λ / (4 co) | ks μ / (4 co²)  (1/(4 (wo·h)²) at h = n) |
/// | Cook-Torrance | λ_k / (4 co) | μ_k · F(co) · G2(wo, r) / (4 co²) |
///
/// `diffuse` is kd/π (Cook-Torrance: kd w(co)/π, see [`BrdfSg::diffuse`]). Returns
/// [`BrdfSg::ZERO`] when wo is below the horizon or not finite.
pub fn warped_lobes_k(brdf: &Brdf, wo_local: Vec3, ggx_lobes: usize) -> BrdfSg {
    let mut out = BrdfSg::ZERO;
    let Some(wo) = wo_local.try_normalize() else {
        return out;
    };
    if !(wo.z > 0.0) {
        return out;
    }
    let co = wo.z.max(COS_EPS);
    let r = Vec3::new(-wo.x, -wo.y, wo.z);
    let kd = brdf.diffuse();
    let ks = brdf.specular();
    let (ndf, n) = ndf_lobes(brdf, ggx_lobes);
    // Sharpness factor of the warp and the scalar smooth factor (without ks / Fresnel).
    let (warp, smooth, colour) = match *brdf {
        Brdf::Lambert { diffuse } => {
            out.diffuse = diffuse * FRAC_1_PI;
            return out;
        }
        Brdf::Phong { .. } => {
            out.diffuse = kd * FRAC_1_PI;
            (1.0, 1.0, ks)
        }
        Brdf::BlinnPhong { .. } | Brdf::Ward { .. } => {
            out.diffuse = kd * FRAC_1_PI;
            (1.0 / (4.0 * co), 1.0 / (4.0 * co * co), ks)
        }
        Brdf::CookTorrance {
            roughness,
            distribution,
            ..
        } => {
            out.diffuse = kd * (coupled_diffuse_weight(wo) * FRAC_1_PI);
            // G2 / (4 ci co) at wi = r (ci = co, Λ(r) = Λ(wo)).
            let vis = match distribution {
                Distribution::Ggx => ggx_visibility(wo, r, roughness),
                Distribution::Beckmann => {
                    1.0 / ((1.0 + 2.0 * beckmann_lambda(wo, roughness)) * 4.0 * co * co)
                }
            };
            (1.0 / (4.0 * co), vis, schlick_fresnel(ks, co))
        }
    };
    for l in &ndf[..n] {
        out.push(Sg {
            axis: r,
            sharpness: l.sharpness * warp,
            amplitude: colour * (l.amplitude * smooth),
        });
    }
    out
}

/// Relative L2 error of [`warped_lobes`] against the exact [`Brdf::eval`], see
/// [`fit_error_of`].
pub fn fit_error(brdf: &Brdf, wo_local: Vec3) -> f64 {
    fit_error_of(brdf, wo_local, &warped_lobes(brdf, wo_local))
}

/// Relative L2 error of the approximation `sg` of `brdf` at the view direction `wo_local`,
/// cosine-weighted over the upper hemisphere of wi, per RGB channel c:
///
/// e_c = sqrt( ∫ (f_sg,c − f_c)² cos θi dωi / ∫ f_c² cos θi dωi ),
///
/// with f_sg = `sg.eval` (diffuse + lobes, in f64) and f = `brdf.eval(wo, wi)`; the result is
/// the mean of e_c over the channels with ∫ f_c² cos > 0 (0 when f_sg and f are both zero
/// everywhere, +∞ when only f_sg is nonzero). Integrated with [`integrate_hemisphere`]
/// (half-vector coordinates about the mirror configuration, geometric θh panels from
/// 1e-7 rad; validated against closed forms by the tests).
pub fn fit_error_of(brdf: &Brdf, wo_local: Vec3, sg: &BrdfSg) -> f64 {
    fit_stats(brdf, wo_local, sg).rel_l2_error
}

/// Error statistics of an SG approximation, see [`fit_stats`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FitStats {
    /// [`fit_error_of`].
    pub rel_l2_error: f64,
    /// Directional albedo of the approximation over that of the exact BRDF,
    /// ∫ f_sg cos θi dωi / ∫ f cos θi dωi over the upper hemisphere, mean over the channels
    /// with nonzero albedo (1 = energy preserved; NaN if the exact albedo is zero).
    pub albedo_ratio: f64,
}

/// [`fit_error_of`] and the albedo ratio, from one quadrature.
pub fn fit_stats(brdf: &Brdf, wo_local: Vec3, sg: &BrdfSg) -> FitStats {
    let zero = FitStats {
        rel_l2_error: 0.0,
        albedo_ratio: f64::NAN,
    };
    let Some(wo) = wo_local.try_normalize() else {
        return zero;
    };
    if !(wo.z > 0.0) {
        return zero;
    }
    let sums = integrate_hemisphere(wo.as_dvec3(), |wi| {
        let f = brdf.eval(wo, wi.as_vec3()).as_dvec3();
        let g = sg.eval_f64(wi);
        let d = g - f;
        let c = wi.z.max(0.0);
        [
            d.x * d.x * c,
            d.y * d.y * c,
            d.z * d.z * c,
            f.x * f.x * c,
            f.y * f.y * c,
            f.z * f.z * c,
            f.x * c,
            f.y * c,
            f.z * c,
            g.x * c,
            g.y * c,
            g.z * c,
        ]
    });
    let (mut l2, mut n_l2, mut residual) = (0.0, 0, 0.0);
    let (mut ratio, mut n_ratio) = (0.0, 0);
    for c in 0..3 {
        residual += sums[c];
        if sums[c + 3] > 0.0 {
            l2 += (sums[c] / sums[c + 3]).sqrt();
            n_l2 += 1;
        }
        if sums[c + 6] > 0.0 {
            ratio += sums[c + 9] / sums[c + 6];
            n_ratio += 1;
        }
    }
    FitStats {
        rel_l2_error: if n_l2 > 0 {
            l2 / n_l2 as f64
        } else if residual > 0.0 {
            f64::INFINITY
        } else {
            0.0
        },
        albedo_ratio: if n_ratio > 0 {
            ratio / n_ratio as f64
        } else {
            f64::NAN
        },
    }
}

/// The factor by which a renderer can multiply [`BrdfSg::diffuse`] to recover the exact
/// diffuse term for the incident direction `wi_local`: w(cos θi)/S̄ for Cook-Torrance (its
/// coupled diffuse weight over its cosine-weighted mean, see `docs/brdf.md`), 1 for the other
/// models. Its cosine-weighted hemispherical mean is 1. Optional: the SG renderer may use the
/// constant instead (error: the `ct-diffuse` rows of `results/brdf-fits.md`).
pub fn diffuse_wi_factor(brdf: &Brdf, wi_local: Vec3) -> f32 {
    match brdf {
        Brdf::CookTorrance { .. } => {
            coupled_diffuse_weight(wi_local) / super::models::COUPLED_DIFFUSE_NORM
        }
        _ => 1.0,
    }
}
