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
