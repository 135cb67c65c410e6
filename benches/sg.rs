//! ns per call of the SG core: the integral of an SG over a spherical triangle (both schemes and
//! their variants) over a fixed table of realistic inputs, and the SG product / inner product.
//!
//! Run: `cargo bench --bench sg`. Every benchmark walks the
//! whole table per iteration; divan's throughput is in calls (items) per second, and the ns per
//! call is the median time divided by the table size. Results: `results/sg-core.md`.

use divan::{Bencher, black_box, counter::ItemsCount};
use glam::Vec3;
use interreflect::math::sg::Sg;
use interreflect::math::spherical_triangle::{
    Scheme, benchmark_inputs, integrate_sg, integrate_sg_gauss_legendre,
    integrate_sg_piecewise_linear, integrate_sg_scheme,
};

fn main() {
    divan::main();
}

const LAMBDAS: [f32; 5] = [1.0, 10.0, 100.0, 1000.0, 10000.0];

/// Rotate `c` by `angle` towards azimuth `az` (in a fixed tangent frame).
fn offset(c: Vec3, az: f32, angle: f32) -> Vec3 {
    let t = if c.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let t = (t - c * c.dot(t)).normalize();
    let b = c.cross(t);
    (c * angle.cos() + (t * az.cos() + b * az.sin()) * angle.sin()).normalize()
}

fn run(
    bencher: Bencher,
    rows: Vec<(Vec3, f32, Vec3, Vec3, Vec3)>,
    f: impl Fn(Vec3, f32, Vec3, Vec3, Vec3) -> f32 + Sync,
) {
    bencher.counter(ItemsCount::new(rows.len())).bench(|| {
        let mut s = 0.0f32;
        for &(p, l, a, b, c) in black_box(&rows) {
            s += f(p, l, a, b, c);
        }
        s
    });
}

/// The default `integrate_sg`, per λ (9 geometries each).
#[divan::bench(args = LAMBDAS)]
fn integrate_sg_default(bencher: Bencher, lam: f32) {
    run(bencher, benchmark_inputs(&[lam]), integrate_sg);
}

/// Gauss-Legendre (default order), per λ.
#[divan::bench(args = LAMBDAS)]
fn integrate_sg_gl(bencher: Bencher, lam: f32) {
    run(
        bencher,
        benchmark_inputs(&[lam]),
        integrate_sg_gauss_legendre,
    );
}

/// The paper's piecewise-linear scheme (default step), per λ.
#[divan::bench(args = LAMBDAS)]
fn integrate_sg_pl(bencher: Bencher, lam: f32) {
    run(
        bencher,
        benchmark_inputs(&[lam]),
        integrate_sg_piecewise_linear,
    );
}

/// Gauss-Legendre orders over the whole table (45 calls), for accuracy per ns.
#[divan::bench(args = [3, 4, 5, 6, 8])]
fn variant_gl_order(bencher: Bencher, order: usize) {
    run(bencher, benchmark_inputs(&LAMBDAS), move |p, l, a, b, c| {
        integrate_sg_scheme(p, l, a, b, c, Scheme::GaussLegendre { order })
    });
}

/// Piecewise-linear knot steps over the whole table (45 calls), for accuracy per ns.
#[divan::bench(args = [0.2, 0.1, 0.05, 0.025])]
fn variant_pl_step(bencher: Bencher, step: f64) {
    run(bencher, benchmark_inputs(&LAMBDAS), move |p, l, a, b, c| {
        integrate_sg_scheme(p, l, a, b, c, Scheme::PiecewiseLinear { step })
    });
}

/// The f32 SIMD kernel (`sg::kernel::integrate_sg_batch`) over the whole table (45 calls) with
/// each instruction set this CPU runs (0: AVX2, 1: SSE2, 2: scalar lanes).
#[divan::bench(args = [0, 1, 2])]
fn kernel_batch(bencher: Bencher, which: usize) {
    use interreflect::sg::kernel::{Isa, TriangleProblems, integrate_sg_batch};
    let isa = [Isa::Avx2, Isa::Sse2, Isa::Scalar][which];
    if !isa.available() {
        return;
    }
    let mut probs = TriangleProblems::default();
    for (p, l, a, b, c) in benchmark_inputs(&LAMBDAS) {
        probs.push(p, l, a, b, c);
    }
    let mut out = vec![0.0; probs.len()];
    bencher
        .counter(ItemsCount::new(probs.len()))
        .bench_local(|| {
            integrate_sg_batch(isa, black_box(&probs), &mut out);
            out[0]
        });
}

fn lobes() -> Vec<(Sg, Sg)> {
    let mut out = Vec::new();
    for (i, l1) in [1.0f32, 30.0, 1000.0, 1e4].into_iter().enumerate() {
        for (j, l2) in [2.133f32, 100.0, 1e5].into_iter().enumerate() {
            let a = Sg::new(offset(Vec3::Z, i as f32, 0.3), l1, Vec3::new(1.0, 0.5, 0.2));
            let b = Sg::new(offset(Vec3::Z, j as f32 + 2.0, 0.1), l2, Vec3::ONE);
            out.push((a, b));
        }
    }
    out
}

/// `Sg::product` over 12 lobe pairs.
#[divan::bench]
fn sg_product(bencher: Bencher) {
    let rows = lobes();
    bencher.counter(ItemsCount::new(rows.len())).bench(|| {
        let mut s = Vec3::ZERO;
        for (a, b) in black_box(&rows) {
            s += a.product(b).amplitude;
        }
        s
    });
}

/// `Sg::inner_product` over 12 lobe pairs.
#[divan::bench]
fn sg_inner_product(bencher: Bencher) {
    let rows = lobes();
    bencher.counter(ItemsCount::new(rows.len())).bench(|| {
        let mut s = Vec3::ZERO;
        for (a, b) in black_box(&rows) {
            s += a.inner_product(b);
        }
        s
    });
}

/// One-triangle SG transport (reflector lobes + receiver integration) over the single-triangle
/// study's material pairs in the mid-size configuration, per call.
#[divan::bench]
fn one_triangle_transport(bencher: Bencher) {
    use interreflect::sg::transport::study;
    let mats = study::materials();
    let g = study::geometries()[1];
    let opts = interreflect::sg::transport::ReceiverOptions::default();
    let pairs: Vec<_> = mats
        .iter()
        .flat_map(|a| mats.iter().map(move |b| (a.brdf, b.brdf)))
        .collect();
    bencher.counter(ItemsCount::new(pairs.len())).bench(|| {
        for (a, b) in &pairs {
            black_box(study::sg_value(
                black_box(&g),
                a,
                b,
                study::Aim::MirrorImage,
                &opts,
            ));
        }
    });
}
