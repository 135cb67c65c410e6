//! The reflector side: radiance reflected by one triangle as SG lobes in the outgoing direction.

use crate::brdf::Brdf;
use crate::brdf::sg_fit::{MAX_LOBES, warped_lobes};
use crate::math::Frame;
use crate::math::sg::Sg;
use glam::Vec3;

/// A flat reflector triangle with its material.
#[derive(Clone, Copy, Debug)]
pub struct Reflector {
    pub vertices: [Vec3; 3],
    pub brdf: Brdf,
}

impl Reflector {
    /// Area-weighted centroid.
    pub fn centroid(&self) -> Vec3 {
        (self.vertices[0] + self.vertices[1] + self.vertices[2]) / 3.0
    }

    /// Unit geometric normal following the winding (zero for a degenerate triangle).
    pub fn normal(&self) -> Vec3 {
        let [a, b, c] = self.vertices;
        (b - a).cross(c - a).normalize_or_zero()
    }
}

/// Radiance leaving a lit reflector: L(r) ≈ `diffuse` + Σ `lobes`(r) for outgoing directions r
/// on the lit side (`normal` · r > 0), in W/(sr·m²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectedSg {
    pub diffuse: Vec3,
    pub lobes: [Sg; MAX_LOBES],
    pub len: usize,
    /// Unit normal of the lit side.
    pub normal: Vec3,
    /// Point the lobes were built at (the centroid).
    pub origin: Vec3,
    /// Light position, kept for the mirror-image refinement.
    pub light: Vec3,
}

impl ReflectedSg {
    /// The lobes in use.
    pub fn lobes(&self) -> &[Sg] {
        &self.lobes[..self.len]
    }

    /// L(r) for a unit outgoing direction (0 on the unlit side).
    pub fn eval(&self, r: Vec3) -> Vec3 {
        if !(r.dot(self.normal) > 0.0) {
            return Vec3::ZERO;
        }
        self.lobes()
            .iter()
            .fold(self.diffuse, |acc, l| acc + l.eval(r))
    }
}

/// The radiance `refl` reflects after being lit by a point light at `light` with RGB intensity
/// `intensity` (W/sr), times the light's `visibility` at the triangle (from a shadow map, or 1),
/// built at the centroid y (Xu et al. 2014, §4):
///
/// L(y, r) = f_y(r, ω_l) cos θ_l I/d² ≈ E cos θ_l [kd-term + Σ_k G(r; mirror(ω_l), λ_k/(4 cos θ_l), μ_k)],
///
/// i.e. the receiver-independent SG fit of the BRDF warped about the light direction (the models
/// are reciprocal, so the lobes over wi for view ω_l are the lobes over r). For a point light the
/// light's own lobe is a delta, so the reflected sharpness is the BRDF lobe's. Two-sided: the
/// side facing the light reflects. `None` when the light is in the triangle's plane or the
/// triangle is degenerate.
pub fn reflected_sg(
    refl: &Reflector,
    light: Vec3,
    intensity: Vec3,
    visibility: f32,
) -> Option<ReflectedSg> {
    let y = refl.centroid();
    let mut n = refl.normal();
    let to_light = light - y;
    let d2 = to_light.length_squared();
    if n == Vec3::ZERO || !(d2 > 0.0) {
        return None;
    }
    let wl = to_light / d2.sqrt();
    if n.dot(wl) < 0.0 {
        n = -n;
    }
    let cos_l = n.dot(wl);
    if !(cos_l > 0.0) {
        return None;
    }
    let e = intensity * (visibility * cos_l / d2);
    let frame = Frame::from_normal(n);
    let b = warped_lobes(&refl.brdf, frame.to_local(wl));
    let mut lobes = b.lobes;
    for l in lobes.iter_mut().take(b.len) {
        l.axis = frame.to_world(l.axis);
        l.amplitude *= e;
    }
    Some(ReflectedSg {
        diffuse: b.diffuse * e,
        lobes,
        len: b.len,
        normal: n,
        origin: y,
        light,
    })
}

/// The mirror-image refinement for a receiver at `x`: the light reflected by a flat triangle
/// reaches x as if it came from the light's mirror image l' across the triangle's plane, so the
/// lobes are re-aimed along l' → x and sharpened by (1 + d_x/d_l)², with d_x and d_l the
/// distances from the specular point (where l'x crosses the plane) to x and to the light: an
/// angular deviation δ at the reflector appears as δ · d_l/(d_l + d_x) seen from x.
/// Returns `s` unchanged when x is not on the lit side.
pub fn aim_at_receiver(s: &ReflectedSg, x: Vec3) -> ReflectedSg {
    let n = s.normal;
    let h_l = (s.light - s.origin).dot(n);
    let h_x = (x - s.origin).dot(n);
    if !(h_l > 0.0 && h_x > 0.0) {
        return *s;
    }
    let image = s.light - 2.0 * h_l * n;
    let Some(axis) = (x - image).try_normalize() else {
        return *s;
    };
    // The segment image → x crosses the plane at the fraction h_l / (h_l + h_x).
    let d = (x - image).length();
    let d_l = d * h_l / (h_l + h_x);
    let d_x = d - d_l;
    let scale = (1.0 + d_x / d_l).powi(2);
    let mut out = *s;
    for l in out.lobes.iter_mut().take(out.len) {
        l.axis = axis;
        l.sharpness *= scale;
    }
    out
}
