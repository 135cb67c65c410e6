//! Renderers: the CPU reference and direct-light renderers, and pre-render sanity checks.

pub mod checks;
pub mod cpu;

/// The rendering methods of `interreflect render --method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Path-traced ground truth: direct light + exactly one indirect bounce (MIS).
    Reference,
    /// Direct light only, exact shadows.
    Direct,
}
