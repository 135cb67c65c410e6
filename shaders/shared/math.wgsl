// WGSL twins of the Rust math functions. Each function has the name of its Rust twin (a method
// `T::f` becomes `t_f`), and `render::gpu::twins` runs both over the same table of inputs.
// f32 throughout; the Rust twins compute some steps in f64, which the tolerances of the GPU
// tests account for.

const PI: f32 = 3.14159265358979;

// e^x − 1 without cancellation for small |x| (WGSL has no expm1): below 0.1 its Taylor series
// to x⁷ (truncation below 3e-12 relative); above, e^x − 1 loses at most ~10 ulp.
fn expm1(x: f32) -> f32 {
    if (abs(x) < 0.1) {
        return x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0 + x * (1.0 / 120.0
            + x * (1.0 / 720.0 + x * (1.0 / 5040.0)))))));
    }
    return exp(x) - 1.0;
}

// ∫_{S²} exp(λ (ω·p − 1)) dω = 2π (1 − e^{−2λ}) / λ, 4π at λ = 0 (`math::sg::lobe_integral`).
fn lobe_integral(sharpness: f32) -> f32 {
    if (sharpness > 0.0) {
        return -2.0 * PI * expm1(-2.0 * sharpness) / sharpness;
    }
    return 4.0 * PI;
}

// `math::sg::MAX_SHARPNESS`.
const MAX_SHARPNESS: f32 = 1e30;

// `math::sg::clean_sharpness`: NaN and negative values are 0, huge ones clamped.
fn clean_sharpness(l: f32) -> f32 {
    if (l > 0.0) {
        return min(l, MAX_SHARPNESS);
    }
    return 0.0;
}

// `Sg::product` (the Rust twin computes the exponent in f64).
fn sg_product(a: GpuSg, b: GpuSg) -> GpuSg {
    let l1 = clean_sharpness(a.sharpness);
    let l2 = clean_sharpness(b.sharpness);
    let v = a.axis * l1 + b.axis * l2;
    let l = length(v);
    let denom = l + l1 + l2;
    var log_scale = 0.0;
    if (denom > 0.0) {
        let d = a.axis - b.axis;
        log_scale = -(l1 * l2) * dot(d, d) / denom;
    }
    var p = a.axis;
    if (l > 0.0) {
        p = v / l;
    }
    return GpuSg(p, l, a.amplitude * b.amplitude * exp(log_scale), 0.0);
}

// `Sg::integral`.
fn sg_integral(s: GpuSg) -> vec3<f32> {
    return s.amplitude * lobe_integral(clean_sharpness(s.sharpness));
}

// ∫_{S²} G1 G2 dω of two lobes (`math::sg::Sg::inner_product`): the integral of their product
// lobe, e^{λ − λ1 − λ2} lobe_integral(λ) with λ = |λ1 p1 + λ2 p2|.
fn sg_inner_product(a: GpuSg, b: GpuSg) -> vec3<f32> {
    return sg_integral(sg_product(a, b));
}

// Chebyshev's upper bound of the lit fraction P(z ≥ t) from the moments (E[z], E[z²])
// (`visibility::vsm::chebyshev_upper_bound`).
fn chebyshev_upper_bound(moments: vec2<f32>, t: f32, min_variance: f32) -> f32 {
    let mu = moments.x;
    if (!(t > mu)) {
        return 1.0;
    }
    let v = max(moments.y - mu * mu, min_variance);
    let d = t - mu;
    return v / (v + d * d);
}

// Light-bleeding reduction: p rescaled from [b, 1] to [0, 1] (`visibility::vsm::reduce_bleeding`).
fn reduce_bleeding(p: f32, b: f32) -> f32 {
    if (!(b > 0.0)) {
        return p;
    }
    return clamp((p - b) / (1.0 - b), 0.0, 1.0);
}

// erf, Abramowitz & Stegun 7.1.26 (`cut::erf`).
fn erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.3275911 * abs(x));
    let y = 1.0 - (((((1.0614054 * t - 1.4531521) * t) + 1.4214137) * t - 0.28449672) * t
        + 0.2548296) * t * exp(-x * x);
    return select(-y, y, x >= 0.0);
}

// E[max(0, n·ω)] under a lobe whose axis has n·p = c (`cut::clamped_cosine_mean`).
fn clamped_cosine_mean(c: f32, sharpness: f32) -> f32 {
    let v = max(1.0 - c * c, 0.0) / max(sharpness, 1e-6);
    let sigma = min(sqrt(v), 1.0);
    if (!(sigma > 1e-6)) {
        return max(c, 0.0);
    }
    let z = c / sigma;
    let pdf = exp(-0.5 * z * z) * 0.3989423;
    let cdf = 0.5 * (1.0 + erf(z * 0.70710678));
    return clamp(c * cdf + sigma * pdf, 0.0, 1.0);
}

// ---- The integral of an SG over a spherical triangle (`math::spherical_triangle`), in f32.
// The Rust twin `integrate_sg` computes in f64; the algorithm is the same: the signed
// decomposition into one edge triangle P X Y per edge around the axis P, the closed radial part
// h(x) = (1 − e^{−λx})/λ, and the azimuthal integral by Gauss–Legendre of order 5 in
// t = tan(σ/2) (near half) or cot(σ/2) (far half), split where y = λx passes fixed offsets.

const TAU: f32 = 6.28318530717959;
const HALF_PI: f32 = 1.5707963267949;

// Solid angle of the spherical triangle a, b, c (unit vectors), Van Oosterom & Strackee.
fn solid_angle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> f32 {
    let num = abs(dot(a, cross(b, c)));
    let den = 1.0 + dot(a, b) + dot(b, c) + dot(c, a);
    return 2.0 * atan2(num, den);
}

struct EdgeFrame {
    s0: f32,
    k: f32,
    x0: f32,
    lam: f32,
}

fn edge_h(f: EdgeFrame, x: f32) -> f32 {
    return -expm1(-f.lam * x) / f.lam;
}

fn gl_integrand(f: EdgeFrame, t: f32, far: bool) -> f32 {
    let t2 = t * t;
    let q = 1.0 + t2;
    let w = 1.0 - t2;
    let jac = 2.0 * f.s0 * q / (f.s0 * f.s0 * w * w + 4.0 * t2);
    let r = f.x0 + 2.0 * f.k * t2 / q;
    if (far) {
        return exp(-f.lam * (2.0 - r)) * expm1(-f.lam * r) / f.lam * jac;
    }
    return edge_h(f, r) * jac;
}

// Gauss–Legendre of order 5 over t ∈ [a, b].
fn gl_piece(f: EdgeFrame, a: f32, b: f32, far: bool) -> f32 {
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    var s = 0.56888888888888889 * gl_integrand(f, mid, far);
    s += 0.47862867049936647 * (gl_integrand(f, mid - half * 0.53846931010568309, far)
        + gl_integrand(f, mid + half * 0.53846931010568309, far));
    s += 0.23692688505618909 * (gl_integrand(f, mid - half * 0.90617984593866399, far)
        + gl_integrand(f, mid + half * 0.90617984593866399, far));
    return s * half;
}

fn gl_r_at(f: EdgeFrame, t: f32) -> f32 {
    return f.x0 + 2.0 * f.k * t * t / (1.0 + t * t);
}

fn gl_t_at(f: EdgeFrame, r: f32) -> f32 {
    let u = clamp((r - f.x0) / (2.0 * f.k), 0.0, 0.5);
    return sqrt(u / (1.0 - u));
}

fn gl_x_at(f: EdgeFrame, t: f32, far: bool) -> f32 {
    let r = gl_r_at(f, t);
    return select(r, 2.0 - r, far);
}

fn gl_side(f: EdgeFrame, t_start: f32, t_end: f32, far: bool) -> f32 {
    var offsets = array<f32, 5>(2.5, 6.0, 12.0, 22.0, 40.0);
    let y_start = f.lam * gl_x_at(f, t_start, far);
    let y_end = f.lam * gl_x_at(f, t_end, far);
    let lo = min(t_start, t_end);
    let hi = max(t_start, t_end);
    let dir = select(1.0, -1.0, far);
    var total = 0.0;
    var t = t_start;
    // The last piece ends at t_end, with the same call of gl_piece as the others: one call site
    // (see integrate_sg).
    var ended = false;
    for (var i = 0u; i < 5u; i = i + 1u) {
        let y = y_start + offsets[i];
        ended = y >= y_end || !(f.k > 0.0);
        var t_next = t_end;
        if (!ended) {
            let x = y / f.lam;
            t_next = clamp(gl_t_at(f, select(x, 2.0 - x, far)), lo, hi);
        }
        total += dir * gl_piece(f, t, t_next, far);
        t = t_next;
        if (ended) {
            break;
        }
    }
    if (ended) {
        return total;
    }
    if (!far) {
        let psi_end = atan2(2.0 * t_end, f.s0 * (1.0 - t_end * t_end));
        let psi_t = atan2(2.0 * t, f.s0 * (1.0 - t * t));
        total += (psi_end - psi_t) / f.lam;
    }
    return total;
}

// tan(σ/2) for cos ψ ≥ 0 and cot(σ/2) for cos ψ ≤ 0.
fn gl_t_of(f: EdgeFrame, p: f32) -> f32 {
    let sp = sin(p);
    let cp = cos(p);
    let a = f.s0 * sp;
    let r = sqrt(a * a + cp * cp);
    let den = r + abs(cp);
    if (den > 0.0) {
        return min(a / den, 1.0);
    }
    return 1.0;
}

fn gl_monotone(f: EdgeFrame, pa: f32, pb: f32) -> f32 {
    var total = 0.0;
    // The near half (ψ < π/2) and the far half, in a loop: one call site of gl_side (see
    // integrate_sg).
    for (var half = 0u; half < 2u; half = half + 1u) {
        let far = half == 1u;
        var run = false;
        var t0 = 1.0;
        var t1 = 1.0;
        if (!far && pa < HALF_PI) {
            run = true;
            t0 = gl_t_of(f, pa);
            if (pb < HALF_PI) {
                t1 = gl_t_of(f, pb);
            }
        } else if (far && pb > HALF_PI) {
            run = true;
            let pf = max(pa, HALF_PI);
            total += edge_h(f, 2.0) * (pb - pf);
            if (pa > HALF_PI) {
                t0 = gl_t_of(f, pa);
            }
            t1 = gl_t_of(f, pb);
        }
        if (run) {
            total += gl_side(f, t0, t1, far);
        }
    }
    return total;
}

// Distance of t from the nearest multiple of 2π, in [0, π].
fn fold_angle(t: f32) -> f32 {
    return abs(t - TAU * round(t / TAU));
}

struct EdgeResult {
    integral: f32,
    dpsi: f32,
    xmin: f32,
}

fn edge_monotone(f: EdgeFrame, a: f32, b: f32, xmin: ptr<function, f32>) -> f32 {
    let fa0 = fold_angle(a);
    let fb0 = fold_angle(b);
    let fa = min(fa0, fb0);
    let fb = max(fa0, fb0);
    if (fb > fa) {
        if (fa == 0.0) {
            *xmin = f.x0;
        }
        return gl_monotone(f, fa, fb);
    }
    return 0.0;
}

fn edge_integral(p: vec3<f32>, lam: f32, x: vec3<f32>, y: vec3<f32>) -> EdgeResult {
    var skip = EdgeResult(0.0, 0.0, 3.0e38);
    let cx = cross(p, x);
    let cy = cross(p, y);
    if (dot(cx, cx) < 1e-14 || dot(cy, cy) < 1e-14) {
        return skip;
    }
    let n = cross(x, y);
    let nlen = length(n);
    let det = dot(p, n);
    if (!(nlen > 0.0) || det == 0.0) {
        return skip;
    }
    let dpsi = atan2(det, dot(cx, cy));
    let m = n * (sign(det) / nlen);
    let s0 = clamp(dot(p, m), 0.0, 1.0);
    let q = p * s0 - m;
    let k = length(q);
    var u: vec3<f32>;
    if (k > 1e-30) {
        u = q / k;
    } else {
        var t = vec3<f32>(0.0, 1.0, 0.0);
        if (abs(p.x) < 0.9) {
            t = vec3<f32>(1.0, 0.0, 0.0);
        }
        u = normalize(t - p * dot(p, t));
    }
    let v = cross(p, u);
    let psi_x = atan2(dot(x, v), dot(x, u));
    let psi_y = psi_x + dpsi;
    let f = EdgeFrame(s0, k, s0 * s0 / (1.0 + k), lam);
    let lo = min(psi_x, psi_y);
    let hi = max(psi_x, psi_y);
    let j = ceil(lo / PI);
    let mid = j * PI;
    var xmin = 3.0e38;
    var total = 0.0;
    // [lo, mid] and [mid, hi], or [lo, hi]: one call site (see integrate_sg).
    let split = mid > lo && mid < hi;
    for (var k = 0u; k < select(1u, 2u, split); k = k + 1u) {
        var start = lo;
        var end = hi;
        if (split && k == 0u) {
            end = mid;
        } else if (split) {
            start = mid;
        }
        total += edge_monotone(f, start, end, &xmin);
    }
    return EdgeResult(sign(dpsi) * total, dpsi, xmin);
}

// ∫_{ABC} exp(λ (ω·axis − 1)) dω (`math::spherical_triangle::integrate_sg`): the vertices need
// not be unit; either winding; never NaN or negative, never above the solid angle.
fn integrate_sg(axis: vec3<f32>, sharpness: f32, a_in: vec3<f32>, b_in: vec3<f32>, c_in: vec3<f32>) -> f32 {
    let la = length(a_in);
    let lb = length(b_in);
    let lc = length(c_in);
    if (!(la > 0.0 && lb > 0.0 && lc > 0.0)) {
        return 0.0;
    }
    let a = a_in / la;
    var b = b_in / lb;
    var c = c_in / lc;
    let lam = max(sharpness, 0.0);
    let lp = length(axis);
    let omega = solid_angle(a, b, c);
    if (!(lp > 0.0)) {
        return select(0.0, omega, lam == 0.0);
    }
    let p = axis / lp;
    if (!(omega > 0.0)) {
        return 0.0;
    }
    if (lam == 0.0) {
        return omega;
    }
    if (dot(a, cross(b, c)) < 0.0) {
        let t = b;
        b = c;
        c = t;
    }
    var xmin = min(0.5 * dot(a - p, a - p), min(0.5 * dot(b - p, b - p), 0.5 * dot(c - p, c - p)));
    // The three edges in a loop: one call site, since lavapipe inlines every call and its cost
    // per invocation grows with the code (docs/gpu.md).
    var sum = 0.0;
    var wind = 0.0;
    var verts = array<vec3<f32>, 3>(a, b, c);
    for (var e = 0u; e < 3u; e = e + 1u) {
        let r = edge_integral(p, lam, verts[e], verts[(e + 1u) % 3u]);
        sum += r.integral;
        wind += r.dpsi;
        xmin = min(xmin, r.xmin);
    }
    let lobe = lobe_integral(lam);
    let w = wind / TAU;
    var frac = -w;
    if (w < -0.999999) {
        frac = 1.0;
    } else if (w > -1e-6) {
        frac = 0.0;
    }
    if (w > 0.25) {
        xmin = 0.0;
    }
    let result = sum + frac * lobe;
    let upper = omega * exp(-lam * xmin);
    let lower = omega * exp(-2.0 * lam);
    if (result != result) {
        return lower;
    }
    return clamp(result, lower, upper);
}

// ---- The cut's error bound (`cut::node_bound`): an upper bound of the summed SG contribution
// of a node's triangles at receiver x (visibility ignored). See docs/sg-renderer.md.

// cos γ − 1 as −2 sin²(γ/2), without cancellation (`cut::cos_minus_one`).
fn cos_minus_one(g: f32) -> f32 {
    let s = sin(0.5 * g);
    return -2.0 * s * s;
}

// The angle between two vectors, robust for small and large angles.
fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return atan2(length(cross(a, b)), dot(a, b));
}

fn node_bound(n: GpuNodeBound, x: vec3<f32>, rx: GpuReceiver) -> vec3<f32> {
    let lo = n.bbox_min;
    let hi = n.bbox_max;
    // Entirely below the receiver's horizon: nothing arrives.
    var above = false;
    for (var i = 0u; i < 8u; i = i + 1u) {
        let corner = vec3<f32>(
            select(hi.x, lo.x, (i & 1u) == 0u),
            select(hi.y, lo.y, (i & 2u) == 0u),
            select(hi.z, lo.z, (i & 4u) == 0u),
        );
        if (dot(rx.normal, corner - x) > 0.0) {
            above = true;
        }
    }
    if (!above) {
        return vec3<f32>(0.0);
    }
    let dd = clamp(x, lo, hi) - x;
    let d2 = dot(dd, dd);
    if (!(d2 > 0.0)) {
        return vec3<f32>(3.0e38);
    }
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * length(hi - lo);
    let to_c = centre - x;
    let dist = length(to_c);
    let has_cone = dist > radius;
    var dir = vec3<f32>(0.0, 0.0, 1.0);
    var half = 0.0;
    if (has_cone) {
        dir = to_c / dist;
        half = asin(radius / dist);
    }
    var hmax = rx.diffuse;
    let widest = 1.0 / rx.stretch;
    for (var i = 0u; i < rx.lobe_count; i = i + 1u) {
        let h = rx.lobes[i];
        if (has_cone) {
            let gap = max(angle_between(h.axis, dir) - half, 0.0);
            hmax += h.amplitude * exp(min(h.sharpness * widest * cos_minus_one(gap), 0.0));
        } else {
            hmax += h.amplitude;
        }
    }
    var has_gap = false;
    var gap = 0.0;
    if (has_cone && n.image_min.x <= n.image_max.x) {
        let ic = 0.5 * (n.image_min + n.image_max);
        let ir = 0.5 * length(n.image_max - n.image_min);
        let to_i = ic - x;
        let di = length(to_i);
        if (di > ir) {
            has_gap = true;
            gap = max(angle_between(dir, to_i / di) - half - asin(ir / di), 0.0);
        }
    }
    var edges = array<f32, 6>(0.0, 2.0, 8.0, 32.0, 128.0, 512.0);
    var radiance = n.diffuse;
    for (var b = 0u; b < 6u; b = b + 1u) {
        var f = 1.0;
        if (has_gap) {
            f = exp(min(edges[b] * cos_minus_one(gap), 0.0));
        }
        radiance += n.peak_by_sharpness[b].xyz * f;
    }
    var cos_max = 1.0;
    if (has_cone && n.has_cone > 0.0) {
        var g = angle_between(n.cone_axis, dir);
        g = min(g, PI - g);
        cos_max = cos(max(g - n.cone_half_angle - half, 0.0));
    }
    return radiance * hmax * (1.001 * cos_max / d2);
}

// ---- Tonemapping (`image::tonemap`).

// The tone curve of operator `op` (0 clamp, 1 Reinhard, 2 ACES) on one exposed linear value
// (`image::tonemap::ToneOperator::apply`): negative and NaN → 0, +∞ → 1.
fn tone_operator_apply(op: u32, x: f32) -> f32 {
    if (x != x || x <= 0.0) {
        return 0.0;
    }
    if (x > 3.4028234e38) {
        return 1.0;
    }
    var y = x;
    if (op == 1u) {
        y = x / (1.0 + x);
    } else if (op == 2u) {
        y = (2.51 * x + 0.03) / (2.43 * x + 0.59 + 0.14 / x);
    }
    return clamp(y, 0.0, 1.0);
}

// The sRGB OETF on [0, 1] (`image::tonemap::srgb_oetf`, which evaluates it in f64).
fn srgb_oetf(x_in: f32) -> f32 {
    var x = 0.0;
    if (x_in == x_in) {
        x = clamp(x_in, 0.0, 1.0);
    }
    if (x <= 0.0031308) {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

// ---- Bilinear lookups in an n × n map of moments over [−1, 1]² (texel centres at
// (2i + 1)/n − 1), clamped to the outermost centres: `visibility::vsm::bilinear_moments`,
// split so that each pass reads the four texels from its own buffer.
struct Bilinear {
    // Offsets of the texels (x0, y0), (x1, y0), (x0, y1), (x1, y1) within the map.
    i00: u32,
    i10: u32,
    i01: u32,
    i11: u32,
    fx: f32,
    fy: f32,
}

fn bilinear_texels(n: u32, u: f32, v: f32) -> Bilinear {
    let top = f32(n - 1u);
    let x = clamp((u + 1.0) * 0.5 * f32(n) - 0.5, 0.0, top);
    let y = clamp((v + 1.0) * 0.5 * f32(n) - 0.5, 0.0, top);
    let x0 = u32(floor(x));
    let y0 = u32(floor(y));
    let x1 = min(x0 + 1u, n - 1u);
    let y1 = min(y0 + 1u, n - 1u);
    return Bilinear(y0 * n + x0, y0 * n + x1, y1 * n + x0, y1 * n + x1, x - f32(x0), y - f32(y0));
}

fn bilinear_mix(b: Bilinear, m00: vec2<f32>, m10: vec2<f32>, m01: vec2<f32>, m11: vec2<f32>) -> vec2<f32> {
    let r0 = m00 * (1.0 - b.fx) + m10 * b.fx;
    let r1 = m01 * (1.0 - b.fx) + m11 * b.fx;
    return r0 * (1.0 - b.fy) + r1 * b.fy;
}
