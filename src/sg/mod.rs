//! The spherical-Gaussian method (Xu et al., "A Practical Algorithm for Rendering
//! Interreflections with All-Frequency BRDFs", TOG 2014): its stages, in the order data flows
//! through them.
//!
//! 1. [`pieces`]: the scene's reflector triangles split into pieces small enough to reflect a
//!    nearly constant radiance; [`tree`]: the PCA tree over them (once per scene).
//! 2. [`lighting`]: per frame and light, every piece lit as an SG reflector and the lit data
//!    summed up the tree ([`LitScene`]).
//! 3. [`bound`]: the error bound of a node at a receiver point; [`cluster`]: the node's
//!    approximation (the node shaded as one reflector); a leaf is shaded by the one-triangle
//!    [`transport`].
//! 4. [`select`]: the cut at a receiver point: refine the node of largest bound until every
//!    bound is below a fraction of the estimate or the cut reaches its cap.
//! 5. [`node_maps`]: the visibility maps at tree nodes between reflectors and receivers
//!    (`--visibility approx`).
//!
//! [`transport`] is the one-triangle SG transport (reflected lobes, their integral at a
//! receiver) and its exact yardstick. The renderer that drives these stages over an image is
//! `render::cpu::sg`. Details and measurements: `docs/sg-renderer.md`.

pub mod bound;
pub mod cluster;
pub mod group;
pub mod kernel;
pub mod lighting;
pub mod node_maps;
pub mod pieces;
pub mod select;
pub mod transport;
pub mod tree;

pub use crate::settings::{CutOptions, DEFAULT_MAX_CUT, DEFAULT_THRESHOLD};
pub use bound::{cos_minus_one, node_bound};
pub use cluster::{clamped_cosine_mean, erf};
pub use lighting::{
    LitNode, LitScene, LitTriangle, NodeLobe, SHARPNESS_BINS, light_anchor, light_triangles,
    visibility_points,
};
pub use pieces::{MAX_SPLIT_LEVELS, ReflectorPiece, build_tree, reflector_pieces};
pub use select::{CutCounters, CutEntry};

#[cfg(test)]
pub(crate) mod tests;
