//! Receiver points in structure-of-arrays form, the lanes of the shading kernels: position,
//! shading normal and the BRDF's SG lobes (`sg::transport::receiver::ReceiverLobes`) of every
//! point of a group. All points of a group share their material, hence their lobe count.

use super::lobes::{AnisoV, SgV};
use super::simd::Vf;
use super::v3::V3;
use crate::brdf::sg_fit::MAX_LOBES;
use crate::sg::transport::receiver::ReceiverLobes;
use glam::Vec3;

/// Three coordinate columns.
pub type Cols3 = [Vec<f32>; 3];

/// The receivers of one group, padded to a multiple of the widest lanes by repeating the last.
#[derive(Clone, Debug, Default)]
pub struct Receivers {
    pub len: usize,
    pub x: Cols3,
    pub n: Cols3,
    pub diffuse: Cols3,
    pub lobe_axis: [Cols3; MAX_LOBES],
    pub lobe_sharp: [Vec<f32>; MAX_LOBES],
    pub lobe_amp: [Cols3; MAX_LOBES],
    pub across: Cols3,
    pub stretch: Vec<f32>,
    /// Lobes per receiver (the group's material's).
    pub n_lobes: usize,
}

fn push3(c: &mut Cols3, v: Vec3) {
    c[0].push(v.x);
    c[1].push(v.y);
    c[2].push(v.z);
}

/// Padding unit: every backend's lane count divides it.
pub const PAD: usize = 16;

impl Receivers {
    /// Clears for reuse (keeps the allocations).
    pub fn clear(&mut self) {
        self.len = 0;
        for c in [
            &mut self.x,
            &mut self.n,
            &mut self.diffuse,
            &mut self.across,
        ] {
            c.iter_mut().for_each(Vec::clear);
        }
        for k in 0..MAX_LOBES {
            self.lobe_axis[k].iter_mut().for_each(Vec::clear);
            self.lobe_amp[k].iter_mut().for_each(Vec::clear);
            self.lobe_sharp[k].clear();
        }
        self.stretch.clear();
        self.n_lobes = 0;
    }

    /// Appends a receiver at `x` with lobes `rx` (whose normal is the shading normal).
    /// `anisotropic`: the receiver lobes keep their stretch (`ReceiverOptions::anisotropic`).
    pub fn push(&mut self, x: Vec3, rx: &ReceiverLobes, anisotropic: bool) {
        if self.len == 0 {
            self.n_lobes = rx.lobes().len();
        }
        debug_assert_eq!(self.n_lobes, rx.lobes().len(), "one material per group");
        self.len += 1;
        push3(&mut self.x, x);
        push3(&mut self.n, rx.normal);
        push3(&mut self.diffuse, rx.diffuse);
        for k in 0..MAX_LOBES {
            let l = rx.lobes().get(k).copied();
            push3(&mut self.lobe_axis[k], l.map_or(Vec3::Z, |l| l.axis));
            self.lobe_sharp[k].push(l.map_or(0.0, |l| l.sharpness));
            push3(&mut self.lobe_amp[k], l.map_or(Vec3::ZERO, |l| l.amplitude));
        }
        push3(&mut self.across, rx.across());
        self.stretch
            .push(if anisotropic { rx.stretch() } else { 1.0 });
    }

    /// Pads every column to a multiple of [`PAD`] by repeating the last receiver.
    pub fn pad(&mut self) {
        let target = self.len.div_ceil(PAD) * PAD;
        let fill = |v: &mut Vec<f32>| {
            let last = v.last().copied().unwrap_or(0.0);
            v.resize(target, last);
        };
        for c in [
            &mut self.x,
            &mut self.n,
            &mut self.diffuse,
            &mut self.across,
        ] {
            c.iter_mut().for_each(fill);
        }
        for k in 0..MAX_LOBES {
            self.lobe_axis[k].iter_mut().for_each(fill);
            self.lobe_amp[k].iter_mut().for_each(fill);
            fill(&mut self.lobe_sharp[k]);
        }
        fill(&mut self.stretch);
    }

    /// Padded length.
    pub fn padded(&self) -> usize {
        self.stretch.len()
    }
}

/// One vector of receivers, the lobes already as anisotropic lobes.
#[derive(Clone, Copy, Debug)]
pub struct ReceiversV<V: Vf> {
    pub x: V3<V>,
    pub n: V3<V>,
    pub diffuse: V3<V>,
    pub lobes: [AnisoV<V>; MAX_LOBES],
    pub n_lobes: usize,
}

#[inline(always)]
fn load3<V: Vf>(c: &Cols3, i: usize) -> V3<V> {
    V3::load(&c[0][i..], &c[1][i..], &c[2][i..])
}

impl<V: Vf> ReceiversV<V> {
    /// Receivers `[i, i + V::N)` of `r` (padded).
    #[inline(always)]
    pub fn load(r: &Receivers, i: usize) -> Self {
        let across = load3::<V>(&r.across, i);
        let stretch = V::load(&r.stretch[i..]);
        let zero = V3::new(V::splat(0.0), V::splat(0.0), V::splat(0.0));
        let mut lobes = [AnisoV {
            sg: SgV {
                axis: zero,
                sharp: V::splat(0.0),
                amp: zero,
            },
            t: zero,
            k: V::splat(1.0),
        }; MAX_LOBES];
        for (k, lobe) in lobes.iter_mut().enumerate().take(r.n_lobes) {
            let sg = SgV {
                axis: load3(&r.lobe_axis[k], i),
                sharp: V::load(&r.lobe_sharp[k][i..]),
                amp: load3(&r.lobe_amp[k], i),
            };
            *lobe = AnisoV::new(sg, across, stretch);
        }
        ReceiversV {
            x: load3(&r.x, i),
            n: load3(&r.n, i),
            diffuse: load3(&r.diffuse, i),
            lobes,
            n_lobes: r.n_lobes,
        }
    }
}
