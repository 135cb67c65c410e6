//! Diagnostics of the SG renderer, as ignored tests: the pixel probe (the transport of every
//! reflector piece at one pixel against its exact integral) and the cut probe (sg against
//! sg-brute, split into the nodes' approximation and their visibility). See
//! `docs/sg-renderer.md`. Also the tests of the shadow-ray helpers that need the same setup.

use super::*;
use crate::sg::transport::brute_force::{Config, one_bounce_exact_shaded};

/// What both probes set up: the scene's reflector pieces and tree at `w` pixels wide, with
/// exact visibility, for its first light.
struct Setup {
    scene: Scene,
    accel: Accel,
    eps: f32,
    opts: SgOptions,
    pieces: Vec<ReflectorPiece>,
    tree: ReflectorTree,
}

impl Setup {
    fn new(scene: Scene, w: u32, brute: bool, cut: CutOptions) -> Setup {
        let accel = Accel::build(&scene.mesh.positions, &scene.mesh.indices);
        let eps = ray_epsilon(&scene);
        let h = (w as f32 * scene.camera.height as f32 / scene.camera.width as f32).round() as u32;
        let opts = SgOptions {
            width: w,
            height: h,
            spp: 1,
            seed: 0,
            direct: false,
            indirect: true,
            brute,
            cut,
            mode: CutMode::Pixel,
            max_edge: scene.mesh.diagonal() / 128.0,
            visibility: crate::render::Visibility::Exact,
            device: crate::render::Device::Cpu,
        };
        let pieces = reflector_pieces(&scene, opts.max_edge);
        let tree = build_tree(&scene, &pieces);
        Setup {
            scene,
            accel,
            eps,
            opts,
            pieces,
            tree,
        }
    }

    /// The first light's lit reflector pieces.
    fn lit(&self) -> LitScene<'_> {
        let s = &self.scene;
        light_scene(
            s,
            &self.accel,
            &self.pieces,
            &self.tree,
            &s.lights[0],
            None,
            self.eps,
            ReceiverOptions::default(),
        )
    }

    fn ctx<'a>(&'a self, lits: &'a [LitScene<'a>]) -> Ctx<'a> {
        Ctx {
            scene: &self.scene,
            accel: &self.accel,
            eps: self.eps,
            lits,
            maps: &[],
            vpl_vis: &[],
            leaf_of: Vec::new(),
            opts: &self.opts,
            brute: self.opts.brute,
            camera_pos: self
                .scene
                .camera
                .with_resolution(self.opts.width, self.opts.height)
                .position,
        }
    }
}

/// Diagnostic for the transport at one pixel: at the centre of pixel (PROBE_X, PROBE_Y) of
/// the scene PROBE_SCENE rendered 64 px wide (first light, a point light), every lit
/// reflector piece's SG transport (what `sg-brute` sums) against its exact integral with
/// the same visibility factor, with shading normals and with flat triangles, summed per
/// object, and the pieces that differ most. Slow (an adaptive integral per piece). Run with
/// `PROBE_SCENE=scenes/dragon.toml PROBE_X=27 PROBE_Y=29 cargo test --release --lib
/// pixel_probe -- --ignored --nocapture`.
#[test]
#[ignore]
fn pixel_probe() {
    let var = |k: &str| std::env::var(k).unwrap_or_else(|_| panic!("set {k}"));
    let scene = Scene::load(std::path::Path::new(&var("PROBE_SCENE"))).expect("scene");
    let px: f32 = var("PROBE_X").parse().expect("PROBE_X");
    let py: f32 = var("PROBE_Y").parse().expect("PROBE_Y");
    let w = 64;
    let su = Setup::new(scene, w, true, CutOptions::default());
    let (scene, accel, eps, pieces, tree) = (&su.scene, &su.accel, su.eps, &su.pieces, &su.tree);
    let light = &scene.lights[0];
    let Light::Point {
        position,
        intensity,
    } = *light
    else {
        panic!("the probe handles point lights");
    };
    let lits = [su.lit()];
    let ctx = su.ctx(&lits);
    let h = su.opts.height;
    let camera = scene.camera.with_resolution(w, h);
    let hit = accel
        .intersect(
            camera.position,
            camera.ray_dir(px + 0.5, py + 0.5),
            0.0,
            f32::INFINITY,
        )
        .expect("the pixel sees the scene");
    let lit = &lits[0];
    let wo = (camera.position - scene.mesh.point(hit.tri, hit.u, hit.v)).normalize();
    let sp = SurfacePoint::from_hit(scene, &hit, wo).expect("a surface point");
    let brdf = scene.tri_material(hit.tri);
    let rx = ReceiverLobes::new(brdf, sp.frame.n, wo);
    let xo = sp.offset(eps);
    println!(
        "receiver: {} {:?}, cos θo {:.3}",
        scene.tri_object(hit.tri).name,
        brdf,
        wo.dot(sp.frame.n)
    );
    let lum = |v: DVec3| (v.x + v.y + v.z) / 3.0;
    // (piece, sg, exact shaded, sg flat, exact flat), each times the visibility factor.
    let rows: Vec<(usize, [f64; 4])> = lit
        .tris
        .par_iter()
        .enumerate()
        .filter(|(_, t)| t.sg.is_some())
        .filter_map(|(i, t)| {
            let (f, _) = ctx.triangle_visibility(xo, t, 0, &rx);
            if !(f > 0.0) {
                return None;
            }
            let f = f64::from(f);
            let lv = f64::from(t.light_visibility);
            let c = Config {
                tri: t.vertices,
                brdf_y: *scene.tri_material(t.tri),
                light: position,
                intensity,
                x: sp.p,
                n_x: sp.frame.n,
                wo,
                brdf_x: *brdf,
            };
            let normals = pieces[tree.tri_order[i] as usize].normals;
            let exact = |n| lum(one_bounce_exact_shaded(&c, n, 1e-3, 10)) * lv * f;
            let refl = crate::sg::transport::Reflector {
                vertices: t.vertices,
                brdf: c.brdf_y,
            };
            let flat = crate::sg::transport::reflector::reflected_sg_light(
                &refl,
                light,
                t.light_visibility,
                1.0,
            )
            .map(|s| {
                let s = crate::sg::transport::aim_at_receiver(&s, sp.p);
                let v = crate::sg::transport::receiver::one_bounce_with(
                    &s,
                    t.vertices,
                    sp.p,
                    &rx,
                    &lit.receiver,
                );
                lum(v.as_dvec3()) * f
            })
            .unwrap_or(0.0);
            let sg = lum(t.shade(sp.p, &rx, &lit.receiver).as_dvec3()) * f;
            Some((i, [sg, exact(Some(normals)), flat, exact(None)]))
        })
        .collect();
    let mut by_obj = std::collections::BTreeMap::<String, [f64; 4]>::new();
    for (i, v) in &rows {
        let e = by_obj
            .entry(scene.tri_object(lit.tris[*i].tri).name.clone())
            .or_default();
        for k in 0..4 {
            e[k] += v[k];
        }
    }
    let total = rows.iter().fold([0.0; 4], |mut a, (_, v)| {
        for k in 0..4 {
            a[k] += v[k];
        }
        a
    });
    by_obj.insert("(all)".into(), total);
    println!("from          sg (shaded)   exact (shaded)   sg (flat)   exact (flat)");
    for (o, v) in &by_obj {
        println!(
            "{o:12} {:12.5} {:16.5} {:11.5} {:14.5}",
            v[0], v[1], v[2], v[3]
        );
    }
    let mut rows = rows;
    rows.sort_by(|a, b| (b.1[0] - b.1[1]).abs().total_cmp(&(a.1[0] - a.1[1]).abs()));
    for (i, v) in rows.iter().take(10) {
        let t = &lit.tris[*i];
        let d = ((t.vertices[0] + t.vertices[1] + t.vertices[2]) / 3.0 - sp.p).length();
        println!(
            "  piece {i} ({}, {d:.3} away): sg {:.5} exact {:.5} | flat: sg {:.5} exact {:.5}",
            scene.tri_object(t.tri).name,
            v[0],
            v[1],
            v[2],
            v[3]
        );
    }
}

/// Diagnostic for the cut: at the centre of every pixel of PROBE_SCENE rendered PROBE_W px
/// wide, splits sg's difference from sg-brute into the cut's approximation (no visibility on
/// either side) and the visibility of non-leaf nodes (one ray to the representative against
/// the per-triangle visibility of sg-brute). Prints rel_rmse (rmse / mean, luminance) of
/// each. Run with `PROBE_SCENE=scenes/dragon.toml PROBE_W=32 cargo test --release --lib
/// cut_probe -- --ignored --nocapture`.
#[test]
#[ignore]
fn cut_probe() {
    let var = |k: &str| std::env::var(k).unwrap_or_else(|_| panic!("set {k}"));
    let scene = Scene::load(std::path::Path::new(&var("PROBE_SCENE"))).expect("scene");
    let w: u32 = var("PROBE_W").parse().expect("PROBE_W");
    let max_cut: u32 = std::env::var("PROBE_CAP")
        .ok()
        .map_or(1000, |s| s.parse().expect("PROBE_CAP"));
    let detail = std::env::var("PROBE_X").ok().map(|x| {
        (
            x.parse::<u32>().expect("PROBE_X"),
            var("PROBE_Y").parse::<u32>().expect("PROBE_Y"),
        )
    });
    let cut = CutOptions {
        max_cut,
        ..CutOptions::default()
    };
    let su = Setup::new(scene, w, false, cut);
    let (scene, accel, eps, opts) = (&su.scene, &su.accel, su.eps, &su.opts);
    let h = opts.height;
    let lits = [su.lit()];
    let lit = &lits[0];
    let camera = scene.camera.with_resolution(w, h);
    let ctx = su.ctx(&lits);
    let lum = |v: Vec3| f64::from(v.x + v.y + v.z) / 3.0;
    // Per pixel: [brute no vis, cut no vis, brute vis, cut vis, cut with ideal node vis].
    // Σ |value − leaves| and Σ (value − leaves) (no visibility) of internal cut nodes, and
    // their number, by receiver object, node object and size.
    let groups = std::sync::Mutex::new(std::collections::BTreeMap::<String, [f64; 3]>::new());
    let rows: Vec<[f64; 5]> = (0..w * h)
        .into_par_iter()
        .filter(|p| detail.is_none_or(|d| d == (p % w, p / w)))
        .map(|p| {
            let (px, py) = (p % w, p / w);
            let Some(hit) = accel.intersect(
                camera.position,
                camera.ray_dir(px as f32 + 0.5, py as f32 + 0.5),
                0.0,
                f32::INFINITY,
            ) else {
                return [0.0; 5];
            };
            if !scene.tri_object(hit.tri).receiver {
                return [0.0; 5];
            }
            let wo = (camera.position - scene.mesh.point(hit.tri, hit.u, hit.v)).normalize();
            let Some(sp) = SurfacePoint::from_hit(scene, &hit, wo) else {
                return [0.0; 5];
            };
            let rx = ReceiverLobes::new(scene.tri_material(hit.tri), sp.frame.n, wo);
            if rx.is_black() {
                return [0.0; 5];
            }
            let xo = sp.offset(eps);
            // Per leaf: (value, visible value).
            let leaf: Vec<(Vec3, Vec3)> = lit
                .tris
                .iter()
                .map(|t| {
                    if t.sg.is_none() {
                        return (Vec3::ZERO, Vec3::ZERO);
                    }
                    let v = t.shade(sp.p, &rx, &lit.receiver);
                    if v == Vec3::ZERO {
                        return (v, v);
                    }
                    let (f, _) = ctx.triangle_visibility(xo, t, 0, &rx);
                    (v, v * f)
                })
                .collect();
            let b0 = leaf.iter().fold(Vec3::ZERO, |a, l| a + l.0);
            let b1 = leaf.iter().fold(Vec3::ZERO, |a, l| a + l.1);
            let mut cut = Vec::new();
            let mut c = CutCounters::default();
            let c0 = lit.select(sp.p, &rx, &opts.cut, &mut cut, &mut c);
            let (mut c1, mut c2) = (Vec3::ZERO, Vec3::ZERO);
            if detail == Some((px, py)) {
                let mut d: Vec<(f64, String)> = cut
                    .iter()
                    .map(|e| {
                        let n = &lit.tree.nodes[e.node as usize];
                        let (s, k) = (n.first as usize, n.count as usize);
                        let v = lum(leaf[s..s + k].iter().fold(Vec3::ZERO, |a, l| a + l.1));
                        let vis = n.is_leaf() || ctx.visible(xo, ctx.rep_point(lit, e.node));
                        let value = if n.is_leaf() {
                            v
                        } else if vis {
                            lum(e.value)
                        } else {
                            0.0
                        };
                        let t = &lit.tris[lit.nodes[e.node as usize].rep as usize];
                        let dist = (n.bbox_min + n.bbox_max - 2.0 * sp.p).length() * 0.5;
                        let diag = (n.bbox_max - n.bbox_min).length();
                        (
                            value - v,
                            format!(
                                "node {} count {k} {} dist {dist:.3} diag {diag:.3}: \
                                 value {:.5} exact {v:.5} bound {:.5}",
                                e.node,
                                scene.tri_object(t.tri).name,
                                lum(e.value),
                                lum(e.bound)
                            ),
                        )
                    })
                    .collect();
                let total: f64 = d.iter().map(|x| x.0).sum();
                let pos: f64 = d.iter().map(|x| x.0.max(0.0)).sum();
                let bsum: f64 = cut.iter().map(|e| lum(e.bound)).sum();
                println!(
                    "pixel ({px},{py}) cut {} leaves {}: Σ diff {total:.5} (+{pos:.5}), Σ bound {bsum:.4}",
                    cut.len(),
                    cut.iter()
                        .filter(|e| lit.tree.nodes[e.node as usize].is_leaf())
                        .count()
                );
                let mut groups = std::collections::BTreeMap::<String, [f64; 4]>::new();
                for e in &cut {
                    let n = &lit.tree.nodes[e.node as usize];
                    let (s, k) = (n.first as usize, n.count as usize);
                    let v = lum(leaf[s..s + k].iter().fold(Vec3::ZERO, |a, l| a + l.0));
                    let t = &lit.tris[lit.nodes[e.node as usize].rep as usize];
                    let b = lum(e.bound);
                    let key = format!(
                        "{} {}",
                        scene.tri_object(t.tri).name,
                        if v < 0.01 * b { "tight<1%" } else if v < 0.1 * b { "1-10%" } else { ">10%" }
                    );
                    let g = groups.entry(key).or_default();
                    g[0] += 1.0;
                    g[1] += b;
                    g[2] += v;
                    g[3] += (lum(e.value) - v).abs();
                }
                let mut tight: Vec<_> = cut
                    .iter()
                    .filter(|e| {
                        let n = &lit.tree.nodes[e.node as usize];
                        let (s, k) = (n.first as usize, n.count as usize);
                        let v = lum(leaf[s..s + k].iter().fold(Vec3::ZERO, |a, l| a + l.0));
                        v < 0.01 * lum(e.bound)
                    })
                    .collect();
                tight.sort_by(|a, b| lum(b.bound).total_cmp(&lum(a.bound)));
                let mut hist = [0usize; 24];
                for e in &tight {
                    let k = lit.tree.nodes[e.node as usize].count;
                    hist[(k as f32).log2() as usize] += 1;
                }
                println!("  tight nodes by log2(count): {hist:?}");
                // The bound with the node's triangles binned by lit normal (cube-map cells of
                // r × r per face; r = 0: one bin per triangle), summed over the bins.
                let cube_bin = |n: Vec3, r: usize| {
                    let a = n.abs();
                    let (f, u, v, m) = if a.x >= a.y && a.x >= a.z {
                        (usize::from(n.x < 0.0), n.y, n.z, a.x)
                    } else if a.y >= a.z {
                        (2 + usize::from(n.y < 0.0), n.x, n.z, a.y)
                    } else {
                        (4 + usize::from(n.z < 0.0), n.x, n.y, a.z)
                    };
                    let cell = |t: f32| (((t / m.max(1e-20) + 1.0) * 0.5 * r as f32) as usize).min(r - 1);
                    (f * r + cell(u)) * r + cell(v)
                };
                // Per triangle with its own box and normal (the tightest bound of this form);
                // the same with each lobe's term capped by its integral over the sphere (hmax μ
                // 2π/λ, λ the lobe's smallest sharpness); and the receiver's cosine bounded over
                // the cone to the node's (or the triangle's) bounding sphere, cos(max(0,
                // angle(n_x, dir) − half)), which the bound takes as 1, with how often the
                // leaves' computed sum exceeds it.
                {
                    let rx_cos = |lo: Vec3, hi: Vec3| {
                        let to_c = 0.5 * (lo + hi) - sp.p;
                        let (dist, radius) = (to_c.length(), 0.5 * (hi - lo).length());
                        if dist > radius {
                            let g = crate::sg::tree::angle_between(sp.frame.n, to_c / dist)
                                - (radius / dist).asin();
                            f64::from(g.max(0.0).cos())
                        } else {
                            1.0
                        }
                    };
                    // Σ own-box bound, capped, times the cosine; Σ node bound times the
                    // cosine; Σ exact; nodes over the cosine bound.
                    let (mut s1, mut s2, mut st, mut sb, mut se, mut over) =
                        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize);
                    for e in cut.iter() {
                        let n = &lit.tree.nodes[e.node as usize];
                        if n.is_leaf() {
                            continue;
                        }
                        let (s0, k) = (n.first as usize, n.count as usize);
                        let b = lum(e.bound) * rx_cos(n.bbox_min, n.bbox_max);
                        let v = lum(leaf[s0..s0 + k].iter().fold(Vec3::ZERO, |a, l| a + l.0));
                        sb += b;
                        se += v;
                        if v > b {
                            over += 1;
                        }
                        for (pos, lv) in leaf.iter().enumerate().skip(s0).take(k) {
                            let t = &lit.tris[pos];
                            let Some(sg) = &t.sg else { continue };
                            let ln = crate::sg::LitNode::from_triangle(t, pos as u32);
                            if !(ln.weight > 0.0) {
                                continue;
                            }
                            let [va, vb, vc] = t.vertices;
                            let tn = crate::sg::tree::Node {
                                bbox_min: va.min(vb).min(vc),
                                bbox_max: va.max(vb).max(vc),
                                cone: Some(crate::sg::tree::NormalCone {
                                    axis: sg.normal,
                                    half_angle: 0.0,
                                }),
                                ..*n
                            };
                            let bt = lum(crate::sg::node_bound(&tn, &ln, sp.p, &rx));
                            s1 += bt;
                            // Each lobe's term alone (its bin, its falloff), then capped by
                            // the lobe's integral over the sphere, μ f hmax 2π/λ, taking
                            // cos_max = 1 (an estimate of what such a cap could reach).
                            let d2 = f64::from((sp.p.clamp(tn.bbox_min, tn.bbox_max) - sp.p).length_squared());
                            let widest = if sg.half_vector { sg.light_cosine().clamp(0.0, 1.0) } else { 1.0 };
                            let mut l0 = ln;
                            l0.peak_by_sharpness = [Vec3::ZERO; 6];
                            let mut b2 = lum(crate::sg::node_bound(&tn, &l0, sp.p, &rx));
                            for l in sg.lobes() {
                                let lam = l.sharpness.max(0.0) * widest;
                                let bin = crate::sg::SHARPNESS_BINS.iter().rposition(|&e| lam >= e).unwrap_or(0);
                                let mut lk = l0;
                                lk.diffuse = Vec3::ZERO;
                                lk.peak_by_sharpness[bin] = l.amplitude * ln.area;
                                let bk = lum(crate::sg::node_bound(&tn, &lk, sp.p, &rx));
                                let cap = bk / f64::from(ln.area).max(1e-30) * d2 * std::f64::consts::TAU / f64::from(lam).max(1e-6);
                                b2 += bk.min(cap);
                            }
                            s2 += b2;
                            let ct = rx_cos(tn.bbox_min, tn.bbox_max);
                            st += bt * ct;
                            // A triangle whose computed value exceeds its own bound times the
                            // largest receiver cosine over its directions: the transport's
                            // cosine factor is above every cosine the triangle subtends.
                            let vt = lum(lv.0);
                            if v > b && vt > bt * ct {
                                println!(
                                    "    node {} triangle {pos}: value {vt:.3e}, own bound {bt:.3e} (value / bound {:.3}), largest cosine over it {ct:.4}",
                                    e.node,
                                    vt / bt.max(1e-30)
                                );
                            }
                        }
                    }
                    println!(
                        "  per triangle, own box: Σ bound {s1:.4}, capped by 2π/λ {s2:.4}, Σ exact {se:.4}: ratios {:.1}, {:.1}",
                        s1 / se.max(1e-30),
                        s2 / se.max(1e-30)
                    );
                    println!(
                        "  with the receiver's cosine: inner nodes' Σ bound {sb:.4} (per triangle {st:.4}), Σ exact {se:.4}: ratios {:.1}, {:.1}; nodes whose leaves' sum exceeds it: {over}",
                        sb / se.max(1e-30),
                        st / se.max(1e-30)
                    );
                }
                for r in [1usize, 2, 4, 0] {
                    let (mut sb, mut se, mut tight_k) = (0.0f64, 0.0f64, 0usize);
                    for e in cut.iter() {
                        let n = &lit.tree.nodes[e.node as usize];
                        if n.is_leaf() {
                            continue;
                        }
                        let (s0, k) = (n.first as usize, n.count as usize);
                        let mut bins = std::collections::BTreeMap::<usize, crate::sg::LitNode>::new();
                        for pos in s0..s0 + k {
                            let t = &lit.tris[pos];
                            let Some(sg) = &t.sg else { continue };
                            let key = if r == 0 { pos } else { cube_bin(sg.normal, r) };
                            let ln = crate::sg::LitNode::from_triangle(t, pos as u32);
                            let m = bins
                                .remove(&key)
                                .map_or(ln, |b| crate::sg::LitNode::merge(&b, &ln));
                            bins.insert(key, m);
                        }
                        let b: f64 = bins
                            .values()
                            .filter(|l| l.weight > 0.0)
                            .map(|l| lum(crate::sg::node_bound(n, l, sp.p, &rx).min(e.bound)))
                            .sum();
                        let v = lum(leaf[s0..s0 + k].iter().fold(Vec3::ZERO, |a, l| a + l.0));
                        sb += b;
                        se += v;
                        if v < 0.01 * b {
                            tight_k += 1;
                        }
                    }
                    println!(
                        "  binned r={r}: inner nodes' Σ bound {sb:.4} Σ exact {se:.4} ratio {:.1}, nodes exact < 1% of bound: {tight_k}",
                        sb / se.max(1e-30)
                    );
                }
                for e in tight.iter().take(8) {
                    let n = &lit.tree.nodes[e.node as usize];
                    println!(
                        "  tight node {} count {} cone {:?}: bound {:.4} parts {:?}",
                        e.node,
                        n.count,
                        n.cone.map(|c| c.half_angle),
                        lum(e.bound),
                        lit.bound_parts(e.node, sp.p, &rx)
                    );
                }
                for (k, g) in &groups {
                    println!("  group {k:20} nodes {:5} Σ bound {:.4} Σ exact {:.4} Σ|err| {:.4}", g[0], g[1], g[2], g[3]);
                }
                d.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
                for x in d.iter().take(15) {
                    println!("  {:+.5} {}", x.0, x.1);
                }
            }
            for e in &cut {
                let n = &lit.tree.nodes[e.node as usize];
                let (s, k) = (n.first as usize, n.count as usize);
                let (v, vv) = leaf[s..s + k]
                    .iter()
                    .fold((Vec3::ZERO, Vec3::ZERO), |a, l| (a.0 + l.0, a.1 + l.1));
                if n.is_leaf() {
                    c1 += vv;
                    c2 += vv;
                    continue;
                }
                c1 += e.value * ctx.node_visibility(xo, lit, e.node).0;
                let lv = lum(v);
                if lv > 0.0 {
                    c2 += e.value * (lum(vv) / lv) as f32;
                }
            }
            {
                let mut g = groups.lock().expect("not poisoned");
                let rx_name = &scene.tri_object(hit.tri).name;
                for e in &cut {
                    let n = &lit.tree.nodes[e.node as usize];
                    if n.is_leaf() {
                        continue;
                    }
                    let (s, k) = (n.first as usize, n.count as usize);
                    let v = lum(leaf[s..s + k].iter().fold(Vec3::ZERO, |a, l| a + l.0));
                    let t = &lit.tris[lit.nodes[e.node as usize].rep as usize];
                    let key = format!(
                        "{rx_name:>6} <- {:6} count ~2^{:2}",
                        scene.tri_object(t.tri).name,
                        (k as f32).log2().round() as u32
                    );
                    let d = lum(e.value) - v;
                    let x = g.entry(key).or_default();
                    x[0] += d.abs();
                    x[1] += d;
                    x[2] += 1.0;
                }
            }
            [lum(b0), lum(c0), lum(b1), lum(c1), lum(c2)]
        })
        .collect();
    let rel = |a: usize, b: usize| {
        let mean = rows.iter().map(|r| r[b]).sum::<f64>() / rows.len() as f64;
        let mse = rows.iter().map(|r| (r[a] - r[b]).powi(2)).sum::<f64>() / rows.len() as f64;
        mse.sqrt() / mean
    };
    println!("pixels {}, cap {max_cut}", rows.len());
    println!("cut vs brute, no visibility:        {:.4}", rel(1, 0));
    println!("cut vs brute, with visibility:      {:.4}", rel(3, 2));
    println!("cut (ideal node vis) vs brute vis:  {:.4}", rel(4, 2));
    println!("brute vis vs brute no vis:          {:.4}", rel(2, 0));
    let mean = |k: usize| rows.iter().map(|r| r[k]).sum::<f64>() / rows.len() as f64;
    println!("means: {:?}", (0..5).map(mean).collect::<Vec<_>>());
    let groups = groups.into_inner().expect("not poisoned");
    let total: f64 = groups.values().map(|g| g[0]).sum();
    let mut by_err: Vec<_> = groups.iter().collect();
    by_err.sort_by(|a, b| b.1[0].total_cmp(&a.1[0]));
    println!("internal cut nodes by |error| share (no visibility):");
    for (k, g) in by_err.iter().take(20) {
        println!(
            "  {k}: {:5.1} % of Σ|err|, bias {:+.4}, nodes {}",
            100.0 * g[0] / total,
            g[1] / g[0].max(1e-30),
            g[2]
        );
    }
    if detail.is_some() {
        return;
    }
    let mut idx: Vec<usize> = (0..rows.len()).collect();
    idx.sort_by(|&a, &b| {
        (rows[b][3] - rows[b][2])
            .abs()
            .total_cmp(&(rows[a][3] - rows[a][2]).abs())
    });
    for &i in idx.iter().take(12) {
        println!(
            "  pixel ({}, {}): brute {:.4} cut {:.4} (with vis: {:.4} {:.4})",
            i as u32 % w,
            i as u32 / w,
            rows[i][0],
            rows[i][1],
            rows[i][2],
            rows[i][3]
        );
    }
}

/// Diagnostic for fireflies: every sample of pixel (PROBE_X, PROBE_Y) of PROBE_SCENE rendered
/// PROBE_W px wide at PROBE_SPP samples (as `render --method sg --indirect-only` does), with its
/// value, and for the brightest sample the cut entries that carry most of it. Run with
/// `PROBE_SCENE=scenes/bunny.toml PROBE_W=64 PROBE_SPP=64 PROBE_X=21 PROBE_Y=22 cargo test
/// --release --lib firefly_probe -- --ignored --nocapture`.
#[test]
#[ignore]
fn firefly_probe() {
    let var = |k: &str| std::env::var(k).unwrap_or_else(|_| panic!("set {k}"));
    let scene = Scene::load(std::path::Path::new(&var("PROBE_SCENE"))).expect("scene");
    let w: u32 = var("PROBE_W").parse().expect("PROBE_W");
    let spp: u32 = var("PROBE_SPP").parse().expect("PROBE_SPP");
    let px: u32 = var("PROBE_X").parse().expect("PROBE_X");
    let py: u32 = var("PROBE_Y").parse().expect("PROBE_Y");
    let su = Setup::new(scene, w, false, CutOptions::default());
    let lits = [su.lit()];
    let ctx = su.ctx(&lits);
    let scene = &su.scene;
    let camera = scene.camera.with_resolution(w, su.opts.height);
    let tally = Tally::default();
    let mut scratch = Vec::new();
    let pixel = (py * w + px) as u64;
    let mut best = (0.0f32, None);
    for s in 0..spp {
        let o = sample_offset(spp, s, 0, pixel);
        let hit = su.accel.intersect(
            camera.position,
            camera.ray_dir(px as f32 + o.x, py as f32 + o.y),
            0.0,
            f32::INFINITY,
        );
        let v = ctx.shade(hit.as_ref(), None, None, None, &mut scratch, &tally);
        let obj = hit.map(|h| scene.tri_object(h.tri).name.clone());
        println!("sample {s:3} at ({:.3}, {:.3}): {obj:?} {v}", o.x, o.y);
        if v.element_sum() > best.0 {
            best = (v.element_sum(), hit);
        }
    }
    let Some(hit) = best.1 else { return };
    // The brightest sample's cut, its largest entries.
    let wo = (camera.position - scene.mesh.point(hit.tri, hit.u, hit.v)).normalize();
    let sp = SurfacePoint::from_hit(scene, &hit, wo).expect("a surface point");
    let rx = ReceiverLobes::new(scene.tri_material(hit.tri), sp.frame.n, wo);
    let mut c = CutCounters::default();
    lits[0].select(sp.p, &rx, &su.opts.cut, &mut scratch, &mut c);
    scratch.sort_by(|a, b| b.value.element_sum().total_cmp(&a.value.element_sum()));
    let total: f32 = scratch.iter().map(|e| e.value.element_sum()).sum();
    println!(
        "brightest sample at {}: cut of {} nodes, unshadowed sum {total}",
        sp.p,
        scratch.len()
    );
    for e in scratch.iter().take(8) {
        let n = &lits[0].tree.nodes[e.node as usize];
        let first = su.pieces[lits[0].tree.tri_order[n.first as usize] as usize].tri;
        println!(
            "  node {} ({} pieces, object {}, centroid {}, distance {:.4}): {}",
            e.node,
            n.count,
            scene.tri_object(first).name,
            n.centroid,
            (n.centroid - sp.p).length(),
            e.value
        );
    }
}

/// The targets that tile cuts share between a group's samples (`Ctx::node_targets`) are the
/// points the node's visibility traces, numbered alike: with every target's result known from
/// the receiver's own rays, the shared visibility equals the traced one exactly, and it traces
/// no ray for an inner node and only the lobe point's (and its light ray) for a leaf. On the
/// bunny, where the bunny blocks part of the floor's view of itself, so that a mismatch in
/// the numbering would show.
#[test]
fn shared_targets_are_the_points_the_visibility_traces() {
    let scene = Scene::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/bunny.toml"
    )))
    .expect("the bunny scene loads");
    let w = 24;
    let su = Setup::new(scene, w, false, CutOptions::default());
    let lits = [su.lit()];
    let ctx = su.ctx(&lits);
    let lit = &lits[0];
    let camera = su.scene.camera.with_resolution(w, su.opts.height);
    let (mut checked, mut blocked, mut seen) = (0, 0, 0);
    for py in (0..su.opts.height).step_by(3) {
        for px in (0..w).step_by(3) {
            let dir = camera.ray_dir(px as f32 + 0.5, py as f32 + 0.5);
            let Some(hit) = su.accel.intersect(camera.position, dir, 0.0, f32::INFINITY) else {
                continue;
            };
            let wo = (camera.position - su.scene.mesh.point(hit.tri, hit.u, hit.v)).normalize();
            let Some(sp) = SurfacePoint::from_hit(&su.scene, &hit, wo) else {
                continue;
            };
            let rx = ReceiverLobes::new(su.scene.tri_material(hit.tri), sp.frame.n, wo);
            let xo = sp.offset(su.eps);
            for node in (0..lit.tree.nodes.len() as u32).step_by(37) {
                let mut shared = SharedRays::NONE;
                for (k, p) in ctx.node_targets(lit, node).into_iter().enumerate() {
                    if let Some(p) = p {
                        let v = ctx.ray_visible(xo, p);
                        shared.known |= 1 << k;
                        shared.visible |= u8::from(v) << k;
                        if v { seen += 1 } else { blocked += 1 }
                    }
                }
                let tn = &lit.tree.nodes[node as usize];
                let (own, shared_f, shared_rays, most) = if tn.is_leaf() {
                    let t = &lit.tris[tn.first as usize];
                    let (own, _) = ctx.triangle_visibility(xo, t, 0, &rx);
                    let (f, r) = ctx.triangle_visibility_shared(xo, t, 0, &rx, shared);
                    (own, f, r, 2)
                } else {
                    let (own, _) = ctx.node_visibility(xo, lit, node);
                    let (f, r) = ctx.node_visibility_shared(xo, lit, node, shared);
                    (own, f, r, 0)
                };
                assert_eq!(
                    own.to_bits(),
                    shared_f.to_bits(),
                    "node {node} at pixel ({px}, {py})"
                );
                assert!(
                    shared_rays <= most,
                    "node {node}: {shared_rays} rays with every target shared"
                );
                checked += 1;
            }
        }
    }
    assert!(
        checked > 1000,
        "only {checked} (receiver, node) pairs checked"
    );
    assert!(
        blocked > 0 && seen > 0,
        "targets blocked {blocked}, seen {seen}: the scene must have both"
    );
}
