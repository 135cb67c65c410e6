//! Spherical Gaussians: G(ω; p, λ, μ) = μ · exp(λ (ω·p − 1)).

use glam::Vec3;

/// A spherical Gaussian with unit `axis` p, `sharpness` λ ≥ 0 and RGB `amplitude` μ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sg {
    pub axis: Vec3,
    pub sharpness: f32,
    pub amplitude: Vec3,
}

impl Sg {
    /// G(ω) = μ exp(λ (ω·p − 1)).
    #[inline]
    pub fn eval(&self, w: Vec3) -> Vec3 {
        self.amplitude * (self.sharpness * (w.dot(self.axis) - 1.0)).exp()
    }
}
