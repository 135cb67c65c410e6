use super::brute_force::{Config, one_bounce_exact};
use super::study;
use crate::brdf::Brdf;
use glam::Vec3;

fn lambert(r: f32) -> Brdf {
    Brdf::Lambert {
        diffuse: Vec3::splat(r),
    }
}

/// The adaptive quadrature against the point approximation on a tiny, distant triangle, where the
/// integrand is constant to first order (relative variation ~ size/distance = 1e-3).
#[test]
fn brute_force_matches_point_approximation_on_a_tiny_triangle() {
    let s = 1e-3f32;
    let tri = [
        Vec3::new(-s, 0.0, -s),
        Vec3::new(s, 0.0, -s),
        Vec3::new(0.0, 0.0, s),
    ];
    let area = 2.0 * s * s;
    let light = Vec3::new(0.0, 1.0, 0.0);
    let x = Vec3::new(0.6, 0.8, 0.0);
    let n_x = -x.normalize();
    let wo = (n_x + Vec3::Y).normalize();
    let c = Config {
        tri,
        brdf_y: lambert(0.5),
        light,
        intensity: Vec3::ONE,
        x,
        n_x,
        wo,
        brdf_x: lambert(0.8),
    };
    let got = one_bounce_exact(&c, 1e-6, 10).x;
    let y = Vec3::new(0.0, 0.0, -s / 3.0);
    let (dl, dx) = ((light - y).length(), (x - y).length());
    let cos_l = (light - y).y / dl;
    let cos_y = (x - y).y / dx;
    let cos_x = n_x.dot((y - x) / dx);
    let expect =
        0.8 / std::f32::consts::PI * cos_x * 0.5 / std::f32::consts::PI * cos_l / (dl * dl) * cos_y
            / (dx * dx)
            * area;
    assert!(
        ((got as f32) / expect - 1.0).abs() < 5e-3,
        "{got} vs {expect}"
    );
}

/// The quadrature converges: tolerances 1e-3 and 1e-5 agree to 1e-3 on a sharp configuration
/// (near-mirror reflector, glossy receiver).
#[test]
fn brute_force_converges_with_its_tolerance() {
    let mats = study::materials();
    let g = study::geometries()[0];
    let c = |tol| {
        one_bounce_exact(
            &Config {
                tri: g.tri,
                brdf_y: mats[4].brdf,
                light: g.light,
                intensity: Vec3::ONE,
                x: g.x,
                n_x: g.n_x,
                wo: g.wo,
                brdf_x: mats[8].brdf,
            },
            tol,
            16,
        )
        .x
    };
    let (a, b) = (c(1e-3), c(1e-5));
    assert!(b > 0.0 && ((a - b) / b).abs() < 1e-3, "{a} vs {b}");
}

/// The paper's claim, measured: over the whole grid (11 × 11 materials from Lambertian to
/// near-mirror, 5 configurations) the default transport's median relative error is below 3 %
/// (measured 1.8 %, `results/single-triangle.md`; the ceiling leaves room for platform
/// differences in libm, not for a regression of the scheme), and the mirror-image aim is at least
/// 5× better than centroid aiming (measured 23.8 % vs 1.8 %).
#[test]
fn single_triangle_median_error_is_below_the_ceiling() {
    let rows = study::run(&study::materials(), &study::geometries());
    let variants = study::variants();
    let default = super::ReceiverOptions::default();
    let v_best = variants
        .iter()
        .position(|(aim, o, _)| *aim == study::Aim::MirrorImage && *o == default)
        .expect("the default is one of the variants");
    let v_centroid = variants
        .iter()
        .position(|(aim, o, _)| *aim == study::Aim::Centroid && *o == default)
        .expect("centroid aim with the default options");
    let med = |v| {
        study::median(
            rows.iter()
                .filter_map(|r| study::rel_error(r, v, 1e-7))
                .collect(),
        )
    };
    let (best, centroid) = (med(v_best), med(v_centroid));
    assert!(
        rows.iter()
            .all(|r| r.sg.iter().all(|v| v.is_finite() && *v >= 0.0))
    );
    assert!(best < 0.03, "median relative error {best}");
    assert!(
        centroid > 5.0 * best,
        "centroid {centroid} vs mirror-image {best}"
    );
}

/// Prints the whole study (run with `--ignored --nocapture`).
#[test]
#[ignore]
fn study_print() {
    let t = std::time::Instant::now();
    let rows = study::run(&study::materials(), &study::geometries());
    println!("{} rows in {:.1} s", rows.len(), t.elapsed().as_secs_f64());
    for (v, (_, _, label)) in study::variants().iter().enumerate() {
        let errs: Vec<f64> = rows
            .iter()
            .filter_map(|r| study::rel_error(r, v, 1e-7))
            .collect();
        let n = errs.len();
        let med = study::median(errs.clone());
        let max = errs.iter().cloned().fold(0.0, f64::max);
        println!("{label}: n {n} median {med:.4} max {max:.3}");
    }
    for r in &rows {
        println!(
            "{:12} {:12} {:16} exact {:.4e} sg {:?}",
            r.reflector,
            r.receiver,
            r.geometry,
            r.exact,
            r.sg.iter()
                .map(|v| format!("{:.3e}", v))
                .collect::<Vec<_>>()
        );
    }
}
