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

// What the cut's error bound needs of a tree node (`cut::node_bound`).
struct GpuNodeBound {
    bbox_min: vec3<f32>,
    has_cone: f32,
    bbox_max: vec3<f32>,
    cone_half_angle: f32,
    cone_axis: vec3<f32>,
    _pad0: f32,
    image_min: vec3<f32>,
    _pad1: f32,
    image_max: vec3<f32>,
    _pad2: f32,
    diffuse: vec3<f32>,
    _pad3: f32,
    peak_by_sharpness: array<vec4<f32>, 6>,
}

// A receiver point's BRDF lobes (`transport::receiver::ReceiverLobes`).
struct GpuReceiver {
    normal: vec3<f32>,
    stretch: f32,
    diffuse: vec3<f32>,
    lobe_count: u32,
    lobes: array<GpuSg, 4>,
}

// One face of a point light's cube shadow map (`render::gpu::vsm`).
struct GpuVsmFace {
    forward: vec3<f32>,
    margin: f32,
    right: vec3<f32>,
    far: f32,
    up: vec3<f32>,
    _pad0: f32,
    light: vec3<f32>,
    _pad1: f32,
}

// The shadow-map blur's uniform.
struct GpuBlurParams {
    resolution: u32,
    radius: u32,
    vertical: u32,
    _pad: u32,
}

// The tonemap pass's uniform (`render::gpu::tonemap`): 2^exposure, the tone operator (0 clamp,
// 1 Reinhard, 2 ACES), the pixel count and the invocations per dispatch row.
struct GpuTonemapParams {
    scale: f32,
    tone_operator: u32,
    count: u32,
    row_stride: u32,
}

// The camera of the G-buffer pass (`scene::Camera`): its frame, tan(fov_y / 2), the aspect
// ratio and the far distance of the depth range.
struct GpuCamera {
    position: vec3<f32>,
    tan_half: f32,
    forward: vec3<f32>,
    aspect: f32,
    right: vec3<f32>,
    far: f32,
    up: vec3<f32>,
    _pad: f32,
}
