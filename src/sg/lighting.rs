//! The lighting stage of a frame (Xu et al. 2014, §4 and §6): every reflector piece lit by one
//! light as an SG reflector ([`LitTriangle`]), and the lit data summed up the tree
//! ([`LitNode`]) into a [`LitScene`], which the bound, the node approximation and the cut
//! selection read. Details: `docs/sg-renderer.md`.

use super::pieces::ReflectorPiece;
use super::transport::receiver::{ReceiverLobes, ReceiverOptions, one_bounce_with};
use super::transport::reflector::{
    ReflectedSg, Reflector, aim_at_receiver, reflected_sg_light_shaded,
};
use super::tree::ReflectorTree;
use crate::brdf::sg_fit::MAX_LOBES;
use crate::math::luminance;
use crate::scene::{Light, Scene};
use glam::Vec3;
use rayon::prelude::*;

/// One reflector triangle lit by one light.
#[derive(Clone, Copy, Debug)]
pub struct LitTriangle {
    /// Scene triangle index.
    pub tri: u32,
    pub vertices: [Vec3; 3],
    /// Reflected radiance as SG lobes; `None` when unlit (shadowed, facing edge-on, degenerate).
    pub sg: Option<ReflectedSg>,
    /// The light's visibility the lobes were scaled by (mean over the triangle), so that a
    /// renderer can swap it for the visibility at the point that matters.
    pub light_visibility: f32,
    /// Which of [`LitTriangle::visibility_points`] the light reaches (bit k for point k).
    pub light_mask: u8,
}

/// The four points of triangle (a, b, c) the light's visibility is sampled at: the centroid and
/// the centroids of the three corner sub-triangles.
pub fn visibility_points([a, b, c]: [Vec3; 3]) -> [Vec3; 4] {
    [
        (a + b + c) / 3.0,
        (4.0 * a + b + c) / 6.0,
        (a + 4.0 * b + c) / 6.0,
        (a + b + 4.0 * c) / 6.0,
    ]
}

impl LitTriangle {
    /// [`visibility_points`] of this triangle.
    pub fn visibility_points(&self) -> [Vec3; 4] {
        visibility_points(self.vertices)
    }

    /// The SG transport of this triangle to receiver point `x` (no visibility): the lobes
    /// re-aimed at x, integrated over the triangle's solid angle. This is what `sg-brute`
    /// sums and what a leaf of the cut contributes.
    pub fn shade(&self, x: Vec3, rx: &ReceiverLobes, opts: &ReceiverOptions) -> Vec3 {
        match &self.sg {
            Some(s) => one_bounce_with(&aim_at_receiver(s, x), self.vertices, x, rx, opts),
            None => Vec3::ZERO,
        }
    }

    /// Σ over the triangle of (peak reflected radiance) × area, per channel: the triangle's
    /// share of a node's bound.
    pub fn peak_power(&self) -> Vec3 {
        let Some(s) = &self.sg else {
            return Vec3::ZERO;
        };
        let [a, b, c] = self.vertices;
        let area = 0.5 * (b - a).cross(c - a).length();
        let peak = s.lobes().iter().fold(s.diffuse, |acc, l| acc + l.amplitude);
        peak * area
    }
}

/// Per-slot sums of the lobes under a node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeLobe {
    /// Σ A_i μ_i / λ_i (the lobes' energy × area, up to 2π), RGB: conserved when lobes merge.
    /// Its luminance is the sum of the merge weights w_i = luminance(A_i μ_i) / λ_i.
    pub energy: Vec3,
    /// Σ w_i p_i (p_i the lobe axes): its length / Σ w_i is the mean resultant length R.
    pub axis_sum: Vec3,
    /// Σ w_i / λ_i: the weighted mean of 1/λ (the lobe's angular variance).
    pub inv_sharpness_sum: f32,
}

/// The lit state of one tree node: sums over its triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LitNode {
    /// Lit area Σ A_i (triangles with light).
    pub area: f32,
    /// Σ A_i n_i over lit triangles, n_i the lit side's unit normal.
    pub normal_sum: Vec3,
    /// Σ A_i d_i (diffuse radiance × area), RGB.
    pub diffuse: Vec3,
    /// Σ w_i c_i with w_i = luminance of the triangle's peak power
    /// ([`LitTriangle::peak_power`]): the centroid of the light.
    pub centroid_sum: Vec3,
    /// Σ w_i; zero when nothing under the node is lit.
    pub weight: f32,
    pub lobes: [NodeLobe; MAX_LOBES],
    /// Tree-order position of the representative leaf (the brightest triangle's), the target of
    /// the node's visibility ray.
    pub rep: u32,
    /// luminance of the representative's peak power.
    pub rep_power: f32,
    /// Σ A_i μ_ik (peak radiance × area, RGB) of every lobe, binned by its sharpness: bin b holds
    /// the lobes with λ ≥ [`SHARPNESS_BINS`][b] (and below the next edge). The bound lets each
    /// bin fall off with its lower edge, so one wide lobe does not loosen the bound of the sharp
    /// ones.
    pub peak_by_sharpness: [Vec3; SHARPNESS_BINS.len()],
    /// Bounding box of the light's mirror images in the planes of the triangles with lobes
    /// (empty: min > max): every such triangle's lobes, re-aimed at a receiver x, peak towards
    /// x → its image.
    pub image_min: Vec3,
    pub image_max: Vec3,
    /// Every lit triangle with lobes has half-vector lobes (anisotropic when reflected
    /// obliquely; see [`crate::brdf::Brdf::has_half_vector_lobe`]).
    pub half_vector: bool,
}

impl Default for LitNode {
    fn default() -> Self {
        LitNode {
            area: 0.0,
            normal_sum: Vec3::ZERO,
            diffuse: Vec3::ZERO,
            centroid_sum: Vec3::ZERO,
            weight: 0.0,
            lobes: [NodeLobe::default(); MAX_LOBES],
            rep: 0,
            rep_power: 0.0,
            image_min: Vec3::splat(f32::INFINITY),
            image_max: Vec3::splat(f32::NEG_INFINITY),
            peak_by_sharpness: [Vec3::ZERO; SHARPNESS_BINS.len()],
            half_vector: true,
        }
    }
}

/// Lower edges of the sharpness bins of [`LitNode::peak_by_sharpness`].
pub const SHARPNESS_BINS: [f32; 6] = [0.0, 2.0, 8.0, 32.0, 128.0, 512.0];

fn sharpness_bin(lambda: f32) -> usize {
    SHARPNESS_BINS
        .iter()
        .rposition(|&edge| lambda >= edge)
        .unwrap_or(0)
}

impl Default for NodeLobe {
    fn default() -> Self {
        NodeLobe {
            energy: Vec3::ZERO,
            axis_sum: Vec3::ZERO,
            inv_sharpness_sum: 0.0,
        }
    }
}

impl LitNode {
    pub(crate) fn from_triangle(t: &LitTriangle, pos: u32) -> LitNode {
        let mut n = LitNode {
            rep: pos,
            ..LitNode::default()
        };
        let Some(s) = &t.sg else {
            return n;
        };
        let [a, b, c] = t.vertices;
        let area = 0.5 * (b - a).cross(c - a).length();
        n.area = area;
        n.normal_sum = s.normal * area;
        n.diffuse = s.diffuse * area;
        let w = luminance(t.peak_power()).max(0.0);
        n.weight = w;
        n.rep_power = w;
        n.centroid_sum = s.origin * w;
        n.half_vector = s.half_vector || s.len == 0;
        if s.len > 0 {
            let image = s.light - 2.0 * (s.light - s.origin).dot(s.normal) * s.normal;
            n.image_min = image;
            n.image_max = image;
        }
        // The smallest sharpness a lobe of this triangle has in any direction at any receiver:
        // an anisotropic (half-vector) lobe is λ_h/4 · (1 + d_x/d_l)² ≥ λ cos θ_l wide in the
        // plane of incidence (`transport::aim_at_receiver`), λ the isotropic warp's sharpness.
        let widest = if s.half_vector {
            s.light_cosine().clamp(0.0, 1.0)
        } else {
            1.0
        };
        for (slot, l) in n.lobes.iter_mut().zip(s.lobes()) {
            let amp = l.amplitude * area;
            let lam = l.sharpness.max(1e-6);
            let wk = luminance(amp).max(0.0) / lam;
            *slot = NodeLobe {
                energy: amp / lam,
                axis_sum: l.axis * wk,
                inv_sharpness_sum: wk / lam,
            };
            n.peak_by_sharpness[sharpness_bin(l.sharpness.max(0.0) * widest)] += amp;
        }
        n
    }

    pub(crate) fn merge(a: &LitNode, b: &LitNode) -> LitNode {
        let mut lobes = [NodeLobe::default(); MAX_LOBES];
        for (k, l) in lobes.iter_mut().enumerate() {
            let (x, y) = (&a.lobes[k], &b.lobes[k]);
            *l = NodeLobe {
                energy: x.energy + y.energy,
                axis_sum: x.axis_sum + y.axis_sum,
                inv_sharpness_sum: x.inv_sharpness_sum + y.inv_sharpness_sum,
            };
        }
        let (rep, rep_power) = if b.rep_power > a.rep_power {
            (b.rep, b.rep_power)
        } else {
            (a.rep, a.rep_power)
        };
        LitNode {
            area: a.area + b.area,
            normal_sum: a.normal_sum + b.normal_sum,
            diffuse: a.diffuse + b.diffuse,
            centroid_sum: a.centroid_sum + b.centroid_sum,
            weight: a.weight + b.weight,
            lobes,
            rep,
            rep_power,
            image_min: a.image_min.min(b.image_min),
            image_max: a.image_max.max(b.image_max),
            peak_by_sharpness: std::array::from_fn(|k| {
                a.peak_by_sharpness[k] + b.peak_by_sharpness[k]
            }),
            half_vector: a.half_vector && b.half_vector,
        }
    }
}

/// Everything the cut needs for one light in one frame: the lit triangles in tree order and
/// the lit sums of every node.
pub struct LitScene<'a> {
    pub tree: &'a ReflectorTree,
    /// Lit triangles in tree order (`tree.tri_order`).
    pub tris: Vec<LitTriangle>,
    /// Lit sums per tree node (same indices as `tree.nodes`).
    pub nodes: Vec<LitNode>,
    /// Position the reflected lobes were aimed from (the light, or a far point for a
    /// directional light).
    pub light_pos: Vec3,
    pub receiver: ReceiverOptions,
}

/// Lights the reflector pieces `order` (indices into `pieces`, e.g. a tree's `tri_order`) with
/// `light`; `visible(point, tri)` is the light's visibility in [0, 1] at a point of a triangle
/// (a shadow ray, or a shadow map's lit fraction); `light_mask` marks the points more than half
/// lit. A piece's visibility is the mean over its centroid and the
/// centroids of its three corner sub-triangles, so that a triangle half in shadow (e.g. a floor
/// triangle under the foot of an object) reflects about half its light rather than all or
/// nothing.
pub fn light_triangles(
    scene: &Scene,
    pieces: &[ReflectorPiece],
    order: &[u32],
    light: &Light,
    visible: &(dyn Fn(Vec3, u32) -> f32 + Sync),
) -> Vec<LitTriangle> {
    let scale = scene.mesh.diagonal().max(1e-3);
    order
        .par_iter()
        .map(|&i| {
            let piece = &pieces[i as usize];
            let t = piece.tri;
            let refl = Reflector {
                vertices: piece.vertices,
                brdf: *scene.tri_material(t),
            };
            let c = refl.centroid();
            let mut vis = 0.0;
            let mut mask = 0u8;
            let sg = match light.incident(c) {
                Some(_) => {
                    let mut sum = 0.0;
                    for (k, &p) in visibility_points(refl.vertices).iter().enumerate() {
                        let f = visible(p, t).clamp(0.0, 1.0);
                        sum += f;
                        if f > 0.5 {
                            mask |= 1 << k;
                        }
                    }
                    let v = 0.25 * sum;
                    vis = v;
                    if v > 0.0 {
                        reflected_sg_light_shaded(&refl, Some(piece.normals), light, v, scale)
                    } else {
                        None
                    }
                }
                None => None,
            };
            LitTriangle {
                tri: t,
                vertices: refl.vertices,
                sg,
                light_visibility: vis,
                light_mask: mask,
            }
        })
        .collect()
}

/// The position reflected lobes are aimed from for `light` (see [`reflected_sg_light`]).
pub fn light_anchor(scene: &Scene, light: &Light) -> Vec3 {
    match light.position() {
        Some(p) => p,
        None => {
            let (lo, hi) = scene.mesh.bounds();
            let scale = (hi - lo).length().max(1e-3);
            let c = 0.5 * (lo + hi);
            let inc = light.incident(c).expect("directional lights always reach");
            c + inc.wi * (1e5 * scale)
        }
    }
}

impl<'a> LitScene<'a> {
    /// Sums the lit triangles (`tris`, in tree order) up the tree.
    pub fn new(
        tree: &'a ReflectorTree,
        tris: Vec<LitTriangle>,
        light_pos: Vec3,
        receiver: ReceiverOptions,
    ) -> LitScene<'a> {
        assert_eq!(tris.len(), tree.tri_order.len());
        let mut nodes = vec![LitNode::default(); tree.nodes.len()];
        // Pre-order: children have larger indices than their parent.
        for i in (0..tree.nodes.len()).rev() {
            let n = &tree.nodes[i];
            nodes[i] = match n.children {
                None => LitNode::from_triangle(&tris[n.first as usize], n.first),
                Some([l, r]) => LitNode::merge(&nodes[l as usize], &nodes[r as usize]),
            };
        }
        LitScene {
            tree,
            tris,
            nodes,
            light_pos,
            receiver,
        }
    }
}
