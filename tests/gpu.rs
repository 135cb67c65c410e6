//! GPU passes against their CPU twins, on whatever adapter wgpu finds (lavapipe on machines
//! without a GPU). With `CI=true` a missing adapter fails these tests instead of skipping them.

mod common;

use glam::Vec3;
use interreflect::math::Rng;
use interreflect::precompute::prt::relight_cpu;
use interreflect::render::gpu::prt::relight;

fn random_table(vertices: usize, coefficients: usize, seed: u64) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut rng = Rng::keyed(seed, 0, 0);
    let mut v = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
    let transfer = (0..vertices * coefficients).map(|_| v()).collect();
    let lighting = (0..coefficients).map(|_| v()).collect();
    (transfer, lighting)
}

/// Both sides sum the same f32 products in the same order; they differ only where the GPU
/// fuses a multiply-add, by at most a few ulps of the sum of magnitudes per term: 1e-5 of
/// Σ|t·l| leaves a factor of ~10 over 64 terms.
fn assert_close(gpu: &[Vec3], cpu: &[Vec3], transfer: &[Vec3], lighting: &[Vec3]) {
    assert_eq!(gpu.len(), cpu.len());
    let n = lighting.len();
    for (v, (g, c)) in gpu.iter().zip(cpu).enumerate() {
        let scale: Vec3 = transfer[v * n..(v + 1) * n]
            .iter()
            .zip(lighting)
            .map(|(t, l)| (*t * *l).abs())
            .sum();
        let tol = scale * 1e-5 + Vec3::splat(1e-30);
        assert!(
            (*g - *c).abs().cmple(tol).all(),
            "vertex {v}: gpu {g} cpu {c} (tolerance {tol})"
        );
    }
}

#[test]
fn prt_relight_matches_its_cpu_twin() {
    let Some(g) = common::gpu() else { return };
    for (order, vertices) in [(1usize, 7usize), (3, 1000), (8, 5003)] {
        let n = order * order;
        let (transfer, lighting) = random_table(vertices, n, order as u64);
        let on_gpu = relight(&g, &transfer, n, &lighting).expect("relight on the GPU");
        let on_cpu = relight_cpu(&transfer, n, &lighting);
        assert_close(&on_gpu, &on_cpu, &transfer, &lighting);
    }
}

#[test]
fn prt_relight_splits_work_over_the_binding_limit() {
    let Some(mut g) = common::gpu() else { return };
    // 1000 vertices per chunk: 4321 vertices take 5 dispatches, the last one partial.
    g.max_binding = 1000 * 64 * 12;
    let (transfer, lighting) = random_table(4321, 64, 9);
    let on_gpu = relight(&g, &transfer, 64, &lighting).expect("relight on the GPU");
    assert_close(
        &on_gpu,
        &relight_cpu(&transfer, 64, &lighting),
        &transfer,
        &lighting,
    );
}

#[test]
fn prt_relight_rejects_inconsistent_sizes() {
    let Some(g) = common::gpu() else { return };
    let (transfer, lighting) = random_table(10, 9, 1);
    let err = relight(&g, &transfer[..85], 9, &lighting).unwrap_err();
    assert!(err.to_string().contains("inconsistent sizes"), "{err}");
}

#[test]
fn a_binding_over_the_device_limit_is_an_error_not_a_panic() {
    let Some(mut g) = common::gpu() else { return };
    let limit = g.max_binding;
    if limit > 512 << 20 {
        eprintln!(
            "skipped: this device's binding limit ({limit} bytes) is too large to exceed cheaply"
        );
        return;
    }
    // Pretend the device takes any binding: the relighter then uploads the whole transfer as one
    // buffer, past the real limit, and the device's validation must turn that into an error.
    g.max_binding = u64::MAX;
    let vertices = (limit / (64 * 12)) as usize + 1024;
    let transfer = vec![Vec3::ONE; vertices * 64];
    let err = relight(&g, &transfer, 64, &[Vec3::ONE; 64]).unwrap_err();
    eprintln!("{err}");
    assert!(err.to_string().contains("PRT relighting"), "{err}");
}

/// No adapter (simulated with `WGPU_BACKEND=dx12`, a backend wgpu is not built with on this
/// platform, so wgpu finds no adapter): `--device gpu` fails at once — before the transfer is
/// computed — with a message saying what to install or which flag to use, and writes nothing;
/// `--device auto` says in one line that it relights on the CPU, and renders.
#[test]
fn no_adapter_fails_clearly_or_falls_back_to_the_cpu() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/prt/ring-diffuse-env.toml"
    );
    let run = |device: &str, quiet: bool| {
        std::process::Command::new(env!("CARGO_BIN_EXE_interreflect"))
            .args(["render", scene, "--method", "prt", "--device", device])
            .args(["--width", "16", "--transfer", "unshadowed", "--output"])
            .arg(dir.path().join(format!("{device}.exr")))
            .arg("--prt-cache")
            .arg(dir.path().join(format!("cache-{device}")))
            .args(quiet.then_some("--quiet"))
            .env("WGPU_BACKEND", "dx12")
            .env("XDG_RUNTIME_DIR", dir.path())
            .output()
            .unwrap()
    };
    // Had the device been opened after the transfer was computed, the transfer would be in the
    // cache (and the log would say "prt: transfer computed ..., cached in ...").
    let gpu = run("gpu", false);
    let stderr = String::from_utf8_lossy(&gpu.stderr);
    assert_eq!(gpu.status.code(), Some(2), "{stderr}");
    let last = stderr.lines().last().unwrap_or_default();
    assert!(last.starts_with("error: no GPU adapter found"), "{stderr}");
    assert!(last.contains("--device cpu"), "{stderr}");
    assert!(last.contains("mesa-vulkan-drivers"), "{stderr}");
    assert!(!stderr.contains("prt: transfer"), "{stderr}");
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");

    let auto = run("auto", true);
    let stderr = String::from_utf8_lossy(&auto.stderr);
    assert_eq!(auto.status.code(), Some(0), "{stderr}");
    let notices = common::notices(&stderr);
    assert_eq!(notices.len(), 1, "{stderr}");
    assert!(
        notices[0].starts_with("notice: relighting on the CPU: no GPU adapter found"),
        "{stderr}"
    );
    assert!(dir.path().join("auto.exr").is_file());
    assert!(dir.path().join("cache-auto").is_dir());
}

/// The same for sg's shadow maps (the stage of sg with a GPU pass): with no adapter,
/// `--device gpu` fails before rendering and writes nothing; `--device auto` makes them on the
/// CPU with one notice and says so in the log.
#[test]
fn sg_shadow_maps_without_an_adapter_fail_clearly_or_fall_back() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bunny.toml");
    let run = |device: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_interreflect"))
            .args(["render", scene, "--method", "sg", "--visibility", "vsm"])
            .args(["--device", device, "--width", "16", "--spp", "1", "--quiet"])
            .arg("--output")
            .arg(dir.path().join(format!("{device}.exr")))
            .env("WGPU_BACKEND", "dx12")
            .env("XDG_RUNTIME_DIR", dir.path())
            .output()
            .unwrap()
    };
    let gpu = run("gpu");
    let stderr = String::from_utf8_lossy(&gpu.stderr);
    assert_eq!(gpu.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("error: --device gpu: the shadow maps need the GPU: no GPU adapter found"),
        "{stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");

    let auto = run("auto");
    let stderr = String::from_utf8_lossy(&auto.stderr);
    assert_eq!(auto.status.code(), Some(0), "{stderr}");
    let notices = common::notices(&stderr);
    assert_eq!(notices.len(), 1, "{stderr}");
    assert!(
        notices[0].starts_with("notice: shadow maps made on the CPU: no GPU"),
        "{stderr}"
    );
    let log: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("auto.json")).unwrap())
            .unwrap();
    let on = log["sg"]["shadow_maps_on"].as_str().unwrap_or_default();
    assert!(on.starts_with("cpu (no GPU"), "{on}");
}

/// Without an adapter, `--device gpu` with a method whose only GPU stage is the PNG's tonemap
/// (`direct`) fails before rendering, names the stage and the fix, and writes nothing.
#[test]
fn tonemap_without_an_adapter_fails_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bunny.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_interreflect"))
        .args(["render", scene, "--method", "direct", "--device", "gpu"])
        .args(["--width", "16", "--spp", "1", "--quiet", "--output"])
        .arg(dir.path().join("direct.exr"))
        .env("WGPU_BACKEND", "dx12")
        .env("XDG_RUNTIME_DIR", dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(
            "error: --device gpu: the PNG is tonemapped on the GPU: no GPU adapter found"
        ),
        "{stderr}"
    );
    assert!(stderr.contains("--device cpu"), "{stderr}");
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert!(left.is_empty(), "{left:?}");
}
