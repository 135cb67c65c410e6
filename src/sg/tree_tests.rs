use super::*;
use crate::math::Rng;
use proptest::prelude::*;
use std::path::Path;

/// Relative tolerance for recomputed sums and means: f32 accumulation over a few hundred terms
/// in a different order than the tree's pairwise combination.
const REL: f32 = 1e-5;
/// Absolute slack (radians) for the cone containment test: the cone is the exact maximum of the
/// same `angle_between` values, so only the rounding of the normalisation differs.
const ANGLE_TOL: f32 = 1e-5;

fn tri(v: [Vec3; 3], albedo: Vec3, material: u32, id: u32) -> TriInput {
    TriInput {
        v,
        normal: (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero(),
        albedo,
        material,
        tri: id,
    }
}

fn close(a: Vec3, b: Vec3, scale: f32) -> bool {
    (a - b).abs().max_element() <= REL * scale.max(1e-30) + 1e-30
}

/// Checks every structural and bound invariant of `tree` against its input `tris`.
fn check_tree(tree: &ReflectorTree, tris: &[TriInput]) {
    let n = tris.len();
    if n == 0 {
        assert!(tree.is_empty());
        assert!(tree.tri_order.is_empty());
        return;
    }
    assert_eq!(tree.nodes.len(), 2 * n - 1);
    assert_eq!(tree.tri_order.len(), n);
    // The leaves are the input triangles, each once (ids are unique in every test input).
    let by_id: std::collections::HashMap<u32, &TriInput> =
        tris.iter().map(|t| (t.tri, t)).collect();
    assert_eq!(by_id.len(), n, "test inputs have unique ids");
    let mut seen = tree.tri_order.clone();
    seen.sort_unstable();
    let mut want: Vec<u32> = tris.iter().map(|t| t.tri).collect();
    want.sort_unstable();
    assert_eq!(seen, want, "tri_order is a permutation of the input");

    let root = tree.root().unwrap();
    assert_eq!((root.first, root.count), (0, n as u32));
    let mut leaves = 0;
    let mut reached = vec![false; tree.nodes.len()];
    reached[0] = true;
    for (i, node) in tree.nodes.iter().enumerate() {
        assert!(reached[i], "node {i} is not reachable from the root");
        let under: Vec<&TriInput> = tree
            .leaves_under(i as u32)
            .iter()
            .map(|id| by_id[id])
            .collect();
        assert_eq!(under.len(), node.count as usize);
        // Bounds contain every vertex, colour range every albedo, cone every normal.
        for t in &under {
            for p in t.v {
                assert!(p.cmpge(node.bbox_min).all() && p.cmple(node.bbox_max).all());
            }
            assert!(t.albedo.cmpge(node.colour_min).all() && t.albedo.cmple(node.colour_max).all());
            let nrm = t.normal.normalize_or_zero();
            if nrm != Vec3::ZERO {
                let cone = node.cone.expect("a node with a normal has a cone");
                assert!(
                    cone.contains(nrm, ANGLE_TOL),
                    "node {i}: normal {nrm} at {} from axis {} > half-angle {}",
                    angle_between(cone.axis, nrm),
                    cone.axis,
                    cone.half_angle
                );
            }
        }
        if let Some(c) = node.cone {
            assert!((c.axis.length() - 1.0).abs() < 1e-5);
            assert!(c.half_angle >= 0.0 && c.half_angle <= PI);
        } else {
            assert!(
                under
                    .iter()
                    .all(|t| t.normal.normalize_or_zero() == Vec3::ZERO)
            );
        }
        assert!(node.mean_normal.length() <= 1.0 + 1e-5);
        for v in [node.centroid, node.mean_normal, node.colour] {
            assert!(v.is_finite(), "node {i}: non-finite mean {v}");
        }
        // Material is Some exactly when uniform.
        let m0 = under[0].material;
        let uniform = under.iter().all(|t| t.material == m0);
        assert_eq!(node.material, uniform.then_some(m0), "node {i} material");
        match node.children {
            None => {
                leaves += 1;
                assert_eq!(node.count, 1);
                let t = under[0];
                assert_eq!(node.centroid, t.centroid());
                assert_eq!(node.area, t.area());
                assert_eq!(node.colour, t.albedo);
            }
            Some([l, r]) => {
                assert!(node.count >= 2);
                assert_eq!(l as usize, i + 1, "pre-order: left child follows");
                let (a, b) = (&tree.nodes[l as usize], &tree.nodes[r as usize]);
                reached[l as usize] = true;
                reached[r as usize] = true;
                // The range is the union of the children's, left then right, balanced.
                assert_eq!(a.first, node.first);
                assert_eq!(b.first, a.first + a.count);
                assert_eq!(a.count + b.count, node.count);
                assert_eq!(a.count, node.count / 2);
                for c in [a, b] {
                    assert!(c.bbox_min.cmpge(node.bbox_min).all());
                    assert!(c.bbox_max.cmple(node.bbox_max).all());
                    assert!(c.colour_min.cmpge(node.colour_min).all());
                    assert!(c.colour_max.cmple(node.colour_max).all());
                }
                assert_eq!(node.area, a.area + b.area);
                let scale = node.bbox_max.abs().max(node.bbox_min.abs()).max_element();
                let (wa, wb) = if node.area > 0.0 {
                    (a.area / node.area, b.area / node.area)
                } else {
                    let c = node.count as f32;
                    (a.count as f32 / c, b.count as f32 / c)
                };
                assert!(close(
                    node.centroid,
                    a.centroid * wa + b.centroid * wb,
                    scale
                ));
                assert!(close(node.colour, a.colour * wa + b.colour * wb, 1.0));
            }
        }
        // Area-weighted means against a direct sum over the triangles (uniform if all zero).
        let total: f64 = under.iter().map(|t| t.area() as f64).sum();
        assert!(((node.area as f64) - total).abs() <= 1e-5 * total + 1e-30);
        let w = |t: &TriInput| {
            if total > 0.0 {
                t.area() as f64 / total
            } else {
                1.0 / under.len() as f64
            }
        };
        let c: DVec3 = under.iter().map(|t| t.centroid().as_dvec3() * w(t)).sum();
        let scale = node.bbox_max.abs().max(node.bbox_min.abs()).max_element();
        assert!(
            close(node.centroid, c.as_vec3(), scale),
            "node {i} centroid"
        );
        let nm: DVec3 = under
            .iter()
            .map(|t| t.normal.normalize_or_zero().as_dvec3() * w(t))
            .sum();
        assert!(
            close(node.mean_normal, nm.as_vec3(), 1.0),
            "node {i} mean normal"
        );
    }
    assert_eq!(leaves, n);
    // Median splits: depth is exactly ⌈log2 n⌉.
    let want_depth = (n as f64).log2().ceil() as u32;
    assert_eq!(tree.depth(), want_depth);
}

/// A random soup: `n` triangles with corners in [-10, 10]³ and edges up to ~2, random albedo,
/// a few materials; about 1 in `degenerate_every` triangles collapsed to a point or a segment.
fn soup(n: usize, seed: u64, degenerate_every: u32) -> Vec<TriInput> {
    let mut rng = Rng::keyed(seed, 0, 0);
    let mut u = || rng.f32();
    (0..n as u32)
        .map(|id| {
            let mut p = || Vec3::new(u(), u(), u());
            let c = p() * 20.0 - 10.0;
            let a = c + p() * 2.0 - 1.0;
            let mut b = c + p() * 2.0 - 1.0;
            let mut d = c + p() * 2.0 - 1.0;
            let albedo = p();
            let material = (u() * 3.0) as u32;
            let r = u();
            if degenerate_every > 0 && (r * degenerate_every as f32) < 1.0 {
                if r * (degenerate_every as f32) < 0.5 {
                    b = a;
                    d = a;
                } else {
                    d = a + (b - a) * 2.0;
                }
            }
            tri([a, b, d], albedo, material, id * 7 + 3)
        })
        .collect()
}

#[test]
fn empty_and_single_and_two() {
    let t = build_from(&[]);
    assert!(t.is_empty() && t.root().is_none() && t.depth() == 0);
    check_tree(&t, &[]);
    let one = soup(1, 1, 0);
    let t = build_from(&one);
    check_tree(&t, &one);
    assert!(t.nodes[0].is_leaf());
    let two = soup(2, 2, 0);
    check_tree(&build_from(&two), &two);
}

#[test]
fn needs_tree_threshold() {
    assert!(!needs_tree(0));
    assert!(!needs_tree(MIN_TRIANGLES_FOR_TREE));
    assert!(needs_tree(MIN_TRIANGLES_FOR_TREE + 1));
}

#[test]
fn random_soups_with_degenerate_triangles() {
    for (n, seed) in [(3, 1), (5, 2), (17, 3), (200, 4), (1000, 5), (5000, 6)] {
        let tris = soup(n, seed, 10);
        check_tree(&build_from(&tris), &tris);
    }
}

#[test]
fn all_degenerate_identical_and_parallel() {
    // Every triangle collapsed to the same point: zero area, no normals, identical centroids.
    let p = Vec3::new(1.0, 2.0, 3.0);
    let tris: Vec<TriInput> = (0..300)
        .map(|i| tri([p; 3], Vec3::splat(0.5), 0, i))
        .collect();
    let t = build_from(&tris);
    check_tree(&t, &tris);
    let root = t.root().unwrap();
    assert_eq!(root.area, 0.0);
    assert_eq!(root.centroid, p);
    assert!(root.cone.is_none());
    assert_eq!(root.material, Some(0));

    // The same triangle 257 times: identical features, all normals equal.
    let v = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let tris: Vec<TriInput> = (0..257).map(|i| tri(v, Vec3::ONE, i % 2, i)).collect();
    let t = build_from(&tris);
    check_tree(&t, &tris);
    let root = t.root().unwrap();
    let cone = root.cone.unwrap();
    assert!((cone.axis - Vec3::Z).length() < 1e-6);
    assert!(cone.half_angle < 1e-6);
    assert!((root.mean_normal.length() - 1.0).abs() < 1e-5);
    assert!(root.material.is_none());

    // A flat grid: all normals equal, centroids on a plane.
    let mut tris = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let o = Vec3::new(i as f32, j as f32, 0.0);
            tris.push(tri(
                [o, o + Vec3::X, o + Vec3::Y],
                Vec3::ONE,
                0,
                tris.len() as u32,
            ));
        }
    }
    let t = build_from(&tris);
    check_tree(&t, &tris);
    assert!(t.nodes.iter().all(|n| n.cone.unwrap().half_angle < 1e-6));
}

#[test]
fn opposite_normals_span_more_than_a_hemisphere() {
    // Up- and down-facing triangles of equal area: the mean normal cancels, the cone must
    // still contain both (half-angle π).
    let up = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let down = [Vec3::ZERO, Vec3::Y, Vec3::X];
    let tris = vec![tri(up, Vec3::ONE, 0, 0), tri(down, Vec3::ONE, 0, 1)];
    let t = build_from(&tris);
    check_tree(&t, &tris);
    let root = t.root().unwrap();
    assert!(root.mean_normal.length() < 1e-6);
    assert!((root.cone.unwrap().half_angle - PI).abs() < 1e-5);
}

/// Which of two groups (by id predicate) each root child holds; asserts they are separated.
fn assert_root_separates(t: &ReflectorTree, in_a: impl Fn(u32) -> bool) {
    let [l, r] = t.root().unwrap().children.unwrap();
    let la: Vec<bool> = t.leaves_under(l).iter().map(|&id| in_a(id)).collect();
    let ra: Vec<bool> = t.leaves_under(r).iter().map(|&id| in_a(id)).collect();
    assert!(
        (la.iter().all(|&x| x) && ra.iter().all(|&x| !x))
            || (la.iter().all(|&x| !x) && ra.iter().all(|&x| x)),
        "root children mix the two groups"
    );
}

#[test]
fn pca_separates_two_clusters() {
    // Two equal-sized clusters of random triangles 50 units apart along a diagonal.
    let mut tris = soup(256, 11, 0);
    let shift = Vec3::new(50.0, -30.0, 40.0);
    for t in tris.iter_mut().skip(128) {
        for p in &mut t.v {
            *p += shift;
        }
    }
    let t = build_from(&tris);
    check_tree(&t, &tris);
    let second: std::collections::HashSet<u32> = tris[128..].iter().map(|t| t.tri).collect();
    assert_root_separates(&t, |id| second.contains(&id));
}

#[test]
fn pca_separates_opposite_planes_at_the_same_place() {
    // A 16×16 grid of up-facing triangles and the same grid facing down, interleaved in the
    // input: positions coincide, so only the normal features can separate them.
    let mut tris = Vec::new();
    for i in 0..16 {
        for j in 0..16 {
            let o = Vec3::new(i as f32, 0.0, j as f32) * 0.1;
            let (a, b, c) = (o, o + Vec3::X * 0.1, o + Vec3::Z * 0.1);
            let id = tris.len() as u32;
            tris.push(tri([a, c, b], Vec3::ONE, 0, id)); // normal +y
            tris.push(tri([a, b, c], Vec3::ONE, 1, id + 1)); // normal −y
        }
    }
    assert!(tris[0].normal.y > 0.99 && tris[1].normal.y < -0.99);
    let t = build_from(&tris);
    check_tree(&t, &tris);
    assert_root_separates(&t, |id| id % 2 == 0);
    let [l, r] = t.root().unwrap().children.unwrap();
    for c in [l, r] {
        let node = &t.nodes[c as usize];
        assert!(node.material.is_some(), "each side has one material");
        assert!(node.cone.unwrap().half_angle < 1e-5);
        assert!((node.mean_normal.length() - 1.0).abs() < 1e-5);
    }
}

#[test]
fn large_soup_builds_fast() {
    let tris = soup(100_000, 99, 50);
    let t0 = std::time::Instant::now();
    let t = build_from(&tris);
    let dt = t0.elapsed();
    println!(
        "build_from: 100k random triangles in {:.1} ms",
        dt.as_secs_f64() * 1e3
    );
    assert_eq!(t.nodes.len(), 2 * tris.len() - 1);
    assert_eq!(t.depth(), 17);
    let mut ids = t.tri_order.clone();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), tris.len());
}

fn scene_tris(scene: &Scene) -> Vec<TriInput> {
    scene
        .objects
        .iter()
        .filter(|o| o.reflector)
        .flat_map(|o| o.first_tri..o.first_tri + o.tri_count)
        .map(|t| TriInput::from_scene(scene, t))
        .collect()
}

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn real_scenes_ring_and_bunny() {
    for name in ["ring.toml", "bunny.toml"] {
        let scene = load(name);
        let tris = scene_tris(&scene);
        assert!(
            needs_tree(tris.len()),
            "{name}: {} reflector triangles",
            tris.len()
        );
        let t = build(&scene);
        check_tree(&t, &tris);
        // Scene triangle ids and materials are the scene's.
        for (i, node) in t.nodes.iter().enumerate() {
            if node.is_leaf() {
                let id = t.leaves_under(i as u32)[0];
                assert_eq!(node.material, Some(scene.tri_object(id).material));
                let brdf = scene.tri_material(id);
                assert_eq!(node.colour, brdf.diffuse() + brdf.specular());
                let cross = scene.mesh.tri_cross(id);
                assert!((node.mean_normal - cross.normalize_or_zero()).length() < 1e-6);
            }
        }
        println!(
            "{name}: {} reflector triangles, depth {}",
            tris.len(),
            t.depth()
        );
    }
}

/// Build times on the dragon scenes (run with `--ignored --nocapture`; numbers in
/// docs/tree.md).
#[test]
#[ignore]
fn dragon_build_times() {
    for name in ["dragon-11k.toml", "dragon-48k.toml", "dragon.toml"] {
        let scene = load(name);
        let n = scene_tris(&scene).len();
        // One warm-up build (thread pool start-up, page faults), then the best of three.
        let _ = build(&scene);
        let best = (0..3)
            .map(|_| {
                let t0 = std::time::Instant::now();
                let t = build(&scene);
                let dt = t0.elapsed().as_secs_f64();
                assert_eq!(t.num_triangles(), n);
                dt
            })
            .fold(f64::INFINITY, f64::min);
        println!(
            "{name}: {n} reflector triangles, build {:.1} ms (best of 3, {} rayon threads)",
            best * 1e3,
            rayon::current_num_threads()
        );
    }
}

fn arb_tri() -> impl Strategy<Value = ([f32; 9], [f32; 3], u32, u8)> {
    (
        prop::array::uniform9(-5.0f32..5.0),
        prop::array::uniform3(0.0f32..1.0),
        0u32..3,
        0u8..10,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn prop_random_soups(raw in prop::collection::vec(arb_tri(), 1..300)) {
        let tris: Vec<TriInput> = raw
            .iter()
            .enumerate()
            .map(|(i, (p, albedo, m, kind))| {
                let a = Vec3::new(p[0], p[1], p[2]);
                let mut b = Vec3::new(p[3], p[4], p[5]);
                let mut c = Vec3::new(p[6], p[7], p[8]);
                match kind {
                    0 => { b = a; c = a; } // a point
                    1 => c = b,            // a segment
                    2 => c = a + (b - a) * 0.5, // collinear
                    _ => {}
                }
                tri([a, b, c], Vec3::from(*albedo), *m, i as u32)
            })
            .collect();
        check_tree(&build_from(&tris), &tris);
    }
}
