//! The GPU data layouts: `#[repr(C)]` structs that are the single source of truth for the WGSL
//! structs of the same names in `shaders/shared/layout.wgsl`. WGSL aligns a `vec3<f32>` to 16
//! bytes; the Rust structs spell that padding out, and [`layouts`] lists every struct's size and
//! member offsets for the test that compares them with naga's layout of the shaders.

use bytemuck::{Pod, Zeroable};
use std::mem::{offset_of, size_of};

/// A spherical Gaussian μ exp(λ (ω·p − 1)) (`math::sg::Sg`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSg {
    pub axis: [f32; 3],
    pub sharpness: f32,
    pub amplitude: [f32; 3],
    pub _pad: f32,
}

impl From<crate::math::sg::Sg> for GpuSg {
    fn from(s: crate::math::sg::Sg) -> Self {
        GpuSg {
            axis: s.axis.to_array(),
            sharpness: s.sharpness,
            amplitude: s.amplitude.to_array(),
            _pad: 0.0,
        }
    }
}

/// One row of a math-twin table (`super::twins`): a function's inputs in four vec4s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TwinQuery {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
    pub d: [f32; 4],
}

/// The math-twin pass's uniform: which function, over how many rows.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TwinParams {
    pub function: u32,
    pub count: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// What the cut's error bound needs of a tree node (`cut::node_bound`): its box, normal cone,
/// the box of the light's mirror images and the lit sums. Empty boxes have min > max; a node
/// without a normal cone has `has_cone` 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuNodeBound {
    pub bbox_min: [f32; 3],
    pub has_cone: f32,
    pub bbox_max: [f32; 3],
    pub cone_half_angle: f32,
    pub cone_axis: [f32; 3],
    pub _pad0: f32,
    pub image_min: [f32; 3],
    pub _pad1: f32,
    pub image_max: [f32; 3],
    pub _pad2: f32,
    pub diffuse: [f32; 3],
    pub _pad3: f32,
    /// Σ A μ per sharpness bin (`cut::SHARPNESS_BINS`), RGB and a pad each.
    pub peak_by_sharpness: [[f32; 4]; 6],
}

/// A receiver point's BRDF lobes (`transport::receiver::ReceiverLobes`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuReceiver {
    pub normal: [f32; 3],
    pub stretch: f32,
    pub diffuse: [f32; 3],
    pub lobe_count: u32,
    pub lobes: [GpuSg; 4],
}

/// One face of a light's shadow map (`super::vsm`): a cube face, a spot's or an orthographic face.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVsmFace {
    pub forward: [f32; 3],
    pub margin: f32,
    pub right: [f32; 3],
    pub far: f32,
    pub up: [f32; 3],
    /// Face coordinates per unit of (right, up): 1 for a cube face, tan of a spot's
    /// half-angle, an orthographic box's half-extent (`visibility::vsm::MapSetup`).
    pub scale: f32,
    /// The light's position, or the orthographic box's origin.
    pub light: [f32; 3],
    /// 1: orthographic (depth along `forward`), 0: perspective (depth the distance).
    pub orthographic: u32,
}

/// The shadow-map blur's uniform.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBlurParams {
    pub resolution: u32,
    pub radius: u32,
    pub vertical: u32,
    pub _pad: u32,
}

/// The tonemap pass's uniform (`super::tonemap`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTonemapParams {
    /// 2^exposure.
    pub scale: f32,
    /// 0 clamp, 1 Reinhard, 2 ACES.
    pub tone_operator: u32,
    pub count: u32,
    /// Invocations per dispatch row.
    pub row_stride: u32,
}

/// The camera of the G-buffer pass (`super::gbuffer`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCamera {
    pub position: [f32; 3],
    pub tan_half: f32,
    pub forward: [f32; 3],
    pub aspect: f32,
    pub right: [f32; 3],
    pub far: f32,
    pub up: [f32; 3],
    pub _pad: f32,
}

/// The SG shading passes' uniform (`super::sg_shade`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShadeParams {
    /// The position the reflected lobes were aimed from (`LitScene::light_pos`).
    pub light_pos: [f32; 3],
    /// The (point, leaf) pairs in this dispatch, and the index of the first pair.
    pub count: u32,
    pub first: u32,
    /// The points whose pairs these are.
    pub point_first: u32,
    pub point_end: u32,
    /// Texels per side of each node map.
    pub map_res: u32,
    pub map_bias: f32,
    /// The index of the first (point, leaf) pair among all points' leaf pairs.
    pub leaf_first: u32,
    /// The (point, inner node) pairs in this dispatch, and the index of the first among all
    /// points' inner-node pairs.
    pub cluster_count: u32,
    pub cluster_first: u32,
}

/// One pixel sample on a receiver, with its cut and BRDF lobes (`super::sg_shade`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShadePoint {
    pub x: [f32; 3],
    pub cut_start: u32,
    /// The point visibility is looked up from (offset along the geometric normal).
    pub xo: [f32; 3],
    pub cut_count: u32,
    /// Unit direction across the plane of incidence (`ReceiverLobes::across`).
    pub across: [f32; 3],
    /// Index of the point's first (point, cut node) pair.
    pub pair_start: u32,
    pub receiver: GpuReceiver,
    /// The cut's leaves, which come first in its nodes, and the index of the point's first
    /// (point, leaf) pair among all points' leaf pairs (its first inner-node pair's is
    /// `pair_start − leaf_pair_start`).
    pub leaf_count: u32,
    pub leaf_pair_start: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// Per-slot sums of the lobes under a node (`cut::NodeLobe`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuNodeLobe {
    pub energy: [f32; 3],
    pub inv_sharpness_sum: f32,
    pub axis_sum: [f32; 3],
    pub _pad: f32,
}

/// A tree node lit by one light (`cut::LitNode`, with its bound's inputs).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLitNode {
    pub bound: GpuNodeBound,
    /// Σ w c / Σ w: the light's centroid under the node.
    pub centroid: [f32; 3],
    pub weight: f32,
    pub normal_sum: [f32; 3],
    pub area: f32,
    pub diffuse: [f32; 3],
    /// Index into the leaves for a leaf node, `u32::MAX` otherwise.
    pub leaf: u32,
    pub lobes: [GpuNodeLobe; 4],
    pub half_vector: u32,
    /// Index into the node maps, `u32::MAX` for none.
    pub map: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// A lit reflector triangle (`cut::LitTriangle` and its `ReflectedSg`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLeaf {
    pub v0: [f32; 3],
    /// 0 when the triangle is unlit (no lobes, no diffuse part).
    pub has_sg: u32,
    pub v1: [f32; 3],
    pub lobe_count: u32,
    pub v2: [f32; 3],
    pub half_vector: u32,
    pub diffuse: [f32; 3],
    pub stretch: f32,
    pub normal: [f32; 3],
    pub _pad0: f32,
    pub geometric_normal: [f32; 3],
    pub _pad1: f32,
    pub origin: [f32; 3],
    pub _pad2: f32,
    pub light: [f32; 3],
    pub _pad3: f32,
    pub lobes: [GpuSg; 4],
}

/// The origin of a visibility map at a tree node: position, paraboloid frame, variance floor.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMapOrigin {
    pub position: [f32; 3],
    pub min_variance: f32,
    pub t: [f32; 3],
    pub _pad0: f32,
    pub b: [f32; 3],
    pub _pad1: f32,
    pub n: [f32; 3],
    pub _pad2: f32,
}

/// A material (`brdf::Brdf`): `model` 0 Lambert, 1 Phong, 2 Blinn-Phong, 3 Ward, 4 Cook-Torrance
/// (`distribution` 0 Beckmann, 1 GGX); `param` the exponent or α.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuBrdf {
    pub diffuse: [f32; 3],
    pub model: u32,
    pub specular: [f32; 3],
    pub param: f32,
    pub distribution: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// The value of the shaders' `BRDF_MODELS` override that compiles exactly the models `materials`
/// use (`shaders/shared/brdf.wgsl`): bit `model` for each, and for Cook-Torrance bit 5
/// (Beckmann) or 6 (GGX).
pub fn brdf_models(materials: &[GpuBrdf]) -> u32 {
    materials.iter().fold(0, |bits, m| {
        let distribution = if m.model == 4 {
            1 << (5 + m.distribution.min(1))
        } else {
            0
        };
        bits | 1 << m.model.min(31) | distribution
    })
}

impl From<&crate::brdf::Brdf> for GpuBrdf {
    fn from(b: &crate::brdf::Brdf) -> Self {
        use crate::brdf::{Brdf, Distribution};
        let (model, diffuse, specular, param, distribution) = match *b {
            Brdf::Lambert { diffuse } => (0, diffuse, glam::Vec3::ZERO, 0.0, 0),
            Brdf::Phong {
                diffuse,
                specular,
                exponent,
            } => (1, diffuse, specular, exponent, 0),
            Brdf::BlinnPhong {
                diffuse,
                specular,
                exponent,
            } => (2, diffuse, specular, exponent, 0),
            Brdf::Ward {
                diffuse,
                specular,
                roughness,
            } => (3, diffuse, specular, roughness, 0),
            Brdf::CookTorrance {
                diffuse,
                specular,
                roughness,
                distribution,
            } => (
                4,
                diffuse,
                specular,
                roughness,
                u32::from(distribution == Distribution::Ggx),
            ),
        };
        GpuBrdf {
            diffuse: diffuse.to_array(),
            model,
            specular: specular.to_array(),
            param,
            distribution,
            ..GpuBrdf::default()
        }
    }
}

/// The VPL pass's uniform (`super::vpl`): the points of this dispatch, the VPLs of this chunk,
/// the geometry term's clamp and the imperfect shadow maps' resolution and bias.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVplParams {
    pub count: u32,
    pub vpl_count: u32,
    /// 0 for the first chunk of VPLs (the sums start from zero), 1 after.
    pub accumulate: u32,
    /// d_c², the geometry term's clamp.
    pub clamp2: f32,
    pub map_res: u32,
    pub map_bias: f32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// A pixel sample on a receiver for the VPL pass: its point, geometric normal, shading frame,
/// the direction to the eye in that frame and its material.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSurfacePoint {
    pub p: [f32; 3],
    pub material: u32,
    pub ng: [f32; 3],
    pub _pad0: f32,
    pub t: [f32; 3],
    pub _pad1: f32,
    pub b: [f32; 3],
    pub _pad2: f32,
    pub n: [f32; 3],
    pub _pad3: f32,
    pub wo: [f32; 3],
    pub _pad4: f32,
}

impl GpuSurfacePoint {
    /// A surface point `p` with geometric normal `ng`, shading frame `frame`, the direction to
    /// the eye `wo_local` in that frame and material index `material`.
    pub fn new(
        p: glam::Vec3,
        ng: glam::Vec3,
        frame: &crate::math::Frame,
        wo_local: glam::Vec3,
        material: u32,
    ) -> GpuSurfacePoint {
        GpuSurfacePoint {
            p: p.to_array(),
            material,
            ng: ng.to_array(),
            t: frame.t.to_array(),
            b: frame.b.to_array(),
            n: frame.n.to_array(),
            wo: wo_local.to_array(),
            ..GpuSurfacePoint::default()
        }
    }
}

/// A VPL (`precompute::vpl::Vpl`) with its shading frame, the direction to its light in that
/// frame, its material and its imperfect shadow map (`map`, `u32::MAX` for none, and the map's
/// origin).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVpl {
    pub position: [f32; 3],
    pub material: u32,
    pub normal: [f32; 3],
    pub map: u32,
    pub t: [f32; 3],
    pub _pad0: f32,
    pub b: [f32; 3],
    pub _pad1: f32,
    pub n: [f32; 3],
    pub _pad2: f32,
    pub wi: [f32; 3],
    pub _pad3: f32,
    pub power: [f32; 3],
    pub _pad4: f32,
    /// The origin of its imperfect shadow map (filled in by `super::vpl::shade`).
    pub origin: GpuMapOrigin,
}

/// What the VPL pass sums per point: the radiance and the pair counts of `VplStats`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVplSum {
    pub radiance: [f32; 3],
    pub pairs: u32,
    pub clamped: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// A light (`scene::Light`): `kind` 0 point, 1 spot, 2 directional; `intensity` is the
/// directional light's irradiance; `map` indexes the shadow maps (`u32::MAX`: none).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub cos_cone: f32,
    pub intensity: [f32; 3],
    pub cos_falloff: f32,
    pub map: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

impl From<&crate::scene::Light> for GpuLight {
    fn from(l: &crate::scene::Light) -> Self {
        use crate::scene::Light;
        let mut g = GpuLight {
            map: u32::MAX,
            ..GpuLight::default()
        };
        match *l {
            Light::Point {
                position,
                intensity,
            } => {
                g.position = position.to_array();
                g.intensity = intensity.to_array();
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cos_cone,
                cos_falloff,
            } => {
                g.kind = 1;
                g.position = position.to_array();
                g.direction = direction.to_array();
                g.intensity = intensity.to_array();
                g.cos_cone = cos_cone;
                g.cos_falloff = cos_falloff;
            }
            Light::Directional {
                direction,
                irradiance,
            } => {
                g.kind = 2;
                g.direction = direction.to_array();
                g.intensity = irradiance.to_array();
            }
        }
        g
    }
}

/// A variance shadow map (`visibility::vsm::VarianceShadowMap`): `projection` 0 cube (six
/// faces about `origin`), 1 perspective (`scale` = tan of the half-angle), 2 orthographic
/// (`scale` = the half-extent); its moments start at texel `first_texel` of the moments buffer,
/// face after face; face k looks along `forward[k]` with `right[k]`, `up[k]` spanning it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuShadowMap {
    pub origin: [f32; 3],
    pub projection: u32,
    pub res: u32,
    pub first_texel: u32,
    pub margin: f32,
    pub min_variance: f32,
    pub bleeding: f32,
    pub scale: f32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub forward: [[f32; 4]; 6],
    pub right: [[f32; 4]; 6],
    pub up: [[f32; 4]; 6],
}

/// A reflector triangle VPLs can sit on (`precompute::vpl::VplSource`; `super::vpl_gen`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVplSource {
    pub v0: [f32; 3],
    pub _pad0: u32,
    pub v1: [f32; 3],
    pub _pad1: u32,
    pub v2: [f32; 3],
    pub _pad2: u32,
    /// Diffuse + specular colour of its material.
    pub albedo: [f32; 3],
    pub _pad3: u32,
}

/// The VPL-weight pass's uniform (`super::vpl_gen`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVplGenParams {
    pub count: u32,
    /// The scene's ray epsilon: the shadow-map lookup is offset by it towards the light.
    pub eps: f32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// The imperfect-shadow-map pass's uniform (`super::ism`), one per dispatch: every map at
/// once (workgroup row y = map), one phase (entry point) each.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuIsmParams {
    /// Texels per side of each map.
    pub res: u32,
    pub points_per_map: u32,
    /// Maps in this dispatch.
    pub maps: u32,
    /// Entries of one map's pull-push pyramid (its levels' texels, finest first).
    pub pyramid_len: u32,
    /// 1 for the 3 × 3 blur after pull-push.
    pub blur: u32,
    /// `visibility::ism::FRONT_LAYER`.
    pub front_layer: f32,
    /// Pull and push: the level's texels per side and its first entry in the pyramid.
    pub level_n: u32,
    pub level_offset: u32,
    /// Pull: the finer level it sums; push: the coarser level holes take from.
    pub other_n: u32,
    pub other_offset: u32,
    /// Push: 1 when there is a coarser level.
    pub has_other: u32,
    pub _pad0: u32,
}

/// The direct-light pass's uniform (`super::direct`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuDirectParams {
    pub count: u32,
    pub light_count: u32,
    /// The scene's ray epsilon: shadow-map lookups are offset by it off the surface and
    /// towards the light.
    pub eps: f32,
    pub _pad0: u32,
}

/// A struct's name, size and (member, offset) list, for comparison with the shaders.
#[derive(Clone, Debug, PartialEq)]
pub struct StructLayout {
    pub name: &'static str,
    pub size: usize,
    pub members: Vec<(&'static str, usize)>,
}

macro_rules! layout {
    ($t:ident { $($m:ident),* $(,)? }) => {
        StructLayout {
            name: stringify!($t),
            size: size_of::<$t>(),
            members: vec![$((stringify!($m), offset_of!($t, $m))),*],
        }
    };
}

/// Every shared struct's Rust layout.
pub fn layouts() -> Vec<StructLayout> {
    vec![
        layout!(GpuSg {
            axis,
            sharpness,
            amplitude,
            _pad
        }),
        layout!(TwinQuery { a, b, c, d }),
        layout!(GpuNodeBound {
            bbox_min,
            has_cone,
            bbox_max,
            cone_half_angle,
            cone_axis,
            _pad0,
            image_min,
            _pad1,
            image_max,
            _pad2,
            diffuse,
            _pad3,
            peak_by_sharpness
        }),
        layout!(GpuVsmFace {
            forward,
            margin,
            right,
            far,
            up,
            scale,
            light,
            orthographic
        }),
        layout!(GpuBlurParams {
            resolution,
            radius,
            vertical,
            _pad
        }),
        layout!(GpuTonemapParams {
            scale,
            tone_operator,
            count,
            row_stride
        }),
        layout!(GpuCamera {
            position,
            tan_half,
            forward,
            aspect,
            right,
            far,
            up,
            _pad
        }),
        layout!(GpuReceiver {
            normal,
            stretch,
            diffuse,
            lobe_count,
            lobes
        }),
        layout!(TwinParams {
            function,
            count,
            _pad0,
            _pad1
        }),
        layout!(GpuShadeParams {
            light_pos,
            count,
            first,
            point_first,
            point_end,
            map_res,
            map_bias,
            leaf_first,
            cluster_count,
            cluster_first
        }),
        layout!(GpuShadePoint {
            x,
            cut_start,
            xo,
            cut_count,
            across,
            pair_start,
            receiver,
            leaf_count,
            leaf_pair_start,
            _pad0,
            _pad1
        }),
        layout!(GpuNodeLobe {
            energy,
            inv_sharpness_sum,
            axis_sum,
            _pad
        }),
        layout!(GpuLitNode {
            bound,
            centroid,
            weight,
            normal_sum,
            area,
            diffuse,
            leaf,
            lobes,
            half_vector,
            map,
            _pad0,
            _pad1
        }),
        layout!(GpuLeaf {
            v0,
            has_sg,
            v1,
            lobe_count,
            v2,
            half_vector,
            diffuse,
            stretch,
            normal,
            _pad0,
            geometric_normal,
            _pad1,
            origin,
            _pad2,
            light,
            _pad3,
            lobes
        }),
        layout!(GpuMapOrigin {
            position,
            min_variance,
            t,
            _pad0,
            b,
            _pad1,
            n,
            _pad2
        }),
        layout!(GpuBrdf {
            diffuse,
            model,
            specular,
            param,
            distribution,
            _pad0,
            _pad1,
            _pad2
        }),
        layout!(GpuVplParams {
            count,
            vpl_count,
            accumulate,
            clamp2,
            map_res,
            map_bias,
            _pad0,
            _pad1
        }),
        layout!(GpuSurfacePoint {
            p,
            material,
            ng,
            _pad0,
            t,
            _pad1,
            b,
            _pad2,
            n,
            _pad3,
            wo,
            _pad4
        }),
        layout!(GpuVpl {
            position,
            material,
            normal,
            map,
            t,
            _pad0,
            b,
            _pad1,
            n,
            _pad2,
            wi,
            _pad3,
            power,
            _pad4,
            origin
        }),
        layout!(GpuLight {
            position,
            kind,
            direction,
            cos_cone,
            intensity,
            cos_falloff,
            map,
            _pad0,
            _pad1,
            _pad2
        }),
        layout!(GpuShadowMap {
            origin,
            projection,
            res,
            first_texel,
            margin,
            min_variance,
            bleeding,
            scale,
            _pad0,
            _pad1,
            forward,
            right,
            up
        }),
        layout!(GpuDirectParams {
            count,
            light_count,
            eps,
            _pad0
        }),
        layout!(GpuVplSource {
            v0,
            _pad0,
            v1,
            _pad1,
            v2,
            _pad2,
            albedo,
            _pad3
        }),
        layout!(GpuIsmParams {
            res,
            points_per_map,
            maps,
            pyramid_len,
            blur,
            front_layer,
            level_n,
            level_offset,
            other_n,
            other_offset,
            has_other,
            _pad0
        }),
        layout!(GpuVplGenParams {
            count,
            eps,
            _pad0,
            _pad1
        }),
        layout!(GpuVplSum {
            radiance,
            pairs,
            clamped,
            _pad0,
            _pad1,
            _pad2
        }),
    ]
}

impl GpuReceiver {
    pub fn new(rx: &crate::sg::transport::receiver::ReceiverLobes) -> GpuReceiver {
        let mut lobes = [GpuSg::default(); 4];
        for (slot, l) in lobes.iter_mut().zip(rx.lobes()) {
            *slot = GpuSg::from(*l);
        }
        GpuReceiver {
            normal: rx.normal.to_array(),
            stretch: rx.stretch(),
            diffuse: rx.diffuse.to_array(),
            lobe_count: rx.lobes().len().min(4) as u32,
            lobes,
        }
    }
}

impl GpuNodeBound {
    /// Node `i` of a lit scene.
    pub fn new(lit: &crate::sg::LitScene, i: u32) -> GpuNodeBound {
        let n = &lit.tree.nodes[i as usize];
        let l = &lit.nodes[i as usize];
        let (has_cone, axis, half) = match n.cone {
            Some(c) => (1.0, c.axis.to_array(), c.half_angle),
            None => (0.0, [0.0; 3], 0.0),
        };
        let mut peaks = [[0.0; 4]; 6];
        for (p, v) in peaks.iter_mut().zip(&l.peak_by_sharpness) {
            *p = [v.x, v.y, v.z, 0.0];
        }
        GpuNodeBound {
            bbox_min: n.bbox_min.to_array(),
            has_cone,
            bbox_max: n.bbox_max.to_array(),
            cone_half_angle: half,
            cone_axis: axis,
            image_min: l.image_min.to_array(),
            image_max: l.image_max.to_array(),
            diffuse: l.diffuse.to_array(),
            peak_by_sharpness: peaks,
            ..GpuNodeBound::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::{Brdf, Distribution};
    use glam::Vec3;

    /// The override compiles the models the materials use and no other: a scene of Lambert and
    /// GGX Cook-Torrance gets bits 0, 4 and 6; every model and distribution has its own bit.
    #[test]
    fn brdf_models_names_the_models_used() {
        let lambert = Brdf::Lambert {
            diffuse: Vec3::splat(0.5),
        };
        let ct = |distribution| Brdf::CookTorrance {
            diffuse: Vec3::ZERO,
            specular: Vec3::splat(0.9),
            roughness: 0.2,
            distribution,
        };
        let gpu = |b: &[Brdf]| brdf_models(&b.iter().map(GpuBrdf::from).collect::<Vec<_>>());
        assert_eq!(gpu(&[lambert, ct(Distribution::Ggx)]), 0b101_0001);
        assert_eq!(gpu(&[ct(Distribution::Beckmann)]), 0b011_0000);
        let phong = Brdf::Phong {
            diffuse: Vec3::ZERO,
            specular: Vec3::ONE,
            exponent: 20.0,
        };
        let blinn = Brdf::BlinnPhong {
            diffuse: Vec3::ZERO,
            specular: Vec3::ONE,
            exponent: 20.0,
        };
        let ward = Brdf::Ward {
            diffuse: Vec3::ZERO,
            specular: Vec3::ONE,
            roughness: 0.1,
        };
        assert_eq!(gpu(&[phong]), 0b10);
        assert_eq!(gpu(&[blinn, ward]), 0b1100);
        assert_eq!(gpu(&[]), 0);
    }
}
