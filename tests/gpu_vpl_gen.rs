//! VPL generation's per-triangle weights on the GPU (`render::gpu::vpl_gen`,
//! `shaders/vpl_gen.wgsl`) against their CPU twin (`precompute::vpl::source_weights` with the
//! light's variance shadow map), on the evaluation scenes and the ring under a spot and a
//! directional light; and the VPLs drawn from either. lavapipe in CI; `CI=true` makes a missing
//! adapter a failure.

mod common;

use interreflect::precompute::vpl;
use interreflect::render::cpu::sg::light_fraction;
use interreflect::render::cpu::surface::ray_epsilon;
use interreflect::visibility::vsm::VarianceShadowMap;

/// The weights on both sides agree triangle by triangle. They are the same f32 formulas —
/// `Light::incident`, the lit side's normal, the area, the albedo's luminance, and the shadow
/// map's Chebyshev bound at the same offset point (`VarianceShadowMap::lit`, which the direct
/// pass's test holds to 2e-7) — except that the CPU normalises the normal by a reciprocal
/// square root: measured 5.7e-7 relative at most, allowed 1e-4 (of the weight, plus 1e-6
/// of the largest weight for triangles whose weight is nearly 0). A triangle whose lit side
/// sits on a rounding edge may be lit on one side only: none measured, allowed 0.01 %. The VPLs
/// drawn from the two sets of weights (200 per light) are then the same points, but where a
/// random number falls on a boundary of the cumulative weights that rounding moved: none
/// measured, allowed 2 of 200.
#[test]
fn gpu_weights_and_vpls_match_the_cpu() {
    let Some(gpu) = common::gpu() else { return };
    for (name, scene, accel) in common::light_cases() {
        let light = scene.lights[0];
        let map =
            VarianceShadowMap::build(&accel, scene.mesh.bounds(), &light, &scene.settings.vsm);
        let eps = ray_epsilon(&scene);
        let visible = |p| light_fraction(&accel, &light, Some(&map), p, eps);
        let sources = vpl::sources(&scene);
        let cpu = vpl::source_weights(&sources, &light, &visible);
        let g = interreflect::render::gpu::vpl_gen::source_weights(
            &gpu,
            &sources,
            &light,
            Some(&map),
            eps,
        )
        .unwrap();
        assert_eq!(cpu.len(), g.len(), "{name}");
        let max = cpu.iter().copied().fold(0.0, f32::max);
        assert!(max > 0.0, "{name}: nothing is lit");
        let zero_mismatch = cpu
            .iter()
            .zip(&g)
            .filter(|(c, g)| (**c == 0.0) != (**g == 0.0))
            .count();
        let worst = cpu
            .iter()
            .zip(&g)
            .map(|(c, g)| (c - g).abs() / (c.abs() + 1e-2 * max))
            .fold(0.0, f32::max);
        let off = cpu
            .iter()
            .zip(&g)
            .filter(|(c, g)| (*c - *g).abs() > 1e-4 * c.abs() + 1e-6 * max)
            .count();
        // The map is read: shadowed triangles weigh less than with the light unshadowed.
        let unshadowed = vpl::source_weights(&sources, &light, &|_| 1.0);
        let shadowed = unshadowed
            .iter()
            .zip(&g)
            .filter(|(u, g)| **g < 0.99 * **u)
            .count();
        eprintln!(
            "{name}: {} triangles, {off} weights off by more than 1e-4, worst {worst:.1e}, {zero_mismatch} lit on one side only, {shadowed} shadowed",
            cpu.len()
        );
        assert!(
            off == 0,
            "{name}: {off} weights differ by more than 1e-4 (worst {worst:e})"
        );
        assert!(
            zero_mismatch as f64 <= 1e-4 * cpu.len() as f64,
            "{name}: {zero_mismatch} triangles lit on one side only"
        );
        assert!(
            shadowed > cpu.len() / 100,
            "{name}: only {shadowed} triangles are shadowed"
        );
        let from_cpu = vpl::generate(&sources, &light, 200, 7, &visible);
        let from_gpu = vpl::generate_weighted(&sources, &g, &light, 200, 7, &visible);
        assert_eq!(from_cpu.len(), from_gpu.len(), "{name}");
        let moved = from_cpu
            .iter()
            .zip(&from_gpu)
            .filter(|(a, b)| a.tri != b.tri || (a.position - b.position).length() > 1e-5)
            .count();
        eprintln!("{name}: {moved} of 200 VPLs moved");
        assert!(moved <= 2, "{name}: {moved} of 200 VPLs moved");
    }
}

/// As a user runs it: `render --method vpl --device gpu` computes the VPLs' weights on the GPU
/// and says so in the JSON log (`vpl.vpls_on`); `--device cpu` and `--visibility exact`
/// (shadow rays, no maps) keep them on the CPU.
#[test]
fn render_computes_vpl_weights_on_the_gpu_when_asked_and_says_so() {
    let Some(_gpu) = common::gpu() else { return };
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/ring.toml");
    let run = |name: &str, method: &str, visibility: &str, device: &str| {
        common::render_cli(
            dir.path(),
            scene,
            name,
            &[
                "--method",
                method,
                "--visibility",
                visibility,
                "--device",
                device,
                "--indirect-only",
                "--width",
                "16",
                "--spp",
                "1",
            ],
        )
        .1
    };
    let log = run("vpl-gpu", "vpl", "approx", "gpu");
    let on = log["vpl"]["vpls_on"].as_str().unwrap_or_default();
    assert!(on.starts_with("gpu ("), "{}", log["vpl"]);
    let log = run("vpl-cpu", "vpl", "approx", "cpu");
    assert_eq!(log["vpl"]["vpls_on"], "cpu", "{}", log["vpl"]);
    let log = run("vpl-exact", "vpl", "exact", "gpu");
    assert_eq!(log["vpl"]["vpls_on"], "cpu", "{}", log["vpl"]);
}
