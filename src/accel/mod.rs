//! Ray queries against the scene's triangles: a compressed-wide BVH from obvhs.
//!
//! Closest hits return the triangle index and barycentrics; occlusion queries stop at the
//! first hit. Triangle indices are those of [`crate::scene::SceneMesh`].

use glam::{Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    cwbvh::{CwBvh, builder::build_cwbvh_from_tris},
    ray::{Ray, RayHit},
    triangle::Triangle,
};
use std::time::Duration;

/// A closest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Triangle index into the scene mesh.
    pub tri: u32,
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// Barycentric weights of vertices 1 and 2 (vertex 0 gets 1 − u − v).
    pub u: f32,
    pub v: f32,
}

/// BVH over a triangle soup.
pub struct Accel {
    bvh: Option<CwBvh>,
    tris: Vec<Triangle>,
}

impl Accel {
    /// Builds the BVH (parallel). An empty triangle list gives an accelerator that never hits.
    pub fn build(positions: &[Vec3], indices: &[[u32; 3]]) -> Accel {
        let tris: Vec<Triangle> = indices
            .iter()
            .map(|t| Triangle {
                v0: Vec3A::from(positions[t[0] as usize]),
                v1: Vec3A::from(positions[t[1] as usize]),
                v2: Vec3A::from(positions[t[2] as usize]),
            })
            .collect();
        let bvh = if tris.is_empty() {
            None
        } else {
            Some(build_cwbvh_from_tris(
                &tris,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            ))
        };
        Accel { bvh, tris }
    }

    /// Closest hit along `dir` (unit) from `origin` within (tmin, tmax).
    pub fn intersect(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let ray = Ray::new(origin.into(), canonical(dir).into(), tmin, tmax);
        let mut hit = RayHit::none();
        let tris = &self.tris;
        let found = bvh.ray_traverse(ray, &mut hit, |r, id| {
            tris[bvh.primitive_indices[id] as usize].intersect(r)
        });
        if !found {
            return None;
        }
        let tri = bvh.primitive_indices[hit.primitive_id as usize];
        let t = &self.tris[tri as usize];
        let (u, v) = crate::math::triangle_barycentrics(
            Vec3::from(t.v0),
            Vec3::from(t.v1),
            Vec3::from(t.v2),
            origin + dir * hit.t,
        );
        Some(Hit {
            tri,
            t: hit.t,
            u,
            v,
        })
    }

    /// True when nothing blocks the open segment (tmin, tmax) along `dir` from `origin`.
    pub fn unoccluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return true;
        };
        if tmax <= tmin {
            return true;
        }
        let ray = Ray::new(origin.into(), canonical(dir).into(), tmin, tmax);
        let tris = &self.tris;
        bvh.ray_traverse_miss(ray, |r, id| {
            tris[bvh.primitive_indices[id] as usize].intersect(r)
        })
    }
}

/// `dir` with every −0.0 component made +0.0. obvhs 0.4 takes a ray's octant from
/// `direction < 0` but its inverse direction from `signum`, which disagree on −0.0: a ray with a
/// −0.0 component (a directional light along an axis plane, e.g. `[4.5, -2.1, 0.0]` negated)
/// traversed the wrong children and missed everything.
#[inline]
fn canonical(dir: Vec3) -> Vec3 {
    dir + Vec3::ZERO
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sampling::{Rng, uniform_sphere};

    /// The BVH agrees with a brute-force loop over all triangles (differential test).
    #[test]
    fn bvh_matches_brute_force() {
        let mut rng = Rng::keyed(11, 0, 0);
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..300u32 {
            let c = (rng.arr3().map(|x| x * 4.0 - 2.0)).into();
            let c: Vec3 = c;
            for _ in 0..3 {
                positions.push(c + 0.3 * uniform_sphere(rng.vec2()));
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let accel = Accel::build(&positions, &indices);
        for _ in 0..2000 {
            let o = 3.0 * uniform_sphere(rng.vec2());
            let d = uniform_sphere(rng.vec2());
            let mut best = f32::INFINITY;
            let mut best_tri = u32::MAX;
            for (k, t) in accel.tris.iter().enumerate() {
                let th = t.intersect(&Ray::new(o.into(), d.into(), 1e-4, f32::INFINITY));
                if th < best {
                    best = th;
                    best_tri = k as u32;
                }
            }
            let hit = accel.intersect(o, d, 1e-4, f32::INFINITY);
            match hit {
                None => assert!(best.is_infinite()),
                Some(h) => {
                    assert_eq!(h.tri, best_tri);
                    assert!((h.t - best).abs() <= 1e-5 * best.max(1.0));
                    let t = &accel.tris[h.tri as usize];
                    let p = Vec3::from(t.v0) * (1.0 - h.u - h.v)
                        + Vec3::from(t.v1) * h.u
                        + Vec3::from(t.v2) * h.v;
                    // Reconstructed hit point within float round-off of the ray point.
                    assert!((p - (o + d * h.t)).length() < 1e-4);
                }
            }
            assert_eq!(
                accel.unoccluded(o, d, 1e-4, f32::INFINITY),
                best.is_infinite()
            );
        }
    }

    /// Rays whose direction has ±0 components (axis-aligned or in an axis plane, as a
    /// directional light along `[4.5, -2.1, 0.0]` gives) hit exactly what brute force hits.
    #[test]
    fn rays_with_zero_components_match_brute_force() {
        let mut rng = Rng::keyed(12, 0, 0);
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for i in 0..300u32 {
            let c: Vec3 = (rng.arr3().map(|x| x * 4.0 - 2.0)).into();
            for _ in 0..3 {
                positions.push(c + 0.3 * uniform_sphere(rng.vec2()));
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let accel = Accel::build(&positions, &indices);
        let mut hits = 0;
        for k in 0..3000 {
            let o = 2.0 * uniform_sphere(rng.vec2());
            let mut d = uniform_sphere(rng.vec2()).to_array();
            // Zero one or two components, with either sign of zero.
            for (j, c) in d.iter_mut().enumerate() {
                if (k >> j) & 1 == 1 && j < 2 + (k % 2) {
                    *c = if (k >> (j + 3)) & 1 == 1 { -0.0 } else { 0.0 };
                }
            }
            let Some(d) = Vec3::from(d).try_normalize() else {
                continue;
            };
            let brute = accel
                .tris
                .iter()
                .map(|t| t.intersect(&Ray::new(o.into(), d.into(), 1e-4, f32::INFINITY)))
                .fold(f32::INFINITY, f32::min);
            let hit = accel.intersect(o, d, 1e-4, f32::INFINITY);
            assert_eq!(hit.is_some(), brute.is_finite(), "ray {k}: o {o} d {d:?}");
            assert_eq!(
                accel.unoccluded(o, d, 1e-4, f32::INFINITY),
                brute.is_infinite(),
                "ray {k}: o {o} d {d:?}"
            );
            hits += hit.is_some() as u32;
        }
        // The rays go through the cloud of triangles: many must hit for the test to mean anything.
        assert!(hits > 300, "only {hits} hits");
    }

    #[test]
    fn empty_scene_never_hits() {
        let a = Accel::build(&[], &[]);
        assert!(a.intersect(Vec3::ZERO, Vec3::Z, 0.0, 1.0).is_none());
        assert!(a.unoccluded(Vec3::ZERO, Vec3::Z, 0.0, 1.0));
    }
}
