//! Visibility maps at tree nodes: the visibility between reflectors and receivers for
//! `sg --visibility approx` (`docs/visibility.md`).
//!
//! The paper gives each tree node the imperfect shadow maps of its 3 nearest VPLs. Measured on
//! ring, bunny and dragon, that proxy is what makes it inaccurate: with exact shadow rays from
//! those 3 VPLs instead of their maps the indirect light is still 66 / 25 / 26 % off exact
//! visibility, while one exact ray per cut node to a point on the node is 12 / 4 / 5 % off. A VPL
//! a few centimetres away, or across an occluder (a floor node inside the ring, its nearest
//! floor VPLs outside), sees the receivers differently from the node.
//!
//! So the maps are placed on the nodes themselves. A top-down cut of the light's tree, splitting
//! the node of largest light weight × size, gives at most `count` maps: every node split on the
//! way and every node of the cut gets a map at its representative (brightest) triangle, facing
//! the lit side of its normals; a node below the cut uses its cut ancestor's map. Each map is a
//! low-resolution paraboloid map of depth moments, like an imperfect shadow map, but made by one
//! ray per texel through the BVH instead of splatted points: at 32² texels, splatting even
//! 16,384 points per map left the three scenes 23–33 % off (thin walls and small objects are
//! sieves at any affordable density), ray-cast maps 8–14 %, in about the same time.

use crate::accel::Accel;
use crate::sg::LitScene;
use crate::visibility::ism::{ImperfectShadowMaps, MapOrigin, MapView};
use glam::Vec3;
use std::collections::BinaryHeap;

/// Where the maps go: their origins, and for every tree node the map it uses.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeMapLayout {
    pub origins: Vec<MapOrigin>,
    /// Per tree node: index into `origins`, or `u32::MAX` for a node nothing under which is lit.
    pub map_of: Vec<u32>,
}

/// Chooses at most `count` maps for the lit tree `lit` (none when nothing is lit or `count` is
/// 0). `offset` lifts each origin off its triangle along its normal (the scene's ray epsilon).
pub fn layout(lit: &LitScene, count: usize, offset: f32) -> NodeMapLayout {
    let nodes = &lit.tree.nodes;
    let weight = |n: u32| lit.nodes[n as usize].weight;
    let priority = |n: u32| {
        let node = &nodes[n as usize];
        // Non-negative and finite: its f32 bits order like the value.
        (weight(n) * (node.bbox_max - node.bbox_min).length()).to_bits()
    };
    let mut has_map = vec![false; nodes.len()];
    let mut heap = BinaryHeap::new();
    if count > 0 && !nodes.is_empty() && weight(0) > 0.0 {
        heap.push((priority(0), 0u32));
    }
    let mut maps = 0usize;
    while let Some((_, n)) = heap.pop() {
        has_map[n as usize] = true;
        maps += 1;
        let lit_children: Vec<u32> = nodes[n as usize]
            .children
            .into_iter()
            .flatten()
            .filter(|&c| weight(c) > 0.0)
            .collect();
        // Split while the maps taken, those waiting and the children fit the budget.
        if maps + heap.len() + lit_children.len() <= count {
            for c in lit_children {
                heap.push((priority(c), c));
            }
        }
    }
    let mut origins = Vec::new();
    let mut map_of = vec![u32::MAX; nodes.len()];
    // Pre-order: a parent comes before its children, so they can inherit its map.
    for i in 0..nodes.len() {
        if has_map[i] {
            map_of[i] = origins.len() as u32;
            origins.push(origin(lit, i, offset));
        }
        if let Some(children) = nodes[i].children {
            for c in children {
                if !has_map[c as usize] {
                    map_of[c as usize] = map_of[i];
                }
            }
        }
    }
    NodeMapLayout { origins, map_of }
}

/// The origin of node `i`'s map: the centroid of its representative triangle, facing the lit
/// side of the node's normals when they agree (|Σ Aᵢ nᵢ| ≥ ½ Σ Aᵢ), else of that triangle's.
fn origin(lit: &LitScene, i: usize, offset: f32) -> MapOrigin {
    let node = &lit.nodes[i];
    let [a, b, c] = lit.tris[node.rep as usize].vertices;
    let mut normal = (b - a).cross(c - a).normalize_or_zero();
    if normal.dot(lit.light_pos - a) < 0.0 {
        normal = -normal;
    }
    if node.area > 0.0 && node.normal_sum.length() >= 0.5 * node.area {
        normal = node.normal_sum.normalize();
    }
    if normal == Vec3::ZERO {
        normal = Vec3::Z;
    }
    MapOrigin {
        position: (a + b + c) / 3.0 + normal * offset,
        normal,
    }
}

/// The visibility maps of one light's lit tree.
pub struct NodeMaps {
    maps: ImperfectShadowMaps,
    map_of: Vec<u32>,
}

impl NodeMaps {
    /// Lays out at most `count` maps of `resolution`² texels over `lit` and ray-casts them.
    pub fn build(
        accel: &Accel,
        lit: &LitScene,
        count: usize,
        resolution: u32,
        bias: f32,
        offset: f32,
        far: f32,
    ) -> NodeMaps {
        let NodeMapLayout { origins, map_of } = layout(lit, count, offset);
        let maps = ImperfectShadowMaps::ray_cast(accel, &origins, resolution, bias, far);
        NodeMaps { maps, map_of }
    }

    /// The maps and, per tree node, the index of the map it reads (`u32::MAX`: none), for the
    /// GPU (`render::gpu::sg_shade`).
    pub(crate) fn parts(&self) -> (&ImperfectShadowMaps, &[u32]) {
        (&self.maps, &self.map_of)
    }

    /// Number of maps.
    pub fn len(&self) -> usize {
        self.maps.len()
    }

    pub fn is_empty(&self) -> bool {
        self.maps.is_empty()
    }

    /// Visibility in [0, 1] of tree node `node` from receiver point `x`: its map's Chebyshev
    /// bound, or 1 where the map knows nothing (an unlit node, or x below the map's horizon:
    /// the transport itself zeroes receivers behind a piece's plane).
    pub fn visibility(&self, node: u32, x: Vec3) -> f32 {
        node_map_visibility(self.map(node).as_ref(), x)
    }

    /// The map that tree node `node` reads, resolved once for many receiver points (`None`:
    /// the node has none, and every point sees it); [`node_map_visibility`] looks it up.
    pub fn map(&self, node: u32) -> Option<MapView<'_>> {
        match self.map_of.get(node as usize) {
            Some(&i) if i != u32::MAX => Some(self.maps.map(i as usize)),
            _ => None,
        }
    }
}

/// [`NodeMaps::visibility`] of a point `x` through the node's resolved map
/// ([`NodeMaps::map`]).
#[inline]
pub fn node_map_visibility(map: Option<&MapView>, x: Vec3) -> f32 {
    map.map_or(1.0, |m| m.visibility_above_horizon(x).unwrap_or(1.0))
}

#[cfg(test)]
mod tests;
