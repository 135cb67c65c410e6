// Imperfect shadow maps (`render::gpu::ism`): every VPL's sparse point set splatted into its
// paraboloid map, each texel's nearest layer of points kept, the holes filled by pull-push and
// the moments blurred. Rust twin: `visibility::ism::ImperfectShadowMaps::build` (the points are
// the same: `IsmSampler` samples them on the CPU). A sequence of dispatches, one entry point per
// phase — separate entry points rather than one switch, because lavapipe runs the code of every
// branch an entry point can reach, taken or not (a dispatch of the clearing code alone took a
// quarter of the time it took inside a switch over all phases). Every dispatch covers every map
// (workgroup row y = map); the end of a dispatch is the barrier between phases. The splat
// buffer starts zeroed (wgpu zero-initialises buffers):
//   `ism` (the pass's name): per point, its texel and distance z (`texel` in Rust); the texel's
//      nearest z, kept as the complement of its f32 bits by atomicMax (the bits of positive
//      floats order as u32; 0 is "no point");
//   `ism_layer`: per point within FRONT_LAYER of its texel's nearest: count, Σ e and Σ e² with
//      e = z / nearest − 1, as 64-bit fixed point in two u32 atomics each (exact, so the sums
//      do not depend on the order lanes run in), and the map's farthest kept z;
//   `ism_finest`: per texel, the finest level of the pyramid: (Σ z, Σ z², count);
//   `ism_pull`, one dispatch per coarser level: each texel the sum of its (up to) four
//      children, in the CPU's order;
//   `ism_push`, one dispatch per level, coarsest first: a texel with points takes its moments
//      (Σ z, Σ z²) / count, a hole its parent's; the moments replace the sums in place;
//   `ism_blur`: per texel, the 3 × 3 box blur (clamped at the edges), or a copy, into the
//      atlas.
// Prepended with shaders/shared/*.wgsl.

@group(0) @binding(0) var<uniform> params: GpuIsmParams;
@group(0) @binding(1) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> origins: array<GpuMapOrigin>;
// Per map, per texel: nearest z (bits), count, Σ e (hi, lo), Σ e² (hi, lo); then per map the
// farthest kept z (bits).
@group(0) @binding(3) var<storage, read_write> splats: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> pyramid: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> atlas: array<vec2<f32>>;

const TEXEL_WORDS: u32 = 6u;

struct IsmSplat {
    k: u32,
    z: f32,
    ok: bool,
}

// `visibility::ism::texel`: the texel and distance of p in the paraboloid map at o (`ok` false
// below its horizon or at its origin).
fn ism_texel(o: GpuMapOrigin, p: vec3<f32>, res: u32) -> IsmSplat {
    var s = IsmSplat(0u, 0.0, false);
    let v = p - o.position;
    let z = length(v);
    if (!(z > 0.0)) {
        return s;
    }
    let w = v / z;
    let d = vec3<f32>(dot(w, o.t), dot(w, o.b), dot(w, o.n));
    if (!(d.z > 0.0)) {
        return s;
    }
    let n = f32(res);
    let i = min(u32(max((d.x / (1.0 + d.z) + 1.0) * 0.5 * n, 0.0)), res - 1u);
    let j = min(u32(max((d.y / (1.0 + d.z) + 1.0) * 0.5 * n, 0.0)), res - 1u);
    s.k = j * res + i;
    s.z = z;
    s.ok = true;
    return s;
}

// Adds x ∈ [0, 128) as 64-bit fixed point (40 fractional bits) to the pair at `at` (hi, lo).
fn add_fixed(at: u32, x: f32) {
    let scaled = x * 256.0;
    let hi = u32(scaled);
    let lo = u32((scaled - f32(hi)) * 4294967296.0);
    let old = atomicAdd(&splats[at + 1u], lo);
    let carry = select(0u, 1u, old + lo < old);
    atomicAdd(&splats[at], hi + carry);
}

fn fixed_value(at: u32) -> f32 {
    return f32(atomicLoad(&splats[at])) * (1.0 / 256.0) + f32(atomicLoad(&splats[at + 1u])) * (1.0 / 1099511627776.0);
}

// The nearest z of the texel whose first word is at `at`.
fn nearest_at(at: u32) -> f32 {
    return bitcast<f32>(~atomicLoad(&splats[at]));
}

// `ism` and `ism_layer`: point gid.x of map gid.y.
fn splat_point(gid: vec3<u32>, layer: bool) {
    let m = gid.y;
    let q = gid.x;
    if (q >= params.points_per_map) {
        return;
    }
    let p = points[m * params.points_per_map + q];
    if (!(p.w > 0.0)) {
        return;
    }
    let s = ism_texel(origins[m], p.xyz, params.res);
    if (!s.ok) {
        return;
    }
    let at = (m * params.res * params.res + s.k) * TEXEL_WORDS;
    if (!layer) {
        atomicMax(&splats[at], ~bitcast<u32>(s.z));
        return;
    }
    let near = nearest_at(at);
    if (s.z <= near * (1.0 + params.front_layer)) {
        let e = s.z / near - 1.0;
        atomicAdd(&splats[at + 1u], 1u);
        add_fixed(at + 2u, e);
        add_fixed(at + 4u, e * e);
        atomicMax(&splats[params.maps * params.res * params.res * TEXEL_WORDS + m], bitcast<u32>(s.z));
    }
}

@compute @workgroup_size(64)
fn ism(@builtin(global_invocation_id) gid: vec3<u32>) {
    splat_point(gid, false);
}

@compute @workgroup_size(64)
fn ism_layer(@builtin(global_invocation_id) gid: vec3<u32>) {
    splat_point(gid, true);
}

// Σ z = n (c + Σ e), Σ z² = n² (c + 2 Σ e + Σ e²).
@compute @workgroup_size(64)
fn ism_finest(@builtin(global_invocation_id) gid: vec3<u32>) {
    let m = gid.y;
    let k = gid.x;
    let texels = params.res * params.res;
    if (k >= texels) {
        return;
    }
    let at = (m * texels + k) * TEXEL_WORDS;
    let c = atomicLoad(&splats[at + 1u]);
    var sums = vec4<f32>(0.0);
    if (c > 0u) {
        let near = nearest_at(at);
        let cf = f32(c);
        let se = fixed_value(at + 2u);
        let se2 = fixed_value(at + 4u);
        sums = vec4<f32>(near * (cf + se), near * near * (cf + 2.0 * se + se2), cf, 0.0);
    }
    pyramid[m * params.pyramid_len + k] = sums;
}

// This level's texel k from its children in the finer level (`other_*`).
@compute @workgroup_size(64)
fn ism_pull(@builtin(global_invocation_id) gid: vec3<u32>) {
    let m = gid.y;
    let k = gid.x;
    let n = params.level_n;
    if (k >= n * n) {
        return;
    }
    let pbase = m * params.pyramid_len;
    let cn = params.other_n;
    let x = 2u * (k % n);
    let y = 2u * (k / n);
    let child = pbase + params.other_offset;
    var s = pyramid[child + y * cn + x];
    if (x + 1u < cn) {
        s += pyramid[child + y * cn + x + 1u];
    }
    if (y + 1u < cn) {
        s += pyramid[child + (y + 1u) * cn + x];
        if (x + 1u < cn) {
            s += pyramid[child + (y + 1u) * cn + x + 1u];
        }
    }
    pyramid[pbase + params.level_offset + k] = s;
}

// This level's texel k, a hole taking its parent's (`other_*`) moments.
@compute @workgroup_size(64)
fn ism_push(@builtin(global_invocation_id) gid: vec3<u32>) {
    let m = gid.y;
    let k = gid.x;
    let n = params.level_n;
    if (k >= n * n) {
        return;
    }
    let pbase = m * params.pyramid_len;
    let at = pbase + params.level_offset + k;
    let e = pyramid[at];
    var mo = vec2<f32>(0.0);
    if (e.z > 0.0) {
        mo = e.xy / e.z;
    } else if (params.has_other != 0u) {
        let pn = params.other_n;
        let px = min((k % n) / 2u, pn - 1u);
        let py = min((k / n) / 2u, pn - 1u);
        mo = pyramid[pbase + params.other_offset + py * pn + px].xy;
    }
    pyramid[at] = vec4<f32>(mo, 0.0, 0.0);
}

@compute @workgroup_size(64)
fn ism_blur(@builtin(global_invocation_id) gid: vec3<u32>) {
    let m = gid.y;
    let k = gid.x;
    let res = params.res;
    let texels = res * res;
    if (k >= texels) {
        return;
    }
    let pbase = m * params.pyramid_len;
    var mo = pyramid[pbase + k].xy;
    if (params.blur != 0u) {
        let x = i32(k % res);
        let y = i32(k / res);
        let last = i32(res) - 1;
        var sum = vec2<f32>(0.0);
        for (var dy = -1; dy <= 1; dy = dy + 1) {
            let yy = u32(clamp(y + dy, 0, last));
            sum += pyramid[pbase + yy * res + u32(clamp(x - 1, 0, last))].xy;
            sum += pyramid[pbase + yy * res + u32(x)].xy;
            sum += pyramid[pbase + yy * res + u32(clamp(x + 1, 0, last))].xy;
        }
        mo = sum / 9.0;
    }
    atlas[m * texels + k] = mo;
}
