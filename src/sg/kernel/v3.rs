//! Three-vectors of SIMD lanes (structure of arrays): lane i of `x`, `y`, `z` is one vector.

use super::simd::Vf;
use glam::Vec3;
use std::ops::{Add, Neg, Sub};

#[derive(Clone, Copy, Debug)]
pub struct V3<V> {
    pub x: V,
    pub y: V,
    pub z: V,
}

impl<V: Vf> V3<V> {
    #[inline(always)]
    pub fn new(x: V, y: V, z: V) -> Self {
        V3 { x, y, z }
    }
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        V3::new(V::splat(v.x), V::splat(v.y), V::splat(v.z))
    }
    /// Lanes `[i, i + N)` of three coordinate slices.
    #[inline(always)]
    pub fn load(x: &[f32], y: &[f32], z: &[f32]) -> Self {
        V3::new(V::load(x), V::load(y), V::load(z))
    }
    #[inline(always)]
    pub fn dot(self, o: Self) -> V {
        self.z.mul_add(o.z, self.y.mul_add(o.y, self.x * o.x))
    }
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    #[inline(always)]
    pub fn scale(self, s: V) -> Self {
        V3::new(self.x * s, self.y * s, self.z * s)
    }
    /// self · s + o.
    #[inline(always)]
    pub fn mul_add(self, s: V, o: Self) -> Self {
        V3::new(
            self.x.mul_add(s, o.x),
            self.y.mul_add(s, o.y),
            self.z.mul_add(s, o.z),
        )
    }
    #[inline(always)]
    pub fn length_squared(self) -> V {
        self.dot(self)
    }
    #[inline(always)]
    pub fn length(self) -> V {
        self.dot(self).sqrt()
    }
    /// self / |self|; zero vectors stay zero.
    #[inline(always)]
    pub fn normalize_or_zero(self) -> Self {
        let l2 = self.length_squared();
        let inv = V::select(l2.gt(V::splat(0.0)), l2.rsqrt(), V::splat(0.0));
        self.scale(inv)
    }
    #[inline(always)]
    pub fn select(m: V::M, a: Self, b: Self) -> Self {
        V3::new(
            V::select(m, a.x, b.x),
            V::select(m, a.y, b.y),
            V::select(m, a.z, b.z),
        )
    }
}

impl<V: Vf> Add for V3<V> {
    type Output = V3<V>;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<V: Vf> Sub for V3<V> {
    type Output = V3<V>;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl<V: Vf> Neg for V3<V> {
    type Output = V3<V>;
    #[inline(always)]
    fn neg(self) -> Self {
        V3::new(-self.x, -self.y, -self.z)
    }
}
