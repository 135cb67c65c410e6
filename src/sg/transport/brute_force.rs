//! The exact one-bounce integral over one reflector triangle, by adaptive quadrature in f64:
//! the yardstick for the SG transport.
//!
//! L₁(x, o) = ∫_T f_x(o, ω_xy) cos θ_x · f_y(ω_yx, ω_yl) cos θ_l I/|l − y|² · cos θ_y/|x − y|² dA_y
//!
//! with the exact BRDFs, a point light, no occlusion, two-sided reflector (the side facing the
//! light reflects) and receiver facing `wo`.

use crate::brdf::Brdf;
use crate::math::Frame;
use glam::{DVec3, Vec3};

/// Degree-5 seven-point rule on a triangle (Dunavant 1985 / Radon): barycentrics and weights.
const RULE: [([f64; 3], f64); 7] = {
    const A1: f64 = 0.059_715_871_789_769_82;
    const B1: f64 = 0.470_142_064_105_115_1;
    const A2: f64 = 0.797_426_985_353_087_3;
    const B2: f64 = 0.101_286_507_323_456_34;
    const W0: f64 = 0.225;
    const W1: f64 = 0.132_394_152_788_506_2;
    const W2: f64 = 0.125_939_180_544_827_15;
    [
        ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], W0),
        ([A1, B1, B1], W1),
        ([B1, A1, B1], W1),
        ([B1, B1, A1], W1),
        ([A2, B2, B2], W2),
        ([B2, A2, B2], W2),
        ([B2, B2, A2], W2),
    ]
};

/// The configuration of one reflector triangle lighting one receiver point.
#[derive(Clone, Copy, Debug)]
pub struct Config {
    pub tri: [Vec3; 3],
    pub brdf_y: Brdf,
    pub light: Vec3,
    pub intensity: Vec3,
    pub x: Vec3,
    pub n_x: Vec3,
    pub wo: Vec3,
    pub brdf_x: Brdf,
}

/// The integrand at a reflector point y (per unit area): `n_y` is the geometric normal (the
/// projected area), `frame_y` the shading frame (the BRDF and the light's cosine).
fn integrand(c: &Config, n_y: DVec3, frame_y: &Frame, frame_x: &Frame, y: DVec3) -> DVec3 {
    let x = c.x.as_dvec3();
    let to_x = x - y;
    let dx2 = to_x.length_squared();
    let to_l = c.light.as_dvec3() - y;
    let dl2 = to_l.length_squared();
    if !(dx2 > 0.0 && dl2 > 0.0) {
        return DVec3::ZERO;
    }
    let w_yx = to_x / dx2.sqrt();
    let w_yl = to_l / dl2.sqrt();
    let cos_y = n_y.dot(w_yx);
    let cos_l = frame_y.n.as_dvec3().dot(w_yl);
    let w_xy = -w_yx;
    let cos_x = c.n_x.as_dvec3().dot(w_xy);
    if !(cos_y > 0.0 && cos_l > 0.0 && cos_x > 0.0) {
        return DVec3::ZERO;
    }
    let f_y = c
        .brdf_y
        .eval(
            frame_y.to_local(w_yx.as_vec3()),
            frame_y.to_local(w_yl.as_vec3()),
        )
        .as_dvec3();
    let f_x = c
        .brdf_x
        .eval(frame_x.to_local(c.wo), frame_x.to_local(w_xy.as_vec3()))
        .as_dvec3();
    f_x * cos_x * f_y * cos_l * c.intensity.as_dvec3() / dl2 * cos_y / dx2
}

/// The exact integral with relative tolerance `rel_tol` (adaptive 4-way subdivision of the
/// triangle, comparing each triangle's 7-point estimate with its children's, up to `max_depth`
/// levels). Returns zero when the receiver is on the reflector's unlit side.
pub fn one_bounce_exact(c: &Config, rel_tol: f64, max_depth: u32) -> DVec3 {
    one_bounce_exact_shaded(c, None, rel_tol, max_depth)
}

/// [`one_bounce_exact`] for a reflector with vertex (shading) normals: the BRDF and the light's
/// cosine use the normal interpolated at each point, as the reference renderer does; the
/// projected area uses the geometric normal.
pub fn one_bounce_exact_shaded(
    c: &Config,
    normals: Option<[Vec3; 3]>,
    rel_tol: f64,
    max_depth: u32,
) -> DVec3 {
    let [a, b, cc] = c.tri.map(|v| v.as_dvec3());
    let mut n_y = (b - a).cross(cc - a).normalize_or_zero();
    if n_y == DVec3::ZERO {
        return DVec3::ZERO;
    }
    let centroid = (a + b + cc) / 3.0;
    if n_y.dot(c.light.as_dvec3() - centroid) < 0.0 {
        n_y = -n_y;
    }
    let frame_y = Frame::from_normal(n_y.as_vec3());
    let frame_x = Frame::from_normal(c.n_x);
    let area2 = (b - a).cross(cc - a).length_squared();
    let f = |p: DVec3| match normals {
        None => integrand(c, n_y, &frame_y, &frame_x, p),
        Some(ns) => {
            // Barycentric coordinates of p, the interpolated normal on the lit side.
            let (v0, v1, v2) = (b - a, cc - a, p - a);
            let cr = v0.cross(v1);
            let u = v2.cross(v1).dot(cr) / area2;
            let v = v0.cross(v2).dot(cr) / area2;
            let m = ns[0].as_dvec3() * (1.0 - u - v) + ns[1].as_dvec3() * u + ns[2].as_dvec3() * v;
            let m = if m.dot(n_y) < 0.0 { -m } else { m };
            match m.try_normalize() {
                Some(m) => integrand(c, n_y, &Frame::from_normal(m.as_vec3()), &frame_x, p),
                None => DVec3::ZERO,
            }
        }
    };
    let rule = |t: &[DVec3; 3]| -> DVec3 {
        let area = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        RULE.iter().fold(DVec3::ZERO, |s, (bary, w)| {
            s + f(t[0] * bary[0] + t[1] * bary[1] + t[2] * bary[2]) * *w
        }) * area
    };
    // A first estimate on a uniform 4-level subdivision sets the absolute tolerance.
    let root = [a, b, cc];
    let mut coarse = vec![root];
    for _ in 0..4 {
        coarse = coarse.iter().flat_map(split).collect();
    }
    let estimate: f64 = coarse.iter().map(|t| rule(t).max_element()).sum();
    let tol = rel_tol * estimate.max(1e-300);
    let mut total = DVec3::ZERO;
    // Explicit stack: (triangle, its estimate, depth, its share of the tolerance).
    let n0 = coarse.len() as f64;
    let mut stack: Vec<([DVec3; 3], DVec3, u32, f64)> =
        coarse.iter().map(|t| (*t, rule(t), 4, tol / n0)).collect();
    while let Some((t, whole, depth, tol_t)) = stack.pop() {
        let children = split(&t);
        let parts = children.map(|ch| rule(&ch));
        let sum = parts.iter().fold(DVec3::ZERO, |s, p| s + *p);
        if depth >= max_depth || (sum - whole).abs().max_element() <= tol_t {
            total += sum;
        } else {
            for (ch, p) in children.iter().zip(parts) {
                stack.push((*ch, p, depth + 1, tol_t / 4.0));
            }
        }
    }
    total
}

fn split(t: &[DVec3; 3]) -> [[DVec3; 3]; 4] {
    let [a, b, c] = *t;
    let (ab, bc, ca) = ((a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0);
    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
}
