//! The receiver side: the one-bounce radiance one reflector triangle sends to a receiver point
//! towards the eye, integrating SG lobes analytically over the triangle's solid angle.

use super::reflector::ReflectedSg;
use crate::brdf::Brdf;
use crate::brdf::sg_fit::{MAX_LOBES, warped_lobes};
use crate::math::Frame;
use crate::math::sg::Sg;
use glam::Vec3;

/// How the receiver's cosine max(0, n·ω) enters the lobe integrals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum CosineMode {
    /// Exact: ∫ G(ω) (n·ω) dω over the clipped triangle from the gradient of the SG integral with
    /// respect to the lobe vector v = λp (∫ G ω = ∇_v I + p I, a central difference along n),
    /// used where the cosine varies across the lobe (lobes near the horizon or wide); elsewhere
    /// the cosine at the lobe axis, which is then accurate.
    Moment,
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
            cosine: CosineMode::Moment,
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
    if !(wo.dot(n_x) > 0.0) {
        return Vec3::ZERO;
    }
    let rx = ReceiverLobes::new(brdf_x, n_x, wo);
    one_bounce_with(refl, tri, x, &rx, opts)
}

/// The receiver's BRDF as SG lobes over the incoming direction, in world space: the SG fit
/// warped about the view direction (`brdf::sg_fit::warped_lobes`). Built once per shading
/// point and shared by every reflector triangle or tree node it integrates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReceiverLobes {
    /// Unit receiver normal (shading normal).
    pub normal: Vec3,
    /// Constant (diffuse) part of the BRDF, 1/sr.
    pub diffuse: Vec3,
    lobes: [Sg; MAX_LOBES],
    len: usize,
}

impl ReceiverLobes {
    /// The lobes of `brdf` at a point with unit normal `n_x` seen from the unit direction `wo`
    /// (towards the eye). A view below the horizon gives no lobes and no diffuse part.
    pub fn new(brdf: &Brdf, n_x: Vec3, wo: Vec3) -> ReceiverLobes {
        let frame = Frame::from_normal(n_x);
        let wo_l = frame.to_local(wo);
        if !(wo_l.z > 0.0) {
            return ReceiverLobes {
                normal: n_x,
                diffuse: Vec3::ZERO,
                lobes: [Sg::new(Vec3::Z, 0.0, Vec3::ZERO); MAX_LOBES],
                len: 0,
            };
        }
        let b = warped_lobes(brdf, wo_l);
        let mut lobes = b.lobes;
        for l in lobes.iter_mut().take(b.len) {
            l.axis = frame.to_world(l.axis);
        }
        ReceiverLobes {
            normal: n_x,
            diffuse: b.diffuse,
            lobes,
            len: b.len,
        }
    }

    /// The lobes in use (world-space axes over the incoming direction).
    pub fn lobes(&self) -> &[Sg] {
        &self.lobes[..self.len]
    }

    /// Whether the receiver reflects nothing towards the view (view below the horizon or a
    /// black BRDF).
    pub fn is_black(&self) -> bool {
        self.diffuse == Vec3::ZERO && self.lobes().iter().all(|l| l.amplitude == Vec3::ZERO)
    }
}

/// [`one_bounce`] with the receiver's lobes prepared by the caller (the shading normal is
/// `rx.normal`).
pub fn one_bounce_with(
    refl: &ReflectedSg,
    tri: [Vec3; 3],
    x: Vec3,
    rx: &ReceiverLobes,
    opts: &ReceiverOptions,
) -> Vec3 {
    let n_x = rx.normal;
    let centroid = (tri[0] + tri[1] + tri[2]) / 3.0;
    // x must be clearly on the lit side: a receiver point in the triangle's own plane (a
    // receiver that is also a reflector, shading a coplanar neighbour or itself) sees the
    // triangle edge-on, but rounding could otherwise let a triangle that surrounds x span a
    // whole hemisphere of directions.
    let to_x = x - centroid;
    if !(to_x.dot(refl.normal) > 1e-4 * to_x.length()) || rx.len == 0 && rx.diffuse == Vec3::ZERO {
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
    let h = rx.lobes();
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
                CosineMode::Moment => s.amplitude * cosine_weighted(s, n_x, a, b, c),
                CosineMode::TriangleCentroid => s.integrate_triangle(a, b, c) * cos_centroid,
                CosineMode::SgProduct => s
                    .product(&Sg::clamped_cosine(n_x))
                    .integrate_triangle(a, b, c),
            }
        };
        sum += refl.diffuse * rx.diffuse * projected_solid_angle(a, b, c, n_x);
        for hj in h {
            sum += refl.diffuse * with_cos(hj);
        }
        for gk in g {
            sum += rx.diffuse * with_cos(gk);
            for hj in h {
                sum += with_cos(&gk.product(hj));
            }
        }
    }
    sum
}

/// ∫_T exp(λ(p·ω − 1)) (n·ω) dω over the spherical triangle T = (a, b, c) (above the horizon of
/// n), for the unit-amplitude lobe of `s`. With J(v) = ∫_T exp(v·ω) dω, ∇J = ∫_T ω exp(v·ω) dω,
/// so at v = λp the wanted integral is e^{−λ} n·∇J(v): a central difference along n of
/// e^{|w| − λ} I(w) for w = v ± h n, where I(w) = ∫_T exp(w·ω − |w|) dω is what `integrate_sg`
/// computes (J is smooth everywhere, unlike I at w = 0). Step h = 0.1 √max(λ, 1): the
/// integrand changes by exp(±h n·ω) and n·ω spans about the lobe's width 1/√λ (or the
/// triangle) around n·p, so the truncation error is about h²/(6λ) ≈ 0.2 % of the result. Where
/// the lobe sits well above the horizon (n·p ≥ 3σ with σ² = (1 − (n·p)²)/λ the variance of n·ω
/// under the lobe) the cosine barely varies across it and the cheaper cosine at the axis is
/// used.
pub fn cosine_weighted(s: &Sg, n: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    use crate::math::spherical_triangle::integrate_sg;
    let lam = s.sharpness.max(0.0);
    let np = n.dot(s.axis);
    let var = (1.0 - np * np).max(0.0) / lam.max(1e-6);
    if np > 0.0 && np * np >= 9.0 * var {
        return integrate_sg(s.axis, lam, a, b, c) * np;
    }
    let v = s.axis * lam;
    let h = 0.1 * lam.max(1.0).sqrt();
    let at = |w: Vec3| -> f64 {
        let len = w.length();
        let i = if len > 0.0 {
            integrate_sg(w / len, len, a, b, c)
        } else {
            integrate_sg(Vec3::Z, 0.0, a, b, c)
        };
        f64::from(i) * (f64::from(len) - f64::from(lam)).exp()
    };
    let d = (at(v + h * n) - at(v - h * n)) / (2.0 * f64::from(h));
    d.max(0.0) as f32
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
