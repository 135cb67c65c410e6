//! The SG transport of one reflector triangle to many receiver points at once, lanes =
//! receivers: the twin of `LitTriangle::shade` (`aim_at_receiver` + `one_bounce_with` with the
//! default `ReceiverOptions`: exact cosine moments, horizon clipping, anisotropic lobes), which
//! stays the oracle.

use super::lobes::{AnisoV, SgV, tangent_of};
use super::receivers::ReceiversV;
use super::simd::Vf;
use super::triangle;
use super::v3::V3;
use super::vmath::{atan2, exp};
use crate::brdf::sg_fit::MAX_LOBES;
use crate::math::sg::Sg;
use crate::sg::lighting::LitTriangle;
use crate::sg::transport::receiver::{CosineMode, MAX_STRETCH, ReceiverOptions};
use glam::Vec3;

/// What the leaf transport needs of a lit triangle, once per triangle.
#[derive(Clone, Copy, Debug)]
pub struct LeafSummary {
    pub lit: bool,
    pub vertices: [Vec3; 3],
    pub centroid: Vec3,
    /// |v0 − centroid|, the triangle's part of the lit-side margin.
    pub radius: f32,
    pub diffuse: Vec3,
    pub lobes: [Sg; MAX_LOBES],
    pub n_lobes: usize,
    pub normal: Vec3,
    pub geometric_normal: Vec3,
    /// The light's height above the plane through the origin, its mirror image, cos θ_l.
    pub h_l: f32,
    pub image: Vec3,
    pub origin: Vec3,
    pub cos_c: f32,
    pub half_vector: bool,
    /// The lobes' anisotropy when not re-aimed.
    pub stretch: f32,
}

impl LeafSummary {
    pub fn new(t: &LitTriangle) -> LeafSummary {
        let [a, b, c] = t.vertices;
        let centroid = (a + b + c) / 3.0;
        let mut out = LeafSummary {
            lit: false,
            vertices: t.vertices,
            centroid,
            radius: (a - centroid).length(),
            diffuse: Vec3::ZERO,
            lobes: [Sg::new(Vec3::Z, 0.0, Vec3::ZERO); MAX_LOBES],
            n_lobes: 0,
            normal: Vec3::Z,
            geometric_normal: Vec3::Z,
            h_l: 0.0,
            image: Vec3::ZERO,
            origin: centroid,
            cos_c: 0.0,
            half_vector: false,
            stretch: 1.0,
        };
        if let Some(s) = &t.sg {
            let h_l = (s.light - s.origin).dot(s.normal);
            out = LeafSummary {
                lit: true,
                diffuse: s.diffuse,
                lobes: s.lobes,
                n_lobes: s.len,
                normal: s.normal,
                geometric_normal: s.geometric_normal,
                h_l,
                image: s.light - 2.0 * h_l * s.normal,
                origin: s.origin,
                cos_c: s.light_cosine(),
                half_vector: s.half_vector,
                stretch: s.stretch,
                ..out
            };
        }
        out
    }
}

/// ∫ max(0, n·ω) dω over the triangle of directions a, b, c (above the horizon):
/// ½ |Σ θ_e n·(v_i × v_{i+1}) / |v_i × v_{i+1}|| (`projected_solid_angle`).
#[inline(always)]
fn projected_solid_angle<V: Vf>(a: V3<V>, b: V3<V>, c: V3<V>, n: V3<V>) -> V {
    let v = [
        a.normalize_or_zero(),
        b.normalize_or_zero(),
        c.normalize_or_zero(),
    ];
    let mut s = V::splat(0.0);
    for i in 0..3 {
        let (p, q) = (v[i], v[(i + 1) % 3]);
        let cr = p.cross(q);
        let l2 = cr.length_squared();
        let ok = l2.gt(V::splat(0.0));
        let inv = l2.max(V::splat(1e-30)).rsqrt();
        let len = l2 * inv;
        let theta = atan2(len, p.dot(q));
        s = V::select(ok, (theta * n.dot(cr) * inv) + s, s);
    }
    (V::splat(0.5) * s).abs()
}

/// e^{|w| − λ} ∫_T exp(w·ω − |w|) dω = e^{−λ} J(w), the smooth SG integral of `cosine_weighted`.
#[inline(always)]
fn scaled_integral<V: Vf>(w: V3<V>, lam: V, a: V3<V>, b: V3<V>, c: V3<V>) -> V {
    let zero = V::splat(0.0);
    let l2 = w.length_squared();
    let pos = l2.gt(zero);
    let inv = l2.max(V::splat(1e-30)).rsqrt();
    let len = l2 * inv;
    let dir = V3::select(pos, w.scale(inv), V3::splat(Vec3::Z));
    triangle::integrate(dir, V::select(pos, len, zero), a, b, c).value * exp(len - lam)
}

/// ∫_T exp(λ(p·ω − 1)) (n·ω) dω for the unit-amplitude lobe (`cosine_weighted`): the cosine at
/// the axis where the lobe is well above the horizon (n·p ≥ 3σ), else the central difference
/// of the SG integral along n. Each form runs only when some lane takes it. The kernel's rare
/// fallback lanes (a wide lobe over a triangle wider than 1.5 rad reaching past 90°) keep their
/// kernel value here; `shade_exact` recomputes them.
#[inline(always)]
fn cosine_weighted<V: Vf>(axis: V3<V>, lam: V, n: V3<V>, a: V3<V>, b: V3<V>, c: V3<V>) -> V {
    let zero = V::splat(0.0);
    let lam = lam.max(zero);
    let np = n.dot(axis);
    let var = (V::splat(1.0) - np * np).max(zero) * lam.max(V::splat(1e-6)).recip();
    let above = np.gt(zero) & (np * np).ge(V::splat(9.0) * var);
    let mut out = zero;
    if V::any(above) {
        out = V::select(
            above,
            triangle::integrate(axis, lam, a, b, c).value * np,
            out,
        );
    }
    if !V::all(above) {
        let v = axis.scale(lam);
        let h = V::splat(0.1) * lam.max(V::splat(1.0)).sqrt();
        let up = scaled_integral(v + n.scale(h), lam, a, b, c);
        let dn = scaled_integral(v - n.scale(h), lam, a, b, c);
        let d = ((up - dn) * (V::splat(2.0) * h).recip()).max(zero);
        out = V::select(above, out, d);
    }
    out
}

/// ∫ over the triangle of the anisotropic lobe times n·ω (`Anisotropic::integrate`): in the
/// whitened directions ω' = Mω, M = I + (k − 1) t tᵀ, where it is isotropic with sharpness
/// s/k, dω = dω'/k and the cosine becomes (M⁻¹n)·ω'.
#[inline(always)]
fn lobe_integral_cos<V: Vf>(l: &AnisoV<V>, n: V3<V>, tri: [V3<V>; 3]) -> V3<V> {
    let one = V::splat(1.0);
    let stretched = l.k.gt(V::splat(1.0 + 1e-4));
    let (t, k) = (l.t, V::select(stretched, l.k, one));
    let km1 = k - one;
    let n_w = n + t.scale((k.recip() - one) * t.dot(n));
    let n_len = n_w.length();
    let n_u = n_w.scale(n_len.max(V::splat(1e-30)).recip());
    let inv_k = k.recip();
    let f = cosine_weighted(
        l.sg.axis,
        l.sg.sharp * inv_k,
        n_u,
        tri[0] + t.scale(km1 * t.dot(tri[0])),
        tri[1] + t.scale(km1 * t.dot(tri[1])),
        tri[2] + t.scale(km1 * t.dot(tri[2])),
    ) * inv_k
        * n_len;
    l.sg.amp.scale(f)
}

/// Vertex `idx[0]` of the triangle rotated so that the second (`first_b`) or third (`first_c`)
/// vertex comes first, with its height above the horizon.
#[inline(always)]
fn rotated<V: Vf>(
    first_b: V::M,
    first_c: V::M,
    rel: &[V3<V>; 3],
    d: &[V; 3],
    idx: [usize; 3],
) -> (V3<V>, V) {
    let [j0, j1, j2] = idx;
    (
        V3::select(first_b, rel[j1], V3::select(first_c, rel[j2], rel[j0])),
        V::select(first_b, d[j1], V::select(first_c, d[j2], d[j0])),
    )
}

/// Multiplies two RGB triples lane-wise.
#[inline(always)]
fn rgb_mul<V: Vf>(a: V3<V>, b: V3<V>) -> V3<V> {
    V3::new(a.x * b.x, a.y * b.y, a.z * b.z)
}

/// The triangle's SG transport at every lane's receiver (no visibility), as
/// `LitTriangle::shade` with `opts` (which must be the default: moment cosine, horizon
/// clipping, anisotropic lobes).
#[inline(always)]
pub fn evaluate<V: Vf>(leaf: &LeafSummary, rx: &ReceiversV<V>, opts: &ReceiverOptions) -> V3<V> {
    debug_assert!(opts.cosine == CosineMode::Moment && opts.clip_horizon && opts.anisotropic);
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    let zero3 = V3::new(zero, zero, zero);
    if !leaf.lit || (rx.n_lobes == 0 && V::all(rx.diffuse.length_squared().le(zero))) {
        return zero3;
    }
    let x = rx.x;
    let n_x = rx.n;
    // Lit side of the geometric plane, with a margin for the triangle's size.
    let to_x = x - V3::splat(leaf.centroid);
    let reach = to_x.length() + V::splat(leaf.radius);
    let lit_side = to_x
        .dot(V3::splat(leaf.geometric_normal))
        .gt(V::splat(1e-4) * reach);
    if !V::any(lit_side) {
        return zero3;
    }
    // Clip the triangle (relative to x) to the horizon of n_x: rotate so that the odd vertex
    // (the only one below, or the only one above) comes first.
    let [va, vb, vc] = leaf.vertices;
    let rel = [V3::splat(va) - x, V3::splat(vb) - x, V3::splat(vc) - x];
    let d = [rel[0].dot(n_x), rel[1].dot(n_x), rel[2].dot(n_x)];
    let up = [d[0].ge(zero), d[1].ge(zero), d[2].ge(zero)];
    let count_up =
        V::select(up[0], one, zero) + V::select(up[1], one, zero) + V::select(up[2], one, zero);
    let one_below = count_up.ge(V::splat(1.5)) & count_up.le(V::splat(2.5));
    let two_below = count_up.ge(V::splat(0.5)) & count_up.le(V::splat(1.5));
    let all_up = count_up.ge(V::splat(2.5));
    // The odd vertex: with one below, the one below; with two below, the one above.
    // (one below: not up; two below: up)
    let first_b = (one_below & !up[1]) | (!one_below & up[1]);
    let first_c = ((one_below & !up[2]) | (!one_below & up[2])) & !first_b;
    let (pa, da) = rotated(first_b, first_c, &rel, &d, [0, 1, 2]);
    let (pb, db) = rotated(first_b, first_c, &rel, &d, [1, 2, 0]);
    let (pc, dc) = rotated(first_b, first_c, &rel, &d, [2, 0, 1]);
    let i_ab = pa + (pb - pa).scale(da * (da - db).recip());
    let i_ca = pa + (pc - pa).scale(da * (da - dc).recip());
    let visible = (all_up | one_below | two_below) & lit_side;
    // all up: [A, B, C, C]; one below (A): [I_AB, B, C, I_CA]; two below (A up): [A, I_AB, I_CA].
    let p0 = V3::select(one_below, i_ab, pa);
    let p1 = V3::select(one_below, pb, V3::select(two_below, i_ab, pb));
    let p2 = V3::select(one_below, pc, V3::select(two_below, i_ca, pc));
    let p3 = V3::select(one_below, i_ca, p2);
    // The reflected lobes re-aimed at x (`aim_at_receiver`).
    let nn = V3::splat(leaf.normal);
    let h_l = V::splat(leaf.h_l);
    let h_x = (x - V3::splat(leaf.origin)).dot(nn);
    let to_img = x - V3::splat(leaf.image);
    let di2 = to_img.length_squared();
    let aim = V::splat(leaf.h_l).gt(zero) & h_x.gt(zero) & di2.gt(zero);
    let axis_a = to_img.scale(di2.max(V::splat(1e-30)).rsqrt());
    let ratio = (h_l + h_x) * h_l.max(V::splat(1e-30)).recip();
    let mut scale = ratio * ratio;
    let mut stretch = V::splat(leaf.stretch);
    if leaf.half_vector {
        let cos_s = axis_a.dot(nn).max(V::splat(1.0 / MAX_STRETCH));
        let inv_s = cos_s.recip();
        if leaf.cos_c > 0.0 {
            scale = scale * V::splat(leaf.cos_c) * inv_s;
        }
        stretch = V::select(aim, inv_s, stretch);
    }
    let scale = V::select(aim, scale, one);
    // The reflector's lobes over incoming directions (flipped), with their anisotropy.
    let zero_lobe = AnisoV {
        sg: SgV {
            axis: zero3,
            sharp: zero,
            amp: zero3,
        },
        t: zero3,
        k: one,
    };
    let mut g = [zero_lobe; MAX_LOBES];
    for (gk, l) in g.iter_mut().zip(&leaf.lobes[..leaf.n_lobes]) {
        let axis = V3::select(aim, axis_a, V3::splat(l.axis));
        let flipped = -axis;
        let sg = SgV {
            axis: flipped,
            sharp: V::splat(l.sharpness) * scale,
            amp: V3::splat(l.amplitude),
        };
        let t = flipped.cross(nn);
        let tl = t.length_squared();
        let t = V3::select(
            tl.gt(V::splat(1e-24)),
            t.scale(tl.max(V::splat(1e-30)).rsqrt()),
            tangent_of(flipped),
        );
        *gk = AnisoV::new(sg, t, stretch);
    }
    let g = &g[..leaf.n_lobes];
    let h = &rx.lobes[..rx.n_lobes];
    let d_r = V3::splat(leaf.diffuse);
    let has_dr = leaf.diffuse != Vec3::ZERO;
    let mut sum = zero3;
    let quad = one_below & visible;
    for (k, tri) in [[p0, p1, p2], [p0, p2, p3]].into_iter().enumerate() {
        if k == 1 && !V::any(quad) {
            break;
        }
        let mut part = zero3;
        if has_dr {
            let psa = projected_solid_angle(tri[0], tri[1], tri[2], n_x);
            part = part + rgb_mul(d_r, rx.diffuse).scale(psa);
            for hj in h {
                part = part + rgb_mul(d_r, lobe_integral_cos(hj, n_x, tri));
            }
        }
        for gk in g {
            part = part + rgb_mul(rx.diffuse, lobe_integral_cos(gk, n_x, tri));
            for hj in h {
                part = part + lobe_integral_cos(&gk.product(hj), n_x, tri);
            }
        }
        let keep = if k == 0 { visible } else { quad };
        sum = V3::select(keep, sum + part, sum);
    }
    sum
}
