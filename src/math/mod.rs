//! Pure maths: orthonormal frames, sampling warps and keyed random streams.
//! Imports nothing from the rest of the crate.

pub mod frame;
pub mod sampling;
pub mod sg;
pub mod spherical_triangle;

pub use frame::Frame;
pub use sampling::Rng;
