//! Elementary functions on SIMD lanes, generic over [`Vf`]: exp, expm1 and atan2 in f32, each
//! with its accuracy tested against f64 (`kernel::tests`).

use super::simd::Vf;

/// e^x: Cody–Waite reduction x = n ln 2 + r, |r| ≤ ln 2 / 2, and the degree-6 polynomial of
/// Cephes' `expf` (Moshier), ≤ 2 ulp on the reduced range; 0 below −87.3 (where f32 leaves its
/// normal range), saturated at 88.7.
#[inline(always)]
pub fn exp<V: Vf>(x: V) -> V {
    let lo = V::splat(-87.336_54);
    let xc = x.min(V::splat(88.376_26)).max(lo);
    let n = (xc * V::splat(std::f32::consts::LOG2_E)).round();
    let r = n.mul_add(V::splat(-0.693_359_4), xc);
    let r = n.mul_add(V::splat(2.121_944_4e-4), r);
    let mut p = V::splat(1.987_569_1e-4);
    p = p.mul_add(r, V::splat(1.398_199_9e-3));
    p = p.mul_add(r, V::splat(8.333_452e-3));
    p = p.mul_add(r, V::splat(4.166_579_6e-2));
    p = p.mul_add(r, V::splat(0.166_666_65));
    p = p.mul_add(r, V::splat(0.5));
    let y = p.mul_add(r * r, r) + V::splat(1.0);
    V::select(x.lt(lo), V::splat(0.0), y * n.exp2i())
}

/// e^x − 1 without cancellation, by the reduction of [`exp`]: with x = n ln 2 + r,
/// e^x − 1 = 2ⁿ (e^r − 1) + (2ⁿ − 1), where e^r − 1 is the same polynomial without its 1
/// (relative error ≤ 3e-7 for |x| ≥ 1e-8); −1 below −87.3.
#[inline(always)]
pub fn expm1<V: Vf>(x: V) -> V {
    let lo = V::splat(-87.336_54);
    let xc = x.min(V::splat(88.376_26)).max(lo);
    let n = (xc * V::splat(std::f32::consts::LOG2_E)).round();
    let r = n.mul_add(V::splat(-0.693_359_4), xc);
    let r = n.mul_add(V::splat(2.121_944_4e-4), r);
    let mut p = V::splat(1.987_569_1e-4);
    p = p.mul_add(r, V::splat(1.398_199_9e-3));
    p = p.mul_add(r, V::splat(8.333_452e-3));
    p = p.mul_add(r, V::splat(4.166_579_6e-2));
    p = p.mul_add(r, V::splat(0.166_666_65));
    p = p.mul_add(r, V::splat(0.5));
    let em1 = p.mul_add(r * r, r);
    let two_n = n.exp2i();
    let y = em1.mul_add(two_n, two_n - V::splat(1.0));
    V::select(x.lt(lo), V::splat(-1.0), y)
}

/// atan2(y, x) in (−π, π]: the reduction of Cephes' `atanf` (|a| ≤ tan(π/8) after subtracting
/// π/4 or π/2) and its degree-9 odd polynomial, ≤ 2e-7 rad; atan2(0, 0) = 0.
#[inline(always)]
pub fn atan2<V: Vf>(y: V, x: V) -> V {
    let (ax, ay) = (x.abs(), y.abs());
    let num = ax.min(ay);
    let den = ax.max(ay);
    let zero = V::splat(0.0);
    // a = min/max ∈ [0, 1]; reduce above tan(π/8) with atan(a) = π/4 + atan((a − 1)/(a + 1)).
    let a = V::select(den.gt(zero), num * den.recip(), zero);
    let big = a.gt(V::splat(0.414_213_57));
    let a2 = V::select(big, (a - V::splat(1.0)) * (a + V::splat(1.0)).recip(), a);
    let z = a2 * a2;
    let mut p = V::splat(8.053_744_5e-2);
    p = p.mul_add(z, V::splat(-1.387_768_6e-1));
    p = p.mul_add(z, V::splat(1.997_771_1e-1));
    p = p.mul_add(z, V::splat(-3.333_295e-1));
    let r = (p * z).mul_add(a2, a2);
    let r = V::select(big, r + V::splat(std::f32::consts::FRAC_PI_4), r);
    // Undo the min/max swap and the quadrant.
    let r = V::select(ay.gt(ax), V::splat(std::f32::consts::FRAC_PI_2) - r, r);
    let r = V::select(x.lt(zero), V::splat(std::f32::consts::PI) - r, r);
    r.copysign(y)
}
