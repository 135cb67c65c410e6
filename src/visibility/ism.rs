//! Imperfect shadow maps (Ritschel et al. 2008; METHOD §7): one small paraboloid depth map per
//! virtual point light, splatted from a sparse random point set of the scene instead of
//! rasterised from its triangles, with the holes filled by pull-push. All maps live in one
//! atlas (map i at offset i · res²).
//!
//! Each VPL gets its own `points_per_map` points, sampled uniformly by area over every scene
//! triangle from a stream keyed by the VPL's index — different VPLs see different subsets, so
//! the errors of the sparse splatting decorrelate between VPLs. A point p at unit direction d
//! from the VPL (in the frame of its normal, d.z > 0) lands at (u, v) = (d.x, d.y) / (1 + d.z)
//! (the paraboloid map of the hemisphere onto the unit disc).
//!
//! A texel keeps the first two moments (E[z], E[z²]) of the distances of its nearest layer of
//! points — its nearest point and those within [`FRONT_LAYER`] of it, since points behind an
//! occluder land in the occluder's texels too — and visibility is the Chebyshev bound of
//! variance shadow maps (`visibility::vsm`). Keeping the nearest point alone (classic ISMs) made
//! floors seen at a grazing angle shadow themselves: a 32² texel then spans ±25 % of the
//! distance, and even a 20 % depth bias left 0.3 % of unoccluded pairs dark (5 %: 22 %); the
//! moments need no such bias. Pull-push fills the texels no point reached with the moments of
//! the smallest enclosing block that has some, and a 3 × 3 blur smooths the result.
//!
//! A receiver point below the VPL's horizon is not lit by it (0).

use crate::accel::Accel;
use crate::math::sampling::{Distribution1D, uniform_triangle};
use crate::math::{Frame, Rng};
use crate::precompute::vpl::Vpl;
pub use crate::settings::IsmOptions;
use crate::visibility::vsm::{bilinear_moments, chebyshev_upper_bound, min_variance};
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// A map's origin: position (a little above its surface) and the unit normal of its hemisphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapOrigin {
    pub position: Vec3,
    pub normal: Vec3,
}

/// The imperfect shadow maps of a set of VPLs.
pub struct ImperfectShadowMaps {
    res: usize,
    /// Per VPL: position and the frame of its normal.
    origins: Vec<(Vec3, Frame)>,
    /// (E[z], E[z²]) of the splatted distances, map after map (rows of `res`).
    atlas: Vec<Vec2>,
    bias: f32,
    /// σ² floor of each map (from its largest depth, as for variance shadow maps).
    min_variance: Vec<f32>,
}

/// The maps as the GPU reads them: texels per side, each map's origin and frame, the atlas
/// (map after map), each map's variance floor and the depth bias.
pub(crate) struct MapParts<'a> {
    pub res: usize,
    pub origins: &'a [(Vec3, Frame)],
    pub atlas: &'a [Vec2],
    pub min_variance: &'a [f32],
    pub bias: f32,
}

/// Where the points splatted into imperfect shadow maps come from: `points_per_map` per VPL,
/// sampled uniformly by area over the scene's triangles from a stream keyed by the VPL's index
/// (`None` where the scene has no area to sample), and each map's origin and frame. The CPU
/// splats them in [`ImperfectShadowMaps::build`], the GPU in `render::gpu::ism`.
pub struct IsmSampler<'a> {
    positions: &'a [Vec3],
    indices: &'a [[u32; 3]],
    dist: Distribution1D,
    seed: u64,
    /// Texels per side of each map.
    pub res: usize,
    pub points_per_map: usize,
    /// Per VPL: position and the frame of its normal.
    pub origins: Vec<(Vec3, Frame)>,
}

impl<'a> IsmSampler<'a> {
    pub fn new(
        positions: &'a [Vec3],
        indices: &'a [[u32; 3]],
        vpls: &[Vpl],
        opts: &IsmOptions,
        seed: u64,
    ) -> IsmSampler<'a> {
        let areas: Vec<f32> = indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .collect();
        IsmSampler {
            positions,
            indices,
            dist: Distribution1D::new(&areas),
            seed,
            res: opts.resolution.max(2) as usize,
            points_per_map: opts.points_per_map as usize,
            origins: vpls
                .iter()
                .map(|v| (v.position, Frame::from_normal(v.normal)))
                .collect(),
        }
    }

    /// The points of map `i`, written to `out` (`points_per_map` of them).
    pub fn map_points(&self, i: usize, out: &mut [Option<Vec3>]) {
        let mut rng = Rng::keyed(self.seed, 0x0049_534d, i as u64);
        for slot in out {
            *slot = self.dist.sample(rng.f32()).map(|t| {
                let b = uniform_triangle(rng.vec2());
                let [a, bb, c] = self.indices[t].map(|i| self.positions[i as usize]);
                a * b[0] + bb * b[1] + c * b[2]
            });
        }
    }
}

impl ImperfectShadowMaps {
    /// Splats the scene (triangles `positions`/`indices`) into one map per VPL.
    pub fn build(
        positions: &[Vec3],
        indices: &[[u32; 3]],
        vpls: &[Vpl],
        opts: &IsmOptions,
        seed: u64,
    ) -> ImperfectShadowMaps {
        let sampler = IsmSampler::new(positions, indices, vpls, opts, seed);
        let res = sampler.res;
        let maps: Vec<(Vec<Vec2>, f32)> = sampler
            .origins
            .par_iter()
            .enumerate()
            .map(|(i, &(y, frame))| {
                let mut points = vec![None; sampler.points_per_map];
                sampler.map_points(i, &mut points);
                let splats: Vec<(usize, f32)> = points
                    .iter()
                    .filter_map(|p| texel(res, y, &frame, (*p)?))
                    .collect();
                // The nearest layer of each texel: its nearest point and those within
                // FRONT_LAYER of it (points behind an occluder land in its texels too).
                let mut nearest = vec![f32::INFINITY; res * res];
                for &(k, z) in &splats {
                    nearest[k] = nearest[k].min(z);
                }
                // (Σ z, Σ z², count) per texel.
                let mut acc = vec![(0.0f32, 0.0f32, 0u32); res * res];
                let mut far = 0.0f32;
                for &(k, z) in &splats {
                    if z <= nearest[k] * (1.0 + FRONT_LAYER) {
                        let e = &mut acc[k];
                        e.0 += z;
                        e.1 += z * z;
                        e.2 += 1;
                        far = far.max(z);
                    }
                }
                let mut m = pull_push(&acc, res);
                if opts.blur {
                    blur3(&mut m, res);
                }
                (m, far)
            })
            .collect();
        let far = maps.iter().map(|m| m.1).collect::<Vec<_>>();
        let atlas = maps.into_iter().flat_map(|m| m.0).collect();
        ImperfectShadowMaps::from_splats(sampler, atlas, &far, opts.bias)
    }

    /// The maps `sampler`'s points were splatted into, from their atlas (map after map,
    /// `res`² texels each) and each map's farthest splatted depth (the scale of its variance
    /// floor): how the GPU's splatting (`render::gpu::ism`) hands its result back.
    pub fn from_splats(
        sampler: IsmSampler,
        atlas: Vec<Vec2>,
        far: &[f32],
        bias: f32,
    ) -> ImperfectShadowMaps {
        ImperfectShadowMaps {
            res: sampler.res,
            origins: sampler.origins,
            atlas,
            bias,
            min_variance: far.iter().map(|f| min_variance(f.max(1e-3))).collect(),
        }
    }

    /// Maps from their parts: `res` texels a side, each map's origin and frame, the atlas (map
    /// after map), the depth bias and one variance floor for all (for tests of the lookups).
    #[cfg(test)]
    pub(crate) fn from_parts(
        res: usize,
        origins: Vec<(Vec3, Frame)>,
        atlas: Vec<Vec2>,
        bias: f32,
        min_variance: f32,
    ) -> ImperfectShadowMaps {
        assert_eq!(atlas.len(), origins.len() * res * res);
        ImperfectShadowMaps {
            res,
            min_variance: vec![min_variance; origins.len()],
            origins,
            atlas,
            bias,
        }
    }

    /// Maps of the same layout made exactly, by one ray per texel centre through the BVH
    /// (nearest hit, or `far` for a miss), for the visibility maps at tree nodes
    /// (`visibility::node_maps`). Texels beyond the hemisphere's disc take the ray of the
    /// nearest point on its rim, so that bilinear lookups near the horizon read real depths.
    pub fn ray_cast(
        accel: &Accel,
        origins: &[MapOrigin],
        resolution: u32,
        bias: f32,
        far: f32,
    ) -> ImperfectShadowMaps {
        let res = resolution.max(2) as usize;
        let origins: Vec<(Vec3, Frame)> = origins
            .iter()
            .map(|o| (o.position, Frame::from_normal(o.normal)))
            .collect();
        let maps: Vec<(Vec<Vec2>, f32)> = origins
            .par_iter()
            .map(|&(y, frame)| {
                let mut deepest = 0.0f32;
                let map = (0..res * res)
                    .map(|k| {
                        let (j, i) = (k / res, k % res);
                        let mut u = 2.0 * (i as f32 + 0.5) / res as f32 - 1.0;
                        let mut v = 2.0 * (j as f32 + 0.5) / res as f32 - 1.0;
                        let r2 = u * u + v * v;
                        if r2 > RIM * RIM {
                            let s = RIM / r2.sqrt();
                            (u, v) = (u * s, v * s);
                        }
                        let r2 = u * u + v * v;
                        let d = Vec3::new(2.0 * u, 2.0 * v, 1.0 - r2) / (1.0 + r2);
                        let z = accel
                            .intersect(y, frame.to_world(d), 0.0, far)
                            .map_or(far, |h| {
                                deepest = deepest.max(h.t);
                                h.t
                            });
                        Vec2::new(z, z * z)
                    })
                    .collect();
                (map, min_variance(deepest.max(1e-3)))
            })
            .collect();
        ImperfectShadowMaps {
            res,
            origins,
            min_variance: maps.iter().map(|m| m.1).collect(),
            atlas: maps.into_iter().flat_map(|m| m.0).collect(),
            bias,
        }
    }

    /// What the GPU reads (`render::gpu::sg_shade`).
    pub(crate) fn parts(&self) -> MapParts<'_> {
        MapParts {
            res: self.res,
            origins: &self.origins,
            atlas: &self.atlas,
            min_variance: &self.min_variance,
            bias: self.bias,
        }
    }

    /// Texels per side of each map.
    pub fn resolution(&self) -> usize {
        self.res
    }

    /// Map `i`'s moments (E[z], E[z²]), rows of [`Self::resolution`] texels.
    pub fn moments(&self, i: usize) -> &[Vec2] {
        &self.atlas[i * self.res * self.res..(i + 1) * self.res * self.res]
    }

    /// Map `i`'s variance floor.
    pub fn min_variance(&self, i: usize) -> f32 {
        self.min_variance[i]
    }

    /// Number of maps.
    pub fn len(&self) -> usize {
        self.origins.len()
    }

    pub fn is_empty(&self) -> bool {
        self.origins.is_empty()
    }

    /// Visibility in [0, 1] between VPL `i` and point `p`: 0 below the VPL's horizon, otherwise
    /// the Chebyshev bound of the bilinearly interpolated moments at p's direction for p's
    /// distance (less the bias); 1 where no point reached the map.
    pub fn visibility(&self, i: usize, p: Vec3) -> f32 {
        self.visibility_above_horizon(i, p).unwrap_or(0.0)
    }

    /// [`Self::visibility`], or `None` when `p` is below the map's horizon (where it knows
    /// nothing).
    pub fn visibility_above_horizon(&self, i: usize, p: Vec3) -> Option<f32> {
        self.map(i).visibility_above_horizon(p)
    }

    /// Map `i` resolved once, for many lookups ([`MapView::visibility_above_horizon`] gives
    /// what [`Self::visibility_above_horizon`] gives for it).
    pub fn map(&self, i: usize) -> MapView<'_> {
        let n = self.res;
        let (y, frame) = &self.origins[i];
        MapView {
            y: *y,
            frame,
            moments: &self.atlas[i * n * n..(i + 1) * n * n],
            res: n,
            bias: self.bias,
            min_variance: self.min_variance[i],
        }
    }
}

/// One map of [`ImperfectShadowMaps`], its origin, texels and constants looked up once.
#[derive(Clone, Copy)]
pub struct MapView<'a> {
    pub(crate) y: Vec3,
    pub(crate) frame: &'a Frame,
    pub(crate) moments: &'a [Vec2],
    pub(crate) res: usize,
    pub(crate) bias: f32,
    pub(crate) min_variance: f32,
}

impl MapView<'_> {
    /// The map's visibility of `p`, or `None` below its horizon (where it knows nothing); see
    /// [`ImperfectShadowMaps::visibility`].
    #[inline]
    pub fn visibility_above_horizon(&self, p: Vec3) -> Option<f32> {
        let (u, w, t) = paraboloid(self.y, self.frame, p)?;
        let m = bilinear_moments(self.moments, self.res, u, w);
        if !(m.x > 0.0) {
            // No point reached this part of the map: nothing occludes.
            return Some(1.0);
        }
        Some(chebyshev_upper_bound(
            m,
            t * (1.0 - self.bias),
            self.min_variance,
        ))
    }
}

/// Radius in the paraboloid's disc of the outermost ray a ray-cast map casts: 1° above the
/// horizon.
const RIM: f32 = 0.983;

/// Depth range of the layer a texel keeps, relative to its nearest point: a floor seen at a
/// grazing angle from just above spans ±25 % of its distance within one 32² texel, an occluder
/// in front of a wall a factor of several.
pub const FRONT_LAYER: f32 = 0.5;

/// Paraboloid coordinates (u, v) in the unit disc and distance of point `p` seen from a VPL at
/// `y` with normal frame `frame`; `None` below its horizon or at the VPL itself.
fn paraboloid(y: Vec3, frame: &Frame, p: Vec3) -> Option<(f32, f32, f32)> {
    let v = p - y;
    let z = v.length();
    if !(z > 0.0) {
        return None;
    }
    let d = frame.to_local(v / z);
    if !(d.z > 0.0) {
        return None;
    }
    Some((d.x / (1.0 + d.z), d.y / (1.0 + d.z), z))
}

/// Texel index and distance of point `p` in the paraboloid map of a VPL at `y`.
fn texel(res: usize, y: Vec3, frame: &Frame, p: Vec3) -> Option<(usize, f32)> {
    let (u, w, z) = paraboloid(y, frame, p)?;
    let i = (((u + 1.0) * 0.5 * res as f32) as usize).min(res - 1);
    let j = (((w + 1.0) * 0.5 * res as f32) as usize).min(res - 1);
    Some((j * res + i, z))
}

/// (Σ z, Σ z², count) of the points of a texel.
type Sums = (f32, f32, u32);

/// The moments (E[z], E[z²]) of every texel, holes (texels no point reached) filled with the
/// moments of the smallest enclosing 2^k-block that holds some: the pull pass sums the points
/// level by level, the push pass hands each hole its parent's moments. A map with no point at
/// all stays zero (nothing occludes).
fn pull_push(acc: &[Sums], res: usize) -> Vec<Vec2> {
    let mut levels: Vec<(usize, Vec<Sums>)> = vec![(res, acc.to_vec())];
    while levels.last().is_some_and(|(n, _)| *n > 1) {
        let (n, prev) = levels.last().expect("non-empty");
        let m = n.div_ceil(2);
        let mut next = vec![(0.0f32, 0.0f32, 0u32); m * m];
        for y in 0..*n {
            for x in 0..*n {
                let (s, s2, c) = prev[y * n + x];
                let e = &mut next[(y / 2) * m + x / 2];
                e.0 += s;
                e.1 += s2;
                e.2 += c;
            }
        }
        levels.push((m, next));
    }
    let mut parent: Option<(usize, Vec<Vec2>)> = None;
    for (n, level) in levels.iter().rev() {
        let moments: Vec<Vec2> = (0..n * n)
            .map(|k| {
                let (s, s2, c) = level[k];
                if c > 0 {
                    Vec2::new(s, s2) / c as f32
                } else if let Some((m, p)) = &parent {
                    let (x, y) = (k % n, k / n);
                    p[(y / 2).min(m - 1) * m + (x / 2).min(m - 1)]
                } else {
                    Vec2::ZERO
                }
            })
            .collect();
        parent = Some((*n, moments));
    }
    parent.expect("at least one level").1
}

/// A 3 × 3 box blur of the moments (clamped at the edges).
fn blur3(m: &mut [Vec2], n: usize) {
    let src = m.to_vec();
    for y in 0..n {
        for x in 0..n {
            let mut sum = Vec2::ZERO;
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let xx = (x as i64 + dx).clamp(0, n as i64 - 1) as usize;
                    let yy = (y as i64 + dy).clamp(0, n as i64 - 1) as usize;
                    sum += src[yy * n + xx];
                }
            }
            m[y * n + x] = sum / 9.0;
        }
    }
}

#[cfg(test)]
mod tests;

/// Interpolation weights of a point among its 3 nearest VPLs (METHOD §7): the point projected
/// on the plane of the three, in barycentric coordinates (negative ones clamped to 0 and the
/// rest renormalised). With `normal` (the unit normal of the surface around the point), only
/// VPLs whose normals are within 60° of it count, when there are 3 such: a VPL's map covers the
/// hemisphere above its own surface, and a wall node's nearest VPLs on the floor would see
/// nothing of what the wall lights. With fewer than 3 VPLs, or 3 (nearly) collinear ones, the
/// weights fall back to inverse distances. Entries with weight 0 are unused.
pub fn nearest_vpl_weights(p: Vec3, normal: Option<Vec3>, vpls: &[Vpl]) -> [(u32, f32); 3] {
    nearest_vpl_weights_among(
        p,
        &|_, v: &Vpl| normal.is_none_or(|n| v.normal.dot(n) >= 0.5),
        vpls,
    )
}

/// [`nearest_vpl_weights`] among the VPLs `accept(index, vpl)` admits, when there are 3 such
/// (all VPLs otherwise).
pub fn nearest_vpl_weights_among(
    p: Vec3,
    accept: &dyn Fn(usize, &Vpl) -> bool,
    vpls: &[Vpl],
) -> [(u32, f32); 3] {
    let nearest = |filter: &dyn Fn(usize, &Vpl) -> bool| {
        let mut best = [(u32::MAX, f32::INFINITY); 3];
        for (i, v) in vpls.iter().enumerate() {
            if !filter(i, v) {
                continue;
            }
            let d = (v.position - p).length_squared();
            if d < best[2].1 {
                best[2] = (i as u32, d);
                best.sort_by(|a, b| a.1.total_cmp(&b.1));
            }
        }
        best
    };
    let mut best = nearest(accept);
    if best[2].0 == u32::MAX {
        best = nearest(&|_, _| true);
    }
    let found = best.iter().filter(|b| b.0 != u32::MAX).count();
    let inverse_distance = |best: &[(u32, f32); 3]| {
        let mut w = [(0u32, 0.0f32); 3];
        let mut total = 0.0;
        for (k, &(i, d2)) in best.iter().enumerate() {
            if i != u32::MAX {
                let x = 1.0 / d2.sqrt().max(1e-6);
                w[k] = (i, x);
                total += x;
            }
        }
        for x in &mut w {
            x.1 /= total.max(1e-30);
        }
        w
    };
    if found < 3 {
        return inverse_distance(&best);
    }
    let [a, b, c] = best.map(|(i, _)| vpls[i as usize].position);
    let n = (b - a).cross(c - a);
    let n2 = n.length_squared();
    // Collinear (or coincident) VPLs: the area is tiny against the spread of the three.
    let scale = (b - a).length_squared().max((c - a).length_squared());
    if !(n2 > 1e-6 * scale * scale) {
        return inverse_distance(&best);
    }
    let q = p - n * ((p - a).dot(n) / n2);
    let bary = [
        (c - b).cross(q - b).dot(n) / n2,
        (a - c).cross(q - c).dot(n) / n2,
        (b - a).cross(q - a).dot(n) / n2,
    ]
    .map(|x| x.max(0.0));
    let total: f32 = bary.iter().sum();
    if !(total > 0.0) {
        return inverse_distance(&best);
    }
    std::array::from_fn(|k| (best[k].0, bary[k] / total))
}

impl ImperfectShadowMaps {
    /// Σ_k w_k · visibility(i_k, p) over interpolation weights (`nearest_vpl_weights`).
    pub fn interpolated(&self, weights: &[(u32, f32); 3], p: Vec3) -> f32 {
        weights
            .iter()
            .filter(|w| w.1 > 0.0)
            .map(|&(i, w)| w * self.visibility(i as usize, p))
            .sum()
    }
}
