//! The SIMD lanes the kernels are written against: one trait, [`Vf`], for a vector of f32
//! lanes with its comparison mask, and three backends chosen at run time ([`Isa`]):
//!
//! - [`Avx`]: 8 lanes, AVX2 + FMA (`std::arch::x86_64`, `__m256`);
//! - [`Sse`]: 4 lanes, SSE2 (every x86-64 CPU), no FMA;
//! - `f32`: 1 lane, portable (every other architecture, and the reference the tests hold the
//!   vector backends to).
//!
//! The kernels are generic over `V: Vf` and `#[inline(always)]` down to their leaves, and each
//! public entry point is instantiated inside a `#[target_feature(enable = "avx2,fma")]` function
//! for [`Avx`] ([`dispatch`]), so that the whole kernel is compiled with those features while
//! the binary still runs on any x86-64. Why `std::arch` and not a crate: `docs/sg-performance.md`.
//!
//! This is the only module of the crate with `unsafe` code: the intrinsics, and the call into
//! the AVX2 instantiation after `is_x86_feature_detected!` said the CPU has it.
#![allow(unsafe_code)]

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// A vector of f32 lanes.
pub trait Vf:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Send
    + Sync
    + 'static
{
    /// Number of lanes.
    const N: usize;
    /// A lane mask (all bits set or clear per lane).
    type M: Copy + BitAnd<Output = Self::M> + BitOr<Output = Self::M> + Not<Output = Self::M>;
    fn splat(x: f32) -> Self;
    /// The first [`Self::N`] values of `s` (which must hold that many).
    fn load(s: &[f32]) -> Self;
    /// Writes the lanes to the first [`Self::N`] values of `s`.
    fn store(self, s: &mut [f32]);
    /// self · b + c (fused where the backend has FMA).
    fn mul_add(self, b: Self, c: Self) -> Self;
    fn sqrt(self) -> Self;
    /// 1/√self for self > 0, to about 2e-7 relative (the hardware estimate and one Newton
    /// step where the backend has one; exact otherwise).
    fn rsqrt(self) -> Self;
    /// 1/self for self ≠ 0, to about 2e-7 relative (as [`Vf::rsqrt`]).
    fn recip(self) -> Self;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    fn abs(self) -> Self;
    fn lt(self, o: Self) -> Self::M;
    fn le(self, o: Self) -> Self::M;
    fn gt(self, o: Self) -> Self::M;
    fn ge(self, o: Self) -> Self::M;
    /// Lane-wise `if m { a } else { b }`.
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    fn any(m: Self::M) -> bool;
    fn all(m: Self::M) -> bool;
    /// Rounded to the nearest integer, for |self| < 2³¹.
    fn round(self) -> Self;
    /// 2ⁿ for integer-valued n in [−126, 127].
    fn exp2i(self) -> Self;
    /// |self| with the sign of `s`.
    fn copysign(self, s: Self) -> Self;
    /// The lanes as an array of [`Self::N`] values, in `out` (for scalar fallbacks).
    fn to_slice(self, out: &mut [f32]) {
        self.store(out)
    }
}

impl Vf for f32 {
    const N: usize = 1;
    type M = bool;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        s[0]
    }
    #[inline(always)]
    fn store(self, s: &mut [f32]) {
        s[0] = self;
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        self * b + c
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        1.0 / f32::sqrt(self)
    }
    #[inline(always)]
    fn recip(self) -> Self {
        1.0 / self
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self < o { self } else { o }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o { self } else { o }
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
    #[inline(always)]
    fn any(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn all(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn round(self) -> Self {
        f32::round_ties_even(self)
    }
    #[inline(always)]
    fn exp2i(self) -> Self {
        f32::from_bits(((self as i32 + 127) as u32) << 23)
    }
    #[inline(always)]
    fn copysign(self, s: Self) -> Self {
        f32::copysign(self, s)
    }
}

#[cfg(target_arch = "x86_64")]
pub use x86::{Avx, Sse};

#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::Vf;
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

    /// 4 lanes of SSE2.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct Sse(pub __m128);
    /// A mask of [`Sse`] lanes.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct SseM(__m128);
    /// 8 lanes of AVX2 with FMA. Only used inside `#[target_feature(enable = "avx2,fma")]`
    /// functions, after the CPU was checked (`super::dispatch`).
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct Avx(pub __m256);
    /// A mask of [`Avx`] lanes.
    #[derive(Clone, Copy, Debug)]
    #[repr(transparent)]
    pub struct AvxM(__m256);

    // SAFETY (every `unsafe` block of this module): the SSE2 intrinsics are part of the x86-64
    // baseline; the AVX/AVX2/FMA intrinsics are reached only from code instantiated inside
    // `#[target_feature(enable = "avx2,fma")]` functions, which `dispatch` calls only after
    // `is_x86_feature_detected!` confirmed both features. Loads and stores are unaligned
    // and bounds-checked by the slice assertions before them.
    macro_rules! binop {
        ($t:ident, $tr:ident, $f:ident, $intr:ident) => {
            impl $tr for $t {
                type Output = $t;
                #[inline(always)]
                fn $f(self, o: $t) -> $t {
                    unsafe { $t($intr(self.0, o.0)) }
                }
            }
        };
    }
    binop!(Sse, Add, add, _mm_add_ps);
    binop!(Sse, Sub, sub, _mm_sub_ps);
    binop!(Sse, Mul, mul, _mm_mul_ps);
    binop!(Sse, Div, div, _mm_div_ps);
    binop!(Avx, Add, add, _mm256_add_ps);
    binop!(Avx, Sub, sub, _mm256_sub_ps);
    binop!(Avx, Mul, mul, _mm256_mul_ps);
    binop!(Avx, Div, div, _mm256_div_ps);
    binop!(SseM, BitAnd, bitand, _mm_and_ps);
    binop!(SseM, BitOr, bitor, _mm_or_ps);
    binop!(AvxM, BitAnd, bitand, _mm256_and_ps);
    binop!(AvxM, BitOr, bitor, _mm256_or_ps);

    impl Neg for Sse {
        type Output = Sse;
        #[inline(always)]
        fn neg(self) -> Sse {
            unsafe { Sse(_mm_xor_ps(self.0, _mm_set1_ps(-0.0))) }
        }
    }
    impl Neg for Avx {
        type Output = Avx;
        #[inline(always)]
        fn neg(self) -> Avx {
            unsafe { Avx(_mm256_xor_ps(self.0, _mm256_set1_ps(-0.0))) }
        }
    }
    impl Not for SseM {
        type Output = SseM;
        #[inline(always)]
        fn not(self) -> SseM {
            unsafe { SseM(_mm_xor_ps(self.0, _mm_castsi128_ps(_mm_set1_epi32(-1)))) }
        }
    }
    impl Not for AvxM {
        type Output = AvxM;
        #[inline(always)]
        fn not(self) -> AvxM {
            unsafe {
                AvxM(_mm256_xor_ps(
                    self.0,
                    _mm256_castsi256_ps(_mm256_set1_epi32(-1)),
                ))
            }
        }
    }

    impl Vf for Sse {
        const N: usize = 4;
        type M = SseM;
        #[inline(always)]
        fn splat(x: f32) -> Self {
            unsafe { Sse(_mm_set1_ps(x)) }
        }
        #[inline(always)]
        fn load(s: &[f32]) -> Self {
            assert!(s.len() >= 4);
            unsafe { Sse(_mm_loadu_ps(s.as_ptr())) }
        }
        #[inline(always)]
        fn store(self, s: &mut [f32]) {
            assert!(s.len() >= 4);
            unsafe { _mm_storeu_ps(s.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            self * b + c
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            unsafe { Sse(_mm_sqrt_ps(self.0)) }
        }
        #[inline(always)]
        fn rsqrt(self) -> Self {
            // y (1.5 − 0.5 x y²): one Newton step on the 12-bit estimate.
            let y = unsafe { Sse(_mm_rsqrt_ps(self.0)) };
            y * (Sse::splat(1.5) - Sse::splat(0.5) * self * y * y)
        }
        #[inline(always)]
        fn recip(self) -> Self {
            let y = unsafe { Sse(_mm_rcp_ps(self.0)) };
            y * (Sse::splat(2.0) - self * y)
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            unsafe { Sse(_mm_min_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            unsafe { Sse(_mm_max_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn abs(self) -> Self {
            unsafe { Sse(_mm_andnot_ps(_mm_set1_ps(-0.0), self.0)) }
        }
        #[inline(always)]
        fn lt(self, o: Self) -> SseM {
            unsafe { SseM(_mm_cmplt_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn le(self, o: Self) -> SseM {
            unsafe { SseM(_mm_cmple_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn gt(self, o: Self) -> SseM {
            unsafe { SseM(_mm_cmpgt_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn ge(self, o: Self) -> SseM {
            unsafe { SseM(_mm_cmpge_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn select(m: SseM, a: Self, b: Self) -> Self {
            unsafe { Sse(_mm_or_ps(_mm_and_ps(m.0, a.0), _mm_andnot_ps(m.0, b.0))) }
        }
        #[inline(always)]
        fn any(m: SseM) -> bool {
            unsafe { _mm_movemask_ps(m.0) != 0 }
        }
        #[inline(always)]
        fn all(m: SseM) -> bool {
            unsafe { _mm_movemask_ps(m.0) == 0xf }
        }
        #[inline(always)]
        fn round(self) -> Self {
            unsafe { Sse(_mm_cvtepi32_ps(_mm_cvtps_epi32(self.0))) }
        }
        #[inline(always)]
        fn exp2i(self) -> Self {
            unsafe {
                let n = _mm_cvtps_epi32(self.0);
                Sse(_mm_castsi128_ps(_mm_slli_epi32::<23>(_mm_add_epi32(
                    n,
                    _mm_set1_epi32(127),
                ))))
            }
        }
        #[inline(always)]
        fn copysign(self, s: Self) -> Self {
            unsafe {
                let sign = _mm_set1_ps(-0.0);
                Sse(_mm_or_ps(
                    _mm_andnot_ps(sign, self.0),
                    _mm_and_ps(sign, s.0),
                ))
            }
        }
    }

    impl Vf for Avx {
        const N: usize = 8;
        type M = AvxM;
        #[inline(always)]
        fn splat(x: f32) -> Self {
            unsafe { Avx(_mm256_set1_ps(x)) }
        }
        #[inline(always)]
        fn load(s: &[f32]) -> Self {
            assert!(s.len() >= 8);
            unsafe { Avx(_mm256_loadu_ps(s.as_ptr())) }
        }
        #[inline(always)]
        fn store(self, s: &mut [f32]) {
            assert!(s.len() >= 8);
            unsafe { _mm256_storeu_ps(s.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        fn mul_add(self, b: Self, c: Self) -> Self {
            unsafe { Avx(_mm256_fmadd_ps(self.0, b.0, c.0)) }
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            unsafe { Avx(_mm256_sqrt_ps(self.0)) }
        }
        #[inline(always)]
        fn rsqrt(self) -> Self {
            let y = unsafe { Avx(_mm256_rsqrt_ps(self.0)) };
            let hx = Avx::splat(0.5) * self;
            y * (hx * y).mul_add(-y, Avx::splat(1.5))
        }
        #[inline(always)]
        fn recip(self) -> Self {
            let y = unsafe { Avx(_mm256_rcp_ps(self.0)) };
            y * self.mul_add(-y, Avx::splat(2.0))
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            unsafe { Avx(_mm256_min_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            unsafe { Avx(_mm256_max_ps(self.0, o.0)) }
        }
        #[inline(always)]
        fn abs(self) -> Self {
            unsafe { Avx(_mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0)) }
        }
        #[inline(always)]
        fn lt(self, o: Self) -> AvxM {
            unsafe { AvxM(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn le(self, o: Self) -> AvxM {
            unsafe { AvxM(_mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn gt(self, o: Self) -> AvxM {
            unsafe { AvxM(_mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn ge(self, o: Self) -> AvxM {
            unsafe { AvxM(_mm256_cmp_ps::<_CMP_GE_OQ>(self.0, o.0)) }
        }
        #[inline(always)]
        fn select(m: AvxM, a: Self, b: Self) -> Self {
            unsafe { Avx(_mm256_blendv_ps(b.0, a.0, m.0)) }
        }
        #[inline(always)]
        fn any(m: AvxM) -> bool {
            unsafe { _mm256_movemask_ps(m.0) != 0 }
        }
        #[inline(always)]
        fn all(m: AvxM) -> bool {
            unsafe { _mm256_movemask_ps(m.0) == 0xff }
        }
        #[inline(always)]
        fn round(self) -> Self {
            unsafe {
                Avx(_mm256_round_ps::<
                    { _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC },
                >(self.0))
            }
        }
        #[inline(always)]
        fn exp2i(self) -> Self {
            unsafe {
                let n = _mm256_cvtps_epi32(self.0);
                Avx(_mm256_castsi256_ps(_mm256_slli_epi32::<23>(
                    _mm256_add_epi32(n, _mm256_set1_epi32(127)),
                )))
            }
        }
        #[inline(always)]
        fn copysign(self, s: Self) -> Self {
            unsafe {
                let sign = _mm256_set1_ps(-0.0);
                Avx(_mm256_or_ps(
                    _mm256_andnot_ps(sign, self.0),
                    _mm256_and_ps(sign, s.0),
                ))
            }
        }
    }
}

/// The instruction sets a kernel can run with, widest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Isa {
    /// 8 lanes: AVX2 and FMA.
    Avx2,
    /// 4 lanes: SSE2 (every x86-64 CPU).
    Sse2,
    /// 1 lane, portable.
    Scalar,
}

impl Isa {
    /// Lanes per vector.
    pub fn lanes(self) -> usize {
        match self {
            Isa::Avx2 => 16,
            Isa::Sse2 => 8,
            Isa::Scalar => 1,
        }
    }

    /// Whether this CPU can run it.
    pub fn available(self) -> bool {
        match self {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(target_arch = "x86_64")]
            Isa::Sse2 => true,
            Isa::Scalar => true,
            #[allow(unreachable_patterns)]
            _ => false,
        }
    }

    /// Every instruction set this CPU can run, widest first.
    pub fn all_available() -> Vec<Isa> {
        [Isa::Avx2, Isa::Sse2, Isa::Scalar]
            .into_iter()
            .filter(|i| i.available())
            .collect()
    }

    /// The widest this CPU runs, or the one `INTERREFLECT_SIMD` (`avx2`, `sse2`, `scalar`)
    /// names when the CPU runs it. Detected once per process.
    pub fn detect() -> Isa {
        static ISA: std::sync::OnceLock<Isa> = std::sync::OnceLock::new();
        *ISA.get_or_init(|| {
            let asked = std::env::var("INTERREFLECT_SIMD").ok();
            let named = match asked.as_deref() {
                Some("avx2") => Some(Isa::Avx2),
                Some("sse2") => Some(Isa::Sse2),
                Some("scalar") => Some(Isa::Scalar),
                _ => None,
            };
            match named {
                Some(i) if i.available() => i,
                _ => Isa::all_available()[0],
            }
        })
    }
}

/// A kernel generic over its lanes: `run::<V>` must be `#[inline(always)]` (and so must
/// everything it calls), so that [`dispatch`] compiles it once per backend with that
/// backend's instruction set.
pub trait Kernel {
    type Output;
    fn run<V: Vf>(self) -> Self::Output;
}

/// Runs `k` with the lanes of `isa` (which must be [`Isa::available`]; otherwise the
/// portable lanes).
#[inline]
pub fn dispatch<K: Kernel>(isa: Isa, k: K) -> K::Output {
    match isa {
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 if Isa::Avx2.available() => {
            // SAFETY: the CPU has AVX2 and FMA (checked just above).
            unsafe { run_avx2(k) }
        }
        #[cfg(target_arch = "x86_64")]
        Isa::Sse2 => k.run::<X2<Sse>>(),
        _ => k.run::<f32>(),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn run_avx2<K: Kernel>(k: K) -> K::Output {
    k.run::<X2<Avx>>()
}

/// Two vectors in lockstep: every operation issues two independent instructions, which
/// doubles the instruction-level parallelism of the kernels' long dependency chains (the
/// exponential, the square roots, the divisions) at the cost of twice the registers.
#[derive(Clone, Copy, Debug)]
pub struct X2<V>(pub V, pub V);
/// A mask of [`X2`] lanes.
#[derive(Clone, Copy, Debug)]
pub struct X2M<M>(pub M, pub M);

macro_rules! x2op {
    ($tr:ident, $f:ident) => {
        impl<V: Vf> $tr for X2<V> {
            type Output = X2<V>;
            #[inline(always)]
            fn $f(self, o: X2<V>) -> X2<V> {
                X2(self.0.$f(o.0), self.1.$f(o.1))
            }
        }
    };
}
x2op!(Add, add);
x2op!(Sub, sub);
x2op!(Mul, mul);
x2op!(Div, div);
impl<V: Vf> Neg for X2<V> {
    type Output = X2<V>;
    #[inline(always)]
    fn neg(self) -> X2<V> {
        X2(-self.0, -self.1)
    }
}
impl<M: Copy + BitAnd<Output = M>> BitAnd for X2M<M> {
    type Output = X2M<M>;
    #[inline(always)]
    fn bitand(self, o: Self) -> Self {
        X2M(self.0 & o.0, self.1 & o.1)
    }
}
impl<M: Copy + BitOr<Output = M>> BitOr for X2M<M> {
    type Output = X2M<M>;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        X2M(self.0 | o.0, self.1 | o.1)
    }
}
impl<M: Copy + Not<Output = M>> Not for X2M<M> {
    type Output = X2M<M>;
    #[inline(always)]
    fn not(self) -> Self {
        X2M(!self.0, !self.1)
    }
}

impl<V: Vf> Vf for X2<V> {
    const N: usize = 2 * V::N;
    type M = X2M<V::M>;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        X2(V::splat(x), V::splat(x))
    }
    #[inline(always)]
    fn load(s: &[f32]) -> Self {
        X2(V::load(s), V::load(&s[V::N..]))
    }
    #[inline(always)]
    fn store(self, s: &mut [f32]) {
        self.0.store(s);
        self.1.store(&mut s[V::N..]);
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        X2(self.0.mul_add(b.0, c.0), self.1.mul_add(b.1, c.1))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        X2(self.0.sqrt(), self.1.sqrt())
    }
    #[inline(always)]
    fn rsqrt(self) -> Self {
        X2(self.0.rsqrt(), self.1.rsqrt())
    }
    #[inline(always)]
    fn recip(self) -> Self {
        X2(self.0.recip(), self.1.recip())
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        X2(self.0.min(o.0), self.1.min(o.1))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        X2(self.0.max(o.0), self.1.max(o.1))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        X2(self.0.abs(), self.1.abs())
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self::M {
        X2M(self.0.lt(o.0), self.1.lt(o.1))
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self::M {
        X2M(self.0.le(o.0), self.1.le(o.1))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self::M {
        X2M(self.0.gt(o.0), self.1.gt(o.1))
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self::M {
        X2M(self.0.ge(o.0), self.1.ge(o.1))
    }
    #[inline(always)]
    fn select(m: Self::M, a: Self, b: Self) -> Self {
        X2(V::select(m.0, a.0, b.0), V::select(m.1, a.1, b.1))
    }
    #[inline(always)]
    fn any(m: Self::M) -> bool {
        V::any(m.0) || V::any(m.1)
    }
    #[inline(always)]
    fn all(m: Self::M) -> bool {
        V::all(m.0) && V::all(m.1)
    }
    #[inline(always)]
    fn round(self) -> Self {
        X2(self.0.round(), self.1.round())
    }
    #[inline(always)]
    fn exp2i(self) -> Self {
        X2(self.0.exp2i(), self.1.exp2i())
    }
    #[inline(always)]
    fn copysign(self, s: Self) -> Self {
        X2(self.0.copysign(s.0), self.1.copysign(s.1))
    }
}
