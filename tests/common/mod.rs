//! Helpers shared by the integration tests (`mod common;` in each).

use interreflect::render::gpu::{Gpu, adapter_required};

/// The GPU for a GPU test: `None` (the test skips, with a note) when no adapter exists, unless
/// `CI=true` asks for one, in which case the test fails.
#[allow(dead_code)] // The CPU-only test binaries that share this module need no GPU.
pub fn gpu() -> Option<Gpu> {
    match Gpu::new() {
        Ok(g) => Some(g),
        Err(e) if adapter_required() => panic!("CI=true requires a GPU adapter: {e}"),
        Err(e) => {
            eprintln!("skipped (no GPU adapter): {e}");
            None
        }
    }
}

/// One sg render of `scene` for the GPU-against-CPU tests: `width` pixels wide (the camera's
/// aspect), 1 spp, seed 3, the default cut, pieces split to 1/128 of the diagonal.
#[allow(dead_code)] // Not every test binary that shares this module renders sg.
pub fn sg_render(
    scene: &interreflect::scene::Scene,
    accel: &interreflect::accel::Accel,
    width: u32,
    direct: bool,
    mode: interreflect::render::cpu::sg::CutMode,
    visibility: interreflect::render::Visibility,
    device: interreflect::render::Device,
) -> (
    interreflect::image::Image,
    interreflect::render::cpu::sg::SgStats,
) {
    use interreflect::render::cpu::sg::{SgOptions, render_sg_quiet};
    let opts = SgOptions {
        width,
        height: (width * scene.camera.height / scene.camera.width).max(1),
        spp: 1,
        seed: 3,
        direct,
        indirect: true,
        brute: false,
        cut: interreflect::sg::CutOptions::default(),
        mode,
        max_edge: scene.mesh.diagonal() / 128.0,
        visibility,
        device,
    };
    render_sg_quiet(scene, accel, &opts)
}

/// An evaluation scene (`scenes/<name>.toml`) and its BVH.
#[allow(dead_code)] // Not every test binary that shares this module loads scenes.
pub fn scene_and_accel(name: &str) -> (interreflect::scene::Scene, interreflect::accel::Accel) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"));
    let scene = interreflect::scene::Scene::load(&path).unwrap();
    let accel = interreflect::accel::Accel::build(&scene.mesh.positions, &scene.mesh.indices);
    (scene, accel)
}

/// The ring with its point light replaced by `light` (TOML): a spot or a directional light.
#[allow(dead_code)] // Not every test binary that shares this module needs it.
pub fn ring_with(light: &str) -> (interreflect::scene::Scene, interreflect::accel::Accel) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/ring.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let point = "type = \"point\"\nposition = [-4.5, 2.1, 0.0]\nintensity = [60.0, 60.0, 60.0]";
    assert!(text.contains(point), "the ring's light changed");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("ring.toml");
    std::fs::write(&file, text.replace(point, light)).unwrap();
    let scene = interreflect::scene::Scene::load(&file).unwrap();
    let accel = interreflect::accel::Accel::build(&scene.mesh.positions, &scene.mesh.indices);
    (scene, accel)
}

/// The light cases of the GPU shadow-map passes' tests: ring, bunny and dragon (point lights)
/// and the ring under [`RING_SPOT`] and [`RING_SUN`].
#[allow(dead_code)]
pub fn light_cases() -> Vec<(
    &'static str,
    interreflect::scene::Scene,
    interreflect::accel::Accel,
)> {
    let mut cases = Vec::new();
    for name in ["ring", "bunny", "dragon"] {
        let (s, a) = scene_and_accel(name);
        cases.push((name, s, a));
    }
    let (s, a) = ring_with(RING_SPOT);
    cases.push(("ring under a spot", s, a));
    let (s, a) = ring_with(RING_SUN);
    cases.push(("ring under a directional light", s, a));
    cases
}

/// The ring under a spot aimed as its point light shines (a 20° cone: one perspective face).
#[allow(dead_code)]
pub const RING_SPOT: &str = "type = \"spot\"\nposition = [-4.5, 2.1, 0.0]\ndirection = [4.5, -2.1, 0.0]\nintensity = [60.0, 60.0, 60.0]\ncone_angle = 20.0\nfalloff_angle = 12.0";
/// The ring under a directional light from its point light's side (an orthographic face).
#[allow(dead_code)]
pub const RING_SUN: &str =
    "type = \"directional\"\ndirection = [4.5, -2.1, 0.0]\nirradiance = [2.4, 2.4, 2.4]";

/// `interreflect render SCENE ARGS --quiet --output DIR/NAME.exr` with a private
/// `XDG_RUNTIME_DIR`, for the tests that run the renderer as a user does: checks that it exits
/// 0 and returns its stderr and its JSON log.
#[allow(dead_code)] // Not every test binary that shares this module runs the CLI.
pub fn render_cli(
    dir: &std::path::Path,
    scene: &str,
    name: &str,
    args: &[&str],
) -> (String, serde_json::Value) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_interreflect"))
        .arg("render")
        .arg(scene)
        .args(args)
        .args(["--quiet", "--output"])
        .arg(dir.join(format!("{name}.exr")))
        .env("XDG_RUNTIME_DIR", dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let log =
        serde_json::from_str(&std::fs::read_to_string(dir.join(format!("{name}.json"))).unwrap())
            .unwrap();
    (stderr, log)
}

/// The `notice:` lines of a run's stderr.
#[allow(dead_code)]
pub fn notices(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| l.starts_with("notice:"))
        .collect()
}
