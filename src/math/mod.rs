//! Pure maths: orthonormal frames, sampling warps, keyed random streams, spherical Gaussians
//! and real spherical harmonics.
//! Imports nothing from the rest of the crate.

pub mod frame;
pub mod sampling;
pub mod sg;
pub mod sh;
pub mod spherical_triangle;

pub use frame::Frame;
pub use sampling::Rng;

use std::f64::consts::PI;

/// Rec. 709 luminance: the scalar that errors and estimates are compared in.
#[inline]
pub fn luminance(c: glam::Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Barycentrics (u, v) of point p in triangle (a, b, c) (the weights of b and c), clamped to
/// the triangle; the centroid for a degenerate triangle.
pub fn triangle_barycentrics(
    a: glam::Vec3,
    b: glam::Vec3,
    c: glam::Vec3,
    p: glam::Vec3,
) -> (f32, f32) {
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (dp1, dp2) = (d.dot(e1), d.dot(e2));
    let den = d11 * d22 - d12 * d12;
    if !(den.abs() > 0.0) {
        return (1.0 / 3.0, 1.0 / 3.0);
    }
    let u = ((d22 * dp1 - d12 * dp2) / den).clamp(0.0, 1.0);
    let v = ((d11 * dp2 - d12 * dp1) / den).clamp(0.0, 1.0 - u);
    (u, v)
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton iteration on P_n; Press et al. §4.5),
/// exact for polynomials of degree ≤ 2n − 1.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = vec![(0.0, 0.0); n];
    for i in 0..n.div_ceil(2) {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // p0 = P_n(x), p1 = P_{n−1}(x).
            let (mut p0, mut p1) = (1.0f64, 0.0f64);
            for j in 0..n {
                let p2 = p1;
                p1 = p0;
                p0 = ((2 * j + 1) as f64 * x * p1 - j as f64 * p2) / (j + 1) as f64;
            }
            dp = n as f64 * (x * p0 - p1) / (x * x - 1.0);
            let dx = p0 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out[i] = (-x, w);
        out[n - 1 - i] = (x, w);
    }
    out
}
