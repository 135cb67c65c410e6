//! CPU renderers (rayon): the path-traced reference (direct light + exactly one indirect bounce)
//! and direct light only, and the SG renderer (`sg`, `sg-brute`).

pub mod env_light;
pub mod prt;
pub mod reference;
pub mod reflectors;
pub mod sg;
pub mod surface;

pub use reference::{Progress, RenderOptions, RenderStats, render};
