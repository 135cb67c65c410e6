//! The integral of a spherical Gaussian over a spherical triangle in f32 SIMD lanes: the fast
//! twin of `math::spherical_triangle::integrate_sg` (f64, the oracle it is tested against).
//!
//! ∫_ABC exp(λ (ω·p − 1)) dω is decomposed around the axis P into the signed edge triangles
//! PXY, each reduced to a 1-D integral along its edge (Xu et al. 2014, §5; `docs/sg-math.md`).
//! Along an edge's great circle, with θ0 the angle from P to the circle, σ the arc from the
//! foot F (the circle's point nearest P), t = tan(σ/2), s0 = sin θ0 and k = cos θ0:
//!
//!   x(t) = 1 − cos θ = x0 + 2k t²/(1 + t²),  dψ/dt = 2 s0 (1 + t²) / (s0² (1 − t²)² + 4t²),
//!
//! and the edge triangle from F to the point t = τ holds F(τ) = ∫_0^τ h(x(t)) dψ/dt dt with the
//! closed radial part h(x) = (1 − e^{−λx})/λ. The kernel's substitution s² = λ (x − x0), i.e.
//! t = s / √(2kλ − s²), makes the integrand smooth for every θ0 and λ (the poles of dψ/dt
//! cancel against h's zero, and the exponential becomes e^{−s²}): a fixed
//! [`NODES`]-point Gauss–Legendre rule on s ∈ [0, min(S, [`S_MAX`])] and, beyond S_MAX, where
//! e^{−λx} < e^{−9} relative, the closed form h ≈ 1/λ: (ψ(τ) − ψ(t(S_MAX)))/λ, with
//! ψ(t) = atan2(2t, s0 (1 − t²)). No adaptive splitting: every lane does the same work.
//!
//! An edge is F(|t_Y|) ± F(|t_X|) (sum when its arc contains the foot), or 2F(∞) − F − F when
//! its arc passes the antipode of the foot (possible only for λ ≥ 25, see below). Arcs beyond
//! 90° from P (σ > π/2) are taken in closed form, which needs λ ≥ 25 (e^{−λ} below 2e-11);
//! lanes with a vertex beyond 90° and λ < 25 are marked for the f64 scalar routine instead.
//! Measured accuracy and cost: `results/sg-performance.md`.

use super::simd::Vf;
use super::v3::V3;
use super::vmath::{atan2, exp, expm1};

/// Gauss–Legendre nodes of the s-integral (5: f32 max error 3.6e-4 over random triangles in
/// the prototype, against 1.4e-3 for 4; measured by `kernel::tests`).
pub const NODES: usize = 4;
/// Upper end of the s-integral: beyond it e^{−s²} < e^{−9} = 1.2e-4 of h's variation, and
/// h = 1/λ is used.
pub const S_MAX: f32 = 3.0;
/// Below this sharpness the closed form of arcs beyond 90° from P (h = 1/λ where x ≥ 1, off by
/// at most e^{−λ}/λ per radian of azimuth: ≤ 3e-4 of any triangle holding 1 % of the lobe) is
/// not accurate: such lanes take [`subdivided`] instead.
pub const FAR_MIN_SHARPNESS: f32 = 12.0;
/// Wider triangles (longest chord between unit vertices) that need [`subdivided`] fall back to
/// the scalar routine: its 16 pieces would be too wide for the 7-point rule.
pub const SUBDIVIDED_MAX_CHORD: f32 = 1.5;
/// Triangles at most this wide (longest chord between unit vertices) take [`subdivided`] with
/// one subdivision: half of [`SUBDIVIDED_MAX_CHORD`], so that their 4 pieces are about as wide as
/// the 16 of the widest triangle the rule takes (measured by
/// `kernel_subdivided_rule_once_meets_the_contract`).
pub const SUBDIVIDED_ONCE_CHORD: f32 = 0.5 * SUBDIVIDED_MAX_CHORD;
/// Edges whose nearest point is more than this many lobe widths² away (λ x0 > 12: e^{−12} =
/// 6e-6) take h = 1/λ along their whole arc, with no quadrature, when every lane's does.
const Y_CLOSED: f32 = 12.0;

const GL_X: [f32; 4] = [-0.861_136_3, -0.339_981_04, 0.339_981_04, 0.861_136_3];
const GL_W: [f32; 4] = [0.347_854_84, 0.652_145_15, 0.652_145_15, 0.347_854_84];

/// The result of one vector of problems.
#[derive(Clone, Copy, Debug)]
pub struct TriangleSg<V: Vf> {
    /// ∫ exp(λ (ω·p − 1)) dω over the triangle (valid where `fallback` is not set).
    pub value: V,
    /// Lanes this kernel cannot do accurately (a vertex beyond 90° from the axis with
    /// λ < [`FAR_MIN_SHARPNESS`], or a non-finite input): compute them with the scalar routine.
    pub fallback: V::M,
}

/// The signed s of a point at t = tan(σ/2) on the near half: sign(t) √(2kλ t²/(1 + t²)), t
/// clamped to [−1, 1] (the far half is taken in closed form).
#[inline(always)]
fn s_of<V: Vf>(kl2: V, t: V) -> V {
    let one = V::splat(1.0);
    let tc = t.max(-one).min(one);
    let tc2 = tc * tc;
    let s2 = kl2 * tc2 * (one + tc2).recip();
    (s2 * s2.max(V::splat(1e-30)).rsqrt()).copysign(tc)
}

/// t at signed s (inverse of [`s_of`] on the near half): s / √(2kλ − s²).
#[inline(always)]
fn t_of_s<V: Vf>(kl2: V, s: V) -> V {
    s * (kl2 - s * s).max(V::splat(1e-30)).rsqrt()
}

/// ψ(t_b) − ψ(t_a) with ψ(t) = atan2(2t, s0 (1 − t²)), the azimuth around P of the point t
/// (one atan2 of the two vectors; |ψ(t_b) − ψ(t_a)| < π).
#[inline(always)]
fn dpsi<V: Vf>(s0: V, ta: V, tb: V) -> V {
    let one = V::splat(1.0);
    let two = V::splat(2.0);
    let (xa, ya) = (s0 * (one - ta * ta), two * ta);
    let (xb, yb) = (s0 * (one - tb * tb), two * tb);
    atan2(xa * yb - ya * xb, xa.mul_add(xb, ya * yb))
}

/// ∫_{s_a}^{s_b} h(x) dψ/ds ds by the [`NODES`]-point rule (the integrand is even and smooth
/// in s: see the module doc), times 1/λ.
#[inline(always)]
fn quadrature<V: Vf>(s0: V, kl2: V, y0: V, inv_lam: V, sa: V, sb: V) -> V {
    let hw = V::splat(0.5) * (sb - sa);
    let mid = V::splat(0.5) * (sa + sb);
    let two_s0 = V::splat(2.0) * s0;
    let s02 = s0 * s0;
    let mut acc = V::splat(0.0);
    let c = two_s0 * kl2 * kl2;
    for i in 0..NODES {
        let s = hw.mul_add(V::splat(GL_X[i]), mid);
        let s2 = s * s;
        // With d = 2kλ − s² and t = s/√d: dt/ds = 2kλ d^{−3/2}, 1 + t² = 2kλ/d, 1 − t² =
        // (d − s²)/d, so dψ/dt · dt/ds = 2 s0 (2kλ)² d^{−1/2} / (s0² (d − s²)² + 4 s² d).
        let d = (kl2 - s2).max(V::splat(1e-30));
        let w = d - s2;
        let den = (s02 * w)
            .mul_add(w, V::splat(4.0) * s2 * d)
            .max(V::splat(1e-30));
        let jac = c * d.rsqrt() * den.recip();
        let h = -expm1(-(y0 + s2));
        acc = (h * jac).mul_add(V::splat(GL_W[i]), acc);
    }
    acc * hw * inv_lam
}

/// The signed integral over the edge triangle P X Y (unit vectors; `n` ∝ X × Y, computed by
/// the caller from the raw vertices so that short edges keep their precision), its
/// orientation ∝ det(P, X, Y), and the smallest 1 − cos θ on the arc's interior (+∞ when the foot is not on the arc).
#[inline(always)]
fn edge<V: Vf>(p: V3<V>, lam: V, inv_lam: V, x: V3<V>, y: V3<V>, n: V3<V>) -> (V, V, V) {
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    let nl2 = n.length_squared();
    let det = p.dot(n);
    let valid = nl2.gt(zero) & det.abs().gt(zero);
    let inv = V::select(valid, nl2.rsqrt(), zero);
    // Unit normal of the great circle on P's side.
    let m = n.scale(inv.copysign(det));
    let s0 = p.dot(m).max(zero).min(one);
    let k = (one - s0 * s0).max(zero).sqrt();
    // The foot F and the circle's tangent there; a pole (k = 0) takes X as its reference.
    let foot = m.scale(-s0) + p;
    let has_foot = k.gt(V::splat(1e-6));
    let f = V3::select(has_foot, foot.scale(k.max(V::splat(1e-30)).recip()), x);
    let e_dir = m.cross(f);
    let (tx, ty) = (half_tangent(x, f, e_dir), half_tangent(y, f, e_dir));
    let x0 = s0 * s0 * (one + k).recip();
    let kl2 = V::splat(2.0) * k * lam;
    let y0 = lam * x0;
    let (t_lo, t_hi) = (tx.min(ty), tx.max(ty));
    // An arc through the antipode of the foot (both ends beyond 90° from it, on either side)
    // lies entirely beyond 90° from P: closed form, no quadrature.
    let far = t_lo.lt(-one) & t_hi.gt(one);
    let through_foot = t_lo.lt(zero) & t_hi.gt(zero) & !far;
    // The whole arc's azimuth span seen from P, with h = 1/λ; where the lobe matters (s within
    // ±S_MAX) the rule replaces that by the integral of h.
    let near_span = dpsi(s0, t_lo, t_hi);
    // Through the antipode, ψ runs from ψ(t_hi) on to ψ(t_lo) + 2π.
    let span = V::select(
        far,
        V::splat(2.0 * std::f32::consts::PI) + near_span,
        near_span,
    );
    let mut v = span * inv_lam;
    if V::any(y0.le(V::splat(Y_CLOSED)) & valid & !far) {
        let smax = V::splat(S_MAX);
        let sa = s_of(kl2, t_lo).max(-smax);
        let sb = s_of(kl2, t_hi).min(smax);
        let has = sb.gt(sa) & !far;
        if V::any(has) {
            let (sa, sb) = (V::select(has, sa, zero), V::select(has, sb, zero));
            let (ta, tb) = (t_of_s(kl2, sa), t_of_s(kl2, sb));
            // Two pieces, split at the foot when the arc holds it (each piece then starts
            // where the integrand is flattest), else at the middle.
            let sm = V::select(through_foot, zero, V::splat(0.5) * (sa + sb));
            let q =
                quadrature(s0, kl2, y0, inv_lam, sa, sm) + quadrature(s0, kl2, y0, inv_lam, sm, sb);
            v = V::select(has, (span - dpsi(s0, ta, tb)).mul_add(inv_lam, q), v);
        }
    }
    let v = V::select(valid, v.copysign(det), zero);
    let xmin = V::select(through_foot & valid, x0, V::splat(f32::INFINITY));
    (v, V::select(valid, det, zero), xmin)
}

/// tan(σ/2) of unit `v` on the great circle through the foot `f` with tangent `e` there, σ the
/// signed arc from `f` (clamped to ±10⁶: `v` near the antipode of the foot).
#[inline(always)]
fn half_tangent<V: Vf>(v: V3<V>, f: V3<V>, e: V3<V>) -> V {
    let c = V::splat(1.0) + v.dot(f);
    let t = v.dot(e) * c.max(V::splat(1e-12)).recip();
    t.max(V::splat(-1e6)).min(V::splat(1e6))
}

/// 1/l for l > 0, else 0.
#[inline(always)]
fn recip_or_zero<V: Vf>(l: V) -> V {
    V::select(l.gt(V::splat(0.0)), l.recip(), V::splat(0.0))
}

/// 1 − p·v for unit p, v, as |v − p|²/2 (no cancellation near the axis).
#[inline(always)]
fn one_minus_cos<V: Vf>(p: V3<V>, v: V3<V>) -> V {
    V::splat(0.5) * (v - p).length_squared()
}

/// Dunavant's degree-5 rule on the triangle (barycentrics of b and c, weight; weights sum to 1).
const D5: [(f32, f32, f32); 7] = [
    (0.333_333_34, 0.333_333_34, 0.225),
    (0.470_142_06, 0.470_142_06, 0.132_394_15),
    (0.059_715_87, 0.470_142_06, 0.132_394_15),
    (0.470_142_06, 0.059_715_87, 0.132_394_15),
    (0.101_286_51, 0.101_286_51, 0.125_939_18),
    (0.797_427, 0.101_286_51, 0.125_939_18),
    (0.101_286_51, 0.797_427, 0.125_939_18),
];

/// The 7-point rule [`D5`] (through the exact Jacobian of the projection onto the sphere: no
/// edge geometry, no atan2 beyond the solid angle's) takes the triangles over which the
/// exponent λ (1 − cos θ) varies by at most [`SMALL_RANGE`] and whose longest chord between
/// unit vertex directions is at most [`SMALL_CHORD`], or by at most [`SMALL_RANGE_TINY`] when
/// the chord is at most [`SMALL_CHORD_TINY`]. Measured in the prototype over 5000 random
/// triangles: max relative error 1.2e-4 and 2e-4 in the two regions; the kernel's own is in
/// `results/sg-performance.md`.
pub const SMALL_CHORD: f32 = 0.5;
/// See [`SMALL_CHORD`].
pub const SMALL_RANGE: f32 = 0.5;
/// See [`SMALL_CHORD`].
pub const SMALL_CHORD_TINY: f32 = 0.1;
/// See [`SMALL_CHORD`].
pub const SMALL_RANGE_TINY: f32 = 1.5;
/// Below this chord the rule runs on the raw triangle (whose edge vectors keep their precision),
/// above it on the flat triangle through the unit vertices (whose projection onto the sphere
/// is more uniform when the raw vertices lie at very different distances).
const RAW_RULE_CHORD: f32 = 0.01;

/// The rule [`D5`] over the flat triangle (A, B, C) (raw vectors): ∫ g(ω) dω =
/// ½ |det(A, B, C)| Σ w_k g(V_k/|V_k|) / |V_k|³ with V_k = A + u_k (B − A) + v_k (C − A).
#[inline(always)]
fn small<V: Vf>(p: V3<V>, lam: V, a: V3<V>, e1: V3<V>, e2: V3<V>, det_abs: V) -> V {
    let mut acc = V::splat(0.0);
    for &(u, v, w) in &D5 {
        let q = e2.mul_add(V::splat(v), e1.mul_add(V::splat(u), a));
        let r2 = q.length_squared();
        let inv_r = r2.max(V::splat(1e-30)).rsqrt();
        let x = one_minus_cos(p, q.scale(inv_r));
        let g = exp(-lam * x) * inv_r * inv_r * inv_r;
        acc = g.mul_add(V::splat(w), acc);
    }
    V::splat(0.5) * det_abs * acc
}

/// The 7-point rule on each of the 16 spherical triangles of two midpoint subdivisions of the
/// triangle of unit vertices `a`, `b`, `c` (geodesic midpoints: the pieces partition the
/// spherical triangle exactly), for wide lobes (λ < [`FAR_MIN_SHARPNESS`]) over triangles that
/// reach beyond 90° from the axis; with `once`, the 4 triangles of one subdivision (for
/// triangles at most [`SUBDIVIDED_ONCE_CHORD`] wide, whose 4 pieces are no wider than the 16 of
/// the widest triangle this rule takes).
#[inline(always)]
fn subdivided<V: Vf>(p: V3<V>, lam: V, a: V3<V>, b: V3<V>, c: V3<V>, once: bool) -> V {
    let mut acc = V::splat(0.0);
    let (ab, bc, ca) = (midpoint(a, b), midpoint(b, c), midpoint(c, a));
    for [x, y, z] in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
        if once {
            acc = acc + flat_piece(p, lam, x, y, z);
            continue;
        }
        let (xy, yz, zx) = (midpoint(x, y), midpoint(y, z), midpoint(z, x));
        for [u, v, w] in [[x, xy, zx], [xy, y, yz], [zx, yz, z], [xy, yz, zx]] {
            acc = acc + flat_piece(p, lam, u, v, w);
        }
    }
    acc
}

/// The 7-point rule over the flat triangle through the unit vertices `u`, `v`, `w`.
#[inline(always)]
fn flat_piece<V: Vf>(p: V3<V>, lam: V, u: V3<V>, v: V3<V>, w: V3<V>) -> V {
    let (e1, e2) = ((v - u), (w - u));
    let det = u.dot(e1.cross(e2)).abs();
    small(p, lam, u, e1, e2, det)
}

/// The geodesic midpoint of unit vectors x and y.
#[inline(always)]
fn midpoint<V: Vf>(x: V3<V>, y: V3<V>) -> V3<V> {
    (x + y).normalize_or_zero()
}

/// What [`integrate`] computes before choosing its path.
#[derive(Clone, Copy)]
pub struct Prepared<V: Vf> {
    p: V3<V>,
    lam: V,
    inv_lam: V,
    sharp: V::M,
    /// Raw vertices (positively oriented), the edges from `ra`, |det(A, B, C)|.
    ra: V3<V>,
    e1: V3<V>,
    e2: V3<V>,
    det_abs: V,
    /// Unit vertices.
    a: V3<V>,
    b: V3<V>,
    c: V3<V>,
    /// The great circles' normals ∝ A × B, B × C, C × A and their dot with p.
    n: [V3<V>; 3],
    d: [V; 3],
    omega: V,
    /// |det(â, b̂, ĉ)| and the longest chord between the unit vertices.
    det_unit: V,
    chord: V,
    inside: V::M,
    xv_min: V,
    x_low: V,
    /// The lanes the 7-point rule takes ([`SMALL_CHORD`], [`SMALL_RANGE`]).
    pub small: V::M,
    /// The lanes the edge integrals take.
    pub edges: V::M,
    /// Lanes with a vertex beyond 90° and λ < [`FAR_MIN_SHARPNESS`], taken by [`subdivided`].
    pub far_weak: V::M,
    /// Of those, the ones too wide for it, left to the scalar routine.
    pub too_wide: V::M,
}

/// The geometry of the problems and the path each lane takes (see [`integrate`]).
#[inline(always)]
pub fn prepare<V: Vf>(p: V3<V>, lam: V, a: V3<V>, b: V3<V>, c: V3<V>) -> Prepared<V> {
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    // Positive orientation: det(A, B, C) > 0. The determinant and the edges' great-circle
    // normals come from the raw vertices' differences, which keep their relative precision on
    // tiny triangles (the differences of unit vectors would not).
    let (ra, rb0, rc0) = (a, b, c);
    let det0 = ra.dot((rb0 - ra).cross(rc0 - ra));
    let flip = det0.lt(zero);
    let rb = V3::select(flip, rc0, rb0);
    let rc = V3::select(flip, rb0, rc0);
    let (e1, e2) = ((rb - ra), (rc - ra));
    let det_abs = det0.abs();
    let (ia, ib, ic) = (
        recip_or_zero(ra.length()),
        recip_or_zero(rb.length()),
        recip_or_zero(rc.length()),
    );
    let (a, b, c) = (ra.scale(ia), rb.scale(ib), rc.scale(ic));
    let omega = V::splat(2.0)
        * atan2(det_abs * ia * ib * ic, one + a.dot(b) + b.dot(c) + c.dot(a)).max(zero);
    let lam = lam.max(zero);
    let sharp = lam.gt(V::splat(1e-6));
    let inv_lam = V::select(sharp, one / lam, zero);
    // Great-circle normals ∝ A × B = A × (B − A), and so on.
    let n = [ra.cross(e1), rb.cross(rc - rb), rc.cross(ra - rc)];
    let d = [p.dot(n[0]), p.dot(n[1]), p.dot(n[2])];
    // P in the closed triangle (on an edge too): the smallest 1 − cos θ is 0.
    let inside = d[0].ge(zero) & d[1].ge(zero) & d[2].ge(zero);
    let (xa, xb, xc) = (
        one_minus_cos(p, a),
        one_minus_cos(p, b),
        one_minus_cos(p, c),
    );
    let xv_min = xa.min(xb).min(xc);
    let xv_max = xa.max(xb).max(xc);
    // A lower bound of 1 − cos θ over the triangle: every point is within the longest chord ℓ
    // of a vertex, so its chord to p is at least d_min − ℓ (d = √(2x)).
    let chord = (a - b).length().max((b - c).length()).max((c - a).length());
    let d_low = ((V::splat(2.0) * xv_min).sqrt() - chord).max(zero);
    let x_low = V::select(inside, zero, V::splat(0.5) * d_low * d_low);
    let range = lam * (xv_max - x_low);
    let small = ((chord.le(V::splat(SMALL_CHORD)) & range.le(V::splat(SMALL_RANGE)))
        | (chord.le(V::splat(SMALL_CHORD_TINY)) & range.le(V::splat(SMALL_RANGE_TINY))))
        & sharp;
    let beyond = a.dot(p).lt(zero) | b.dot(p).lt(zero) | c.dot(p).lt(zero);
    let far_weak = beyond & lam.lt(V::splat(FAR_MIN_SHARPNESS)) & !small & sharp;
    let too_wide = far_weak & chord.gt(V::splat(SUBDIVIDED_MAX_CHORD));
    let edges = !small & !far_weak & sharp;
    Prepared {
        p,
        lam,
        inv_lam,
        sharp,
        ra,
        e1,
        e2,
        det_abs,
        a,
        b,
        c,
        n,
        d,
        omega,
        det_unit: det_abs * ia * ib * ic,
        chord,
        inside,
        xv_min,
        x_low,
        small,
        edges,
        far_weak,
        too_wide,
    }
}

/// ∫ over the spherical triangle of vertex directions `a`, `b`, `c` (any length, either
/// winding) of exp(λ (ω·p − 1)), p unit, λ ≥ 0. λ = 0 gives the solid angle. Never NaN for
/// finite input; lanes it cannot do are flagged in [`TriangleSg::fallback`].
#[inline(always)]
pub fn integrate<V: Vf>(p: V3<V>, lam: V, a: V3<V>, b: V3<V>, c: V3<V>) -> TriangleSg<V> {
    finish(&prepare(p, lam, a, b, c))
}

/// [`integrate`] from its [`prepare`]d geometry: the 7-point rule where it is accurate, the
/// edge integrals elsewhere (each computed only when some lane needs it), clamped to
/// [Ω e^{−2λ}, Ω e^{−λ x_min}].
#[inline(always)]
pub fn finish<V: Vf>(q: &Prepared<V>) -> TriangleSg<V> {
    let zero = V::splat(0.0);
    let (p, lam, inv_lam) = (q.p, q.lam, q.inv_lam);
    let mut value = zero;
    // The clamp's smallest 1 − cos θ: the safe bound for the rule, the exact minimum (vertices
    // and the edges' feet) where the edges are integrated.
    let mut xmin = q.x_low;
    if V::any(q.small) {
        let raw = q.chord.lt(V::splat(RAW_RULE_CHORD));
        let base = V3::select(raw, q.ra, q.a);
        let e1 = V3::select(raw, q.e1, q.b - q.a);
        let e2 = V3::select(raw, q.e2, q.c - q.a);
        let det = V::select(raw, q.det_abs, q.det_unit);
        value = small(p, lam, base, e1, e2, det);
    }
    if V::any(q.far_weak) {
        // One subdivision (28 exponentials, not 112) when every lane that takes the rule is
        // narrow enough for it.
        let once = V::all(!q.far_weak | q.chord.le(V::splat(SUBDIVIDED_ONCE_CHORD)));
        value = V::select(q.far_weak, subdivided(p, lam, q.a, q.b, q.c, once), value);
    }
    if V::any(q.edges) {
        let (ea, _, ma) = edge(p, lam, inv_lam, q.a, q.b, q.n[0]);
        let (eb, _, mb) = edge(p, lam, inv_lam, q.b, q.c, q.n[1]);
        let (ec, _, mc) = edge(p, lam, inv_lam, q.c, q.a, q.n[2]);
        let mut sum = ea + eb + ec;
        // −P inside: the edge triangles wrap around the sphere; add the lobe's whole integral.
        let anti = q.d[0].lt(zero) & q.d[1].lt(zero) & q.d[2].lt(zero);
        let lobe = V::splat(2.0 * std::f32::consts::PI) * -expm1(V::splat(-2.0) * lam) * inv_lam;
        sum = V::select(anti, sum + lobe, sum);
        let xe = V::select(q.inside, zero, q.xv_min.min(ma).min(mb).min(mc));
        xmin = V::select(q.edges, xe, xmin);
        value = V::select(q.edges, sum, value);
    }
    let upper = q.omega * exp(-lam * xmin);
    let lower = q.omega * exp(V::splat(-2.0) * lam);
    let value = V::select(q.sharp, value.max(lower).min(upper), q.omega);
    // NaN fails every comparison: a lane whose value is not ≥ 0 is not finite.
    let bad = !(value.ge(zero) & value.le(V::splat(f32::MAX)));
    TriangleSg {
        value: V::select(bad, zero, value),
        fallback: q.too_wide | bad,
    }
}
