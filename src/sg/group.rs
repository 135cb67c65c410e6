//! Cuts for groups of receivers (`docs/sg-performance.md`, "Tile cuts"): the samples of one
//! screen tile that share a material select one cut together, with a bound that holds for every
//! sample of the group, and then evaluate each node of that cut for all of them at once — the
//! SIMD lanes hold samples that share a node.
//!
//! **The guarantee.** [`LitScene::group_bound`] is at least the point bound
//! ([`LitScene::bound`]) at every sample of the group, per channel, hence at least the true
//! contribution of the node's triangles and its clamped approximation at every sample: it is the
//! point bound with each of its factors replaced by its worst case over the group — the samples
//! lie in a ball (centre `c`, radius `r`), so a distance from a sample is at least the distance
//! from `c` minus `r` and a direction from a sample to the node's bounding sphere lies in the
//! cone from `c` to that sphere grown by `r`; each lobe slot's axes lie in a cone, its sharpness
//! is at least the group's smallest (divided by the largest stretch) and its amplitude at most
//! the largest; the diffuse part is at most the largest. Every factor of the point bound is
//! monotone in these quantities. `group_bound_holds_for_every_sample` checks it on random
//! groups.

use super::bound::{angle, cos_max_bound, cos_minus_one, radiance_bound};
use super::kernel::leaf::LeafSummary;
use super::kernel::receivers::Receivers;
use super::kernel::simd::{Isa, Kernel, Vf, dispatch};
use super::kernel::{cluster, cluster::NodeSummary, leaf, receivers::ReceiversV};
use super::lighting::LitScene;
use super::select::Pending;
use super::transport::receiver::{ReceiverLobes, ReceiverOptions};
use crate::brdf::sg_fit::MAX_LOBES;
use crate::math::luminance;
use crate::settings::CutOptions;
use glam::Vec3;
use std::collections::BinaryHeap;

/// How many of a group's samples estimate its radiance during selection (spread evenly over
/// the group): one vector of the widest lanes.
pub const REPRESENTATIVES: usize = 16;

/// What the group bound needs of a group of receivers.
#[derive(Clone, Copy, Debug)]
pub struct GroupSummary {
    /// A ball holding every sample position.
    pub centre: Vec3,
    pub radius: f32,
    /// Unit mean of the samples' normals and the largest chord |n − n̄|.
    pub normal: Vec3,
    pub normal_chord: f32,
    /// Largest diffuse part per channel.
    pub diffuse: Vec3,
    /// Per lobe slot: unit mean axis, the largest angle of an axis from it, the smallest
    /// sharpness / stretch and the largest amplitude per channel.
    pub lobe_axis: [Vec3; MAX_LOBES],
    pub lobe_spread: [f32; MAX_LOBES],
    pub lobe_sharpness: [f32; MAX_LOBES],
    pub lobe_amp: [Vec3; MAX_LOBES],
    pub n_lobes: usize,
}

impl GroupSummary {
    /// The summary of the receivers `(x, lobes)` (not empty; one material, so one lobe count).
    pub fn new(points: &[(Vec3, ReceiverLobes)]) -> GroupSummary {
        let n = points.len().max(1) as f32;
        let mean = points.iter().fold(Vec3::ZERO, |a, p| a + p.0) / n;
        // Centre of the bounding box: a tighter ball than the mean for clustered samples.
        let (lo, hi) = points.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p.0), hi.max(p.0)),
        );
        let centre = if lo.x <= hi.x { 0.5 * (lo + hi) } else { mean };
        let radius = points
            .iter()
            .map(|p| (p.0 - centre).length())
            .fold(0.0f32, f32::max);
        let normal = points
            .iter()
            .fold(Vec3::ZERO, |a, p| a + p.1.normal)
            .normalize_or(Vec3::Z);
        let normal_chord = points
            .iter()
            .map(|p| (p.1.normal - normal).length())
            .fold(0.0f32, f32::max);
        let diffuse = points.iter().fold(Vec3::ZERO, |a, p| a.max(p.1.diffuse));
        let n_lobes = points.iter().map(|p| p.1.lobes().len()).max().unwrap_or(0);
        let mut s = GroupSummary {
            centre,
            radius,
            normal,
            normal_chord,
            diffuse,
            lobe_axis: [Vec3::Z; MAX_LOBES],
            lobe_spread: [0.0; MAX_LOBES],
            lobe_sharpness: [0.0; MAX_LOBES],
            lobe_amp: [Vec3::ZERO; MAX_LOBES],
            n_lobes,
        };
        for k in 0..n_lobes {
            let lobes = || {
                points
                    .iter()
                    .filter_map(|p| p.1.lobes().get(k).map(|l| (l, p)))
            };
            let axis = lobes()
                .fold(Vec3::ZERO, |a, (l, _)| a + l.axis)
                .normalize_or(Vec3::Z);
            s.lobe_axis[k] = axis;
            s.lobe_spread[k] = lobes()
                .map(|(l, _)| angle(axis, l.axis))
                .fold(0.0, f32::max);
            s.lobe_sharpness[k] = lobes()
                .map(|(l, p)| l.sharpness / p.1.stretch())
                .fold(f32::INFINITY, f32::min);
            s.lobe_amp[k] = lobes().fold(Vec3::ZERO, |a, (l, _)| a.max(l.amplitude));
            if !s.lobe_sharpness[k].is_finite() {
                s.lobe_sharpness[k] = 0.0;
            }
        }
        s
    }
}

impl LitScene<'_> {
    /// Upper bound (per channel) of the summed SG contribution of the triangles under `node`
    /// at every receiver of the group `g` (see the module's guarantee). Zero for a leaf, whose
    /// value is evaluated exactly; infinite when the group's ball reaches the node's box.
    pub fn group_bound(&self, node: u32, g: &GroupSummary) -> Vec3 {
        let n = &self.tree.nodes[node as usize];
        let lit = &self.nodes[node as usize];
        if n.is_leaf() || !(lit.weight > 0.0) {
            return Vec3::ZERO;
        }
        let (lo, hi) = (n.bbox_min, n.bbox_max);
        let (x, r) = (g.centre, g.radius);
        // Below every sample's horizon: n·(p − x) ≤ n̄·(p − c) + |n − n̄| |p − c| + r.
        let mut above = false;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            let v = corner - x;
            if g.normal.dot(v) + g.normal_chord * v.length() + r > 0.0 {
                above = true;
                break;
            }
        }
        if !above {
            return Vec3::ZERO;
        }
        let d = (x.clamp(lo, hi) - x).length() - r;
        if !(d > 0.0) {
            return Vec3::splat(f32::INFINITY);
        }
        let d2 = d * d;
        let centre = 0.5 * (lo + hi);
        let radius = 0.5 * (hi - lo).length() + r;
        let to_c = centre - x;
        let dist = to_c.length();
        let cone = (dist > radius).then(|| (to_c / dist, (radius / dist).asin()));
        let mut hmax = g.diffuse;
        for k in 0..g.n_lobes {
            let f = match cone {
                Some((dir, half)) => {
                    let gap = (angle(g.lobe_axis[k], dir) - half - g.lobe_spread[k]).max(0.0);
                    (g.lobe_sharpness[k] * cos_minus_one(gap)).min(0.0).exp()
                }
                None => 1.0,
            };
            hmax += g.lobe_amp[k] * f;
        }
        let gap = match cone {
            Some((dir, half)) if lit.image_min.x <= lit.image_max.x => {
                let ic = 0.5 * (lit.image_min + lit.image_max);
                let ir = 0.5 * (lit.image_max - lit.image_min).length() + r;
                let to_i = ic - x;
                let di = to_i.length();
                (di > ir).then(|| (angle(dir, to_i / di) - half - (ir / di).asin()).max(0.0))
            }
            _ => None,
        };
        let radiance = radiance_bound(lit, gap);
        let cos_max = cos_max_bound(n.cone, cone);
        // 2e-3: the point bound's 1e-3 rounding headroom, and as much again for the f32
        // rounding of the enlarged cones' angles.
        radiance * hmax * (1.002 * cos_max / d2)
    }
}

/// The per-node data the SIMD kernels read, built once per light and frame.
pub struct Summaries {
    pub nodes: Vec<NodeSummary>,
    /// Per tree-order triangle position.
    pub leaves: Vec<LeafSummary>,
}

impl Summaries {
    pub fn new(lit: &LitScene) -> Summaries {
        use rayon::prelude::*;
        Summaries {
            nodes: lit
                .nodes
                .par_iter()
                .map(|n| NodeSummary::new(n, lit.light_pos, lit.receiver.anisotropic))
                .collect(),
            leaves: lit.tris.par_iter().map(LeafSummary::new).collect(),
        }
    }
}

/// Evaluates `nodes` at every receiver of `rec` on the lanes of `isa`: a leaf's exact SG
/// transport, an inner node's approximation clamped to `clamp[i]`. `out[i * rec.len + j]` is
/// node `i` at receiver `j` (no visibility).
#[allow(clippy::too_many_arguments)]
pub fn evaluate_nodes(
    isa: Isa,
    lit: &LitScene,
    s: &Summaries,
    nodes: &[u32],
    clamp: &[Vec3],
    rec: &Receivers,
    out: &mut Vec<Vec3>,
) {
    out.clear();
    out.resize(nodes.len() * rec.len, Vec3::ZERO);
    dispatch(
        isa,
        EvalNodes {
            lit,
            s,
            nodes,
            clamp,
            rec,
            out,
        },
    );
}

struct EvalNodes<'a, 'l> {
    lit: &'a LitScene<'l>,
    s: &'a Summaries,
    nodes: &'a [u32],
    clamp: &'a [Vec3],
    rec: &'a Receivers,
    out: &'a mut [Vec3],
}

impl Kernel for EvalNodes<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf>(self) {
        let n = self.rec.len;
        let opts: &ReceiverOptions = &self.lit.receiver;
        let mut buf = [[0.0f32; 16]; 3];
        let mut i = 0;
        while i < self.rec.padded() {
            let rx = ReceiversV::<V>::load(self.rec, i);
            let lanes = V::N.min(n.saturating_sub(i));
            for (k, &node) in self.nodes.iter().enumerate() {
                let tn = &self.lit.tree.nodes[node as usize];
                let v = if tn.is_leaf() {
                    leaf::evaluate(&self.s.leaves[tn.first as usize], &rx, opts)
                } else {
                    let c = self.clamp[k];
                    let v = cluster::evaluate(&self.s.nodes[node as usize], &rx);
                    super::kernel::v3::V3::new(
                        v.x.min(V::splat(c.x)),
                        v.y.min(V::splat(c.y)),
                        v.z.min(V::splat(c.z)),
                    )
                };
                v.x.store(&mut buf[0]);
                v.y.store(&mut buf[1]);
                v.z.store(&mut buf[2]);
                let row = &mut self.out[k * n + i..k * n + i + lanes];
                for (j, o) in row.iter_mut().enumerate() {
                    *o = Vec3::new(buf[0][j], buf[1][j], buf[2][j]);
                }
            }
            i += V::N;
        }
    }
}

/// A group's cut: its nodes (ascending) and each one's group bound.
#[derive(Clone, Debug, Default)]
pub struct GroupCut {
    pub nodes: Vec<u32>,
    pub bounds: Vec<Vec3>,
    /// Nodes whose bound was evaluated during selection, and of those leaves.
    pub evaluated: u64,
    pub leaves: u64,
    /// The selection ended at the cap with nodes of infinite group bound still in the cut
    /// (the group's ball meets their boxes): a smaller group would bound them.
    pub unbounded: bool,
    /// Node `k`'s value at representative `j` (`rep_values[k * m + j]`, `m` representatives),
    /// as [`evaluate_nodes`] gives it: the selection evaluated every node of the cut there, so
    /// shading need not evaluate the representatives again.
    pub rep_values: Vec<Vec3>,
}

/// What the group selection keeps of a node in its heap: its group bound and the row of its
/// values at the representatives in `SelectScratch::values`.
struct Waiting {
    bound: Vec3,
    row: usize,
}

/// Scratch space of [`LitScene::select_group`], reused across groups.
#[derive(Default)]
pub struct SelectScratch {
    values: Vec<Vec3>,
    pair: Vec<Vec3>,
    estimate: Vec<Vec3>,
}

impl LitScene<'_> {
    /// Selects the cut of group `g` (METHOD §6 with the group bound): from the root, repeatedly
    /// replace the node with the largest group bound (luminance) by its two children, until that
    /// bound is at most `threshold` × the smallest positive estimate among the representatives
    /// `reps` (their radiance under the current cut, evaluated on the SIMD lanes) or the cut
    /// holds `max_cut` nodes.
    #[allow(clippy::too_many_arguments)]
    pub fn select_group(
        &self,
        isa: Isa,
        s: &Summaries,
        g: &GroupSummary,
        reps: &Receivers,
        opts: &CutOptions,
        scratch: &mut SelectScratch,
        out: &mut GroupCut,
    ) {
        out.nodes.clear();
        out.bounds.clear();
        out.evaluated = 0;
        out.leaves = 0;
        out.unbounded = false;
        out.rep_values.clear();
        if self.tree.nodes.is_empty() || reps.len == 0 {
            return;
        }
        let cap = if opts.max_cut == 0 {
            usize::MAX
        } else {
            opts.max_cut as usize
        };
        let m = reps.len;
        let values = &mut scratch.values;
        values.clear();
        let root_bound = self.group_bound(0, g);
        evaluate_nodes(isa, self, s, &[0], &[root_bound], reps, &mut scratch.pair);
        values.extend_from_slice(&scratch.pair);
        scratch.estimate.clear();
        scratch.estimate.extend_from_slice(&scratch.pair);
        out.evaluated += 1;
        let mut heap = BinaryHeap::new();
        let mut size = 1usize;
        let mut settled: Vec<(u32, Vec3, usize)> = Vec::new();
        let mut push =
            |node: u32, bound: Vec3, row: usize, heap: &mut BinaryHeap<Pending<Waiting>>| {
                let key = luminance(bound);
                if key > 0.0 || key.is_nan() {
                    let key = if key.is_nan() { f32::INFINITY } else { key };
                    heap.push(Pending {
                        key,
                        node,
                        item: Waiting { bound, row },
                    });
                } else {
                    settled.push((node, bound, row));
                }
            };
        push(0, root_bound, 0, &mut heap);
        let smallest = |est: &[Vec3]| {
            est.iter()
                .map(|e| luminance(*e))
                .filter(|&l| l > 0.0)
                .fold(f32::INFINITY, f32::min)
        };
        let mut floor = smallest(&scratch.estimate);
        while let Some(top) = heap.peek() {
            let limit = if floor.is_finite() {
                opts.threshold * floor
            } else {
                0.0
            };
            if size >= cap || top.key <= limit {
                break;
            }
            let top = heap.pop().expect("peeked");
            let Some([l, r]) = self.tree.nodes[top.node as usize].children else {
                // A leaf with a non-zero bound (none today: a leaf's value is exact).
                push(top.node, Vec3::ZERO, top.item.row, &mut heap);
                continue;
            };
            let bounds = [self.group_bound(l, g), self.group_bound(r, g)];
            evaluate_nodes(isa, self, s, &[l, r], &bounds, reps, &mut scratch.pair);
            out.evaluated += 2;
            for c in [l, r] {
                out.leaves += u64::from(self.tree.nodes[c as usize].is_leaf());
            }
            let row = values.len() / m;
            values.extend_from_slice(&scratch.pair);
            for j in 0..m {
                let e = &mut scratch.estimate[j];
                *e +=
                    values[row * m + j] + values[(row + 1) * m + j] - values[top.item.row * m + j];
            }
            floor = smallest(&scratch.estimate);
            push(l, bounds[0], row, &mut heap);
            push(r, bounds[1], row + 1, &mut heap);
            size += 1;
        }
        out.unbounded = heap.peek().is_some_and(|p| p.key == f32::INFINITY);
        settled.extend(heap.into_iter().map(|p| (p.node, p.item.bound, p.item.row)));
        settled.sort_unstable_by_key(|e| e.0);
        out.nodes.extend(settled.iter().map(|e| e.0));
        out.bounds.extend(settled.iter().map(|e| e.1));
        for &(_, _, row) in &settled {
            out.rep_values
                .extend_from_slice(&values[row * m..(row + 1) * m]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rng;
    use crate::sg::tests::{config, materials};
    use proptest::prelude::*;

    fn rvec(rng: &mut Rng) -> Vec3 {
        Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0
    }

    /// A group of `k` receivers of material `m` clustered around a random point (spread
    /// `spread`): positions, normals and views vary across it as a tile's do.
    fn group(rng: &mut Rng, m: usize, k: usize, spread: f32) -> Vec<(Vec3, ReceiverLobes)> {
        let mats = materials();
        let x0 = rvec(rng) * 2.5;
        let n0 = rvec(rng).try_normalize().unwrap_or(Vec3::Y);
        let eye = x0 + (n0 + rvec(rng) * 0.9) * 3.0;
        (0..k)
            .map(|_| {
                let x = x0 + rvec(rng) * spread;
                let n = (n0 + rvec(rng) * spread).try_normalize().unwrap_or(n0);
                let wo = (eye - x).try_normalize().unwrap_or(n);
                let wo = if wo.dot(n) > 0.05 { wo } else { n };
                (x, ReceiverLobes::new(&mats[m], n, wo))
            })
            .collect()
    }

    /// The representatives' values the selection hands to shading (`GroupCut::rep_values`) are
    /// exactly what evaluating the selected cut at them gives, node for node, with every ISA
    /// (no tolerance: the same lanes run the same arithmetic), and the cut's nodes are distinct
    /// tree nodes. Shading reuses them instead of evaluating the representatives again.
    #[test]
    fn selection_hands_over_the_representatives_values() {
        let mut checked = 0;
        for seed in 0..12u64 {
            let cfg = config(seed, 30, seed % 2 == 0);
            let lit = LitScene::new(
                &cfg.tree,
                cfg.tris.clone(),
                cfg.light,
                ReceiverOptions::default(),
            );
            let s = Summaries::new(&lit);
            let mut rng = Rng::keyed(seed, 41, 7);
            for m in 0..4 {
                let pts: Vec<_> = group(&mut rng, m, 20, 0.1)
                    .into_iter()
                    .filter(|p| !p.1.is_black())
                    .collect();
                if pts.is_empty() {
                    continue;
                }
                let g = GroupSummary::new(&pts);
                let mut reps = Receivers::default();
                for (x, rx) in pts.iter().take(REPRESENTATIVES) {
                    reps.push(*x, rx, true);
                }
                reps.pad();
                for isa in Isa::all_available() {
                    for max_cut in [4, 1000] {
                        let opts = CutOptions {
                            threshold: 0.01,
                            max_cut,
                        };
                        let mut cut = GroupCut::default();
                        let mut scratch = SelectScratch::default();
                        lit.select_group(isa, &s, &g, &reps, &opts, &mut scratch, &mut cut);
                        assert!(cut.nodes.windows(2).all(|w| w[0] < w[1]));
                        let mut direct = Vec::new();
                        evaluate_nodes(isa, &lit, &s, &cut.nodes, &cut.bounds, &reps, &mut direct);
                        assert_eq!(cut.rep_values.len(), cut.nodes.len() * reps.len);
                        assert_eq!(cut.rep_values, direct, "seed {seed} m {m} {isa:?}");
                        checked += usize::from(direct.iter().any(|v| *v != Vec3::ZERO));
                    }
                }
            }
        }
        // Some cuts must carry light, or the comparison above proves nothing.
        assert!(checked > 10, "only {checked} cuts with non-zero values");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The group bound is conservative for every sample of the group: for every node of
        /// random configurations, at every sample it is at least the exact sum of the node's
        /// leaves (the true contribution, which with the clamped approximation lies in
        /// [0, bound]) and at least the point bound. Tolerance: 1e-6 relative plus 1e-12
        /// absolute for the f32 rounding of the sums, as the point bound's own test.
        #[test]
        fn group_bound_holds_for_every_sample(
            seed in 0u64..1_000_000,
            n in 2usize..40,
            sheet: bool,
            spread in 0.005f32..0.4,
        ) {
            let cfg = config(seed, n, sheet);
            let lit = LitScene::new(&cfg.tree, cfg.tris.clone(), cfg.light, ReceiverOptions::default());
            let mut rng = Rng::keyed(seed, 31, 5);
            for m in 0..4 {
                let pts = group(&mut rng, m, 12, spread);
                let pts: Vec<_> = pts.into_iter().filter(|p| !p.1.is_black()).collect();
                if pts.is_empty() {
                    continue;
                }
                let g = GroupSummary::new(&pts);
                for node in 0..cfg.tree.nodes.len() as u32 {
                    let gb = lit.group_bound(node, &g);
                    let tn = &cfg.tree.nodes[node as usize];
                    if tn.is_leaf() {
                        continue;
                    }
                    for (x, rx) in &pts {
                        let exact = lit.tris[tn.range()]
                            .iter()
                            .fold(Vec3::ZERO, |a, t| a + t.shade(*x, rx, &lit.receiver));
                        let pb = lit.bound(node, *x, rx);
                        for c in 0..3 {
                            prop_assert!(
                                exact[c] <= gb[c] * (1.0 + 1e-6) + 1e-12,
                                "node {node} m {m} channel {c}: exact {} > group bound {}",
                                exact[c], gb[c]
                            );
                            prop_assert!(
                                pb[c] <= gb[c] * (1.0 + 1e-6) + 1e-12,
                                "node {node} m {m} channel {c}: point bound {} > group bound {}",
                                pb[c], gb[c]
                            );
                        }
                    }
                }
            }
        }
    }
}
