//! `interreflect bench`: the performance suite (`docs/bench.md`), written to
//! `<out>/bench.md` with plots in `<out>/bench/`. Scene-level measurements run
//! `interreflect render` as child processes and read their JSON logs (each its own process, so
//! its time is its own); the kernel throughputs run in this process, single-threaded.

use anyhow::{Context, bail};
use interreflect::compare::metrics;
use interreflect::compare::plot::{self, PALETTE, Plot, Series};
use interreflect::fsutil::write_bytes_atomic;
use interreflect::image::{read_exr, write_png_rgb8};
use interreflect::math::spherical_triangle::{benchmark_inputs, integrate_sg};
use serde_json::Value;
use std::fmt::Write as _;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Where bench.md and bench/ go.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// A fast smoke version: the two smallest dragons, tiny images, short kernel loops.
    #[arg(long)]
    pub quick: bool,
    /// Only the GPU pipeline against its CPU twin, written to <out>/gpu.md (docs/gpu.md).
    #[arg(long)]
    pub gpu: bool,
}

/// The dragon at each resolution: scene file and label.
const DRAGONS: [(&str, &str); 4] = [
    ("scenes/dragon-11k.toml", "dragon-11k"),
    ("scenes/dragon-48k.toml", "dragon-48k"),
    ("scenes/dragon.toml", "dragon (202k)"),
    ("scenes/dragon-871k.toml", "dragon-871k"),
];

struct Rendered {
    log: Value,
    exr: PathBuf,
}

fn render(exe: &Path, work: &Path, name: &str, args: &[&str]) -> anyhow::Result<Rendered> {
    let exr = work.join(format!("{name}.exr"));
    let log = super::child::render(exe, args, &exr, true)?;
    Ok(Rendered { log, exr })
}

fn f(v: &Value, path: &[&str]) -> f64 {
    let mut v = v;
    for k in path {
        v = &v[*k];
    }
    v.as_f64().unwrap_or(f64::NAN)
}

/// Calls per second of `call` over `inputs`, timed for at least `min_seconds` (the best of
/// three such rounds, to stay clear of interruptions by other processes).
fn throughput<T>(inputs: &[T], min_seconds: f64, mut call: impl FnMut(&T) -> f32) -> f64 {
    let mut best = 0.0f64;
    for _ in 0..3 {
        let t0 = Instant::now();
        let mut calls = 0u64;
        let mut sink = 0.0f32;
        while t0.elapsed().as_secs_f64() < min_seconds {
            for x in inputs {
                sink += call(black_box(x));
            }
            calls += inputs.len() as u64;
        }
        black_box(sink);
        best = best.max(calls as f64 / t0.elapsed().as_secs_f64());
    }
    best
}

fn scaling_plot(title: &str, y_label: &str, series: Vec<(String, Vec<(f64, f64)>)>) -> Plot {
    Plot {
        title: title.into(),
        x_label: "reflector triangles".into(),
        y_label: y_label.into(),
        log_x: true,
        log_y: true,
        series: series
            .into_iter()
            .enumerate()
            .map(|(i, (label, points))| Series {
                label,
                color: PALETTE[i % PALETTE.len()],
                dashed: false,
                markers: true,
                points,
            })
            .collect(),
        ..Plot::default()
    }
}

pub fn run(args: BenchArgs) -> anyhow::Result<i32> {
    if args.gpu {
        return gpu_bench(&args);
    }
    let (exe, work, plots) = bench_dirs(&args.out, "bench", "bench")?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let t_all = Instant::now();
    let mut md = String::new();
    let _ = writeln!(md, "# Performance\n");
    let _ = writeln!(
        md,
        "Written by `interreflect bench{}` (`docs/bench.md`) on {} with {threads} hardware \
         threads, no GPU (wgpu on lavapipe, Mesa's software Vulkan). Times are wall-clock; each \
         scene-level figure is one render in its own process, read from its JSON log.\n",
        if args.quick { " --quick" } else { "" },
        interreflect::report::cpu_model()
    );

    // 1. Tree build and frame time against triangle count.
    let (w, points_w) = if args.quick {
        ("32", "8")
    } else {
        ("64", "16")
    };
    let dragons: Vec<(&str, &str)> = DRAGONS
        .iter()
        .copied()
        .take(if args.quick { 2 } else { 4 })
        .collect();
    let mut rows = Vec::new();
    let mut missing = Vec::new();
    for (scene, label) in &dragons {
        if *scene == "scenes/dragon-871k.toml"
            && !Path::new("scenes/models/dragon-871k.ply.gz").is_file()
        {
            missing.push(*label);
            continue;
        }
        eprint!("bench: {label}: sg frame at {w} px ... ");
        let r = render(
            &exe,
            &work,
            &format!("frame-{}", label.split_whitespace().next().unwrap_or(label)),
            &[
                scene,
                "--method",
                "sg",
                "--visibility",
                "exact",
                "--indirect-only",
                "--width",
                w,
                "--spp",
                "1",
            ],
        )?;
        let sg = &r.log["sg"];
        let row = (
            label.to_string(),
            sg["reflector_triangles"].as_u64().unwrap_or(0),
            sg["reflector_pieces"].as_u64().unwrap_or(0),
            f(sg, &["seconds", "tree"]),
            f(sg, &["seconds", "lighting"]),
            f(sg, &["seconds", "shading"]),
            f(&r.log, &["seconds", "render"]),
            f(sg, &["cut_size_mean"]),
        );
        eprintln!("{:.2} s", row.6);
        rows.push(row);
    }
    let _ = writeln!(md, "## Tree build and frame time against triangle count\n");
    let _ = writeln!(
        md,
        "`render <dragon> --method sg --visibility exact --indirect-only --width {w} --spp 1`: the default cut (1 %, \
         1000 nodes), exact visibility, floor and wall included in the reflectors.\n"
    );
    let _ = writeln!(
        md,
        "| model | reflector triangles | pieces | tree build | lighting | shading | frame | cut mean |\n|---|---|---|---|---|---|---|---|"
    );
    for r in &rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.3} s | {:.3} s | {:.2} s | {:.2} s | {:.0} |",
            r.0, r.1, r.2, r.3, r.4, r.5, r.6, r.7
        );
    }
    for m in &missing {
        let _ = writeln!(
            md,
            "\n{m} is not measured: its model is fetched by `scripts/fetch-models.sh`."
        );
    }
    if let (Some(a), Some(b)) = (rows.first(), rows.last())
        && rows.len() > 1
    {
        let _ = writeln!(
            md,
            "\nFrom {} to {} reflector triangles ({:.0}×) the frame time grows {:.1}× and the \
             shading (the cut) {:.1}×; the tree build, O(n log n) and done once per scene, grows \
             {:.0}×.\n",
            a.1,
            b.1,
            b.1 as f64 / a.1 as f64,
            b.6 / a.6,
            b.5 / a.5,
            b.3 / a.3
        );
    }
    let series = vec![
        (
            "frame".to_string(),
            rows.iter().map(|r| (r.1 as f64, r.6)).collect(),
        ),
        (
            "shading (cut)".to_string(),
            rows.iter().map(|r| (r.1 as f64, r.5)).collect(),
        ),
        (
            "tree build".to_string(),
            rows.iter().map(|r| (r.1 as f64, r.3)).collect(),
        ),
        (
            "lighting".to_string(),
            rows.iter().map(|r| (r.1 as f64, r.4)).collect(),
        ),
    ];
    let raster = plot::render(
        &scaling_plot(
            "sg on the dragon: time against triangle count",
            "seconds",
            series,
        ),
        720,
        480,
    );
    write_png_rgb8(
        &plots.join("scaling.png"),
        raster.width,
        raster.height,
        &raster.pixels,
    )?;
    let _ = writeln!(md, "<img src=\"bench/scaling.png\" width=\"640\">\n");

    // 2. Cut against brute force.
    let _ = writeln!(md, "## Cut against brute force\n");
    let _ = writeln!(
        md,
        "`--method sg` (default cut) against `--method sg-brute` (every reflector piece) at \
         {points_w} px wide, 1 spp, indirect only: shading time and the cut's error against \
         brute force.\n"
    );
    let _ = writeln!(
        md,
        "| model | sg shading | sg-brute shading | speed-up | sg against sg-brute (rel_rmse) |\n|---|---|---|---|---|"
    );
    let brute_models: Vec<(&str, &str)> = dragons
        .iter()
        .copied()
        .filter(|(s, _)| *s != "scenes/dragon-871k.toml")
        .take(if args.quick { 1 } else { 3 })
        .collect();
    for (scene, label) in &brute_models {
        let stem = label.split_whitespace().next().unwrap_or(label).to_string();
        eprint!("bench: {label}: sg against sg-brute at {points_w} px ... ");
        let common = [*scene, "--indirect-only", "--width", points_w, "--spp", "1"];
        let sg = render(
            &exe,
            &work,
            &format!("cut-{stem}"),
            &[&common[..], &["--method", "sg", "--visibility", "exact"]].concat(),
        )?;
        let bf = render(
            &exe,
            &work,
            &format!("brute-{stem}"),
            &[
                &common[..],
                &["--method", "sg-brute", "--visibility", "exact"],
            ]
            .concat(),
        )?;
        let (ts, tb) = (
            f(&sg.log, &["sg", "seconds", "shading"]),
            f(&bf.log, &["sg", "seconds", "shading"]),
        );
        let m = metrics(&read_exr(&sg.exr)?, &read_exr(&bf.exr)?)?;
        eprintln!("{:.0}×", tb / ts);
        let _ = writeln!(
            md,
            "| {label} | {ts:.2} s | {tb:.1} s | {:.0}× | {:.1} % |",
            tb / ts,
            100.0 * m.rel_rmse
        );
    }
    md.push('\n');

    // 3. The kernel against the machine's exp.
    eprintln!("bench: integrate_sg and exp throughput");
    let secs = if args.quick { 0.05 } else { 0.5 };
    let inputs = benchmark_inputs(&[1.0, 10.0, 100.0, 1000.0, 10000.0]);
    let integrals = throughput(&inputs, secs, |&(p, l, a, b, c)| {
        integrate_sg(p, l, a, b, c)
    });
    let xs: Vec<f32> = (0..4096).map(|i| -(i as f32) * 0.01).collect();
    let exps = throughput(&xs, secs, |&x| x.exp());
    let xs64: Vec<f64> = xs.iter().map(|&x| x as f64).collect();
    let exps64 = throughput(&xs64, secs, |&x| x.exp() as f32);
    let _ = writeln!(md, "## The SG integral against the machine's exp\n");
    let _ = writeln!(
        md,
        "One thread. `integrate_sg` over the benchmark table of `math::spherical_triangle::\
         benchmark_inputs` (45 configurations: λ from 1 to 10⁴; small, medium and large \
         triangles; the axis inside, beside and away), against `f32::exp` and `f64::exp` in the same run.\n"
    );
    let _ = writeln!(
        md,
        "| kernel | calls per second | ns per call |\n|---|---|---|\n| `f32::exp` | {:.3e} | {:.2} |\n| `f64::exp` | {:.3e} | {:.2} |\n| `integrate_sg` | {:.3e} | {:.1} |\n",
        exps,
        1e9 / exps,
        exps64,
        1e9 / exps64,
        integrals,
        1e9 / integrals
    );
    let _ = writeln!(
        md,
        "One SG integral costs as much as {:.0} f64 exps. Its default scheme evaluates the \
         closed radial part (an `exp_m1`) at 5 Gauss–Legendre nodes on every piece of each of \
         the three edges, in f64: on a non-degenerate triangle at least 15 exponentials, \
         {:.0} ns at the f64 exp's rate here, the floor the exponentials alone set. The rest \
         is per-edge geometry: the decomposition around the axis (atan2, square roots) and the \
         pieces' boundaries; the quadrature nodes themselves need no trigonometry \
         (`docs/sg-math.md`).\n",
        exps64 / integrals,
        15.0e9 / exps64
    );

    // 4. The reference's paths per second.
    let _ = writeln!(md, "## The reference renderer\n");
    let _ = writeln!(
        md,
        "`render <scene> --method reference --indirect-only` at {w} px, {} spp, all threads: \
         camera paths (each with its light paths) per second.\n",
        if args.quick { 4 } else { 64 }
    );
    let _ = writeln!(
        md,
        "| scene | paths per second | rays per second |\n|---|---|---|"
    );
    for scene in [
        "scenes/ring.toml",
        "scenes/bunny.toml",
        "scenes/dragon.toml",
    ] {
        let stem = Path::new(scene)
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        eprint!("bench: reference on {stem} ... ");
        let spp = if args.quick { "4" } else { "64" };
        let r = render(
            &exe,
            &work,
            &format!("reference-{stem}"),
            &[
                scene,
                "--method",
                "reference",
                "--indirect-only",
                "--width",
                w,
                "--spp",
                spp,
            ],
        )?;
        let (p, ry) = (
            f(&r.log, &["paths_per_second"]),
            f(&r.log, &["rays_per_second"]),
        );
        eprintln!("{:.2} M paths/s", p / 1e6);
        let _ = writeln!(md, "| {stem} | {:.2} M | {:.2} M |", p / 1e6, ry / 1e6);
    }
    md.push('\n');

    // 5. GPU against its CPU twin: PRT relighting, the one pass on the GPU so far.
    let _ = writeln!(md, "## GPU against its CPU twin\n");
    let _ = writeln!(
        md,
        "PRT relighting (`shaders/prt_relight.wgsl` against `precompute::prt::relight_cpu`), the \
         pass that runs on the GPU so far, with the transfer cached: the same transfer relit \
         with `--device gpu` and `--device cpu`.\n"
    );
    let _ = writeln!(
        md,
        "| scene | vertices | GPU relight | CPU relight | CPU ÷ GPU | adapter |\n|---|---|---|---|---|---|"
    );
    for scene in [
        "scenes/prt/bunny-diffuse-env.toml",
        "scenes/prt/ring-diffuse-env.toml",
    ] {
        let stem = Path::new(scene)
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        eprint!("bench: prt relight on {stem} ... ");
        let cache = work.join("prt-cache");
        let cache_s = cache.to_string_lossy().to_string();
        let base = [
            scene,
            "--method",
            "prt",
            "--width",
            w,
            "--spp",
            "1",
            "--prt-cache",
            &cache_s,
        ];
        // The first render computes the transfer (or finds it cached).
        let g = render(
            &exe,
            &work,
            &format!("prt-gpu-{stem}"),
            &[&base[..], &["--device", "gpu"]].concat(),
        );
        let g = match g {
            Ok(g) => g,
            Err(e) => {
                eprintln!("no GPU: {e}");
                let _ = writeln!(md, "| {stem} | — | no GPU adapter: {e} | | | |");
                continue;
            }
        };
        let c = render(
            &exe,
            &work,
            &format!("prt-cpu-{stem}"),
            &[&base[..], &["--device", "cpu"]].concat(),
        )?;
        let (tg, tc) = (
            f(&g.log, &["prt", "seconds", "relight"]),
            f(&c.log, &["prt", "seconds", "relight"]),
        );
        eprintln!("CPU ÷ GPU {:.2}", tc / tg);
        let _ = writeln!(
            md,
            "| {stem} | {} | {:.2} ms | {:.2} ms | {:.2}× | {} |",
            g.log["prt"]["vertices"].as_u64().unwrap_or(0),
            tg * 1e3,
            tc * 1e3,
            tc / tg,
            g.log["prt"]["adapter"].as_str().unwrap_or("?")
        );
    }
    let _ = writeln!(
        md,
        "\nOn lavapipe the GPU is a software rasteriser on the same cores, so a pass this small \
         is dominated by dispatch and read-back.\n"
    );
    // The point light's shadow map: rasterised on the GPU against ray-cast on the CPU.
    let _ = writeln!(
        md,
        "Variance shadow maps (512² faces, blur radius 2) of each scene's point light (six \
         faces) and, on the ring, of a 20° spot and a directional light in its place (one \
         perspective face, one orthographic face): `render::gpu::vsm::ShadowMapper` \
         (rasterised, `shaders/vsm.wgsl` + \
         `shaders/vsm_blur.wgsl`, read back to the CPU) against its twin \
         `VarianceShadowMap::build` (a ray per texel through the BVH, all threads), in this \
         process, best of three. The wall time includes uploads, dispatch and read-back; the \
         passes' own GPU time comes from timestamp queries.\n"
    );
    let _ = writeln!(
        md,
        "| scene, light | triangles | GPU setup (compile, upload; once) | GPU per map (wall) | of which GPU passes: raster / blur (timestamps) | CPU per map | CPU ÷ GPU per map |\n|---|---|---|---|---|---|---|"
    );
    // (wall, blur timestamps) at blur radius 2 and 8 on the first scene, to check the timestamps.
    let mut radius_check: Option<[(f64, f64); 2]> = None;
    match interreflect::render::gpu::Gpu::new() {
        Ok(gpu) => {
            for scene in [
                "scenes/ring.toml",
                "scenes/bunny.toml",
                "scenes/dragon.toml",
            ] {
                eprint!("bench: shadow map of {scene} ... ");
                let sc = interreflect::scene::Scene::load(Path::new(scene))?;
                let accel = interreflect::accel::Accel::build(&sc.mesh.positions, &sc.mesh.indices);
                let opts = interreflect::visibility::vsm::VsmOptions {
                    resolution: 512,
                    blur: 2,
                    light_bleeding: 0.2,
                };
                let mut lights = vec![("point", sc.lights[0])];
                if let interreflect::scene::Light::Point {
                    position,
                    intensity,
                } = sc.lights[0]
                    && sc.name == "ring"
                {
                    let (lo, hi) = sc.mesh.bounds();
                    let direction = (0.5 * (lo + hi) - position).normalize();
                    lights.push((
                        "spot",
                        interreflect::scene::Light::Spot {
                            position,
                            direction,
                            intensity,
                            cos_cone: 20f32.to_radians().cos(),
                            cos_falloff: 12f32.to_radians().cos(),
                        },
                    ));
                    lights.push((
                        "directional",
                        interreflect::scene::Light::Directional {
                            direction,
                            irradiance: glam::Vec3::splat(2.4),
                        },
                    ));
                }
                for (kind, light) in lights {
                    let mut map = None;
                    let tc = best_of_three(&mut || {
                        map = Some(interreflect::visibility::vsm::VarianceShadowMap::build(
                            &accel,
                            sc.mesh.bounds(),
                            &light,
                            &opts,
                        ))
                    });
                    let Some(setup) = map.as_ref().map(|m| m.setup()) else {
                        continue;
                    };
                    let t0 = Instant::now();
                    let mapper = interreflect::render::gpu::vsm::ShadowMapper::new(
                        &gpu,
                        &sc.mesh.positions,
                        &sc.mesh.indices,
                    )
                    .map_err(|e| anyhow::anyhow!("shadow map on the GPU: {e}"))?;
                    let t_setup = t0.elapsed().as_secs_f64();
                    let mut err = None;
                    let mut passes: Option<interreflect::render::gpu::vsm::PassTimes> = None;
                    let tg =
                        best_of_three(&mut || match mapper.map_moments_timed(&setup, opts.blur) {
                            Ok((_, t)) => {
                                if let Some(t) = t
                                    && passes.is_none_or(|p| t.raster + t.blur < p.raster + p.blur)
                                {
                                    passes = Some(t);
                                }
                            }
                            Err(e) => err = Some(e.to_string()),
                        });
                    if let Some(e) = err {
                        bail!("shadow map on the GPU: {e}");
                    }
                    if radius_check.is_none() {
                        let at = |radius: u32| -> anyhow::Result<(f64, f64)> {
                            let mut out = (f64::INFINITY, f64::NAN);
                            for _ in 0..3 {
                                let t = Instant::now();
                                let (_, p) = mapper
                                    .map_moments_timed(&setup, radius)
                                    .map_err(|e| anyhow::anyhow!("shadow map on the GPU: {e}"))?;
                                let wall = t.elapsed().as_secs_f64();
                                if wall < out.0 {
                                    out = (wall, p.map_or(f64::NAN, |p| p.blur));
                                }
                            }
                            Ok(out)
                        };
                        radius_check = Some([at(2)?, at(8)?]);
                    }
                    eprintln!("{kind}: CPU ÷ GPU {:.2}", tc / tg);
                    let stages = passes
                        .map(|p| format!("{:.1} / {:.1} ms", p.raster * 1e3, p.blur * 1e3))
                        .unwrap_or_else(|| "no timestamps".into());
                    let _ = writeln!(
                        md,
                        "| {}, {kind} | {} | {:.0} ms | {:.0} ms | {stages} | {:.0} ms | {:.2}× |",
                        sc.name,
                        sc.mesh.indices.len(),
                        t_setup * 1e3,
                        tg * 1e3,
                        tc * 1e3,
                        tc / tg
                    );
                }
            }
        }
        Err(e) => {
            let _ = writeln!(md, "| — | | no GPU adapter: {e} | | | | |");
        }
    }
    if let Some([(w2, b2), (w8, b8)]) = radius_check {
        let _ = writeln!(
            md,
            "\nCheck of the timestamps (ring, best of three): raising the blur's radius from 2 to \
             8 takes the wall time per map from {:.0} to {:.0} ms and the blur's timestamps from \
             {:.1} to {:.1} ms. Where the timestamps grow far less than the wall time, the \
             driver's timestamps do not bracket its compute work (lavapipe's do not), and the \
             wall time is the figure to trust; on a hardware GPU the timestamps are the passes' \
             own time.",
            w2 * 1e3,
            w8 * 1e3,
            b2 * 1e3,
            b8 * 1e3
        );
    }
    ism_section(&mut md)?;
    md.push('\n');
    let _ = writeln!(
        md,
        "The whole suite took {:.0} s. Kernel micro-benchmarks: `cargo bench --bench sg` and \
         `cargo bench --bench cut` (divan).",
        t_all.elapsed().as_secs_f64()
    );
    write_page(&args.out.join("bench.md"), &md, t_all)
}

/// The shortest of three timed calls of `f`, in seconds.
fn best_of_three(f: &mut dyn FnMut()) -> f64 {
    (0..3)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The VPLs' imperfect shadow maps splatted on the GPU (`render::gpu::ism`) against their CPU
/// twin, with the point sampling both share timed on its own.
fn ism_section(md: &mut String) -> anyhow::Result<()> {
    use interreflect::visibility::ism::{ImperfectShadowMaps, IsmSampler};
    use rayon::prelude::*;
    let _ = writeln!(
        md,
        "\nImperfect shadow maps of each scene's 200 VPLs at the scene's settings (32² texels, \
         4096 points per map, blurred): `render::gpu::ism::build` (`shaders/ism.wgsl`: \
         projection, nearest layers, pull-push, blur; read back) against its twin \
         `ImperfectShadowMaps::build` (all threads), in this process, best of three after one \
         warm-up. Both sample the points on the CPU with the same `IsmSampler`, timed alone in \
         the third column and included in both sides.\n"
    );
    let _ = writeln!(
        md,
        "| scene | maps × points | point sampling (CPU, both sides) | CPU maps | GPU maps (wall) | CPU ÷ GPU |\n|---|---|---|---|---|---|"
    );
    let gpu = match interreflect::render::gpu::Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            let _ = writeln!(md, "| — | | no GPU adapter: {e} | | | |");
            return Ok(());
        }
    };
    for scene in [
        "scenes/ring.toml",
        "scenes/bunny.toml",
        "scenes/dragon.toml",
    ] {
        eprint!("bench: imperfect shadow maps of {scene} ... ");
        let sc = interreflect::scene::Scene::load(Path::new(scene))?;
        let accel = interreflect::accel::Accel::build(&sc.mesh.positions, &sc.mesh.indices);
        let light = sc.lights[0];
        let map = interreflect::visibility::vsm::VarianceShadowMap::build(
            &accel,
            sc.mesh.bounds(),
            &light,
            &sc.settings.vsm,
        );
        let eps = interreflect::render::cpu::surface::ray_epsilon(&sc);
        let visible =
            |p| interreflect::render::cpu::sg::light_fraction(&accel, &light, Some(&map), p, eps);
        let vpls = interreflect::precompute::vpl::generate(
            &interreflect::precompute::vpl::sources(&sc),
            &light,
            200,
            1,
            &visible,
        );
        let (pos, idx, opts) = (&sc.mesh.positions, &sc.mesh.indices, &sc.settings.ism);
        // Best of three after one warm-up.
        let best = |f: &mut dyn FnMut()| {
            f();
            best_of_three(f)
        };
        let ts = best(&mut || {
            let sampler = IsmSampler::new(pos, idx, &vpls, opts, 1);
            (0..vpls.len()).into_par_iter().for_each_init(
                || vec![None; sampler.points_per_map],
                |out, i| sampler.map_points(i, out),
            );
        });
        let tc = best(&mut || {
            ImperfectShadowMaps::build(pos, idx, &vpls, opts, 1);
        });
        let mut err = None;
        let tg = best(&mut || {
            if let Err(e) = interreflect::render::gpu::ism::build(&gpu, pos, idx, &vpls, opts, 1) {
                err = Some(e.to_string());
            }
        });
        if let Some(e) = err {
            bail!("imperfect shadow maps on the GPU: {e}");
        }
        eprintln!("CPU ÷ GPU {:.2}", tc / tg);
        let _ = writeln!(
            md,
            "| {} | {} × {} | {:.1} ms | {:.1} ms | {:.1} ms | {:.2}× |",
            sc.name,
            vpls.len(),
            opts.points_per_map,
            ts * 1e3,
            tc * 1e3,
            tg * 1e3,
            tc / tg
        );
    }
    Ok(())
}

/// Writes a finished page atomically and says so.
fn write_page(path: &Path, md: &str, started: Instant) -> anyhow::Result<i32> {
    write_bytes_atomic(path, md.as_bytes())
        .with_context(|| format!("cannot write {}", path.display()))?;
    eprintln!(
        "wrote {} in {:.0} s",
        path.display(),
        started.elapsed().as_secs_f64()
    );
    Ok(0)
}

/// This executable (to run renders with), and `<out>/cache/<work>` and `<out>/<plots>`, created.
fn bench_dirs(out: &Path, work: &str, plots: &str) -> anyhow::Result<(PathBuf, PathBuf, PathBuf)> {
    let exe = std::env::current_exe().context("cannot find this executable to run renders")?;
    let work = out.join("cache").join(work);
    let plots = out.join(plots);
    for d in [&work, &plots] {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    Ok((exe, work, plots))
}

/// One method's GPU stage on the GPU and on the CPU: the render arguments and how to read the
/// stages from its log.
struct GpuCase {
    label: &'static str,
    method: &'static str,
    args: &'static [&'static str],
    /// Width and spp instead of the run's small ones (`None`: the small ones).
    size: Option<(&'static str, &'static str)>,
    /// The device of the CPU twin: `auto` (the same GPU shadow maps, so the same VPLs), or
    /// `cpu` where `auto` itself would take the GPU (ray-cast shadow maps, so slightly other
    /// VPLs).
    twin: &'static str,
}

const GPU_CASES: [GpuCase; 3] = [
    GpuCase {
        label: "sg",
        method: "sg",
        args: &["--visibility", "approx", "--cut", "vertex"],
        size: None,
        twin: "auto",
    },
    GpuCase {
        label: "vpl",
        method: "vpl",
        args: &["--visibility", "approx"],
        size: None,
        twin: "auto",
    },
    GpuCase {
        label: "vpl, 256 px, 4 spp",
        method: "vpl",
        args: &["--visibility", "approx"],
        size: Some(("256", "4")),
        twin: "cpu",
    },
];

/// `bench --gpu`: every per-frame stage that has a GPU pass, on the GPU (`--device gpu`) and
/// on the CPU with the same GPU shadow maps (`--device auto`), on the dragon at each
/// resolution; `<out>/gpu.md` and `<out>/gpu/frame.png`.
fn gpu_bench(args: &BenchArgs) -> anyhow::Result<i32> {
    let (exe, work, plots) = bench_dirs(&args.out, "bench-gpu", "gpu")?;
    let adapter = match interreflect::render::gpu::Gpu::new() {
        Ok(g) => g.adapter.clone(),
        Err(e) => bail!("bench --gpu needs a GPU adapter: {e}"),
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let t_all = Instant::now();
    let (w, spp) = if args.quick { ("24", "1") } else { ("64", "1") };
    let dragons: Vec<(&str, &str)> = DRAGONS
        .iter()
        .copied()
        .take(if args.quick { 2 } else { 4 })
        .collect();
    let mut md = String::new();
    let _ = writeln!(md, "# The GPU pipeline against its CPU twin\n");
    let _ = writeln!(
        md,
        "Written by `interreflect bench --gpu{}` (`docs/gpu.md`) on {} with {threads} hardware \
         threads; GPU adapter: {adapter}. Each figure is one `interreflect render` in its own \
         process, read from its JSON log: `render <dragon> --method <m> --visibility approx \
         [--cut vertex] --width {w} --spp {spp}` (direct and indirect light), with `--device \
         gpu` and with `--device auto`. Both make the point light's shadow maps on the GPU; \
         `auto` keeps the stages below on the CPU at this size (it moves vpl's sum to the GPU \
         only from 10 million sample–VPL pairs), so it is the GPU passes' CPU twin with the \
         same inputs. The rows \"vpl, 256 px, 4 spp\" render at that size (39 million pairs), \
         where `auto` would sum on the GPU; their twin is `--device cpu`, whose shadow maps are \
         ray-cast: the VPLs are drawn from other weights, so the two images differ by the \
         VPLs' noise and are not compared here (`tests/gpu_vpl.rs` compares the sums over the \
         same VPLs: at most 0.0008 % rel_rmse).\n",
        if args.quick { " --quick" } else { "" },
        interreflect::report::cpu_model()
    );
    let _ = writeln!(
        md,
        "Stages on the GPU with `--device gpu`: the shadow maps (both columns), sg's shading \
         over the vertex cuts (`sg_shade`, `sg_shade_sum`), the VPL baseline's sum (`vpl`), \
         the direct light (`direct`), the VPLs' sampling weights and imperfect shadow maps (`vpl_gen`, `ism`, vpl only) and the PNG's tonemap. The GPU stages' time is wall time \
         around the passes (gathering, uploads, dispatches, read-back); the pixel loop that \
         follows only adds up their results. \
         Per-pass GPU timestamps are not given: lavapipe's timestamps do not bracket compute \
         work (`results/bench.md` prints the check), so on this machine the wall time is the \
         figure to trust.\n"
    );
    let _ = writeln!(
        md,
        "| model | scene triangles | method | frame, CPU twin | frame, GPU | CPU ÷ GPU (frame) | pixel loop on the CPU | GPU passes (+ pixel loop) | CPU ÷ GPU (stage) | GPU against CPU (rel_rmse) |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let mut missing = Vec::new();
    let mut ratios: Vec<f64> = Vec::new();
    for case in &GPU_CASES {
        let mut cpu_pts = Vec::new();
        let mut gpu_pts = Vec::new();
        for (scene, label) in &dragons {
            if *scene == "scenes/dragon-871k.toml"
                && !Path::new("scenes/models/dragon-871k.ply.gz").is_file()
            {
                if !missing.contains(label) {
                    missing.push(*label);
                }
                continue;
            }
            let stem = label.split_whitespace().next().unwrap_or(label);
            let mut logs = Vec::new();
            let (cw, cspp) = match (case.size, args.quick) {
                (Some(size), false) => size,
                _ => (w, spp),
            };
            for device in [case.twin, "gpu"] {
                eprint!("bench: {label}: {} on {device} ... ", case.label);
                let mut a: Vec<&str> = vec![scene, "--method", case.method];
                a.extend_from_slice(case.args);
                a.extend_from_slice(&["--width", cw, "--spp", cspp, "--device", device]);
                let name = format!("{stem}-{}-{cw}-{device}", case.method);
                let r = render(&exe, &work, &name, &a)?;
                eprintln!("{:.2} s", f(&r.log, &["seconds", "render"]));
                logs.push(r);
            }
            let (c, g) = (&logs[0], &logs[1]);
            let m = &case.method;
            let on = g.log[m][if *m == "sg" {
                "shading_on"
            } else {
                "indirect_on"
            }]
            .as_str()
            .unwrap_or_default()
            .to_string();
            if !on.starts_with("gpu") {
                bail!("{label}: {} did not run on the GPU: {on}", case.label);
            }
            let frame = |r: &Rendered| f(&r.log, &["seconds", "render"]);
            let stage_cpu = f(&c.log[m], &["seconds", "shading"]);
            let (gpu_stage, gpu_loop) = (
                f(&g.log[m], &["seconds", "gpu_shading"])
                    + f(&g.log[m], &["seconds", "gpu_direct"]),
                f(&g.log[m], &["seconds", "shading"]),
            );
            let err = if case.twin == "auto" {
                metrics(&read_exr(&g.exr)?, &read_exr(&c.exr)?)
                    .map(|m| format!("{:.4} %", 100.0 * m.rel_rmse))
                    .unwrap_or_else(|e| format!("— ({e})"))
            } else {
                // Other shadow maps draw other VPLs: the images differ by the VPLs' noise.
                "— (other VPLs)".to_string()
            };
            let tris = c.log["triangles"].as_u64().unwrap_or(0);
            let _ = writeln!(
                md,
                "| {label} | {tris} | {} | {:.2} s | {:.2} s | {:.2}× | {:.2} s | {:.2} s (+ {:.2} s) | {:.2}× | {err} |",
                case.label,
                frame(c),
                frame(g),
                frame(c) / frame(g),
                stage_cpu,
                gpu_stage,
                gpu_loop,
                stage_cpu / (gpu_stage + gpu_loop),
            );
            ratios.push(stage_cpu / (gpu_stage + gpu_loop));
            cpu_pts.push((tris as f64, frame(c)));
            gpu_pts.push((tris as f64, frame(g)));
        }
        series.push((format!("{}, CPU twin", case.label), cpu_pts));
        series.push((format!("{}, GPU", case.label), gpu_pts));
    }
    for m in &missing {
        let _ = writeln!(
            md,
            "\n{m} is not measured: its model is fetched by `scripts/fetch-models.sh`."
        );
    }
    let mut plot = scaling_plot(
        "frame time on the dragon: GPU and CPU twin",
        "seconds",
        series,
    );
    plot.x_label = "scene triangles".into();
    // One colour per method, the GPU dashed.
    for (i, s) in plot.series.iter_mut().enumerate() {
        s.color = PALETTE[(i / 2) % PALETTE.len()];
        s.dashed = i % 2 == 1;
    }
    let raster = plot::render(&plot, 720, 480);
    write_png_rgb8(
        &plots.join("frame.png"),
        raster.width,
        raster.height,
        &raster.pixels,
    )?;
    let _ = writeln!(md, "\n<img src=\"gpu/frame.png\" width=\"640\">\n");
    let (lo, hi) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &r| {
        (lo.min(r), hi.max(r))
    });
    let verdict = if hi < 1.0 {
        format!(
            "On this adapter every stage is slower on the GPU than on the CPU ({lo:.2}–{hi:.2}×){}",
            if adapter.contains("llvmpipe") {
                ": lavapipe runs every branch of a shader whether or not a lane takes it \
                 (`docs/gpu.md`), where the CPU twins skip most of the work"
            } else {
                ""
            }
        )
    } else {
        format!("The stages' ratios range over {lo:.2}–{hi:.2}×")
    };
    let _ = writeln!(
        md,
        "The \"pixel loop on the CPU\" is the CPU twin's pixel loop (indirect and direct light); the \
         GPU side is the GPU passes' time (indirect and direct) plus its pixel loop, the same \
         work. The target is a GPU stage five times faster \
         than its twin. {verdict}. The whole run took {:.0} s.",
        t_all.elapsed().as_secs_f64()
    );
    write_page(&args.out.join("gpu.md"), &md, t_all)
}
