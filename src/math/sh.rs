//! Real spherical harmonics (SH): evaluation, projection, clamped-cosine convolution, windows
//! and rotation, for the diffuse PRT comparison method. Derivations and references: `docs/sh.md`.
//!
//! # Convention (stated once; everything in this module follows it)
//!
//! - Basis function y_l^m, band l ≥ 0, −l ≤ m ≤ l, stored at index i = l(l+1) + m
//!   ([`sh_index`]). An expansion of "order" n has the bands l = 0..n−1 and n² coefficients
//!   ([`sh_count`]); orders 1..=[`MAX_ORDER`] are accepted.
//! - Polar axis +z: θ is the angle from +z, φ the azimuth in the xy-plane from +x towards +y,
//!   d = (sin θ cos φ, sin θ sin φ, cos θ). Directions are used as given, in whatever frame the
//!   caller works in; in the scene frame (+y up) the zonal axis is therefore *not* the up axis.
//! - Orthonormal: ∫_{S²} y_i y_j dω = δ_ij.
//! - y_l^0 = K_l^0 P_l^0(cos θ), y_l^m = √2 K_l^m cos(mφ) P_l^m(cos θ) and
//!   y_l^{−m} = √2 K_l^m sin(mφ) P_l^m(cos θ) for m > 0, with
//!   K_l^m = √((2l+1)/(4π) · (l−m)!/(l+m)!) and P_l^m the associated Legendre function
//!   **without** the Condon–Shortley phase (P_m^m = (2m−1)!! sin^m θ > 0). Equivalently: the
//!   phase (−1)^m is included in P_l^m and cancelled by a factor (−1)^m in the real basis.
//!   The closed forms are those of Ramamoorthi & Hanrahan (2001), Green (2003) and `sphrs`:
//!   y_0^0 = 0.282095, (y_1^{−1}, y_1^0, y_1^1) = 0.488603 (y, z, x),
//!   y_2^{−2} = 1.092548 xy, y_2^{−1} = 1.092548 yz, y_2^0 = 0.315392 (3z² − 1),
//!   y_2^1 = 1.092548 xz, y_2^2 = 0.546274 (x² − y²).
//!   (D3DX / DirectXMath SH and Sloan's "Efficient SH evaluation" keep the phase: their
//!   coefficients are (−1)^m times ours.)
//!
//! Bands l ≤ 2 use the closed forms; bands l ≥ 3 the associated-Legendre recurrence in f64
//! (P_m^m, P_{m+1}^m, then upward in l), with sin^m θ cos(mφ), sin^m θ sin(mφ) taken as
//! Re, Im (x + iy)^m, so no trigonometry, no atan2 and no division by sin θ at the poles.
//! Results are returned in f32; sums (projection, evaluation of expansions) run in f64.
//!
//! Invalid orders (0 or above [`MAX_ORDER`]) are a caller bug: they trip a `debug_assert` and
//! are otherwise clamped into 1..=[`MAX_ORDER`]. Slices shorter than the order needs are
//! handled without panicking (missing coefficients count as 0, extra outputs are not written).

use super::gauss_legendre;
use glam::{DMat3, DVec3, Mat3, Vec3};
use std::f64::consts::PI;
use std::sync::LazyLock;

/// Largest accepted order (number of bands): l ≤ 15, 256 coefficients.
pub const MAX_ORDER: u32 = 16;

/// Number of coefficients of an order-[`MAX_ORDER`] expansion.
const MAX_COEFFS: usize = (MAX_ORDER * MAX_ORDER) as usize;

/// 1 / (2√π): y_0^0.
const Y00: f64 = 0.282_094_791_773_878_14;
/// √(3 / (4π)): band 1.
const Y1: f64 = 0.488_602_511_902_919_9;
/// √(15 / (4π)): y_2^{−2}, y_2^{−1}, y_2^1.
const Y2_XY: f64 = 1.092_548_430_592_079_2;
/// √(5 / (16π)): y_2^0 = Y2_Z · (3z² − 1).
const Y2_Z: f64 = 0.315_391_565_252_520_05;
/// √(15 / (16π)): y_2^2 = Y2_XX · (x² − y²).
const Y2_XX: f64 = 0.546_274_215_296_039_6;

/// Index of y_l^m: l(l+1) + m. Requires |m| ≤ l.
#[inline]
pub fn sh_index(l: u32, m: i32) -> usize {
    debug_assert!(
        m.unsigned_abs() <= l,
        "sh_index: |m| = {} > l = {l}",
        m.unsigned_abs()
    );
    let l = l as usize;
    (l * (l + 1)).wrapping_add_signed(m as isize)
}

/// Number of coefficients of an expansion of the given order (bands l < order): order².
#[inline]
pub fn sh_count(order: u32) -> usize {
    let n = order as usize;
    n * n
}

/// The order as a band count, checked in debug builds and clamped into 1..=[`MAX_ORDER`].
#[inline]
fn bands(order: u32) -> usize {
    debug_assert!(
        (1..=MAX_ORDER).contains(&order),
        "SH order {order} outside 1..={MAX_ORDER}"
    );
    order.clamp(1, MAX_ORDER) as usize
}

/// K_l^m for m ≥ 0, times √2 for m > 0, at index l(l+1) + m and l(l+1) − m.
/// (l−m)!/(l+m)! is a product of 2m reciprocals in f64: no factorial overflows (30! ≈ 2.7e32
/// would fit anyway) and the relative error stays at a few ulp for l < [`MAX_ORDER`].
static NORM: LazyLock<[f64; MAX_COEFFS]> = LazyLock::new(|| {
    let mut k = [0.0; MAX_COEFFS];
    for l in 0..MAX_ORDER as usize {
        for m in 0..=l {
            let mut r = (2 * l + 1) as f64 / (4.0 * PI);
            for f in (l - m + 1)..=(l + m) {
                r /= f as f64;
            }
            let v = if m == 0 { r.sqrt() } else { (2.0 * r).sqrt() };
            k[l * (l + 1) + m] = v;
            k[l * (l + 1) - m] = v;
        }
    }
    k
});

/// `d` normalised in f64, or `None` if it has no direction (zero, infinite or NaN).
#[inline]
fn unit_f64(d: DVec3) -> Option<DVec3> {
    let len = d.length();
    (len > 0.0 && len.is_finite()).then(|| d / len)
}

/// Closed forms of bands l < min(bands, 3) at unit `d`.
#[inline]
fn eval_closed_f64(bands: usize, d: DVec3, out: &mut [f64]) {
    let (x, y, z) = (d.x, d.y, d.z);
    out[0] = Y00;
    if bands > 1 {
        out[1] = Y1 * y;
        out[2] = Y1 * z;
        out[3] = Y1 * x;
    }
    if bands > 2 {
        out[4] = Y2_XY * x * y;
        out[5] = Y2_XY * y * z;
        out[6] = Y2_Z * (3.0 * z * z - 1.0);
        out[7] = Y2_XY * x * z;
        out[8] = Y2_XX * (x * x - y * y);
    }
}

/// Bands `l_begin..bands` at unit `d` by the associated-Legendre recurrence, in f64.
///
/// With P̃_l^m = P_l^m / sin^m θ (a polynomial in z = cos θ, no Condon–Shortley phase):
/// P̃_m^m = (2m−1)!!, P̃_{m+1}^m = (2m+1) z P̃_m^m,
/// P̃_l^m = ((2l−1) z P̃_{l−1}^m − (l+m−1) P̃_{l−2}^m) / (l−m); and
/// sin^m θ (cos mφ, sin mφ) = (Re, Im) (x + iy)^m.
fn eval_recurrence_f64(bands: usize, l_begin: usize, d: DVec3, out: &mut [f64]) {
    let norm = &*NORM;
    let (x, y, z) = (d.x, d.y, d.z);
    // (c, s) = (Re, Im) (x + iy)^m; pmm = (2m − 1)!!.
    let (mut c, mut s) = (1.0f64, 0.0f64);
    let mut pmm = 1.0f64;
    for m in 0..bands {
        let (mut p2, mut p1) = (0.0f64, 0.0f64);
        for l in m..bands {
            let p = if l == m {
                pmm
            } else if l == m + 1 {
                (2 * m + 1) as f64 * z * pmm
            } else {
                ((2 * l - 1) as f64 * z * p1 - (l + m - 1) as f64 * p2) / (l - m) as f64
            };
            if l >= l_begin {
                let i = l * (l + 1);
                if m == 0 {
                    out[i] = norm[i] * p;
                } else {
                    let kp = norm[i + m] * p;
                    out[i + m] = kp * c;
                    out[i - m] = kp * s;
                }
            }
            p2 = p1;
            p1 = p;
        }
        pmm *= (2 * m + 1) as f64;
        (c, s) = (x * c - y * s, x * s + y * c);
    }
}

/// All bands l < `bands` at `d` (normalised here) in f64, into `out[..bands²]`.
/// A `d` without a direction (zero, infinite, NaN) gives y_0^0 and zeros.
#[inline]
fn eval_f64(bands: usize, d: DVec3, out: &mut [f64]) {
    let out = &mut out[..bands * bands];
    let Some(d) = unit_f64(d) else {
        out.fill(0.0);
        out[0] = Y00;
        return;
    };
    eval_closed_f64(bands, d, out);
    if bands > 3 {
        eval_recurrence_f64(bands, 3, d, out);
    }
}

/// All real SH of bands l < `order` at the direction `d`, written into `out[..order²]`.
///
/// `d` should be unit length; it is normalised in f64, so f32 rounding of its length does not
/// matter. A `d` without a direction (zero, infinite or NaN components) gives y_0^0 and zeros.
/// If `out` is shorter than order² (a caller bug, flagged by a debug assertion), only its
/// length is written.
pub fn eval_sh(order: u32, d: Vec3, out: &mut [f32]) {
    let n = bands(order);
    debug_assert!(out.len() >= n * n, "eval_sh: output shorter than order²");
    let mut y = [0.0f64; MAX_COEFFS];
    eval_f64(n, d.as_dvec3(), &mut y);
    for (o, v) in out.iter_mut().zip(&y[..n * n]) {
        *o = *v as f32;
    }
}

/// Projects an RGB function onto the SH bands l < `order` from samples: coefficient
/// c_i = Σ_k w_k f(d_k) y_i(d_k) over the items (direction d_k, solid-angle weight w_k in sr,
/// value f(d_k)). Weights are whatever the quadrature or Monte Carlo estimator needs (texel
/// solid angle, 4π/N for uniform sphere samples, 1/pdf/N, ...). Accumulated in f64; returns
/// order² coefficients.
pub fn project_samples(
    order: u32,
    samples: impl IntoIterator<Item = (Vec3, f32, Vec3)>,
) -> Vec<Vec3> {
    let n = bands(order);
    let count = n * n;
    let mut acc = vec![DVec3::ZERO; count];
    let mut y = [0.0f64; MAX_COEFFS];
    for (d, w, v) in samples {
        let wv = v.as_dvec3() * f64::from(w);
        if wv == DVec3::ZERO {
            continue;
        }
        eval_f64(n, d.as_dvec3(), &mut y);
        for (a, yi) in acc.iter_mut().zip(&y[..count]) {
            *a += wv * *yi;
        }
    }
    acc.into_iter().map(DVec3::as_vec3).collect()
}

/// Exact solid angle of one texel of row `y` of a lat-long map with `height` rows spanning the
/// polar angle θ ∈ [0, π] (row 0 at θ = 0) and `width` columns spanning 2π:
/// (2π / width) · (cos θ0 − cos θ1) with θ0 = π y / height, θ1 = π (y+1) / height, evaluated as
/// 2 sin((θ0+θ1)/2) sin((θ1−θ0)/2) to keep the small polar texels accurate. Over all
/// rows × width texels the sum is 4π. Returns 0 for an empty map or `y ≥ height`.
pub fn latlong_texel_solid_angle(width: u32, height: u32, y: u32) -> f32 {
    if width == 0 || y >= height {
        return 0.0;
    }
    let h = f64::from(height);
    let t0 = PI * f64::from(y) / h;
    let t1 = PI * (f64::from(y) + 1.0) / h;
    let band = 2.0 * (0.5 * (t0 + t1)).sin() * (0.5 * (t1 - t0)).sin();
    (2.0 * PI / f64::from(width) * band) as f32
}

/// SH coefficients of a directional (delta) light arriving from the unit direction `d` (the
/// direction towards the light) with radiance times solid angle `e` (the irradiance it gives a
/// surface facing it): c_i = e · y_i(d). After [`convolve_cosine`] the expansion evaluates at a
/// normal n to ≈ e · max(n·d, 0), with the ringing of the truncated series (see [`Window`]).
pub fn project_directional(order: u32, d: Vec3, e: Vec3) -> Vec<Vec3> {
    let n = bands(order);
    let mut y = [0.0f64; MAX_COEFFS];
    eval_f64(n, d.as_dvec3(), &mut y);
    let e = e.as_dvec3();
    y[..n * n].iter().map(|&yi| (e * yi).as_vec3()).collect()
}

/// ∏_{k=1}^{h} (2k−1)/(2k) = C(2h, h) / 4^h = Γ(h + ½) / (√π Γ(h + 1)).
/// Exact product up to h = 4096, beyond it the asymptotic series of the Gamma ratio, whose
/// truncation error there is below 1e-19 relative.
fn central_binomial_ratio(h: u32) -> f64 {
    if h <= 4096 {
        (1..=h).fold(1.0, |r, k| {
            r * (2.0 * f64::from(k) - 1.0) / (2.0 * f64::from(k))
        })
    } else {
        let x = f64::from(h);
        let inv = 1.0 / x;
        let series = 1.0
            + inv
                * (-1.0 / 8.0 + inv * (1.0 / 128.0 + inv * (5.0 / 1024.0 - inv * 21.0 / 32768.0)));
        series / (PI * x).sqrt()
    }
}

/// f64 version of [`cosine_convolution_factor`].
fn cosine_factor_f64(l: u32) -> f64 {
    match l {
        0 => PI,
        1 => 2.0 * PI / 3.0,
        l if l % 2 == 1 => 0.0,
        l => {
            let h = l / 2;
            let sign = if h % 2 == 1 { 1.0 } else { -1.0 };
            let lf = f64::from(l);
            2.0 * PI * sign * central_binomial_ratio(h) / ((lf + 2.0) * (lf - 1.0))
        }
    }
}

/// Â_l, the factor that maps radiance coefficients L_lm to irradiance coefficients
/// E_lm = Â_l L_lm (convolution with the clamped cosine max(cos θ, 0); Ramamoorthi & Hanrahan
/// 2001): Â_l = √(4π/(2l+1)) times the clamped cosine's zonal coefficient. Closed form:
/// Â_0 = π, Â_1 = 2π/3, Â_l = 0 for odd l > 1, and for even l
/// Â_l = 2π (−1)^{l/2−1} / ((l+2)(l−1)) · l! / (2^l ((l/2)!)²), i.e. π, 2π/3, π/4, 0, −π/24,
/// 0, π/64, ... Valid for every l (|Â_l| decays like l^{−5/2}).
pub fn cosine_convolution_factor(l: u32) -> f32 {
    cosine_factor_f64(l) as f32
}

/// Radiance coefficients to irradiance coefficients in place: E_lm = Â_l L_lm for the bands
/// l < `order` ([`cosine_convolution_factor`]).
pub fn convolve_cosine(coeffs: &mut [Vec3], order: u32) {
    scale_bands(coeffs, order, cosine_convolution_factor);
}

/// Multiplies every coefficient of band l < `order` present in `coeffs` by `factor(l)`.
fn scale_bands(coeffs: &mut [Vec3], order: u32, factor: impl Fn(u32) -> f32) {
    let n = bands(order) as u32;
    for l in 0..n {
        let f = factor(l);
        let lo = (l * l) as usize;
        let hi = (((l + 1) * (l + 1)) as usize).min(coeffs.len());
        if lo >= hi {
            break;
        }
        for c in &mut coeffs[lo..hi] {
            *c *= f;
        }
    }
}

/// A per-band window w_l against ringing (Gibbs oscillations of the truncated series; Sloan,
/// "Stupid Spherical Harmonics (SH) Tricks", GDC 2008). `width` is typically the order.
/// Band 0 is never changed (w_0 = 1), and w_l = 0 for l ≥ `width`; a `width` that is not
/// positive (0, negative, NaN) therefore keeps band 0 only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Window {
    /// w_l = 1.
    None,
    /// w_l = (1 + cos(π l / width)) / 2 for l < width, else 0.
    Hanning {
        /// Band at which the window reaches 0.
        width: f32,
    },
    /// Lanczos sigma factors: w_l = sin(π l / width) / (π l / width) for l < width (1 at l = 0),
    /// else 0.
    Lanczos {
        /// Band at which the window reaches 0.
        width: f32,
    },
}

impl Window {
    /// The factor w_l of band `l`.
    pub fn factor(self, l: u32) -> f32 {
        let (width, hanning) = match self {
            Window::None => return 1.0,
            Window::Hanning { width } => (f64::from(width), true),
            Window::Lanczos { width } => (f64::from(width), false),
        };
        if l == 0 {
            return 1.0;
        }
        let lf = f64::from(l);
        if !(lf < width) {
            return 0.0;
        }
        let x = PI * lf / width;
        let w = if hanning {
            0.5 * (1.0 + x.cos())
        } else {
            x.sin() / x
        };
        w as f32
    }
}

/// Multiplies band l < `order` by the window's w_l ([`Window::factor`]).
pub fn apply_window(coeffs: &mut [Vec3], order: u32, window: Window) {
    if window != Window::None {
        scale_bands(coeffs, order, |l| window.factor(l));
    }
}

/// Evaluates the RGB expansion Σ_i c_i y_i(d) of bands l < `order` at the direction `d`
/// (normalised in f64, see [`eval_sh`]); summed in f64. Coefficients missing from a short
/// `coeffs` count as 0.
pub fn eval_rgb(order: u32, coeffs: &[Vec3], d: Vec3) -> Vec3 {
    let n = bands(order);
    let mut y = [0.0f64; MAX_COEFFS];
    eval_f64(n, d.as_dvec3(), &mut y);
    coeffs
        .iter()
        .zip(&y[..n * n])
        .fold(DVec3::ZERO, |acc, (c, yi)| acc + c.as_dvec3() * *yi)
        .as_vec3()
}

/// Product quadrature over the sphere: `nz` Gauss–Legendre nodes in z = cos θ times `nphi`
/// equally spaced azimuths. Exact for polynomials in (x, y, z) of degree ≤ min(2 nz − 1,
/// nphi − 1), hence for products y_i y_j of bands l_i + l_j ≤ that degree.
fn sphere_quadrature(nz: usize, nphi: usize) -> Vec<(DVec3, f64)> {
    let dphi = 2.0 * PI / nphi as f64;
    let mut out = Vec::with_capacity(nz * nphi);
    for (z, wz) in gauss_legendre(nz) {
        let rho = (1.0 - z * z).max(0.0).sqrt();
        for j in 0..nphi {
            let phi = dphi * (j as f64 + 0.5);
            out.push((DVec3::new(rho * phi.cos(), rho * phi.sin(), z), wz * dphi));
        }
    }
    out
}

/// Offset of band l's (2l+1)² matrix in [`ShRotation`]'s storage: Σ_{k<l} (2k+1)².
#[inline]
fn band_offset(l: usize) -> usize {
    l * (2 * l + 1) * (2 * l).saturating_sub(1) / 3
}

/// The nearest orthogonal matrix to `r` (polar decomposition by the Newton iteration
/// Q ← (Q + Q⁻ᵀ)/2), so that the f32 rounding of a rotation matrix does not make the band
/// matrices non-orthogonal. A singular `r` is returned unchanged.
fn orthonormalise(r: DMat3) -> DMat3 {
    let mut q = r;
    for _ in 0..8 {
        let det = q.determinant();
        if !(det.abs() > 1e-12) {
            return r;
        }
        let next = (q + q.inverse().transpose()) * 0.5;
        let done = (next - q).to_cols_array().iter().all(|v| v.abs() < 1e-16);
        q = next;
        if done {
            break;
        }
    }
    q
}

/// Rotation of SH expansions: for a rotation matrix R, maps the coefficients of f to those of
/// f'(d) = f(R⁻¹ d). Rotations never mix bands; band l is a (2l+1)×(2l+1) orthogonal matrix
///
/// D^l_{m'm} = ∫_{S²} y_l^{m'}(ω) y_l^m(R⁻¹ ω) dω,
///
/// the Galerkin projection of the rotated basis function onto its own band. Both factors are
/// polynomials of degree l on the sphere (a rotated harmonic stays in its band), so the product
/// quadrature of `order` Gauss–Legendre nodes in cos θ × (2·order − 1) azimuths integrates it
/// exactly: the matrices are exact to f64 rounding for any order, with no linear solve and no
/// special cases (Ivanic–Ruedenberg recurrences would be faster to build but need the basis'
/// sign convention threaded through every step). R is first made exactly orthogonal in f64
/// (polar decomposition), then R⁻¹ = Rᵀ. Building costs ≈ 3 M multiply-adds at order 16;
/// [`ShRotation::apply`] Σ (2l+1)² per channel.
#[derive(Clone, Debug)]
pub struct ShRotation {
    order: u32,
    /// Band l's matrix, row-major (row m' + l, column m + l), at [`band_offset`]`(l)`.
    mats: Vec<f64>,
}

impl ShRotation {
    /// The band matrices of bands l < `order` for the rotation matrix `r` (orthogonal with
    /// determinant +1; a reflection also works and maps f to f(R⁻¹ d) the same way).
    pub fn new(order: u32, r: Mat3) -> ShRotation {
        let n = bands(order);
        let rinv = orthonormalise(r.as_dmat3()).transpose();
        let mut mats = vec![0.0f64; band_offset(n)];
        let mut ya = [0.0f64; MAX_COEFFS];
        let mut yb = [0.0f64; MAX_COEFFS];
        for (w_dir, w) in sphere_quadrature(n, 2 * n - 1) {
            eval_f64(n, w_dir, &mut ya);
            eval_f64(n, rinv * w_dir, &mut yb);
            for l in 0..n {
                let size = 2 * l + 1;
                let base = l * l;
                let mat = &mut mats[band_offset(l)..band_offset(l + 1)];
                for (row, &a) in mat.chunks_exact_mut(size).zip(&ya[base..base + size]) {
                    let wa = w * a;
                    for (e, &b) in row.iter_mut().zip(&yb[base..base + size]) {
                        *e += wa * b;
                    }
                }
            }
        }
        ShRotation {
            order: n as u32,
            mats,
        }
    }

    /// The order (number of bands) the rotation was built for.
    pub fn order(&self) -> u32 {
        self.order
    }

    /// Rotates RGB coefficients: returns order² coefficients of f(R⁻¹ d); input coefficients
    /// beyond order² are ignored, missing ones count as 0. Summed in f64.
    pub fn apply(&self, coeffs: &[Vec3]) -> Vec<Vec3> {
        let n = self.order as usize;
        let mut out = vec![Vec3::ZERO; n * n];
        for l in 0..n {
            let size = 2 * l + 1;
            let base = l * l;
            let mat = &self.mats[band_offset(l)..band_offset(l + 1)];
            let input = &coeffs[base.min(coeffs.len())..(base + size).min(coeffs.len())];
            for (o, row) in out[base..base + size]
                .iter_mut()
                .zip(mat.chunks_exact(size))
            {
                *o = row
                    .iter()
                    .zip(input)
                    .fold(DVec3::ZERO, |acc, (&d, c)| acc + c.as_dvec3() * d)
                    .as_vec3();
            }
        }
        out
    }

    /// [`ShRotation::apply`] for one channel.
    pub fn apply_scalar(&self, coeffs: &[f32]) -> Vec<f32> {
        let n = self.order as usize;
        let mut out = vec![0.0f32; n * n];
        for l in 0..n {
            let size = 2 * l + 1;
            let base = l * l;
            let mat = &self.mats[band_offset(l)..band_offset(l + 1)];
            let input = &coeffs[base.min(coeffs.len())..(base + size).min(coeffs.len())];
            for (o, row) in out[base..base + size]
                .iter_mut()
                .zip(mat.chunks_exact(size))
            {
                *o = row
                    .iter()
                    .zip(input)
                    .fold(0.0f64, |acc, (&d, &c)| acc + f64::from(c) * d)
                    as f32;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests;
