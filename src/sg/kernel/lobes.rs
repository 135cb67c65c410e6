//! Spherical Gaussians on SIMD lanes: the lane-wise twins of `math::sg::Sg` (product, sphere
//! integral) and of `sg::transport::receiver::Anisotropic` (the tangent-plane anisotropic lobe
//! and its product), and of `sg::cluster::clamped_cosine_mean`. Each function follows its
//! scalar twin's formulas step by step, in f32; the tests compare them on random lobes.

use super::simd::Vf;
use super::v3::V3;
use super::vmath::{exp, expm1};
use crate::sg::transport::receiver::{ANISOTROPY_FADE, MAX_STRETCH};

/// A spherical Gaussian per lane: unit `axis`, sharpness ≥ 0, RGB amplitude.
#[derive(Clone, Copy, Debug)]
pub struct SgV<V: Vf> {
    pub axis: V3<V>,
    pub sharp: V,
    pub amp: V3<V>,
}

/// An anisotropic lobe per lane (`Anisotropic`): the isotropic lobe `sg` (whose sharpness is
/// the geometric mean s of the principal ones), stretched by `k` ≥ 1 across the unit tangent
/// `t`: precision s/k along t × axis and s·k along t.
#[derive(Clone, Copy, Debug)]
pub struct AnisoV<V: Vf> {
    pub sg: SgV<V>,
    pub t: V3<V>,
    pub k: V,
}

/// The first tangent of `Frame::from_normal(n)` (Duff et al. 2017), lane-wise.
#[inline(always)]
pub fn tangent_of<V: Vf>(n: V3<V>) -> V3<V> {
    let one = V::splat(1.0);
    let sign = one.copysign(n.z);
    let a = -(sign + n.z).recip();
    let b = n.x * n.y * a;
    V3::new((sign * n.x * n.x).mul_add(a, one), sign * b, -(sign * n.x))
}

/// ∫_{S²} exp(λ (ω·p − 1)) dω = 2π (1 − e^{−2λ}) / λ, → 4π at λ → 0 (`math::sg::lobe_integral`).
#[inline(always)]
pub fn lobe_integral<V: Vf>(lam: V) -> V {
    let tau = V::splat(2.0 * std::f32::consts::PI);
    let small = lam.le(V::splat(1e-6));
    let safe = V::select(small, V::splat(1.0), lam);
    V::select(
        small,
        V::splat(4.0 * std::f32::consts::PI),
        tau * -expm1(V::splat(-2.0) * safe) * safe.recip(),
    )
}

/// The product of two lobes as one SG (`Sg::product`): v = λ1 p1 + λ2 p2, λ = |v|, p = v/λ,
/// μ = μ1 μ2 exp(−λ1 λ2 |p1 − p2|² / (λ + λ1 + λ2)); p = p1 when λ = 0.
#[inline(always)]
pub fn sg_product<V: Vf>(a: &SgV<V>, b: &SgV<V>) -> SgV<V> {
    let (l1, l2) = (a.sharp.max(V::splat(0.0)), b.sharp.max(V::splat(0.0)));
    let v = a.axis.scale(l1) + b.axis.scale(l2);
    let l2v = v.length_squared();
    let pos = l2v.gt(V::splat(0.0));
    let inv = V::select(pos, l2v.max(V::splat(1e-30)).rsqrt(), V::splat(0.0));
    let lam = l2v * inv;
    let denom = lam + l1 + l2;
    let d = (a.axis - b.axis).length_squared();
    let log_s = V::select(
        denom.gt(V::splat(0.0)),
        -(l1 * l2) * d * denom.max(V::splat(1e-30)).recip(),
        V::splat(0.0),
    );
    let s = exp(log_s);
    SgV {
        axis: V3::select(pos, v.scale(inv), a.axis),
        sharp: lam,
        amp: V3::new(
            a.amp.x * b.amp.x * s,
            a.amp.y * b.amp.y * s,
            a.amp.z * b.amp.z * s,
        ),
    }
}

impl<V: Vf> SgV<V> {
    /// ∫_{S²} G dω, RGB.
    #[inline(always)]
    pub fn integral(&self) -> V3<V> {
        self.amp.scale(lobe_integral(self.sharp))
    }
}

impl<V: Vf> AnisoV<V> {
    /// The lobe without anisotropy (`Anisotropic::isotropic`).
    #[inline(always)]
    pub fn isotropic(sg: SgV<V>) -> Self {
        AnisoV {
            sg,
            t: tangent_of(sg.axis),
            k: V::splat(1.0),
        }
    }

    /// `sg` stretched by `k` across `t`, faded out for wide lobes (`Anisotropic::new`):
    /// k ← 1 + (k − 1) min(1, s / k / ANISOTROPY_FADE) with k clamped to [1, MAX_STRETCH].
    #[inline(always)]
    pub fn new(sg: SgV<V>, t: V3<V>, k: V) -> Self {
        let one = V::splat(1.0);
        let s = sg.sharp.max(V::splat(0.0));
        let k = k.max(one).min(V::splat(MAX_STRETCH));
        let fade = (s * k.recip() * V::splat(1.0 / ANISOTROPY_FADE)).min(one);
        AnisoV {
            sg,
            t,
            k: (k - one).mul_add(fade, one),
        }
    }

    /// The 2×2 precision [xx, xy, yy] in the tangent basis (e1, e2): P = (s/k)(I − a aᵀ − t tᵀ)
    /// + s k t tᵀ, restricted. `iso` ignores the stretch (k = 1: s (I − a aᵀ)).
    #[inline(always)]
    fn precision_in(&self, e1: V3<V>, e2: V3<V>, iso: bool) -> [V; 3] {
        let s = self.sg.sharp.max(V::splat(0.0));
        let a = self.sg.axis;
        let (x1, x2) = (e1.dot(a), e2.dot(a));
        if iso {
            return [
                s * (V::splat(1.0) - x1 * x1),
                s * -(x1 * x2),
                s * (V::splat(1.0) - x2 * x2),
            ];
        }
        let (lo, hi) = (s * self.k.recip(), s * self.k);
        let (t1, t2) = (e1.dot(self.t), e2.dot(self.t));
        let e12 = e1.dot(e2);
        let one = V::splat(1.0);
        [
            quad_form(lo, hi, one, x1, x1, t1, t1),
            quad_form(lo, hi, e12, x1, x2, t1, t2),
            quad_form(lo, hi, one, x2, x2, t2, t2),
        ]
    }

    /// P b̃ in the basis (e1, e2), without cancellation (`Anisotropic::precision_times_offset`).
    #[inline(always)]
    fn precision_times_offset(&self, g: V3<V>, e1: V3<V>, e2: V3<V>, iso: bool) -> [V; 2] {
        let s = self.sg.sharp.max(V::splat(0.0));
        let a = self.sg.axis;
        let c = a.dot(g);
        let (lo, hi) = if iso {
            (s, s)
        } else {
            (s * self.k.recip(), s * self.k)
        };
        let v = ((a.scale(c) - g).scale(lo) - self.t.scale((hi - lo) * g.dot(self.t))).scale(c);
        [v.dot(e1), v.dot(e2)]
    }

    /// The product with another lobe (`Anisotropic::product`): the isotropic product corrected in
    /// the tangent plane of this lobe's axis to the product of the anisotropic ones.
    #[inline(always)]
    pub fn product(&self, other: &AnisoV<V>) -> AnisoV<V> {
        let zero = V::splat(0.0);
        let one = V::splat(1.0);
        let (g, h) = (&self.sg, &other.sg);
        let p0 = sg_product(g, h);
        let (lam, kap) = (g.sharp.max(zero), h.sharp.max(zero));
        let both_iso = self.k.le(one) & other.k.le(one);
        let iso_result = AnisoV::isotropic(p0);
        if V::all(both_iso | !(lam + kap).gt(zero)) {
            return iso_result;
        }
        let e2r = self.t - g.axis.scale(self.t.dot(g.axis));
        let e2l = e2r.length_squared();
        let e2 = V3::select(
            e2l.gt(V::splat(1e-24)),
            e2r.scale(e2l.max(V::splat(1e-30)).rsqrt()),
            tangent_of(g.axis),
        );
        let e1 = e2.cross(g.axis);
        let b = [h.axis.dot(e1), h.axis.dot(e2)];
        let an = TangentProductV::new(
            self.precision_in(e1, e2, false),
            other.precision_in(e1, e2, false),
            b,
            other.precision_times_offset(g.axis, e1, e2, false),
        );
        let is = TangentProductV::new(
            self.precision_in(e1, e2, true),
            other.precision_in(e1, e2, true),
            b,
            other.precision_times_offset(g.axis, e1, e2, true),
        );
        let ok = an.valid & is.valid;
        let mut amp = p0.amp;
        let rescale = is.attenuation.gt(V::splat(1e-12)) & h.axis.dot(g.axis).gt(zero);
        if V::any(rescale & ok) {
            let kk = self.k * other.k;
            let ratio = (an.attenuation * is.attenuation.max(V::splat(1e-30)).recip())
                .max(kk.recip())
                .min(kk);
            let log_iso = -(lam * kap)
                * (g.axis - h.axis).length_squared()
                * (p0.sharp + lam + kap).max(V::splat(1e-30)).recip();
            let f = exp((log_iso * ratio).min(zero));
            let scaled = V3::new(
                g.amp.x * h.amp.x * f,
                g.amp.y * h.amp.y * f,
                g.amp.z * h.amp.z * f,
            );
            amp = V3::select(rescale, scaled, amp);
        }
        let shifted =
            p0.axis + e1.scale(an.centre[0] - is.centre[0]) + e2.scale(an.centre[1] - is.centre[1]);
        let axis = normalize_or(shifted, p0.axis);
        let t0 = normalize_or(e1.scale(an.widest[0]) + e2.scale(an.widest[1]), e2);
        let t = normalize_or(t0 - axis.scale(t0.dot(axis)), e2);
        let ratio = an.det * is.det.max(V::splat(1e-30)).recip();
        let sharp = p0.sharp * ratio.max(zero).sqrt().sqrt();
        let aniso = AnisoV {
            sg: SgV { axis, sharp, amp },
            t,
            k: an.stretch.min(V::splat(MAX_STRETCH)),
        };
        let use_iso = both_iso | !(lam + kap).gt(zero) | !ok;
        AnisoV {
            sg: SgV {
                axis: V3::select(use_iso, iso_result.sg.axis, aniso.sg.axis),
                sharp: V::select(use_iso, iso_result.sg.sharp, aniso.sg.sharp),
                amp: V3::select(use_iso, iso_result.sg.amp, aniso.sg.amp),
            },
            t: V3::select(use_iso, iso_result.t, aniso.t),
            k: V::select(use_iso, one, aniso.k),
        }
    }
}

/// lo (x·y − (x·a)(y·a) − (x·t)(y·t)) + hi (x·t)(y·t), one entry of the tangent precision.
#[inline(always)]
fn quad_form<V: Vf>(lo: V, hi: V, xy: V, xa: V, ya: V, xt: V, yt: V) -> V {
    lo * (xy - xa * ya - xt * yt) + hi * xt * yt
}

/// `v` normalised, or `fallback` where `v` is (nearly) zero.
#[inline(always)]
fn normalize_or<V: Vf>(v: V3<V>, fallback: V3<V>) -> V3<V> {
    let l2 = v.length_squared();
    V3::select(
        l2.gt(V::splat(1e-24)),
        v.scale(l2.max(V::splat(1e-30)).rsqrt()),
        fallback,
    )
}

/// The product of two tangent-plane Gaussians (`TangentProduct`).
struct TangentProductV<V: Vf> {
    valid: V::M,
    det: V,
    centre: [V; 2],
    attenuation: V,
    stretch: V,
    widest: [V; 2],
}

impl<V: Vf> TangentProductV<V> {
    #[inline(always)]
    fn new(pa: [V; 3], pb: [V; 3], b: [V; 2], pb_b: [V; 2]) -> Self {
        let zero = V::splat(0.0);
        let p = [pa[0] + pb[0], pa[1] + pb[1], pa[2] + pb[2]];
        let det = p[0] * p[2] - p[1] * p[1];
        let valid = det.gt(zero);
        let idet = det.max(V::splat(1e-30)).recip();
        let inv = [p[2] * idet, -p[1] * idet, p[0] * idet];
        let centre = [
            inv[0] * pb_b[0] + inv[1] * pb_b[1],
            inv[1] * pb_b[0] + inv[2] * pb_b[1],
        ];
        // bᵀ P_a P⁻¹ P_b b = (P_a b)·centre (no cancellation; `TangentProduct`).
        let pa_b = [pa[0] * b[0] + pa[1] * b[1], pa[1] * b[0] + pa[2] * b[1]];
        let attenuation = (pa_b[0] * centre[0] + pa_b[1] * centre[1]).max(zero);
        let mean = V::splat(0.5) * (p[0] + p[2]);
        let half = V::splat(0.5) * (p[0] - p[2]);
        let d = half.mul_add(half, p[1] * p[1]).sqrt();
        let (hi, lo) = (mean + d, (mean - d).max(V::splat(1e-20)));
        let first = p[0].ge(p[2]);
        let widest = [
            V::select(first, hi - p[2], p[1]),
            V::select(first, p[1], hi - p[0]),
        ];
        TangentProductV {
            valid,
            det,
            centre,
            attenuation,
            stretch: (hi * lo.recip()).sqrt(),
            widest,
        }
    }
}

/// erf (Abramowitz & Stegun 7.1.26, absolute error ≤ 1.5e-7; `sg::cluster::erf`).
#[inline(always)]
pub fn erf<V: Vf>(x: V) -> V {
    let one = V::splat(1.0);
    let t = V::splat(0.327_591_1).mul_add(x.abs(), one).recip();
    let mut p = V::splat(1.061_405_4);
    p = p.mul_add(t, V::splat(-1.453_152_1));
    p = p.mul_add(t, V::splat(1.421_413_7));
    p = p.mul_add(t, V::splat(-0.284_496_72));
    p = p.mul_add(t, V::splat(0.254_829_6));
    let y = one - p * t * exp(-(x * x));
    y.copysign(x)
}

/// E[max(0, n·ω)] under a lobe with n·p = `c` and sharpness λ (`clamped_cosine_mean`): n·ω
/// normal with mean c and variance (1 − c²)/λ; c Φ(c/σ) + σ φ(c/σ), in [0, 1].
#[inline(always)]
pub fn clamped_cosine_mean<V: Vf>(c: V, sharp: V) -> V {
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    let var = (one - c * c).max(zero) * sharp.max(V::splat(1e-6)).recip();
    let sigma = var.sqrt().min(one);
    let narrow = !sigma.gt(V::splat(1e-6));
    let z = c * sigma.max(V::splat(1e-6)).recip();
    let pdf = exp(V::splat(-0.5) * z * z) * V::splat(0.398_942_3);
    let cdf = V::splat(0.5) * (one + erf(z * V::splat(std::f32::consts::FRAC_1_SQRT_2)));
    let wide = c.mul_add(cdf, sigma * pdf).max(zero).min(one);
    V::select(narrow, c.max(zero), wide)
}
