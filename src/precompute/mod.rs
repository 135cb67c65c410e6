//! Scene-dependent, light-independent precomputation for the SG renderer (Xu et al. 2014, §6).
//!
//! - [`tree`]: the PCA-split binary tree over the reflector triangles, with per-node shading
//!   data (centroid, average normal, colour, area, material) and bounds (box, normal cone,
//!   colour range).
//! - [`vpl`]: virtual point lights on the lit reflectors, sampled by reflected flux.
//! - [`prt`]: SH diffuse precomputed radiance transfer per vertex (the comparison method).

pub mod prt;
pub mod vpl;
