//! scene
pub mod mesh;
