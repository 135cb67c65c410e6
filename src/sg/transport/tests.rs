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
/// near-mirror, 5 configurations) the default transport's median relative error is below 1.5 %
/// (measured 0.7 %, `results/single-triangle.md`; the ceiling leaves room for platform
/// differences in libm, not for a regression of the scheme), the mirror-image aim is at least
/// 5× better than centroid aiming (measured 23.5 % vs 0.7 %), and the anisotropic lobes beat the
/// isotropic warp in median and 90th percentile (measured 0.7 % vs 1.8 % and 7.2 % vs 12.9 %).
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
    let isotropic = super::ReceiverOptions {
        anisotropic: false,
        ..default
    };
    let v_iso = variants
        .iter()
        .position(|(aim, o, _)| *aim == study::Aim::MirrorImage && *o == isotropic)
        .expect("mirror-image aim with isotropic lobes");
    let errs = |v| -> Vec<f64> {
        rows.iter()
            .filter_map(|r| study::rel_error(r, v, 1e-7))
            .collect()
    };
    let med = |v| study::median(errs(v));
    let p90 = |v| {
        let mut e = errs(v);
        e.sort_by(|a, b| a.total_cmp(b));
        e[e.len() * 9 / 10]
    };
    assert!(med(v_best) < med(v_iso) && p90(v_best) < p90(v_iso));
    let (best, centroid) = (med(v_best), med(v_centroid));
    assert!(
        rows.iter()
            .all(|r| r.sg.iter().all(|v| v.is_finite() && *v >= 0.0))
    );
    assert!(best < 0.015, "median relative error {best}");
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

/// One random configuration of the transport with its exact value and the SG value with the
/// isotropic (index 0) and the anisotropic (index 1) lobes.
struct RandomRow {
    reflector: &'static str,
    receiver: &'static str,
    exact: f64,
    sg: [f64; 2],
    /// Cosine of the view at the receiver.
    cos_o: f32,
}

/// `n` random configurations (fixed seed): a triangle of size 0.05–0.45 in the plane y = 0, a
/// point light above it at distance 1–4 and 3° to 90° elevation, a receiver point above it at
/// distance 0.3–2.3, its normal roughly towards the triangle and a random view on its side;
/// materials cycle through the study grid.
fn random_rows(n: usize, rel_tol: f64) -> Vec<RandomRow> {
    use super::receiver::{ReceiverOptions, one_bounce};
    use super::reflector::{Reflector, aim_at_receiver, reflected_sg};
    use rayon::prelude::*;
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let dir = |z: f32, phi: f32| {
        let s = (1.0 - z * z).max(0.0).sqrt();
        let p = std::f32::consts::TAU * phi;
        Vec3::new(s * p.cos(), z, s * p.sin())
    };
    let mats = study::materials();
    let configs: Vec<(usize, Config)> = (0..n)
        .map(|i| {
            let size = 0.05 + 0.4 * rnd();
            let tri = [
                Vec3::new(-size, 0.0, -size * (0.5 + rnd())),
                Vec3::new(size * (0.5 + rnd()), 0.0, -size * 0.3),
                Vec3::new(size * (rnd() - 0.5), 0.0, size),
            ];
            let light = dir(0.05 + 0.95 * rnd(), rnd()) * (1.0 + 3.0 * rnd());
            let x = dir(0.05 + 0.95 * rnd(), rnd()) * (0.3 + 2.0 * rnd());
            let n_x = (-x.normalize() + 0.9 * dir(2.0 * rnd() - 1.0, rnd())).normalize();
            let w = dir(2.0 * rnd() - 1.0, rnd());
            let wo = if w.dot(n_x) > 0.0 { w } else { -w };
            let c = Config {
                tri,
                brdf_y: mats[i % mats.len()].brdf,
                light,
                intensity: Vec3::ONE,
                x,
                n_x,
                wo,
                brdf_x: mats[(i / mats.len()) % mats.len()].brdf,
            };
            (i, c)
        })
        .collect();
    configs
        .par_iter()
        .filter_map(|(i, c)| {
            let r = Reflector {
                vertices: c.tri,
                brdf: c.brdf_y,
            };
            let s = aim_at_receiver(&reflected_sg(&r, c.light, Vec3::ONE, 1.0)?, c.x);
            let mut sg = [0.0; 2];
            for (k, anisotropic) in [false, true].into_iter().enumerate() {
                let o = ReceiverOptions {
                    anisotropic,
                    ..ReceiverOptions::default()
                };
                let v = one_bounce(&s, c.tri, c.x, c.n_x, c.wo, &c.brdf_x, &o);
                sg[k] = f64::from(v.x + v.y + v.z) / 3.0;
            }
            let e = one_bounce_exact(c, rel_tol, 12);
            Some(RandomRow {
                reflector: mats[i % mats.len()].name,
                receiver: mats[(i / mats.len()) % mats.len()].name,
                exact: (e.x + e.y + e.z) / 3.0,
                sg,
                cos_o: c.wo.dot(c.n_x),
            })
        })
        .collect()
}

/// (mean |SG − exact| / mean exact, 99th percentile of |SG − exact| / (exact + 1 % of the mean
/// exact)) of variant `k`.
fn random_errors(rows: &[RandomRow], k: usize) -> (f64, f64) {
    let mean = rows.iter().map(|r| r.exact).sum::<f64>() / rows.len() as f64;
    let abs = rows.iter().map(|r| (r.sg[k] - r.exact).abs()).sum::<f64>() / rows.len() as f64;
    let mut rel: Vec<f64> = rows
        .iter()
        .map(|r| (r.sg[k] - r.exact).abs() / (r.exact + 0.01 * mean))
        .collect();
    rel.sort_by(|a, b| a.total_cmp(b));
    (abs / mean, rel[rel.len() * 99 / 100])
}

/// The anisotropic lobes (the default) against the isotropic warp on random configurations —
/// grazing lights and views, misaligned lobes, every material pair of the study grid — where
/// the tangent-plane model could break down: the total error must not grow. Measured on these
/// 400 rows: mean |error| / mean value 0.353 (isotropic) → 0.324 (anisotropic). The tail is
/// not asserted, and is worse: the 99th percentile of the relative error goes from 6.5 to 8.1,
/// all of it receivers seen within 10° of grazing with wide lobes, where both variants are off
/// by several times (`docs/sg-renderer.md`).
#[test]
fn anisotropic_lobes_are_not_worse_on_random_configurations() {
    let rows = random_rows(400, 1e-3);
    assert!(rows.len() > 350, "{} rows", rows.len());
    assert!(
        rows.iter()
            .all(|r| r.sg.iter().all(|v| v.is_finite() && *v >= 0.0))
    );
    let (iso, aniso) = (random_errors(&rows, 0), random_errors(&rows, 1));
    assert!(
        aniso.0 <= iso.0,
        "mean error: isotropic {iso:?}, anisotropic {aniso:?}"
    );
}

/// Random configurations: prints the error summary and the worst cases of both variants
/// (run with `--ignored --nocapture`; about 10 minutes on 2 cores).
#[test]
#[ignore]
fn random_probe_print() {
    let rows = random_rows(3000, 1e-4);
    for k in 0..2 {
        println!(
            "variant {k} (0 isotropic, 1 anisotropic): {:?}",
            random_errors(&rows, k)
        );
    }
    let mut rows = rows;
    rows.sort_by(|p, q| {
        (q.sg[1] - q.exact)
            .abs()
            .total_cmp(&(p.sg[1] - p.exact).abs())
    });
    for r in rows.iter().take(12) {
        println!(
            "{:12} {:12} exact {:.3e} isotropic {:.3e} anisotropic {:.3e} cos_o {:.3}",
            r.reflector, r.receiver, r.exact, r.sg[0], r.sg[1], r.cos_o
        );
    }
}

/// A receiver behind a reflector triangle's geometric plane gets nothing from it, even when the
/// triangle's shading normals lean so far that their mean faces the receiver (on a curved mesh,
/// the neighbour of a receiver point; before the check used the geometric plane, such a
/// neighbour lit a bunny point 500× too brightly).
#[test]
fn a_receiver_behind_the_geometric_plane_gets_nothing() {
    use super::receiver::{ReceiverLobes, ReceiverOptions, one_bounce_with};
    use super::reflector::{Reflector, aim_at_receiver, reflected_sg_shaded};
    let brdf = Brdf::Ward {
        diffuse: Vec3::splat(0.05),
        specular: Vec3::splat(0.9),
        roughness: 0.12,
    };
    // A small triangle in the plane y = 0, geometric normal +y; vertex normals tilted 60°
    // towards +x, so their mean leans towards the receiver side x > 0.
    let tri = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.01, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -0.01),
    ];
    let refl = Reflector {
        vertices: tri,
        brdf,
    };
    let tilted = Vec3::new(60f32.to_radians().sin(), 60f32.to_radians().cos(), 0.0);
    let light = Vec3::new(-1.0, 2.0, 0.0);
    let s = reflected_sg_shaded(&refl, Some([tilted; 3]), light, Vec3::splat(10.0), 1.0)
        .expect("lit from above");
    let receiver_brdf = brdf;
    let eye = Vec3::new(0.0, 1.0, 1.0);
    for (x, n_x, behind) in [
        // Just below the plane, beside the triangle, facing up-and-sideways: behind the plane.
        (
            Vec3::new(0.02, -0.002, -0.003),
            Vec3::new(-0.2, 1.0, 0.0).normalize(),
            true,
        ),
        // Above the plane: in front of it, lit.
        (
            Vec3::new(0.03, 0.01, -0.003),
            Vec3::new(-1.0, 0.2, 0.0).normalize(),
            false,
        ),
    ] {
        let rx = ReceiverLobes::new(&receiver_brdf, n_x, (eye - x).normalize());
        let v = one_bounce_with(
            &aim_at_receiver(&s, x),
            tri,
            x,
            &rx,
            &ReceiverOptions::default(),
        );
        assert!(
            s.normal.dot(x - refl.centroid()) > 0.0 || !behind,
            "the shading normal faces x"
        );
        if behind {
            assert_eq!(v, Vec3::ZERO, "behind the plane at {x}");
        } else {
            assert!(v.max_element() > 0.0, "in front of the plane at {x}: {v}");
        }
    }
}
