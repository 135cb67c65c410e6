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
//!
//! **Near nodes.** The ball bound grows without limit as a node comes within the group's radius
//! of the ball (its distance factor `1/(d − r)²`), so near nodes would be refined far below
//! what any one sample needs. [`Group::bound`] therefore takes, for a node whose box lies
//! within [`NEAR`] radii of the group's centre, the smaller of the ball bound and the largest
//! point bound over the group's samples: both are at least the point bound at every sample, so
//! the guarantee holds for either and for their minimum (`group_bound_holds_for_every_sample`
//! checks the near bound too).

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

/// Nodes whose box lies within this many group radii of the group's centre are bounded by
/// the largest point bound over the group's samples where that is smaller than the ball bound
/// (see the module's "Near nodes"). Measured on ring, dragon and bunny
/// (`docs/sg-performance.md`, "Near nodes").
pub const NEAR: usize = 1;

/// A group of receivers as the cut selection sees it: its summary for the ball bound, its
/// samples for the point bounds of near nodes, and how near is near (in group radii; 0 never
/// takes point bounds).
pub struct Group<'a> {
    pub summary: GroupSummary,
    pub points: &'a [(Vec3, ReceiverLobes)],
    pub near: f32,
}

impl<'a> Group<'a> {
    pub fn new(points: &'a [(Vec3, ReceiverLobes)], near: f32) -> Group<'a> {
        Group {
            summary: GroupSummary::new(points),
            points,
            near,
        }
    }

    /// Upper bound of node `node`'s contribution at every sample of the group: the ball bound
    /// ([`LitScene::group_bound`]), or for a near node the smaller of it and the largest point
    /// bound over the samples.
    pub fn bound(&self, lit: &LitScene, node: u32) -> Vec3 {
        let ball = lit.group_bound(node, &self.summary);
        let g = &self.summary;
        if self.points.len() < 2 || !(self.near > 0.0) || ball == Vec3::ZERO {
            return ball;
        }
        let n = &lit.tree.nodes[node as usize];
        let d = (g.centre.clamp(n.bbox_min, n.bbox_max) - g.centre).length();
        if d >= self.near * g.radius {
            return ball;
        }
        // The ball bound stands as soon as one sample's point bound reaches it (e.g. a sample
        // inside the node's box, where both are infinite).
        let mut points = Vec3::ZERO;
        for (x, rx) in self.points {
            points = points.max(lit.bound(node, *x, rx));
            if points.cmpge(ball).all() {
                return ball;
            }
        }
        ball.min(points)
    }
}

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
    /// Node evaluations at the representatives during selection, one per node and
    /// representative (each check of the stopping rule evaluates the whole cut there), and of
    /// those leaves'.
    pub evaluated: u64,
    pub leaves: u64,
    /// Checks of the stopping rule against a freshly evaluated estimate.
    pub checks: u32,
    /// The selection ended at the cap with nodes of infinite group bound still in the cut
    /// (the group's ball meets their boxes): a smaller group would bound them.
    pub unbounded: bool,
    /// Node `k`'s value at representative `j` (`rep_values[k * m + j]`, `m` representatives),
    /// as [`evaluate_nodes`] gives it: the selection evaluated every node of the cut there, so
    /// shading need not evaluate the representatives again.
    pub rep_values: Vec<Vec3>,
}

/// Scratch space of [`LitScene::select_group`], reused across groups.
#[derive(Default)]
pub struct SelectScratch {
    settled: Vec<(u32, Vec3)>,
    cut: Vec<(u32, Vec3)>,
    estimate: Vec<Vec3>,
}

/// The smallest positive luminance among the representatives' estimates (∞ when none is).
fn smallest(est: &[Vec3]) -> f32 {
    est.iter()
        .map(|e| luminance(*e))
        .filter(|&l| l > 0.0)
        .fold(f32::INFINITY, f32::min)
}

impl LitScene<'_> {
    /// Selects the cut of group `g` (METHOD §6 with the group bound, [`Group::bound`]): from the root, repeatedly
    /// replace the node with the largest group bound (luminance) by its two children, until that
    /// bound is at most `threshold` × the smallest positive estimate among the representatives
    /// `reps` (their radiance under the current cut, evaluated on the SIMD lanes) or the cut
    /// holds `max_cut` nodes.
    ///
    /// The order of refinement depends on the bounds alone, so the representatives' values are
    /// needed only to test the stopping rule. They are not evaluated for every node the
    /// selection creates (half of which it refines away again) but for the whole cut when the
    /// rule, tested against the last evaluated estimate, says stop (and at the cap): if the
    /// fresh estimate agrees the selection ends, else it goes on with the fresh estimate, and
    /// checks again no sooner than at 1.5× the size (so all checks together cost at most three
    /// evaluations of the final cut; at the cap, where almost every cut ends, one). A cut can
    /// therefore end later than the eager rule would end it, never earlier, and where both end
    /// at the cap they are the same cut with the same values.
    #[allow(clippy::too_many_arguments)]
    pub fn select_group(
        &self,
        isa: Isa,
        s: &Summaries,
        g: &Group,
        reps: &Receivers,
        opts: &CutOptions,
        scratch: &mut SelectScratch,
        out: &mut GroupCut,
    ) {
        out.nodes.clear();
        out.bounds.clear();
        out.evaluated = 0;
        out.leaves = 0;
        out.checks = 0;
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
        let limit = |floor: f32| {
            if floor.is_finite() {
                opts.threshold * floor
            } else {
                0.0
            }
        };
        let mut heap: BinaryHeap<Pending<Vec3>> = BinaryHeap::new();
        let settled = &mut scratch.settled;
        settled.clear();
        let push = |node: u32,
                    bound: Vec3,
                    heap: &mut BinaryHeap<Pending<Vec3>>,
                    settled: &mut Vec<(u32, Vec3)>| {
            let key = luminance(bound);
            if key > 0.0 || key.is_nan() {
                let key = if key.is_nan() { f32::INFINITY } else { key };
                heap.push(Pending {
                    key,
                    node,
                    item: bound,
                });
            } else {
                settled.push((node, bound));
            }
        };
        push(0, g.bound(self, 0), &mut heap, settled);
        let mut size = 1usize;
        // The estimate's floor at the last check (none yet), and the size from which the next
        // check may run.
        let mut floor: Option<f32> = None;
        let mut next_check = 1usize;
        loop {
            let top = heap.peek().map(|p| p.key);
            let forced = size >= cap || top.is_none();
            let says_stop = match (floor, top) {
                (Some(f), Some(k)) => k <= limit(f),
                _ => true,
            };
            if forced || (says_stop && size >= next_check) {
                let cut = &mut scratch.cut;
                cut.clear();
                cut.extend_from_slice(settled);
                cut.extend(heap.iter().map(|p| (p.node, p.item)));
                cut.sort_unstable_by_key(|e| e.0);
                out.nodes.clear();
                out.bounds.clear();
                out.nodes.extend(cut.iter().map(|e| e.0));
                out.bounds.extend(cut.iter().map(|e| e.1));
                evaluate_nodes(
                    isa,
                    self,
                    s,
                    &out.nodes,
                    &out.bounds,
                    reps,
                    &mut out.rep_values,
                );
                out.checks += 1;
                let leaves = out
                    .nodes
                    .iter()
                    .filter(|&&v| self.tree.nodes[v as usize].is_leaf())
                    .count();
                out.evaluated += (out.nodes.len() * m) as u64;
                out.leaves += (leaves * m) as u64;
                let est = &mut scratch.estimate;
                est.clear();
                est.resize(m, Vec3::ZERO);
                for row in out.rep_values.chunks_exact(m) {
                    for (e, v) in est.iter_mut().zip(row) {
                        *e += *v;
                    }
                }
                let fresh = smallest(est);
                if forced || top.is_some_and(|k| k <= limit(fresh)) {
                    out.unbounded = top == Some(f32::INFINITY);
                    return;
                }
                floor = Some(fresh);
                next_check = size + size.div_ceil(2);
            }
            let top = heap.pop().expect("not forced: the heap holds a node");
            let Some([l, r]) = self.tree.nodes[top.node as usize].children else {
                // A leaf with a non-zero bound (none today: a leaf's value is exact).
                settled.push((top.node, Vec3::ZERO));
                continue;
            };
            for c in [l, r] {
                push(c, g.bound(self, c), &mut heap, settled);
            }
            size += 1;
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
                let g = Group::new(&pts, NEAR as f32);
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

    /// The cut after `steps` refinements by the group bound alone (the order `select_group`
    /// follows): its nodes (ascending) with their bounds, and the largest key left to refine.
    fn refined(lit: &LitScene, g: &Group, steps: usize) -> (Vec<(u32, Vec3)>, Option<f32>) {
        let mut heap = BinaryHeap::new();
        let mut cut = Vec::new();
        let add = |node: u32, heap: &mut BinaryHeap<Pending<Vec3>>, cut: &mut Vec<(u32, Vec3)>| {
            let b = g.bound(lit, node);
            let key = luminance(b);
            if key > 0.0 || key.is_nan() {
                let key = if key.is_nan() { f32::INFINITY } else { key };
                heap.push(Pending { key, node, item: b });
            } else {
                cut.push((node, b));
            }
        };
        add(0, &mut heap, &mut cut);
        for _ in 0..steps {
            let Some(top) = heap.pop() else { break };
            let [l, r] = lit.tree.nodes[top.node as usize]
                .children
                .expect("leaves have bound 0");
            add(l, &mut heap, &mut cut);
            add(r, &mut heap, &mut cut);
        }
        let top = heap.peek().map(|p| p.key);
        cut.extend(heap.into_iter().map(|p| (p.node, p.item)));
        cut.sort_unstable_by_key(|e| e.0);
        (cut, top)
    }

    /// The stopping rule at a cut: its largest key at most `threshold` × the smallest positive
    /// estimate of the representatives (evaluated afresh), or nothing left to refine.
    fn rule_holds(
        lit: &LitScene,
        s: &Summaries,
        reps: &Receivers,
        threshold: f32,
        cut: &[(u32, Vec3)],
        top: Option<f32>,
    ) -> bool {
        let nodes: Vec<u32> = cut.iter().map(|e| e.0).collect();
        let bounds: Vec<Vec3> = cut.iter().map(|e| e.1).collect();
        let mut v = Vec::new();
        evaluate_nodes(Isa::Scalar, lit, s, &nodes, &bounds, reps, &mut v);
        let mut est = vec![Vec3::ZERO; reps.len];
        for row in v.chunks_exact(reps.len) {
            for (e, x) in est.iter_mut().zip(row) {
                *e += *x;
            }
        }
        let floor = smallest(&est);
        let limit = if floor.is_finite() {
            threshold * floor
        } else {
            0.0
        };
        top.is_none_or(|k| k <= limit)
    }

    /// `select_group` checks its stopping rule only now and then (its doc): against the eager
    /// rule, which tests it after every refinement, its cut is the same where the eager one ends
    /// at the cap, never smaller, always a cut of the bound order (the eager selection's cut at
    /// the same size), and one at which the rule holds unless it is at the cap. Its
    /// representatives' values are the ones the cut gives there.
    #[test]
    fn lazy_checks_end_where_the_eager_rule_would_or_later() {
        let (mut at_cap, mut early, mut later) = (0, 0, 0);
        for seed in 0..16u64 {
            let cfg = config(seed, 24, seed % 3 == 0);
            let lit = LitScene::new(
                &cfg.tree,
                cfg.tris.clone(),
                cfg.light,
                ReceiverOptions::default(),
            );
            let s = Summaries::new(&lit);
            let mut rng = Rng::keyed(seed, 43, 9);
            for m in 0..4 {
                let pts: Vec<_> = group(&mut rng, m, 20, 0.05)
                    .into_iter()
                    .filter(|p| !p.1.is_black())
                    .collect();
                if pts.is_empty() {
                    continue;
                }
                let g = Group::new(&pts, NEAR as f32);
                let mut reps = Receivers::default();
                for (x, rx) in pts.iter().take(REPRESENTATIVES) {
                    reps.push(*x, rx, true);
                }
                reps.pad();
                for threshold in [0.0, 0.01, 0.1, 0.5] {
                    for max_cut in [6, 1000] {
                        let opts = CutOptions { threshold, max_cut };
                        let mut cut = GroupCut::default();
                        let mut scratch = SelectScratch::default();
                        lit.select_group(Isa::Scalar, &s, &g, &reps, &opts, &mut scratch, &mut cut);
                        let size = cut.nodes.len();
                        // The eager stop: the first size at which the rule holds or the cap is met.
                        let eager = (1..=max_cut as usize)
                            .find(|&k| {
                                let (c, top) = refined(&lit, &g, k - 1);
                                c.len() < k
                                    || k == max_cut as usize
                                    || rule_holds(&lit, &s, &reps, threshold, &c, top)
                            })
                            .expect("the cap ends it");
                        let (want, top) = refined(&lit, &g, size - 1);
                        let what = format!("seed {seed} m {m} threshold {threshold} cap {max_cut}");
                        assert_eq!(
                            cut.nodes,
                            want.iter().map(|e| e.0).collect::<Vec<_>>(),
                            "{what}"
                        );
                        assert_eq!(
                            cut.bounds,
                            want.iter().map(|e| e.1).collect::<Vec<_>>(),
                            "{what}"
                        );
                        let (eager_cut, _) = refined(&lit, &g, eager - 1);
                        assert!(
                            size >= eager_cut.len(),
                            "{what}: {size} < eager {}",
                            eager_cut.len()
                        );
                        if eager_cut.len() == max_cut as usize {
                            assert_eq!(size, max_cut as usize, "{what}");
                            at_cap += 1;
                        } else if size < max_cut as usize {
                            assert!(rule_holds(&lit, &s, &reps, threshold, &want, top), "{what}");
                            early += 1;
                            later += usize::from(size > eager_cut.len());
                        }
                        let mut direct = Vec::new();
                        evaluate_nodes(
                            Isa::Scalar,
                            &lit,
                            &s,
                            &cut.nodes,
                            &cut.bounds,
                            &reps,
                            &mut direct,
                        );
                        assert_eq!(cut.rep_values, direct, "{what}");
                    }
                }
            }
        }
        // Both endings must occur, or half of the comparison proves nothing.
        assert!(at_cap > 10 && early > 10, "at cap {at_cap}, early {early}");
        eprintln!(
            "cuts at the cap {at_cap}, ended by the rule {early} (of those later than eager: {later})"
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// The group bound is conservative for every sample of the group: for every node of
        /// random configurations, at every sample it is at least the exact sum of the node's
        /// leaves (the true contribution, which with the clamped approximation lies in
        /// [0, bound]) and at least the point bound; the near bound ([`Group::bound`]) too, and
        /// it is never above the ball bound. Tolerance: 1e-6 relative plus 1e-12
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
                // The near bound, with every node near and with the default reach.
                let all_near = Group::new(&pts, f32::INFINITY);
                let near = Group::new(&pts, NEAR as f32);
                for node in 0..cfg.tree.nodes.len() as u32 {
                    let gb = lit.group_bound(node, &g);
                    let tn = &cfg.tree.nodes[node as usize];
                    if tn.is_leaf() {
                        continue;
                    }
                    let nb = [all_near.bound(&lit, node), near.bound(&lit, node)];
                    for b in nb {
                        for c in 0..3 {
                            // The near bound takes a minimum with the ball bound: never above it.
                            prop_assert!(b[c] <= gb[c], "node {node}: near {} > ball {}", b[c], gb[c]);
                        }
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
                            for b in nb {
                                prop_assert!(
                                    exact[c] <= b[c] * (1.0 + 1e-6) + 1e-12,
                                    "node {node} m {m} channel {c}: exact {} > near bound {}",
                                    exact[c], b[c]
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}
