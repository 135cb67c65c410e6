//! The reflector tree: a binary tree over the scene's reflector triangles, split by PCA over
//! (centroid, scaled normal) features at the median, with per-node shading data and bounds
//! (Xu et al. 2014, §6). See `docs/tree.md`.
//!
//! Layout: a flat node array in pre-order, root at 0. A node covers the contiguous range
//! `first..first + count` of [`ReflectorTree::tri_order`]; a leaf covers exactly one
//! triangle, an internal node always has two children whose ranges split its own (left first).
//! Because every split is balanced (left gets ⌊count/2⌋), a tree over n triangles has exactly
//! 2n − 1 nodes and depth ⌈log2 n⌉, whatever the input (identical centroids, equal normals,
//! zero-area triangles).
//!
//! Weights: every per-node mean (centroid, normal, colour) is area-weighted; when every
//! triangle under a node has zero area, the weights fall back to uniform, so no mean is NaN.

use crate::scene::Scene;
use glam::{DVec3, Vec3};
use std::f32::consts::PI;

/// Scenes with at most this many reflector triangles are rendered triangle by triangle; the
/// tree (and the cut) only pay off above it.
pub const MIN_TRIANGLES_FOR_TREE: usize = 200;

/// Subtrees with more triangles than this are built in parallel (rayon `join`).
const PARALLEL_THRESHOLD: usize = 4096;

/// Whether a scene with `n_reflector_triangles` reflector triangles should get a tree.
pub fn needs_tree(n_reflector_triangles: usize) -> bool {
    n_reflector_triangles > MIN_TRIANGLES_FOR_TREE
}

/// One reflector triangle as the tree sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriInput {
    /// Corner positions (world space). Must be finite.
    pub v: [Vec3; 3],
    /// Unit geometric normal following the winding; zero when the triangle has none
    /// (degenerate). A non-unit value is normalised; a zero or non-finite one means "none".
    pub normal: Vec3,
    /// RGB colour used for the per-node average and colour range. [`build`] uses the material's
    /// diffuse + specular colour (kd + ks; F0 for Cook-Torrance), a receiver-independent proxy
    /// for how much the triangle can reflect.
    pub albedo: Vec3,
    /// Material index (into `Scene::materials` for [`build`]).
    pub material: u32,
    /// Caller's triangle id, stored in [`ReflectorTree::tri_order`] (the scene triangle index
    /// for [`build`]).
    pub tri: u32,
}

impl TriInput {
    /// The reflector input for scene triangle `t`: geometric normal, kd + ks, object material.
    pub fn from_scene(scene: &Scene, t: u32) -> TriInput {
        let brdf = scene.tri_material(t);
        TriInput {
            v: scene.mesh.tri(t),
            normal: scene.mesh.tri_cross(t).normalize_or_zero(),
            albedo: brdf.diffuse() + brdf.specular(),
            material: scene.tri_object(t).material,
            tri: t,
        }
    }

    /// Triangle area (0 for a degenerate or non-finite triangle).
    pub fn area(&self) -> f32 {
        let [a, b, c] = self.v;
        let a = 0.5 * (b - a).cross(c - a).length();
        if a.is_finite() { a } else { 0.0 }
    }

    /// Vertex mean (the area-weighted centroid of a flat triangle).
    pub fn centroid(&self) -> Vec3 {
        (self.v[0] + self.v[1] + self.v[2]) / 3.0
    }
}

/// A cone of directions: every direction d with angle(axis, d) ≤ `half_angle`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalCone {
    /// Unit axis.
    pub axis: Vec3,
    /// Half-angle in radians, in [0, π]; ≥ π/2 when the normals span more than a hemisphere.
    pub half_angle: f32,
}

impl NormalCone {
    /// Whether unit direction `d` lies in the cone, up to `tol` radians.
    pub fn contains(&self, d: Vec3, tol: f32) -> bool {
        angle_between(self.axis, d) <= self.half_angle + tol
    }
}

/// Angle between two non-zero vectors in [0, π], accurate also near 0 and π
/// (atan2 of |a×b| and a·b, not acos of the dot).
pub fn angle_between(a: Vec3, b: Vec3) -> f32 {
    a.cross(b).length().atan2(a.dot(b)).clamp(0.0, PI)
}

/// A tree node: the triangles `tri_order[first..first + count]`, their shading summary and
/// bounds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    /// First index into [`ReflectorTree::tri_order`].
    pub first: u32,
    /// Number of triangles (1 for a leaf).
    pub count: u32,
    /// `[left, right]` node indices; `None` for a leaf. The left child is always the next node.
    pub children: Option<[u32; 2]>,
    /// Total area of the triangles.
    pub area: f32,
    /// Area-weighted mean of the triangle centroids.
    pub centroid: Vec3,
    /// Area-weighted mean of the unit triangle normals. Its length in [0, 1] measures normal
    /// coherence (1: all normals equal; 0 for opposite normals of equal area or no normals).
    pub mean_normal: Vec3,
    /// Normal cone containing every defined triangle normal under the node; its axis is
    /// `mean_normal` normalised (or, when that is zero, a child's axis). `None` when no triangle
    /// under the node has a normal (all degenerate).
    pub cone: Option<NormalCone>,
    /// Area-weighted mean albedo.
    pub colour: Vec3,
    /// Per-channel minimum of the triangles' albedos.
    pub colour_min: Vec3,
    /// Per-channel maximum of the triangles' albedos.
    pub colour_max: Vec3,
    /// The material when every triangle under the node has the same one.
    pub material: Option<u32>,
    /// Bounding box of every vertex under the node.
    pub bbox_min: Vec3,
    pub bbox_max: Vec3,
}

impl Node {
    pub fn is_leaf(&self) -> bool {
        self.children.is_none()
    }

    /// Unit axis of the normal cone; +z when the node has no normal.
    pub fn axis(&self) -> Vec3 {
        self.cone.map_or(Vec3::Z, |c| c.axis)
    }

    /// Index range into [`ReflectorTree::tri_order`].
    pub fn range(&self) -> std::ops::Range<usize> {
        self.first as usize..(self.first + self.count) as usize
    }
}

/// The tree. Empty (no nodes) for a scene without reflector triangles.
#[derive(Clone, Debug, Default)]
pub struct ReflectorTree {
    /// Nodes in pre-order, root at 0; 2n − 1 of them for n triangles.
    pub nodes: Vec<Node>,
    /// The input triangle ids (`TriInput::tri`) permuted so that every node's triangles are
    /// contiguous.
    pub tri_order: Vec<u32>,
}

impl ReflectorTree {
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Number of triangles (leaves).
    pub fn num_triangles(&self) -> usize {
        self.tri_order.len()
    }

    /// The root, `None` for an empty tree.
    pub fn root(&self) -> Option<&Node> {
        self.nodes.first()
    }

    /// The triangle ids (`TriInput::tri`) under node `node`.
    pub fn leaves_under(&self, node: u32) -> &[u32] {
        &self.tri_order[self.nodes[node as usize].range()]
    }

    /// Number of edges on the longest root-to-leaf path (0 for a single leaf or empty tree).
    pub fn depth(&self) -> u32 {
        let mut max = 0;
        let mut stack = Vec::new();
        if !self.nodes.is_empty() {
            stack.push((0u32, 0u32));
        }
        while let Some((i, d)) = stack.pop() {
            max = max.max(d);
            if let Some([l, r]) = self.nodes[i as usize].children {
                stack.push((l, d + 1));
                stack.push((r, d + 1));
            }
        }
        max
    }
}

/// Builds the tree over the reflector triangles of `scene` (objects with `reflector = true`).
/// Works for any count (empty tree for none); whether to use it is [`needs_tree`]'s decision.
pub fn build(scene: &Scene) -> ReflectorTree {
    let tris: Vec<TriInput> = scene
        .objects
        .iter()
        .filter(|o| o.reflector)
        .flat_map(|o| o.first_tri..o.first_tri + o.tri_count)
        .map(|t| TriInput::from_scene(scene, t))
        .collect();
    build_from(&tris)
}

/// Per-triangle working data, permuted in place while building.
#[derive(Clone, Copy, Debug)]
struct Item {
    centroid: Vec3,
    /// Unit normal or zero.
    normal: Vec3,
    lo: Vec3,
    hi: Vec3,
    albedo: Vec3,
    area: f32,
    material: u32,
    tri: u32,
    /// Projection on the split direction (scratch).
    key: f32,
}

/// Builds the tree over arbitrary triangles (O(n log n), parallel above a size threshold).
///
/// # Panics
/// When there are more than 2^31 − 1 triangles (node indices are `u32`).
pub fn build_from(tris: &[TriInput]) -> ReflectorTree {
    let n = tris.len();
    if n == 0 {
        return ReflectorTree::default();
    }
    assert!(n < (1usize << 31), "too many reflector triangles: {n}");
    let mut items: Vec<Item> = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.v;
            Item {
                centroid: t.centroid(),
                normal: t.normal.normalize_or_zero(),
                lo: a.min(b).min(c),
                hi: a.max(b).max(c),
                albedo: t.albedo,
                area: t.area(),
                material: t.material,
                tri: t.tri,
                key: 0.0,
            }
        })
        .collect();
    let mut nodes = vec![Node::default(); 2 * n - 1];
    build_rec(&mut items, &mut nodes, 0, 0);
    ReflectorTree {
        nodes,
        tri_order: items.iter().map(|it| it.tri).collect(),
    }
}

/// Builds the subtree over `items` into `nodes` (length 2·len − 1, pre-order); `base` is the
/// global index of `nodes[0]`, `first` the global index of `items[0]`.
fn build_rec(items: &mut [Item], nodes: &mut [Node], base: u32, first: u32) {
    debug_assert_eq!(nodes.len(), 2 * items.len() - 1);
    if items.len() == 1 {
        nodes[0] = leaf(&items[0], first);
        return;
    }
    let mid = items.len() / 2;
    let dir = split_direction(items);
    for it in items.iter_mut() {
        it.key = project(it, &dir);
    }
    items.select_nth_unstable_by(mid, |a, b| a.key.total_cmp(&b.key));
    let (head, rest) = nodes.split_first_mut().expect("at least one node");
    let (left_nodes, right_nodes) = rest.split_at_mut(2 * mid - 1);
    let (left_items, right_items) = items.split_at_mut(mid);
    let left = base + 1;
    let right = base + 2 * mid as u32;
    let right_first = first + mid as u32;
    if items_len_parallel(left_items.len() + right_items.len()) {
        rayon::join(
            || build_rec(left_items, left_nodes, left, first),
            || build_rec(right_items, right_nodes, right, right_first),
        );
    } else {
        build_rec(left_items, left_nodes, left, first);
        build_rec(right_items, right_nodes, right, right_first);
    }
    *head = combine(&left_nodes[0], &right_nodes[0], [left, right], items);
}

fn items_len_parallel(n: usize) -> bool {
    n > PARALLEL_THRESHOLD
}

fn leaf(it: &Item, first: u32) -> Node {
    Node {
        first,
        count: 1,
        children: None,
        area: it.area,
        centroid: it.centroid,
        mean_normal: it.normal,
        cone: (it.normal != Vec3::ZERO).then_some(NormalCone {
            axis: it.normal,
            half_angle: 0.0,
        }),
        colour: it.albedo,
        colour_min: it.albedo,
        colour_max: it.albedo,
        material: Some(it.material),
        bbox_min: it.lo,
        bbox_max: it.hi,
    }
}

/// The parent of `a` and `b`; `items` are the parent's triangles (for the exact cone).
fn combine(a: &Node, b: &Node, children: [u32; 2], items: &[Item]) -> Node {
    let area = a.area + b.area;
    // Area weights, uniform (by triangle count) when every triangle has zero area.
    let (wa, wb) = if area > 0.0 {
        (a.area / area, b.area / area)
    } else {
        let c = (a.count + b.count) as f32;
        (a.count as f32 / c, b.count as f32 / c)
    };
    let mean_normal = a.mean_normal * wa + b.mean_normal * wb;
    let cone = match (a.cone, b.cone) {
        (None, None) => None,
        (ca, cb) => {
            let axis = mean_normal
                .try_normalize()
                .unwrap_or_else(|| ca.or(cb).expect("one cone").axis);
            // Exact: the largest angle from the axis to any triangle normal under the node
            // (O(count), so O(n log n) over the tree; tighter than merging the children's cones).
            let half_angle = items
                .iter()
                .filter(|it| it.normal != Vec3::ZERO)
                .map(|it| angle_between(axis, it.normal))
                .fold(0.0f32, f32::max);
            Some(NormalCone { axis, half_angle })
        }
    };
    Node {
        first: a.first,
        count: a.count + b.count,
        children: Some(children),
        area,
        centroid: a.centroid * wa + b.centroid * wb,
        mean_normal,
        cone,
        colour: a.colour * wa + b.colour * wb,
        colour_min: a.colour_min.min(b.colour_min),
        colour_max: a.colour_max.max(b.colour_max),
        material: match (a.material, b.material) {
            (Some(x), Some(y)) if x == y => Some(x),
            _ => None,
        },
        bbox_min: a.bbox_min.min(b.bbox_min),
        bbox_max: a.bbox_max.max(b.bbox_max),
    }
}

/// Split direction in feature space: centre and scale, then the top eigenvector.
struct SplitDir {
    mean_c: DVec3,
    mean_n: DVec3,
    /// Scale applied to the normal features.
    s: f64,
    /// Unit eigenvector: position part, normal part.
    vc: DVec3,
    vn: DVec3,
}

fn project(it: &Item, d: &SplitDir) -> f32 {
    let c = it.centroid.as_dvec3() - d.mean_c;
    let n = (it.normal.as_dvec3() - d.mean_n) * d.s;
    (c.dot(d.vc) + n.dot(d.vn)) as f32
}

/// PCA of the features (centroid, s · normal), with s the RMS distance of the centroids from
/// their mean (1 when they coincide): the normals' spread (at most 1 before scaling) then
/// weighs at most as much as the centroids' spread. Unweighted by area (the split balances
/// triangle counts). Returns the direction of largest variance.
#[allow(clippy::needless_range_loop)] // index loops over a 6×6 matrix read best
fn split_direction(items: &[Item]) -> SplitDir {
    let inv = 1.0 / items.len() as f64;
    let (mut mc, mut mn) = (DVec3::ZERO, DVec3::ZERO);
    for it in items {
        mc += it.centroid.as_dvec3();
        mn += it.normal.as_dvec3();
    }
    mc *= inv;
    mn *= inv;
    let mut spread = 0.0;
    for it in items {
        spread += (it.centroid.as_dvec3() - mc).length_squared();
    }
    let rms = (spread * inv).sqrt();
    let s = if rms > 0.0 && rms.is_finite() {
        rms
    } else {
        1.0
    };
    let mut cov = [[0.0f64; 6]; 6];
    for it in items {
        let c = it.centroid.as_dvec3() - mc;
        let n = (it.normal.as_dvec3() - mn) * s;
        let f = [c.x, c.y, c.z, n.x, n.y, n.z];
        for i in 0..6 {
            for j in i..6 {
                cov[i][j] += f[i] * f[j];
            }
        }
    }
    for i in 0..6 {
        for j in 0..i {
            cov[i][j] = cov[j][i];
        }
    }
    let v = top_eigenvector(cov);
    SplitDir {
        mean_c: mc,
        mean_n: mn,
        s,
        vc: DVec3::new(v[0], v[1], v[2]),
        vn: DVec3::new(v[3], v[4], v[5]),
    }
}

/// Unit eigenvector of the largest eigenvalue of a symmetric 6×6 matrix (cyclic Jacobi).
/// Returns e₀ for a zero or non-finite matrix.
#[allow(clippy::needless_range_loop)] // index loops over a 6×6 matrix read best
fn top_eigenvector(mut a: [[f64; 6]; 6]) -> [f64; 6] {
    const N: usize = 6;
    let mut v = [[0.0f64; N]; N];
    for (i, row) in v.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    let mut e0 = [0.0; N];
    e0[0] = 1.0;
    if !a.iter().flatten().all(|x| x.is_finite()) {
        return e0;
    }
    for _sweep in 0..50 {
        let off: f64 = (0..N)
            .flat_map(|i| (i + 1..N).map(move |j| (i, j)))
            .map(|(i, j)| a[i][j] * a[i][j])
            .sum();
        let diag: f64 = (0..N).map(|i| a[i][i] * a[i][i]).sum();
        if !(off > 1e-30 * diag) {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                let apq = a[p][q];
                if apq == 0.0 {
                    continue;
                }
                // Rotation zeroing a[p][q] (Golub & Van Loan, Alg. 8.4.1).
                let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..N {
                    let akp = a[k][p];
                    let akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for k in 0..N {
                    let apk = a[p][k];
                    let aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for row in v.iter_mut() {
                    let vp = row[p];
                    let vq = row[q];
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    let best = (0..N)
        .max_by(|&i, &j| a[i][i].total_cmp(&a[j][j]))
        .unwrap_or(0);
    let out: [f64; N] = std::array::from_fn(|k| v[k][best]);
    if out.iter().all(|x| x.is_finite()) {
        out
    } else {
        e0
    }
}

#[cfg(test)]
#[path = "tree_tests.rs"]
mod tests;
