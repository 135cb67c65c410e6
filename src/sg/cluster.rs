//! The approximation of a tree node at a receiver point (`docs/sg-renderer.md`, "Shading a
//! node as one reflector"): the node's lit sums shaded as one reflector, its lobes merged per
//! slot, its solid angle as an SG cap, every product integrated in closed form.

use super::lighting::LitScene;
use super::transport::receiver::{Anisotropic, MAX_STRETCH, ReceiverLobes};
use crate::brdf::sg_fit::MAX_LOBES;
use crate::math::luminance;
use crate::math::sg::{Sg, lobe_integral};
use glam::Vec3;

impl LitScene<'_> {
    /// The node's approximate contribution at `x` (no visibility), clamped to `bound`. A leaf
    /// gives its exact SG transport.
    pub fn approx(&self, node: u32, x: Vec3, rx: &ReceiverLobes, bound: Vec3) -> Vec3 {
        let n = &self.tree.nodes[node as usize];
        if n.is_leaf() {
            return self.tris[n.first as usize].shade(x, rx, &self.receiver);
        }
        self.cluster(node, x, rx).min(bound)
    }

    /// A node shaded as one reflector (before clamping).
    pub fn cluster(&self, node: u32, x: Vec3, rx: &ReceiverLobes) -> Vec3 {
        let lit = &self.nodes[node as usize];
        if !(lit.weight > 0.0 && lit.area > 0.0) {
            return Vec3::ZERO;
        }
        let c = lit.centroid_sum / lit.weight;
        let v = x - c;
        let d2 = v.length_squared();
        if !(d2 > 0.0) {
            return Vec3::ZERO;
        }
        let r = v / d2.sqrt(); // node → x
        let proj = lit.normal_sum.dot(r) / lit.area;
        if !(proj > 0.0) {
            return Vec3::ZERO;
        }
        // The node's solid angle from x, as a unit-height SG cap with the same integral.
        let omega = (lit.area * proj / d2).clamp(1e-12, 2.0 * std::f32::consts::PI);
        let cap_sharp = 2.0 * std::f32::consts::PI / omega;
        let cap = Sg::new(-r, cap_sharp, Vec3::splat(omega / lobe_integral(cap_sharp)));
        let inv_area = 1.0 / lit.area;
        let aniso = self.receiver.anisotropic;
        let cap_a = Anisotropic::isotropic(&cap);
        let mut incoming = [cap_a; MAX_LOBES + 1];
        let mut count = 0;
        if lit.diffuse != Vec3::ZERO {
            let mut d = cap;
            d.amplitude *= lit.diffuse * inv_area;
            incoming[0] = Anisotropic::isotropic(&d);
            count = 1;
        }
        // Mirror-image aiming about the node's mean plane (exact for a flat node).
        let nbar = lit.normal_sum.normalize_or_zero();
        let h_l = (self.light_pos - c).dot(nbar);
        let h_x = v.dot(nbar);
        // As `transport::aim_at_receiver` does for one triangle: half-vector lobes take the
        // incidence angle at the specular point (sharpness × cos θ_c / cos θ_s, stretch
        // 1/cos θ_s across the plane of incidence).
        let aim = if h_l > 0.0 && h_x > 0.0 {
            let image = self.light_pos - 2.0 * h_l * nbar;
            (x - image).try_normalize().map(|axis| {
                let d = (x - image).length();
                let d_l = d * h_l / (h_l + h_x);
                let mut scale = (1.0 + (d - d_l) / d_l).powi(2);
                let mut stretch = 1.0;
                if lit.half_vector && aniso {
                    let cos_c = h_l / (self.light_pos - c).length();
                    let cos_s = axis.dot(nbar).max(1.0 / MAX_STRETCH);
                    scale *= cos_c / cos_s;
                    stretch = 1.0 / cos_s;
                }
                (axis, scale, stretch)
            })
        } else {
            None
        };
        for l in &lit.lobes {
            let weight = luminance(l.energy);
            if !(weight > 0.0) {
                continue;
            }
            let mean_axis = l.axis_sum / weight;
            let rlen = mean_axis.length().min(1.0);
            // Outgoing-direction variance: the lobes' own plus the spread of their axes
            // (vMF: 1 − R ≈ 1/κ for a concentrated distribution).
            let own = l.inv_sharpness_sum / weight;
            let spread = 1.0 - rlen;
            let (axis, scale, stretch) = aim.unwrap_or((mean_axis.normalize_or_zero(), 1.0, 1.0));
            if axis == Vec3::ZERO {
                continue;
            }
            // Peak radiance of the merged lobe: its energy over its width (μ/λ is conserved).
            let var = (own + spread).max(1e-12);
            let lobe = Sg::new(-axis, scale / var, l.energy * (inv_area / var));
            let lobe = match (-axis).cross(nbar).try_normalize() {
                Some(t) if stretch > 1.0 => Anisotropic::new(&lobe, t, stretch),
                _ => Anisotropic::isotropic(&lobe),
            };
            incoming[count] = lobe.product(&cap_a);
            count += 1;
        }
        let n_x = rx.normal;
        let mut sum = Vec3::ZERO;
        for s in &incoming[..count] {
            let s0 = s.lobe();
            sum += rx.diffuse * s0.integral() * clamped_cosine_mean(n_x.dot(s0.axis), s0.sharpness);
            for h in rx.anisotropic_lobes(aniso) {
                let p = *s.product(&h).lobe();
                sum += p.integral() * clamped_cosine_mean(n_x.dot(p.axis), p.sharpness);
            }
        }
        sum
    }
}

/// E[max(0, n·ω)] under a lobe whose axis has n·p = `c` and sharpness λ: n·ω is treated as
/// normal with mean c and variance σ² = (1 − c²)/λ (the lobe's tangential variance 1/λ projected
/// on n), so E = c Φ(c/σ) + σ φ(c/σ). It tends to max(0, c) for sharp lobes and, unlike it, keeps
/// the light of a lobe that straddles the horizon.
pub fn clamped_cosine_mean(c: f32, sharpness: f32) -> f32 {
    let var = (1.0 - c * c).max(0.0) / sharpness.max(1e-6);
    let sigma = var.sqrt().min(1.0);
    if !(sigma > 1e-6) {
        return c.max(0.0);
    }
    let z = c / sigma;
    let pdf = (-0.5 * z * z).exp() * 0.398_942_3;
    let cdf = 0.5 * (1.0 + erf(z * std::f32::consts::FRAC_1_SQRT_2));
    (c * cdf + sigma * pdf).clamp(0.0, 1.0)
}

/// erf (Abramowitz & Stegun 7.1.26, absolute error ≤ 1.5e-7).
pub fn erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let y = 1.0
        - (((((1.061_405_4 * t - 1.453_152_1) * t) + 1.421_413_7) * t - 0.284_496_72) * t
            + 0.254_829_6)
            * t
            * (-x * x).exp();
    y.copysign(x)
}
