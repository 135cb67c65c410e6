// GPU data layouts shared by the passes. Rust is the source of truth: every struct here mirrors
// a `#[repr(C)]` struct of `render::gpu::layout` with the same name, and the test
// `shaders_validate_and_layouts_match` compares each member's offset and the struct's size
// with Rust's (vec3<f32> is 16-byte aligned in WGSL: Rust spells the padding out).

// A spherical Gaussian μ exp(λ (ω·p − 1)) (`math::sg::Sg`).
struct GpuSg {
    axis: vec3<f32>,
    sharpness: f32,
    amplitude: vec3<f32>,
    _pad: f32,
}

// One row of a math-twin table: the inputs of a function, packed in four vec4s, and the
// function to call (`render::gpu::twins`).
struct TwinQuery {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
    d: vec4<f32>,
}

struct TwinParams {
    function: u32,
    count: u32,
    _pad0: u32,
    _pad1: u32,
}
