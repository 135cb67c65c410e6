//! The reflector side: radiance reflected by one triangle as SG lobes in the outgoing direction.

use crate::brdf::Brdf;
use crate::brdf::sg_fit::{MAX_LOBES, warped_lobes};
use crate::math::Frame;
use crate::math::sg::Sg;
use crate::scene::Light;
use glam::Vec3;

/// Largest anisotropy given to a half-vector lobe (an incidence or view 6° above the
/// surface): beyond it the tangent-plane model of the warped lobe no longer holds.
pub const MAX_STRETCH: f32 = 10.0;

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
    /// Unit normal of the lit side (the mean shading normal on curved meshes).
    pub normal: Vec3,
    /// Unit geometric normal of the lit side: a receiver behind this plane gets no light from
    /// the triangle, whatever its shading normals say (as in the exact integral).
    pub geometric_normal: Vec3,
    /// Point the lobes were built at (the centroid).
    pub origin: Vec3,
    /// Light position, kept for the mirror-image refinement.
    pub light: Vec3,
    /// Whether the lobes are warped half-vector lobes (Blinn-Phong, Ward, Cook-Torrance), whose
    /// true reflected shape is anisotropic; Phong's lobes are isotropic about the mirror
    /// direction.
    pub half_vector: bool,
    /// Anisotropy of the lobes (≥ 1), set by [`aim_at_receiver`]: each lobe's sharpness is
    /// the geometric mean λ of its sharpness λ/k in the plane of incidence and λ·k across it.
    /// 1 is isotropic.
    pub stretch: f32,
}

impl ReflectedSg {
    /// The lobes in use.
    pub fn lobes(&self) -> &[Sg] {
        &self.lobes[..self.len]
    }

    /// cos θ_l at the origin: the light's incidence the lobes were warped for (≤ 0 for a light
    /// on the unlit side).
    pub fn light_cosine(&self) -> f32 {
        (self.light - self.origin)
            .normalize_or_zero()
            .dot(self.normal)
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
    reflected_sg_shaded(refl, None, light, intensity, visibility)
}

/// As [`reflected_sg`], with the triangle's vertex (shading) normals when it has them: the
/// lobes are built about the mean shading normal, and widened by the spread of the mirror
/// directions across the triangle, so that a faceted smooth surface reflects like the smooth
/// surface the reference renders. With vertex normals m + d_i (Σ d_i = 0, R = |m| the length of
/// their mean, mean |d_i|² ≈ 2(1 − R)), the normal interpolated at a uniform point of the
/// triangle deviates by E|Σ b_i d_i|² = (1/12) Σ |d_i|² = (1 − R)/2 (barycentric
/// b uniform: Var b_i = 1/18, Cov = −1/36); mirror directions deviate twice as much, 2(1 − R),
/// which is 2/λ for an SG: the widening adds 1/λ = 1 − R. (The vertices' own spread, 4(1 − R),
/// was used before and lost up to 40 % of glossy-to-glossy light on the bunny:
/// `docs/sg-renderer.md`.)
pub fn reflected_sg_shaded(
    refl: &Reflector,
    normals: Option<[Vec3; 3]>,
    light: Vec3,
    intensity: Vec3,
    visibility: f32,
) -> Option<ReflectedSg> {
    let y = refl.centroid();
    let ng = refl.normal();
    let to_light = light - y;
    let d2 = to_light.length_squared();
    if ng == Vec3::ZERO || !(d2 > 0.0) {
        return None;
    }
    let wl = to_light / d2.sqrt();
    let flip = ng.dot(wl) < 0.0;
    let (mut n, spread) = match normals {
        Some(ns) => {
            let m = (ns[0] + ns[1] + ns[2]) / 3.0;
            match m.try_normalize() {
                Some(u) if u.dot(ng) > 0.0 => (u, 1.0 - m.length().min(1.0)),
                _ => (ng, 0.0),
            }
        }
        None => (ng, 0.0),
    };
    if flip {
        n = -n;
    }
    let cos_l = n.dot(wl);
    if !(cos_l > 0.0) || (if flip { -ng } else { ng }).dot(wl) <= 0.0 {
        return None;
    }
    let e = intensity * (visibility * cos_l / d2);
    let frame = Frame::from_normal(n);
    let b = warped_lobes(&refl.brdf, frame.to_local(wl));
    let mut lobes = b.lobes;
    for l in lobes.iter_mut().take(b.len) {
        l.axis = frame.to_world(l.axis);
        l.amplitude *= e;
        if spread > 0.0 {
            // Convolution with the spread keeps the lobe's energy μ/λ.
            let wide = 1.0 / (1.0 / l.sharpness.max(1e-12) + spread);
            l.amplitude *= wide / l.sharpness.max(1e-12);
            l.sharpness = wide;
        }
    }
    Some(ReflectedSg {
        diffuse: b.diffuse * e,
        lobes,
        len: b.len,
        normal: n,
        geometric_normal: if flip { -ng } else { ng },
        origin: y,
        light,
        half_vector: refl.brdf.has_half_vector_lobe(),
        stretch: 1.0,
    })
}

/// As [`reflected_sg`] for any scene light (point, spot or directional), lit with the incident
/// light at the centroid times `visibility`. A directional light is placed at a far point along
/// its direction (10⁵ × `scale`, `scale` a length of the scene), so that the mirror-image
/// refinement degenerates to the constant mirror direction it should give.
pub fn reflected_sg_light(
    refl: &Reflector,
    light: &Light,
    visibility: f32,
    scale: f32,
) -> Option<ReflectedSg> {
    reflected_sg_light_shaded(refl, None, light, visibility, scale)
}

/// [`reflected_sg_light`] with vertex normals (see [`reflected_sg_shaded`]).
pub fn reflected_sg_light_shaded(
    refl: &Reflector,
    normals: Option<[Vec3; 3]>,
    light: &Light,
    visibility: f32,
    scale: f32,
) -> Option<ReflectedSg> {
    let y = refl.centroid();
    let inc = light.incident(y)?;
    let dist = if inc.dist.is_finite() {
        inc.dist
    } else {
        1e5 * scale.max(1e-3)
    };
    let pos = y + inc.wi * dist;
    // reflected_sg divides the intensity by d²; hand it the irradiance times d².
    reflected_sg_shaded(
        refl,
        normals,
        pos,
        inc.irradiance * (dist * dist),
        visibility,
    )
}

/// The mirror-image refinement for a receiver at `x`: the light reflected by a flat triangle
/// reaches x as if it came from the light's mirror image l' across the triangle's plane, so the
/// lobes are re-aimed along l' → x and sharpened by (1 + d_x/d_l)², with d_x and d_l the
/// distances from the specular point (where l'x crosses the plane) to x and to the light: an
/// angular deviation δ at the reflector appears as δ · d_l/(d_l + d_x) seen from x.
///
/// Half-vector lobes are also given their anisotropy at the specular point: a lobe of
/// sharpness λ_h about the half vector reflects into sharpness λ_h/4 in the plane of incidence
/// and λ_h/(4 cos² θ) across it (θ the incidence angle), where the isotropic warp has the
/// geometric mean λ_h/(4 cos θ) (`results/brdf-fits.md`). The lobes keep the geometric mean,
/// now at the specular point's θ rather than the centroid's, and `stretch` = 1/cos θ
/// (at most [`MAX_STRETCH`]) records the ratio for the receiver's integral.
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
    let mut scale = (1.0 + d_x / d_l).powi(2);
    let mut out = *s;
    if s.half_vector {
        // cos θ at the centroid (what the warp used) and at the specular point.
        let cos_c = s.light_cosine();
        let cos_s = axis.dot(n).max(1.0 / MAX_STRETCH);
        if cos_c > 0.0 {
            scale *= cos_c / cos_s;
        }
        out.stretch = 1.0 / cos_s;
    }
    for l in out.lobes.iter_mut().take(out.len) {
        l.axis = axis;
        l.sharpness *= scale;
    }
    out
}
