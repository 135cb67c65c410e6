//! f64 reference quadratures for the SG tests: adaptive Gauss-Kronrod (G7-K15) in 1-D, a nested
//! version over the sphere, the exact azimuthal reference for an SG over a spherical triangle
//! (parametrised along each edge, independent of the production formulas) and a brute-force
//! 2-D quadrature over the triangle.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_8,
];
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// One G7-K15 panel: (Kronrod estimate, |Kronrod − Gauss|).
fn gk15(f: &mut impl FnMut(f64) -> f64, a: f64, b: f64) -> (f64, f64) {
    let c = 0.5 * (a + b);
    let h = 0.5 * (b - a);
    let fc = f(c);
    let mut rk = fc * WGK[7];
    let mut rg = fc * WG[3];
    for j in 0..7 {
        let x = h * XGK[j];
        let s = f(c - x) + f(c + x);
        rk += WGK[j] * s;
        if j % 2 == 1 {
            rg += WG[j / 2] * s;
        }
    }
    (rk * h, ((rk - rg) * h).abs())
}

/// Adaptive Gauss-Kronrod: ∫_a^b f, always splitting the panel with the largest error estimate
/// (a max-heap) until the summed estimate is below max(abs_tol, rel_tol |I|).
pub fn integrate(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, rel_tol: f64, abs_tol: f64) -> f64 {
    use std::cmp::Ordering;
    use std::collections::BinaryHeap;
    struct Panel(f64, f64, f64, f64);
    impl PartialEq for Panel {
        fn eq(&self, o: &Self) -> bool {
            self.3 == o.3
        }
    }
    impl Eq for Panel {}
    impl PartialOrd for Panel {
        fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Panel {
        fn cmp(&self, o: &Self) -> Ordering {
            self.3.total_cmp(&o.3)
        }
    }
    if a == b {
        return 0.0;
    }
    let (v, e) = gk15(&mut f, a, b);
    let (mut total, mut err) = (v, e);
    let mut heap = BinaryHeap::new();
    heap.push(Panel(a, b, v, e));
    for _ in 0..5_000 {
        if err <= abs_tol.max(rel_tol * total.abs()) {
            break;
        }
        let Some(Panel(pa, pb, pv, pe)) = heap.pop() else {
            break;
        };
        let m = 0.5 * (pa + pb);
        let (v1, e1) = gk15(&mut f, pa, m);
        let (v2, e2) = gk15(&mut f, m, pb);
        total += v1 + v2 - pv;
        err += e1 + e2 - pe;
        heap.push(Panel(pa, m, v1, e1));
        heap.push(Panel(m, pb, v2, e2));
    }
    // Re-sum to shed the running-sum rounding.
    heap.iter().map(|p| p.2).sum()
}

/// Orthonormal (t, b) around unit n.
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let t = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let t = (t - n * n.dot(t)).normalize();
    (t, n.cross(t))
}

/// ∫_{S²} f(ω) dω in polar coordinates around the unit `pole` (where f should peak): the
/// azimuth by adaptive GK (outer), x = 1 − cos θ by adaptive GK (inner) on panels split at
/// x = 10^−k (k = 0..12) so lobes as sharp as λ = 1e8 are resolved.
pub fn sphere_integral(f: impl Fn(DVec3) -> f64, pole: DVec3, rel_tol: f64) -> f64 {
    let (t, b) = basis(pole);
    let mut cuts = vec![0.0];
    cuts.extend((0..=12).rev().map(|k| 10f64.powi(-k)));
    cuts.push(2.0);
    integrate(
        |phi| {
            let (s, c) = phi.sin_cos();
            let d = t * c + b * s;
            let g = |x: f64| {
                let st = (x * (2.0 - x)).max(0.0).sqrt();
                f(pole * (1.0 - x) + d * st)
            };
            cuts.windows(2)
                .map(|w| integrate(g, w[0], w[1], rel_tol * 0.1, 1e-300))
                .sum::<f64>()
        },
        0.0,
        TAU,
        rel_tol,
        1e-300,
    )
}

/// Radial part h(x) = (1 − e^{−λx})/λ (x at λ = 0).
pub fn radial(lam: f64, x: f64) -> f64 {
    if lam > 0.0 {
        -(-lam * x).exp_m1() / lam
    } else {
        x
    }
}

/// Reference ∫_{ABC} exp(λ(ω·p − 1)) dω: Σ over edges of ∫_0^1 h(x(t)) φ'(t) dt with the edge
/// parametrised by slerp, φ' the azimuthal rate around p (signed), and the lobe integral added
/// when −p is strictly inside ABC. Independent of the production formulas.
pub fn reference_triangle(p: DVec3, lam: f64, a: DVec3, b: DVec3, c: DVec3, rel_tol: f64) -> f64 {
    let mut sum = 0.0;
    let o = a.dot(b.cross(c)).signum();
    for (x, y) in [(a, b), (b, c), (c, a)] {
        let om = x.dot(y).clamp(-1.0, 1.0).acos();
        let so = om.sin();
        if !(so > 0.0) {
            continue;
        }
        let g = |t: f64| {
            let q = (x * ((1.0 - t) * om).sin() + y * (t * om).sin()) / so;
            let dq = (y * (t * om).cos() - x * ((1.0 - t) * om).cos()) * (om / so);
            let cr = p.cross(q);
            let r2 = cr.length_squared();
            if r2 == 0.0 {
                return 0.0;
            }
            let rate = p.dot(q.cross(dq)) / r2;
            radial(lam, 0.5 * (q - p).length_squared()) * rate
        };
        // Split at the point of the edge closest to p (the sharp spot).
        sum += integrate(g, 0.0, 0.5, rel_tol, 1e-300) + integrate(g, 0.5, 1.0, rel_tol, 1e-300);
    }
    let mp = -p;
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|(x, y)| x.cross(*y).dot(mp) * o > 0.0);
    let lobe = if lam > 0.0 {
        -TAU * (-2.0 * lam).exp_m1() / lam
    } else {
        4.0 * PI
    };
    o * sum + if inside { lobe } else { 0.0 }
}

/// Brute-force 2-D reference for an SG: [`brute_force_triangle_fn`] of exp(λ (ω·p − 1)).
pub fn brute_force_triangle(p: DVec3, lam: f64, a: DVec3, b: DVec3, c: DVec3, n: usize) -> f64 {
    brute_force_triangle_fn(|w| (lam * (w.dot(p) - 1.0)).exp(), a, b, c, n)
}

/// Brute-force 2-D reference for ∫ f(ω) dω over the spherical triangle (a, b, c):
/// ω = normalize(a + u (b − a) + v (c − a)) over the unit simplex,
/// dω = |det(a,b,c)| / |q|³ du dv, with an n×n grid of panels (Duffy-collapsed squares) each
/// with an 8×8 Gauss-Legendre rule.
pub fn brute_force_triangle_fn(
    f: impl Fn(DVec3) -> f64,
    a: DVec3,
    b: DVec3,
    c: DVec3,
    n: usize,
) -> f64 {
    const X8: [f64; 8] = [
        -0.960_289_856_497_536_2,
        -0.796_666_477_413_626_7,
        -0.525_532_409_916_329,
        -0.183_434_642_495_649_78,
        0.183_434_642_495_649_78,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_2,
    ];
    const W8: [f64; 8] = [
        0.101_228_536_290_377_06,
        0.222_381_034_453_374_43,
        0.313_706_645_877_886_9,
        0.362_683_783_378_361_66,
        0.362_683_783_378_361_66,
        0.313_706_645_877_886_9,
        0.222_381_034_453_374_43,
        0.101_228_536_290_377_06,
    ];
    let det = a.dot(b.cross(c)).abs();
    let h = 1.0 / n as f64;
    let mut sum = 0.0;
    // Duffy: u = s (1 − t), v = s t, du dv = s ds dt, (s, t) ∈ [0,1]².
    for i in 0..n {
        for j in 0..n {
            for (xs, ws) in X8.iter().zip(W8) {
                let s = h * (i as f64 + 0.5 + 0.5 * xs);
                for (xt, wt) in X8.iter().zip(W8) {
                    let t = h * (j as f64 + 0.5 + 0.5 * xt);
                    let q = a + (b - a) * (s * (1.0 - t)) + (c - a) * (s * t);
                    let l = q.length();
                    let w = q / l;
                    sum += ws * wt * 0.25 * h * h * s * det / (l * l * l) * f(w);
                }
            }
        }
    }
    sum
}
