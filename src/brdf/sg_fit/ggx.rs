//! Multi-lobe SG fit of the GGX NDF and its precomputed table over α.
//!
//! With x = cos θh and s = 1 − x, the GGX NDF is
//! D(h) = 1/(π α²) · d(s), d(s) = 1 / (1 + (1/α² − 1) s (2 − s))²,
//! and K SG lobes around n are D ≈ 1/(π α²) Σ_k m_k exp(−(c_k/α²) s), i.e. sharpness
//! λ_k = c_k/α² and amplitude μ_k = m_k/(π α²). For small α, d depends on s only through
//! s/α², so (c_k, m_k) tend to constants as α → 0: the table stores them on a grid of ln α
//! (16 columns per decade) and c_k, m_k are interpolated linearly in ln α (clamped at the
//! ends; linear rather than logarithmic in c because the lobes collapse to c → 0 as α → 1).
//!
//! Fit (offline, [`fit_table`]): for each α and K, minimise the cosine-weighted L2 error over
//! the hemisphere of h, L = ∫₀¹ (d(s) − Σ m_k e^{−λ_k s})² (1 − s) ds (∝ ∫ (D − D_SG)² cos θh dωh),
//! subject to m_k ≥ 0 and to energy preservation, ∫₀¹ Σ m_k e^{−λ_k s} (1 − s) ds =
//! ∫₀¹ d(s) (1 − s) ds (i.e. ∫ D_SG cos θh dωh = ∫ D cos θh dωh = 1 over the hemisphere of h;
//! without it the least-squares lobes miss the energy of GGX's long tail: −3.3 % with K = 3),
//! by variable projection: for given λ the amplitudes are the constrained non-negative
//! least-squares solution (exact, by enumerating the active sets), and Nelder–Mead minimises
//! over ln c_k,
//! from several geometric starts and from the previous α's solution (continuation from small α
//! upwards, which keeps the table continuous).

use super::{MAX_LOBES, NdfLobe, quadrature::gauss_legendre};
use std::f32::consts::PI;

use super::ggx_table::GGX_TABLE;
pub use super::ggx_table::{ALPHA_COUNT, ALPHA_MAX, ALPHA_MIN};

/// One table entry: normalised sharpnesses c_k = λ_k α² (descending), normalised amplitudes
/// m_k = μ_k π α², and the relative L2 error of the NDF fit, sqrt(L / ∫ d² (1 − s) ds).
/// Unused lobes (k ≥ K) have c = m = 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GgxEntry {
    pub c: [f64; MAX_LOBES],
    pub m: [f64; MAX_LOBES],
    pub ndf_error: f64,
}

/// α of table column `j` (geometric from [`ALPHA_MIN`] to [`ALPHA_MAX`]).
pub fn table_alpha(j: usize) -> f64 {
    grid_alpha(j, ALPHA_MIN, ALPHA_MAX, ALPHA_COUNT)
}

/// The α grid [`fit_table`] fits: (min, max, count), geometric, 16 columns per decade. (The
/// committed table's own constants [`ALPHA_MIN`], [`ALPHA_MAX`], [`ALPHA_COUNT`] are checked
/// against it by the tests.)
pub const GRID: (f64, f64, usize) = (1e-3, 1.0, 49);

fn grid_alpha(j: usize, lo: f64, hi: f64, count: usize) -> f64 {
    let t = j as f64 / (count - 1) as f64;
    (lo.ln() + t * (hi.ln() - lo.ln())).exp()
}

/// The normalised fit (c_k, m_k) for `k` lobes at `alpha`, interpolated from the table:
/// c_k and m_k linearly in ln α, α clamped to [`ALPHA_MIN`], [`ALPHA_MAX`].
pub fn ggx_normalised(alpha: f32, k: usize) -> GgxEntry {
    let k = k.clamp(1, MAX_LOBES);
    let row = &GGX_TABLE[k - 1];
    let a = if alpha.is_finite() {
        (alpha as f64).clamp(ALPHA_MIN, ALPHA_MAX)
    } else {
        ALPHA_MAX
    };
    let t =
        (a.ln() - ALPHA_MIN.ln()) / (ALPHA_MAX.ln() - ALPHA_MIN.ln()) * (ALPHA_COUNT - 1) as f64;
    let j = (t.floor() as usize).min(ALPHA_COUNT - 2);
    let f = (t - j as f64).clamp(0.0, 1.0);
    let (e0, e1) = (&row[j], &row[j + 1]);
    let mut out = GgxEntry {
        c: [0.0; MAX_LOBES],
        m: [0.0; MAX_LOBES],
        ndf_error: e0.ndf_error + f * (e1.ndf_error - e0.ndf_error),
    };
    for i in 0..k {
        out.c[i] = e0.c[i] * (1.0 - f) + e1.c[i] * f;
        out.m[i] = e0.m[i] * (1.0 - f) + e1.m[i] * f;
    }
    out
}

/// The `k` GGX NDF lobes (λ_k = c_k/α², μ_k = m_k/(π α²)) at roughness `alpha`, from the table.
pub fn ggx_ndf_lobes(alpha: f32, k: usize) -> [NdfLobe; MAX_LOBES] {
    let e = ggx_normalised(alpha, k);
    let a2 = alpha * alpha;
    let mut out = [NdfLobe {
        sharpness: 0.0,
        amplitude: 0.0,
    }; MAX_LOBES];
    for (i, o) in out.iter_mut().enumerate().take(k.clamp(1, MAX_LOBES)) {
        *o = NdfLobe {
            sharpness: (e.c[i] / a2 as f64) as f32,
            amplitude: (e.m[i] / (PI * a2) as f64) as f32,
        };
    }
    out
}

/// Quadrature in s ∈ [0, 1] with the cosine weight (1 − s) folded in: Gauss–Legendre panels
/// (8 points) with edges geometric (ratio 1.4) from s = 1e-4 α² to 1.
pub struct SRule {
    pub s: Vec<f64>,
    pub w: Vec<f64>,
}

impl SRule {
    pub fn new(alpha: f64) -> SRule {
        let gl = gauss_legendre(8);
        let mut edges = vec![0.0];
        let mut e = 1e-4 * alpha * alpha;
        while e < 1.0 / 1.4 {
            edges.push(e);
            e *= 1.4;
        }
        edges.push(1.0);
        let (mut s, mut w) = (Vec::new(), Vec::new());
        for p in edges.windows(2) {
            let h = 0.5 * (p[1] - p[0]);
            for &(x, wx) in &gl {
                let si = p[0] + h * (x + 1.0);
                s.push(si);
                w.push(h * wx * (1.0 - si));
            }
        }
        SRule { s, w }
    }
}

/// d(s) = π α² D_GGX at cos θh = 1 − s.
pub fn ggx_normalised_ndf(alpha: f64, s: f64) -> f64 {
    let q = 1.0 + (1.0 / (alpha * alpha) - 1.0) * s * (2.0 - s);
    1.0 / (q * q)
}

/// The fitting problem for one α: quadrature, target values and their weighted energy.
pub struct Problem {
    pub alpha: f64,
    rule: SRule,
    target: Vec<f64>,
    energy: f64,
    /// ∫ d (1 − s) ds, the projected integral the lobes must reproduce.
    mass: f64,
}

impl Problem {
    pub fn new(alpha: f64) -> Problem {
        let rule = SRule::new(alpha);
        let target: Vec<f64> = rule
            .s
            .iter()
            .map(|&s| ggx_normalised_ndf(alpha, s))
            .collect();
        let energy = target.iter().zip(&rule.w).map(|(d, w)| d * d * w).sum();
        let mass = target.iter().zip(&rule.w).map(|(d, w)| d * w).sum();
        Problem {
            alpha,
            rule,
            target,
            energy,
            mass,
        }
    }

    /// Optimal energy-preserving non-negative amplitudes m for the normalised sharpnesses `c`
    /// and the relative L2 error sqrt(L / ∫ d² w).
    pub fn amplitudes(&self, c: &[f64]) -> (Vec<f64>, f64) {
        let k = c.len();
        let a2 = self.alpha * self.alpha;
        let mut gram = vec![0.0; k * k];
        let mut rhs = vec![0.0; k];
        let mut mass = vec![0.0; k];
        let mut b = vec![0.0; k];
        for ((&s, &w), &d) in self.rule.s.iter().zip(&self.rule.w).zip(&self.target) {
            for i in 0..k {
                b[i] = (-(c[i] / a2) * s).exp();
            }
            for i in 0..k {
                rhs[i] += w * d * b[i];
                mass[i] += w * b[i];
                for j in 0..=i {
                    gram[i * k + j] += w * b[i] * b[j];
                }
            }
        }
        for i in 0..k {
            for j in 0..i {
                gram[j * k + i] = gram[i * k + j];
            }
        }
        let (m, loss) = nnls_enumerate(&gram, &rhs, self.energy, &mass, self.mass);
        (m, (loss.max(0.0) / self.energy).sqrt())
    }

    /// Relative L2 error sqrt(L / ∫ d² w) of the given lobes (c_k, m_k), e.g. interpolated ones.
    pub fn error_of(&self, c: &[f64], m: &[f64]) -> f64 {
        let a2 = self.alpha * self.alpha;
        let mut l = 0.0;
        for ((&s, &w), &d) in self.rule.s.iter().zip(&self.rule.w).zip(&self.target) {
            let g: f64 = c
                .iter()
                .zip(m)
                .map(|(c, m)| m * (-(c / a2) * s).exp())
                .sum();
            l += w * (g - d) * (g - d);
        }
        (l / self.energy).sqrt()
    }

    /// Relative L2 error of the best non-negative amplitudes for ln c = `x` (clamped to
    /// [`C_RANGE`]).
    fn objective(&self, x: &[f64]) -> f64 {
        let c: Vec<f64> = x.iter().map(|&v| c_of(v)).collect();
        self.amplitudes(&c).1
    }
}

/// Range of the normalised sharpness c = λ α² searched by the fit. The lower end 1e-4 is an
/// almost constant lobe (the fit of the flat GGX NDF at α → 1 wants λ → 0); the bound keeps
/// the table finite and smooth there.
pub const C_RANGE: (f64, f64) = (1e-4, 1e3);

fn c_of(ln_c: f64) -> f64 {
    ln_c.exp().clamp(C_RANGE.0, C_RANGE.1)
}

/// min over m ≥ 0 with a·m = t of E − 2 m·r + mᵀ G m, by enumerating the active sets (K ≤ 4:
/// ≤ 15 systems). On a set S: m = G⁻¹(r − ν a) with ν = (a·G⁻¹r − t)/(a·G⁻¹a) (Lagrange
/// multiplier of the constraint), solved by Cholesky with a 1e-13 relative ridge for nearly
/// equal lobes. Returns (m, L) with L = +∞ if no set is feasible.
fn nnls_enumerate(gram: &[f64], rhs: &[f64], energy: f64, a: &[f64], t: f64) -> (Vec<f64>, f64) {
    let k = rhs.len();
    let mut best = (vec![0.0; k], f64::INFINITY);
    for mask in 1u32..(1 << k) {
        let idx: Vec<usize> = (0..k).filter(|i| mask & (1 << i) != 0).collect();
        let n = idx.len();
        let mut g = vec![0.0; n * n];
        let mut y = vec![0.0; n];
        let mut aa = vec![0.0; n];
        for (p, &i) in idx.iter().enumerate() {
            y[p] = rhs[i];
            aa[p] = a[i];
            for (q, &j) in idx.iter().enumerate() {
                g[p * n + q] = gram[i * k + j];
            }
        }
        let Some(l) = cholesky(&mut g, n) else {
            continue;
        };
        let gr = cholesky_apply(&l, n, &y);
        let ga = cholesky_apply(&l, n, &aa);
        let aga: f64 = aa.iter().zip(&ga).map(|(x, y)| x * y).sum();
        let agr: f64 = aa.iter().zip(&gr).map(|(x, y)| x * y).sum();
        if !(aga > 0.0) {
            continue;
        }
        let nu = (agr - t) / aga;
        let x: Vec<f64> = gr.iter().zip(&ga).map(|(p, q)| p - nu * q).collect();
        if x.iter().any(|&v| !(v >= 0.0)) {
            continue;
        }
        let mut quad = 0.0;
        for p in 0..n {
            for q in 0..n {
                quad += x[p] * gram[idx[p] * k + idx[q]] * x[q];
            }
        }
        let lin: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        let loss = energy - 2.0 * lin + quad;
        if loss < best.1 {
            let mut m = vec![0.0; k];
            for (p, &i) in idx.iter().enumerate() {
                m[i] = x[p];
            }
            best = (m, loss);
        }
    }
    best
}

/// In-place Cholesky factor (lower triangle) of the n×n matrix `a` with a 1e-13 relative ridge.
fn cholesky(a: &mut [f64], n: usize) -> Option<Vec<f64>> {
    let tr: f64 = (0..n).map(|i| a[i * n + i]).sum::<f64>() / n as f64;
    for i in 0..n {
        a[i * n + i] += 1e-13 * tr;
    }
    for j in 0..n {
        let mut d = a[j * n + j];
        for p in 0..j {
            d -= a[j * n + p] * a[j * n + p];
        }
        if !(d > 0.0) {
            return None;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut v = a[i * n + j];
            for p in 0..j {
                v -= a[i * n + p] * a[j * n + p];
            }
            a[i * n + j] = v / d;
        }
    }
    Some(a.to_vec())
}

/// Solves L Lᵀ x = y for the factor from [`cholesky`].
fn cholesky_apply(l: &[f64], n: usize, y: &[f64]) -> Vec<f64> {
    let mut z = vec![0.0; n];
    for i in 0..n {
        let mut v = y[i];
        for p in 0..i {
            v -= l[i * n + p] * z[p];
        }
        z[i] = v / l[i * n + i];
    }
    for i in (0..n).rev() {
        let mut v = z[i];
        for p in i + 1..n {
            v -= l[p * n + i] * z[p];
        }
        z[i] = v / l[i * n + i];
    }
    z
}
/// Nelder–Mead minimisation of `f` from `x0` with initial step `step` (Lagarias et al. 1998
/// coefficients), until the simplex's value spread is < `tol` or `max_eval` evaluations.
pub fn nelder_mead(
    f: impl Fn(&[f64]) -> f64,
    x0: &[f64],
    step: f64,
    tol: f64,
    max_eval: usize,
) -> (Vec<f64>, f64) {
    let n = x0.len();
    let mut pts: Vec<Vec<f64>> = vec![x0.to_vec()];
    for i in 0..n {
        let mut p = x0.to_vec();
        p[i] += step;
        pts.push(p);
    }
    let mut vals: Vec<f64> = pts.iter().map(|p| f(p)).collect();
    let mut evals = n + 1;
    while evals < max_eval {
        let mut order: Vec<usize> = (0..=n).collect();
        order.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
        pts = order.iter().map(|&i| pts[i].clone()).collect();
        vals = order.iter().map(|&i| vals[i]).collect();
        if vals[n] - vals[0] < tol {
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|d| pts[..n].iter().map(|p| p[d]).sum::<f64>() / n as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            (0..n)
                .map(|d| centroid[d] + t * (pts[n][d] - centroid[d]))
                .collect()
        };
        let xr = along(-1.0);
        let fr = f(&xr);
        evals += 1;
        if fr < vals[0] {
            let xe = along(-2.0);
            let fe = f(&xe);
            evals += 1;
            if fe < fr {
                pts[n] = xe;
                vals[n] = fe;
            } else {
                pts[n] = xr;
                vals[n] = fr;
            }
        } else if fr < vals[n - 1] {
            pts[n] = xr;
            vals[n] = fr;
        } else {
            let (xc, fc) = if fr < vals[n] {
                let x = along(-0.5);
                let v = f(&x);
                (x, v)
            } else {
                let x = along(0.5);
                let v = f(&x);
                (x, v)
            };
            evals += 1;
            if fc < vals[n].min(fr) {
                pts[n] = xc;
                vals[n] = fc;
            } else {
                let (best, rest) = pts.split_at_mut(1);
                for (p, v) in rest.iter_mut().zip(vals[1..].iter_mut()) {
                    for (x, b) in p.iter_mut().zip(&best[0]) {
                        *x = b + 0.5 * (*x - b);
                    }
                    *v = f(p);
                }
                evals += n;
            }
        }
    }
    let best = (0..=n)
        .min_by(|&a, &b| vals[a].total_cmp(&vals[b]))
        .unwrap_or(0);
    (pts[best].clone(), vals[best])
}

/// Minimises the relative error for `k` lobes from the start ln c = `x0` (Nelder–Mead with two
/// restarts), returns the entry with lobes sorted by descending sharpness.
fn refine(p: &Problem, x0: &[f64]) -> GgxEntry {
    let mut x = x0.to_vec();
    let mut v = f64::INFINITY;
    for step in [0.7, 0.2, 0.05] {
        let (nx, nv) = nelder_mead(|x| p.objective(x), &x, step, 1e-12, 4000);
        if nv <= v {
            x = nx;
            v = nv;
        }
    }
    entry_from(p, &x)
}

fn entry_from(p: &Problem, x: &[f64]) -> GgxEntry {
    let c: Vec<f64> = x.iter().map(|&v| c_of(v)).collect();
    let (m, err) = p.amplitudes(&c);
    let mut lobes: Vec<(f64, f64)> = c.into_iter().zip(m).collect();
    lobes.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut e = GgxEntry {
        c: [0.0; MAX_LOBES],
        m: [0.0; MAX_LOBES],
        ndf_error: err,
    };
    for (i, (c, m)) in lobes.into_iter().enumerate() {
        e.c[i] = c;
        e.m[i] = m;
    }
    e
}

/// Fits `k` lobes at `alpha`. Without `prev`: the best of several geometric starts
/// c_j = c0 q^j. With `prev` (the fit at the neighbouring, smaller α): continuation from it,
/// replaced by a cold start only if that is better by 10 % and uses all its lobes, so that the
/// table stays a continuous function of α. Lobes whose amplitude is zero keep `prev`'s
/// sharpness (they contribute nothing; this only keeps the interpolation smooth).
pub fn fit(alpha: f64, k: usize, prev: Option<&GgxEntry>) -> GgxEntry {
    let k = k.clamp(1, MAX_LOBES);
    let p = Problem::new(alpha);
    let mut best: Option<GgxEntry> = prev.map(|e| {
        let x: Vec<f64> = e.c[..k].iter().map(|&c| c.max(C_RANGE.0).ln()).collect();
        refine(&p, &x)
    });
    let margin = if prev.is_some() { 0.9 } else { 1.0 };
    for c0 in [1.0f64, 2.0, 4.0] {
        for q in [0.08f64, 0.25, 0.5] {
            let x: Vec<f64> = (0..k).map(|j| (c0 * q.powi(j as i32)).ln()).collect();
            let e = refine(&p, &x);
            let all_used = e.m[..k].iter().all(|&m| m > 0.0);
            let better = match &best {
                None => true,
                Some(b) => e.ndf_error < margin * b.ndf_error && (prev.is_none() || all_used),
            };
            if better {
                best = Some(e);
            }
        }
    }
    let mut e = best.expect("at least one start");
    if let Some(pe) = prev {
        for i in 0..k {
            if !(e.m[i] > 0.0) {
                e.m[i] = 0.0;
                e.c[i] = pe.c[i];
            }
        }
        let mut lobes: Vec<(f64, f64)> = (0..k).map(|i| (e.c[i], e.m[i])).collect();
        lobes.sort_by(|a, b| b.0.total_cmp(&a.0));
        for (i, (c, m)) in lobes.into_iter().enumerate() {
            e.c[i] = c;
            e.m[i] = m;
        }
    }
    e
}

/// Fits the whole table: for K = 1..=4, the α grid from small to large with continuation.
/// Takes a few seconds (release build).
pub fn fit_table() -> Vec<Vec<GgxEntry>> {
    let (lo, hi, count) = GRID;
    (1..=MAX_LOBES)
        .map(|k| {
            let mut row: Vec<GgxEntry> = Vec::with_capacity(count);
            for j in 0..count {
                let e = fit(grid_alpha(j, lo, hi, count), k, row.last());
                row.push(e);
            }
            row
        })
        .collect()
}

/// Rust source of `ggx_table.rs` for the `table` fitted on [`GRID`] by [`fit_table`].
pub fn table_source(table: &[Vec<GgxEntry>]) -> String {
    let (lo, hi, count) = GRID;
    let mut s = String::new();
    s.push_str(
        "//! GGX NDF → K spherical Gaussians, fitted table (see `ggx.rs` and docs/sg-brdf-fits.md).\n\
         //!\n\
         //! GENERATED by `interreflect fit --write-ggx-table src/brdf/sg_fit/ggx_table.rs`\n\
         //! (`ggx::fit_table` + `ggx::table_source`); do not edit by hand.\n\
         //!\n\
         //! `GGX_TABLE[K − 1][j]` is the K-lobe fit at α_j = exp(ln ALPHA_MIN + j/(ALPHA_COUNT − 1)\n\
         //! · ln(ALPHA_MAX/ALPHA_MIN)): λ_k = c_k/α², μ_k = m_k/(π α²), lobes by descending c.\n\n\
         use super::ggx::GgxEntry;\n\n",
    );
    s.push_str(&format!("pub const ALPHA_MIN: f64 = {lo:e};\n"));
    s.push_str(&format!("pub const ALPHA_MAX: f64 = {hi:e};\n"));
    s.push_str(&format!("pub const ALPHA_COUNT: usize = {count};\n\n"));
    s.push_str("#[rustfmt::skip]\n");
    s.push_str(&format!(
        "pub(super) static GGX_TABLE: [[GgxEntry; ALPHA_COUNT]; {}] = [\n",
        table.len()
    ));
    let f = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.9e}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for (k, row) in table.iter().enumerate() {
        s.push_str(&format!("    // K = {}\n    [\n", k + 1));
        for (j, e) in row.iter().enumerate() {
            s.push_str(&format!(
                "        // α = {:.6}\n        GgxEntry {{ c: [{}], m: [{}], ndf_error: {:.9e} }},\n",
                grid_alpha(j, lo, hi, count),
                f(&e.c),
                f(&e.m),
                e.ndf_error
            ));
        }
        s.push_str("    ],\n");
    }
    s.push_str("];\n");
    s
}
