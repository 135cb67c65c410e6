//! Renderers.
pub mod cpu;
