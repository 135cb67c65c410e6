//! The parameter sweep behind `interreflect fit`: per model, parameter and view angle, the
//! warped lobes and the relative L2 error, and plane-of-incidence slices for the plots.

use super::{BrdfSg, GGX_DEFAULT_LOBES, fit_stats, warped_lobes_k};
use crate::brdf::{Brdf, Distribution};
use glam::Vec3;
use rayon::prelude::*;

/// Phong / Blinn-Phong exponents of the sweep.
pub const EXPONENTS: [f32; 5] = [1.0, 10.0, 100.0, 1000.0, 10000.0];
/// Ward / Beckmann / GGX roughnesses α of the sweep.
pub const ALPHAS: [f32; 7] = [1.0, 0.5, 0.2, 0.1, 0.05, 0.02, 0.01];
/// View angles θo of the sweep, degrees.
pub const THETA_O_DEG: [f32; 3] = [0.0, 45.0, 75.0];

/// A model family of the sweep, with the fixed colours used for it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Family {
    /// ks = 1, kd = 0.
    Phong,
    /// ks = 1, kd = 0.
    BlinnPhong,
    /// ks = 1, kd = 0.
    Ward,
    /// Cook-Torrance Beckmann, F0 = 1 (F ≡ 1), kd = 0.
    Beckmann,
    /// Cook-Torrance GGX, F0 = 1 (F ≡ 1), kd = 0.
    Ggx,
    /// Cook-Torrance Beckmann with F0 = 0.04 (dielectric), kd = 0.
    BeckmannF004,
    /// Cook-Torrance GGX with F0 = 0.04 (dielectric), kd = 0.
    GgxF004,
    /// Cook-Torrance GGX α = 0.5, kd = 1, F0 = 0: the coupled diffuse term alone.
    CookTorranceDiffuse,
}

impl Family {
    /// Short name used in tables, JSON and plot file names.
    pub fn name(self) -> &'static str {
        match self {
            Family::Phong => "phong",
            Family::BlinnPhong => "blinn-phong",
            Family::Ward => "ward",
            Family::Beckmann => "ct-beckmann",
            Family::Ggx => "ct-ggx",
            Family::BeckmannF004 => "ct-beckmann-f0.04",
            Family::GgxF004 => "ct-ggx-f0.04",
            Family::CookTorranceDiffuse => "ct-diffuse",
        }
    }

    /// "exponent" or "alpha".
    pub fn parameter_name(self) -> &'static str {
        match self {
            Family::Phong | Family::BlinnPhong => "exponent",
            _ => "alpha",
        }
    }

    /// The swept parameter values.
    pub fn parameters(self) -> &'static [f32] {
        match self {
            Family::Phong | Family::BlinnPhong => &EXPONENTS,
            // The coupled diffuse term does not depend on α.
            Family::CookTorranceDiffuse => &[0.5],
            _ => &ALPHAS,
        }
    }

    /// The BRDF for parameter value `p`.
    pub fn brdf(self, p: f32) -> Brdf {
        let one = Vec3::ONE;
        let zero = Vec3::ZERO;
        let ct = |distribution, f0: f32, kd: f32| Brdf::CookTorrance {
            diffuse: Vec3::splat(kd),
            specular: Vec3::splat(f0),
            roughness: p,
            distribution,
        };
        match self {
            Family::Phong => Brdf::Phong {
                diffuse: zero,
                specular: one,
                exponent: p,
            },
            Family::BlinnPhong => Brdf::BlinnPhong {
                diffuse: zero,
                specular: one,
                exponent: p,
            },
            Family::Ward => Brdf::Ward {
                diffuse: zero,
                specular: one,
                roughness: p,
            },
            Family::Beckmann => ct(Distribution::Beckmann, 1.0, 0.0),
            Family::Ggx => ct(Distribution::Ggx, 1.0, 0.0),
            Family::BeckmannF004 => ct(Distribution::Beckmann, 0.04, 0.0),
            Family::GgxF004 => ct(Distribution::Ggx, 0.04, 0.0),
            Family::CookTorranceDiffuse => ct(Distribution::Ggx, 0.0, 1.0),
        }
    }

    /// Numbers of GGX lobes reported (1..=4 for GGX F0 = 1, the default otherwise).
    pub fn lobe_counts(self) -> &'static [usize] {
        match self {
            Family::Ggx => &[1, 2, 3, 4],
            _ => &[GGX_DEFAULT_LOBES],
        }
    }

    /// Whether the lobe count matters for this family.
    pub fn is_ggx(self) -> bool {
        matches!(
            self,
            Family::Ggx | Family::GgxF004 | Family::CookTorranceDiffuse
        )
    }

    /// All families, in report order.
    pub const ALL: [Family; 8] = [
        Family::Phong,
        Family::BlinnPhong,
        Family::Ward,
        Family::Beckmann,
        Family::Ggx,
        Family::BeckmannF004,
        Family::GgxF004,
        Family::CookTorranceDiffuse,
    ];
}

/// One warped lobe (local frame).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct LobeRow {
    pub axis: [f32; 3],
    pub sharpness: f32,
    pub amplitude: [f32; 3],
}

/// One row of the sweep. JSON keys are the field names.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FitRow {
    /// [`Family::name`].
    pub model: &'static str,
    /// "exponent" or "alpha".
    pub parameter: &'static str,
    pub value: f32,
    pub theta_o_deg: f32,
    /// Number of GGX lobes requested (null for non-GGX models).
    pub ggx_lobes: Option<usize>,
    /// The constant diffuse term (1/sr).
    pub diffuse: [f32; 3],
    pub lobes: Vec<LobeRow>,
    /// [`super::fit_error_of`]: relative L2 error, cosine-weighted, mean over channels.
    pub rel_l2_error: f64,
    /// [`super::FitStats::albedo_ratio`]: SG albedo / exact albedo.
    pub albedo_ratio: f64,
}

/// wo at polar angle `theta_o_deg` in the xz-plane (azimuth 0).
pub fn view_dir(theta_o_deg: f32) -> Vec3 {
    let t = theta_o_deg.to_radians();
    Vec3::new(t.sin(), 0.0, t.cos())
}

/// One row: the warped fit of `family` at parameter `p`, view angle θo, `k` GGX lobes.
pub fn row(family: Family, p: f32, theta_o_deg: f32, k: usize) -> FitRow {
    let brdf = family.brdf(p);
    let wo = view_dir(theta_o_deg);
    let sg: BrdfSg = warped_lobes_k(&brdf, wo, k);
    let stats = fit_stats(&brdf, wo, &sg);
    FitRow {
        model: family.name(),
        parameter: family.parameter_name(),
        value: p,
        theta_o_deg,
        ggx_lobes: family.is_ggx().then_some(k),
        diffuse: sg.diffuse.to_array(),
        lobes: sg
            .lobes()
            .iter()
            .map(|l| LobeRow {
                axis: l.axis.to_array(),
                sharpness: l.sharpness,
                amplitude: l.amplitude.to_array(),
            })
            .collect(),
        rel_l2_error: stats.rel_l2_error,
        albedo_ratio: stats.albedo_ratio,
    }
}

/// The whole sweep (in parallel with rayon; deterministic order): for every family, lobe
/// count, parameter and θo in [`THETA_O_DEG`].
pub fn sweep() -> Vec<FitRow> {
    let mut jobs = Vec::new();
    for f in Family::ALL {
        for &k in f.lobe_counts() {
            for &p in f.parameters() {
                for t in THETA_O_DEG {
                    jobs.push((f, k, p, t));
                }
            }
        }
    }
    jobs.par_iter()
        .map(|&(f, k, p, t)| row(f, p, t, k))
        .collect()
}

/// A slice in the plane of incidence: wo = [`view_dir`]`(theta_o_deg)`,
/// wi = (−sin θi, 0, cos θi) for θi ∈ [−90°, 90°] (`n` points), so the mirror direction is at
/// θi = +θo. Returns (θi in degrees, exact f·cos θi, SG f·cos θi).
pub fn plane_slice(
    brdf: &Brdf,
    theta_o_deg: f32,
    k: usize,
    n: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let wo = view_dir(theta_o_deg);
    let sg = warped_lobes_k(brdf, wo, k);
    let mut th = Vec::with_capacity(n);
    let mut exact = Vec::with_capacity(n);
    let mut approx = Vec::with_capacity(n);
    for i in 0..n {
        let t = -90.0 + 180.0 * i as f64 / (n - 1).max(1) as f64;
        let r = t.to_radians();
        let wi = glam::DVec3::new(-r.sin(), 0.0, r.cos());
        let c = wi.z.max(0.0);
        let lum = |v: glam::DVec3| (v.x + v.y + v.z) / 3.0;
        th.push(t);
        exact.push(lum(brdf.eval(wo, wi.as_vec3()).as_dvec3()) * c);
        approx.push(lum(sg.eval_f64(wi)) * c);
    }
    (th, exact, approx)
}
