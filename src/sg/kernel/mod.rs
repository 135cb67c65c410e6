//! The SG method's data-parallel kernels: f32, structure of arrays, SIMD lanes chosen at run
//! time ([`simd`]). The f64 scalar code (`math::spherical_triangle`, `sg::transport`,
//! `sg::cluster`, `sg::bound`) stays the oracle the kernels are tested against.
//!
//! - [`triangle`]: the integral of an SG over a spherical triangle.
//! - [`maps`]: the node maps' visibility lookups (`--visibility approx`) for many points.
//!
//! Speed and accuracy: `docs/sg-performance.md`, `results/sg-performance.md`.

pub mod cluster;
pub mod leaf;
pub mod lobes;
pub mod maps;
pub mod receivers;
pub mod simd;
pub mod triangle;
pub mod v3;
pub mod vmath;

pub use simd::{Isa, Kernel, Vf, dispatch};

#[cfg(test)]
mod shading_tests;

use glam::Vec3;
use v3::V3;

/// SG-over-triangle problems in structure-of-arrays form: problem i is the lobe of unit axis
/// `axis[..][i]` and sharpness `sharpness[i]` over the spherical triangle of vertex directions
/// `a`, `b`, `c` (any length).
#[derive(Clone, Debug, Default)]
pub struct TriangleProblems {
    pub axis: [Vec<f32>; 3],
    pub sharpness: Vec<f32>,
    pub a: [Vec<f32>; 3],
    pub b: [Vec<f32>; 3],
    pub c: [Vec<f32>; 3],
}

impl TriangleProblems {
    pub fn len(&self) -> usize {
        self.sharpness.len()
    }
    pub fn is_empty(&self) -> bool {
        self.sharpness.is_empty()
    }
    /// Appends one problem.
    pub fn push(&mut self, axis: Vec3, sharpness: f32, a: Vec3, b: Vec3, c: Vec3) {
        for (dst, v) in [
            (&mut self.axis, axis),
            (&mut self.a, a),
            (&mut self.b, b),
            (&mut self.c, c),
        ] {
            dst[0].push(v.x);
            dst[1].push(v.y);
            dst[2].push(v.z);
        }
        self.sharpness.push(sharpness);
    }
    /// Problem i as (axis, λ, a, b, c).
    pub fn get(&self, i: usize) -> (Vec3, f32, Vec3, Vec3, Vec3) {
        let v = |s: &[Vec<f32>; 3]| Vec3::new(s[0][i], s[1][i], s[2][i]);
        (
            v(&self.axis),
            self.sharpness[i],
            v(&self.a),
            v(&self.b),
            v(&self.c),
        )
    }
}

/// Batches from this size are sorted by path first (smaller ones run in order: the sort costs
/// more than the divergence it saves).
const SORT_FROM: usize = 64;

/// [`triangle::integrate`] over every problem, written to `out` (as long as the problems), with
/// the lanes of `isa`; lanes the kernel flags are computed by the f64 scalar routine
/// (`math::spherical_triangle::integrate_sg`). Returns how many fell back.
pub fn integrate_sg_batch(isa: Isa, problems: &TriangleProblems, out: &mut [f32]) -> usize {
    assert_eq!(out.len(), problems.len());
    let n = problems.len();
    if n < SORT_FROM {
        return dispatch(isa, BatchSg { problems, out });
    }
    // Lanes of one vector run every path some lane needs: sort the problems by path first.
    let mut class = vec![0u8; n];
    dispatch(
        isa,
        Classify {
            problems,
            class: &mut class,
        },
    );
    let class = &class;
    let order: Vec<usize> = [0u8, 1, 2]
        .iter()
        .flat_map(|&want| (0..n).filter(move |&i| class[i] == want))
        .collect();
    let pick = |v: &Vec<f32>| -> Vec<f32> { order.iter().map(|&i| v[i]).collect() };
    let pick3 = |v: &[Vec<f32>; 3]| [pick(&v[0]), pick(&v[1]), pick(&v[2])];
    let sorted = TriangleProblems {
        axis: pick3(&problems.axis),
        sharpness: pick(&problems.sharpness),
        a: pick3(&problems.a),
        b: pick3(&problems.b),
        c: pick3(&problems.c),
    };
    let mut vals = vec![0.0; sorted.len()];
    let mut fallbacks = dispatch(
        isa,
        BatchSg {
            problems: &sorted,
            out: &mut vals,
        },
    );
    for (&i, &v) in order.iter().zip(&vals) {
        out[i] = v;
    }
    for (i, _) in class.iter().enumerate().filter(|(_, c)| **c == 3) {
        let (ax, l, a, b, c) = problems.get(i);
        out[i] = crate::math::spherical_triangle::integrate_sg(ax, l, a, b, c);
        fallbacks += 1;
    }
    fallbacks
}

/// The path of every problem of a batch: 0 the 7-point rule (or λ = 0), 1 the edge integrals,
/// 2 the subdivided rule, 3 the scalar fallback.
struct Classify<'a> {
    problems: &'a TriangleProblems,
    class: &'a mut [u8],
}

impl Kernel for Classify<'_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf>(self) {
        let p = self.problems;
        let n = p.len();
        let mut buf = [0f32; 16];
        let mut i = 0;
        while i + V::N <= n {
            let q = triangle::prepare(
                load3::<V>(&p.axis, i),
                V::load(&p.sharpness[i..]),
                load3::<V>(&p.a, i),
                load3::<V>(&p.b, i),
                load3::<V>(&p.c, i),
            );
            let code = V::select(
                q.too_wide,
                V::splat(3.0),
                V::select(
                    q.far_weak,
                    V::splat(2.0),
                    V::select(q.edges, V::splat(1.0), V::splat(0.0)),
                ),
            );
            code.store(&mut buf);
            for (c, &b) in self.class[i..i + V::N].iter_mut().zip(&buf) {
                *c = b as u8;
            }
            i += V::N;
        }
        // The remainder: edge path (correct for every lane; the kernel flags its fallbacks).
        for c in &mut self.class[i..] {
            *c = 1;
        }
    }
}

struct BatchSg<'a> {
    problems: &'a TriangleProblems,
    out: &'a mut [f32],
}

impl Kernel for BatchSg<'_> {
    type Output = usize;
    #[inline(always)]
    fn run<V: Vf>(self) -> usize {
        let p = self.problems;
        let n = p.len();
        let mut fallbacks = 0;
        let mut lane_buf = [0f32; 16];
        // The last, partial vector, padded with copies of the last problem: 13 coordinates.
        let mut pad = [[0f32; 16]; 13];
        let mut i = 0;
        while i < n {
            let count = V::N.min(n - i);
            let r = if count == V::N {
                triangle::integrate(
                    load3::<V>(&p.axis, i),
                    V::load(&p.sharpness[i..]),
                    load3::<V>(&p.a, i),
                    load3::<V>(&p.b, i),
                    load3::<V>(&p.c, i),
                )
            } else {
                let srcs = [
                    &p.axis[0],
                    &p.axis[1],
                    &p.axis[2],
                    &p.sharpness,
                    &p.a[0],
                    &p.a[1],
                    &p.a[2],
                    &p.b[0],
                    &p.b[1],
                    &p.b[2],
                    &p.c[0],
                    &p.c[1],
                    &p.c[2],
                ];
                for (dst, src) in pad.iter_mut().zip(srcs) {
                    for (j, d) in dst.iter_mut().enumerate().take(V::N) {
                        *d = src[(i + j).min(n - 1)];
                    }
                }
                let v3 = |k: usize| V3::<V>::load(&pad[k], &pad[k + 1], &pad[k + 2]);
                triangle::integrate(v3(0), V::load(&pad[3]), v3(4), v3(7), v3(10))
            };
            r.value.store(&mut lane_buf);
            self.out[i..i + count].copy_from_slice(&lane_buf[..count]);
            if V::any(r.fallback) {
                let flags = V::select(r.fallback, V::splat(1.0), V::splat(0.0));
                flags.store(&mut lane_buf);
                for (j, &flag) in lane_buf.iter().enumerate().take(count) {
                    if flag != 0.0 {
                        let (ax, l, a, b, c) = p.get(i + j);
                        self.out[i + j] =
                            crate::math::spherical_triangle::integrate_sg(ax, l, a, b, c);
                        fallbacks += 1;
                    }
                }
            }
            i += V::N;
        }
        fallbacks
    }
}

/// Lanes `[base, base + N)` of a structure-of-arrays vector.
#[inline(always)]
pub fn load3<V: Vf>(s: &[Vec<f32>; 3], base: usize) -> V3<V> {
    V3::load(&s[0][base..], &s[1][base..], &s[2][base..])
}

#[cfg(test)]
mod tests;
