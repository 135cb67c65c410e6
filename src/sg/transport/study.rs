//! The single-triangle accuracy study: SG transport against the exact integral over a grid of
//! reflector and receiver materials (Lambertian to near-mirror) and geometric configurations.
//! Used by the tests (a median-error ceiling) and by `interreflect single-triangle`, which writes
//! `results/single-triangle.md`.

use super::brute_force::{Config, one_bounce_exact};
use super::receiver::{CosineMode, ReceiverOptions, one_bounce};
use super::reflector::{Reflector, aim_at_receiver, reflected_sg};
use crate::brdf::{Brdf, Distribution};
use glam::Vec3;
use rayon::prelude::*;

/// A named material of the study grid.
#[derive(Clone, Copy, Debug)]
pub struct NamedBrdf {
    pub name: &'static str,
    pub brdf: Brdf,
}

/// Lambert, Blinn-Phong exponents 1 … 10⁴ and GGX α 1 … 0.01 (glossy ones without diffuse).
pub fn materials() -> Vec<NamedBrdf> {
    let mut m = vec![NamedBrdf {
        name: "lambert",
        brdf: Brdf::Lambert {
            diffuse: Vec3::splat(0.8),
        },
    }];
    for (name, e) in [
        ("blinn n=1", 1.0),
        ("blinn n=10", 10.0),
        ("blinn n=100", 100.0),
        ("blinn n=1e3", 1e3),
        ("blinn n=1e4", 1e4),
    ] {
        m.push(NamedBrdf {
            name,
            brdf: Brdf::BlinnPhong {
                diffuse: Vec3::ZERO,
                specular: Vec3::splat(0.9),
                exponent: e,
            },
        });
    }
    for (name, a) in [
        ("ggx a=1", 1.0),
        ("ggx a=0.3", 0.3),
        ("ggx a=0.1", 0.1),
        ("ggx a=0.03", 0.03),
        ("ggx a=0.01", 0.01),
    ] {
        m.push(NamedBrdf {
            name,
            brdf: Brdf::CookTorrance {
                diffuse: Vec3::ZERO,
                specular: Vec3::splat(0.9),
                roughness: a,
                distribution: Distribution::Ggx,
            },
        });
    }
    m
}

/// A geometric configuration: reflector triangle, light, receiver point, normal and view.
#[derive(Clone, Copy, Debug)]
pub struct Geometry {
    pub name: &'static str,
    pub tri: [Vec3; 3],
    pub light: Vec3,
    pub x: Vec3,
    pub n_x: Vec3,
    pub wo: Vec3,
}

/// Five configurations. In each the receiver sits on the mirror direction of the light at the
/// triangle's centroid, faces back towards the triangle, and is viewed from the direction that
/// mirrors the light's image into the eye, so glossy-to-glossy transport is at its strongest
/// (the case the method is for): a large triangle close to the receiver (≈ 1.2 rad across), a
/// mid-size one, a small far one, the large one under a grazing light, and the mid-size one
/// viewed 10° away from the double-mirror direction.
pub fn geometries() -> Vec<Geometry> {
    let big = [
        Vec3::new(-0.5, 0.0, -0.4),
        Vec3::new(0.5, 0.0, -0.4),
        Vec3::new(0.0, 0.0, 0.5),
    ];
    let centroid = (big[0] + big[1] + big[2]) / 3.0;
    let scaled = |k: f32| big.map(|v| centroid + (v - centroid) * k);
    let place = |tri: [Vec3; 3], light: Vec3, dist: f32, view_off_deg: f32, name| {
        let image = Vec3::new(light.x, -light.y, light.z);
        let dir = (centroid - image).normalize();
        let x = centroid + dir * dist;
        // The receiver faces the triangle, tilted sideways so it is not a trivial mirror pair.
        let n_x = (-dir + Vec3::new(0.0, 0.0, 0.35)).normalize();
        let to_image = (image - x).normalize();
        let wo = 2.0 * to_image.dot(n_x) * n_x - to_image;
        // Rotating about the normal keeps the elevation and turns the view away.
        let wo = (glam::Quat::from_axis_angle(n_x, view_off_deg.to_radians()) * wo).normalize();
        Geometry {
            name,
            tri,
            light,
            x,
            n_x,
            wo,
        }
    };
    let light = Vec3::new(-1.0, 1.0, -0.1);
    let grazing = Vec3::new(-2.0, 0.55, -0.1);
    vec![
        place(big, light, 0.8, 0.0, "large, near"),
        place(scaled(0.3), light, 1.0, 0.0, "mid-size"),
        place(scaled(0.1), light, 2.0, 0.0, "small, far"),
        place(big, grazing, 0.8, 0.0, "large, grazing light"),
        place(scaled(0.3), light, 1.0, 10.0, "mid-size, view 10° off"),
    ]
}

/// Reflector-lobe aiming.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Aim {
    /// Lobes built at the centroid.
    Centroid,
    /// Lobes re-aimed at the receiver through the light's mirror image.
    MirrorImage,
}

/// SG transport of one configuration.
pub fn sg_value(g: &Geometry, refl: &Brdf, recv: &Brdf, aim: Aim, opts: &ReceiverOptions) -> Vec3 {
    let r = Reflector {
        vertices: g.tri,
        brdf: *refl,
    };
    let Some(s) = reflected_sg(&r, g.light, Vec3::ONE, 1.0) else {
        return Vec3::ZERO;
    };
    let s = match aim {
        Aim::Centroid => s,
        Aim::MirrorImage => aim_at_receiver(&s, g.x),
    };
    one_bounce(&s, g.tri, g.x, g.n_x, g.wo, recv, opts)
}

/// Exact value of one configuration (relative tolerance 1e-4).
pub fn exact_value(g: &Geometry, refl: &Brdf, recv: &Brdf) -> f64 {
    let c = Config {
        tri: g.tri,
        brdf_y: *refl,
        light: g.light,
        intensity: Vec3::ONE,
        x: g.x,
        n_x: g.n_x,
        wo: g.wo,
        brdf_x: *recv,
    };
    let v = one_bounce_exact(&c, 1e-4, 14);
    (v.x + v.y + v.z) / 3.0
}

/// One row of the study.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    pub reflector: &'static str,
    pub receiver: &'static str,
    pub geometry: &'static str,
    pub exact: f64,
    /// SG value per variant, in the order of [`variants`].
    pub sg: Vec<f64>,
}

/// The variants compared: (aim, receiver options, label).
pub fn variants() -> Vec<(Aim, ReceiverOptions, &'static str)> {
    // Centroid-aimed lobes are isotropic (the anisotropy is set by the aim), so `anisotropic`
    // only matters for the mirror-image rows.
    let o = |cosine, anisotropic| ReceiverOptions {
        cosine,
        clip_horizon: true,
        anisotropic,
    };
    vec![
        (
            Aim::Centroid,
            o(CosineMode::TriangleCentroid, true),
            "centroid aim, cos at triangle centroid",
        ),
        (
            Aim::Centroid,
            o(CosineMode::LobeAxis, true),
            "centroid aim, cos at lobe axis",
        ),
        (
            Aim::Centroid,
            o(CosineMode::SgProduct, true),
            "centroid aim, cos as SG",
        ),
        (
            Aim::Centroid,
            o(CosineMode::Moment, true),
            "centroid aim, exact cos (moment)",
        ),
        (
            Aim::MirrorImage,
            o(CosineMode::TriangleCentroid, false),
            "mirror-image aim, cos at triangle centroid",
        ),
        (
            Aim::MirrorImage,
            o(CosineMode::LobeAxis, false),
            "mirror-image aim, cos at lobe axis",
        ),
        (
            Aim::MirrorImage,
            o(CosineMode::Moment, false),
            "mirror-image aim, exact cos (moment)",
        ),
        (
            Aim::MirrorImage,
            ReceiverOptions::default(),
            "mirror-image aim, exact cos, anisotropic warp",
        ),
    ]
}

/// Runs the study over `mats` × `mats` × `geoms` (parallel).
pub fn run(mats: &[NamedBrdf], geoms: &[Geometry]) -> Vec<Row> {
    let vars = variants();
    let mut jobs = Vec::new();
    for a in mats {
        for b in mats {
            for g in geoms {
                jobs.push((*a, *b, *g));
            }
        }
    }
    jobs.par_iter()
        .map(|(a, b, g)| {
            let exact = exact_value(g, &a.brdf, &b.brdf);
            let sg = vars
                .iter()
                .map(|(aim, opts, _)| {
                    let v = sg_value(g, &a.brdf, &b.brdf, *aim, opts);
                    ((v.x + v.y + v.z) / 3.0) as f64
                })
                .collect();
            Row {
                reflector: a.name,
                receiver: b.name,
                geometry: g.name,
                exact,
                sg,
            }
        })
        .collect()
}

/// Relative error of variant `v` in `row`; `None` when the exact value is negligible
/// (below `floor`), where a relative error means nothing.
pub fn rel_error(row: &Row, v: usize, floor: f64) -> Option<f64> {
    (row.exact > floor).then(|| (row.sg[v] - row.exact).abs() / row.exact)
}

/// Median of a list (NaN-free input).
pub fn median(mut xs: Vec<f64>) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    xs.sort_by(|a, b| a.total_cmp(b));
    let n = xs.len();
    if n % 2 == 1 {
        xs[n / 2]
    } else {
        0.5 * (xs[n / 2 - 1] + xs[n / 2])
    }
}
