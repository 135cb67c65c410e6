use glam::{DVec3, Vec3};
use proptest::prelude::*;

use super::*;
use crate::math::spherical_triangle::quadrature::{integrate, sphere_integral};

const LAMBDAS: [f32; 9] = [0.0, 1e-4, 0.01, 0.5, 2.133, 10.0, 300.0, 1e4, 1e5];

fn lobe_f64(p: DVec3, l: f64, w: DVec3) -> f64 {
    (l * (w.dot(p) - 1.0)).exp()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn sphere_integral_matches_quadrature() {
    let p = DVec3::new(0.2, -0.3, 0.9).normalize();
    for &l in &LAMBDAS {
        let l64 = f64::from(l);
        let num = sphere_integral(|w| lobe_f64(p, l64, w), p, 1e-10);
        let closed = f64::from(lobe_integral(l));
        assert!(rel(closed, num) <= 1e-6, "λ {l}: {closed} vs {num}");
        let sg = Sg::new(p.as_vec3(), l, Vec3::new(1.0, 2.0, 0.5));
        let v = sg.integral();
        assert!(rel(f64::from(v.y), 2.0 * num) <= 1e-6);
        assert!(v.is_finite());
    }
    assert_eq!(lobe_integral(0.0), 4.0 * std::f32::consts::PI);
    assert_eq!(lobe_integral(f32::NAN), 4.0 * std::f32::consts::PI);
    assert!(lobe_integral(1e-30) > 12.56);
    assert!(lobe_integral(f32::MAX) >= 0.0);
}

/// Pairs of lobes: sharpnesses over 0..1e5 and axes from equal to opposite.
fn pairs() -> Vec<(DVec3, f32, DVec3, f32)> {
    let p1 = DVec3::new(0.3, 0.5, -0.8).normalize();
    let mut out = Vec::new();
    for &l1 in &[0.0f32, 0.01, 1.0, 30.0, 1e3, 1e5] {
        for &l2 in &[0.0f32, 0.5, 7.0, 2e3, 1e5] {
            for ang in [0.0, 1e-3, 0.05, 0.7, 2.0, std::f64::consts::PI] {
                let (t, _) = super::super::spherical_triangle::quadrature::basis(p1);
                let p2 = (p1 * ang.cos() + t * ang.sin())
                    .as_vec3()
                    .as_dvec3()
                    .normalize();
                out.push((p1.as_vec3().as_dvec3().normalize(), l1, p2, l2));
            }
        }
    }
    out
}

#[test]
fn product_and_inner_product_match_quadrature() {
    let mut checked = 0;
    for (p1, l1, p2, l2) in pairs() {
        let g1 = Sg::new(p1.as_vec3(), l1, Vec3::new(1.0, 0.5, 2.0));
        let g2 = Sg::new(p2.as_vec3(), l2, Vec3::new(3.0, 1.0, 0.25));
        let prod = g1.product(&g2);
        assert!(prod.axis.is_finite() && prod.sharpness.is_finite() && prod.amplitude.is_finite());
        assert!(prod.sharpness >= 0.0 && prod.amplitude.min_element() >= 0.0);
        let ip = g1.inner_product(&g2);
        assert!(ip.is_finite() && ip.min_element() >= 0.0);
        let (l1d, l2d) = (f64::from(l1), f64::from(l2));
        // Pointwise: the product lobe equals G1 G2 (relative to the product's peak value).
        let (pp, lp, ls) = product_lobe_f64(p1, l1d, p2, l2d);
        let peak = ls.exp();
        for w in [
            pp,
            p1,
            p2,
            (p1 + pp * 0.1).normalize(),
            (pp + p2 * 0.01).normalize(),
        ] {
            if !w.is_finite() || w.length() < 0.5 {
                continue;
            }
            let direct = lobe_f64(p1, l1d, w) * lobe_f64(p2, l2d, w);
            let via = peak * lobe_f64(pp, lp, w);
            assert!((direct - via).abs() <= 1e-9 * peak.max(1e-300), "pointwise");
        }
        // Integral of the pointwise product, in polar coordinates around the product axis.
        let closed = inner_product_f64(p1, l1d, p2, l2d);
        if closed < 1e-200 {
            // e^{−λ1 λ2 |p1−p2|²/…} underflows: the quadrature has nothing to integrate.
            continue;
        }
        let num = sphere_integral(|w| lobe_f64(p1, l1d, w) * lobe_f64(p2, l2d, w), pp, 1e-9);
        assert!(
            rel(closed, num) <= 1e-6,
            "λ {l1} {l2} {p1} {p2}: {closed} vs {num}"
        );
        checked += 1;
        if closed < 1e-30 {
            continue; // below f32's normal range
        }
        // The f32 API (amplitude 1 · 3 in the red channel) within 1e-4.
        assert!(
            rel(f64::from(ip.x) / 3.0, num) <= 1e-4,
            "f32 inner product {ip} vs {num}"
        );
        assert!(
            rel(f64::from(prod.integral().x) / 3.0, num) <= 1e-4,
            "integral of product {} vs {num}",
            prod.integral()
        );
    }
    assert!(checked > 100, "{checked}");
}

#[test]
fn extreme_sharpness_is_stable() {
    let a = Vec3::new(0.0, 0.6, 0.8);
    for &l in &[
        0.0f32,
        1e-30,
        1e5,
        1e30,
        f32::MAX,
        f32::INFINITY,
        f32::NAN,
        -3.0,
    ] {
        for b in [a, -a, Vec3::X, (a + Vec3::X * 1e-4).normalize()] {
            let g1 = Sg::new(a, l, Vec3::ONE);
            let g2 = Sg::new(b, 1e5, Vec3::ONE);
            let p = g1.product(&g2);
            let ip = g1.inner_product(&g2);
            assert!(
                !p.axis.is_nan() && !p.sharpness.is_nan() && !p.amplitude.is_nan(),
                "{p:?}"
            );
            assert!(!ip.is_nan() && ip.min_element() >= 0.0, "{ip}");
            assert!(!g1.integral().is_nan());
        }
    }
    // Opposite lobes of equal sharpness: the product is the constant e^{−2λ}.
    let p = Sg::new(Vec3::Z, 3.0, Vec3::ONE).product(&Sg::new(-Vec3::Z, 3.0, Vec3::ONE));
    assert_eq!(p.sharpness, 0.0);
    assert!((p.amplitude.x - (-6.0f32).exp()).abs() < 1e-8);
}

#[test]
fn clamped_cosine_fit_errors() {
    let fit = |c: f64| 1.17 * (2.133 * (c - 1.0)).exp();
    let n = 200_001;
    let (mut over, mut under, mut at_under) = (f64::MIN, f64::MAX, 0.0);
    for i in 0..n {
        let c = -1.0 + 2.0 * i as f64 / (n - 1) as f64;
        let d = fit(c) - c.max(0.0);
        if d > over {
            over = d;
        }
        if d < under {
            under = d;
            at_under = c;
        }
    }
    assert!(
        (over - f64::from(CLAMPED_COSINE_MAX_OVERSHOOT)).abs() < 1e-4,
        "{over}"
    );
    assert!(
        (-under - f64::from(CLAMPED_COSINE_MAX_UNDERSHOOT)).abs() < 1e-4,
        "{under}"
    );
    assert!((at_under - 0.571).abs() < 1e-3, "{at_under}");
    assert!((fit(0.0) - f64::from(CLAMPED_COSINE_HORIZON_VALUE)).abs() < 1e-4);
    // Integral: 3.398 against π.
    let sg = Sg::clamped_cosine(Vec3::Y);
    assert!((sg.integral().x - 3.398).abs() < 1e-3, "{}", sg.integral());
    let num = integrate(fit, -1.0, 1.0, 1e-12, 0.0) * std::f64::consts::TAU;
    assert!(rel(f64::from(sg.integral().x), num) < 1e-5);
    let e = sg.eval(Vec3::Y);
    assert!((e.x - 1.17).abs() < 1e-6);
}

#[test]
fn triangle_integral_scales_amplitude() {
    let sg = Sg::new(Vec3::Z, 5.0, Vec3::new(1.0, 2.0, 0.0));
    let (a, b, c) = (
        Vec3::new(0.3, 0.0, 1.0),
        Vec3::new(-0.2, 0.3, 1.0),
        Vec3::new(-0.2, -0.3, 1.0),
    );
    let v = sg.integrate_triangle(a, b, c);
    let s = super::super::spherical_triangle::integrate_sg(Vec3::Z, 5.0, a, b, c);
    assert_eq!(v, Vec3::new(s, 2.0 * s, 0.0));
}

fn unit_vec() -> impl Strategy<Value = Vec3> {
    (-1.0f32..1.0, 0.0f32..std::f32::consts::TAU).prop_map(|(z, phi)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

fn lobe() -> impl Strategy<Value = Sg> {
    (unit_vec(), -3.0f32..5.0, 0.01f32..10.0)
        .prop_map(|(p, ll, m)| Sg::new(p, 10f32.powf(ll), Vec3::new(m, 1.0, 0.5 * m)))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, .. ProptestConfig::default() })]

    #[test]
    fn product_commutes(a in lobe(), b in lobe()) {
        let ab = a.product(&b);
        let ba = b.product(&a);
        prop_assert!((ab.axis - ba.axis).length() <= 1e-5);
        prop_assert!((ab.sharpness - ba.sharpness).abs() <= 1e-5 * ab.sharpness.max(1.0));
        prop_assert!((ab.amplitude - ba.amplitude).abs().max_element() <= 1e-5 * ab.amplitude.max_element().max(1e-30));
    }

    #[test]
    fn inner_product_symmetric_nonnegative(a in lobe(), b in lobe()) {
        let ab = a.inner_product(&b);
        let ba = b.inner_product(&a);
        prop_assert!(ab.min_element() >= 0.0 && ab.is_finite());
        prop_assert!((ab - ba).abs().max_element() <= 1e-5 * ab.max_element().max(1e-30));
        // ⟨G1, G2⟩ = ∫ product.
        let via = a.product(&b).integral();
        prop_assert!((ab - via).abs().max_element() <= 1e-4 * ab.max_element().max(1e-30));
    }
}
