//! # interreflect
//!
//! One-bounce glossy interreflections with spherical Gaussians (Xu et al., "A Practical Algorithm
//! for Rendering Interreflections with All-Frequency BRDFs", TOG 2014), measured against a
//! path-traced ground truth.
//!
//! Data flows one way:
//!
//! ```text
//! scene (TOML + meshes) ──► accel (BVH) ──► render (reference | direct) ──► image (EXR/PNG) ──► compare
//! ```
//!
//! - [`math`]: pure maths (frames, sampling, random streams); imports nothing from the crate.
//! - [`brdf`]: exact analytic BRDF models with importance sampling.
//! - [`scene`]: the scene-file schema, mesh loading, procedural shapes; immutable once loaded.
//! - [`accel`]: the BVH (obvhs) for rays and occlusion.
//! - [`visibility`]: approximate visibility (variance shadow maps).
//! - [`render`]: the renderers (CPU, rayon).
//! - [`image`]: image buffers, EXR/PNG I/O, tonemapping.
//! - [`compare`]: error metrics and false-colour error maps.
//! - [`export`]: Mitsuba 3 export of a loaded scene.
//! - [`fsutil`]: atomic output files; [`hash`]: stable hashes for cache keys.
//! - [`report`]: the comparison reports of `interreflect report` (planning, interpolation,
//!   markdown).
//! - [`memory`]: the memory budget and the estimate of a render's peak memory.
//! - [`viewer`]: the interactive viewer's state, camera controller, scripts and frames (the
//!   window itself is `interreflect view`, in the binary).
// `unsafe` only in `sg::kernel::simd` (SIMD intrinsics), which allows it explicitly.
#![deny(unsafe_code)]
// `!(x > 0.0)` is written on purpose throughout: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod brdf;
pub mod compare;
pub mod export;
pub mod fsutil;
pub mod hash;
pub mod image;
pub mod math;
pub mod memory;
pub mod precompute;
pub mod progress;
pub mod render;
pub mod report;
pub mod scene;
pub mod settings;
pub mod sg;
pub mod viewer;
pub mod visibility;
