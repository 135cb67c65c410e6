//! Every WGSL math function against its Rust twin over the same table of inputs, on the GPU
//! (lavapipe in CI; `CI=true` makes a missing adapter a failure, otherwise the test skips with a
//! note).

mod common;

use glam::Vec3;
use interreflect::brdf::{Brdf, Distribution};
use interreflect::math::sampling::Rng;
use interreflect::math::sg::lobe_integral;
use interreflect::math::spherical_triangle::benchmark_inputs;
use interreflect::render::gpu::layout::TwinQuery;
use interreflect::render::gpu::twins::{Twin, brdf_row, cpu, run};

fn unit(rng: &mut Rng) -> [f32; 3] {
    loop {
        let v = [
            2.0 * rng.f32() - 1.0,
            2.0 * rng.f32() - 1.0,
            2.0 * rng.f32() - 1.0,
        ];
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if l > 0.1 && l <= 1.0 {
            return [v[0] / l, v[1] / l, v[2] / l];
        }
    }
}

/// λ log-uniform in [10^lo, 10^hi].
fn log_uniform(rng: &mut Rng, lo: f32, hi: f32) -> f32 {
    10f32.powf(lo + (hi - lo) * rng.f32())
}

fn row(a: [f32; 4]) -> TwinQuery {
    TwinQuery {
        a,
        ..TwinQuery::default()
    }
}

/// The table of each twin: edge cases, then random rows.
fn table(t: Twin) -> Vec<TwinQuery> {
    let mut rng = Rng::keyed(7, t as u64, 0);
    let mut out = Vec::new();
    match t {
        Twin::LobeIntegral => {
            for l in [
                0.0, 1e-7, 1e-4, 4e-3, 0.01, 0.1, 0.5, 1.0, 2.133, 10.0, 1e2, 1e3, 1e4, 1e5,
            ] {
                out.push(row([l, 0.0, 0.0, 0.0]));
            }
            for _ in 0..500 {
                out.push(row([log_uniform(&mut rng, -4.0, 5.0), 0.0, 0.0, 0.0]));
            }
        }
        Twin::SgInnerProduct => {
            for i in 0..1000 {
                let p1 = unit(&mut rng);
                // Every 4th pair nearly aligned (sharp products), the rest random.
                let p2 = if i % 4 == 0 {
                    let d = unit(&mut rng);
                    let e = 0.02 * rng.f32();
                    let v = [p1[0] + e * d[0], p1[1] + e * d[1], p1[2] + e * d[2]];
                    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    [v[0] / l, v[1] / l, v[2] / l]
                } else {
                    unit(&mut rng)
                };
                let (l1, l2) = (
                    log_uniform(&mut rng, -2.0, 4.0),
                    log_uniform(&mut rng, -2.0, 4.0),
                );
                let amp = |rng: &mut Rng| [2.0 * rng.f32(), 2.0 * rng.f32(), 2.0 * rng.f32(), 0.0];
                out.push(TwinQuery {
                    a: [p1[0], p1[1], p1[2], l1],
                    b: amp(&mut rng),
                    c: [p2[0], p2[1], p2[2], l2],
                    d: amp(&mut rng),
                });
            }
        }
        Twin::ChebyshevUpperBound => {
            for _ in 0..1000 {
                let mu = 10.0 * rng.f32();
                let var = 0.5 * rng.f32() * rng.f32();
                let t = mu + 2.0 * (rng.f32() - 0.3);
                out.push(row([mu, mu * mu + var, t, 1e-6]));
            }
        }
        Twin::ReduceBleeding => {
            for b in [0.0, 0.2, 0.5, 0.9] {
                for i in 0..=100 {
                    out.push(row([i as f32 / 100.0, b, 0.0, 0.0]));
                }
            }
        }
        Twin::ClampedCosineMean => {
            for c in [-1.0, -0.5, 0.0, 1e-4, 0.5, 1.0] {
                for l in [0.0, 1e-3, 2.133, 100.0, 1e5] {
                    out.push(row([c, l, 0.0, 0.0]));
                }
            }
            for _ in 0..1000 {
                out.push(row([
                    2.0 * rng.f32() - 1.0,
                    log_uniform(&mut rng, -3.0, 5.0),
                    0.0,
                    0.0,
                ]));
            }
        }
        Twin::IntegrateSg => {
            let tri = |p: [f32; 3], q: [f32; 3], r: [f32; 3]| TwinQuery {
                a: [0.0; 4],
                b: [p[0], p[1], p[2], 0.0],
                c: [q[0], q[1], q[2], 0.0],
                d: [r[0], r[1], r[2], 0.0],
            };
            for (axis, lam, a, b, c) in benchmark_inputs(&[0.0, 1.0, 10.0, 100.0, 1000.0, 10000.0])
            {
                let mut r = tri(a.to_array(), b.to_array(), c.to_array());
                r.a = [axis.x, axis.y, axis.z, lam];
                out.push(r);
            }
            // Random triangles of every size around random axes, the axis inside or outside.
            for _ in 0..2000 {
                let centre = unit(&mut rng);
                let size = log_uniform(&mut rng, -2.5, 0.2);
                let mut v = [[0.0f32; 3]; 3];
                for vk in &mut v {
                    let d = unit(&mut rng);
                    let w = [
                        centre[0] + size * d[0],
                        centre[1] + size * d[1],
                        centre[2] + size * d[2],
                    ];
                    // Not unit on purpose: the integral normalises its vertices.
                    let s = 0.5 + rng.f32();
                    *vk = [w[0] * s, w[1] * s, w[2] * s];
                }
                let off = unit(&mut rng);
                let spread = 2.0 * size * rng.f32();
                let ax = [
                    centre[0] + spread * off[0],
                    centre[1] + spread * off[1],
                    centre[2] + spread * off[2],
                ];
                let l = (ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]).sqrt();
                let mut r = tri(v[0], v[1], v[2]);
                r.a = [
                    ax[0] / l,
                    ax[1] / l,
                    ax[2] / l,
                    log_uniform(&mut rng, -1.0, 4.0),
                ];
                out.push(r);
            }
        }
        Twin::CosineWeighted => {
            // The integral's rows, each with a receiver normal: half of them nearly
            // perpendicular to the axis (the lobe near the horizon, where the central
            // difference runs), half random.
            for (k, mut r) in table(Twin::IntegrateSg).into_iter().enumerate() {
                let p = [r.a[0], r.a[1], r.a[2]];
                let mut n = unit(&mut rng);
                if k % 2 == 0 {
                    let d = n[0] * p[0] + n[1] * p[1] + n[2] * p[2];
                    let t = 0.3 * (rng.f32() - 0.5);
                    n = [
                        n[0] - (d - t) * p[0],
                        n[1] - (d - t) * p[1],
                        n[2] - (d - t) * p[2],
                    ];
                    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                    n = [n[0] / l, n[1] / l, n[2] / l];
                }
                r.b[3] = n[0];
                r.c[3] = n[1];
                r.d[3] = n[2];
                out.push(r);
            }
        }
        Twin::BrdfEval => {
            // Every model with random colours (diffuse + specular ≤ 1) and parameters from
            // rough to near-mirror; half the rows near the specular peak (wi the mirror of wo,
            // perturbed by a few lobe widths), a tenth with wi or wo below the horizon.
            let upper = |rng: &mut Rng| {
                let v = unit(rng);
                [v[0], v[1], v[2].abs().max(1e-4)]
            };
            for i in 0..3000 {
                let model = i % 6;
                let kd: [f32; 3] = [rng.f32(), rng.f32(), rng.f32()];
                let ks: [f32; 3] = [0, 1, 2].map(|k| (1.0 - kd[k]) * rng.f32());
                let (diffuse, specular) = (Vec3::from(kd), Vec3::from(ks));
                let exponent = if i % 50 == 1 {
                    0.0
                } else {
                    log_uniform(&mut rng, 0.0, 6.0)
                };
                let roughness = log_uniform(&mut rng, -3.0, 0.0);
                let brdf = match model {
                    0 => Brdf::Lambert { diffuse },
                    1 => Brdf::Phong {
                        diffuse,
                        specular,
                        exponent,
                    },
                    2 => Brdf::BlinnPhong {
                        diffuse,
                        specular,
                        exponent,
                    },
                    3 => Brdf::Ward {
                        diffuse,
                        specular,
                        roughness,
                    },
                    m => Brdf::CookTorrance {
                        diffuse,
                        specular,
                        roughness,
                        distribution: if m == 4 {
                            Distribution::Beckmann
                        } else {
                            Distribution::Ggx
                        },
                    },
                };
                let wo = Vec3::from(upper(&mut rng));
                let mut wi = if i % 2 == 0 {
                    // Within a few lobe widths of the mirror direction.
                    let width = match model {
                        1 | 2 => 3.0 / (exponent + 1.0).sqrt(),
                        _ => 3.0 * roughness,
                    };
                    let r = Vec3::new(-wo.x, -wo.y, wo.z);
                    let j = Vec3::from(unit(&mut rng)) * (width * rng.f32());
                    let w = (r + j).normalize();
                    Vec3::new(w.x, w.y, w.z.abs().max(1e-4)).normalize()
                } else {
                    Vec3::from(upper(&mut rng))
                };
                if i % 10 == 3 {
                    wi.z = -wi.z;
                }
                let wo = if i % 10 == 7 {
                    Vec3::new(wo.x, wo.y, -wo.z)
                } else {
                    wo
                };
                out.push(brdf_row(&brdf, wo, wi));
            }
        }
    }
    out
}

/// (relative, absolute) tolerance per twin and row, with why.
fn tolerance(t: Twin, q: &TwinQuery) -> (f32, f32) {
    match t {
        // f32 exp on the GPU (Vulkan allows 3 + 2|x| ulp; lavapipe's is near 1 ulp) against an
        // f64 evaluation rounded once: 1e-5 relative is ~100 ulp of headroom.
        Twin::LobeIntegral => (1e-5, 0.0),
        // The exponent −λ1λ2|p1 − p2|²/(λ + λ1 + λ2) in f32 (the Rust twin is f64) reaches
        // tens for these sharpnesses: its rounding, ~1e-7 × |exponent|, becomes a relative error
        // of the result of the same size, 1e-5 at |exponent| = 100; results below 1e-30 are 0 on
        // one side or the other.
        Twin::SgInnerProduct => (1e-4, 1e-30),
        // The same f32 formulas on both sides: only contraction into FMAs differs.
        Twin::ChebyshevUpperBound | Twin::ReduceBleeding => (1e-6, 1e-7),
        // The same f32 formula with two exps: a few ulp of each.
        Twin::ClampedCosineMean => (1e-5, 1e-6),
        // The f32 port against the f64 Rust. The three signed edge integrals and the winding
        // term each reach the lobe's whole integral 2π(1 − e^{−2λ})/λ and cancel down to the
        // result, so f32 rounding leaves an error measured against the lobe: at most 1.5e-4
        // of it, where a sharp lobe's axis lies within ~1e-3 rad of a vertex (azimuths of
        // nearly coincident directions in f32), under 3e-5 of it on all but 5 of these 2054
        // rows. Allowed: twice the worst, plus 1e-3 relative for the exponentials.
        Twin::IntegrateSg => (1e-3, 3e-4 * lobe_integral(q.a[3])),
        // The same cancellation, inherited from the integral it calls once or twice, and near
        // the horizon a central difference of two integrals divided by 2h = 0.2√λ: measured
        // at most 1.4e-4 of the lobe's integral on these rows (half of them with the lobe
        // within ±0.15 of the horizon); allowed as for the integral.
        Twin::CosineWeighted => (1e-3, 3e-4 * lobe_integral(q.a[3])),
        // f32 against the Rust twin's f64 half vector and 1 − a·b. Near a sharp peak the
        // exponent n (1 − cos θh) reaches tens for exponents up to 1e6 (α down to 1e-3), and
        // the f32 rounding of the inputs' tangent components (~1e-7 absolute) moves 1 − cos θh
        // by ~1e-5 relative: measured at most 3.7e-4 relative on these rows. Allowed 2e-3
        // relative; values below 1e-6 (1/sr, far outside a lobe) are zero on one side or the
        // other.
        Twin::BrdfEval => (2e-3, 1e-6),
    }
}

#[test]
fn every_wgsl_math_function_matches_its_rust_twin() {
    let Some(gpu) = common::gpu() else { return };
    for t in Twin::ALL {
        let rows = table(t);
        let g = run(&gpu, t, &rows).unwrap_or_else(|e| panic!("{}: {e}", t.wgsl_name()));
        assert_eq!(g.len(), rows.len());
        let mut worst = 0.0f32;
        let mut worst_abs = 0.0f32;
        let mut worst_of_allowed = 0.0f32;
        // Rows whose difference exceeds a tenth of the absolute tolerance (the tail).
        let mut tail = 0usize;
        for (q, gv) in rows.iter().zip(&g) {
            let (rel, abs) = tolerance(t, q);
            let cv = cpu(t, q);
            for k in 0..4 {
                let err = (gv[k] - cv[k]).abs();
                let allowed = rel * cv[k].abs() + abs;
                assert!(
                    err <= allowed && gv[k].is_finite(),
                    "{}: row {q:?}: GPU {} against Rust {} (lane {k})",
                    t.wgsl_name(),
                    gv[k],
                    cv[k]
                );
                worst_abs = worst_abs.max(err);
                worst_of_allowed = worst_of_allowed.max(err / allowed.max(1e-38));
                if abs > 0.0 && err > 0.1 * abs {
                    tail += 1;
                }
                // The relative difference where it means something (well above `abs`).
                if cv[k].abs() > 1e3 * abs.max(1e-30) {
                    worst = worst.max(err / cv[k].abs());
                }
            }
        }
        eprintln!(
            "{}: {} rows, largest relative difference {worst:.2e} (where the value is well above \
             the absolute tolerance), largest absolute difference {worst_abs:.2e}, largest \
             share of the tolerance used {worst_of_allowed:.2}; {tail} above a tenth of the \
             absolute tolerance",
            t.wgsl_name(),
            rows.len(),
        );
    }
}

/// The comparison is not vacuous: a twin evaluated on the wrong function differs.
#[test]
fn a_wrong_function_is_detected() {
    let Some(gpu) = common::gpu() else { return };
    let rows = table(Twin::ClampedCosineMean);
    let g = run(&gpu, Twin::LobeIntegral, &rows).unwrap();
    let differs = rows
        .iter()
        .zip(&g)
        .any(|(q, gv)| (gv[0] - cpu(Twin::ClampedCosineMean, q)[0]).abs() > 1e-3);
    assert!(differs);
}

/// The cut's error bound on the GPU against `cut::node_bound`, over real nodes: the bunny
/// scene's tree (gold Ward bunny, near-mirror Phong wall, Lambertian floor), lit without
/// shadows, at receiver points on its surfaces with random views. Points inside a node's box
/// have an infinite bound on both sides (3e38 in WGSL).
#[test]
fn node_bound_matches_its_rust_twin() {
    use interreflect::render::gpu::layout::GpuNodeBound;
    use interreflect::render::gpu::twins::run_node_bound;
    use interreflect::sg::node_bound;

    let Some(gpu) = common::gpu() else { return };
    let (scene, pieces, tree) = scene_tree("bunny");
    let lit = unshadowed(&scene, &pieces, &tree);
    let internal: Vec<u32> = (0..tree.nodes.len() as u32)
        .filter(|&i| {
            tree.nodes[i as usize].children.is_some() && lit.nodes[i as usize].weight > 0.0
        })
        .collect();
    let mut rng = Rng::keyed(11, 0, 0);
    let (mut nodes, mut receivers, mut points, mut want) = (vec![], vec![], vec![], vec![]);
    for (row, rx) in lit_rows(&scene, 3000, 12) {
        // Half the rows from the top of the tree (large, loose nodes), half from anywhere.
        let k = if points.len() % 2 == 0 {
            internal[(rng.f32() * internal.len().min(64) as f32) as usize % internal.len().min(64)]
        } else {
            internal[((rng.f32() * internal.len() as f32) as usize).min(internal.len() - 1)]
        };
        nodes.push(GpuNodeBound::new(&lit, k));
        receivers.push(row.receiver);
        points.push(row.x);
        want.push(node_bound(
            &tree.nodes[k as usize],
            &lit.nodes[k as usize],
            row.x,
            &rx,
        ));
    }
    let got = run_node_bound(&gpu, &nodes, &receivers, &points).unwrap();
    let (mut worst, mut infinite, mut zero, mut loose) = (0.0f32, 0usize, 0usize, 0usize);
    for (i, (g, w)) in got.iter().zip(&want).enumerate() {
        for k in 0..3 {
            let (g, w) = (g[k], w[k]);
            if w.is_infinite() {
                assert!(g >= 1e38, "row {i}: GPU {g} where Rust is infinite");
                infinite += 1;
                continue;
            }
            if w == 0.0 {
                zero += 1;
            }
            // The same f32 formula on both sides, but the GPU's asin, atan2, sin and exp differ
            // from Rust's by ulps, and two factors amplify them: the box's angular radius
            // asin(r/d) is ill-conditioned for a receiver just outside a node's bounding sphere
            // (r/d → 1), and a sharp receiver lobe (λ = 400 on the wall) raises the angle's error
            // to an exponent. Measured at most 7.5e-3 relative on these rows (1.7e-2 on an
            // earlier draw), 1e-4 on most (printed below); allowed 5e-2. The cut only orders
            // refinement by the bound.
            let err = (g - w).abs();
            assert!(
                err <= 5e-2 * w.abs() + 1e-30 && g.is_finite(),
                "row {i} (node {:?}): GPU {g} against Rust {w}",
                nodes[i].bbox_min
            );
            if w > 0.0 {
                worst = worst.max(err / w);
                if err > 1e-4 * w {
                    loose += 1;
                }
            }
        }
    }
    eprintln!(
        "node_bound: {} rows, largest relative difference {worst:.2e}, {loose} channels above \
         1e-4 relative; {infinite} infinite and {zero} zero channels",
        points.len()
    );
    // Not vacuous: many rows have a finite, positive bound.
    let positive = want.iter().filter(|w| w.x.is_finite() && w.x > 0.0).count();
    assert!(
        positive > points.len() / 4,
        "only {positive} rows with a finite positive bound"
    );
}

/// An evaluation scene with its reflector pieces (split to 1/128 of the diagonal) and tree.
fn scene_tree(
    name: &str,
) -> (
    interreflect::scene::Scene,
    Vec<interreflect::sg::ReflectorPiece>,
    interreflect::sg::tree::ReflectorTree,
) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"));
    let scene = interreflect::scene::Scene::load(&path).unwrap();
    let pieces = interreflect::sg::reflector_pieces(&scene, scene.mesh.diagonal() / 128.0);
    let tree = interreflect::sg::build_tree(&scene, &pieces);
    (scene, pieces, tree)
}

/// The tree lit by the scene's first light, without shadows.
fn unshadowed<'t>(
    scene: &interreflect::scene::Scene,
    pieces: &[interreflect::sg::ReflectorPiece],
    tree: &'t interreflect::sg::tree::ReflectorTree,
) -> interreflect::sg::LitScene<'t> {
    use interreflect::sg::{LitScene, light_anchor, light_triangles};
    let light = scene.lights[0];
    let all = |_: glam::Vec3, _: u32| 1.0;
    let tris = light_triangles(scene, pieces, &tree.tri_order, &light, &all);
    LitScene::new(
        tree,
        tris,
        light_anchor(scene, &light),
        interreflect::sg::transport::receiver::ReceiverOptions::default(),
    )
}

/// Receiver rows on the surfaces of `scene`: a random triangle, point (1e-4 above it) and view
/// each, skipping receivers that reflect nothing towards the view.
fn lit_rows(
    scene: &interreflect::scene::Scene,
    count: usize,
    seed: u64,
) -> Vec<(
    interreflect::render::gpu::twins::ReceiverRow,
    interreflect::sg::transport::receiver::ReceiverLobes,
)> {
    use interreflect::render::gpu::layout::GpuReceiver;
    use interreflect::render::gpu::twins::ReceiverRow;
    use interreflect::sg::transport::receiver::ReceiverLobes;
    let mut rng = Rng::keyed(seed, 0, 0);
    let triangles = scene.mesh.indices.len() as u32;
    let mut rows = Vec::new();
    while rows.len() < count {
        let t = ((rng.f32() * triangles as f32) as u32).min(triangles - 1);
        let (u, v) = (rng.f32(), rng.f32());
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        let [a, b, c] = scene.mesh.indices[t as usize].map(|i| scene.mesh.positions[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        if n == glam::Vec3::ZERO {
            continue;
        }
        let x = scene.mesh.point(t, u, v) + 1e-4 * n;
        let d = glam::Vec3::from(unit(&mut rng));
        let wo = if d.dot(n) < 0.0 { -d } else { d };
        let rx = ReceiverLobes::new(scene.tri_material(t), n, wo);
        if rx.is_black() {
            continue;
        }
        rows.push((
            ReceiverRow {
                x,
                receiver: GpuReceiver::new(&rx),
                across: rx.across(),
            },
            rx,
        ));
    }
    rows
}

/// The SG transport on the GPU against its Rust twins, over real reflectors and receivers of the
/// ring and bunny scenes (lit without shadows): `lit_triangle_shade` (`LitTriangle::shade`: the
/// lobes re-aimed at the receiver, integrated with the receiver's lobes over the triangle's
/// solid angle) and `lit_scene_cluster` (`LitScene::cluster`). Rows pair a random receiver
/// point with a random lit triangle and a random inner node, and then each receiver point a
/// 24 × 18 view sees with the leaves and inner nodes of its own cut, where the light is.
#[test]
fn transport_matches_its_rust_twins() {
    use glam::Vec3;
    use interreflect::render::gpu::layout::{GpuLeaf, GpuLitNode};
    use interreflect::render::gpu::twins::{run_cluster, run_leaf_shade};

    let Some(gpu) = common::gpu() else { return };
    for name in ["ring", "bunny"] {
        let (scene, pieces, tree) = scene_tree(name);
        let lit = unshadowed(&scene, &pieces, &tree);
        let lit_leaves: Vec<u32> = (0..lit.tris.len() as u32)
            .filter(|&i| lit.tris[i as usize].sg.is_some())
            .collect();
        let internal: Vec<u32> = (0..tree.nodes.len() as u32)
            .filter(|&i| {
                tree.nodes[i as usize].children.is_some() && lit.nodes[i as usize].weight > 0.0
            })
            .collect();
        let mut rows = lit_rows(&scene, 2000, 5);
        let mut rng = Rng::keyed(6, 0, 0);
        let pick = |rng: &mut Rng, list: &[u32]| {
            list[((rng.f32() * list.len() as f32) as usize).min(list.len() - 1)]
        };
        let mut leaves: Vec<u32> = rows.iter().map(|_| pick(&mut rng, &lit_leaves)).collect();
        let mut nodes: Vec<u32> = rows.iter().map(|_| pick(&mut rng, &internal)).collect();
        // And the pairs an image shades: the points a 24 × 18 view sees, each with the leaves and
        // inner nodes of its cut.
        let accel = interreflect::accel::Accel::build(&scene.mesh.positions, &scene.mesh.indices);
        let camera = scene.camera.with_resolution(24, 18);
        let mut scratch = Vec::new();
        for p in 0..24 * 18 {
            let dir = camera.ray_dir((p % 24) as f32 + 0.5, (p / 24) as f32 + 0.5);
            let Some(hit) = accel.intersect(camera.position, dir, 0.0, f32::INFINITY) else {
                continue;
            };
            let wo = -dir.normalize();
            let Some(sp) =
                interreflect::render::cpu::surface::SurfacePoint::from_hit(&scene, &hit, wo)
            else {
                continue;
            };
            let rx = interreflect::sg::transport::receiver::ReceiverLobes::new(
                scene.tri_material(hit.tri),
                sp.frame.n,
                wo,
            );
            if rx.is_black() || !scene.tri_object(hit.tri).receiver {
                continue;
            }
            let mut c = interreflect::sg::CutCounters::default();
            lit.select(
                sp.p,
                &rx,
                &interreflect::sg::CutOptions::default(),
                &mut scratch,
                &mut c,
            );
            let row = interreflect::render::gpu::twins::ReceiverRow {
                x: sp.p,
                receiver: interreflect::render::gpu::layout::GpuReceiver::new(&rx),
                across: rx.across(),
            };
            let cut_leaves: Vec<u32> = scratch
                .iter()
                .filter(|e| tree.nodes[e.node as usize].is_leaf())
                .map(|e| tree.nodes[e.node as usize].first)
                .collect();
            let cut_inner: Vec<u32> = scratch
                .iter()
                .filter(|e| !tree.nodes[e.node as usize].is_leaf())
                .map(|e| e.node)
                .collect();
            for k in 0..cut_leaves.len().max(cut_inner.len()).min(40) {
                if cut_leaves.is_empty() || cut_inner.is_empty() {
                    break;
                }
                rows.push((row, rx));
                leaves.push(cut_leaves[k % cut_leaves.len()]);
                nodes.push(cut_inner[k % cut_inner.len()]);
            }
        }
        let gpu_rows: Vec<_> = rows.iter().map(|r| r.0).collect();
        let got_leaf = run_leaf_shade(
            &gpu,
            &leaves
                .iter()
                .map(|&i| GpuLeaf::new(&lit.tris[i as usize]))
                .collect::<Vec<_>>(),
            &gpu_rows,
        )
        .unwrap();
        let got_cluster = run_cluster(
            &gpu,
            &nodes
                .iter()
                .map(|&i| GpuLitNode::new(&lit, i, u32::MAX, u32::MAX))
                .collect::<Vec<_>>(),
            lit.light_pos,
            &gpu_rows,
        )
        .unwrap();
        for (what, got, want) in [
            (
                "lit_triangle_shade",
                &got_leaf,
                rows.iter()
                    .zip(&leaves)
                    .map(|(r, &i)| lit.tris[i as usize].shade(r.0.x, &r.1, &lit.receiver))
                    .collect::<Vec<_>>(),
            ),
            (
                "lit_scene_cluster",
                &got_cluster,
                rows.iter()
                    .zip(&nodes)
                    .map(|(r, &i)| lit.cluster(i, r.0.x, &r.1))
                    .collect::<Vec<_>>(),
            ),
        ] {
            let scale = want.iter().map(|w| w.max_element()).fold(0.0f32, f32::max);
            let (mut worst, mut nonzero) = (0.0f32, 0usize);
            let (mut abs_sum, mut val_sum) = (0.0f64, 0.0f64);
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                for k in 0..3 {
                    let (g, w) = (g[k], w[k]);
                    assert!(g.is_finite() && g >= 0.0, "{name} {what} row {i}: GPU {g}");
                    let err = (g - w).abs();
                    nonzero += usize::from(w > 0.0);
                    worst = worst.max(err / scale);
                    abs_sum += f64::from(err);
                    val_sum += f64::from(w.abs());
                }
            }
            let summed = abs_sum / val_sum;
            eprintln!(
                "{name} {what}: {} rows, {nonzero} nonzero channels; summed difference / summed value {summed:.2e}, largest difference / largest value {worst:.2e}",
                rows.len()
            );
            // Not vacuous: thousands of channels carry light.
            assert!(nonzero > 1000, "{name} {what}: {nonzero} nonzero channels");
            // f32 against a Rust twin that computes the SG integral and the lobe products in
            // f64: the WGSL integral is off by up to 1.5e-4 of the lobe's integral (the
            // integrate_sg twin above), and near the receiver's horizon the cosine's central
            // difference subtracts two such integrals. A tiny value can therefore be far off
            // relatively, but the error is small against the light that matters: measured at
            // most 6.3e-5 of the summed value and 2.5e-5 of the largest value (ring and bunny,
            // leaves and clusters); allowed 1e-3 and 5e-4.
            assert!(summed < 1e-3, "{name} {what}: summed difference {summed}");
            assert!(
                worst < 5e-4,
                "{name} {what}: largest difference {worst} of the largest value"
            );
            // And the comparison can fail: against the Rust values of the next row, the
            // summed difference is far above its tolerance.
            let shifted: f64 = got
                .iter()
                .zip(want.iter().cycle().skip(1))
                .map(|(g, w)| f64::from((Vec3::new(g[0], g[1], g[2]) - *w).abs().element_sum()))
                .sum();
            assert!(
                shifted / val_sum > 1e-2,
                "{name} {what}: shifted rows compare too well ({})",
                shifted / val_sum
            );
        }
    }
}
