//! Renderers: the CPU reference, direct-light and SG renderers, and pre-render sanity checks.

pub mod checks;
pub mod cpu;
pub mod gpu;

/// The rendering methods of `interreflect render --method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Path-traced ground truth: direct light + exactly one indirect bounce (MIS).
    Reference,
    /// Direct light only, exact shadows.
    Direct,
    /// The SG method: direct light + one bounce over a per-point cut of the reflector tree.
    Sg,
    /// The SG method over every reflector triangle (no tree): the cut's own yardstick.
    SgBrute,
    /// The VPL baseline (instant radiosity): the sg method's VPLs as clamped point lights, with
    /// exact BRDFs at both ends.
    Vpl,
    /// SH diffuse precomputed radiance transfer under distant lighting (environment maps and
    /// directional lights): the low-frequency comparison method.
    Prt,
}

/// Where the stages that have a GPU pass run (`render --device`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Device {
    /// The GPU when an adapter exists, otherwise the CPU (with a one-line notice).
    Auto,
    /// The GPU; an error when no adapter exists.
    Gpu,
    /// The CPU twins of the GPU passes.
    Cpu,
}

/// Visibility between reflectors and receivers (and from the light to reflectors) for `sg`,
/// `sg-brute` and `vpl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Visibility {
    /// Shadow rays through the BVH: one per reflector triangle from the light, one per cut node
    /// (or triangle) from the receiver.
    Exact,
    /// Variance shadow maps for the light's visibility (direct light and the light on every
    /// reflector piece), shadow rays between reflectors and receivers as in `exact`.
    Vsm,
    /// The default: the paper's kind of visibility, without shadow rays — variance shadow
    /// maps for the light, and between reflectors and receivers visibility maps at the
    /// reflector tree's nodes (or, with `node_maps = 0`, the paper's proxy: each cut node
    /// interpolates the imperfect shadow maps of its 3 nearest VPLs). 10–14 % off `Exact` on
    /// the evaluation scenes' indirect light (`docs/visibility.md`).
    Approx,
}
