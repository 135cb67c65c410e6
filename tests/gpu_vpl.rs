//! The VPL baseline's one-bounce sum on the GPU (`render::gpu::vpl`) against its CPU twin, the
//! sum in `render::cpu::vpl`, on the evaluation scenes: the same shadow maps, VPLs and imperfect
//! shadow maps, summed on either side.

mod common;

use interreflect::image::Image;
use interreflect::render::cpu::vpl::{
    VplOptions, VplStats, default_clamp_distance, render_vpl_quiet,
};
use interreflect::render::{Device, Visibility};

fn vpl_render(name: &str, cpu_sum: bool) -> (Image, VplStats) {
    let (scene, accel) = common::scene_and_accel(name);
    let width = 48;
    let opts = VplOptions {
        width,
        height: (width * scene.camera.height / scene.camera.width).max(1),
        spp: 2,
        seed: 3,
        direct: false,
        indirect: true,
        visibility: Visibility::Approx,
        vpl_count: 200,
        clamp_distance: default_clamp_distance(&scene),
        device: Device::Gpu,
        cpu_sum,
    };
    render_vpl_quiet(&scene, &accel, &opts)
}

/// The indirect light of ring, bunny and dragon (vpl, `--visibility approx`, 48 px, 2 spp)
/// summed on the GPU and on the CPU. Both sides make the shadow maps on the GPU, so the VPLs
/// and their imperfect shadow maps are the same and only the sum differs. Indirect only, so
/// that direct light does not dilute the comparison. The bar is the GPU pipeline's 1 %
/// rel_rmse: the pass evaluates both BRDFs in f32 where the CPU takes the half vector and
/// 1 − a·b in f64 (`brdf_eval` against `Brdf::eval`: at most 4e-4 relative,
/// `tests/gpu_twins.rs`), and a pair whose facing test sits on a rounding edge may be taken on
/// one side only.
#[test]
fn vpl_indirect_light_summed_on_the_gpu_matches_the_cpu() {
    use interreflect::compare::metrics;
    let Some(_gpu) = common::gpu() else { return };
    for name in ["ring", "bunny", "dragon"] {
        let (cpu_img, cpu_stats) = vpl_render(name, true);
        let (gpu_img, gpu_stats) = vpl_render(name, false);
        assert_eq!(cpu_stats.indirect_on, "cpu", "{name}");
        assert!(
            gpu_stats.indirect_on.starts_with("gpu ("),
            "{name}: {}",
            gpu_stats.indirect_on
        );
        assert_eq!(gpu_stats.vpls, cpu_stats.vpls, "{name}: the same VPLs");
        // The same pairs, but for the few on a rounding edge of a facing test.
        let pairs = |s: &VplStats| s.pairs as f64;
        let dp = (pairs(&gpu_stats) - pairs(&cpu_stats)).abs() / pairs(&cpu_stats).max(1.0);
        assert!(
            dp < 1e-3,
            "{name}: {} pairs on the GPU, {} on the CPU",
            gpu_stats.pairs,
            cpu_stats.pairs
        );
        // Not vacuous: the scenes have indirect light.
        let mean = cpu_img.data.iter().map(|p| p.y as f64).sum::<f64>() / cpu_img.data.len() as f64;
        assert!(mean > 0.0, "{name}: no indirect light");
        let m = metrics(&gpu_img, &cpu_img).unwrap();
        eprintln!(
            "{name}: VPL sum on the GPU against the CPU, rel_rmse {:.4} %, pairs {} / {}; GPU {:.2} s, CPU {:.2} s",
            100.0 * m.rel_rmse,
            gpu_stats.pairs,
            cpu_stats.pairs,
            gpu_stats.seconds.gpu_shading,
            cpu_stats.seconds.shading
        );
        assert!(m.rel_rmse < 0.01, "{name}: rel_rmse {}", m.rel_rmse);
    }
}

/// As a user runs it: `render --method vpl --visibility approx --device gpu` sums the VPLs on
/// the GPU and says so in the log (`vpl.indirect_on`); `--visibility vsm` (shadow rays between
/// VPLs and receivers) sums on the CPU with one notice saying why.
#[test]
fn render_sums_the_vpls_on_the_gpu_when_asked_and_says_so() {
    let Some(_gpu) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/ring.toml");
    let run = |visibility: &str| {
        common::render_cli(
            dir.path(),
            scene,
            visibility,
            &[
                "--method",
                "vpl",
                "--visibility",
                visibility,
                "--device",
                "gpu",
                "--width",
                "16",
                "--spp",
                "1",
            ],
        )
    };
    let (stderr, log) = run("approx");
    assert!(!stderr.contains("notice:"), "{stderr}");
    let on = log["vpl"]["indirect_on"].as_str().unwrap_or_default();
    assert!(on.starts_with("gpu ("), "{}", log["vpl"]);
    assert!(log["vpl"]["pairs"].as_u64().unwrap() > 0);
    // The PNG is tonemapped on the GPU too.
    let tm = log["tonemap_on"].as_str().unwrap_or_default();
    assert!(tm.starts_with("gpu ("), "{tm}");

    let (stderr, log) = run("vsm");
    let notices = common::notices(&stderr);
    assert_eq!(notices.len(), 1, "{stderr}");
    assert!(
        notices[0].contains("only with --visibility approx"),
        "{stderr}"
    );
    assert_eq!(log["vpl"]["indirect_on"], "cpu", "{}", log["vpl"]);
}

/// `--device auto` sums the VPLs on the GPU (and computes the direct light there) once the sum
/// has at least `AUTO_GPU_MIN_PAIRS` sample–VPL pairs, where lavapipe is measured faster than
/// the CPU, and says so; a smaller sum stays on the CPU. The ring at 16 px and 1 spp has
/// 200 × 256 = 51,200 pairs, at 192 px and 4 spp 200 × 147,456 = 29.5 million.
#[test]
fn auto_sums_large_vpl_renders_on_the_gpu() {
    use interreflect::render::cpu::vpl::AUTO_GPU_MIN_PAIRS;
    let Some(_gpu) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/ring.toml");
    let run = |name: &str, width: &str, spp: &str| {
        let args = ["--method", "vpl", "--width", width, "--spp", spp];
        common::render_cli(dir.path(), scene, name, &args)
    };
    let samples = |log: &serde_json::Value| {
        ["width", "height", "spp"]
            .iter()
            .map(|k| log[k].as_u64().unwrap_or(0))
            .product::<u64>()
    };
    let (stderr, log) = run("small", "16", "1");
    assert!(samples(&log) * 200 < AUTO_GPU_MIN_PAIRS, "{}", log["width"]);
    assert_eq!(log["vpl"]["indirect_on"], "cpu", "{}", log["vpl"]);
    assert_eq!(log["vpl"]["direct_on"], "cpu", "{}", log["vpl"]);
    assert!(!stderr.contains("notice:"), "{stderr}");
    let (stderr, log) = run("large", "192", "4");
    assert!(
        samples(&log) * 200 >= AUTO_GPU_MIN_PAIRS,
        "{}",
        log["width"]
    );
    for stage in ["indirect_on", "direct_on"] {
        let on = log["vpl"][stage].as_str().unwrap_or_default();
        assert!(on.starts_with("gpu ("), "{stage}: {}", log["vpl"]);
    }
    assert_eq!(log["vpl"]["auto_gpu"], true, "{}", log["vpl"]);
    assert!(!stderr.contains("notice:"), "{stderr}");
    // The VPLs' weights and maps stay on the CPU under auto (slower on lavapipe).
    assert_eq!(log["vpl"]["ism_on"], "cpu", "{}", log["vpl"]);
    assert_eq!(log["vpl"]["vpls_on"], "cpu", "{}", log["vpl"]);
}
