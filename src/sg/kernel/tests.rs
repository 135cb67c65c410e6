//! The kernels' elementary functions against f64, with every instruction set this CPU runs.

use super::simd::{Isa, Kernel, Vf, dispatch};
use super::vmath;

/// Evaluates `f` lane-wise over `xs` (pairs: `ys` too) with `isa`'s lanes.
struct Map<'a> {
    xs: &'a [f32],
    ys: &'a [f32],
    which: u8,
}

impl Kernel for Map<'_> {
    type Output = Vec<f32>;
    #[inline(always)]
    fn run<V: Vf>(self) -> Vec<f32> {
        let n = self.xs.len();
        let pad = |s: &[f32]| {
            let mut v = s.to_vec();
            v.resize(n.div_ceil(V::N) * V::N, 0.5);
            v
        };
        let (xs, ys) = (pad(self.xs), pad(self.ys));
        let mut out = vec![0.0; xs.len()];
        for i in (0..xs.len()).step_by(V::N) {
            let x = V::load(&xs[i..]);
            let y = V::load(&ys[i..]);
            let r = match self.which {
                0 => vmath::exp(x),
                1 => vmath::expm1(x),
                _ => vmath::atan2(y, x),
            };
            r.store(&mut out[i..]);
        }
        out.truncate(n);
        out
    }
}

fn sweep(lo: f32, hi: f32, n: usize) -> Vec<f32> {
    (0..n)
        .map(|i| lo + (hi - lo) * i as f32 / (n - 1) as f32)
        .collect()
}

/// exp within 3e-7 relative over [−87, 88] (Cephes' expf is ≤ 2 ulp, 2.4e-7), 0 below the
/// normal range.
#[test]
fn exp_is_accurate() {
    let xs = sweep(-87.0, 88.0, 20_001);
    for isa in Isa::all_available() {
        let got = dispatch(
            isa,
            Map {
                xs: &xs,
                ys: &xs,
                which: 0,
            },
        );
        for (&x, &g) in xs.iter().zip(&got) {
            let want = f64::from(x).exp();
            let rel = (f64::from(g) - want).abs() / want;
            assert!(
                rel <= 3e-7,
                "{isa:?}: exp({x}) = {g}, want {want} ({rel:.2e})"
            );
        }
        let under = dispatch(
            isa,
            Map {
                xs: &[-100.0, -1e30],
                ys: &[0.0; 2],
                which: 0,
            },
        );
        assert_eq!(under, vec![0.0, 0.0], "{isa:?}");
    }
}

/// expm1 within 4e-7 relative over [−30, 10], including the small arguments where e^x − 1
/// would cancel (down to 1e-8).
#[test]
fn expm1_is_accurate_near_zero() {
    let mut xs = sweep(-30.0, 10.0, 8_001);
    xs.extend((0..40).flat_map(|k| {
        let v = 10f32.powf(-8.0 + 0.2 * k as f32);
        [v, -v]
    }));
    for isa in Isa::all_available() {
        let got = dispatch(
            isa,
            Map {
                xs: &xs,
                ys: &xs,
                which: 1,
            },
        );
        for (&x, &g) in xs.iter().zip(&got) {
            let want = f64::from(x).exp_m1();
            let rel = (f64::from(g) - want).abs() / want.abs().max(1e-300);
            assert!(
                rel <= 4e-7,
                "{isa:?}: expm1({x}) = {g}, want {want} ({rel:.2e})"
            );
        }
    }
}

/// atan2 within 3e-7 rad over every quadrant and both axes (Cephes' atanf reduction: ≤ 2e-7).
#[test]
fn atan2_is_accurate_in_every_quadrant() {
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    for i in 0..721 {
        let a = (i as f32 - 360.0) * std::f32::consts::PI / 360.0;
        for r in [1e-6f32, 1.0, 1e6] {
            xs.push(r * a.cos());
            ys.push(r * a.sin());
        }
    }
    xs.extend([0.0, 0.0, 1.0, -1.0, 0.0]);
    ys.extend([1.0, -1.0, 0.0, 0.0, 0.0]);
    for isa in Isa::all_available() {
        let got = dispatch(
            isa,
            Map {
                xs: &xs,
                ys: &ys,
                which: 2,
            },
        );
        for ((&x, &y), &g) in xs.iter().zip(&ys).zip(&got) {
            let want = f64::from(y).atan2(f64::from(x));
            let mut d = (f64::from(g) - want).abs();
            // ±π are the same angle.
            d = d.min((d - std::f64::consts::TAU).abs());
            assert!(d <= 3e-7, "{isa:?}: atan2({y}, {x}) = {g}, want {want}");
        }
    }
}
