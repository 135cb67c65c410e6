//! The scene-file schema (TOML, serde). Field-by-field documentation: `docs/scene-format.md`.
//!
//! Every table rejects unknown fields, so a typo is an error that names the field, not a silently
//! ignored setting.

use serde::Deserialize;
use std::collections::BTreeMap;

/// The whole file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Scene name (default: the file stem); used for default output names.
    pub name: Option<String>,
    pub camera: CameraSpec,
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    #[serde(default)]
    pub objects: Vec<ObjectSpec>,
    #[serde(default)]
    pub render: RenderSpec,
    #[serde(default)]
    pub methods: MethodsSpec,
    #[serde(default)]
    pub visibility: VisibilitySpec,
    /// Environment lighting (a lat-long map at infinity).
    #[serde(default)]
    pub environment: Option<EnvironmentSpec>,
}

/// `[environment]`: a lat-long radiance map lighting the scene from infinity.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentSpec {
    /// The map, relative to the scene file: `.exr` or `.hdr`.
    pub file: String,
    /// Degrees about +y (right-handed), default 0.
    #[serde(default)]
    pub rotation: f32,
    /// Scale of the map's radiance, default 1.
    #[serde(default = "unit_intensity")]
    pub intensity: f32,
}

fn unit_intensity() -> f32 {
    1.0
}

/// Settings of the approximate visibility (`render --visibility vsm`).
#[derive(Debug, Deserialize, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VisibilitySpec {
    /// Texels per side of each variance-shadow-map face.
    #[serde(default = "default_shadow_map_resolution")]
    pub shadow_map_resolution: u32,
    /// Radius of the shadow maps' Gaussian blur, in texels (0 = none).
    #[serde(default = "default_vsm_blur")]
    pub vsm_blur: u32,
    /// Light-bleeding reduction of the variance shadow maps, in [0, 1) (0 = none).
    #[serde(default = "default_light_bleeding")]
    pub light_bleeding: f32,
    /// Virtual point lights per light (`--visibility approx`).
    #[serde(default = "default_vpl_count")]
    pub vpl_count: u32,
    /// Texels per side of each imperfect shadow map.
    #[serde(default = "default_ism_resolution")]
    pub ism_resolution: u32,
    /// Scene points splatted into each imperfect shadow map.
    #[serde(default = "default_ism_points")]
    pub ism_points: u32,
    /// Depth bias of the imperfect shadow maps, a fraction of the distance.
    #[serde(default = "default_ism_bias")]
    pub ism_bias: f32,
    /// sg `--visibility approx`: tree nodes that get a visibility map of their own (0: the
    /// paper's proxy, each node interpolating its 3 nearest VPLs' imperfect shadow maps).
    #[serde(default = "default_node_maps")]
    pub node_maps: u32,
}

fn default_node_maps() -> u32 {
    crate::settings::IsmOptions::default().node_maps
}

fn default_vpl_count() -> u32 {
    200
}

fn default_ism_resolution() -> u32 {
    crate::settings::IsmOptions::default().resolution
}

fn default_ism_points() -> u32 {
    crate::settings::IsmOptions::default().points_per_map
}

fn default_ism_bias() -> f32 {
    crate::settings::IsmOptions::default().bias
}

fn default_shadow_map_resolution() -> u32 {
    crate::settings::VsmOptions::default().resolution
}

fn default_vsm_blur() -> u32 {
    crate::settings::VsmOptions::default().blur
}

fn default_light_bleeding() -> f32 {
    crate::settings::VsmOptions::default().light_bleeding
}

impl Default for VisibilitySpec {
    fn default() -> Self {
        VisibilitySpec {
            shadow_map_resolution: default_shadow_map_resolution(),
            vsm_blur: default_vsm_blur(),
            light_bleeding: default_light_bleeding(),
            vpl_count: default_vpl_count(),
            ism_resolution: default_ism_resolution(),
            ism_points: default_ism_points(),
            ism_bias: default_ism_bias(),
            node_maps: default_node_maps(),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    pub position: [f32; 3],
    pub look_at: [f32; 3],
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    pub fov_y: f32,
    pub width: u32,
    pub height: u32,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightSpec {
    /// Isotropic point light; `intensity` in W/sr per RGB channel.
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    /// Spot light: `intensity` (W/sr) on the axis, full inside `falloff_angle`, smoothly down to 0
    /// at `cone_angle` (half-angles in degrees).
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        intensity: [f32; 3],
        cone_angle: f32,
        #[serde(default)]
        falloff_angle: Option<f32>,
    },
    /// Distant light travelling along `direction`; `irradiance` in W/m² on a surface facing it.
    Directional {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
}

#[derive(Debug, Deserialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialSpec {
    Lambert {
        diffuse: [f32; 3],
    },
    Phong {
        #[serde(default)]
        diffuse: [f32; 3],
        specular: [f32; 3],
        exponent: f32,
    },
    BlinnPhong {
        #[serde(default)]
        diffuse: [f32; 3],
        specular: [f32; 3],
        exponent: f32,
    },
    Ward {
        #[serde(default)]
        diffuse: [f32; 3],
        specular: [f32; 3],
        roughness: f32,
    },
    CookTorrance {
        #[serde(default)]
        diffuse: [f32; 3],
        specular: [f32; 3],
        roughness: f32,
        distribution: DistributionSpec,
    },
}

#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(rename_all = "snake_case")]
pub enum DistributionSpec {
    Beckmann,
    Ggx,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    pub name: Option<String>,
    pub material: String,
    pub shape: ShapeSpec,
    #[serde(default)]
    pub transform: TransformSpec,
    /// Whether the object reflects light onto others (one-bounce sources).
    #[serde(default = "yes")]
    pub reflector: bool,
    /// Whether the object receives reflected light.
    #[serde(default = "yes")]
    pub receiver: bool,
}

fn yes() -> bool {
    true
}

#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// A mesh file, relative to the scene file.
    Mesh { file: String },
    /// Square grid in the xz-plane centred at the origin, normal +y.
    Plane {
        size: [f32; 2],
        #[serde(default = "one")]
        subdivisions: u32,
    },
    /// Axis-aligned box centred at the origin.
    Box { size: [f32; 3] },
    /// UV sphere centred at the origin.
    Sphere {
        radius: f32,
        #[serde(default = "sphere_segments")]
        segments: u32,
    },
    /// Cylindrical band around +y from y = 0 to `height`, inner radius `radius`, wall `thickness`.
    Ring {
        radius: f32,
        height: f32,
        thickness: f32,
        #[serde(default = "ring_segments")]
        segments: u32,
    },
}

fn one() -> u32 {
    1
}
fn sphere_segments() -> u32 {
    64
}
fn ring_segments() -> u32 {
    256
}

/// Scale, then rotate (degrees about x, then y, then z), then translate.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    #[serde(default)]
    pub translate: Option<[f32; 3]>,
    #[serde(default)]
    pub rotate: Option<[f32; 3]>,
    #[serde(default)]
    pub scale: Option<ScaleSpec>,
}

impl TransformSpec {
    /// True when nothing is given (the object stays as its shape defines it).
    pub fn is_identity(&self) -> bool {
        self.translate.is_none() && self.rotate.is_none() && self.scale.is_none()
    }
}

#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(untagged)]
pub enum ScaleSpec {
    Uniform(f32),
    PerAxis([f32; 3]),
}

/// Defaults for `render` (command-line flags override them).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSpec {
    #[serde(default = "default_spp")]
    pub spp: u32,
    #[serde(default)]
    pub seed: u64,
}

fn default_spp() -> u32 {
    64
}

impl Default for RenderSpec {
    fn default() -> Self {
        RenderSpec {
            spp: default_spp(),
            seed: 0,
        }
    }
}

/// Per-method settings.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MethodsSpec {
    #[serde(default)]
    pub reference: ReferenceSpec,
    #[serde(default)]
    pub sg: SgSpec,
    #[serde(default)]
    pub prt: PrtSpec,
    #[serde(default)]
    pub vpl: VplSpec,
}

/// Settings of the VPL baseline (`vpl`). The VPLs themselves (count, imperfect shadow maps) are
/// the ones in `[visibility]`, shared with sg's approximate visibility.
#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct VplSpec {
    /// The geometry term is clamped at this distance (scene units): cos θ_x cos θ_y /
    /// max(d², clamp_distance²); 0 = no clamp; absent = 1/50 of the scene's diagonal.
    #[serde(default)]
    pub clamp_distance: Option<f32>,
    /// Samples per pixel (absent = methods.sg.spp, so that the two compare at equal sampling).
    #[serde(default)]
    pub spp: Option<u32>,
}

/// Settings of SH diffuse precomputed radiance transfer (`prt`).
#[derive(Debug, Deserialize, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PrtSpec {
    /// SH order: bands l < order, order² coefficients per vertex and channel.
    #[serde(default = "default_prt_order")]
    pub order: u32,
    /// What the transfer includes: "unshadowed", "shadowed" or "interreflected".
    #[serde(default = "default_prt_transfer")]
    pub transfer: crate::settings::TransferKind,
    /// Reflections added to the shadowed transfer when `transfer = "interreflected"`.
    #[serde(default = "one")]
    pub bounces: u32,
    /// Ray directions per vertex (cosine-distributed, stratified).
    #[serde(default = "default_prt_samples")]
    pub samples: u32,
    /// Window applied to the SH lighting against ringing: "none", "hanning" or "lanczos".
    #[serde(default = "default_prt_window")]
    pub window: crate::settings::WindowKind,
    /// Band at which the window reaches 0 (Hanning) or its first zero (Lanczos); absent =
    /// twice the order (measured in `docs/prt.md`: the order itself blurs too much).
    #[serde(default)]
    pub window_width: Option<f32>,
    /// Samples per pixel of the final interpolation pass.
    #[serde(default = "one")]
    pub spp: u32,
}

fn default_prt_order() -> u32 {
    5
}

fn default_prt_transfer() -> crate::settings::TransferKind {
    crate::settings::TransferKind::Interreflected
}

fn default_prt_samples() -> u32 {
    1024
}

fn default_prt_window() -> crate::settings::WindowKind {
    crate::settings::WindowKind::Hanning
}

impl Default for PrtSpec {
    fn default() -> Self {
        PrtSpec {
            order: default_prt_order(),
            transfer: default_prt_transfer(),
            bounces: 1,
            samples: default_prt_samples(),
            window: default_prt_window(),
            window_width: None,
            spp: 1,
        }
    }
}

/// Settings of the SG method (`sg`, `sg-brute`).
#[derive(Debug, Deserialize, Clone, Copy, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SgSpec {
    /// Cut threshold: refine until every node's error bound is below this fraction of the
    /// estimate (0.01 = 1 %).
    #[serde(default = "default_threshold")]
    pub threshold: f32,
    /// Maximum nodes per cut; 0 = no cap.
    #[serde(default = "default_max_cut")]
    pub max_cut: u32,
    /// Where cuts are chosen: "pixel" (every pixel sample, the default), "tile" (a screen
    /// tile's samples of one material; faster, less accurate on the dragon:
    /// `docs/sg-performance.md`) or "vertex" (every receiver vertex).
    #[serde(default = "default_cut_mode")]
    pub cut: crate::settings::CutMode,
    /// Samples per pixel of the SG methods (the reference's count is `render.spp`).
    #[serde(default = "one")]
    pub spp: u32,
    /// Reflector triangles are split until their longest edge is at most this many scene units;
    /// 0 = never; absent = 1/128 of the scene's bounding-box diagonal.
    #[serde(default)]
    pub max_edge: Option<f32>,
}

fn default_threshold() -> f32 {
    crate::settings::DEFAULT_THRESHOLD
}

fn default_max_cut() -> u32 {
    crate::settings::DEFAULT_MAX_CUT
}

fn default_cut_mode() -> crate::settings::CutMode {
    crate::settings::CutMode::Pixel
}

impl Default for SgSpec {
    fn default() -> Self {
        SgSpec {
            threshold: default_threshold(),
            max_cut: default_max_cut(),
            cut: default_cut_mode(),
            spp: 1,
            max_edge: None,
        }
    }
}

/// Settings of the path-traced reference.
#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// Reflector points sampled from the lights per camera sample (light-side strategy).
    #[serde(default = "one")]
    pub reflector_samples: u32,
    /// Directions sampled from the receiver's BRDF per camera sample.
    #[serde(default = "one")]
    pub bsdf_samples: u32,
    /// Light paths (light tracing) per camera sample.
    #[serde(default = "one")]
    pub light_paths: u32,
}

impl Default for ReferenceSpec {
    fn default() -> Self {
        ReferenceSpec {
            reflector_samples: 1,
            bsdf_samples: 1,
            light_paths: 1,
        }
    }
}
