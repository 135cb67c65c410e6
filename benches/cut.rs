//! The SG renderer's per-frame and per-point stages on the evaluation scenes: tree build over the
//! reflector pieces, lighting every piece (exact shadow rays), and one cut selection at a
//! receiver point (1 %, 1000 nodes). Run: `cargo bench --bench cut`. Scene-level timings (frame
//! time against triangle count) are in `results/sg-cpu.md`.

use divan::{Bencher, black_box};
use glam::Vec3;
use interreflect::accel::Accel;
use interreflect::render::cpu::surface::{light_visible, ray_epsilon};
use interreflect::scene::Scene;
use interreflect::sg::transport::receiver::{ReceiverLobes, ReceiverOptions};
use interreflect::sg::tree::ReflectorTree;
use interreflect::sg::{
    CutCounters, CutOptions, LitScene, ReflectorPiece, build_tree, light_anchor, light_triangles,
    reflector_pieces,
};
use std::path::Path;

fn main() {
    divan::main();
}

const SCENES: [&str; 3] = ["dragon-11k", "dragon-48k", "dragon"];

/// An evaluation scene with its BVH, reflector pieces (the default split) and tree.
fn setup(name: &str) -> (Scene, Accel, Vec<ReflectorPiece>, ReflectorTree) {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"));
    let scene = Scene::load(&p).expect("evaluation scene");
    let accel = Accel::build(&scene.mesh.positions, &scene.mesh.indices);
    let pieces = reflector_pieces(&scene, scene.mesh.diagonal() / 128.0);
    let tree = build_tree(&scene, &pieces);
    (scene, accel, pieces, tree)
}

#[divan::bench(args = SCENES, sample_count = 5)]
fn tree_build(bencher: Bencher, name: &str) {
    let (scene, _, pieces, _) = setup(name);
    bencher.bench(|| build_tree(&scene, black_box(&pieces)));
}

#[divan::bench(args = SCENES, sample_count = 5)]
fn lighting(bencher: Bencher, name: &str) {
    let (scene, accel, pieces, tree) = setup(name);
    let light = scene.lights[0];
    let eps = ray_epsilon(&scene);
    let visible = |p: Vec3, _t: u32| -> f32 {
        if light_visible(&accel, &light, p, eps) {
            1.0
        } else {
            0.0
        }
    };
    bencher.bench(|| {
        light_triangles(
            &scene,
            &pieces,
            black_box(&tree.tri_order),
            &light,
            &visible,
        )
    });
}

#[divan::bench(args = SCENES, sample_count = 20)]
fn cut_selection(bencher: Bencher, name: &str) {
    let (scene, accel, pieces, tree) = setup(name);
    let light = scene.lights[0];
    let none = |_: Vec3, _: u32| 1.0;
    let tris = light_triangles(&scene, &pieces, &tree.tri_order, &light, &none);
    let lit = LitScene::new(
        &tree,
        tris,
        light_anchor(&scene, &light),
        ReceiverOptions::default(),
    );
    // A floor point beside the dragon, seen from the camera.
    let cam = scene.camera;
    let dir = cam.ray_dir(0.55 * cam.width as f32, 0.8 * cam.height as f32);
    let hit = accel
        .intersect(cam.position, dir, 0.0, f32::INFINITY)
        .expect("hit");
    let x = scene.mesh.point(hit.tri, hit.u, hit.v);
    let n = scene.mesh.shading_normal(hit.tri, hit.u, hit.v);
    let n = if n.dot(-dir) < 0.0 { -n } else { n };
    let rx = ReceiverLobes::new(scene.tri_material(hit.tri), n, -dir);
    let mut out = Vec::new();
    bencher.bench_local(|| {
        let mut c = CutCounters::default();
        lit.select(black_box(x), &rx, &CutOptions::default(), &mut out, &mut c)
    });
}
