//! Reflector pieces: the scene's reflector triangles split at their edge midpoints until they
//! are small enough to reflect a nearly constant radiance, and the tree over them.

use super::tree::{ReflectorTree, TriInput};
use crate::scene::Scene;
use glam::Vec3;
use rayon::prelude::*;

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
    crate::sg::tree::build_from(&inputs)
}
