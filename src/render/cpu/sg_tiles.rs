//! Tile cuts (`CutMode::Tile`, `--cut tile`; `docs/sg-performance.md`): the samples of one
//! screen tile that share a material form a group, which selects one cut with the group bound
//! (`sg::group`) and evaluates every node of it for all its samples on the SIMD lanes; then
//! each sample weighs the values by its own visibility.
//!
//! With shadow rays (`--visibility exact`) a sample traces rays for its cut's largest values
//! until the untraced rest holds at most [`RAY_TAIL`] of its estimate; the rest is weighed by
//! the traced values' mean visibility (weighted by luminance).

use super::sg::{ApproxVisibility, Ctx, NodeView, SharedRays, Tally};
use crate::accel::Hit;
use crate::math::luminance;
use crate::render::cpu::Progress;
use crate::render::cpu::surface::SurfacePoint;
use crate::sg::group::{
    Group, GroupCut, NEAR, REPRESENTATIVES, SelectScratch, Summaries, evaluate_nodes,
};
use crate::sg::kernel::maps::map_visibility;
use crate::sg::kernel::receivers::Receivers;
use crate::sg::kernel::simd::Isa;
use crate::sg::transport::receiver::ReceiverLobes;
use crate::sg::{CutCounters, LitScene};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::Ordering;

/// Largest part of a sample's estimate whose visibility is not traced but taken as the traced
/// part's mean (exact visibility). Measured on ring, dragon and bunny at 256×192
/// (`docs/sg-performance.md`).
pub const RAY_TAIL: f32 = 0.05;

/// Samples per group at most (the tile's side shrinks with the samples per pixel).
pub const GROUP_SAMPLES: usize = 64;

/// Smallest group that is split in two when its cut ends at the cap with nodes of infinite
/// group bound (`GroupCut::unbounded`), or the size `INTERREFLECT_SPLIT_MIN` asks for (a
/// measurement knob, `docs/sg-performance.md`; 0 never splits).
pub fn split_min() -> usize {
    env_knob("INTERREFLECT_SPLIT_MIN").unwrap_or(SPLIT_MIN)
}

/// How near (in group radii) a node must be for the group bound to try the samples' point
/// bounds (`sg::group::NEAR`), or the reach `INTERREFLECT_NEAR` asks for (a measurement knob,
/// `docs/sg-performance.md`; 0 never tries them).
pub fn near() -> f32 {
    env_knob("INTERREFLECT_NEAR").unwrap_or(NEAR) as f32
}

/// Samples of a group that must trace a node before its rays are shared
/// ([`Ctx::traced_group`]), or the count `INTERREFLECT_SHARE` asks for (a measurement knob,
/// `docs/sg-performance.md`; 0 never shares).
pub fn share_min() -> usize {
    env_knob("INTERREFLECT_SHARE").unwrap_or(SHARE_MIN)
}

/// See [`share_min`].
pub const SHARE_MIN: usize = 32;

/// A measurement knob from the environment: the variable's value if it parses as a count.
fn env_knob(name: &str) -> Option<usize> {
    std::env::var(name).ok().and_then(|v| v.parse().ok())
}

/// See [`split_min`]: groups of more than this many samples are split.
pub const SPLIT_MIN: usize = 1;

/// Tile side in pixels for `spp` samples per pixel: about [`GROUP_SAMPLES`] samples a tile,
/// or the side the environment variable `INTERREFLECT_TILE_SIDE` asks for (a measurement knob:
/// `docs/sg-performance.md` sweeps it).
pub fn tile_side(spp: u32) -> usize {
    if let Some(side) = env_knob("INTERREFLECT_TILE_SIDE").filter(|v| (1..=64).contains(v)) {
        return side;
    }
    let per_side = (spp as f64).sqrt().ceil() as usize;
    (8 / per_side.max(1)).max(1)
}

/// What every tile of a frame's pass shares.
struct Pass<'p> {
    isa: Isa,
    /// Per light: its tree's node and leaf summaries for the kernel.
    summaries: &'p [Summaries],
    /// Groups of more than this many samples whose cut is unbounded are halved (0: never).
    split: usize,
    /// Reach of the near bound in group radii (0: ball bound only).
    near: f32,
    /// Nodes that at least this many of a group's samples trace share their rays (0: never).
    share: usize,
    tally: &'p Tally,
}

/// One receiver sample of a tile.
pub(super) struct Sample {
    /// Index into the frame's samples (pixel × spp + s).
    index: usize,
    /// Material index and the receiver's lobe count (0: diffuse only).
    pub(super) material: (u32, usize),
    pub(super) x: Vec3,
    xo: Vec3,
    pub(super) rx: ReceiverLobes,
}

/// What a tile returns: per receiver sample, its index, indirect light and cut size.
type TileOut = Vec<(usize, Vec3, f32)>;

impl Ctx<'_> {
    /// Per light: its tree's summaries for the kernel, which every [`Ctx::tile_indirect`]
    /// call of a frame shares.
    pub(super) fn tile_summaries(&self) -> Vec<Summaries> {
        self.lits.iter().map(Summaries::new).collect()
    }

    /// The indirect light of every sample (`hits`) with tile cuts of `side` pixels, and each
    /// sample's cut size (summed over the lights); `summaries` are
    /// [`Ctx::tile_summaries`]. `None` when cancelled.
    pub(super) fn tile_indirect(
        &self,
        hits: &[Option<Hit>],
        side: usize,
        summaries: &[Summaries],
        tally: &Tally,
        progress: &Progress,
    ) -> Option<(Vec<Vec3>, Vec<f32>)> {
        let pass = Pass {
            isa: Isa::detect(),
            summaries,
            split: split_min(),
            near: near(),
            share: share_min(),
            tally,
        };
        let (w, h) = (self.opts.width as usize, self.opts.height as usize);
        let spp = self.opts.spp as usize;
        let (tx, ty) = (w.div_ceil(side), h.div_ceil(side));
        let tiles: Vec<TileOut> = (0..tx * ty)
            .into_par_iter()
            .map_init(TileScratch::default, |scratch, t| {
                if progress.cancel.load(Ordering::Relaxed) {
                    return Vec::new();
                }
                let (x0, y0) = ((t % tx) * side, (t / tx) * side);
                let out = self.shade_tile(&pass, hits, (x0, y0, side, w, h, spp), scratch);
                if t % tx == tx - 1 {
                    (progress.done)(side.min(h - y0) as u64);
                }
                out
            })
            .collect();
        if progress.cancel.load(Ordering::Relaxed) {
            return None;
        }
        let mut values = vec![Vec3::ZERO; hits.len()];
        let mut sizes = vec![0f32; hits.len()];
        for (i, v, s) in tiles.into_iter().flatten() {
            values[i] = v;
            sizes[i] = s;
        }
        Some((values, sizes))
    }

    /// The tile at pixel (x0, y0), `side` pixels wide, of a `w` × `h` image.
    fn shade_tile(
        &self,
        pass: &Pass,
        hits: &[Option<Hit>],
        (x0, y0, side, w, h, spp): (usize, usize, usize, usize, usize, usize),
        scratch: &mut TileScratch,
    ) -> TileOut {
        let mut samples = Vec::new();
        for y in y0..(y0 + side).min(h) {
            for x in x0..(x0 + side).min(w) {
                for s in 0..spp {
                    let index = (y * w + x) * spp + s;
                    if let Some(sample) = self.receiver_sample(hits[index].as_ref(), index) {
                        samples.push(sample);
                    }
                }
            }
        }
        // Groups: one material each, in a fixed order (material, then sample index).
        samples.sort_by_key(|s| (s.material, s.index));
        let mut out = Vec::with_capacity(samples.len());
        for group in samples.chunk_by_mut(|a, b| a.material == b.material) {
            for chunk in group.chunks_mut(GROUP_SAMPLES) {
                self.shade_group(pass, chunk, scratch, &mut out);
            }
        }
        out
    }

    /// A sample's receiver data, when it receives indirect light.
    pub(super) fn receiver_sample(&self, hit: Option<&Hit>, index: usize) -> Option<Sample> {
        let hit = hit?;
        if !self.scene.tri_object(hit.tri).receiver {
            return None;
        }
        let wo = (self.camera_pos - self.scene.mesh.point(hit.tri, hit.u, hit.v)).normalize();
        let sp = SurfacePoint::from_hit(self.scene, hit, wo)?;
        let rx = ReceiverLobes::new(self.scene.tri_material(hit.tri), sp.frame.n, wo);
        if rx.is_black() {
            return None;
        }
        Some(Sample {
            index,
            material: (self.scene.tri_material_index(hit.tri), rx.lobes().len()),
            x: sp.p,
            xo: sp.offset(self.eps),
            rx,
        })
    }

    /// Selects the group's cuts and shades its samples; a group whose cut ends at the cap with
    /// nodes of infinite bound and has more than `split` samples (`split` > 0) is split in two
    /// halves along its positions' longest axis instead, and each half is shaded on its own.
    fn shade_group(
        &self,
        pass: &Pass,
        group: &mut [Sample],
        sc: &mut TileScratch,
        out: &mut TileOut,
    ) {
        let Pass {
            isa,
            summaries,
            split,
            near,
            share,
            tally,
        } = *pass;
        let n = group.len();
        let points: Vec<(Vec3, ReceiverLobes)> = group.iter().map(|s| (s.x, s.rx)).collect();
        let group_bound = Group::new(&points, near);
        // The representatives estimate during selection; the selection's values at them are
        // reused, so shading evaluates the cut at the others (`rest`) only.
        let m = n.min(REPRESENTATIVES);
        sc.reps.clear();
        sc.rec.clear();
        sc.source.clear();
        let mut next_rep = 0;
        for (j, s) in group.iter().enumerate() {
            if next_rep < m && j == next_rep * n / m {
                sc.source.push(Column::Rep(next_rep));
                sc.reps.push(s.x, &s.rx, true);
                next_rep += 1;
            } else {
                sc.source.push(Column::Rest(sc.rec.len));
                sc.rec.push(s.x, &s.rx, true);
            }
        }
        sc.reps.pad();
        sc.rec.pad();
        let rest = sc.rec.len;
        let mut radiance = vec![Vec3::ZERO; n];
        let mut size = 0usize;
        let mut rays = 0u64;
        let mut shaded = 0u64;
        for (k, (lit, sums)) in self.lits.iter().zip(summaries).enumerate() {
            lit.select_group(
                isa,
                sums,
                &group_bound,
                &sc.reps,
                &self.opts.cut,
                &mut sc.select,
                &mut sc.cut,
            );
            if sc.cut.unbounded && split > 0 && n > split {
                // The work so far is counted; the halves start again from the first light.
                tally.add_counters(&CutCounters {
                    evaluated: sc.cut.evaluated,
                    leaves: sc.cut.leaves,
                });
                tally.rays.fetch_add(rays, Ordering::Relaxed);
                let (a, b) = halve(group);
                self.shade_group(pass, a, sc, out);
                self.shade_group(pass, b, sc, out);
                return;
            }
            shaded += n as u64;
            tally.add_cut(
                sc.cut.nodes.len(),
                &CutCounters {
                    evaluated: sc.cut.evaluated,
                    leaves: sc.cut.leaves,
                },
            );
            size += sc.cut.nodes.len();
            let cut = &sc.cut;
            sc.values.clear();
            if rest > 0 {
                evaluate_nodes(
                    isa,
                    lit,
                    sums,
                    &cut.nodes,
                    &cut.bounds,
                    &sc.rec,
                    &mut sc.values,
                );
            }
            let leaves = cut
                .nodes
                .iter()
                .filter(|&&v| lit.tree.nodes[v as usize].is_leaf())
                .count();
            tally.add_counters(&CutCounters {
                evaluated: (cut.nodes.len() * rest) as u64,
                leaves: (leaves * rest) as u64,
            });
            let (values, rep_values, source) = (&sc.values, &cut.rep_values, &sc.source);
            let value = |j: usize, i: usize| match source[j] {
                Column::Rep(r) => rep_values[i * m + r],
                Column::Rest(q) => values[i * rest + q],
            };
            match self.vpl_vis(k) {
                Some(vv) => {
                    approx_visible(
                        isa,
                        vv,
                        &cut.nodes,
                        group,
                        value,
                        &mut sc.approx,
                        &mut radiance,
                    );
                }
                None => {
                    rays += self.traced_group(
                        lit,
                        k,
                        &cut.nodes,
                        group,
                        value,
                        share,
                        &mut sc.rays,
                        &mut radiance,
                    );
                }
            }
        }
        tally.rays.fetch_add(rays, Ordering::Relaxed);
        tally.shading_points.fetch_add(shaded, Ordering::Relaxed);
        let size = size as f32;
        out.extend(group.iter().zip(radiance).map(|(s, v)| (s.index, v, size)));
    }

    /// The group's radiance over a cut with shadow rays, added to `radiance`: each sample
    /// traces rays for its largest values until the untraced rest is at most [`RAY_TAIL`] of
    /// its sum, and the rest takes the traced part's mean visibility ([`plan_rays`]). A node
    /// that at least `share` samples trace (and `share` > 0) has the rays to its targets
    /// ([`Ctx::node_targets`]) traced from probes spread over the group ([`spread_probes`])
    /// first; where they all agree, every sample takes their result instead of tracing its own
    /// ([`SHARE_MIN`], `docs/sg-performance.md`). Returns the rays traced.
    #[allow(clippy::too_many_arguments)]
    fn traced_group(
        &self,
        lit: &LitScene,
        k: usize,
        nodes: &[u32],
        group: &[Sample],
        value: impl Fn(usize, usize) -> Vec3,
        share: usize,
        sc: &mut RayScratch,
        radiance: &mut [Vec3],
    ) -> u64 {
        let n = group.len();
        sc.plans.clear();
        sc.starts.clear();
        sc.rest.clear();
        for j in 0..n {
            sc.starts.push(sc.plans.len());
            let rest = plan_rays(|i| value(j, i), nodes.len(), &mut sc.order, &mut sc.plans);
            sc.rest.push(rest);
        }
        sc.starts.push(sc.plans.len());
        let mut rays = 0u64;
        sc.shared.clear();
        sc.shared.resize(nodes.len(), SharedRays::NONE);
        let m = n.min(REPRESENTATIVES);
        if share > 0 && n >= share && m > 1 {
            sc.count.clear();
            sc.count.resize(nodes.len(), 0);
            for &(i, _) in &sc.plans {
                sc.count[i as usize] += 1;
            }
            spread_probes(n, |j| group[j].xo, m, &mut sc.reach, &mut sc.probes);
            for (i, &node) in nodes.iter().enumerate() {
                if (sc.count[i] as usize) < share {
                    continue;
                }
                let mut shared = SharedRays::NONE;
                for (t, p) in self.node_targets(lit, node).into_iter().enumerate() {
                    let Some(p) = p else { continue };
                    let (mut any, mut all) = (false, true);
                    for &r in &sc.probes {
                        rays += 1;
                        let v = self.ray_visible(group[r as usize].xo, p);
                        any |= v;
                        all &= v;
                        if any && !all {
                            break;
                        }
                    }
                    if any == all {
                        shared.known |= 1 << t;
                        shared.visible |= u8::from(all) << t;
                    }
                }
                sc.shared[i] = shared;
            }
        }
        for (j, s) in group.iter().enumerate() {
            let (mut traced, mut seen, mut lit_sum) = (0.0f32, 0.0f32, Vec3::ZERO);
            for &(i, l) in &sc.plans[sc.starts[j]..sc.starts[j + 1]] {
                let i = i as usize;
                let tn = &lit.tree.nodes[nodes[i] as usize];
                let (f, r) = if tn.is_leaf() {
                    self.triangle_visibility_shared(
                        s.xo,
                        &lit.tris[tn.first as usize],
                        k,
                        &s.rx,
                        sc.shared[i],
                    )
                } else {
                    self.node_visibility_shared(s.xo, lit, nodes[i], sc.shared[i])
                };
                rays += r;
                traced += l;
                seen += l * f;
                lit_sum += value(j, i) * f;
            }
            let mean = if traced > 0.0 { seen / traced } else { 1.0 };
            radiance[j] += lit_sum + sc.rest[j] * mean;
        }
        rays
    }
}

/// Which of a sample's values over a cut (`value(i)`, i < `len`) get shadow rays: the largest
/// (by luminance; ties by position, so the order is deterministic) until the untraced rest is
/// at most [`RAY_TAIL`] of the sum. Appends them to `plan` as (position, luminance), largest
/// first, and returns the sum of the rest.
fn plan_rays(
    value: impl Fn(usize) -> Vec3,
    len: usize,
    order: &mut Vec<(f32, u32)>,
    plan: &mut Vec<(u32, f32)>,
) -> Vec3 {
    order.clear();
    let mut total = 0.0f32;
    for i in 0..len {
        let l = luminance(value(i)).max(0.0);
        if l > 0.0 {
            order.push((l, i as u32));
            total += l;
        }
    }
    // Largest first; ties by position. Only the traced values need their order, so they are
    // selected in chunks of doubling size (each chunk the largest of what is left, then
    // sorted) until the untraced rest is small enough; the rest is summed unsorted.
    let cmp = |a: &(f32, u32), b: &(f32, u32)| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1));
    let tail = RAY_TAIL * total;
    let (mut traced, mut rest) = (0.0f32, Vec3::ZERO);
    let (mut start, mut chunk) = (0, 32);
    let mut stop = order.len();
    'chunks: while start < order.len() {
        let end = (start + chunk).min(order.len());
        if end < order.len() {
            order[start..].select_nth_unstable_by(end - start - 1, cmp);
        }
        order[start..end].sort_unstable_by(cmp);
        for (at, &(l, i)) in order[start..end].iter().enumerate() {
            if total - traced <= tail {
                stop = start + at;
                break 'chunks;
            }
            traced += l;
            plan.push((i, l));
        }
        start = end;
        chunk *= 2;
    }
    for &(_, i) in &order[stop..] {
        rest += value(i as usize);
    }
    rest
}

/// The two halves of `group` along the longest axis of its positions' bounding box (ties by
/// sample index, so the split is the same on every run).
fn halve(group: &mut [Sample]) -> (&mut [Sample], &mut [Sample]) {
    let (lo, hi) = group.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), s| (lo.min(s.x), hi.max(s.x)),
    );
    let axis = (hi - lo).max_position();
    group.sort_unstable_by(|a, b| a.x[axis].total_cmp(&b.x[axis]).then(a.index.cmp(&b.index)));
    let mid = group.len() / 2;
    group.split_at_mut(mid)
}

/// The group's radiance over a cut with the visibility maps of `--visibility approx`, added to
/// `radiance`: sample j's is Σ_i value(j, i) · visibility(node i, its point), summed in the
/// cut's order. The nodes run in the outer loop, so each node's map is resolved once, its
/// texels stay in cache while every sample of the group reads them, and a node map is read
/// for all the samples at once on the lanes of `isa` (`sg::kernel::maps`, bit for bit the
/// scalar lookup; `docs/sg-performance.md`: "The approx lookups, node by node").
fn approx_visible(
    isa: Isa,
    vv: &ApproxVisibility,
    nodes: &[u32],
    group: &[Sample],
    value: impl Fn(usize, usize) -> Vec3,
    sc: &mut ApproxScratch,
    radiance: &mut [Vec3],
) {
    let n = group.len();
    for (k, p) in sc.points.iter_mut().enumerate() {
        p.clear();
        p.extend(group.iter().map(|s| s.xo[k]));
    }
    sc.lit.clear();
    sc.lit.resize(n, Vec3::ZERO);
    sc.vis.resize(n, 0.0);
    for (i, &node) in nodes.iter().enumerate() {
        let vis = &mut sc.vis[..n];
        match vv.node_view(node) {
            NodeView::Map(Some(map)) => {
                let [x, y, z] = &sc.points;
                map_visibility(isa, &map, [x, y, z], 1.0, vis);
            }
            view => {
                for (v, s) in vis.iter_mut().zip(group) {
                    *v = view.at(s.xo);
                }
            }
        }
        for (j, (l, &f)) in sc.lit.iter_mut().zip(vis.iter()).enumerate() {
            let v = value(j, i);
            if v != Vec3::ZERO {
                *l += v * f;
            }
        }
    }
    for (r, l) in radiance.iter_mut().zip(&sc.lit) {
        *r += *l;
    }
}

/// Per-thread buffers of [`approx_visible`]: the group's points (x, y and z), one node's
/// visibility of each and each sample's sum.
#[derive(Default)]
struct ApproxScratch {
    points: [Vec<f32>; 3],
    vis: Vec<f32>,
    lit: Vec<Vec3>,
}

/// Where a sample's values over the cut are: the selection's column of representative r
/// (`GroupCut::rep_values`), or shading's column q of the other samples.
#[derive(Clone, Copy)]
enum Column {
    Rep(usize),
    Rest(usize),
}

/// Per-thread buffers of the tile pass.
#[derive(Default)]
struct TileScratch {
    rec: Receivers,
    reps: Receivers,
    select: SelectScratch,
    cut: GroupCut,
    values: Vec<Vec3>,
    approx: ApproxScratch,
    /// Per sample of the group: where its values are (see `shade_group`).
    source: Vec<Column>,
    rays: RayScratch,
}

/// Per-thread buffers of [`Ctx::traced_group`].
#[derive(Default)]
struct RayScratch {
    order: Vec<(f32, u32)>,
    /// Every sample's planned rays (`plan_rays`), sample j's at `starts[j]..starts[j + 1]`.
    plans: Vec<(u32, f32)>,
    starts: Vec<usize>,
    /// Per sample: the sum of its untraced values.
    rest: Vec<Vec3>,
    /// Per cut node: how many samples trace it, and the rays they share.
    count: Vec<u32>,
    shared: Vec<SharedRays>,
    /// The group's probes ([`spread_probes`]) and each sample's squared distance to them.
    probes: Vec<u32>,
    reach: Vec<f32>,
}

/// Up to `m` of the group's `n` samples (at positions `pos(j)`), spread over it, whose
/// shadow rays stand for the group's ([`Ctx::traced_group`]). The first are the group's
/// extremes: the sample farthest from the centroid, then the samples extreme along eight
/// directions, 45° apart, in the plane of the group's two widest spreads. A half-plane that
/// holds any sample holds a vertex of their convex hull, and on a tile (a quadrilateral of
/// samples, flat or seen in perspective) these extremes are its corners, so a shadow edge
/// that is straight across the tile cannot leave every probe on one side of it. The rest
/// fill the largest gaps by farthest-point sampling. Ties go to the lower index, so the
/// choice is deterministic, and a sample at the position of an earlier probe is never
/// picked.
fn spread_probes(
    n: usize,
    pos: impl Fn(usize) -> Vec3,
    m: usize,
    reach: &mut Vec<f32>,
    probes: &mut Vec<u32>,
) {
    probes.clear();
    reach.clear();
    if n == 0 || m == 0 {
        return;
    }
    // The lowest index where `key` is largest.
    let argmax = |key: &dyn Fn(usize) -> f32| {
        let (mut best, mut top) = (0, key(0));
        for j in 1..n {
            let k = key(j);
            if k > top {
                (best, top) = (j, k);
            }
        }
        best
    };
    let centroid = (0..n).map(&pos).sum::<Vec3>() / n as f32;
    let first = argmax(&|j| pos(j).distance_squared(centroid));
    let e1 = (pos(first) - centroid).normalize_or_zero();
    let off_axis = |j: usize| {
        let d = pos(j) - centroid;
        d - e1 * e1.dot(d)
    };
    let e2 = off_axis(argmax(&|j| off_axis(j).length_squared())).normalize_or_zero();
    // `reach[j]`: sample j's squared distance to the nearest probe so far.
    let anchor = pos(first);
    reach.extend((0..n).map(|j| pos(j).distance_squared(anchor)));
    probes.push(first as u32);
    let add = |j: usize, reach: &mut [f32], probes: &mut Vec<u32>| {
        probes.push(j as u32);
        let p = pos(j);
        for (i, d) in reach.iter_mut().enumerate() {
            *d = d.min(pos(i).distance_squared(p));
        }
    };
    for k in 0..8 {
        if probes.len() == m {
            return;
        }
        let (s, c) = (k as f32 * std::f32::consts::FRAC_PI_4).sin_cos();
        let dir = e1 * c + e2 * s;
        let j = argmax(&|j| dir.dot(pos(j) - centroid));
        if reach[j] > 0.0 {
            add(j, reach, probes);
        }
    }
    while probes.len() < m {
        let j = argmax(&|j| reach[j]);
        if reach[j] <= 0.0 {
            return;
        }
        add(j, reach, probes);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sampling::Rng;

    /// Which side of the line `a·(x, z) = c` each probe and each sample is on: a straight
    /// shadow edge that splits the samples must split the probes too, or the shared rays
    /// would give one side the other side's visibility.
    fn split_unseen(points: &[Vec3], probes: &[u32], a: (f32, f32), c: f32) -> bool {
        let side = |p: Vec3| a.0 * p.x + a.1 * p.z > c;
        let all = (
            points.iter().any(|&p| side(p)),
            points.iter().any(|&p| !side(p)),
        );
        let seen = (
            probes.iter().any(|&j| side(points[j as usize])),
            probes.iter().any(|&j| !side(points[j as usize])),
        );
        all.0 && all.1 && !(seen.0 && seen.1)
    }

    /// On tiles of 8 × 8 samples (flat, tilted with perspective-like spacing, and stretched
    /// and turned in a sloping plane), the 16 spread probes include the tile's corners, are
    /// distinct, and no line across the tile splits its samples without splitting the probes
    /// (2000 random lines each). The probes the rays were first shared from, every fourth
    /// sample in scan order (columns 0 and 4), miss such splits: the test checks that it can
    /// tell the two apart.
    #[test]
    fn spread_probes_see_every_straight_split() {
        let mut rng = Rng::keyed(26, 1, 0);
        // Pixel (x, y) of the tile at a world point on a plane: `tilt` slopes the plane and
        // makes the spacing grow with y (a plane seen in perspective); `turn` stretches x
        // three times and turns the tile in a plane that slopes with x.
        let tiles = [(0.0f32, None), (0.3, None), (0.8, None), (2.0, None)]
            .into_iter()
            .chain([0.1f32, 0.7, 1.3].map(|a| (0.0, Some(a))));
        for (tilt, turn) in tiles {
            let points: Vec<Vec3> = (0..64)
                .map(|j| {
                    let (x, y) = ((j % 8) as f32, (j / 8) as f32);
                    if let Some(a) = turn {
                        let (s, c) = a.sin_cos();
                        return Vec3::new(3.0 * x * c - y * s, 0.5 * x, 3.0 * x * s + y * c);
                    }
                    // A homography of the pixel grid, as a camera sees a plane: lines stay
                    // lines and the spacing grows with y.
                    let w = 1.0 - tilt * y / 20.0;
                    Vec3::new(x / w, tilt * y / w, y / w)
                })
                .collect();
            let name = format!("tilt {tilt}, turn {turn:?}");
            let (mut reach, mut probes) = (Vec::new(), Vec::new());
            spread_probes(64, |j| points[j], 16, &mut reach, &mut probes);
            assert_eq!(probes.len(), 16);
            for corner in [0, 7, 56, 63] {
                assert!(
                    probes.contains(&corner),
                    "{name}: corner {corner} not a probe"
                );
            }
            let mut distinct = probes.clone();
            distinct.sort_unstable();
            distinct.dedup();
            assert_eq!(distinct.len(), 16, "{name}: a probe picked twice");
            let scan: Vec<u32> = (0..16).map(|r| r * 4).collect();
            let mut scan_missed = 0;
            for _ in 0..2000 {
                let angle = rng.f32() * std::f32::consts::TAU;
                let a = (angle.cos(), angle.sin());
                let p = points[(rng.f32() * 64.0) as usize % 64];
                let c = a.0 * p.x + a.1 * p.z + (rng.f32() - 0.5);
                assert!(
                    !split_unseen(&points, &probes, a, c),
                    "{name}: a line splits the samples but not the probes"
                );
                scan_missed += usize::from(split_unseen(&points, &scan, a, c));
            }
            assert!(
                scan_missed > 0,
                "{name}: the test cannot tell the probes apart"
            );
        }
        // Coincident samples: only distinct positions are picked.
        let points = [Vec3::ZERO, Vec3::ZERO, Vec3::X, Vec3::X];
        let (mut reach, mut probes) = (Vec::new(), Vec::new());
        spread_probes(4, |j| points[j], 16, &mut reach, &mut probes);
        assert_eq!(probes, vec![0, 2]);
    }

    /// The traced values `plan_rays` selects in chunks are exactly those of sorting all of them
    /// (the same nodes in the same order), and the untraced rest is their sum up to f32
    /// rounding in another order: at most 1e-5 of the total (1000 values of ~1e-7 relative
    /// rounding each, summed).
    #[test]
    fn planned_rays_are_those_of_the_full_sort() {
        let mut rng = Rng::keyed(26, 0, 0);
        let (mut order, mut plan) = (Vec::new(), Vec::new());
        for case in 0..200 {
            let len = [0, 1, 5, 31, 32, 33, 100, 1000][case % 8];
            // Heavy-tailed values, some zero, some tied.
            let values: Vec<Vec3> = (0..len)
                .map(|i| {
                    let u = rng.f32();
                    let l = if u < 0.1 {
                        0.0
                    } else if u < 0.2 {
                        0.5
                    } else {
                        (u * 12.0).exp()
                    };
                    Vec3::new(l, l * (i % 3) as f32, 0.3 * l)
                })
                .collect();
            plan.clear();
            let rest = plan_rays(|i| values[i], len, &mut order, &mut plan);
            // The reference: sort everything, walk it.
            let mut all: Vec<(f32, u32)> = (0..len)
                .map(|i| (luminance(values[i]).max(0.0), i as u32))
                .filter(|e| e.0 > 0.0)
                .collect();
            let total: f32 = all.iter().map(|e| e.0).sum();
            all.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            let (mut traced, mut want, mut want_rest) = (0.0f32, Vec::new(), Vec3::ZERO);
            for &(l, i) in &all {
                if total - traced <= RAY_TAIL * total {
                    want_rest += values[i as usize];
                } else {
                    traced += l;
                    want.push((i, l));
                }
            }
            assert_eq!(plan, want, "case {case}: {len} values");
            let scale = values
                .iter()
                .map(|v| v.max_element())
                .sum::<f32>()
                .max(1e-30);
            assert!(
                (rest - want_rest).abs().max_element() <= 1e-5 * scale,
                "case {case}: rest {rest} against {want_rest}"
            );
        }
    }
}
