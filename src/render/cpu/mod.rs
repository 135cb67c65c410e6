//! CPU renderers (rayon): the path-traced reference (direct light + exactly one indirect bounce)
//! and direct light only, the SG renderer (`sg`, `sg-brute`), the VPL baseline (`vpl`) and PRT's
//! image pass.

pub mod env_light;
pub mod prt;
pub mod reference;
pub mod reflectors;
pub mod sg;
mod sg_sparse;
mod sg_tiles;
pub mod surface;
pub mod vpl;

pub use reference::{Progress, RenderOptions, RenderStats, render};
