// The G-buffer: the scene's triangles rasterised from the camera, keeping per pixel the nearest
// triangle's index, the barycentrics (u, v) of vertices 1 and 2 at the pixel centre and the
// distance t from the camera, as u32 bits in an Rgba32Uint target (no triangle: index
// 0xffffffff). Rust twin: the primary hit of the ray through the pixel centre
// (`Camera::ray_dir` + `Accel::intersect`). Triangles are drawn unindexed, three vertices each,
// so that every vertex carries its triangle's index and its corner's barycentric coordinates.
// Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> cam: GpuCamera;

struct GbufferVertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) bary: vec2<f32>,
    @location(2) @interpolate(flat) tri: u32,
}

@vertex
fn gbuffer_vertex(@location(0) p: vec3<f32>, @builtin(vertex_index) vi: u32) -> GbufferVertexOut {
    let d = p - cam.position;
    let w = dot(d, cam.forward);
    let x = dot(d, cam.right) / (cam.tan_half * cam.aspect);
    let y = dot(d, cam.up) / cam.tan_half;
    let near = 1e-5 * cam.far;
    let z = (w - near) * cam.far / (cam.far - near);
    let corner = vi % 3u;
    var bary = vec2<f32>(0.0, 0.0);
    if (corner == 1u) {
        bary = vec2<f32>(1.0, 0.0);
    } else if (corner == 2u) {
        bary = vec2<f32>(0.0, 1.0);
    }
    return GbufferVertexOut(vec4<f32>(x, y, z, w), p, bary, vi / 3u);
}

@fragment
fn gbuffer(in: GbufferVertexOut) -> @location(0) vec4<u32> {
    let t = length(in.world - cam.position);
    return vec4<u32>(in.tri, bitcast<u32>(in.bary.x), bitcast<u32>(in.bary.y), bitcast<u32>(t));
}
