//! The receiver side: the one-bounce radiance one reflector triangle sends to a receiver point
//! towards the eye, integrating SG lobes analytically over the triangle's solid angle.

pub use super::reflector::MAX_STRETCH;
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
    /// Integrate half-vector reflector lobes with their anisotropy ([`ReflectedSg::stretch`]):
    /// the directions are mapped by a linear transform that makes the lobe isotropic, so the
    /// spherical-triangle integral still applies. Off: the isotropic lobe of the same energy.
    pub anisotropic: bool,
}

impl Default for ReceiverOptions {
    /// The measured best choice (see `results/single-triangle.md`).
    fn default() -> Self {
        ReceiverOptions {
            cosine: CosineMode::Moment,
            clip_horizon: true,
            anisotropic: true,
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
    /// Unit direction across the plane of incidence (mirror direction × normal).
    across: Vec3,
    /// Anisotropy of half-vector lobes, 1/cos θ_o (at most [`MAX_STRETCH`]); 1 for Phong.
    stretch: f32,
}

impl ReceiverLobes {
    /// The lobes of `brdf` at a point with unit normal `n_x` seen from the unit direction `wo`
    /// (towards the eye). A view below the horizon gives no lobes and no diffuse part.
    pub fn new(brdf: &Brdf, n_x: Vec3, wo: Vec3) -> ReceiverLobes {
        let frame = Frame::from_normal(n_x);
        let wo_l = frame.to_local(wo);
        let mut out = ReceiverLobes {
            normal: n_x,
            diffuse: Vec3::ZERO,
            lobes: [Sg::new(Vec3::Z, 0.0, Vec3::ZERO); MAX_LOBES],
            len: 0,
            across: frame.to_world(Vec3::X),
            stretch: 1.0,
        };
        if !(wo_l.z > 0.0) {
            return out;
        }
        let b = warped_lobes(brdf, wo_l);
        out.lobes = b.lobes;
        for l in out.lobes.iter_mut().take(b.len) {
            l.axis = frame.to_world(l.axis);
        }
        out.diffuse = b.diffuse;
        out.len = b.len;
        if brdf.has_half_vector_lobe() && b.len > 0 {
            // The lobes share the mirror direction r of wo; the plane of incidence holds r and n.
            if let Some(t) = out.lobes[0].axis.cross(n_x).try_normalize() {
                out.across = t;
                out.stretch = 1.0 / wo_l.z.max(1.0 / MAX_STRETCH);
            }
        }
        out
    }

    /// The lobes in use (world-space axes over the incoming direction).
    pub fn lobes(&self) -> &[Sg] {
        &self.lobes[..self.len]
    }

    /// Unit direction across the plane of incidence, which half-vector lobes are narrow across.
    pub fn across(&self) -> Vec3 {
        self.across
    }

    /// The anisotropy of the lobes (≥ 1): their sharpness is as low as 1/stretch of
    /// [`Sg::sharpness`] in the plane of incidence.
    pub fn stretch(&self) -> f32 {
        self.stretch
    }

    /// The lobes with their anisotropy when `anisotropic` (as [`one_bounce_with`] integrates
    /// them), otherwise isotropic.
    pub fn anisotropic_lobes(&self, anisotropic: bool) -> impl Iterator<Item = Anisotropic> + '_ {
        let k = if anisotropic { self.stretch } else { 1.0 };
        self.lobes()
            .iter()
            .map(move |h| Anisotropic::new(h, self.across, k))
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
    // The geometric plane decides, not the shading normal: on a curved mesh a neighbour's
    // interpolated normal can face a receiver that lies behind the neighbour's plane (a firefly:
    // a bunny point lit 500× too brightly by the piece next to it). The margin counts the
    // triangle's size as well as the distance: a receiver point inside the triangle itself, near
    // its centroid, would otherwise pass on rounding alone (a wall point lit by its own piece,
    // found by the GPU twin, which rounded it differently).
    let reach = to_x.length() + (tri[0] - centroid).length();
    if !(to_x.dot(refl.geometric_normal) > 1e-4 * reach) || rx.len == 0 && rx.diffuse == Vec3::ZERO
    {
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
    // The lobes with their anisotropy. Incoming radiance from direction ω is L_r(−ω): the
    // reflector's lobes flip.
    let (g_k, h_k) = if opts.anisotropic {
        (refl.stretch, rx.stretch)
    } else {
        (1.0, 1.0)
    };
    let mut g = [Anisotropic::isotropic(&Sg::new(Vec3::Z, 0.0, Vec3::ZERO)); MAX_LOBES];
    for (out, l) in g.iter_mut().zip(refl.lobes()) {
        let flipped = Sg::new(-l.axis, l.sharpness, l.amplitude);
        *out = match flipped.axis.cross(refl.normal).try_normalize() {
            Some(t) => Anisotropic::new(&flipped, t, g_k),
            None => Anisotropic::isotropic(&flipped),
        };
    }
    let g = &g[..refl.len];
    let mut h = [Anisotropic::isotropic(&Sg::new(Vec3::Z, 0.0, Vec3::ZERO)); MAX_LOBES];
    for (out, l) in h.iter_mut().zip(rx.lobes()) {
        *out = Anisotropic::new(l, rx.across, h_k);
    }
    let h = &h[..rx.len];
    let mut sum = Vec3::ZERO;
    for k in 1..count - 1 {
        let tri = [poly[0], poly[k], poly[k + 1]];
        let integrate = |lobe: &Anisotropic| lobe.integrate(n_x, tri, opts.cosine);
        sum += refl.diffuse * rx.diffuse * projected_solid_angle(tri[0], tri[1], tri[2], n_x);
        for hj in h {
            sum += refl.diffuse * integrate(hj);
        }
        for gk in g {
            sum += rx.diffuse * integrate(gk);
            for hj in h {
                sum += integrate(&gk.product(hj));
            }
        }
    }
    sum
}

/// Below this in-plane sharpness a lobe's anisotropy fades out: it is a property of the
/// tangent plane about a sharp lobe, and wide lobes keep the isotropic warp (measured in
/// `interreflect single-triangle`: 0.5–2 give the same median and 90th percentile, larger
/// values raise both).
pub const ANISOTROPY_FADE: f32 = 1.0;

/// A lobe with its anisotropy, in the tangent-plane model (Xu et al. 2013, anisotropic SGs).
///
/// A half-vector lobe of sharpness λ_h about the half vector, reflected about a direction at
/// angle θ from the normal, has sharpness λ_h/4 in the plane of incidence and λ_h/(4 cos² θ)
/// across it; the isotropic warp (Wang et al. 2009) uses their geometric mean λ_h/(4 cos θ)
/// and is what [`Sg`] lobes carry. Here `iso` holds the axis, the amplitude and that geometric
/// mean s, and the precision is s/k along u = t × axis and s·k along the unit `t`.
#[derive(Clone, Copy, Debug)]
pub struct Anisotropic {
    iso: Sg,
    t: Vec3,
    k: f32,
}

impl Anisotropic {
    /// `lobe` without anisotropy.
    pub fn isotropic(lobe: &Sg) -> Anisotropic {
        let t = Frame::from_normal(lobe.axis).to_world(Vec3::X);
        Anisotropic {
            iso: *lobe,
            t,
            k: 1.0,
        }
    }

    /// `lobe` stretched by `k` across `t` (unit, ⊥ the axis), faded out for wide lobes.
    pub fn new(lobe: &Sg, t: Vec3, k: f32) -> Anisotropic {
        let s = lobe.sharpness.max(0.0);
        let k = k.clamp(1.0, MAX_STRETCH);
        let fade = (s / k / ANISOTROPY_FADE).min(1.0);
        Anisotropic {
            iso: *lobe,
            t,
            k: 1.0 + (k - 1.0) * fade,
        }
    }

    /// The isotropic lobe of the same axis, amplitude and energy (sharpness: the geometric
    /// mean of the two principal ones).
    pub fn lobe(&self) -> &Sg {
        &self.iso
    }

    /// The 2×2 precision [xx, xy, yy] of the lobe in the orthonormal tangent basis (e1, e2)
    /// of another axis: P = (s/k)(I − a aᵀ − t tᵀ) + s k t tᵀ, restricted.
    fn precision_in(&self, e1: Vec3, e2: Vec3) -> [f32; 3] {
        let s = self.iso.sharpness.max(0.0);
        let a = self.iso.axis;
        let (lo, hi) = (s / self.k, s * self.k);
        let q = |x: Vec3, y: Vec3| {
            lo * (x.dot(y) - x.dot(a) * y.dot(a) - x.dot(self.t) * y.dot(self.t))
                + hi * x.dot(self.t) * y.dot(self.t)
        };
        [q(e1, e1), q(e1, e2), q(e2, e2)]
    }

    /// P b in the basis (e1, e2) of the tangent plane at `g` (unit), P this lobe's precision and
    /// b the offset of its axis a from g, b̃ = a − c g with c = a·g: with lo = s/k, hi = s k,
    /// P b̃ = c [lo (c a − g) − (hi − lo) (g·t) t], every term carrying its factor c, where the
    /// matrix product would cancel (for lobes far apart b̃ lies almost along a, which P
    /// nearly annihilates). `iso`: with k = 1.
    fn precision_times_offset(&self, g: Vec3, e1: Vec3, e2: Vec3, iso: bool) -> [f32; 2] {
        let s = self.iso.sharpness.max(0.0);
        let a = self.iso.axis;
        let c = a.dot(g);
        let (lo, hi) = if iso {
            (s, s)
        } else {
            (s / self.k, s * self.k)
        };
        let v = c * (lo * (c * a - g) - (hi - lo) * g.dot(self.t) * self.t);
        [v.dot(e1), v.dot(e2)]
    }

    /// The product with another lobe: the exact product of the isotropic lobes (axis,
    /// amplitude, sharpness), corrected in the tangent plane of this lobe's axis to the product
    /// of the anisotropic ones — precisions add, the centre moves to P⁻¹ P_h b (b the other
    /// axis's offset), the attenuation of a misaligned pair is bᵀ P_g P⁻¹ P_h b instead of
    /// λκ/(λ + κ) |b|², and the anisotropy is that of P = P_g + P_h. Equal to the isotropic
    /// product when both lobes are isotropic.
    pub fn product(&self, other: &Anisotropic) -> Anisotropic {
        let (g, h) = (&self.iso, &other.iso);
        let p0 = g.product(h);
        let (lam, kap) = (g.sharpness.max(0.0), h.sharpness.max(0.0));
        if self.k <= 1.0 && other.k <= 1.0 || !(lam + kap > 0.0) {
            return Anisotropic::isotropic(&p0);
        }
        let e2 = (self.t - self.t.dot(g.axis) * g.axis)
            .try_normalize()
            .unwrap_or_else(|| Frame::from_normal(g.axis).to_world(Vec3::X));
        let e1 = e2.cross(g.axis);
        let b = [h.axis.dot(e1), h.axis.dot(e2)];
        let aniso = TangentProduct::new(
            self.precision_in(e1, e2),
            other.precision_in(e1, e2),
            b,
            other.precision_times_offset(g.axis, e1, e2, false),
        );
        // The same with both lobes isotropic: every correction is a ratio to it, so that the
        // product is exactly the isotropic one when k = 1, at any angle between the lobes.
        let iso = TangentProduct::new(
            Anisotropic::isotropic(g).precision_in(e1, e2),
            Anisotropic::isotropic(h).precision_in(e1, e2),
            b,
            other.precision_times_offset(g.axis, e1, e2, true),
        );
        let (Some(aniso), Some(iso)) = (aniso, iso) else {
            return Anisotropic::isotropic(&p0);
        };
        let mut amplitude = p0.amplitude;
        if iso.attenuation > 1e-12 && h.axis.dot(g.axis) > 0.0 {
            // The isotropic product's exponent rescaled by the ratio of the tangent-plane
            // attenuations, bounded by the stretches (never positive).
            let kk = self.k * other.k;
            let ratio = (aniso.attenuation / iso.attenuation).clamp(1.0 / kk, kk);
            let log_iso =
                -(lam * kap) * (g.axis - h.axis).length_squared() / (p0.sharpness + lam + kap);
            amplitude = g.amplitude * h.amplitude * (log_iso * ratio).min(0.0).exp();
        }
        let axis = (p0.axis
            + (aniso.centre[0] - iso.centre[0]) * e1
            + (aniso.centre[1] - iso.centre[1]) * e2)
            .try_normalize()
            .unwrap_or(p0.axis);
        let t = (aniso.widest_across[0] * e1 + aniso.widest_across[1] * e2)
            .try_normalize()
            .unwrap_or(e2);
        let t = (t - t.dot(axis) * axis).try_normalize().unwrap_or(e2);
        Anisotropic {
            iso: Sg::new(
                axis,
                p0.sharpness * (aniso.det / iso.det).sqrt().sqrt(),
                amplitude,
            ),
            t,
            k: aniso.stretch.min(MAX_STRETCH),
        }
    }

    /// ∫ over the spherical triangle `tri` of the lobe times n·ω. An anisotropic lobe is
    /// integrated in the whitened directions ω' = Mω/|Mω|, M = I + (k − 1) t tᵀ, where it is
    /// isotropic with sharpness s/k: the triangle stays a spherical triangle (M is linear),
    /// dω = dω'/k near the lobe, and the cosine n·ω becomes (M⁻¹n)·ω'.
    fn integrate(&self, n: Vec3, tri: [Vec3; 3], mode: CosineMode) -> Vec3 {
        if !(self.k > 1.0 + 1e-4) {
            return lobe_with_cosine(&self.iso, n, tri, mode);
        }
        let (t, k) = (self.t, self.k);
        let forward = |v: Vec3| v + (k - 1.0) * t.dot(v) * t;
        let n_w = n + (1.0 / k - 1.0) * t.dot(n) * t;
        let n_len = n_w.length();
        let lobe = Sg::new(
            self.iso.axis,
            self.iso.sharpness / k,
            self.iso.amplitude / k,
        );
        lobe_with_cosine(&lobe, n_w / n_len, tri.map(forward), mode) * n_len
    }
}

/// The product of two Gaussians in a tangent plane, with precisions `pa`, `pb` ([xx, xy, yy])
/// and the second centred at `b` (the first at 0).
struct TangentProduct {
    /// det(P) of P = P_a + P_b.
    det: f32,
    /// The product's centre P⁻¹ P_b b.
    centre: [f32; 2],
    /// bᵀ P_a P⁻¹ P_b b (the exponent of a misaligned pair is −½ of it).
    attenuation: f32,
    /// √(largest / smallest eigenvalue of P).
    stretch: f32,
    /// Eigenvector of the largest eigenvalue (the narrowest direction).
    widest_across: [f32; 2],
}

impl TangentProduct {
    /// `pb_b`: P_b b, computed by the caller without cancellation
    /// (`Anisotropic::precision_times_offset`).
    fn new(pa: [f32; 3], pb: [f32; 3], b: [f32; 2], pb_b: [f32; 2]) -> Option<TangentProduct> {
        let p = [pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]];
        let det = p[0] * p[2] - p[1] * p[1];
        if !(det > 0.0) {
            return None;
        }
        let mul = |m: [f32; 3], v: [f32; 2]| [m[0] * v[0] + m[1] * v[1], m[1] * v[0] + m[2] * v[1]];
        let inv = [p[2] / det, -p[1] / det, p[0] / det];
        let centre = mul(inv, pb_b);
        // bᵀ P_a P⁻¹ P_b b = (P_a b)·centre, which does not cancel (the equal form
        // bᵀ P_b b − (P_b b)ᵀ P⁻¹ (P_b b) loses the digits of P_a/P_b when one lobe is much
        // sharper than the other: 1 % of a tail product's value in f32, found by the SIMD twin).
        let pa_b = mul(pa, b);
        let attenuation = (pa_b[0] * centre[0] + pa_b[1] * centre[1]).max(0.0);
        let mean = 0.5 * (p[0] + p[2]);
        let d = (0.25 * (p[0] - p[2]).powi(2) + p[1] * p[1]).sqrt();
        let (hi, lo) = (mean + d, (mean - d).max(1e-20));
        let widest_across = if p[0] >= p[2] {
            [hi - p[2], p[1]]
        } else {
            [p[1], hi - p[0]]
        };
        Some(TangentProduct {
            det,
            centre,
            attenuation,
            stretch: (hi / lo).sqrt(),
            widest_across,
        })
    }
}

/// ∫ over the spherical triangle `tri` of the lobe `s` times the receiver's cosine n·ω (unit
/// n), the cosine handled as `mode` says.
fn lobe_with_cosine(s: &Sg, n: Vec3, [a, b, c]: [Vec3; 3], mode: CosineMode) -> Vec3 {
    match mode {
        CosineMode::LobeAxis => s.integrate_triangle(a, b, c) * n.dot(s.axis).max(0.0),
        CosineMode::Moment => s.amplitude * cosine_weighted(s, n, a, b, c),
        CosineMode::TriangleCentroid => {
            s.integrate_triangle(a, b, c) * n.dot((a + b + c).normalize_or_zero()).max(0.0)
        }
        CosineMode::SgProduct => s
            .product(&Sg::clamped_cosine(n))
            .integrate_triangle(a, b, c),
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::spherical_triangle::quadrature::brute_force_triangle_fn;

    /// With both lobes isotropic the product is exactly the SG product, at any angle.
    #[test]
    fn isotropic_product_is_the_sg_product() {
        let g = Sg::new(Vec3::new(0.3, 0.2, 0.9).normalize(), 40.0, Vec3::splat(2.0));
        let h = Sg::new(
            Vec3::new(-0.5, 0.1, 0.7).normalize(),
            7.0,
            Vec3::new(1.0, 0.5, 0.2),
        );
        let p = Anisotropic::isotropic(&g).product(&Anisotropic::isotropic(&h));
        assert_eq!(p.iso, g.product(&h));
        assert_eq!(p.k, 1.0);
    }

    /// The whitened integral equals the direct integral of the lobe it stands for,
    /// L(ω) = μ G(Mω/|Mω|; p, s/k) / |Mω|³ (peak μ at p, sharpness s/k along u and ≈ s·k
    /// along t), over a triangle that clips the lobe. The cosine is taken at the axis
    /// (`CosineMode::LobeAxis`, n = p: a factor 1) so that only the change of variables is
    /// checked. Tolerance 0.5 %: `integrate_sg`'s own accuracy (≤ 1 % documented, far better
    /// for a triangle holding most of the lobe); the reference quadrature (24² Gauss-Legendre
    /// panels) is exact to far less.
    #[test]
    fn whitened_integral_matches_the_stretched_lobe() {
        let axis = Vec3::Z;
        let t = Vec3::X;
        for (s, k) in [(200.0f32, 3.0f32), (60.0, 1.8), (500.0, 8.0)] {
            let lobe = Anisotropic {
                iso: Sg::new(axis, s, Vec3::ONE),
                t,
                k,
            };
            // A triangle around the axis, 1 unit away, clipping the lobe on one side.
            let tri = [
                Vec3::new(-0.4, -0.3, 1.0),
                Vec3::new(0.05, -0.3, 1.0),
                Vec3::new(-0.1, 0.4, 1.0),
            ];
            let got = lobe.integrate(axis, tri, CosineMode::LobeAxis).x as f64;
            let m = |w: Vec3| w + (k - 1.0) * t.dot(w) * t;
            let [a, b, c] = tri.map(|v| v.as_dvec3());
            let want = brute_force_triangle_fn(
                |w| {
                    let mw = m(w.as_vec3());
                    let len = mw.length();
                    let g = (f64::from(s / k) * (f64::from(mw.dot(axis) / len) - 1.0)).exp();
                    g / f64::from(len).powi(3)
                },
                a,
                b,
                c,
                24,
            );
            let rel = (got - want).abs() / want;
            assert!(
                rel < 0.005,
                "s {s} k {k}: whitened {got} direct {want} ({rel})"
            );
        }
    }
}
