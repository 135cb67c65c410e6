//! Diffuse receivers shaded on a sparse lattice (`docs/sg-performance.md`, "Tried, kept as a
//! knob: diffuse receivers interpolated"): with tile cuts, a diffuse-only receiver sample (no glossy lobe, so its
//! indirect light does not depend on the view) at a pixel off the even lattice (x and y both
//! even) takes the mean of its lattice neighbours' values of the same sample number, when every
//! neighbour is a diffuse-only sample of the same material on the same plane (normals within
//! [`NORMAL_COS`], off the sample's plane by at most [`PLANE_SLOPE`] of their distance) and their
//! luminances agree within [`AGREE`]. Every other sample is shaded with its own cut, as without
//! this pass. Off by default: a measurement knob ([`sparse_agree`]) until it pays on every
//! scene (it does not yet on the bunny under approximate visibility).

use super::sg::{Ctx, Tally};
use super::sg_tiles::tile_side;
use crate::accel::Hit;
use crate::math::luminance;
use crate::render::cpu::Progress;
use glam::Vec3;
use rayon::prelude::*;

/// Smallest cosine between the normals of a sample and a neighbour it takes its value from.
pub const NORMAL_COS: f32 = 0.95;

/// Largest distance of a neighbour from the sample's tangent plane, as a fraction of their
/// distance (about 3°).
pub const PLANE_SLOPE: f32 = 0.05;

/// Largest spread of the neighbours' luminances, relative to the smallest: `max ≤ (1 + AGREE)
/// · min`. Where they disagree more (a caustic's or a shadow's edge), the sample is shaded.
pub const AGREE: f32 = 0.1;

/// The sparse pass's tolerance on the neighbours' agreement, when the environment variable
/// `INTERREFLECT_SPARSE` asks for the pass (a measurement knob, off by default: measured in
/// `docs/sg-performance.md`). `on` is [`AGREE`], a number is the tolerance; a negative value
/// or none turns the pass off.
pub fn sparse_agree() -> Option<f32> {
    let v = std::env::var("INTERREFLECT_SPARSE").ok()?;
    if v == "on" {
        return Some(AGREE);
    }
    v.parse::<f32>().ok().filter(|v| *v >= 0.0)
}

/// What the interpolation needs of one sample: its point, normal and material, when it is a
/// diffuse-only receiver.
#[derive(Clone, Copy, Debug)]
struct Diffuse {
    x: Vec3,
    n: Vec3,
    material: u32,
}

impl Ctx<'_> {
    /// [`Ctx::tile_indirect`] with diffuse receivers off the even lattice interpolated where
    /// their neighbours agree (module docs). `None` when cancelled.
    pub(super) fn sparse_tile_indirect(
        &self,
        hits: &[Option<Hit>],
        tally: &Tally,
        progress: &Progress,
        agree: f32,
    ) -> Option<(Vec<Vec3>, Vec<f32>)> {
        let (w, h) = (self.opts.width as usize, self.opts.height as usize);
        let spp = self.opts.spp.max(1) as usize;
        let diffuse: Vec<Option<Diffuse>> = hits
            .par_iter()
            .enumerate()
            .map(|(i, hit)| {
                let s = self.receiver_sample(hit.as_ref(), i)?;
                (s.material.1 == 0).then_some(Diffuse {
                    x: s.x,
                    n: s.rx.normal,
                    material: s.material.0,
                })
            })
            .collect();
        let on_lattice = |p: usize| (p % w).is_multiple_of(2) && (p / w).is_multiple_of(2);
        let deferred = |i: usize| diffuse[i].is_some() && !on_lattice(i / spp);
        // Pass 1: the glossy samples in the usual tiles, the diffuse samples on the lattice in
        // tiles twice as wide (as many samples a group as the usual tiles hold).
        let side = tile_side(self.opts.spp);
        let glossy: Vec<Option<Hit>> = hits
            .iter()
            .enumerate()
            .map(|(i, hit)| if diffuse[i].is_some() { None } else { *hit })
            .collect();
        let lattice: Vec<Option<Hit>> = hits
            .iter()
            .enumerate()
            .map(|(i, hit)| {
                if diffuse[i].is_some() && !deferred(i) {
                    *hit
                } else {
                    None
                }
            })
            .collect();
        let quiet = Progress {
            done: &crate::progress::no_progress,
            cancel: progress.cancel,
        };
        let sums = self.tile_summaries();
        let (mut values, mut sizes) = self.tile_indirect(&glossy, side, &sums, tally, progress)?;
        let (lv, ls) = self.tile_indirect(&lattice, 2 * side, &sums, tally, &quiet)?;
        for i in 0..hits.len() {
            if lattice[i].is_some() {
                values[i] = lv[i];
                sizes[i] = ls[i];
            }
        }
        // The deferred samples: the neighbours' mean, or shaded in pass 2.
        let neighbours = |i: usize| lattice_neighbours(i, w, h, spp);
        let filled: Vec<(usize, Option<(Vec3, f32)>)> = (0..hits.len())
            .into_par_iter()
            .filter(|&i| deferred(i))
            .map(|i| {
                let me = diffuse[i].expect("deferred samples are diffuse");
                let ns: Vec<(Option<Diffuse>, Vec3, f32)> = neighbours(i)
                    .into_iter()
                    .map(|j| (diffuse[j], values[j], sizes[j]))
                    .collect();
                (i, fill(me, &ns, agree))
            })
            .collect();
        let mut second: Vec<Option<Hit>> = vec![None; hits.len()];
        let mut any = false;
        for &(i, f) in &filled {
            match f {
                Some((v, size)) => {
                    values[i] = v;
                    sizes[i] = size;
                }
                None => {
                    second[i] = hits[i];
                    any = true;
                }
            }
        }
        if any {
            // The samples left are sparse: tiles twice as wide, as in pass 1.
            let (v2, s2) = self.tile_indirect(&second, 2 * side, &sums, tally, &quiet)?;
            for &(i, f) in &filled {
                if f.is_none() {
                    values[i] = v2[i];
                    sizes[i] = s2[i];
                }
            }
        }
        Some((values, sizes))
    }
}

/// The lattice neighbours (sample indices, the same sample number `i % spp`) that the sample
/// `i` of a `w` × `h` image takes its value from: left and right at odd x on an even row, above
/// and below at odd y on an even column, the four diagonals at odd x and y; none where one of
/// them falls outside the image.
fn lattice_neighbours(i: usize, w: usize, h: usize, spp: usize) -> Vec<usize> {
    let (p, s) = (i / spp, i % spp);
    let (x, y) = ((p % w) as isize, (p / w) as isize);
    let (dx, dy): (&[isize], &[isize]) = match (x % 2, y % 2) {
        (1, 0) => (&[-1, 1], &[0]),
        (0, 1) => (&[0], &[-1, 1]),
        (1, 1) => (&[-1, 1], &[-1, 1]),
        _ => return Vec::new(),
    };
    let mut out = Vec::with_capacity(4);
    for &oy in dy {
        for &ox in dx {
            let (nx, ny) = (x + ox, y + oy);
            if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                return Vec::new();
            }
            out.push((ny as usize * w + nx as usize) * spp + s);
        }
    }
    out
}

/// The value and cut size a deferred sample `me` takes from its neighbours (their receiver
/// data, indirect light and cut size): their mean when every one is a diffuse receiver of the
/// same material on the sample's plane and their luminances agree within `agree`; `None`
/// (shade the sample) otherwise.
fn fill(me: Diffuse, ns: &[(Option<Diffuse>, Vec3, f32)], agree: f32) -> Option<(Vec3, f32)> {
    let fits = !ns.is_empty()
        && ns.iter().all(|(d, _, _)| match d {
            Some(d) => {
                let dist = (d.x - me.x).length();
                d.material == me.material
                    && d.n.dot(me.n) >= NORMAL_COS
                    && me.n.dot(d.x - me.x).abs() <= PLANE_SLOPE * dist
            }
            None => false,
        });
    if !fits {
        return None;
    }
    let lum = ns.iter().map(|(_, v, _)| luminance(*v));
    let lo = lum.clone().fold(f32::INFINITY, f32::min);
    let hi = lum.fold(0.0f32, f32::max);
    if !(hi <= (1.0 + agree) * lo) {
        return None;
    }
    let k = ns.len() as f32;
    let v = ns.iter().map(|(_, v, _)| *v).sum::<Vec3>() / k;
    let size = ns.iter().map(|(_, _, s)| *s).sum::<f32>() / k;
    Some((v, size))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Which neighbours each parity takes, at spp 1 and 4, and none at the image's border.
    #[test]
    fn lattice_neighbours_by_parity() {
        let (w, h) = (6, 4);
        assert_eq!(lattice_neighbours(2 * w + 2, w, h, 1), Vec::<usize>::new());
        assert_eq!(lattice_neighbours(3, w, h, 1), vec![2, 4]);
        assert_eq!(lattice_neighbours(w + 2, w, h, 1), vec![2, 2 * w + 2]);
        assert_eq!(
            lattice_neighbours(w + 3, w, h, 1),
            vec![2, 4, 2 * w + 2, 2 * w + 4]
        );
        // The last column is odd: its right neighbour is outside the image.
        assert_eq!(lattice_neighbours(5, w, h, 1), Vec::<usize>::new());
        // The bottom row is odd: its lower neighbours are outside.
        assert_eq!(lattice_neighbours(3 * w + 1, w, h, 1), Vec::<usize>::new());
        // Sample 3 of pixel 3 takes sample 3 of pixels 2 and 4.
        assert_eq!(
            lattice_neighbours(3 * 4 + 3, w, h, 4),
            vec![2 * 4 + 3, 4 * 4 + 3]
        );
    }

    /// The mean where the neighbours fit and agree; a shaded sample where any one of them is
    /// glossy, of another material, turned, off the plane, or where their luminances spread.
    #[test]
    fn fill_takes_the_mean_only_where_the_neighbours_fit() {
        let me = Diffuse {
            x: Vec3::ZERO,
            n: Vec3::Y,
            material: 1,
        };
        let at = |x: f32| Diffuse {
            x: Vec3::new(x, 0.0, 0.0),
            ..me
        };
        let v = Vec3::new(1.0, 0.8, 0.6);
        let good = [
            (Some(at(-0.1)), v, 900.0),
            (Some(at(0.1)), 1.05 * v, 1000.0),
        ];
        let (mean, size) = fill(me, &good, 0.1).expect("fits and agrees");
        assert!((mean - 1.025 * v).abs().max_element() < 1e-6);
        assert_eq!(size, 950.0);
        // All dark: the mean, zero.
        let dark = [
            (Some(at(-0.1)), Vec3::ZERO, 1.0),
            (Some(at(0.1)), Vec3::ZERO, 1.0),
        ];
        assert_eq!(fill(me, &dark, 0.1), Some((Vec3::ZERO, 1.0)));
        let mut cases: Vec<(&str, Option<Diffuse>, Vec3)> = vec![
            ("glossy", None, v),
            (
                "material",
                Some(Diffuse {
                    material: 2,
                    ..at(0.1)
                }),
                v,
            ),
            (
                "turned",
                Some(Diffuse {
                    n: Vec3::new(0.4, 0.9165, 0.0),
                    ..at(0.1)
                }),
                v,
            ),
            (
                "off the plane",
                Some(Diffuse {
                    x: Vec3::new(0.1, 0.01, 0.0),
                    ..me
                }),
                v,
            ),
            ("spread", Some(at(0.1)), 1.2 * v),
        ];
        for (name, d, value) in cases.drain(..) {
            let ns = [(Some(at(-0.1)), v, 1.0), (d, value, 1.0)];
            assert_eq!(fill(me, &ns, 0.1), None, "{name}");
        }
        // No neighbours (the border): shaded.
        assert_eq!(fill(me, &[], 0.1), None);
    }
}
