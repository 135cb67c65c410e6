//! The per-frame cut through the reflector tree (Xu et al. 2014, §6): every frame, each
//! reflector triangle is lit as an SG reflector ([`LitScene`]), the lit data are summed up the
//! tree, and at every receiver point a *cut* — a set of nodes that partitions the reflector
//! triangles — is chosen by refining the node with the largest error bound until every bound is
//! below a fraction of the estimate, or the cut reaches its size cap.
//!
//! - A leaf (one triangle) is shaded exactly as `sg-brute` shades it: its lobes re-aimed at the
//!   receiver (mirror image) and integrated over the triangle's solid angle. Leaves have no
//!   approximation error.
//! - An internal node is shaded as one reflector: its lit power, normal and lobes summed over its
//!   triangles, the lobes merged per slot (von Mises–Fisher moment matching), its solid angle
//!   represented by an SG "cap", and every product integrated in closed form over the sphere.
//! - The bound of a node at x is an upper bound of every leaf's contribution summed, from the
//!   node's summed peak radiance × area, the receiver lobes' maximum over the node's bounding
//!   sphere and the distance to its bounding box; the node's approximation is clamped to the same
//!   bound, so the bound is never below the true error (both lie in [0, bound]).
//!
//! Details and measurements: `docs/sg-renderer.md`.

use crate::brdf::sg_fit::MAX_LOBES;
use crate::math::sg::{Sg, lobe_integral};
use crate::precompute::tree::{Node, ReflectorTree, TriInput};
use crate::scene::{Light, Scene};
use crate::transport::receiver::{
    Anisotropic, MAX_STRETCH, ReceiverLobes, ReceiverOptions, one_bounce_with,
};
use crate::transport::reflector::{
    ReflectedSg, Reflector, aim_at_receiver, reflected_sg_light_shaded,
};
use glam::Vec3;
use rayon::prelude::*;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

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

/// Rec. 709 luminance: the scalar that errors and estimates are compared in.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

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
    fn from_triangle(t: &LitTriangle, pos: u32) -> LitNode {
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

    fn merge(a: &LitNode, b: &LitNode) -> LitNode {
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

/// A reflector triangle as the SG transport sees it: a scene triangle, or a piece of one when
/// it is split to keep the reflected radiance nearly constant across each piece.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectorPiece {
    /// Scene triangle it belongs to (material, object).
    pub tri: u32,
    pub vertices: [Vec3; 3],
    /// Shading normals at the corners (interpolated from the scene triangle's).
    pub normals: [Vec3; 3],
}

/// Most times a scene triangle is split (into at most 4⁵ = 1024 pieces).
pub const MAX_SPLIT_LEVELS: usize = 5;

/// The scene's reflector triangles, each split at its edge midpoints into 4, recursively, until
/// its longest edge is at most `max_edge` (0 = no splitting; at most [`MAX_SPLIT_LEVELS`]
/// levels). The SG transport lights a triangle at its
/// centroid and reflects a constant radiance across it; a large floor triangle under a point
/// light, seen in a glossy receiver, would show as a flat facet.
pub fn reflector_pieces(scene: &Scene, max_edge: f32) -> Vec<ReflectorPiece> {
    let ids: Vec<u32> = scene
        .objects
        .iter()
        .filter(|o| o.reflector)
        .flat_map(|o| o.first_tri..o.first_tri + o.tri_count)
        .collect();
    ids.par_iter()
        .flat_map_iter(|&t| {
            let idx = scene.mesh.indices[t as usize];
            let root = ReflectorPiece {
                tri: t,
                vertices: scene.mesh.tri(t),
                normals: idx.map(|i| scene.mesh.normals[i as usize]),
            };
            let mut out = vec![root];
            if max_edge > 0.0 {
                for _ in 0..MAX_SPLIT_LEVELS {
                    let longest = |p: &ReflectorPiece| {
                        let [a, b, c] = p.vertices;
                        (b - a).length().max((c - b).length()).max((a - c).length())
                    };
                    if out.iter().all(|p| longest(p) <= max_edge) {
                        break;
                    }
                    out = out.iter().flat_map(split4).collect();
                }
            }
            out
        })
        .collect()
}

fn split4(p: &ReflectorPiece) -> [ReflectorPiece; 4] {
    let [a, b, c] = p.vertices;
    let [na, nb, nc] = p.normals;
    let mid = |x: Vec3, y: Vec3| 0.5 * (x + y);
    let nmid = |x: Vec3, y: Vec3| (x + y).normalize_or_zero();
    let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
    let (nab, nbc, nca) = (nmid(na, nb), nmid(nb, nc), nmid(nc, na));
    let piece = |vertices, normals| ReflectorPiece {
        tri: p.tri,
        vertices,
        normals,
    };
    [
        piece([a, ab, ca], [na, nab, nca]),
        piece([ab, b, bc], [nab, nb, nbc]),
        piece([ca, bc, c], [nca, nbc, nc]),
        piece([ab, bc, ca], [nab, nbc, nca]),
    ]
}

/// The tree over reflector pieces (its `tri_order` holds piece indices).
pub fn build_tree(scene: &Scene, pieces: &[ReflectorPiece]) -> ReflectorTree {
    let inputs: Vec<TriInput> = pieces
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let brdf = scene.tri_material(p.tri);
            let [a, b, c] = p.vertices;
            TriInput {
                v: p.vertices,
                normal: (b - a).cross(c - a).normalize_or_zero(),
                albedo: brdf.diffuse() + brdf.specular(),
                material: scene.tri_object(p.tri).material,
                tri: i as u32,
            }
        })
        .collect();
    crate::precompute::tree::build_from(&inputs)
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

    /// Upper bound (per channel) of the summed SG contribution of the triangles under `node` at
    /// receiver `x`, without visibility (visibility only lowers it). Zero for a leaf, whose
    /// value is exact; infinite when x lies inside the node's bounding box.
    pub fn bound(&self, node: u32, x: Vec3, rx: &ReceiverLobes) -> Vec3 {
        let n = &self.tree.nodes[node as usize];
        let lit = &self.nodes[node as usize];
        if n.is_leaf() || !(lit.weight > 0.0) {
            return Vec3::ZERO;
        }
        node_bound(n, lit, x, rx)
    }

    /// The factors of [`Self::bound`] (see `node_bound_parts`), for diagnostics.
    #[cfg(test)]
    pub(crate) fn bound_parts(&self, node: u32, x: Vec3, rx: &ReceiverLobes) -> [f32; 6] {
        let mut parts = [0.0; 6];
        let n = &self.tree.nodes[node as usize];
        node_bound_parts(n, &self.nodes[node as usize], x, rx, Some(&mut parts));
        parts
    }

    /// The node's approximate contribution at `x` (no visibility), clamped to `bound`. A leaf
    /// gives its exact SG transport.
    pub fn approx(&self, node: u32, x: Vec3, rx: &ReceiverLobes, bound: Vec3) -> Vec3 {
        let n = &self.tree.nodes[node as usize];
        if n.is_leaf() {
            return self.tris[n.first as usize].shade(x, rx, &self.receiver);
        }
        self.cluster(node, x, rx).min(bound)
    }

    /// A node shaded as one reflector (before clamping).
    pub fn cluster(&self, node: u32, x: Vec3, rx: &ReceiverLobes) -> Vec3 {
        let lit = &self.nodes[node as usize];
        if !(lit.weight > 0.0 && lit.area > 0.0) {
            return Vec3::ZERO;
        }
        let c = lit.centroid_sum / lit.weight;
        let v = x - c;
        let d2 = v.length_squared();
        if !(d2 > 0.0) {
            return Vec3::ZERO;
        }
        let r = v / d2.sqrt(); // node → x
        let proj = lit.normal_sum.dot(r) / lit.area;
        if !(proj > 0.0) {
            return Vec3::ZERO;
        }
        // The node's solid angle from x, as a unit-height SG cap with the same integral.
        let omega = (lit.area * proj / d2).clamp(1e-12, 2.0 * std::f32::consts::PI);
        let cap_sharp = 2.0 * std::f32::consts::PI / omega;
        let cap = Sg::new(-r, cap_sharp, Vec3::splat(omega / lobe_integral(cap_sharp)));
        let inv_area = 1.0 / lit.area;
        let aniso = self.receiver.anisotropic;
        let cap_a = Anisotropic::isotropic(&cap);
        let mut incoming = [cap_a; MAX_LOBES + 1];
        let mut count = 0;
        if lit.diffuse != Vec3::ZERO {
            let mut d = cap;
            d.amplitude *= lit.diffuse * inv_area;
            incoming[0] = Anisotropic::isotropic(&d);
            count = 1;
        }
        // Mirror-image aiming about the node's mean plane (exact for a flat node).
        let nbar = lit.normal_sum.normalize_or_zero();
        let h_l = (self.light_pos - c).dot(nbar);
        let h_x = v.dot(nbar);
        // As `transport::aim_at_receiver` does for one triangle: half-vector lobes take the
        // incidence angle at the specular point (sharpness × cos θ_c / cos θ_s, stretch
        // 1/cos θ_s across the plane of incidence).
        let aim = if h_l > 0.0 && h_x > 0.0 {
            let image = self.light_pos - 2.0 * h_l * nbar;
            (x - image).try_normalize().map(|axis| {
                let d = (x - image).length();
                let d_l = d * h_l / (h_l + h_x);
                let mut scale = (1.0 + (d - d_l) / d_l).powi(2);
                let mut stretch = 1.0;
                if lit.half_vector && aniso {
                    let cos_c = h_l / (self.light_pos - c).length();
                    let cos_s = axis.dot(nbar).max(1.0 / MAX_STRETCH);
                    scale *= cos_c / cos_s;
                    stretch = 1.0 / cos_s;
                }
                (axis, scale, stretch)
            })
        } else {
            None
        };
        for l in &lit.lobes {
            let weight = luminance(l.energy);
            if !(weight > 0.0) {
                continue;
            }
            let mean_axis = l.axis_sum / weight;
            let rlen = mean_axis.length().min(1.0);
            // Outgoing-direction variance: the lobes' own plus the spread of their axes
            // (vMF: 1 − R ≈ 1/κ for a concentrated distribution).
            let own = l.inv_sharpness_sum / weight;
            let spread = 1.0 - rlen;
            let (axis, scale, stretch) = aim.unwrap_or((mean_axis.normalize_or_zero(), 1.0, 1.0));
            if axis == Vec3::ZERO {
                continue;
            }
            // Peak radiance of the merged lobe: its energy over its width (μ/λ is conserved).
            let var = (own + spread).max(1e-12);
            let lobe = Sg::new(-axis, scale / var, l.energy * (inv_area / var));
            let lobe = match (-axis).cross(nbar).try_normalize() {
                Some(t) if stretch > 1.0 => Anisotropic::new(&lobe, t, stretch),
                _ => Anisotropic::isotropic(&lobe),
            };
            incoming[count] = lobe.product(&cap_a);
            count += 1;
        }
        let n_x = rx.normal;
        let mut sum = Vec3::ZERO;
        for s in &incoming[..count] {
            let s0 = s.lobe();
            sum += rx.diffuse * s0.integral() * clamped_cosine_mean(n_x.dot(s0.axis), s0.sharpness);
            for h in rx.anisotropic_lobes(aniso) {
                let p = *s.product(&h).lobe();
                sum += p.integral() * clamped_cosine_mean(n_x.dot(p.axis), p.sharpness);
            }
        }
        sum
    }
}

/// Upper bound of Σ_i ∫_{Ω_i} L_i f_x cos dω over the triangles i under `n`: each triangle's
/// solid angle is at most A_i / d_min², the cosine at most 1, the receiver lobes at most their
/// maximum over the cone of directions to the node's bounding sphere, and the reflected
/// radiance at most its diffuse part plus each lobe's peak times its falloff: a triangle's lobes,
/// re-aimed at x, peak towards x → its light image and have at least their own sharpness (the
/// re-aiming only sharpens), so over the node they are at most exp(λ_min (cos γ − 1)) with γ the
/// smallest angle at x between the node's bounding sphere and the images' bounding sphere.
pub fn node_bound(n: &Node, lit: &LitNode, x: Vec3, rx: &ReceiverLobes) -> Vec3 {
    node_bound_parts(n, lit, x, rx, None)
}

/// [`node_bound`], with its factors written to `parts` when given (diagnostics): [luminance of
/// the radiance bound, of hmax, cos_max / d², gap (radians, −1 when none), image radius angle,
/// node half-angle].
fn node_bound_parts(
    n: &Node,
    lit: &LitNode,
    x: Vec3,
    rx: &ReceiverLobes,
    mut parts: Option<&mut [f32; 6]>,
) -> Vec3 {
    let (lo, hi) = (n.bbox_min, n.bbox_max);
    // Entirely below the receiver's horizon: nothing arrives (the transport clips to it).
    let nx = rx.normal;
    let mut above = false;
    for i in 0..8 {
        let corner = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        if nx.dot(corner - x) > 0.0 {
            above = true;
            break;
        }
    }
    if !above {
        return Vec3::ZERO;
    }
    let d2 = (x.clamp(lo, hi) - x).length_squared();
    if !(d2 > 0.0) {
        return Vec3::splat(f32::INFINITY);
    }
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let to_c = centre - x;
    let dist = to_c.length();
    let mut hmax = rx.diffuse;
    let cone = (dist > radius).then(|| (to_c / dist, (radius / dist).asin()));
    match cone {
        Some((dir, half)) => {
            // An anisotropic receiver lobe is wider by its stretch in one direction.
            let widest = 1.0 / rx.stretch();
            for h in rx.lobes() {
                let gap = (angle(h.axis, dir) - half).max(0.0);
                hmax += h.amplitude * (h.sharpness * widest * cos_minus_one(gap)).min(0.0).exp();
            }
        }
        None => {
            for h in rx.lobes() {
                hmax += h.amplitude;
            }
        }
    }
    let gap = match cone {
        Some((dir, half)) if lit.image_min.x <= lit.image_max.x => {
            let ic = 0.5 * (lit.image_min + lit.image_max);
            let ir = 0.5 * (lit.image_max - lit.image_min).length();
            let to_i = ic - x;
            let di = to_i.length();
            if let Some(p) = parts.as_deref_mut() {
                p[4] = (ir / di).min(1.0).asin();
                p[5] = half;
            }
            (di > ir).then(|| (angle(dir, to_i / di) - half - (ir / di).asin()).max(0.0))
        }
        _ => None,
    };
    let mut radiance = lit.diffuse;
    for (edge, peak) in SHARPNESS_BINS.iter().zip(&lit.peak_by_sharpness) {
        let f = match gap {
            Some(g) => (edge * cos_minus_one(g)).min(0.0).exp(),
            None => 1.0,
        };
        radiance += *peak * f;
    }
    // Each triangle's solid angle is ∫ cos θ_y / r² dA ≤ A cos_max / d²: the largest |cos| between
    // a normal of the cone (either orientation) and a direction from the box to x.
    let cos_max = match (cone, n.cone) {
        (Some((dir, half)), Some(c)) => {
            let g = angle(c.axis, dir);
            let g = g.min(std::f32::consts::PI - g);
            (g - c.half_angle - half).max(0.0).cos()
        }
        _ => 1.0,
    };
    if let Some(p) = parts {
        p[..4].copy_from_slice(&[
            luminance(radiance),
            luminance(hmax),
            cos_max / d2,
            gap.unwrap_or(-1.0),
        ]);
    }
    // 1e-3: headroom for the rounding of the f32 sums and of the quadrature (≤ 5e-7 relative).
    radiance * hmax * (1.001 * cos_max / d2)
}

/// cos γ − 1 as −2 sin²(γ/2): exact to rounding for small γ, where cos γ − 1 would cancel (and
/// an exponent λ (cos γ − 1) of a sharp lobe magnify the cancellation).
#[inline]
pub fn cos_minus_one(g: f32) -> f32 {
    let s = (0.5 * g).sin();
    -2.0 * s * s
}

/// E[max(0, n·ω)] under a lobe whose axis has n·p = `c` and sharpness λ: n·ω is treated as
/// normal with mean c and variance σ² = (1 − c²)/λ (the lobe's tangential variance 1/λ projected
/// on n), so E = c Φ(c/σ) + σ φ(c/σ). It tends to max(0, c) for sharp lobes and, unlike it, keeps
/// the light of a lobe that straddles the horizon.
pub fn clamped_cosine_mean(c: f32, sharpness: f32) -> f32 {
    let var = (1.0 - c * c).max(0.0) / sharpness.max(1e-6);
    let sigma = var.sqrt().min(1.0);
    if !(sigma > 1e-6) {
        return c.max(0.0);
    }
    let z = c / sigma;
    let pdf = (-0.5 * z * z).exp() * 0.398_942_3;
    let cdf = 0.5 * (1.0 + erf(z * std::f32::consts::FRAC_1_SQRT_2));
    (c * cdf + sigma * pdf).clamp(0.0, 1.0)
}

/// erf (Abramowitz & Stegun 7.1.26, absolute error ≤ 1.5e-7).
pub fn erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let y = 1.0
        - (((((1.061_405_4 * t - 1.453_152_1) * t) + 1.421_413_7) * t - 0.284_496_72) * t
            + 0.254_829_6)
            * t
            * (-x * x).exp();
    y.copysign(x)
}

#[inline]
fn angle(a: Vec3, b: Vec3) -> f32 {
    a.cross(b).length().atan2(a.dot(b))
}

/// A cut entry: a node and its contribution at the point the cut was chosen for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutEntry {
    pub node: u32,
    /// Approximate contribution (no visibility), clamped to the bound.
    pub value: Vec3,
    pub bound: Vec3,
}

/// Counters of one cut selection.
#[derive(Clone, Copy, Debug, Default)]
pub struct CutCounters {
    /// Nodes whose bound and approximation were evaluated.
    pub evaluated: u64,
    /// Of those, leaves (exact triangle integrations).
    pub leaves: u64,
}

struct Pending {
    key: f32,
    entry: CutEntry,
}

impl PartialEq for Pending {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Pending {}
impl PartialOrd for Pending {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Pending {
    fn cmp(&self, o: &Self) -> Ordering {
        // Larger bound first; ties by node index, so selection is deterministic.
        self.key
            .total_cmp(&o.key)
            .then_with(|| o.entry.node.cmp(&self.entry.node))
    }
}

impl LitScene<'_> {
    fn entry(&self, node: u32, x: Vec3, rx: &ReceiverLobes, c: &mut CutCounters) -> CutEntry {
        c.evaluated += 1;
        if self.tree.nodes[node as usize].is_leaf() {
            c.leaves += 1;
        }
        let bound = self.bound(node, x, rx);
        let value = self.approx(node, x, rx, bound);
        CutEntry { node, value, bound }
    }

    /// Selects the cut at receiver point `x` (METHOD §6): start from the root, repeatedly
    /// replace the node with the largest bound (luminance) by its two children, until that bound
    /// is at most `threshold` × the estimate's luminance or the cut holds `max_cut` nodes.
    /// Appends the cut to `out` (cleared first) and returns the estimate (no visibility).
    pub fn select(
        &self,
        x: Vec3,
        rx: &ReceiverLobes,
        opts: &CutOptions,
        out: &mut Vec<CutEntry>,
        c: &mut CutCounters,
    ) -> Vec3 {
        out.clear();
        if self.tree.nodes.is_empty() || rx.is_black() {
            return Vec3::ZERO;
        }
        let cap = if opts.max_cut == 0 {
            usize::MAX
        } else {
            opts.max_cut as usize
        };
        let mut heap = BinaryHeap::new();
        let mut size = 1usize;
        let root = self.entry(0, x, rx, c);
        let mut estimate = root.value;
        let push = |e: CutEntry, heap: &mut BinaryHeap<Pending>, out: &mut Vec<CutEntry>| {
            let key = luminance(e.bound);
            if key > 0.0 || key.is_nan() {
                heap.push(Pending {
                    key: if key.is_nan() { f32::INFINITY } else { key },
                    entry: e,
                });
            } else {
                out.push(e);
            }
        };
        push(root, &mut heap, out);
        while let Some(top) = heap.peek() {
            if size >= cap || top.key <= opts.threshold * luminance(estimate).max(0.0) {
                break;
            }
            let top = heap.pop().expect("peeked").entry;
            let Some([l, r]) = self.tree.nodes[top.node as usize].children else {
                out.push(top);
                continue;
            };
            estimate -= top.value;
            for child in [l, r] {
                let e = self.entry(child, x, rx, c);
                estimate += e.value;
                push(e, &mut heap, out);
            }
            size += 1;
        }
        out.extend(heap.into_iter().map(|p| p.entry));
        // Re-sum in a fixed order (node index) so the result does not depend on the heap's.
        out.sort_unstable_by_key(|e| e.node);
        out.iter().fold(Vec3::ZERO, |a, e| a + e.value)
    }

    /// Evaluates a given cut (e.g. a neighbouring vertex's) at `x`: Σ clamped approximations.
    pub fn evaluate(
        &self,
        nodes: impl Iterator<Item = u32>,
        x: Vec3,
        rx: &ReceiverLobes,
        out: &mut Vec<CutEntry>,
        c: &mut CutCounters,
    ) -> Vec3 {
        out.clear();
        let mut sum = Vec3::ZERO;
        for n in nodes {
            let e = self.entry(n, x, rx, c);
            sum += e.value;
            out.push(e);
        }
        sum
    }

    /// The exact target of the cut: every lit triangle's SG transport summed (no visibility).
    pub fn brute_force(&self, x: Vec3, rx: &ReceiverLobes) -> Vec3 {
        self.tris
            .iter()
            .fold(Vec3::ZERO, |a, t| a + t.shade(x, rx, &self.receiver))
    }
}

#[cfg(test)]
pub(crate) mod tests;
