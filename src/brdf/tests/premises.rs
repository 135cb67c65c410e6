//! The premises of the energy arguments in docs/brdf.md: NDF normalisation, the projected-area
//! constraint of the masking functions, the coupled-diffuse normalisation and the bound of
//! Schlick's grazing term by the coupled-diffuse weight.

use super::{FINE, dir, integrate_upper_about};
use crate::brdf::microfacet::{
    beckmann_d, beckmann_lambda, blinn_phong_d, ggx_d, ggx_lambda, v_cavity_g1,
};
use crate::brdf::models::{COUPLED_DIFFUSE_NORM, coupled_diffuse_weight};
use crate::math::sampling::{Rng, uniform_sphere};
use glam::{DVec3, Vec3};

/// Roughness values checked (the furnace sweep's).
const ROUGHNESS: [f32; 11] = [1e-3, 3e-3, 0.01, 0.03, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0];
/// Exponents checked (the furnace sweep's).
const EXPONENTS: [f32; 9] = [0.0, 1.0, 5.0, 20.0, 100.0, 1e3, 1e4, 1e5, 1e6];

/// Energy-argument premise: every NDF is normalised, ∫ D(h) cos θh dωh = 1.
#[test]
fn ndfs_are_normalised() {
    let mut worst = 0.0f64;
    for a in ROUGHNESS {
        let b = integrate_upper_about(Vec3::Z, FINE, |h| {
            DVec3::splat((beckmann_d(h, a) * h.z) as f64)
        })
        .x;
        let g =
            integrate_upper_about(Vec3::Z, FINE, |h| DVec3::splat((ggx_d(h, a) * h.z) as f64)).x;
        // GGX's tail D cos ~ α²/(π cos³θ ...) is captured by the quadrature up to ~1e-7; f32
        // evaluation of D adds ~1e-7 relative. 1e-5 is generous but far below any missing
        // normalisation factor.
        worst = worst.max((b - 1.0).abs()).max((g - 1.0).abs());
        assert!((b - 1.0).abs() < 1e-5, "Beckmann α={a}: {b}");
        assert!((g - 1.0).abs() < 1e-5, "GGX α={a}: {g}");
    }
    for n in EXPONENTS {
        let v = integrate_upper_about(Vec3::Z, FINE, |h| {
            DVec3::splat((blinn_phong_d(h, n) * h.z) as f64)
        })
        .x;
        worst = worst.max((v - 1.0).abs());
        assert!((v - 1.0).abs() < 1e-5, "Blinn-Phong n={n}: {v}");
    }
    println!("NDF normalisation: worst |∫D cos − 1| = {worst:.1e}");
}

/// Energy-argument premise: the masking functions satisfy the projected-area constraint
/// ∫ G1(wo, h) max(0, wo·h) D(h) dωh = cos θo (Heitz 2014) — Smith G1 = 1/(1 + Λ) for
/// Beckmann and GGX, and the V-cavity G1 with the Blinn-Phong NDF.
#[test]
fn masking_satisfies_projected_area_constraint() {
    let mut worst = 0.0f64;
    for &c in &[1.0f32, 0.7, 0.3, 0.1, 0.02] {
        let wo = dir(c, 0.4);
        for a in [1e-3f32, 0.05, 0.3, 1.0] {
            let smith = |d: fn(Vec3, f32) -> f32, l: fn(Vec3, f32) -> f32| {
                let g1 = 1.0 / (1.0 + l(wo, a));
                integrate_upper_about(Vec3::Z, FINE, |h| {
                    DVec3::splat((g1 * wo.dot(h).max(0.0) * d(h, a)) as f64)
                })
                .x
            };
            let b = smith(beckmann_d, beckmann_lambda);
            let g = smith(ggx_d, ggx_lambda);
            worst = worst
                .max((b / c as f64 - 1.0).abs())
                .max((g / c as f64 - 1.0).abs());
            // erfc has relative error 1.2e-7; the integrand has kinks (at wo·h = 0, and the
            // V-cavity min()) inside the quadrature rings, where it converges only as O(h²):
            // measured worst 9.6e-6 relative; 5e-5 leaves margin yet is far below the
            // percent-level error of a wrong Λ or a non-normalised masking function.
            assert!(
                (b / c as f64 - 1.0).abs() < 5e-5,
                "Beckmann α={a} cosθo={c}: {}",
                b / c as f64
            );
            assert!(
                (g / c as f64 - 1.0).abs() < 5e-5,
                "GGX α={a} cosθo={c}: {}",
                g / c as f64
            );
        }
        for n in [0.0f32, 1.0, 20.0, 1000.0] {
            let v = integrate_upper_about(Vec3::Z, FINE, |h| {
                DVec3::splat((v_cavity_g1(wo, h) * wo.dot(h).max(0.0) * blinn_phong_d(h, n)) as f64)
            })
            .x;
            worst = worst.max((v / c as f64 - 1.0).abs());
            assert!(
                (v / c as f64 - 1.0).abs() < 5e-5,
                "V-cavity n={n} cosθo={c}: {}",
                v / c as f64
            );
        }
    }
    println!("projected-area constraint: worst relative error {worst:.1e}");
}

/// The constant S̄ of the coupled diffuse term is 2 ∫₀¹ w(μ) μ dμ, rounded up.
#[test]
fn coupled_diffuse_normalisation() {
    let s = integrate_upper_about(Vec3::Z, FINE, |w| {
        DVec3::splat((coupled_diffuse_weight(w) * w.z) as f64 / std::f64::consts::PI)
    })
    .x;
    // The f64 Simpson value is 0.841187953129302; f32 evaluation of w adds ~1e-7.
    assert!((s - 0.841_187_953_129_302).abs() < 1e-6, "{s}");
    assert!(COUPLED_DIFFUSE_NORM as f64 >= 0.841_187_953_129_302);
    assert!((COUPLED_DIFFUSE_NORM as f64 - s).abs() < 1e-6);
}

/// The lemma behind the Cook-Torrance energy bound: for every wo and every above-horizon wi,
/// Schlick's grazing term (1 − wo·h)^5 ≤ 1 − w(cos θo). Checked in f64 over random pairs and
/// the worst case (wi on the horizon opposite wo), where it is an equality; and the f32
/// implementation of w against the f64 formula.
#[test]
fn coupled_weight_bounds_the_fresnel_excess() {
    let w64 = |o: DVec3| {
        let s = (o.x * o.x + o.y * o.y).sqrt();
        1.0 - (1.0 - o.z / (2.0 * (1.0 + s)).sqrt()).powi(5)
    };
    let mut rng = Rng::keyed(0xF5E1, 0, 0);
    let mut worst_impl = 0.0f64;
    for k in 0..200_000 {
        let a = uniform_sphere(rng.vec2()).as_dvec3();
        let b = uniform_sphere(rng.vec2()).as_dvec3();
        let wo = DVec3::new(a.x, a.y, a.z.abs().max(1e-9)).normalize();
        let wi = if k % 4 == 0 {
            // On the horizon, opposite wo: the minimiser of wo·h.
            DVec3::new(-wo.x, -wo.y, 0.0)
                .try_normalize()
                .unwrap_or(DVec3::X)
        } else {
            DVec3::new(b.x, b.y, b.z.abs()).normalize()
        };
        let oh = 0.5 * (wo + wi).length();
        let excess = (1.0 - oh).powi(5);
        // 1e-12: f64 rounding at the equality case.
        assert!(
            excess <= 1.0 - w64(wo) + 1e-12,
            "wo={wo:?} wi={wi:?}: {excess} > {}",
            1.0 - w64(wo)
        );
        worst_impl = worst_impl.max((coupled_diffuse_weight(wo.as_vec3()) as f64 - w64(wo)).abs());
    }
    // f32 evaluation of w: a few ulps (measured ~2e-7).
    assert!(worst_impl < 1e-6, "{worst_impl}");
}
