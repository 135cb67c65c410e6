//! Spherical triangles: solid angle and the integral of a spherical Gaussian over a triangle.
//!
//! [`integrate_sg`] computes ∫_{ABC} exp(λ (ω·p − 1)) dω by the scheme of Xu et al., "A
//! Practical Algorithm for Rendering Interreflections with All-Frequency BRDFs" (TOG 2014, §5):
//!
//! 1. Signed decomposition around P = p: Ω_ABC = Ω_PAB + Ω_PBC + Ω_PCA, each edge triangle
//!    carrying the sign of det(P, X, Y). In polar coordinates (θ, φ) around P the edge triangle
//!    PXY is {φ between the azimuths of X and Y, θ < θ_e(φ)}, θ_e(φ) on the edge's great circle.
//! 2. Closed-form radial part: ∫_{cos θ_e}^1 e^{λ (t − 1)} dt = h(x_e) with x = 1 − cos θ and
//!    h(x) = (1 − e^{−λ x}) / λ = −expm1(−λ x) / λ (→ x at λ → 0), leaving a 1-D integral over
//!    the azimuth per edge.
//! 3. Along an edge, with ψ the azimuth measured from the foot F of the perpendicular from P to
//!    the edge's great circle and θ0 = ∠(P, F): cos θ_e(ψ) = cos θ0 cos ψ / √(1 − cos²θ0 sin²ψ),
//!    i.e. cos ψ / √(cos²ψ + tan²θ0).
//! 4. When −P lies inside ABC the edge triangles wrap around: their signed sum is −(sphere ∖
//!    ABC), so the lobe's sphere integral is added. In general the correction is the lobe
//!    integral times −W / 2π, W = Σ signed edge azimuth spans (W = 2π if P is inside, −2π if −P
//!    is inside, 0 otherwise, ±π / ±α on the boundary), which is exact also when −P lies on an
//!    edge or a vertex.
//!
//! The 1-D azimuthal integral has two implementations: the paper's piecewise-linear one
//! ([`Scheme::PiecewiseLinear`]: h interpolated linearly in cos θ, every piece integrated
//! exactly with ∫ cos θ_e dψ = asin(cos θ0 sin ψ)) and Gauss-Legendre quadrature
//! ([`Scheme::GaussLegendre`]) of the same integral substituted to t = tan(σ/2), σ the edge's arc
//! length from the foot, where the Jacobian's poles cancel against the integrand's zeros. Both
//! split the range adaptively from λ and the edge's extent in y = λ (1 − cos θ).
//! [`integrate_sg`] uses Gauss-Legendre, 6.6× faster and far more accurate than the
//! piecewise-linear scheme at their defaults (`results/sg-core.md`). All internal arithmetic is
//! f64. Derivations: `docs/sg-math.md`.

use std::f64::consts::{PI, TAU};

use glam::{DVec3, Vec3};

use super::sg::lobe_integral_f64;

/// How the 1-D azimuthal integral of [`integrate_sg_scheme`] is evaluated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheme {
    /// The paper's scheme: h(x) interpolated linearly in x = 1 − cos θ between knots spaced in
    /// y = λ x by `step` (grown with the distance from the edge's smallest y, see
    /// `docs/sg-math.md`); each piece is integrated exactly over ψ.
    PiecewiseLinear { step: f64 },
    /// Gauss-Legendre quadrature of the given order (2, 3, 4, 5, 6 or 8; 7 uses 6, below 2
    /// uses 2, above 8 uses 8) of the same azimuthal integral,
    /// substituted to the edge's arc length σ with the Jacobian's poles cancelled, on pieces
    /// split in y = λ x.
    GaussLegendre { order: usize },
}

/// The scheme [`integrate_sg`] uses.
pub const DEFAULT_SCHEME: Scheme = Scheme::GaussLegendre {
    order: GL_DEFAULT_ORDER,
};
/// The order [`integrate_sg_gauss_legendre`] uses.
pub const GL_DEFAULT_ORDER: usize = 5;
/// The knot step [`integrate_sg_piecewise_linear`] uses.
pub const PL_DEFAULT_STEP: f64 = 0.05;

/// Below this |P × X| a vertex X counts as exactly ±P (azimuth undefined; the edge triangle
/// has zero area or is a degenerate lune, handled by the winding correction).
const COINCIDENT: f64 = 1e-10;

/// Normalised f64 copy; None for zero or non-finite vectors.
#[inline]
fn unit(v: Vec3) -> Option<DVec3> {
    let d = v.as_dvec3();
    let l = d.length();
    if l > 0.0 && l.is_finite() {
        Some(d / l)
    } else {
        None
    }
}

/// Solid angle of the spherical triangle with unit vertices a, b, c (f64), by Van Oosterom &
/// Strackee, "The Solid Angle of a Plane Triangle" (IEEE TBME 1983):
/// tan(Ω / 2) = |a·(b × c)| / (1 + a·b + b·c + c·a). In [0, 2π].
#[inline]
pub fn solid_angle_f64(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let det = a.dot(b.cross(c));
    let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    2.0 * det.abs().atan2(den)
}

/// A fixed table of realistic `integrate_sg` inputs (axis, λ, a, b, c) for benchmarks: per λ,
/// small (0.01 rad), medium (0.1) and large (1 rad) triangles with the axis inside, just
/// outside (1.5 radii from the centre) and 0.5 rad away.
pub fn benchmark_inputs(lambdas: &[f32]) -> Vec<(Vec3, f32, Vec3, Vec3, Vec3)> {
    // Rotates `c` by `angle` towards azimuth `az` in a fixed tangent frame.
    let offset = |c: Vec3, az: f32, angle: f32| {
        let t = if c.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
        let t = (t - c * c.dot(t)).normalize();
        let b = c.cross(t);
        (c * angle.cos() + (t * az.cos() + b * az.sin()) * angle.sin()).normalize()
    };
    let c = Vec3::new(0.3, -0.4, 0.87).normalize();
    let mut out = Vec::new();
    for &lam in lambdas {
        for size in [0.01f32, 0.1, 1.0] {
            let r = size / 3f32.sqrt();
            let a = offset(c, 0.2, r);
            let b = offset(c, 2.3, 0.8 * r);
            let cc = offset(c, 4.3, 1.1 * r);
            for p in [
                offset(c, 1.0, 0.2 * r),
                offset(c, 5.5, 1.5 * r),
                offset(c, 3.3, r + 0.5),
            ] {
                out.push((p, lam, a, b, cc));
            }
        }
    }
    out
}

/// Solid angle of the spherical triangle with vertex directions a, b, c (normalised here; any
/// winding): 2 atan2(|a·(b × c)|, 1 + a·b + b·c + c·a) (Van Oosterom & Strackee 1983),
/// computed in f64. 0 for zero or non-finite vertices; never NaN.
pub fn solid_angle(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    match (unit(a), unit(b), unit(c)) {
        (Some(a), Some(b), Some(c)) => solid_angle_f64(a, b, c) as f32,
        _ => 0.0,
    }
}

/// ∫_{ABC} exp(λ (ω·axis − 1)) dω over the spherical triangle with vertex directions a, b, c
/// (normalised here; either winding), by the signed decomposition around the axis, the closed
/// radial part (1 − e^{−λ (1 − cos θ_e)}) / λ and the 1-D azimuthal integral with
/// [`DEFAULT_SCHEME`] (Xu et al. 2014, §5). Accuracy (tests): ≤ 1 % relative wherever the
/// triangle holds ≥ 1 % of the lobe's integral 2π (1 − e^{−2λ}) / λ. λ = 0 gives the solid
/// angle; the result is never NaN, never negative and never above the solid angle.
pub fn integrate_sg(axis: Vec3, sharpness: f32, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    integrate_sg_scheme(axis, sharpness, a, b, c, DEFAULT_SCHEME)
}

/// [`integrate_sg`] with the azimuthal integral by Gauss-Legendre quadrature of order
/// [`GL_DEFAULT_ORDER`] on adaptively split pieces.
pub fn integrate_sg_gauss_legendre(axis: Vec3, sharpness: f32, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    integrate_sg_scheme(
        axis,
        sharpness,
        a,
        b,
        c,
        Scheme::GaussLegendre {
            order: GL_DEFAULT_ORDER,
        },
    )
}

/// [`integrate_sg`] with the paper's piecewise-linear azimuthal integral (knot step
/// [`PL_DEFAULT_STEP`]).
pub fn integrate_sg_piecewise_linear(axis: Vec3, sharpness: f32, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    integrate_sg_scheme(
        axis,
        sharpness,
        a,
        b,
        c,
        Scheme::PiecewiseLinear {
            step: PL_DEFAULT_STEP,
        },
    )
}

/// [`integrate_sg`] with an explicit [`Scheme`] (for measurements).
pub fn integrate_sg_scheme(
    axis: Vec3,
    sharpness: f32,
    a: Vec3,
    b: Vec3,
    c: Vec3,
    scheme: Scheme,
) -> f32 {
    let (Some(a), Some(b), Some(c)) = (unit(a), unit(b), unit(c)) else {
        return 0.0;
    };
    let lam = if sharpness > 0.0 {
        f64::from(sharpness.min(f32::MAX))
    } else {
        0.0
    };
    let Some(p) = unit(axis) else {
        return if lam == 0.0 {
            solid_angle_f64(a, b, c) as f32
        } else {
            0.0
        };
    };
    integrate_sg_f64(p, lam, a, b, c, scheme) as f32
}

/// f64 core of [`integrate_sg_scheme`]: unit p, a, b, c; λ ≥ 0 finite.
pub fn integrate_sg_f64(p: DVec3, lam: f64, a: DVec3, b: DVec3, c: DVec3, scheme: Scheme) -> f64 {
    let omega = solid_angle_f64(a, b, c);
    if !(omega > 0.0) {
        return 0.0;
    }
    if lam == 0.0 {
        return omega;
    }
    // Positive orientation: det(a, b, c) > 0.
    let (b, c) = if a.dot(b.cross(c)) < 0.0 {
        (c, b)
    } else {
        (b, c)
    };
    let mut sum = 0.0;
    let mut wind = 0.0;
    // Smallest x = 1 − cos θ over the triangle (vertices and edge feet), for the clamp.
    let mut xmin = [a, b, c]
        .iter()
        .map(|v| 0.5 * (*v - p).length_squared())
        .fold(f64::INFINITY, f64::min);
    for (x, y) in [(a, b), (b, c), (c, a)] {
        let e = edge_integral(p, lam, x, y, scheme);
        sum += e.integral;
        wind += e.dpsi;
        xmin = xmin.min(e.xmin);
    }
    let lobe = lobe_integral_f64(lam);
    // W / 2π: +1 with P inside, −1 with −P inside, fractions on the boundary.
    let w = wind / TAU;
    let frac = if w < -0.999_999 {
        1.0
    } else if w > -1e-6 {
        0.0
    } else {
        -w
    };
    if w > 0.25 {
        // P inside (W = 2π) or on an edge (W = π; that edge was skipped if det = 0 exactly).
        xmin = 0.0;
    }
    let result = sum + frac * lobe;
    let upper = omega * (-lam * xmin).exp();
    let lower = omega * (-2.0 * lam).exp();
    if result.is_nan() {
        return lower;
    }
    result.clamp(lower, upper)
}

struct EdgeResult {
    /// Signed integral over the edge triangle PXY.
    integral: f64,
    /// Signed azimuth span of the edge seen from P.
    dpsi: f64,
    /// Smallest x = 1 − cos θ along the edge's arc (∞ when not computed).
    xmin: f64,
}

const SKIP: EdgeResult = EdgeResult {
    integral: 0.0,
    dpsi: 0.0,
    xmin: f64::INFINITY,
};

/// Geometry of one edge's great circle seen from P.
#[derive(Clone, Copy)]
struct EdgeFrame {
    /// sin θ0 ≥ 0: distance of P from the edge's great circle.
    s0: f64,
    /// cos θ0 ≥ 0.
    k: f64,
    /// x0 = 1 − cos θ0, the smallest x on the great circle (at ψ = 0).
    x0: f64,
    lam: f64,
}

impl EdgeFrame {
    /// x(ψ) = 1 − cos θ_e(ψ) for folded ψ ∈ [0, π], without cancellation:
    /// cos θ_e = k cos ψ / √D, D = cos²ψ + s0² sin²ψ, and for cos θ_e ≥ 0
    /// x = sin²θ_e / (1 + cos θ_e) = s0² / (D (1 + cos θ_e)).
    #[inline]
    fn x_of(&self, psi: f64) -> f64 {
        let (s, c) = psi.sin_cos();
        let d = c * c + self.s0 * self.s0 * s * s;
        let sd = d.sqrt();
        if !(sd > 0.0) {
            return 1.0;
        }
        let ct = self.k * c / sd;
        if ct >= 0.0 {
            self.s0 * self.s0 / (d * (1.0 + ct))
        } else {
            1.0 - ct
        }
    }

    /// Antiderivative of x(ψ): X(ψ) = ψ − asin(cos θ0 sin ψ) (from ∫ cos θ_e dψ =
    /// asin(cos θ0 sin ψ)), as atan2(sin(ψ − α), cos(ψ − α)) with α = asin(k sin ψ),
    /// sin(ψ − α) = sin ψ · s0² / (cos α + k cos ψ) for cos ψ ≥ 0: no cancellation for small
    /// θ0 and ψ. ψ ∈ [0, π].
    #[inline]
    fn big_x(&self, psi: f64) -> f64 {
        let (s, c) = psi.sin_cos();
        let sd = (c * c + self.s0 * self.s0 * s * s).sqrt();
        let diff = if c >= 0.0 {
            let den = sd + self.k * c;
            if den > 0.0 {
                self.s0 * self.s0 / den
            } else {
                0.0
            }
        } else {
            sd - self.k * c
        };
        (s * diff).atan2(c * sd + self.k * s * s)
    }

    /// Inverse of x(ψ) on [0, π]: ψ = atan2(√((x − x0)(2 − x − x0)), s0 (1 − x)).
    #[inline]
    fn psi_of(&self, x: f64) -> f64 {
        let a = ((x - self.x0).max(0.0) * (2.0 - x - self.x0).max(0.0)).sqrt();
        a.atan2(self.s0 * (1.0 - x))
    }

    /// Radial part h(x) = ∫_{1−x}^1 e^{λ (t − 1)} dt = −expm1(−λ x) / λ.
    #[inline]
    fn h(&self, x: f64) -> f64 {
        -(-self.lam * x).exp_m1() / self.lam
    }
}

/// The signed integral over the edge triangle P X Y and its signed azimuth span.
fn edge_integral(p: DVec3, lam: f64, x: DVec3, y: DVec3, scheme: Scheme) -> EdgeResult {
    let cx = p.cross(x);
    let cy = p.cross(y);
    if cx.length_squared() < COINCIDENT * COINCIDENT
        || cy.length_squared() < COINCIDENT * COINCIDENT
    {
        // X or Y at ±P: PXY has zero area (X = P) or lies along one meridian (X = −P).
        return SKIP;
    }
    let n = x.cross(y);
    let nlen = n.length();
    // det(P, X, Y) = P·(X × Y); the azimuth span from the projections onto the tangent plane
    // at P: sin-part det, cos-part (P × X)·(P × Y).
    let det = p.dot(n);
    if !(nlen > 0.0) || det == 0.0 {
        // Degenerate edge or P on the edge's great circle: PXY has zero area.
        return SKIP;
    }
    let dpsi = det.atan2(cx.dot(cy));
    // Unit normal of the great circle on P's side; s0 = sin θ0 = P·m.
    let m = n * (det.signum() / nlen);
    let s0 = p.dot(m).clamp(0.0, 1.0);
    // Tangent direction from P towards the foot F: the projection of −m, of length cos θ0.
    let q = p * s0 - m;
    let k = q.length();
    let u = if k > 1e-300 {
        q / k
    } else {
        // P is a pole of the great circle: θ_e = π/2 at every azimuth, any reference works.
        let t = if p.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        (t - p * p.dot(t)).normalize()
    };
    let v = p.cross(u);
    let psi_x = x.dot(v).atan2(x.dot(u));
    let psi_y = psi_x + dpsi;
    let frame = EdgeFrame {
        s0,
        k,
        x0: s0 * s0 / (1.0 + k),
        lam,
    };
    let (lo, hi) = if psi_x <= psi_y {
        (psi_x, psi_y)
    } else {
        (psi_y, psi_x)
    };
    // x(ψ) is even and 2π-periodic, increasing on [0, π]: split at the multiple of π inside.
    let j = (lo / PI).ceil();
    let mid = j * PI;
    let mut total = 0.0;
    let mut xmin = f64::INFINITY;
    let mut piece = |a: f64, b: f64| {
        let (fa, fb) = (fold(a), fold(b));
        let (fa, fb) = if fa <= fb { (fa, fb) } else { (fb, fa) };
        if fb > fa {
            if fa == 0.0 {
                // The foot lies on the arc (the vertices' x are taken by the caller).
                xmin = frame.x0;
            }
            total += match scheme {
                Scheme::PiecewiseLinear { step } => {
                    pl_monotone(&frame, fa, fb, frame.x_of(fa), frame.x_of(fb), step)
                }
                Scheme::GaussLegendre { order } => gl_monotone(&frame, fa, fb, order),
            };
        }
    };
    if mid > lo && mid < hi {
        piece(lo, mid);
        piece(mid, hi);
    } else {
        piece(lo, hi);
    }
    EdgeResult {
        integral: dpsi.signum() * total,
        dpsi,
        xmin,
    }
}

/// Distance of ψ from the nearest multiple of 2π, in [0, π].
#[inline]
fn fold(t: f64) -> f64 {
    (t - TAU * (t / TAU).round()).abs()
}

/// Piece boundaries of the Gauss-Legendre scheme, as offsets in y = λ x above a half-edge's
/// smallest y: e^{−y} varies by at most e^{2.5} on the first piece; later pieces, weighted by
/// e^{−d}, may vary more. Past the last offset the e^{−y} part is below e^{−40} of the first
/// piece's and the rest is closed-form.
const GL_Y_OFFSETS: [f64; 5] = [2.5, 6.0, 12.0, 22.0, 40.0];

/// Gauss-Legendre nodes (non-negative half) and weights on [−1, 1].
fn gl_rule(order: usize) -> (&'static [f64], &'static [f64]) {
    match order {
        0..=2 => (&[0.577_350_269_189_625_8], &[1.0]),
        3 => (
            &[0.0, 0.774_596_669_241_483_4],
            &[0.888_888_888_888_888_8, 0.555_555_555_555_555_7],
        ),
        4 => (
            &[0.339_981_043_584_856_26, 0.861_136_311_594_052_6],
            &[0.652_145_154_862_546_4, 0.347_854_845_137_453_57],
        ),
        5 => (
            &[0.0, 0.538_469_310_105_683_1, 0.906_179_845_938_664],
            &[
                0.568_888_888_888_888_7,
                0.478_628_670_499_366_3,
                0.236_926_885_056_189_28,
            ],
        ),
        6 | 7 => (
            &[
                0.238_619_186_083_196_9,
                0.661_209_386_466_264_5,
                0.932_469_514_203_151_9,
            ],
            &[
                0.467_913_934_572_691_04,
                0.360_761_573_048_138_7,
                0.171_324_492_379_170_27,
            ],
        ),
        _ => (
            &[
                0.183_434_642_495_649_78,
                0.525_532_409_916_329,
                0.796_666_477_413_626_7,
                0.960_289_856_497_536_2,
            ],
            &[
                0.362_683_783_378_361_66,
                0.313_706_645_877_886_9,
                0.222_381_034_453_374_43,
                0.101_228_536_290_377_06,
            ],
        ),
    }
}

/// Integrand of the Gauss-Legendre scheme. With σ the edge's arc length from the foot F
/// (tan σ = sin θ0 tan ψ) and t = tan(σ/2) on the near half (σ ≤ π/2, t ∈ [0, 1]) or
/// t = cot(σ/2) on the far half (σ ≥ π/2): x = x0 + 2k t²/(1 + t²) (near) or
/// 2 − x = x0 + 2k t²/(1 + t²) (far), and dψ = 2 s0 (1 + t²) / (s0² (1 − t²)² + 4t²) dt, all
/// rational in t (no trigonometry per node). The Jacobian's poles (tan σ = ±i s0) sit where
/// x = 0 (near) or x = 2 (far); the integrand is (h(x) − h_c) dψ/dt with h_c = h(0) = 0 or
/// h(2), which cancels them, so it is analytic near the real axis for every θ0.
#[inline]
fn gl_integrand(f: &EdgeFrame, t: f64, far: bool) -> f64 {
    let t2 = t * t;
    let q = 1.0 + t2;
    let w = 1.0 - t2;
    let jac = 2.0 * f.s0 * q / (f.s0 * f.s0 * w * w + 4.0 * t2);
    let r = f.x0 + 2.0 * f.k * t2 / q;
    if far {
        // h(x) − h(2) = e^{−λx} expm1(−λz) / λ with z = 2 − x = r.
        (-f.lam * (2.0 - r)).exp() * (-f.lam * r).exp_m1() / f.lam * jac
    } else {
        f.h(r) * jac
    }
}

/// One Gauss-Legendre piece of [`gl_integrand`] over t ∈ [a, b].
#[inline]
fn gl_piece(f: &EdgeFrame, a: f64, b: f64, far: bool, nodes: &[f64], weights: &[f64]) -> f64 {
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    let mut s = 0.0;
    for (&t, &w) in nodes.iter().zip(weights) {
        if t == 0.0 {
            s += w * gl_integrand(f, mid, far);
        } else {
            s += w * (gl_integrand(f, mid - half * t, far) + gl_integrand(f, mid + half * t, far));
        }
    }
    s * half
}

/// ∫ of [`gl_integrand`] over one half, t between `t_start` (the end with the smallest x)
/// and `t_end`, split where y = λ x passes the offsets [`GL_Y_OFFSETS`] above its value at
/// `t_start`. Past the last offset the e^{−y} part is below e^{−40} of the piece's and the
/// rest is closed-form: h ≈ 1/λ with ∫ dψ = Δψ (near half), h − h(2) ≈ 0 (far half).
fn gl_side(f: &EdgeFrame, t_start: f64, t_end: f64, far: bool, order: usize) -> f64 {
    let (nodes, weights) = gl_rule(order);
    // r = x (near) or 2 − x (far) at t, and t at r.
    let r_at = |t: f64| f.x0 + 2.0 * f.k * t * t / (1.0 + t * t);
    let t_at = |r: f64| {
        let u = ((r - f.x0) / (2.0 * f.k)).clamp(0.0, 0.5);
        (u / (1.0 - u)).sqrt()
    };
    let x_at = |t: f64| if far { 2.0 - r_at(t) } else { r_at(t) };
    let y_start = f.lam * x_at(t_start);
    let y_end = f.lam * x_at(t_end);
    let (lo, hi) = if t_start <= t_end {
        (t_start, t_end)
    } else {
        (t_end, t_start)
    };
    // ψ grows with x; t does on the near half, cot(σ/2) falls on the far half.
    let dir = if far { -1.0 } else { 1.0 };
    let mut total = 0.0;
    let mut t = t_start;
    for &d in &GL_Y_OFFSETS {
        let y = y_start + d;
        if y >= y_end || !(f.k > 0.0) {
            return total + dir * gl_piece(f, t, t_end, far, nodes, weights);
        }
        let x = y / f.lam;
        let t_next = t_at(if far { 2.0 - x } else { x }).clamp(lo, hi);
        total += dir * gl_piece(f, t, t_next, far, nodes, weights);
        t = t_next;
    }
    if !far {
        // ψ = atan2(sin σ, s0 cos σ) = atan2(2t, s0 (1 − t²)).
        let psi = |t: f64| (2.0 * t).atan2(f.s0 * (1.0 - t * t));
        total += (psi(t_end) - psi(t)) / f.lam;
    }
    total
}

/// ∫ h(x(ψ)) dψ over [ψa, ψb] ⊂ [0, π] by Gauss-Legendre in t = tan(σ/2) or cot(σ/2) (see
/// [`gl_integrand`]), split at ψ = σ = π/2 (x = 1) into the near and the far half; the far
/// half adds h(2) Δψ.
fn gl_monotone(f: &EdgeFrame, pa: f64, pb: f64, order: usize) -> f64 {
    let half = std::f64::consts::FRAC_PI_2;
    // tan(σ/2) for cos ψ ≥ 0 and cot(σ/2) for cos ψ ≤ 0, from (sin σ, cos σ) ∝
    // (s0 sin ψ, cos ψ): t = s0 sin ψ / (R + cos ψ), cot = s0 sin ψ / (R − cos ψ).
    let t_of = |p: f64| {
        let (sp, cp) = p.sin_cos();
        let a = f.s0 * sp;
        let r = (a * a + cp * cp).sqrt();
        let den = r + cp.abs();
        if den > 0.0 { (a / den).min(1.0) } else { 1.0 }
    };
    let mut total = 0.0;
    if pa < half {
        let tb = if pb < half { t_of(pb) } else { 1.0 };
        total += gl_side(f, t_of(pa), tb, false, order);
    }
    if pb > half {
        let pf = pa.max(half);
        total += f.h(2.0) * (pb - pf);
        let ta = if pa > half { t_of(pa) } else { 1.0 };
        total += gl_side(f, ta, t_of(pb), true, order);
    }
    total
}

/// e^{−y} and h = (1 − e^{−y}) / λ, each without cancellation.
#[inline]
fn exp_and_h(f: &EdgeFrame, x: f64) -> (f64, f64) {
    let y = f.lam * x;
    if y < 0.5 {
        let em = (-y).exp_m1();
        (1.0 + em, -em / f.lam)
    } else {
        let e = (-y).exp();
        (e, (1.0 - e) / f.lam)
    }
}

/// ∫ h(x(ψ)) dψ over [ψa, ψb] ⊂ [0, π] (x increasing) with h interpolated linearly in x
/// between knots; each piece exactly: ∫ (h_i + s_i (x − x_i)) dψ = h_i Δψ + s_i (ΔX − x_i Δψ)
/// with X(ψ) = ψ − asin(cos θ0 sin ψ) and the slope s_i = e^{−y_i} (1 − e^{−Δy}) / Δy.
/// Knots: Δy = step · (√min(y, 1) + step) · e^{d/2}, d = y − y_start (the chord error
/// Δy² e^{−y} / 8 relative to the edge's largest e^{−y}), and one last piece beyond d = 30.
fn pl_monotone(f: &EdgeFrame, pa: f64, pb: f64, xa: f64, xb: f64, step: f64) -> f64 {
    let y_start = f.lam * xa;
    let y_end = f.lam * xb;
    let (mut e_i, mut h_i) = exp_and_h(f, xa);
    let mut x_i = xa;
    let mut psi_i = pa;
    let mut bx_i = f.big_x(pa);
    let mut total = 0.0;
    let mut y = y_start;
    for _ in 0..4096 {
        let d = y - y_start;
        let mut y_next = if d > 30.0 {
            y_end
        } else {
            y + step * (y.min(1.0).sqrt() + step) * (0.5 * d).exp()
        };
        let last = y_next >= y_end;
        if last {
            y_next = y_end;
        }
        let (x_n, psi_n) = if last {
            (xb, pb)
        } else {
            let x_n = y_next / f.lam;
            (x_n, f.psi_of(x_n).clamp(psi_i, pb))
        };
        let bx_n = f.big_x(psi_n);
        let (e_n, h_n) = exp_and_h(f, x_n);
        let dpsi = psi_n - psi_i;
        let dy = f.lam * (x_n - x_i);
        let slope = if dy > 1e-12 {
            e_i * (-(-dy).exp_m1()) / dy
        } else {
            e_i
        };
        total += h_i * dpsi + slope * (bx_n - bx_i - x_i * dpsi);
        if last {
            return total;
        }
        (e_i, h_i, x_i, psi_i, bx_i, y) = (e_n, h_n, x_n, psi_n, bx_n, y_next);
    }
    total
}

#[cfg(test)]
#[path = "quadrature_tests.rs"]
pub(crate) mod quadrature;

#[cfg(test)]
#[path = "spherical_triangle_tests.rs"]
mod tests;
