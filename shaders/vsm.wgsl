// Variance shadow map of a light, one face per render pass: the scene's triangles are
// rasterised (no rays) into an Rg32Float target holding the moments (z, z²) of the depth z,
// nearest surface first (depth test); texels that see nothing keep (far, far²). A perspective
// face (a point light's cube face, a spot's one face) measures z as the distance to the light;
// an orthographic face (a directional light's box) as the distance along `forward` from the
// plane through `light`. Rust twin: `visibility::vsm::VarianceShadowMap::build`, which casts
// one ray per texel centre; the blur is `shaders/vsm_blur.wgsl`. Prepended with
// shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> face: GpuVsmFace;

struct VsmVertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
}

@vertex
fn vsm_vertex(@location(0) p: vec3<f32>) -> VsmVertexOut {
    let d = p - face.light;
    let w = dot(d, face.forward);
    // Texel row 0 is v = −margin; the framebuffer's row 0 is NDC y = +1.
    let s = face.margin * face.scale;
    let x = dot(d, face.right) / s;
    let y = -dot(d, face.up) / s;
    if (face.orthographic != 0u) {
        // Depth along the light's direction, [0, far] to [0, 1]; the ray casts stop at far too.
        return VsmVertexOut(vec4<f32>(x, y, w / face.far, 1.0), p);
    }
    // Depth for the depth test only (monotone in w); near = 1e-5 far clips what lies behind.
    let near = 1e-5 * face.far;
    let z = (w - near) * face.far / (face.far - near);
    return VsmVertexOut(vec4<f32>(x, y, z, w), p);
}

@fragment
fn vsm(in: VsmVertexOut) -> @location(0) vec2<f32> {
    var z = length(in.world - face.light);
    if (face.orthographic != 0u) {
        z = dot(in.world - face.light, face.forward);
    }
    return vec2<f32>(z, z * z);
}
