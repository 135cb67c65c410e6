//! Tests of the SG fits: quadrature against closed forms, peak values, error ceilings, the GGX
//! table, warp symmetry and robustness.

use super::ggx::{self, Problem, table_alpha};
use super::quadrature::gauss_legendre;
use super::report::{ALPHAS, EXPONENTS, Family, THETA_O_DEG, view_dir};
use super::*;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI as PI64;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Phong albedo (ks = 1) by an independent 1D rule: polar angle β about r, with the azimuthal
/// integral of max(0, wi.z) over the ring in closed form (wi.z = a + b cos γ with
/// a = cos β cos θo, b = sin β sin θo: ∫ max(0, a + b cos γ) dγ = 2 (a γ0 + b sin γ0),
/// γ0 = acos(−a/b) clamped to [0, π]).
fn phong_albedo_1d(n: f64, theta_o: f64) -> f64 {
    let (so, co) = theta_o.sin_cos();
    let mut sum = 0.0;
    let gl = gauss_legendre(8);
    // β panels geometric from 1e-6 to π/2 (the lobe is cut at r·wi = 0).
    let mut edges = vec![0.0];
    let mut e = 1e-6;
    while e < std::f64::consts::FRAC_PI_2 {
        edges.push(e);
        e *= 1.1;
    }
    edges.push(std::f64::consts::FRAC_PI_2);
    for p in edges.windows(2) {
        let h = 0.5 * (p[1] - p[0]);
        for &(x, w) in &gl {
            let beta = p[0] + h * (x + 1.0);
            let (sb, cb) = beta.sin_cos();
            let a = cb * co;
            let b = sb * so;
            let g0 = if b <= 0.0 {
                if a > 0.0 { PI64 } else { 0.0 }
            } else {
                (-a / b).clamp(-1.0, 1.0).acos()
            };
            let ring = 2.0 * (a * g0 + b * g0.sin());
            sum += h * w * (n + 2.0) / (2.0 * PI64) * cb.powf(n) * sb * ring;
        }
    }
    sum
}

#[test]
fn quadrature_integrates_the_cosine() {
    // ∫ cos θi dωi = π over the hemisphere, including the horizon-clipped rings at grazing.
    for t in [0.0f32, 30.0, 45.0, 75.0, 89.0, 89.9] {
        let v = integrate_hemisphere(view_dir(t).as_dvec3(), |wi| [wi.z]);
        assert!(rel(v[0], PI64) < 1e-5, "θo {t}: {}", v[0]);
    }
}

#[test]
fn quadrature_matches_closed_forms_for_sharp_lobes() {
    // Phong (ks = 1) albedo = cos θo exactly when the lobe does not reach the horizon (the
    // clipped part is ≤ cos^n(horizon distance): < 1e-40 in these cases), for lobes down to
    // 1e-3 rad wide, anisotropic by 1/cos θo in half-vector space.
    for (n, t) in [
        (100.0f32, 0.0f32),
        (100.0, 45.0),
        (1e4, 0.0),
        (1e4, 45.0),
        (1e4, 75.0),
        (1e6, 0.0),
        (1e6, 45.0),
        (1e6, 75.0),
        (1e6, 89.0),
    ] {
        let b = Brdf::Phong {
            diffuse: Vec3::ZERO,
            specular: Vec3::ONE,
            exponent: n,
        };
        let wo = view_dir(t);
        let v = integrate_hemisphere(wo.as_dvec3(), |wi| {
            [b.eval(wo, wi.as_vec3()).x as f64 * wi.z]
        });
        // Measured ≤ 6e-7, except 4.4e-6 for n = 1e6 at θo = 89° (a lobe 1e-3 rad wide and
        // 57 times narrower out of plane in half-vector space).
        assert!(rel(v[0], wo.z as f64) < 1e-5, "n {n} θo {t}: {}", v[0]);
    }
    // ∫ G(wi; r, λ)² cos θi dωi for an SG around the mirror direction (f64 integrand), against
    // the whole-sphere closed form cos θo · 2π [(1/a − 1/a²) + e^{−2a}(1/a + 1/a²)], a = 2λ
    // (the part below the horizon is < e^{−2a(1−sin θo)} ≈ 1e-15 or less here).
    for (lam, t) in [
        (1e2f64, 0.0f32),
        (1e2, 45.0),
        (1e4, 45.0),
        (1e4, 75.0),
        (1e6, 75.0),
        (1e6, 89.0),
        (1e7, 89.0),
    ] {
        let wo = view_dir(t).as_dvec3();
        let r = DVec3::new(-wo.x, -wo.y, wo.z);
        let v = integrate_hemisphere(wo, |wi| {
            [(-2.0 * lam * 0.5 * (wi - r).length_squared()).exp() * wi.z]
        });
        let a = 2.0 * lam;
        let exact = wo.z
            * 2.0
            * PI64
            * ((1.0 / a - 1.0 / (a * a)) + (-2.0 * a).exp() * (1.0 / a + 1.0 / (a * a)));
        assert!(
            rel(v[0], exact) < 5e-5,
            "λ {lam} θo {t}: {} vs {exact}",
            v[0]
        );
    }
}

#[test]
fn quadrature_matches_independent_rule_for_clipped_lobes() {
    // Phong lobes cut by the horizon (broad lobes, grazing views) against `phong_albedo_1d`.
    // Measured: ≤ 2.3e-6, except n = 1 at θo = 89° (5.3e-4: the lobe's kink at r·wi = 0 cuts
    // across the rings of the half-vector rule there; for n ≥ 2 the integrand is C¹).
    for (n, t, tol) in [
        (1.0f32, 45.0f32, 1e-5),
        (1.0, 89.0, 1e-3),
        (10.0, 75.0, 1e-5),
        (10.0, 89.9, 1e-5),
        (100.0, 75.0, 1e-5),
        (100.0, 89.0, 1e-5),
        (1e4, 89.0, 1e-5),
    ] {
        let b = Brdf::Phong {
            diffuse: Vec3::ZERO,
            specular: Vec3::ONE,
            exponent: n,
        };
        let wo = view_dir(t);
        let v = integrate_hemisphere(wo.as_dvec3(), |wi| {
            [b.eval(wo, wi.as_vec3()).x as f64 * wi.z]
        });
        let want = phong_albedo_1d(n as f64, (t as f64).to_radians());
        assert!(rel(v[0], want) < tol, "n {n} θo {t}: {} vs {want}", v[0]);
    }
}

#[test]
fn fit_error_reaches_the_closed_form_warp_floor() {
    // For very sharp lobes the exact BRDF lobe in wi is a Gaussian with widths in the ratio
    // r = 1/cos θo (in-plane vs out-of-plane), while the warped SG is isotropic with the
    // geometric-mean width and the same peak. The relative L2 error between the two is
    // sqrt(2 − 4 √r / (r + 1)) (0.1725 at 45°, 0.6194 at 75°): a closed-form check of
    // fit_error and of the quadrature on anisotropic integrands.
    for t in [0.0f32, 45.0, 75.0] {
        let r = 1.0 / (t as f64).to_radians().cos();
        let floor = (2.0 - 4.0 * r.sqrt() / (r + 1.0)).max(0.0).sqrt();
        let b = Family::Ward.brdf(1e-3);
        let e = fit_error(&b, view_dir(t));
        assert!((e - floor).abs() < 1e-3, "θo {t}: {e} vs {floor}");
    }
}

/// Specular-only BRDFs over the glossy range, for the peak test.
fn peak_cases() -> Vec<(Family, f32)> {
    let mut v = Vec::new();
    for f in [Family::Phong, Family::BlinnPhong] {
        for n in [10.0, 100.0, 1000.0, 1e4, 1e6] {
            v.push((f, n));
        }
    }
    for f in [
        Family::Ward,
        Family::Beckmann,
        Family::Ggx,
        Family::BeckmannF004,
        Family::GgxF004,
    ] {
        for a in [1e-3, 0.01, 0.1, 0.3, 0.5] {
            v.push((f, a));
        }
    }
    v
}

#[test]
fn peak_matches_the_exact_brdf() {
    // At the lobe peak wi = r every smooth factor is evaluated exactly where the method
    // evaluates it, and every NDF SG (except GGX's) equals the NDF at h = n, so
    // Σ lobes(r) = f(wo, r) up to f32 rounding (tolerance 2e-5). GGX: Σ_k μ_k is a
    // least-squares fit of D(n) = 1/(π α²), not an interpolation: over the table columns
    // |Σ m_k − 1| ≤ 19.3 % (K = 1), 4.1 % (2), 1.12 % (3), 0.35 % (4); tolerance 2 % for the
    // default K = 3 (interpolation between columns included).
    let mut worst_ggx: f64 = 0.0;
    for (f, p) in peak_cases() {
        let brdf = f.brdf(p);
        for t in [0.0f32, 45.0, 75.0, 89.0] {
            let wo = view_dir(t);
            let sg = warped_lobes(&brdf, wo);
            let r = sg.lobes()[0].axis;
            assert!((r - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
            let approx = sg.eval_f64(r.as_dvec3()).x;
            let exact = brdf.eval(wo, r).x as f64;
            let e = rel(approx, exact);
            if f.is_ggx() {
                worst_ggx = worst_ggx.max(e);
                assert!(e < 0.02, "{} {p} θo {t}: {approx} vs {exact}", f.name());
            } else {
                assert!(e < 2e-5, "{} {p} θo {t}: {approx} vs {exact}", f.name());
            }
        }
    }
    assert!(worst_ggx > 1e-4, "GGX peak suspiciously exact: {worst_ggx}");
}

#[test]
fn diffuse_constant_preserves_the_diffuse_albedo() {
    // Cook-Torrance: diffuse = kd w(co)/π, whose albedo kd w(co) equals the albedo of the exact
    // coupled diffuse kd w(ci) w(co)/(π S̄) (S̄ rounded up by 6e-8 in COUPLED_DIFFUSE_NORM);
    // the other models: kd/π exactly. (Compared with the diffuse term alone: with F0 = 0 the
    // Cook-Torrance specular lobe keeps Schlick's grazing excess (1 − wo·h)^5.)
    use crate::brdf::models::{COUPLED_DIFFUSE_NORM, coupled_diffuse_weight};
    let kd = Vec3::new(0.2, 0.5, 0.9);
    for t in [0.0f32, 45.0, 75.0, 89.0] {
        let wo = view_dir(t);
        let ct = Brdf::CookTorrance {
            diffuse: kd,
            specular: Vec3::ZERO,
            roughness: 0.3,
            distribution: Distribution::Ggx,
        };
        let exact_ct = |wi: Vec3| {
            kd * coupled_diffuse_weight(wo) * coupled_diffuse_weight(wi)
                / (std::f32::consts::PI * COUPLED_DIFFUSE_NORM)
        };
        let lambert = Brdf::Lambert { diffuse: kd };
        let exact_l = |wi: Vec3| lambert.eval(wo, wi);
        for (brdf, exact) in [
            (ct, &exact_ct as &dyn Fn(Vec3) -> Vec3),
            (lambert, &exact_l as &dyn Fn(Vec3) -> Vec3),
        ] {
            let sg = warped_lobes(&brdf, wo);
            let v = integrate_hemisphere(wo.as_dvec3(), |wi| {
                let f = exact(wi.as_vec3()).as_dvec3() * wi.z;
                let g = sg.diffuse.as_dvec3() * wi.z;
                [f.x, f.y, f.z, g.x, g.y, g.z]
            });
            for c in 0..3 {
                assert!(rel(v[c + 3], v[c]) < 2e-6, "{brdf:?} θo {t}: {v:?}");
            }
            // The factor that restores the exact diffuse has cosine-weighted mean 1.
            let m = integrate_hemisphere(wo.as_dvec3(), |wi| {
                [diffuse_wi_factor(&brdf, wi.as_vec3()) as f64 * wi.z / PI64]
            });
            assert!((m[0] - 1.0).abs() < 2e-6, "{m:?}");
        }
    }
}

#[test]
fn lambert_is_exact_and_wo_below_horizon_is_zero() {
    let b = Brdf::Lambert {
        diffuse: Vec3::splat(0.7),
    };
    for t in THETA_O_DEG {
        assert_eq!(fit_error(&b, view_dir(t)), 0.0);
        assert_eq!(warped_lobes(&b, view_dir(t)).len, 0);
    }
    let g = Family::Ggx.brdf(0.1);
    for wo in [
        Vec3::new(0.6, 0.0, -0.8),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::ZERO,
        Vec3::NAN,
    ] {
        assert_eq!(warped_lobes(&g, wo), BrdfSg::ZERO);
        assert_eq!(fit_error(&g, wo), 0.0);
    }
}

/// (family, θo, parameters, ceiling) for the error ceilings.
type Ceiling = (Family, f32, &'static [f32], f64);

#[test]
fn fit_error_is_below_the_measured_ceilings() {
    // Ceilings = measured maximum (results/brdf-fits.md) + ~10 %, rounded up. Where they come
    // from:
    // - Phong: no warp and no smooth factor; the only error is (x)^n ≈ exp(n (x − 1)) and the
    //   cut at r·wi = 0: 0.55/n relative for large n (measured 0.0061 at n = 100, 0.0663 at
    //   n = 10 for θo = 75°).
    // - Blinn-Phong, Ward, Beckmann, GGX at normal incidence: the warp is exact in shape for
    //   sharp lobes; the error comes from the NDF fit (GGX, K = 3: 1.2 %), the variation of G,
    //   1/cos θi and the warp over the lobe, growing with the lobe width (measured: α = 0.2:
    //   ≤ 7.7 %, α ≤ 0.1: ≤ 2.1 %, n ≥ 100: ≤ 1.9 %).
    // - Oblique views: dominated by the isotropic warp, whose floor for sharp lobes is
    //   sqrt(2 − 4 √r/(r + 1)), r = 1/cos θo (17.25 % at 45°, 61.9 % at 75°; see
    //   `fit_error_reaches_the_closed_form_warp_floor`), plus the wide-lobe effects above.
    let glossy_n: &[f32] = &[100.0, 1000.0, 10000.0];
    let glossy_a: &[f32] = &[0.1, 0.05, 0.02, 0.01];
    let all_a: &[f32] = &ALPHAS;
    let cases: Vec<Ceiling> = vec![
        (Family::Phong, 0.0, &EXPONENTS[1..], 0.06),
        (Family::Phong, 75.0, &EXPONENTS[1..], 0.075),
        (Family::Phong, 75.0, glossy_n, 0.007),
        (Family::BlinnPhong, 0.0, glossy_n, 0.021),
        (Family::BlinnPhong, 45.0, glossy_n, 0.24),
        (Family::BlinnPhong, 75.0, glossy_n, 0.71),
        (Family::Ward, 0.0, glossy_a, 0.014),
        (Family::Ward, 0.0, &[0.2], 0.053),
        (Family::Ward, 45.0, glossy_a, 0.21),
        (Family::Ward, 75.0, glossy_a, 0.70),
        (Family::Beckmann, 0.0, glossy_a, 0.021),
        (Family::Beckmann, 0.0, &[0.2], 0.083),
        (Family::Beckmann, 45.0, glossy_a, 0.22),
        (Family::Beckmann, 75.0, glossy_a, 0.73),
        (Family::Ggx, 0.0, glossy_a, 0.023),
        (Family::Ggx, 0.0, &[0.2], 0.084),
        (Family::Ggx, 45.0, glossy_a, 0.20),
        (Family::Ggx, 75.0, glossy_a, 0.65),
        (Family::Ggx, 0.0, all_a, 0.28),
        (Family::Ggx, 45.0, all_a, 0.27),
        (Family::Ggx, 75.0, all_a, 0.76),
    ];
    let measured: Vec<(usize, f32, f64)> = cases
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, &(f, t, params, _))| {
            params
                .iter()
                .map(move |&p| (i, p, fit_error(&f.brdf(p), view_dir(t))))
        })
        .collect();
    for (i, p, e) in measured {
        let (f, t, _, ceiling) = cases[i];
        assert!(
            e.is_finite() && e <= ceiling,
            "{} {p} θo {t}: error {e:.4} above ceiling {ceiling}",
            f.name()
        );
    }
}

#[test]
fn ggx_error_decreases_with_the_lobe_count() {
    // The NDF fit itself (table columns) improves strictly with K up to α = 0.5 and never gets
    // worse above (there the K = 4 fit keeps one lobe at zero amplitude at some α, and at
    // α = 1 the NDF is constant and one nearly flat lobe is already exact).
    for j in 0..ggx::ALPHA_COUNT {
        let a = table_alpha(j) as f32;
        let e: Vec<f64> = (1..=MAX_LOBES)
            .map(|k| ggx::ggx_normalised(a, k).ndf_error)
            .collect();
        if a <= 0.5 {
            assert!(e.windows(2).all(|w| w[1] < w[0]), "α {a}: {e:?}");
        } else {
            assert!(e.windows(2).all(|w| w[1] <= w[0] + 1e-9), "α {a}: {e:?}");
        }
        assert!(e[3] < 0.004 && e[2] < 0.013 && e[1] < 0.05, "α {a}: {e:?}");
    }
    // The BRDF fit error follows where the NDF fit dominates it, α ≤ 0.05: non-increasing in K
    // at every view angle (within 0.5 % relative) and strictly decreasing, by a factor > 5
    // from K = 1 to 4, at normal incidence (measured 23.0 / 4.3 / 1.07 / 0.47 % at α = 0.05).
    // At α = 0.1..0.2 the variation of G, 1/cos θi and the warp across the lobe dominate
    // (measured K = 2..4: 3.9 / 1.78 / 1.80 % at α = 0.1, 6.9 / 7.7 / 7.7 % at α = 0.2), so
    // only "several lobes beat one lobe" is asserted there.
    let cases: Vec<(f32, f32)> = [0.2f32, 0.1, 0.05, 0.02, 0.01]
        .iter()
        .flat_map(|&a| THETA_O_DEG.iter().map(move |&t| (a, t)))
        .collect();
    let errors: Vec<Vec<f64>> = cases
        .par_iter()
        .map(|&(a, t)| {
            let b = Family::Ggx.brdf(a);
            let wo = view_dir(t);
            (1..=MAX_LOBES)
                .map(|k| fit_error_of(&b, wo, &warped_lobes_k(&b, wo, k)))
                .collect()
        })
        .collect();
    for ((a, t), e) in cases.iter().zip(&errors) {
        assert!(e[1..].iter().all(|&x| x < e[0]), "α {a} θo {t}: {e:?}");
        if *a <= 0.05 {
            assert!(
                e.windows(2).all(|w| w[1] <= w[0] * 1.005),
                "α {a} θo {t}: {e:?}"
            );
            if *t == 0.0 {
                assert!(e.windows(2).all(|w| w[1] < w[0]), "α {a}: {e:?}");
                assert!(e[3] < e[0] / 5.0, "α {a}: {e:?}");
            }
        }
    }
}

#[test]
fn ggx_table_is_reproducible_and_interpolates_well() {
    // The committed table was generated on the grid `fit_table` uses.
    assert_eq!(
        (ggx::ALPHA_MIN, ggx::ALPHA_MAX, ggx::ALPHA_COUNT),
        ggx::GRID
    );
    // Refitting a table column (continuation from the previous column, as `fit_table` does)
    // reproduces its error to 1 %.
    for (j, k) in [(16usize, 2usize), (33, 3)] {
        let prev = ggx::ggx_normalised(table_alpha(j - 1) as f32, k);
        let e = ggx::fit(table_alpha(j), k, Some(&prev));
        let t = ggx::ggx_normalised(table_alpha(j) as f32, k);
        assert!(
            rel(e.ndf_error, t.ndf_error) < 0.01,
            "j {j} K {k}: {e:?} vs {t:?}"
        );
    }
    // Between two columns the interpolated lobes fit the NDF almost as well as the columns for
    // α ≤ 0.35 (measured ≤ 1.1 × + 0.1 %); above, the optimal lobes move quickly with α
    // (lobes collapse towards the flat NDF at α = 1) and the interpolated fit is measured at
    // ≤ 2.9 % (K ≥ 2) and 18.4 % (K = 1) — still far below the other errors of the BRDF fit
    // at such roughness (≥ 20 %, see the report).
    for j in (0..ggx::ALPHA_COUNT - 1).step_by(2) {
        let a = (table_alpha(j) * table_alpha(j + 1)).sqrt();
        let p = Problem::new(a);
        for k in 1..=MAX_LOBES {
            let e = ggx::ggx_normalised(a as f32, k);
            let got = p.error_of(&e.c[..k], &e.m[..k]);
            let ends = ggx::ggx_normalised(table_alpha(j) as f32, k)
                .ndf_error
                .max(ggx::ggx_normalised(table_alpha(j + 1) as f32, k).ndf_error);
            let ok = if a <= 0.35 {
                got <= 1.1 * ends + 1e-3
            } else {
                got < if k == 1 { 0.19 } else { 0.03 }
            };
            assert!(ok, "α {a} K {k}: {got} vs {ends}");
        }
    }
}

#[test]
fn warp_at_normal_incidence_and_rotation_symmetry() {
    // Normal incidence: the reflected axis is n and the sharpness is λ/4.
    for (f, p) in peak_cases() {
        let b = f.brdf(p);
        let sg = warped_lobes(&b, Vec3::Z);
        let (ndf, n) = ndf_lobes(&b, GGX_DEFAULT_LOBES);
        assert_eq!(sg.len, n);
        for (l, d) in sg.lobes().iter().zip(&ndf) {
            assert_eq!(l.axis, Vec3::Z);
            let want = if f == Family::Phong {
                d.sharpness
            } else {
                d.sharpness / 4.0
            };
            assert!(rel(l.sharpness as f64, want as f64) < 1e-6);
        }
    }
    // Rotating wo about the normal rotates the axes and leaves sharpness and amplitude alone.
    let b = Family::GgxF004.brdf(0.2);
    let wo = view_dir(60.0);
    let base = warped_lobes(&b, wo);
    for phi in [0.3f32, 1.7, 3.0, -2.2] {
        let q = glam::Quat::from_rotation_z(phi);
        let sg = warped_lobes(&b, q * wo);
        for (a, l) in base.lobes().iter().zip(sg.lobes()) {
            assert!((q * a.axis - l.axis).length() < 1e-6);
            assert!(rel(l.sharpness as f64, a.sharpness as f64) < 1e-5);
            assert!((l.amplitude - a.amplitude).length() <= 1e-5 * a.amplitude.length());
        }
        assert!(rel(fit_error_of(&b, q * wo, &sg), fit_error_of(&b, wo, &base)) < 1e-4);
    }
}

#[test]
fn extreme_parameters_stay_finite() {
    let one = Vec3::ONE;
    let zero = Vec3::ZERO;
    let mut brdfs = vec![
        Brdf::Phong {
            diffuse: zero,
            specular: one,
            exponent: 1e6,
        },
        Brdf::Phong {
            diffuse: zero,
            specular: one,
            exponent: 0.0,
        },
        Brdf::BlinnPhong {
            diffuse: zero,
            specular: one,
            exponent: 1e6,
        },
        Brdf::BlinnPhong {
            diffuse: Vec3::splat(0.5),
            specular: Vec3::splat(0.5),
            exponent: 0.0,
        },
    ];
    for a in [1e-3f32, 1.0] {
        brdfs.push(Family::Ward.brdf(a));
        brdfs.push(Family::Beckmann.brdf(a));
        brdfs.push(Family::GgxF004.brdf(a));
    }
    let wos: Vec<Vec3> = [0.0f32, 89.0, 89.99]
        .iter()
        .map(|&t| view_dir(t))
        .chain([
            Vec3::new(1.0, 0.0, 1e-7).normalize(),
            Vec3::new(0.3, -0.2, 1e-6),
        ])
        .collect();
    let jobs: Vec<(Brdf, Vec3)> = brdfs
        .iter()
        .flat_map(|b| wos.iter().map(move |&w| (*b, w)))
        .collect();
    jobs.par_iter().for_each(|(b, wo)| {
        for k in 1..=MAX_LOBES {
            let sg = warped_lobes_k(b, *wo, k);
            assert!(sg.diffuse.is_finite());
            for l in sg.lobes() {
                assert!(
                    l.axis.is_finite() && l.sharpness.is_finite() && l.amplitude.is_finite(),
                    "{b:?} {wo:?}: {l:?}"
                );
                assert!(l.sharpness >= 0.0 && l.amplitude.min_element() >= 0.0);
            }
            let r = Vec3::new(-wo.x, -wo.y, wo.z).normalize();
            assert!(sg.eval(r).is_finite() && sg.eval_f64(r.as_dvec3()).is_finite());
        }
        // The full error quadrature only where it is cheap enough (and defined: wo.z ≥ 1e-4).
        if wo.z > 1e-4 {
            let e = fit_error(b, *wo);
            assert!(e.is_finite(), "{b:?} {wo:?}: {e}");
        }
    });
}

#[test]
fn sweep_rows_are_complete() {
    // The report's row set without running the quadrature: counts and lobe numbers.
    let mut rows = 0;
    for f in Family::ALL {
        for &k in f.lobe_counts() {
            for &p in f.parameters() {
                for t in THETA_O_DEG {
                    let sg = warped_lobes_k(&f.brdf(p), view_dir(t), k);
                    let want = match f {
                        Family::Ggx | Family::GgxF004 => k,
                        Family::CookTorranceDiffuse => GGX_DEFAULT_LOBES,
                        _ => 1,
                    };
                    assert_eq!(sg.len, want, "{} {p}", f.name());
                    rows += 1;
                }
            }
        }
    }
    assert_eq!(rows, 3 * (5 + 5 + 7 + 7 + 4 * 7 + 7 + 7 + 1));
}
