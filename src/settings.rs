//! The settings that scene files and the command line fill for the methods: the SG cut, the
//! shadow maps, the imperfect shadow maps and visibility maps, and PRT's transfer and window.
//! They sit below the modules that use them (`scene` parses them, the methods read them), so that
//! the scene layer does not import the methods.

use crate::math::sh;

/// Where the SG method selects its cuts (`[methods.sg] cut`, `--cut`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
#[derive(clap::ValueEnum)]
pub enum CutMode {
    /// One cut per group of samples — a screen tile's samples of one material — with a bound
    /// that holds for every sample of the group, evaluated for all of them on the SIMD lanes
    /// (`docs/sg-performance.md`: 10–15× faster than pixel cuts on ring and bunny, but its
    /// group bound is loose near the receiver, which costs the dragon 21 points of rel_rmse at
    /// 8×8 tiles, so pixel cuts stay the default).
    Tile,
    /// One cut per pixel sample, at the shaded point.
    Pixel,
    /// One cut per receiver vertex (the paper's scheme); a pixel sample evaluates the cut of
    /// its triangle's nearest vertex at its own position.
    Vertex,
}

/// Default error threshold: stop refining when the largest bound is below 1 % of the estimate.
pub const DEFAULT_THRESHOLD: f32 = 0.01;
/// Default cap on the cut size.
pub const DEFAULT_MAX_CUT: u32 = 1000;

/// Cut-selection parameters (`[methods.sg]` in the scene file).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CutOptions {
    /// Relative error threshold (fraction of the estimate's luminance), ≥ 0.
    pub threshold: f32,
    /// Maximum number of nodes in a cut; 0 = no cap.
    pub max_cut: u32,
}

impl Default for CutOptions {
    fn default() -> Self {
        CutOptions {
            threshold: DEFAULT_THRESHOLD,
            max_cut: DEFAULT_MAX_CUT,
        }
    }
}

/// Settings of a variance shadow map (scene file: `[visibility]`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct VsmOptions {
    /// Texels per side of each face.
    pub resolution: u32,
    /// Radius of the Gaussian blur in texels (σ = radius / 2); 0 = none.
    pub blur: u32,
    /// Light-bleeding reduction b in [0, 1): p ← clamp((p − b) / (1 − b), 0, 1).
    pub light_bleeding: f32,
}

impl Default for VsmOptions {
    fn default() -> Self {
        VsmOptions {
            resolution: 512,
            blur: 2,
            light_bleeding: 0.2,
        }
    }
}

/// Settings of the imperfect shadow maps.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct IsmOptions {
    /// Texels per side of each paraboloid map.
    pub resolution: u32,
    /// Scene points splatted into each map.
    pub points_per_map: u32,
    /// Depth bias, a fraction of the distance to the VPL (small: the moments carry the spread
    /// of depths within a texel).
    pub bias: f32,
    /// A 3 × 3 blur of the moments after pull-push.
    pub blur: bool,
    /// sg `--visibility approx`: the tree nodes that get a ray-cast visibility map of their own
    /// (`render::cpu::sg`, `docs/visibility.md`); 0 for the paper's proxy (3 nearest VPLs).
    pub node_maps: u32,
}

impl Default for IsmOptions {
    fn default() -> Self {
        IsmOptions {
            resolution: 32,
            points_per_map: 4096,
            bias: 0.02,
            blur: true,
            node_maps: 8000,
        }
    }
}

/// What the transfer vectors include.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize, clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
pub enum TransferKind {
    /// Cosine only: no shadows, no interreflections (closed form).
    Unshadowed,
    /// Cosine and the vertex's own visibility of the lighting (shadows).
    Shadowed,
    /// Shadowed plus `bounces` diffuse reflections off the reflectors.
    Interreflected,
}

/// The window applied to the SH lighting against ringing.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize, clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
pub enum WindowKind {
    None,
    /// (1 + cos(π l / w)) / 2 below band w, 0 from w on (Sloan 2008).
    Hanning,
    /// sinc(π l / w).
    Lanczos,
}

impl WindowKind {
    /// The SH window of this kind whose zero is at band `width`.
    pub fn window(self, width: f32) -> sh::Window {
        match self {
            WindowKind::None => sh::Window::None,
            WindowKind::Hanning => sh::Window::Hanning { width },
            WindowKind::Lanczos => sh::Window::Lanczos { width },
        }
    }
}
