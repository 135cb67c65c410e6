//! The receiver side: the one-bounce radiance one reflector triangle sends to a receiver point
//! towards the eye, integrating SG lobes analytically over the triangle's solid angle.

use super::reflector::ReflectedSg;
use crate::brdf::Brdf;
use crate::brdf::sg_fit::warped_lobes;
use crate::math::Frame;
use crate::math::sg::Sg;
use glam::Vec3;

/// How the receiver's cosine max(0, n·ω) enters the lobe integrals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum CosineMode {
    /// A smooth factor evaluated at the product lobe's axis (METHOD §5 as written).
    LobeAxis,
    /// A smooth factor evaluated at the direction of the (clipped) triangle's centroid.
    TriangleCentroid,
    /// Multiplied in as the SG fit 1.17 exp(2.133 (n·ω − 1)) (overshoots; see `math::sg`).
    SgProduct,
}

/// Options of [`one_bounce`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ReceiverOptions {
    pub cosine: CosineMode,
    /// Clip the triangle to the receiver's horizon before integrating.
    pub clip_horizon: bool,
}

impl Default for ReceiverOptions {
    /// The measured best choice (see `results/single-triangle.md`).
    fn default() -> Self {
        ReceiverOptions {
            cosine: CosineMode::LobeAxis,
            clip_horizon: true,
        }
    }
}

/// One-bounce radiance at receiver point `x` (unit normal `n_x`, BRDF `brdf_x`) towards the unit
/// direction `wo`, from the reflector triangle `tri` whose reflected radiance is `refl`
/// (Xu et al. 2014, §5):
///
/// L₁ = ∫_{Ω_T(x)} L_r(−ω) f_x(wo, ω) max(0, n_x·ω) dω,
/// L_r(−ω) = d_r + Σ_k G_k(−ω),  f_x(wo, ω) ≈ d_x + Σ_j H_j(ω),
///
/// expanded into diffuse×diffuse (the exact projected solid angle of the triangle),
/// diffuse×lobe, lobe×diffuse and lobe×lobe terms; every lobe product is one SG (exact), integrated
/// over the spherical triangle with [`Sg::integrate_triangle`], with the cosine handled as
/// `opts.cosine` says. Visibility between x and the triangle is not included (callers multiply
/// by theirs). Zero when x is on the unlit side of the reflector or the receiver faces away.
pub fn one_bounce(
    refl: &ReflectedSg,
    tri: [Vec3; 3],
    x: Vec3,
    n_x: Vec3,
    wo: Vec3,
    brdf_x: &Brdf,
    opts: &ReceiverOptions,
) -> Vec3 {
    let centroid = (tri[0] + tri[1] + tri[2]) / 3.0;
    if !((x - centroid).dot(refl.normal) > 0.0) || !(wo.dot(n_x) > 0.0) {
        return Vec3::ZERO;
    }
    let rel = tri.map(|v| v - x);
    let mut poly = [Vec3::ZERO; 4];
    let count = if opts.clip_horizon {
        clip_to_horizon(&rel, n_x, &mut poly)
    } else {
        poly[..3].copy_from_slice(&rel);
        3
    };
    if count < 3 {
        return Vec3::ZERO;
    }
    let frame = Frame::from_normal(n_x);
    let bx = warped_lobes(brdf_x, frame.to_local(wo));
    let mut h = bx.lobes;
    for l in h.iter_mut().take(bx.len) {
        l.axis = frame.to_world(l.axis);
    }
    let h = &h[..bx.len];
    // Incoming radiance from direction ω is L_r(−ω): the lobes flip.
    let mut g = refl.lobes;
    for l in g.iter_mut().take(refl.len) {
        l.axis = -l.axis;
    }
    let g = &g[..refl.len];
    let mut sum = Vec3::ZERO;
    for k in 1..count - 1 {
        let (a, b, c) = (poly[0], poly[k], poly[k + 1]);
        let cos_centroid = n_x.dot((a + b + c).normalize_or_zero()).max(0.0);
        let with_cos = |s: &Sg| -> Vec3 {
            match opts.cosine {
                CosineMode::LobeAxis => s.integrate_triangle(a, b, c) * n_x.dot(s.axis).max(0.0),
                CosineMode::TriangleCentroid => s.integrate_triangle(a, b, c) * cos_centroid,
                CosineMode::SgProduct => s
                    .product(&Sg::clamped_cosine(n_x))
                    .integrate_triangle(a, b, c),
            }
        };
        sum += refl.diffuse * bx.diffuse * projected_solid_angle(a, b, c, n_x);
        for hj in h {
            sum += refl.diffuse * with_cos(hj);
        }
        for gk in g {
            sum += bx.diffuse * with_cos(gk);
            for hj in h {
                sum += with_cos(&gk.product(hj));
            }
        }
    }
    sum
}

/// ∫ max(0, n·ω) dω over the spherical triangle of directions a, b, c, for a triangle entirely
/// above the horizon: Lambert's formula ½ |Σ_edges θ_e n·(v_i × v_{i+1})/|v_i × v_{i+1}||.
pub fn projected_solid_angle(a: Vec3, b: Vec3, c: Vec3, n: Vec3) -> f32 {
    let v = [a, b, c].map(|p| p.normalize_or_zero());
    let mut s = 0.0f32;
    for i in 0..3 {
        let (p, q) = (v[i], v[(i + 1) % 3]);
        let cr = p.cross(q);
        let len = cr.length();
        if len > 0.0 {
            let theta = len.atan2(p.dot(q));
            s += theta * n.dot(cr / len);
        }
    }
    (0.5 * s).abs()
}

/// Clips the triangle (points relative to the receiver) to the half-space n·p ≥ 0
/// (Sutherland–Hodgman); writes up to 4 vertices and returns their count.
fn clip_to_horizon(tri: &[Vec3; 3], n: Vec3, out: &mut [Vec3; 4]) -> usize {
    let d = tri.map(|p| p.dot(n));
    let mut k = 0;
    for i in 0..3 {
        let j = (i + 1) % 3;
        let (p, q, dp, dq) = (tri[i], tri[j], d[i], d[j]);
        if dp >= 0.0 {
            if k < 4 {
                out[k] = p;
                k += 1;
            }
            if dq < 0.0 && k < 4 {
                out[k] = p + (q - p) * (dp / (dp - dq));
                k += 1;
            }
        } else if dq >= 0.0 && k < 4 {
            out[k] = p + (q - p) * (dp / (dp - dq));
            k += 1;
        }
    }
    k
}
