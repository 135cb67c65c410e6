//! The node maps' lookups (`--visibility approx`) on the lanes: one map's visibility of many
//! receiver points at once ([`map_visibility`]). The lanes run the f32 operations of the
//! scalar [`MapView::visibility_above_horizon`] in its order — exact division and square root,
//! no fused multiply-add, the floor and the clamps as comparisons and selects — and read the
//! four texels of each lane one by one, so the result is the scalar one bit for bit (the test
//! `lanes_match_the_scalar_lookup_bit_for_bit` holds it with every ISA). `docs/sg-performance.md`,
//! "The approx lookups, node by node", has what it saves.

use super::simd::{Isa, Kernel, Vf, dispatch};
use crate::visibility::ism::MapView;
use glam::Vec3;

/// `out[j]`: the visibility that `map` gives point j of `points` (x, y and z, as long as
/// `out`), or `none` where the point is below the map's horizon (where
/// [`MapView::visibility_above_horizon`] is `None`), with the lanes of `isa`.
pub fn map_visibility(isa: Isa, map: &MapView, points: [&[f32]; 3], none: f32, out: &mut [f32]) {
    assert!(points.iter().all(|p| p.len() == out.len()));
    dispatch(
        isa,
        Lookup {
            map,
            points,
            none,
            out,
        },
    )
}

struct Lookup<'a> {
    map: &'a MapView<'a>,
    points: [&'a [f32]; 3],
    none: f32,
    out: &'a mut [f32],
}

impl Kernel for Lookup<'_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf>(self) {
        let Lookup {
            map,
            points: [px, py, pz],
            none,
            out,
        } = self;
        let n = out.len();
        let full = n - n % V::N;
        for j in (0..full).step_by(V::N) {
            lookup::<V>(map, [&px[j..], &py[j..], &pz[j..]], none).store(&mut out[j..]);
        }
        for j in full..n {
            out[j] = map
                .visibility_above_horizon(Vec3::new(px[j], py[j], pz[j]))
                .unwrap_or(none);
        }
    }
}

/// The first [`Vf::N`] points of `p` (see the module docs for why this equals the scalar
/// lookup). No closures here: a closure would not inherit the AVX2 entry point's target
/// feature and would call the intrinsics out of line (`simd` module docs).
#[inline(always)]
fn lookup<V: Vf>(m: &MapView, p: [&[f32]; 3], none: f32) -> V {
    let (zero, one, half) = (V::splat(0.0), V::splat(1.0), V::splat(0.5));
    // paraboloid(): the direction from the map's origin in its frame.
    let vx = V::load(p[0]) - V::splat(m.y.x);
    let vy = V::load(p[1]) - V::splat(m.y.y);
    let vz = V::load(p[2]) - V::splat(m.y.z);
    let z = (vx * vx + vy * vy + vz * vz).sqrt();
    let d = [vx / z, vy / z, vz / z];
    let f = m.frame;
    let (lx, ly, lz) = (dot(d, f.t), dot(d, f.b), dot(d, f.n));
    let above = z.gt(zero) & lz.gt(zero);
    let den = one + lz;
    // Lanes below the horizon (or at the origin) read texel (0, 0) and return `none`.
    let u = V::select(above, lx / den, zero);
    let w = V::select(above, ly / den, zero);
    // bilinear_moments(): texel coordinates clamped to the outermost centres (f32::clamp).
    let res = m.res;
    let (nf, maxf) = (V::splat(res as f32), V::splat((res - 1) as f32));
    let x = clamp((u + one) * half * nf - half, maxf);
    let y = clamp((w + one) * half * nf - half, maxf);
    let (x0, y0) = (floor(x), floor(y));
    let (fx, fy) = (x - x0, y - y0);
    let (mut xs, mut ys) = ([0f32; 16], [0f32; 16]);
    x0.to_slice(&mut xs);
    y0.to_slice(&mut ys);
    // Texels (x0, y0), (x1, y0), (x0, y1), (x1, y1), each moment in its own column.
    let mut t = [[0f32; 16]; 8];
    for l in 0..V::N {
        let (i0, j0) = (xs[l] as usize, ys[l] as usize);
        let (i1, j1) = ((i0 + 1).min(res - 1), (j0 + 1).min(res - 1));
        let idx = [j0 * res + i0, j0 * res + i1, j1 * res + i0, j1 * res + i1];
        for k in 0..4 {
            let texel = m.moments[idx[k]];
            t[2 * k][l] = texel.x;
            t[2 * k + 1][l] = texel.y;
        }
    }
    let (gx, gy) = (one - fx, one - fy);
    let r0 = V::load(&t[0]) * gx + V::load(&t[2]) * fx;
    let r1 = V::load(&t[4]) * gx + V::load(&t[6]) * fx;
    let mu = r0 * gy + r1 * fy;
    let r0 = V::load(&t[1]) * gx + V::load(&t[3]) * fx;
    let r1 = V::load(&t[5]) * gx + V::load(&t[7]) * fx;
    let m2 = r0 * gy + r1 * fy;
    // chebyshev_upper_bound() at the biased distance, where some point reached the texels.
    let t = z * V::splat(1.0 - m.bias);
    let var = m2 - mu * mu;
    let floor_var = V::splat(m.min_variance);
    let var = V::select(var.gt(floor_var), var, floor_var);
    let d = t - mu;
    let vis = V::select(t.gt(mu), var / (var + d * d), one);
    let vis = V::select(mu.gt(zero), vis, one);
    V::select(above, vis, V::splat(none))
}

/// d · a, summed as glam's `Vec3::dot` sums (x, then y, then z).
#[inline(always)]
fn dot<V: Vf>(d: [V; 3], a: Vec3) -> V {
    d[0] * V::splat(a.x) + d[1] * V::splat(a.y) + d[2] * V::splat(a.z)
}

/// `x.clamp(0, max)` as `f32::clamp` does it.
#[inline(always)]
fn clamp<V: Vf>(x: V, max: V) -> V {
    let zero = V::splat(0.0);
    let x = V::select(x.lt(zero), zero, x);
    V::select(x.gt(max), max, x)
}

/// `x.floor()` for x in [0, 2²³): the nearest integer, less one where it rounded up.
#[inline(always)]
fn floor<V: Vf>(x: V) -> V {
    let r = x.round();
    r - V::select(r.gt(x), V::splat(1.0), V::splat(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Frame;
    use crate::visibility::ism::ImperfectShadowMaps;
    use glam::Vec2;

    /// Random maps with texels that are empty, lit or occluded, and points all around them
    /// (behind, beside, on the horizon, at the origin, near and far): the lanes' visibility
    /// must equal the scalar lookup's bit for bit with every ISA, for every count of points
    /// (the tails go through the scalar path).
    #[test]
    fn lanes_match_the_scalar_lookup_bit_for_bit() {
        let mut rng = crate::math::Rng::keyed(7, 79, 0);
        let res = 8;
        let origins: Vec<(Vec3, Frame)> = (0..6)
            .map(|_| {
                let y = Vec3::from(rng.arr3()) * 2.0 - 1.0;
                let n = (Vec3::from(rng.arr3()) - 0.5).normalize_or(Vec3::Z);
                (y, Frame::from_normal(n))
            })
            .collect();
        let atlas: Vec<Vec2> = (0..origins.len() * res * res)
            .map(|i| {
                if i % 5 == 0 {
                    Vec2::ZERO
                } else {
                    let mu = 0.2 + 2.0 * rng.f32();
                    Vec2::new(mu, mu * mu + 0.05 * rng.f32())
                }
            })
            .collect();
        let maps = ImperfectShadowMaps::from_parts(res, origins.clone(), atlas, 0.02, 1e-4);
        for (i, (y, frame)) in origins.iter().enumerate() {
            let map = maps.map(i);
            let mut pts: Vec<Vec3> = (0..61)
                .map(|_| *y + (Vec3::from(rng.arr3()) - 0.5) * 5.0)
                .collect();
            pts.push(*y);
            pts.push(*y + frame.t);
            pts.push(*y + frame.n * 1e-3);
            pts.push(*y - frame.n);
            let p: [Vec<f32>; 3] = [
                pts.iter().map(|p| p.x).collect(),
                pts.iter().map(|p| p.y).collect(),
                pts.iter().map(|p| p.z).collect(),
            ];
            for isa in Isa::all_available() {
                for len in [pts.len(), 17, 8, 3] {
                    let mut out = vec![f32::NAN; len];
                    map_visibility(
                        isa,
                        &map,
                        [&p[0][..len], &p[1][..len], &p[2][..len]],
                        -1.0,
                        &mut out,
                    );
                    for (j, &v) in out.iter().enumerate() {
                        let want = map.visibility_above_horizon(pts[j]).unwrap_or(-1.0);
                        assert_eq!(
                            v.to_bits(),
                            want.to_bits(),
                            "{isa:?}, map {i}, point {j} of {len}: {v} against {want}"
                        );
                    }
                }
            }
        }
    }
}
