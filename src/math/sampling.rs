//! Random streams keyed by (seed, pixel, sample) and the sampling warps built on them.
//!
//! Output of every stochastic renderer depends only on the key, never on which thread drew the
//! numbers, so images are bit-identical for any thread count.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// SplitMix64 finaliser (Steele et al. 2014): a bijective 64-bit mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// PCG32 (O'Neill 2014, XSH-RR variant) seeded from a hashed key.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

impl Rng {
    const MULT: u64 = 6364136223846793005;

    /// A stream for `(seed, a, b)`, e.g. `(seed, pixel index, sample index)`.
    pub fn keyed(seed: u64, a: u64, b: u64) -> Rng {
        let k1 = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
        let k2 = mix64(k1 ^ a.wrapping_mul(0xd1b5_4a32_d192_ed03));
        let k3 = mix64(k2 ^ b.wrapping_mul(0x8cb9_2ba7_2f3d_8dd7));
        let mut rng = Rng {
            state: 0,
            inc: (mix64(k3 ^ 0x5851_f42d_4c95_7f2d) << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(k3);
        rng.next_u32();
        rng
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(Self::MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1), 24 bits of precision (never returns 1.0).
    #[inline]
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    #[inline]
    pub fn vec2(&mut self) -> Vec2 {
        Vec2::new(self.f32(), self.f32())
    }

    #[inline]
    pub fn arr3(&mut self) -> [f32; 3] {
        [self.f32(), self.f32(), self.f32()]
    }
}

/// Cosine-weighted hemisphere around +z (Malley's method on a concentric disk); pdf = cos θ / π.
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Shirley–Chiu concentric map of the unit square to the unit disk.
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, (PI / 4.0) * (o.y / o.x))
    } else {
        (o.y, PI / 2.0 - (PI / 4.0) * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Uniform direction on the unit sphere; pdf = 1 / (4π).
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform barycentrics (b0, b1, b2) on a triangle (Heitz 2019's low-distortion map).
pub fn uniform_triangle(u: Vec2) -> [f32; 3] {
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    [b0, b1, 1.0 - b0 - b1]
}

/// Solid angle of the spherical triangle with unit vertices a, b, c (Van Oosterom & Strackee 1983);
/// always ≥ 0 whatever the winding.
pub fn spherical_triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let num = a.dot(b.cross(c)).abs();
    let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    let omega = 2.0 * num.atan2(den);
    if omega.is_finite() {
        omega.max(0.0)
    } else {
        0.0
    }
}

/// Uniform sampling of the spherical triangle a, b, c (unit vectors) by solid angle
/// (Arvo, "Stratified Sampling of Spherical Triangles", SIGGRAPH 1995).
/// Returns the direction; its pdf is 1 / area. `None` for a degenerate triangle.
pub fn sample_spherical_triangle(a: Vec3, b: Vec3, c: Vec3, u: Vec2) -> Option<Vec3> {
    let area = spherical_triangle_area(a, b, c);
    if !(area > 1e-7) {
        return None;
    }
    // Interior angles at a and b (angle at a between the planes (a,b) and (a,c)).
    let angle = |v: Vec3, p: Vec3, q: Vec3| -> f32 {
        let n1 = v.cross(p);
        let n2 = v.cross(q);
        let l = n1.length() * n2.length();
        if l <= 0.0 {
            return 0.0;
        }
        (n1.dot(n2) / l).clamp(-1.0, 1.0).acos()
    };
    let alpha = angle(a, b, c);
    let beta = angle(b, c, a);
    let cos_c = a.dot(b).clamp(-1.0, 1.0);
    let a_hat = u.x * area;
    let s = (a_hat - alpha).sin();
    let t = (a_hat - alpha).cos();
    let uu = t - alpha.cos();
    let vv = s + alpha.sin() * cos_c;
    let denom = (vv * s + uu * t) * alpha.sin();
    if denom == 0.0 {
        return None;
    }
    let q = ((vv * t - uu * s) * alpha.cos() - vv) / denom;
    let q = q.clamp(-1.0, 1.0);
    let c_perp = c - c.dot(a) * a;
    let c_perp_len = c_perp.length();
    if c_perp_len <= 0.0 {
        return None;
    }
    let c_hat = q * a + (1.0 - q * q).max(0.0).sqrt() * (c_perp / c_perp_len);
    let z = 1.0 - u.y * (1.0 - c_hat.dot(b));
    let bc_perp = c_hat - c_hat.dot(b) * b;
    let l = bc_perp.length();
    let _ = beta;
    let dir = if l > 0.0 {
        z * b + (1.0 - z * z).max(0.0).sqrt() * (bc_perp / l)
    } else {
        b
    };
    let dir = dir.normalize_or_zero();
    if dir == Vec3::ZERO || !dir.is_finite() {
        None
    } else {
        Some(dir)
    }
}

/// A discrete distribution over indices with probability proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    total: f64,
}

impl Distribution1D {
    /// Builds the distribution; negative or non-finite weights count as 0.
    pub fn new(weights: &[f32]) -> Distribution1D {
        let mut cdf = Vec::with_capacity(weights.len());
        let mut acc = 0.0f64;
        for &w in weights {
            if w.is_finite() && w > 0.0 {
                acc += w as f64;
            }
            cdf.push(acc);
        }
        Distribution1D { cdf, total: acc }
    }

    /// Sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    pub fn is_empty(&self) -> bool {
        self.total <= 0.0
    }

    /// Probability of index `i`.
    pub fn pmf(&self, i: usize) -> f32 {
        if self.total <= 0.0 || i >= self.cdf.len() {
            return 0.0;
        }
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        ((self.cdf[i] - lo) / self.total) as f32
    }

    /// Draws an index with probability ∝ weight; `None` when every weight is 0.
    pub fn sample(&self, u: f32) -> Option<usize> {
        if self.total <= 0.0 {
            return None;
        }
        let target = u as f64 * self.total;
        let mut i = self.cdf.partition_point(|&c| c <= target);
        if i >= self.cdf.len() {
            i = self.cdf.len() - 1;
        }
        // Skip zero-weight entries (possible only when target lands exactly on a boundary).
        while self.pmf(i) == 0.0 && i + 1 < self.cdf.len() {
            i += 1;
        }
        Some(i)
    }

    /// [`sample`](Self::sample), also returning where `u` fell inside the chosen entry's share of
    /// [0, 1), rescaled to [0, 1): a fresh uniform number for a second, nested choice (pbrt's
    /// "sample reuse"). Its precision is that of `u` less the bits the choice used.
    pub fn sample_remapped(&self, u: f32) -> Option<(usize, f32)> {
        let i = self.sample(u)?;
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let w = self.cdf[i] - lo;
        let r = if w > 0.0 {
            ((u as f64 * self.total - lo) / w).clamp(0.0, 1.0)
        } else {
            0.5
        };
        // The largest f32 below 1 (1 − 2⁻²⁴), so the result stays in [0, 1).
        Some((i, (r as f32).min(f32::from_bits(0x3f7f_ffff))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyed_streams_are_reproducible_and_distinct() {
        let mut a = Rng::keyed(1, 2, 3);
        let mut b = Rng::keyed(1, 2, 3);
        let mut c = Rng::keyed(1, 2, 4);
        let xa: Vec<u32> = (0..8).map(|_| a.next_u32()).collect();
        let xb: Vec<u32> = (0..8).map(|_| b.next_u32()).collect();
        let xc: Vec<u32> = (0..8).map(|_| c.next_u32()).collect();
        assert_eq!(xa, xb);
        assert_ne!(xa, xc);
    }

    #[test]
    fn uniform_floats_have_the_right_mean_and_range() {
        let mut r = Rng::keyed(7, 0, 0);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let x = r.f32();
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
        }
        // Standard error of the mean of U(0,1) is 1/sqrt(12 n) ≈ 6.5e-4; 5 sigma.
        assert!((sum / n as f64 - 0.5).abs() < 3.3e-3);
    }

    #[test]
    fn spherical_triangle_sampling_stays_inside_and_is_uniform() {
        let a = Vec3::new(1.0, 0.1, 0.2).normalize();
        let b = Vec3::new(0.1, 1.0, 0.3).normalize();
        let c = Vec3::new(0.2, 0.3, 1.0).normalize();
        let area = spherical_triangle_area(a, b, c);
        let mut rng = Rng::keyed(3, 0, 0);
        // Uniformity: the fraction of samples falling into the sub-triangle (a, b, m) must match
        // its share of the solid angle.
        let m = (a + b + c).normalize();
        let sub = spherical_triangle_area(a, b, m);
        let n_ab = a.cross(b);
        let n_bm = b.cross(m);
        let n_ma = m.cross(a);
        let inside_sub = |d: Vec3| d.dot(n_ab) >= 0.0 && d.dot(n_bm) >= 0.0 && d.dot(n_ma) >= 0.0;
        let (na, nb, nc) = (a.cross(b), b.cross(c), c.cross(a));
        let n = 100_000;
        let mut hits = 0;
        for _ in 0..n {
            let d = sample_spherical_triangle(a, b, c, rng.vec2()).unwrap();
            assert!(d.dot(na) >= -1e-4 && d.dot(nb) >= -1e-4 && d.dot(nc) >= -1e-4);
            if inside_sub(d) {
                hits += 1;
            }
        }
        let p = sub / area;
        let sigma = (p * (1.0 - p) / n as f32).sqrt();
        assert!(
            ((hits as f32 / n as f32) - p).abs() < 5.0 * sigma,
            "p={p} got {}",
            hits as f32 / n as f32
        );
    }

    #[test]
    fn distribution_matches_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert_eq!(d.pmf(1), 0.0);
        assert!((d.pmf(2) - 0.75).abs() < 1e-6);
        assert_eq!(d.sample(0.0), Some(0));
        assert_eq!(d.sample(0.3), Some(2));
        assert_eq!(Distribution1D::new(&[0.0]).sample(0.5), None);
    }
}
