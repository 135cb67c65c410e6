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
    scale: f32,
    light: vec3<f32>,
    orthographic: u32,
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

// The SG shading passes' uniform (`render::gpu::sg_shade`): the light the lobes were aimed
// from, this dispatch's (point, cut node) pairs (`count` from `first`) and points (`point_first`
// to `point_end`), and the node maps' resolution and depth bias.
struct GpuShadeParams {
    light_pos: vec3<f32>,
    count: u32,
    first: u32,
    point_first: u32,
    point_end: u32,
    map_res: u32,
    map_bias: f32,
    leaf_first: u32,
    cluster_count: u32,
    cluster_first: u32,
}

// One pixel sample on a receiver: its point x, the point offset along the geometric normal that
// visibility is looked up from, its cut (`cut_count` entries of `cut_nodes` from `cut_start`),
// the index of its first (point, node) pair, the direction across its plane of incidence and
// its BRDF lobes.
struct GpuShadePoint {
    x: vec3<f32>,
    cut_start: u32,
    xo: vec3<f32>,
    cut_count: u32,
    across: vec3<f32>,
    pair_start: u32,
    receiver: GpuReceiver,
    leaf_count: u32,
    leaf_pair_start: u32,
    _pad0: u32,
    _pad1: u32,
}

// Per-slot sums of the lobes under a node (`cut::NodeLobe`).
struct GpuNodeLobe {
    energy: vec3<f32>,
    inv_sharpness_sum: f32,
    axis_sum: vec3<f32>,
    _pad: f32,
}

// A tree node lit by one light (`cut::LitNode` with its bound's inputs): `leaf` indexes the
// leaves for a leaf node (0xffffffff otherwise), `map` the node maps (0xffffffff: none).
struct GpuLitNode {
    bound: GpuNodeBound,
    centroid: vec3<f32>,
    weight: f32,
    normal_sum: vec3<f32>,
    area: f32,
    diffuse: vec3<f32>,
    leaf: u32,
    lobes: array<GpuNodeLobe, 4>,
    half_vector: u32,
    map: u32,
    _pad0: u32,
    _pad1: u32,
}

// A lit reflector triangle (`cut::LitTriangle` and its `transport::reflector::ReflectedSg`).
struct GpuLeaf {
    v0: vec3<f32>,
    has_sg: u32,
    v1: vec3<f32>,
    lobe_count: u32,
    v2: vec3<f32>,
    half_vector: u32,
    diffuse: vec3<f32>,
    stretch: f32,
    normal: vec3<f32>,
    _pad0: f32,
    geometric_normal: vec3<f32>,
    _pad1: f32,
    origin: vec3<f32>,
    _pad2: f32,
    light: vec3<f32>,
    _pad3: f32,
    lobes: array<GpuSg, 4>,
}

// The origin of a visibility map at a tree node (`visibility::node_maps`): its position, the
// frame (t, b, n) of its paraboloid and the map's variance floor.
struct GpuMapOrigin {
    position: vec3<f32>,
    min_variance: f32,
    t: vec3<f32>,
    _pad0: f32,
    b: vec3<f32>,
    _pad1: f32,
    n: vec3<f32>,
    _pad2: f32,
}

// A material (`brdf::Brdf`; the encoding is in shared/brdf.wgsl).
struct GpuBrdf {
    diffuse: vec3<f32>,
    model: u32,
    specular: vec3<f32>,
    param: f32,
    distribution: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// The VPL pass's uniform (`render::gpu::vpl`).
struct GpuVplParams {
    count: u32,
    vpl_count: u32,
    accumulate: u32,
    clamp2: f32,
    map_res: u32,
    map_bias: f32,
    _pad0: u32,
    _pad1: u32,
}

// A pixel sample on a receiver for the VPL pass: point, normals, frame, eye direction.
struct GpuSurfacePoint {
    p: vec3<f32>,
    material: u32,
    ng: vec3<f32>,
    _pad0: f32,
    t: vec3<f32>,
    _pad1: f32,
    b: vec3<f32>,
    _pad2: f32,
    n: vec3<f32>,
    _pad3: f32,
    wo: vec3<f32>,
    _pad4: f32,
}

// A VPL with its shading frame, light direction (local), material and imperfect shadow map.
struct GpuVpl {
    position: vec3<f32>,
    material: u32,
    normal: vec3<f32>,
    map: u32,
    t: vec3<f32>,
    _pad0: f32,
    b: vec3<f32>,
    _pad1: f32,
    n: vec3<f32>,
    _pad2: f32,
    wi: vec3<f32>,
    _pad3: f32,
    power: vec3<f32>,
    _pad4: f32,
    origin: GpuMapOrigin,
}

// The VPL pass's per-point sums: radiance and the pair counts.
struct GpuVplSum {
    radiance: vec3<f32>,
    pairs: u32,
    clamped: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// A light (`scene::Light`): kind 0 point, 1 spot, 2 directional (intensity = its irradiance).
struct GpuLight {
    position: vec3<f32>,
    kind: u32,
    direction: vec3<f32>,
    cos_cone: f32,
    intensity: vec3<f32>,
    cos_falloff: f32,
    map: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// A variance shadow map: projection 0 cube, 1 perspective, 2 orthographic; its faces' frames.
struct GpuShadowMap {
    origin: vec3<f32>,
    projection: u32,
    res: u32,
    first_texel: u32,
    margin: f32,
    min_variance: f32,
    bleeding: f32,
    scale: f32,
    _pad0: u32,
    _pad1: u32,
    forward: array<vec4<f32>, 6>,
    right: array<vec4<f32>, 6>,
    up: array<vec4<f32>, 6>,
}

// A reflector triangle VPLs can sit on (`render::gpu::vpl_gen`).
struct GpuVplSource {
    v0: vec3<f32>,
    _pad0: u32,
    v1: vec3<f32>,
    _pad1: u32,
    v2: vec3<f32>,
    _pad2: u32,
    albedo: vec3<f32>,
    _pad3: u32,
}

// The imperfect-shadow-map pass's uniform (`render::gpu::ism`).
struct GpuIsmParams {
    res: u32,
    points_per_map: u32,
    maps: u32,
    pyramid_len: u32,
    blur: u32,
    front_layer: f32,
    level_n: u32,
    level_offset: u32,
    other_n: u32,
    other_offset: u32,
    has_other: u32,
    _pad0: u32,
}

// The VPL-weight pass's uniform (`render::gpu::vpl_gen`).
struct GpuVplGenParams {
    count: u32,
    eps: f32,
    _pad0: u32,
    _pad1: u32,
}

// The direct-light pass's uniform (`render::gpu::direct`).
struct GpuDirectParams {
    count: u32,
    light_count: u32,
    eps: f32,
    _pad0: u32,
}
