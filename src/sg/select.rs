//! Cut selection (Xu et al. 2014, §6): from the root, repeatedly replace the node with the
//! largest bound by its two children until every bound is below a fraction of the estimate or
//! the cut reaches its size cap.

use super::lighting::LitScene;
use super::transport::receiver::ReceiverLobes;
use crate::math::luminance;
use crate::settings::CutOptions;
use glam::Vec3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// A cut entry: a node and its contribution at the point the cut was chosen for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutEntry {
    pub node: u32,
    /// Approximate contribution (no visibility), clamped to the bound.
    pub value: Vec3,
    pub bound: Vec3,
}

/// Counters of one cut selection.
#[derive(Clone, Copy, Debug, Default)]
pub struct CutCounters {
    /// Nodes whose bound and approximation were evaluated.
    pub evaluated: u64,
    /// Of those, leaves (exact triangle integrations).
    pub leaves: u64,
}

/// A node waiting in a selection's heap with its bound's luminance `key` and what the selection
/// keeps of it (`item`).
pub(super) struct Pending<T> {
    pub(super) key: f32,
    pub(super) node: u32,
    pub(super) item: T,
}

impl<T> PartialEq for Pending<T> {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl<T> Eq for Pending<T> {}
impl<T> PartialOrd for Pending<T> {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl<T> Ord for Pending<T> {
    fn cmp(&self, o: &Self) -> Ordering {
        // Larger bound first; ties by node index, so selection is deterministic.
        self.key
            .total_cmp(&o.key)
            .then_with(|| o.node.cmp(&self.node))
    }
}

impl LitScene<'_> {
    fn entry(&self, node: u32, x: Vec3, rx: &ReceiverLobes, c: &mut CutCounters) -> CutEntry {
        c.evaluated += 1;
        if self.tree.nodes[node as usize].is_leaf() {
            c.leaves += 1;
        }
        let bound = self.bound(node, x, rx);
        let value = self.approx(node, x, rx, bound);
        CutEntry { node, value, bound }
    }

    /// Selects the cut at receiver point `x` (METHOD §6): start from the root, repeatedly
    /// replace the node with the largest bound (luminance) by its two children, until that bound
    /// is at most `threshold` × the estimate's luminance or the cut holds `max_cut` nodes.
    /// Appends the cut to `out` (cleared first) and returns the estimate (no visibility).
    pub fn select(
        &self,
        x: Vec3,
        rx: &ReceiverLobes,
        opts: &CutOptions,
        out: &mut Vec<CutEntry>,
        c: &mut CutCounters,
    ) -> Vec3 {
        out.clear();
        if self.tree.nodes.is_empty() || rx.is_black() {
            return Vec3::ZERO;
        }
        let cap = if opts.max_cut == 0 {
            usize::MAX
        } else {
            opts.max_cut as usize
        };
        let mut heap = BinaryHeap::new();
        let mut size = 1usize;
        let root = self.entry(0, x, rx, c);
        let mut estimate = root.value;
        let push =
            |e: CutEntry, heap: &mut BinaryHeap<Pending<CutEntry>>, out: &mut Vec<CutEntry>| {
                let key = luminance(e.bound);
                if key > 0.0 || key.is_nan() {
                    heap.push(Pending {
                        key: if key.is_nan() { f32::INFINITY } else { key },
                        node: e.node,
                        item: e,
                    });
                } else {
                    out.push(e);
                }
            };
        push(root, &mut heap, out);
        while let Some(top) = heap.peek() {
            if size >= cap || top.key <= opts.threshold * luminance(estimate).max(0.0) {
                break;
            }
            let top = heap.pop().expect("peeked").item;
            let Some([l, r]) = self.tree.nodes[top.node as usize].children else {
                out.push(top);
                continue;
            };
            estimate -= top.value;
            for child in [l, r] {
                let e = self.entry(child, x, rx, c);
                estimate += e.value;
                push(e, &mut heap, out);
            }
            size += 1;
        }
        out.extend(heap.into_iter().map(|p| p.item));
        // Re-sum in a fixed order (node index) so the result does not depend on the heap's.
        out.sort_unstable_by_key(|e| e.node);
        out.iter().fold(Vec3::ZERO, |a, e| a + e.value)
    }

    /// Evaluates a given cut (e.g. a neighbouring vertex's) at `x`: Σ clamped approximations.
    pub fn evaluate(
        &self,
        nodes: impl Iterator<Item = u32>,
        x: Vec3,
        rx: &ReceiverLobes,
        out: &mut Vec<CutEntry>,
        c: &mut CutCounters,
    ) -> Vec3 {
        out.clear();
        let mut sum = Vec3::ZERO;
        for n in nodes {
            let e = self.entry(n, x, rx, c);
            sum += e.value;
            out.push(e);
        }
        sum
    }

    /// The exact target of the cut: every lit triangle's SG transport summed (no visibility).
    pub fn brute_force(&self, x: Vec3, rx: &ReceiverLobes) -> Vec3 {
        self.tris
            .iter()
            .fold(Vec3::ZERO, |a, t| a + t.shade(x, rx, &self.receiver))
    }
}
