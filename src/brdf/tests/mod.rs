//! Tests of the BRDF models: sampler χ² goodness of fit, pdf normalisation, sampler/pdf
//! consistency, white furnace and reciprocity, robustness and validation.
//!
//! Shared here: deterministic quadrature on the sphere (f64 accumulation), the χ² machinery and
//! the parameter sweeps.

mod chi2;
mod energy;
mod pdf;
mod premises;
mod robust;

use super::{Brdf, Distribution};
use crate::math::frame::Frame;
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// Gauss–Legendre nodes and weights on [−1, 1]: the same rule the SG-fit quadrature uses.
pub(super) use crate::brdf::sg_fit::quadrature::gauss_legendre;

/// Composite Gauss–Legendre rule on [a, b]: `panels` panels of `order` points.
pub(super) fn composite_gl(a: f64, b: f64, panels: usize, order: usize) -> Vec<(f64, f64)> {
    let gl = gauss_legendre(order);
    let h = (b - a) / panels as f64;
    let mut out = Vec::with_capacity(panels * order);
    for p in 0..panels {
        let lo = a + p as f64 * h;
        for &(x, w) in &gl {
            out.push((lo + 0.5 * h * (x + 1.0), 0.5 * h * w));
        }
    }
    out
}

/// Resolution of [`integrate_upper`]: GL panels (4 points each) per θh segment and in φh.
#[derive(Clone, Copy, Debug)]
pub(super) struct Quad {
    pub theta_panels: usize,
    pub phi_panels: usize,
}

/// Default quadrature; `FINE` doubles it, and the difference between the two is the quadrature
/// error estimate quoted in the tolerances.
pub(super) const QUAD: Quad = Quad {
    theta_panels: 48,
    phi_panels: 24,
};
pub(super) const FINE: Quad = Quad {
    theta_panels: 96,
    phi_panels: 48,
};

/// ∫₀^θ2 ring(θ) dθ for a ring integral that is smooth on [0, θ1] (whole rings) and has
/// square-root ends on [θ1, θ2] (rings clipped by the horizon). [0, θ1] uses θ = θ1 t³, which
/// clusters nodes at the pole (the lobe axis) so lobes of width 1e-3 rad are resolved;
/// [θ1, θm] and [θm, θ2] use quadratic warps towards θ1 and θ2, which turn the square-root ends
/// into smooth ones.
fn integrate_rings(th1: f64, th2: f64, q: Quad, mut ring: impl FnMut(f64) -> DVec3) -> DVec3 {
    let thm = 0.5 * (th1 + th2);
    let mut total = DVec3::ZERO;
    for (t, w) in composite_gl(0.0, 1.0, q.theta_panels, 4) {
        if th1 > 0.0 {
            total += ring(th1 * t * t * t) * (w * 3.0 * th1 * t * t);
        }
        if th2 > th1 {
            total += ring(th1 + (thm - th1) * t * t) * (w * 2.0 * (thm - th1) * t);
            let u = 1.0 - t;
            total += ring(th2 - (th2 - thm) * u * u) * (w * 2.0 * (th2 - thm) * u);
        }
    }
    total
}

/// Half-width of the arc of φ where A + B cos(φ − φ0) > 0: π (whole ring), 0 (empty) or
/// acos(−A/B).
fn arc_half_width(a: f64, b: f64) -> f64 {
    if b <= 1e-300 {
        return if a > 0.0 { PI } else { 0.0 };
    }
    let k = -a / b;
    if k <= -1.0 {
        PI
    } else if k >= 1.0 {
        0.0
    } else {
        k.acos()
    }
}

/// ∫ g(wi) dωi over the upper hemisphere (wi.z > 0), computed in the half-vector domain:
/// wi = 2 (wo·h) h − wo, dωi = 4 (wo·h) dωh (Walter et al. 2007). Used for the
/// microfacet models: their lobes are isotropic bumps around h = n there (as narrow as
/// α = 1e-3), whereas in wi-space a lobe near grazing is compressed sideways by cos θo.
///
/// Rings of constant θh are clipped exactly to the arc where wi is above the horizon,
/// 2 (wo·h) cos θh > cos θo, i.e. where
/// cos θo (2 cos²θh − 1)/(2 cos θh) + sin θh sin θo cos(φh − φo) is positive, so the integrand
/// may jump at the horizon. Rings with θh ≤ (π/2 − θo)/2 are whole, rings
/// with θh ≥ (π/2 + θo)/2 empty.
pub(super) fn integrate_upper_h(wo: Vec3, q: Quad, mut g: impl FnMut(Vec3) -> DVec3) -> DVec3 {
    let o = wo.as_dvec3().normalize();
    let so = (o.x * o.x + o.y * o.y).sqrt();
    let co = o.z;
    let phio = o.y.atan2(o.x);
    let theta_o = so.atan2(co);
    let phi_rule = composite_gl(-1.0, 1.0, q.phi_panels, 4);
    let ring = |theta: f64| -> DVec3 {
        let (sh, ch) = theta.sin_cos();
        let half = arc_half_width(co * (2.0 * ch * ch - 1.0) / (2.0 * ch), sh * so);
        if half == 0.0 {
            return DVec3::ZERO;
        }
        let mut s = DVec3::ZERO;
        for &(x, w) in &phi_rule {
            let phi = phio + half * x;
            let h = DVec3::new(sh * phi.cos(), sh * phi.sin(), ch);
            let oh = o.dot(h);
            let wi = (2.0 * oh * h - o).normalize().as_vec3();
            if wi.z > 0.0 && oh > 0.0 {
                s += g(wi) * (w * half * 4.0 * oh);
            }
        }
        s * sh
    };
    integrate_rings(
        0.5 * (PI / 2.0 - theta_o),
        0.5 * (PI / 2.0 + theta_o),
        q,
        ring,
    )
}

/// ∫ g(wi) dωi over the upper hemisphere in spherical coordinates (θ', φ') about the unit
/// `axis`. Used for the Phong lobe, which is isotropic about the mirror direction. Rings are
/// clipped exactly to their above-horizon arc cos θ' a_z + sin θ' b cos(φ' − φ0) > 0; with β the
/// angle of `axis` from the normal, rings with θ' ≤ π/2 − β are whole and rings with
/// θ' ≥ π/2 + β empty.
pub(super) fn integrate_upper_about(
    axis: Vec3,
    q: Quad,
    mut g: impl FnMut(Vec3) -> DVec3,
) -> DVec3 {
    let frame = Frame::from_normal(axis.normalize());
    let (t, b, a) = (frame.t.as_dvec3(), frame.b.as_dvec3(), frame.n.as_dvec3());
    let beta = a.z.clamp(-1.0, 1.0).acos();
    let phi0 = b.z.atan2(t.z);
    let b0 = (t.z * t.z + b.z * b.z).sqrt();
    let phi_rule = composite_gl(-1.0, 1.0, q.phi_panels, 4);
    let ring = |theta: f64| -> DVec3 {
        let (st, ct) = theta.sin_cos();
        let half = arc_half_width(ct * a.z, st * b0);
        if half == 0.0 {
            return DVec3::ZERO;
        }
        let mut s = DVec3::ZERO;
        for &(x, w) in &phi_rule {
            let phi = phi0 + half * x;
            let (sp, cp) = phi.sin_cos();
            let d = (t * (st * cp) + b * (st * sp) + a * ct)
                .normalize()
                .as_vec3();
            if d.z > 0.0 {
                s += g(d) * (w * half);
            }
        }
        s * st
    };
    integrate_rings(
        (PI / 2.0 - beta).max(0.0),
        (PI / 2.0 + beta).min(PI),
        q,
        ring,
    )
}

/// ∫ g(wi) dωi over the upper hemisphere with the parameterisation suited to `brdf`'s lobe:
/// about the mirror direction for Phong, in the half-vector domain otherwise.
pub(super) fn integrate_upper(
    brdf: &Brdf,
    wo: Vec3,
    q: Quad,
    g: impl FnMut(Vec3) -> DVec3,
) -> DVec3 {
    match brdf {
        Brdf::Phong { .. } => integrate_upper_about(Vec3::new(-wo.x, -wo.y, wo.z), q, g),
        _ => integrate_upper_h(wo, q, g),
    }
}

/// Unit direction with polar angle acos(`cos_theta`) and azimuth `phi`.
pub(super) fn dir(cos_theta: f32, phi: f32) -> Vec3 {
    let s = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), cos_theta)
}

/// ∫ pdf(wo, wi) dωi over the upper hemisphere.
pub(super) fn pdf_integral(brdf: &Brdf, wo: Vec3, q: Quad) -> f64 {
    integrate_upper(brdf, wo, q, |wi| {
        DVec3::splat(super::models::pdf(brdf, wo, wi) as f64)
    })
    .x
}

/// Directional albedo ∫ f(wo, wi) cos θi dωi per channel, by [`integrate_upper`].
pub(super) fn albedo(brdf: &Brdf, wo: Vec3, q: Quad) -> DVec3 {
    integrate_upper(brdf, wo, q, |wi| {
        (super::models::eval(brdf, wo, wi) * wi.z).as_dvec3()
    })
}

/// Name of a model for messages.
pub(super) fn name(b: &Brdf) -> String {
    match *b {
        Brdf::Lambert { .. } => "Lambert".into(),
        Brdf::Phong { exponent, .. } => format!("Phong n={exponent}"),
        Brdf::BlinnPhong { exponent, .. } => format!("BlinnPhong n={exponent}"),
        Brdf::Ward { roughness, .. } => format!("Ward a={roughness}"),
        Brdf::CookTorrance {
            roughness,
            distribution,
            ..
        } => {
            format!("CT-{distribution:?} a={roughness}")
        }
    }
}

/// The sampling-test sweep: every model, from near-diffuse to very glossy (exponents 1, 20,
/// 1000; roughness 1, 0.3, 0.05), mixed with a diffuse lobe so both lobes and the mixture
/// weights are exercised.
pub(super) fn sampling_configs() -> Vec<Brdf> {
    let kd = Vec3::new(0.2, 0.25, 0.3);
    let ks = Vec3::new(0.7, 0.65, 0.6);
    let mut v = vec![Brdf::Lambert {
        diffuse: Vec3::new(0.8, 0.5, 0.2),
    }];
    for n in [1.0, 20.0, 1000.0] {
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
    for a in [1.0, 0.3, 0.05] {
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
    v
}

/// Outgoing directions of the sampling tests: normal, 30°, 65° and near-grazing 86°
/// (cos θo ≈ 0.07), at an azimuth that is not aligned with the histogram grid.
pub(super) fn sampling_wos() -> Vec<Vec3> {
    [0.0f32, 30.0, 65.0, 86.0]
        .iter()
        .map(|d| dir(d.to_radians().cos(), 0.7))
        .collect()
}
