//! The GPU data layouts: `#[repr(C)]` structs that are the single source of truth for the WGSL
//! structs of the same names in `shaders/shared/layout.wgsl`. WGSL aligns a `vec3<f32>` to 16
//! bytes; the Rust structs spell that padding out, and [`layouts`] lists every struct's size and
//! member offsets for the test that compares them with naga's layout of the shaders.

use bytemuck::{Pod, Zeroable};
use std::mem::{offset_of, size_of};

/// A spherical Gaussian μ exp(λ (ω·p − 1)) (`math::sg::Sg`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSg {
    pub axis: [f32; 3],
    pub sharpness: f32,
    pub amplitude: [f32; 3],
    pub _pad: f32,
}

impl From<crate::math::sg::Sg> for GpuSg {
    fn from(s: crate::math::sg::Sg) -> Self {
        GpuSg {
            axis: s.axis.to_array(),
            sharpness: s.sharpness,
            amplitude: s.amplitude.to_array(),
            _pad: 0.0,
        }
    }
}

/// One row of a math-twin table (`super::twins`): a function's inputs in four vec4s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TwinQuery {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
    pub d: [f32; 4],
}

/// The math-twin pass's uniform: which function, over how many rows.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TwinParams {
    pub function: u32,
    pub count: u32,
    pub _pad0: u32,
    pub _pad1: u32,
}

/// A struct's name, size and (member, offset) list, for comparison with the shaders.
#[derive(Clone, Debug, PartialEq)]
pub struct StructLayout {
    pub name: &'static str,
    pub size: usize,
    pub members: Vec<(&'static str, usize)>,
}

macro_rules! layout {
    ($t:ident { $($m:ident),* $(,)? }) => {
        StructLayout {
            name: stringify!($t),
            size: size_of::<$t>(),
            members: vec![$((stringify!($m), offset_of!($t, $m))),*],
        }
    };
}

/// Every shared struct's Rust layout.
pub fn layouts() -> Vec<StructLayout> {
    vec![
        layout!(GpuSg {
            axis,
            sharpness,
            amplitude,
            _pad
        }),
        layout!(TwinQuery { a, b, c, d }),
        layout!(TwinParams {
            function,
            count,
            _pad0,
            _pad1
        }),
    ]
}
