//! Imperfect shadow maps splatted on the GPU (`render::gpu::ism`, `shaders/ism.wgsl`) against
//! their CPU twin (`ImperfectShadowMaps::build`), on the evaluation scenes and the ring under a
//! spot and a directional light, at the scenes' settings and at an odd resolution without the
//! blur; and the vpl renderer with either. lavapipe in CI; `CI=true` makes a missing adapter a
//! failure.

mod common;

use interreflect::precompute::vpl;
use interreflect::render::cpu::sg::light_fraction;
use interreflect::render::cpu::surface::ray_epsilon;
use interreflect::visibility::ism::{ImperfectShadowMaps, IsmOptions};
use interreflect::visibility::vsm::VarianceShadowMap;

/// Texels whose moments differ by more than `rel` of the map's largest first moment (the
/// distances' scale), and the largest difference so measured, over every map.
fn differing(a: &ImperfectShadowMaps, b: &ImperfectShadowMaps, rel: f32) -> (usize, usize, f32) {
    let (mut off, mut all, mut worst) = (0, 0, 0.0f32);
    for i in 0..a.len() {
        let (ma, mb) = (a.moments(i), b.moments(i));
        let scale = ma.iter().map(|m| m.x).fold(1e-6, f32::max);
        for (x, y) in ma.iter().zip(mb) {
            let d = ((x.x - y.x).abs() / scale).max((x.y - y.y).abs() / (scale * scale));
            worst = worst.max(d);
            off += usize::from(d > rel);
            all += 1;
        }
    }
    (off, all, worst)
}

/// The two sides splat the same points (the CPU samples them for both) with the same f32
/// projection, so a texel's layer and moments agree to rounding: the CPU adds z and z² in f32
/// in point order, the GPU adds z / nearest − 1 and its square as exact fixed point. Measured
/// at most 6.5e-7 of the map's depth scale (five cases, two settings each); allowed 1e-4 of
/// it. Beyond that a texel differs only where a point changed texel or layer, when the
/// projection's last bit (GPU dot products may fuse) puts it across a texel edge or the layer's
/// 1.5 × nearest: measured on no texel, allowed 0.5 % (pull-push and the blur spread one such
/// point over a few texels). The variance floor comes from the farthest kept depth, the same f32
/// on both sides unless that point moved: measured equal, allowed 1e-5 relative on 2 % of maps.
/// Visibility through either map at scene points (the Chebyshev bound amplifies moment
/// differences where the variance is small): measured equal to 1e-3 everywhere, allowed 1 % of
/// points. Against maps of another seed the comparison fails, so it can.
#[test]
fn gpu_maps_match_the_cpu() {
    let Some(gpu) = common::gpu() else { return };
    let odd = IsmOptions {
        resolution: 33,
        points_per_map: 3000,
        blur: false,
        ..IsmOptions::default()
    };
    for (name, scene, accel) in common::light_cases() {
        let light = scene.lights[0];
        let map =
            VarianceShadowMap::build(&accel, scene.mesh.bounds(), &light, &scene.settings.vsm);
        let eps = ray_epsilon(&scene);
        let visible = |p| light_fraction(&accel, &light, Some(&map), p, eps);
        let vpls = vpl::generate(&vpl::sources(&scene), &light, 200, 5, &visible);
        assert!(vpls.len() > 100, "{name}: {} VPLs", vpls.len());
        let (pos, idx) = (&scene.mesh.positions, &scene.mesh.indices);
        for (label, opts) in [
            ("scene settings", scene.settings.ism),
            ("33², no blur", odd),
        ] {
            let cpu = ImperfectShadowMaps::build(pos, idx, &vpls, &opts, 9);
            let g = interreflect::render::gpu::ism::build(&gpu, pos, idx, &vpls, &opts, 9).unwrap();
            assert_eq!((cpu.len(), cpu.resolution()), (g.len(), g.resolution()));
            let (off, all, worst) = differing(&cpu, &g, 1e-4);
            let floors = (0..cpu.len())
                .filter(|&i| {
                    let (a, b) = (cpu.min_variance(i), g.min_variance(i));
                    (a - b).abs() > 1e-5 * a
                })
                .count();
            // Visibility at scene points from every map, where both sides know something.
            let mut rng = interreflect::math::Rng::keyed(1, 2, 3);
            let (mut vis_off, mut vis_all) = (0usize, 0usize);
            for _ in 0..12000 {
                let t = (rng.f32() * idx.len() as f32) as usize % idx.len();
                let [a, b, c] = idx[t].map(|i| pos[i as usize]);
                let p = (a + b + c) / 3.0;
                let i = (rng.f32() * cpu.len() as f32) as usize % cpu.len();
                if let (Some(x), Some(y)) = (
                    cpu.visibility_above_horizon(i, p),
                    g.visibility_above_horizon(i, p),
                ) {
                    vis_all += 1;
                    vis_off += usize::from((x - y).abs() > 1e-3);
                }
            }
            eprintln!(
                "{name} ({label}): {off} of {all} texels differ by more than 1e-4 (worst {worst:.1e}), {floors} variance floors differ, visibility differs by more than 1e-3 at {vis_off} of {vis_all} points"
            );
            assert!(
                off as f64 <= 5e-3 * all as f64,
                "{name} ({label}): {off} of {all} texels differ (worst {worst:e})"
            );
            assert!(
                floors <= cpu.len() / 50,
                "{name} ({label}): {floors} variance floors differ"
            );
            assert!(
                vis_off as f64 <= 1e-2 * vis_all as f64 && vis_all > 2000,
                "{name} ({label}): visibility differs at {vis_off} of {vis_all} points"
            );
        }
        // The comparison can fail: other points, other maps.
        let opts = scene.settings.ism;
        let other = ImperfectShadowMaps::build(pos, idx, &vpls, &opts, 10);
        let g = interreflect::render::gpu::ism::build(&gpu, pos, idx, &vpls, &opts, 9).unwrap();
        let (off, all, _) = differing(&other, &g, 1e-4);
        assert!(
            off as f64 > 0.2 * all as f64,
            "{name}: maps of another seed differ on only {off} of {all} texels"
        );
    }
}

/// The vpl renderer's indirect light with the maps splatted on the GPU (`--device gpu`, the sum
/// kept on the CPU) against `--device auto` (the maps splatted on the CPU), ring and bunny,
/// 48 px, 1 spp. Both make the light's shadow maps on the GPU, and the VPLs drawn from the
/// GPU's weights are the CPU's (`tests/gpu_vpl_gen.rs`), so the maps are what differs: within
/// the GPU pipeline's 1 % rel_rmse, measured far below it.
#[test]
fn vpl_images_with_gpu_maps_match_the_cpu() {
    use interreflect::compare::metrics;
    use interreflect::render::cpu::vpl::{VplOptions, default_clamp_distance, render_vpl_quiet};
    use interreflect::render::{Device, Visibility};
    let Some(_gpu) = common::gpu() else { return };
    for name in ["ring", "bunny"] {
        let (scene, accel) = common::scene_and_accel(name);
        let opts = |device| VplOptions {
            width: 48,
            height: (48 * scene.camera.height / scene.camera.width).max(1),
            spp: 1,
            seed: 3,
            direct: false,
            indirect: true,
            visibility: Visibility::Approx,
            vpl_count: 200,
            clamp_distance: default_clamp_distance(&scene),
            device,
            cpu_sum: true,
        };
        let (cpu_img, cpu) = render_vpl_quiet(&scene, &accel, &opts(Device::Auto));
        let (gpu_img, g) = render_vpl_quiet(&scene, &accel, &opts(Device::Gpu));
        assert_eq!(cpu.ism_on, "cpu", "{name}");
        assert!(g.ism_on.starts_with("gpu ("), "{name}: {}", g.ism_on);
        let e = metrics(&gpu_img, &cpu_img).unwrap().rel_rmse;
        eprintln!("{name}: rel_rmse {:.5} %", 100.0 * e);
        assert!(e <= 0.01, "{name}: rel_rmse {e}");
        assert!(cpu_img.mean() > 0.0, "{name}: black");
    }
}

/// As a user runs it: `render --method vpl --device gpu` splats the imperfect shadow maps on the
/// GPU and says so in the JSON log (`vpl.ism_on`), and so does sg with the paper's proxy
/// (`--node-maps 0`, `sg.ism_on`); `--device cpu` splats them on the CPU.
#[test]
fn render_splats_the_maps_on_the_gpu_when_asked_and_says_so() {
    let Some(_gpu) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/ring.toml");
    let run = |name: &str, method: &str, device: &str| {
        let args = [
            "--method",
            method,
            "--device",
            device,
            "--node-maps",
            "0",
            "--indirect-only",
            "--width",
            "16",
            "--spp",
            "1",
        ];
        common::render_cli(dir.path(), scene, name, &args).1
    };
    for method in ["vpl", "sg"] {
        let log = run(&format!("{method}-gpu"), method, "gpu");
        let on = log[method]["ism_on"].as_str().unwrap_or_default();
        assert!(on.starts_with("gpu ("), "{method}: {}", log[method]);
        let log = run(&format!("{method}-cpu"), method, "cpu");
        assert_eq!(log[method]["ism_on"], "cpu", "{method}: {}", log[method]);
    }
}

/// Maps the GPU cannot splat in one dispatch row (5 million points per map: more than 65,535
/// workgroups of 64) are an error under `--device gpu` naming the scene file and the setting,
/// before rendering, for vpl and for sg with the VPLs' maps, and nothing is written;
/// `--device auto` splats them on the CPU (not run here: it would draw a billion points).
#[test]
fn too_many_points_for_the_gpu_fail_clearly() {
    let Some(_gpu) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let ring =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/ring.toml")).unwrap();
    let scene = dir.path().join("ring.toml");
    std::fs::write(
        &scene,
        format!("{ring}\n[visibility]\nism_points = 5000000\n"),
    )
    .unwrap();
    let out = dir.path().join("ring.exr");
    for args in [
        &["--method", "vpl"][..],
        &["--method", "sg", "--node-maps", "0"][..],
    ] {
        let run = std::process::Command::new(env!("CARGO_BIN_EXE_interreflect"))
            .arg("render")
            .arg(&scene)
            .args(args)
            .args(["--device", "gpu", "--width", "16", "--spp", "1"])
            .args(["--quiet", "--output"])
            .arg(&out)
            .env("XDG_RUNTIME_DIR", dir.path())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_ne!(run.status.code(), Some(0), "{stderr}");
        assert!(
            stderr.contains("ring.toml")
                && stderr.contains("imperfect shadow maps")
                && stderr.contains("ism_points"),
            "{args:?}: {stderr}"
        );
        assert!(!out.exists() && !dir.path().join("ring.png").exists());
    }
}
