//! Spherical-Gaussian light transport of one reflector triangle (Xu et al. 2014, §4–5).
//!
//! - [`reflector`]: the radiance a triangle reflects after being lit by a point light, as a
//!   diffuse constant plus SG lobes in the outgoing direction (centroid form), and the
//!   mirror-image refinement that re-aims the lobes at a given receiver.
//! - [`receiver`]: the one-bounce radiance that one reflector triangle sends to a receiver
//!   point towards the eye: every pair of (reflected lobe, receiver BRDF lobe) is multiplied
//!   into one SG and integrated analytically over the triangle's solid angle.
//! - [`brute_force`]: the exact one-bounce integral over the triangle with the exact BRDFs, by
//!   adaptive quadrature: the yardstick of the two above.

pub mod brute_force;
pub mod receiver;
pub mod reflector;
pub mod study;

pub use receiver::{CosineMode, ReceiverOptions, one_bounce};
pub use reflector::{ReflectedSg, Reflector, aim_at_receiver, reflected_sg};

#[cfg(test)]
mod tests;
