//! Test 5: robustness (no NaN / inf / negative values, no below-horizon samples, pdf > 0 for
//! every sampled direction) over random and degenerate directions and the parameter extremes,
//! and parameter validation. Also the accuracy of the erfc used by the Beckmann Smith term.

use super::{dir, name};
use crate::brdf::microfacet::erfc;
use crate::brdf::models::{eval, pdf, sample};
use crate::brdf::{Brdf, Distribution};
use crate::math::sampling::{Rng, uniform_sphere};
use glam::Vec3;

/// Every model at the corners of its parameter space.
fn extreme_models() -> Vec<Brdf> {
    let colours = [
        (Vec3::ZERO, Vec3::ZERO),
        (Vec3::ONE, Vec3::ZERO),
        (Vec3::ZERO, Vec3::ONE),
        (Vec3::new(0.5, 0.0, 1.0), Vec3::new(0.5, 1.0, 0.0)),
    ];
    let mut v = Vec::new();
    for (kd, ks) in colours {
        v.push(Brdf::Lambert { diffuse: kd });
        for n in [0.0, 1e-3, 1.0, 1e3, 1e6] {
            v.push(Brdf::Phong {
                diffuse: kd,
                specular: ks,
                exponent: n,
            });
            v.push(Brdf::BlinnPhong {
                diffuse: kd,
                specular: ks,
                exponent: n,
            });
        }
        for a in [1e-3, 0.02, 1.0] {
            v.push(Brdf::Ward {
                diffuse: kd,
                specular: ks,
                roughness: a,
            });
            for distribution in [Distribution::Beckmann, Distribution::Ggx] {
                v.push(Brdf::CookTorrance {
                    diffuse: kd,
                    specular: ks,
                    roughness: a,
                    distribution,
                });
            }
        }
    }
    for b in &v {
        b.validate().unwrap();
    }
    v
}

/// Degenerate unit directions: the normal, grazing at several depths (down to z = 1e-30 and
/// exactly 0, ±), below the horizon, and their mirror images.
fn special_directions() -> Vec<Vec3> {
    let mut v = vec![Vec3::Z, -Vec3::Z, Vec3::X, -Vec3::X, Vec3::Y];
    for z in [1e-30f32, 1e-20, 1e-7, 1e-4, 1e-2, 0.0, -0.0, -1e-7, -0.5] {
        for phi in [0.0f32, 1.0, 2.5, std::f32::consts::PI] {
            let s = (1.0 - z * z).max(0.0).sqrt();
            let d = Vec3::new(s * phi.cos(), s * phi.sin(), z);
            v.push(d);
            v.push(Vec3::new(-d.x, -d.y, d.z));
        }
    }
    v.push(dir(0.999_999_9, 0.3));
    v
}

fn value_ok(f: Vec3, p: f32) -> bool {
    f.is_finite() && f.min_element() >= 0.0 && p.is_finite() && p >= 0.0
}

fn check_pair(brdf: &Brdf, wo: Vec3, wi: Vec3) {
    // The raw model functions, not the sanitising public wrappers, so that the wrappers' final
    // is_finite guard cannot hide a bug.
    let (f, p) = (eval(brdf, wo, wi), pdf(brdf, wo, wi));
    let below_is_zero = (wo.z > 0.0 && wi.z > 0.0) || (f == Vec3::ZERO && p == 0.0);
    assert!(
        value_ok(f, p) && below_is_zero,
        "{} wo={wo:?} wi={wi:?}: eval = {f:?}, pdf = {p}",
        name(brdf)
    );
}

fn check_sample(brdf: &Brdf, wo: Vec3, u: [f32; 3]) {
    let Some(wi) = sample(brdf, wo, u) else {
        return;
    };
    let (f, p) = (eval(brdf, wo, wi), pdf(brdf, wo, wi));
    let ok = wo.z > 0.0
        && wi.is_finite()
        && wi.z > 0.0
        && (wi.length() - 1.0).abs() < 1e-4
        && p > 0.0
        && value_ok(f, p);
    assert!(
        ok,
        "{} wo={wo:?} u={u:?}: wi={wi:?} eval={f:?} pdf={p}",
        name(brdf)
    );
}

#[test]
fn eval_pdf_sample_never_nan_or_inf() {
    let one_minus = 1.0 - f32::EPSILON / 2.0; // largest f32 below 1 (what Rng::f32 can return)
    let edge_u = [0.0, 1e-7, 0.5, one_minus];
    let special = special_directions();
    let mut rng = Rng::keyed(0x0B57, 0, 0);
    for brdf in extreme_models() {
        for &wo in &special {
            for &wi in &special {
                check_pair(&brdf, wo, wi);
            }
            for a in edge_u {
                for b in edge_u {
                    for c in edge_u {
                        check_sample(&brdf, wo, [a, b, c]);
                    }
                }
            }
        }
        for k in 0..3000 {
            let wo = uniform_sphere(rng.vec2());
            let wi = uniform_sphere(rng.vec2());
            check_pair(&brdf, wo, wi);
            // The mirror configuration, where glossy lobes peak.
            let up = Vec3::new(wo.x, wo.y, wo.z.abs());
            check_pair(&brdf, up, Vec3::new(-wo.x, -wo.y, wo.z.abs()));
            check_sample(&brdf, up, rng.arr3());
            if k % 10 == 0 {
                for &s in &special {
                    check_pair(&brdf, wo, s);
                    check_pair(&brdf, s, wo);
                }
            }
        }
        // The public API: zero / None below the horizon.
        assert_eq!(brdf.eval(-Vec3::Z, Vec3::Z), Vec3::ZERO);
        assert_eq!(brdf.eval(Vec3::Z, dir(-0.1, 0.0)), Vec3::ZERO);
        assert_eq!(brdf.pdf(dir(-0.1, 0.0), Vec3::Z), 0.0);
        assert_eq!(brdf.sample(dir(-0.1, 0.0), [0.3, 0.3, 0.3]), None);
    }
}

#[test]
fn validate_accepts_the_documented_ranges() {
    let kd = Vec3::new(0.7, 0.3, 0.0);
    let ks = Vec3::new(0.3, 0.7, 1.0); // kd + ks = 1 exactly in decimal, ≥ 1 by an ulp in f32
    let ok = [
        Brdf::Lambert { diffuse: Vec3::ONE },
        Brdf::Lambert {
            diffuse: Vec3::ZERO,
        },
        Brdf::Phong {
            diffuse: kd,
            specular: ks,
            exponent: 0.0,
        },
        Brdf::Phong {
            diffuse: kd,
            specular: ks,
            exponent: 1e6,
        },
        Brdf::BlinnPhong {
            diffuse: kd,
            specular: ks,
            exponent: 37.5,
        },
        Brdf::Ward {
            diffuse: kd,
            specular: ks,
            roughness: 1e-3,
        },
        Brdf::Ward {
            diffuse: kd,
            specular: ks,
            roughness: 1.0,
        },
        Brdf::CookTorrance {
            diffuse: kd,
            specular: ks,
            roughness: 0.3,
            distribution: Distribution::Ggx,
        },
        Brdf::CookTorrance {
            diffuse: Vec3::splat(0.96),
            specular: Vec3::splat(0.04),
            roughness: 1e-3,
            distribution: Distribution::Beckmann,
        },
    ];
    for b in ok {
        assert_eq!(b.validate(), Ok(()), "{b:?}");
    }
}

/// Asserts that `b` is rejected with a message containing every fragment of `needles`.
fn rejects(b: Brdf, needles: &[&str]) {
    let err = b.validate().expect_err(&format!("{b:?} was accepted"));
    for n in needles {
        assert!(
            err.contains(n),
            "message {err:?} for {b:?} does not mention {n:?}"
        );
    }
}

#[test]
fn validate_rejects_bad_parameters_naming_them() {
    let kd = Vec3::splat(0.3);
    let ks = Vec3::splat(0.3);
    let bad_colours = [
        (Vec3::new(f32::NAN, 0.1, 0.1), "r"),
        (Vec3::new(0.1, -0.1, 0.1), "g"),
        (Vec3::new(0.1, 0.1, 1.5), "b"),
        (Vec3::new(f32::INFINITY, 0.1, 0.1), "r"),
        (Vec3::new(0.1, f32::NEG_INFINITY, 0.1), "g"),
    ];
    for (c, ch) in bad_colours {
        rejects(Brdf::Lambert { diffuse: c }, &["diffuse", ch, "[0, 1]"]);
        rejects(
            Brdf::Phong {
                diffuse: c,
                specular: ks,
                exponent: 10.0,
            },
            &["diffuse", ch],
        );
        rejects(
            Brdf::BlinnPhong {
                diffuse: kd,
                specular: c,
                exponent: 10.0,
            },
            &["specular", ch],
        );
        rejects(
            Brdf::Ward {
                diffuse: kd,
                specular: c,
                roughness: 0.1,
            },
            &["specular", ch],
        );
        let ct = Brdf::CookTorrance {
            diffuse: c,
            specular: ks,
            roughness: 0.1,
            distribution: Distribution::Ggx,
        };
        rejects(ct, &["diffuse", ch]);
    }
    let over = (Vec3::new(0.5, 0.6, 0.5), Vec3::new(0.5, 0.5, 0.5));
    let msg = ["diffuse + specular exceeds 1 in channel g"];
    rejects(
        Brdf::Phong {
            diffuse: over.0,
            specular: over.1,
            exponent: 1.0,
        },
        &msg,
    );
    rejects(
        Brdf::BlinnPhong {
            diffuse: over.0,
            specular: over.1,
            exponent: 1.0,
        },
        &msg,
    );
    rejects(
        Brdf::Ward {
            diffuse: over.0,
            specular: over.1,
            roughness: 0.5,
        },
        &msg,
    );
    let ct = Brdf::CookTorrance {
        diffuse: over.0,
        specular: over.1,
        roughness: 0.5,
        distribution: Distribution::Beckmann,
    };
    rejects(ct, &msg);
    for n in [
        f32::NAN,
        -1.0,
        -0.0 - 1e-6,
        1.000_001e6,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ] {
        rejects(
            Brdf::Phong {
                diffuse: kd,
                specular: ks,
                exponent: n,
            },
            &["exponent", "[0, 1e6]"],
        );
        rejects(
            Brdf::BlinnPhong {
                diffuse: kd,
                specular: ks,
                exponent: n,
            },
            &["exponent", "[0, 1e6]"],
        );
    }
    for a in [f32::NAN, 0.0, 9e-4, -0.5, 1.01, f32::INFINITY] {
        rejects(
            Brdf::Ward {
                diffuse: kd,
                specular: ks,
                roughness: a,
            },
            &["roughness", "[0.001, 1]"],
        );
        for distribution in [Distribution::Beckmann, Distribution::Ggx] {
            let ct = Brdf::CookTorrance {
                diffuse: kd,
                specular: ks,
                roughness: a,
                distribution,
            };
            rejects(ct, &["roughness", "[0.001, 1]"]);
        }
    }
}

#[test]
fn erfc_is_accurate() {
    // Reference values of erfc (Abramowitz & Stegun table 7.1 / mpmath, 16 digits).
    let refs = [
        (0.0, 1.0),
        (0.1, 0.887_537_083_981_715),
        (0.5, 0.479_500_122_186_953_5),
        (1.0, 0.157_299_207_050_285_1),
        (2.0, 4.677_734_981_047_266e-3),
        (3.0, 2.209_049_699_858_544e-5),
        (5.0, 1.537_459_794_428_035e-12),
        (-1.0, 1.842_700_792_949_715),
    ];
    for (x, e) in refs {
        // Numerical Recipes quotes a fractional error below 1.2e-7 for erfcc.
        assert!(
            ((erfc(x) - e) / e).abs() < 1.2e-7,
            "erfc({x}) = {} vs {e}",
            erfc(x)
        );
    }
}
