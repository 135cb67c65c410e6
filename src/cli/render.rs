//! `interreflect render`.

use super::progress;
use anyhow::{Context, bail};
use interreflect::accel::Accel;
use interreflect::fsutil::same_file;
use interreflect::image::{Tonemap, write_exr, write_png, write_png_rgb8};
use interreflect::memory::{self, Budget, Workload};
use interreflect::precompute::prt::{TransferKind, WindowKind};
use interreflect::render::checks::camera_inside_geometry;
use interreflect::render::cpu::reference::work_units;
use interreflect::render::cpu::sg::{CutMode, SgOptions, SgStats, render_sg, sg_work_units};
use interreflect::render::cpu::vpl::{VplOptions, VplStats, render_vpl};
use interreflect::render::cpu::{RenderOptions, render};
use interreflect::render::{Device, Method, Visibility};
use interreflect::scene::{
    MAX_IMAGE_SIDE, MAX_NODE_MAPS, MAX_SPP, MAX_VPLS, RenderSettings, Scene, ScenePreview,
};
use interreflect::sg::CutOptions;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Rendering method.
    #[arg(long, value_enum, default_value_t = Method::Reference)]
    pub method: Method,
    /// Visibility for sg, sg-brute and vpl (approx: variance shadow maps for the light and
    /// visibility maps at the reflector tree's nodes between reflectors and receivers, the
    /// paper's kind; vsm: the shadow maps, and shadow rays between reflectors and receivers;
    /// exact: shadow rays through the BVH, the oracle; settings in the scene's [visibility]).
    #[arg(long, value_enum, default_value_t = Visibility::Approx)]
    pub visibility: Visibility,
    /// Where sg selects cuts (default: the scene's methods.sg.cut).
    #[arg(long, value_enum)]
    pub cut: Option<CutMode>,
    /// Cut error threshold, a fraction of the estimate (default: methods.sg.threshold).
    #[arg(long, allow_negative_numbers = true)]
    pub threshold: Option<f32>,
    /// Cut size cap, 0 = none (default: methods.sg.max_cut).
    #[arg(long, allow_negative_numbers = true)]
    pub max_cut: Option<u32>,
    /// Split reflector triangles to at most this edge length for sg, 0 = never
    /// (default: methods.sg.max_edge, or 1/128 of the scene's diagonal).
    #[arg(long, allow_negative_numbers = true)]
    pub max_edge: Option<f32>,
    /// Samples per pixel (default: the scene's render.spp; methods.sg.spp for sg and sg-brute).
    #[arg(long, allow_negative_numbers = true)]
    pub spp: Option<u32>,
    /// Seed of the random streams (default: the scene's render.seed).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long, allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Image width (default: the scene's camera.width; height follows the aspect if not given).
    #[arg(long, allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Image height (default: the scene's camera.height; width follows the aspect if not given).
    #[arg(long, allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// Render only the one-bounce indirect light.
    #[arg(long)]
    pub indirect_only: bool,
    /// Output EXR; a PNG and a JSON log are written beside it
    /// (default: results/renders/<scene>.exr).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Exposure of the PNG in stops.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// No progress bar and no log lines (errors and warnings still go to stderr).
    #[arg(long, short)]
    pub quiet: bool,
    /// Where passes that have a GPU version run. `auto` (GPU when an adapter exists): prt's
    /// relighting, every light's shadow map for sg and vpl with --visibility vsm or approx, and
    /// vpl's sum and direct light with --visibility approx from 10 million sample–VPL pairs
    /// (where it is faster) up to 2 million samples. `gpu` also: sg's shading with --cut vertex and --visibility approx,
    /// vpl's sum at any size, the VPLs' weights and imperfect shadow maps, the direct light and
    /// the PNG's tonemap (slower than the CPU on a software GPU, docs/gpu.md).
    #[arg(long, value_enum, default_value_t = Device::Auto)]
    pub device: Device,
    /// prt: SH order, bands l < order (default: methods.prt.order).
    #[arg(long, allow_negative_numbers = true)]
    pub order: Option<u32>,
    /// prt: what the transfer includes (default: methods.prt.transfer).
    #[arg(long, value_enum)]
    pub transfer: Option<TransferKind>,
    /// prt: reflections of the interreflected transfer (default: methods.prt.bounces).
    #[arg(long, allow_negative_numbers = true)]
    pub bounces: Option<u32>,
    /// prt: window applied to the SH lighting (default: methods.prt.window).
    #[arg(long, value_enum)]
    pub window: Option<WindowKind>,
    /// prt: band where the window reaches zero (default: methods.prt.window_width, or twice the
    /// order).
    #[arg(long, allow_negative_numbers = true)]
    pub window_width: Option<f32>,
    /// prt: rotate the SH lighting about the up (+y) axis by this many degrees, without
    /// recomputing the transfer.
    #[arg(long, allow_hyphen_values = true)]
    pub rotate_lighting: Option<f32>,
    /// prt: directory of the transfer cache.
    #[arg(long, default_value = "results/cache/prt")]
    pub prt_cache: PathBuf,
    /// prt: neither read nor write the transfer cache.
    #[arg(long)]
    pub no_cache: bool,
    /// VPLs per light for vpl, and for sg's approximate visibility with visibility.node_maps = 0
    /// (default: visibility.vpl_count).
    #[arg(long, allow_negative_numbers = true)]
    pub vpls: Option<u32>,
    /// sg --visibility approx: the most visibility maps per light at the tree's nodes, 0 = the
    /// paper's 3 nearest VPLs instead (default: visibility.node_maps).
    #[arg(long, allow_negative_numbers = true)]
    pub node_maps: Option<u32>,
    /// vpl: clamp the geometry term at this distance, 0 = no clamp
    /// (default: methods.vpl.clamp_distance, or 1/50 of the scene's diagonal).
    #[arg(long, allow_negative_numbers = true)]
    pub clamp_distance: Option<f32>,
    /// Refuse, before loading the meshes, a render whose estimated peak memory exceeds this
    /// size (e.g. 4GiB, 512MiB; "off" = no check). Default: INTERREFLECT_MEMORY_BUDGET, or 75 %
    /// of the physical memory.
    #[arg(long, value_name = "SIZE")]
    pub memory_budget: Option<String>,
}

/// The JSON log written beside the image.
#[derive(Serialize)]
struct RenderLog<'a> {
    scene: &'a str,
    scene_file: String,
    method: Method,
    indirect_only: bool,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
    threads: usize,
    triangles: usize,
    tonemap: String,
    /// Where the PNG's pixels were tonemapped: "cpu", or "gpu (adapter)" with `--device gpu`.
    tonemap_on: String,
    seconds: Timings,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    reference: Option<ReferenceLog>,
    #[serde(skip_serializing_if = "Option::is_none")]
    sg: Option<SgLog>,
    #[serde(skip_serializing_if = "Option::is_none")]
    prt: Option<super::prt::PrtLog>,
    #[serde(skip_serializing_if = "Option::is_none")]
    vpl: Option<VplLog>,
    memory: MemoryLog,
}

/// VPL-baseline fields of the log.
#[derive(Serialize)]
struct VplLog {
    visibility: Visibility,
    vpls_per_light: u32,
    #[serde(flatten)]
    stats: VplStats,
}

/// The memory estimate checked against the budget (`interreflect::memory`).
#[derive(Serialize)]
struct MemoryLog {
    estimate_bytes: u64,
    /// `None` when the budget is off.
    budget_bytes: Option<u64>,
    /// The estimate's parts, in bytes.
    estimate: std::collections::BTreeMap<&'static str, u64>,
    /// The process's peak resident memory when the outputs were written (Linux), for
    /// comparing with the estimate.
    #[serde(skip_serializing_if = "Option::is_none")]
    peak_bytes: Option<u64>,
}

/// Reference-renderer fields of the log.
#[derive(Serialize)]
struct ReferenceLog {
    reflector_samples: u32,
    bsdf_samples: u32,
    light_paths_per_sample: u32,
    camera_paths: u64,
    light_paths: u64,
    rays: u64,
    paths_per_second: f64,
    rays_per_second: f64,
    nonfinite_samples: u64,
}

/// SG-method fields of the log.
#[derive(Serialize)]
struct SgLog {
    visibility: Visibility,
    cut_mode: CutMode,
    cut: CutOptions,
    max_edge: f32,
    #[serde(flatten)]
    stats: SgStats,
}

#[derive(Serialize, Clone, Copy, Default)]
struct Timings {
    load: f64,
    bvh: f64,
    render: f64,
    write: f64,
    total: f64,
}

/// Largest accepted `--exposure`, in stops either way (2⁶⁴ is far past any image).
const MAX_EXPOSURE: f32 = 64.0;

/// Image size from the flags and the camera's size, unchecked.
fn requested_size(args: &RenderArgs, cw: u32, ch: u32) -> (u32, u32) {
    let (cw, ch) = (cw.max(1), ch.max(1));
    match (args.width, args.height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (
            w,
            ((w as u64 * ch as u64 + cw as u64 / 2) / cw as u64).max(1) as u32,
        ),
        (None, Some(h)) => (
            ((h as u64 * cw as u64 + ch as u64 / 2) / ch as u64).max(1) as u32,
            h,
        ),
        (None, None) => (cw, ch),
    }
}

fn resolve_size(args: &RenderArgs, scene: &Scene) -> anyhow::Result<(u32, u32)> {
    let (w, h) = requested_size(args, scene.camera.width, scene.camera.height);
    for (name, v) in [("--width", w), ("--height", h)] {
        if v == 0 || v > MAX_IMAGE_SIDE {
            bail!("{name} must be between 1 and {MAX_IMAGE_SIDE}, got {v}");
        }
    }
    Ok((w, h))
}

/// Output EXR path, checked: ends in .exr and overwrites no input.
fn output_path(args: &RenderArgs, scene: &Scene) -> anyhow::Result<PathBuf> {
    let out = args
        .output
        .clone()
        .unwrap_or_else(|| Path::new("results/renders").join(format!("{}.exr", scene.name)));
    if out
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.eq_ignore_ascii_case("exr"))
        != Some(true)
    {
        bail!(
            "--output {}: the output must be an .exr file (a .png is written beside it)",
            out.display()
        );
    }
    let png = out.with_extension("png");
    let json = out.with_extension("json");
    for o in [&out, &png, &json] {
        if o.is_dir() {
            bail!(
                "--output {}: {} is a directory; the outputs (.exr, and .png and .json beside it) are files",
                out.display(),
                o.display()
            );
        }
    }
    // Missing directories are created when the outputs are written: the nearest existing
    // ancestor must be a directory, or they cannot be.
    let mut ancestor = out.parent();
    while let Some(a) = ancestor.filter(|a| !a.as_os_str().is_empty()) {
        if a.exists() {
            if !a.is_dir() {
                bail!(
                    "--output {}: {} is not a directory, so the output's directory cannot be created there",
                    out.display(),
                    a.display()
                );
            }
            break;
        }
        ancestor = a.parent();
    }
    for input in std::iter::once(&scene.path).chain(scene.inputs.iter()) {
        for o in [&out, &png, &json] {
            if same_file(o, input) {
                bail!(
                    "refusing to overwrite the input {} with an output",
                    input.display()
                );
            }
        }
    }
    Ok(out)
}

pub fn run(args: RenderArgs) -> anyhow::Result<i32> {
    let t0 = Instant::now();
    let mut times = Timings::default();
    if args.method == Method::Direct && args.indirect_only {
        bail!(
            "--indirect-only with --method direct would render nothing: direct renders direct light only"
        );
    }
    if let Some(0) = args.threads {
        bail!("--threads must be at least 1");
    }
    if !(args.exposure.is_finite() && args.exposure.abs() <= MAX_EXPOSURE) {
        bail!(
            "--exposure must be a finite number of stops between -{MAX_EXPOSURE} and {MAX_EXPOSURE}, got {}",
            args.exposure
        );
    }
    // Ctrl-C from here on sets a flag that every stage polls: an interrupted render exits
    // with 130 and writes nothing (outputs are written only after the last check).
    let cancel = progress::interrupt_flag();
    let budget = Budget::resolve(args.memory_budget.as_deref()).map_err(anyhow::Error::msg)?;
    // The `--method` value as typed (its name in clap's list of values).
    let method = clap::ValueEnum::to_possible_value(&args.method)
        .map(|v| v.get_name().to_string())
        .unwrap_or_default();
    let scene = Scene::load_checked(
        &args.scene,
        Some(&mut |p: &ScenePreview| {
            let (w, h) = requested_size(&args, p.camera_width, p.camera_height);
            let load = workload(
                &args,
                &p.settings,
                p.triangles,
                p.vertices,
                w as u64 * h as u64,
                p.environment_texels,
                p.lights,
            );
            let what = memory::describe_workload(&load, &method, w, h);
            budget.check(&memory::estimate(&load), &what)
        }),
    )?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let is_sg = matches!(args.method, Method::Sg | Method::SgBrute);
    if (is_sg || args.method == Method::Vpl) && scene.environment.is_some() {
        eprintln!(
            "warning: {}: environment: --method {method} ignores environment lighting (reference, direct and prt render it); the image shows the delta lights only",
            scene.path.display(),
        );
    }
    let spp = args
        .spp
        .unwrap_or_else(|| default_spp(args.method, &scene.settings));
    if spp == 0 || spp > MAX_SPP {
        bail!("--spp must be between 1 and {MAX_SPP}, got {spp}");
    }
    let seed = args.seed.unwrap_or(scene.settings.seed);
    let (width, height) = resolve_size(&args, &scene)?;
    let out = output_path(&args, &scene)?;
    // The check again with the loaded sizes (polygons, glTF meshes, the image size as resolved),
    // before the BVH is built.
    let load = workload(
        &args,
        &scene.settings,
        scene.mesh.indices.len() as u64,
        scene.mesh.positions.len() as u64,
        width as u64 * height as u64,
        scene
            .environment
            .as_ref()
            .map(|e| e.width() as u64 * e.height() as u64)
            .unwrap_or(0),
        scene.lights.len(),
    );
    let estimate = memory::estimate(&load);
    if let Err(m) = budget.check(
        &estimate,
        &memory::describe_workload(&load, &method, width, height),
    ) {
        bail!("{}: {m}", scene.path.display());
    }
    let r = scene.settings.reference;
    let sgs = scene.settings.sg;
    let cut = CutOptions {
        threshold: args.threshold.unwrap_or(sgs.threshold),
        max_cut: args.max_cut.unwrap_or(sgs.max_cut),
    };
    if !(cut.threshold.is_finite() && (0.0..=1.0).contains(&cut.threshold)) {
        bail!(
            "--threshold must be between 0 and 1 (a fraction of the estimate), got {}",
            cut.threshold
        );
    }
    let cut_mode = args.cut.unwrap_or(sgs.cut);
    let max_edge = args
        .max_edge
        .or(sgs.max_edge)
        .unwrap_or_else(|| scene.mesh.diagonal() / 128.0);
    if !(max_edge.is_finite() && max_edge >= 0.0) {
        bail!("--max-edge must be a length ≥ 0 (0 = never split), got {max_edge}");
    }
    let prt = if args.method == Method::Prt {
        Some(super::prt::settings(&args, &scene, seed)?)
    } else {
        None
    };
    let vpl_count = args.vpls.unwrap_or(scene.settings.vpl_count);
    if !(1..=MAX_VPLS).contains(&vpl_count) {
        bail!("--vpls must be between 1 and {MAX_VPLS}, got {vpl_count}");
    }
    let clamp_distance = args
        .clamp_distance
        .or(scene.settings.vpl.clamp_distance)
        .unwrap_or_else(|| interreflect::render::cpu::vpl::default_clamp_distance(&scene));
    if !(clamp_distance.is_finite() && clamp_distance >= 0.0) {
        bail!("--clamp-distance must be a length ≥ 0 (0 = no clamp), got {clamp_distance}");
    }
    let node_maps = args.node_maps.unwrap_or(scene.settings.ism.node_maps);
    if node_maps > MAX_NODE_MAPS {
        bail!("--node-maps must be between 0 and {MAX_NODE_MAPS}, got {node_maps}");
    }
    let mut scene = scene;
    scene.settings.vpl_count = vpl_count;
    scene.settings.ism.node_maps = node_maps;
    times.load = t0.elapsed().as_secs_f64();

    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(n) = args.threads {
            b = b.num_threads(n);
        }
        b.build().context("cannot start the worker threads")?
    };
    let threads = pool.current_num_threads();
    let log = |s: String| {
        if !args.quiet {
            eprintln!("{s}");
        }
    };
    log(format!(
        "scene {}: {} triangles in {} objects, {} lights{}; {:?}{} {}x{} at {} spp, seed {}, {} threads",
        scene.name,
        scene.mesh.indices.len(),
        scene.objects.len(),
        scene.lights.len(),
        scene
            .environment
            .as_ref()
            .map(|e| format!(", a {}x{} environment map", e.width(), e.height()))
            .unwrap_or_default(),
        args.method,
        if args.indirect_only {
            " (indirect only)"
        } else {
            ""
        },
        width,
        height,
        spp,
        seed,
        threads
    ));

    if cancel.load(Ordering::SeqCst) {
        return Ok(interrupted());
    }
    let t = Instant::now();
    let accel = pool.install(|| Accel::build(&scene.mesh.positions, &scene.mesh.indices));
    times.bvh = t.elapsed().as_secs_f64();
    if cancel.load(Ordering::SeqCst) {
        return Ok(interrupted());
    }
    if let Some(w) = camera_inside_geometry(&scene, &accel) {
        eprintln!("warning: {}: {w}", scene.path.display());
    }

    // --device gpu tonemaps the PNG on the GPU: without an adapter, fail before rendering
    // (prt and the shadow maps check for themselves, with their own messages).
    let checked_elsewhere = prt.is_some()
        || ((is_sg || args.method == Method::Vpl) && args.visibility != Visibility::Exact);
    if args.device == Device::Gpu && !checked_elsewhere {
        interreflect::render::gpu::Gpu::shared()
            .map_err(|e| anyhow::anyhow!("--device gpu: the PNG is tonemapped on the GPU: {e}"))?;
    }
    let t = Instant::now();
    let rendered = if let Some(prt) = &prt {
        let Some((img, prt_log)) =
            super::prt::render(&args, &scene, &accel, &pool, (width, height), spp, prt)?
        else {
            return Ok(interrupted());
        };
        (img, None, None, Some(prt_log), None, 0)
    } else if args.method == Method::Vpl {
        shadow_map_device_check(&args)?;
        ism_device_check(&args, &scene)?;
        if args.device == Device::Gpu && args.visibility != Visibility::Approx {
            eprintln!(
                "notice: vpl sums its VPLs on the GPU only with --visibility approx (the other visibilities cast shadow rays); summing on the CPU"
            );
        }
        let opts = VplOptions {
            width,
            height,
            spp,
            seed,
            direct: !args.indirect_only,
            indirect: true,
            visibility: args.visibility,
            vpl_count,
            clamp_distance,
            device: args.device,
            cpu_sum: false,
        };
        let result = progress::run(height as u64, args.quiet, |prog| {
            pool.install(|| render_vpl(&scene, &accel, &opts, prog))
        });
        let Some((img, stats)) = result else {
            return Ok(interrupted());
        };
        shadow_map_fallback(&args, &stats.shadow_maps_on)?;
        gpu_shading_fallback(&args, &stats.indirect_on)?;
        gpu_direct_fallback(&args, &stats.direct_on)?;
        gpu_vpls_fallback(&args, &stats.vpls_on)?;
        gpu_ism_fallback(&args, &stats.ism_on)?;
        log(format!(
            "vpl: {} VPLs, clamp distance {:.4} ({} of {} pairs clamped), {} visibility rays",
            stats.vpls,
            stats.clamp_distance,
            stats.clamped_pairs,
            stats.pairs,
            stats.visibility_rays
        ));
        log(format!(
            "vpl stages: shadow maps {:.2} s, VPLs {:.2} s, imperfect shadow maps {:.2} s, shading {:.2} s",
            stats.seconds.shadow_maps, stats.seconds.vpls, stats.seconds.ism, stats.seconds.shading
        ));
        if stats.auto_gpu {
            log(format!(
                "vpl: --device auto sums on the GPU: {} VPLs × {} samples, at least {} pairs",
                stats.vpls,
                u64::from(width) * u64::from(height) * u64::from(spp),
                interreflect::render::cpu::vpl::AUTO_GPU_MIN_PAIRS
            ));
        }
        if let Some(adapter) = stats.indirect_on.strip_prefix("gpu ") {
            log(format!(
                "vpl one-bounce sum on the GPU {adapter}: {:.2} s (primary hits included)",
                stats.seconds.gpu_shading
            ));
        }
        if let Some(adapter) = stats.direct_on.strip_prefix("gpu ") {
            log(format!(
                "vpl direct light on the GPU {adapter}: {:.2} s",
                stats.seconds.gpu_direct
            ));
        }
        if let Some(adapter) = stats.vpls_on.strip_prefix("gpu ") {
            log(format!(
                "vpl VPLs drawn from weights computed on the GPU {adapter}: {:.2} s",
                stats.seconds.vpls
            ));
        }
        if let Some(adapter) = stats.ism_on.strip_prefix("gpu ") {
            log(format!(
                "vpl imperfect shadow maps splatted on the GPU {adapter}: {:.2} s",
                stats.seconds.ism
            ));
        }
        let nonfinite = stats.nonfinite_samples;
        (
            img,
            None,
            None,
            None,
            Some(VplLog {
                visibility: args.visibility,
                vpls_per_light: vpl_count,
                stats,
            }),
            nonfinite,
        )
    } else if is_sg {
        shadow_map_device_check(&args)?;
        if scene.settings.ism.node_maps == 0 {
            ism_device_check(&args, &scene)?;
        }
        if args.device == Device::Gpu
            && args.method == Method::Sg
            && (cut_mode != CutMode::Vertex || args.visibility != Visibility::Approx)
        {
            eprintln!(
                "notice: sg shades its indirect light on the GPU only with --cut vertex and --visibility approx; shading on the CPU"
            );
        }
        let opts = SgOptions {
            width,
            height,
            spp,
            seed,
            direct: !args.indirect_only,
            indirect: true,
            brute: args.method == Method::SgBrute,
            cut,
            mode: cut_mode,
            max_edge,
            visibility: args.visibility,
            device: args.device,
        };
        let result = progress::run(sg_work_units(&opts), args.quiet, |prog| {
            pool.install(|| render_sg(&scene, &accel, &opts, prog))
        });
        let Some((img, stats)) = result else {
            return Ok(interrupted());
        };
        shadow_map_fallback(&args, &stats.shadow_maps_on)?;
        gpu_shading_fallback(&args, &stats.shading_on)?;
        gpu_direct_fallback(&args, &stats.direct_on)?;
        gpu_vpls_fallback(&args, &stats.vpls_on)?;
        gpu_ism_fallback(&args, &stats.ism_on)?;
        let s = &stats;
        log(format!(
            "sg: {} reflector triangles ({} pieces), {} tree nodes; cut size mean {:.1}, max {}, {} of {} cuts ended at the cap; {:.1} nodes and {:.1} triangle integrations per pixel; {} visibility rays",
            s.reflector_triangles,
            s.reflector_pieces,
            s.tree_nodes,
            s.cut_size_mean,
            s.cut_size_max,
            s.cuts_at_cap,
            s.cuts,
            s.nodes_evaluated_per_pixel,
            s.leaves_evaluated_per_pixel,
            s.visibility_rays
        ));
        log(format!(
            "sg stages: tree {:.2} s, lighting {:.2} s, visibility maps {:.2} s, primary hits {:.2} s, vertex cuts {:.2} s, tile cuts {:.2} s, shading {:.2} s",
            s.seconds.tree,
            s.seconds.lighting,
            s.seconds.vpls,
            s.seconds.primary,
            s.seconds.vertex_cuts,
            s.seconds.tile_cuts,
            s.seconds.shading
        ));
        if let Some(adapter) = s.shading_on.strip_prefix("gpu ") {
            let bytes: u64 = s.gpu_uploads.iter().map(|u| u.bytes).sum();
            log(format!(
                "sg shading on the GPU {adapter}: {:.2} s, {} nodes, {} leaves and {} maps uploaded ({:.1} MiB)",
                s.seconds.gpu_shading,
                s.gpu_uploads.iter().map(|u| u.nodes).sum::<usize>(),
                s.gpu_uploads.iter().map(|u| u.leaves).sum::<usize>(),
                s.gpu_uploads.iter().map(|u| u.maps).sum::<usize>(),
                bytes as f64 / (1u64 << 20) as f64
            ));
        }
        if let Some(adapter) = s.direct_on.strip_prefix("gpu ") {
            log(format!(
                "sg direct light on the GPU {adapter}: {:.2} s",
                s.seconds.gpu_direct
            ));
        }
        if args.visibility == Visibility::Approx {
            log(format!(
                "sg visibility: shadow maps {:.2} s; {} {:.2} s",
                s.seconds.shadow_maps,
                if s.node_maps > 0 {
                    format!("{} visibility maps at tree nodes", s.node_maps)
                } else {
                    "VPLs with imperfect shadow maps".to_string()
                },
                s.seconds.vpls
            ));
        }
        let nonfinite = stats.nonfinite_samples;
        (
            img,
            None,
            Some(SgLog {
                visibility: args.visibility,
                cut_mode,
                cut,
                max_edge,
                stats,
            }),
            None,
            None,
            nonfinite,
        )
    } else {
        let opts = RenderOptions {
            width,
            height,
            spp,
            seed,
            direct: !args.indirect_only,
            indirect: args.method == Method::Reference,
            reflector_samples: r.reflector_samples,
            bsdf_samples: r.bsdf_samples,
            light_paths: r.light_paths,
        };
        let result = progress::run(work_units(&opts), args.quiet, |prog| {
            pool.install(|| render(&scene, &accel, &opts, prog))
        });
        let Some((img, stats)) = result else {
            return Ok(interrupted());
        };
        let secs = t.elapsed().as_secs_f64().max(1e-9);
        (
            img,
            Some(ReferenceLog {
                reflector_samples: r.reflector_samples,
                bsdf_samples: r.bsdf_samples,
                light_paths_per_sample: r.light_paths,
                camera_paths: stats.camera_paths,
                light_paths: stats.light_paths,
                rays: stats.rays,
                paths_per_second: (stats.camera_paths + stats.light_paths) as f64 / secs,
                rays_per_second: stats.rays as f64 / secs,
                nonfinite_samples: stats.nonfinite_samples,
            }),
            None,
            None,
            None,
            stats.nonfinite_samples,
        )
    };
    let (img, reference_log, sg_log, prt_log, vpl_log, nonfinite) = rendered;
    times.render = t.elapsed().as_secs_f64();
    // The last check: once writing starts, all three outputs are written (each atomically).
    if cancel.load(Ordering::SeqCst) {
        return Ok(interrupted());
    }
    if nonfinite > 0 {
        eprintln!("warning: {nonfinite} samples were not finite and were dropped");
    }

    let tm = Tonemap {
        exposure: args.exposure,
        ..Tonemap::default()
    };
    let t = Instant::now();
    let png = out.with_extension("png");
    let json = out.with_extension("json");
    // All three outputs or none: a failed write removes those this run wrote before it.
    let mut written: Vec<&Path> = Vec::new();
    let remove_written = |written: &[&Path]| {
        for p in written {
            let _ = std::fs::remove_file(p);
        }
    };
    if let Err(e) = write_exr(&out, &img) {
        return Err(e.into());
    }
    written.push(&out);
    // With --device gpu the tonemap pass encodes the PNG's pixels (`render::gpu::tonemap`;
    // at most one 8-bit step from the CPU's, docs/gpu.md).
    let mut tonemap_on = "cpu".to_string();
    let written_png = if args.device == Device::Gpu {
        let pixels = interreflect::render::gpu::Gpu::shared().and_then(|gpu| {
            tonemap_on = format!("gpu ({})", gpu.adapter);
            interreflect::render::gpu::tonemap::to_srgb8(&gpu, &img, &tm)
        });
        match pixels {
            Ok(p) => write_png_rgb8(&png, img.width, img.height, &p),
            Err(e) => {
                remove_written(&written);
                anyhow::bail!("--device gpu: the PNG could not be tonemapped on the GPU: {e}");
            }
        }
    } else {
        write_png(&png, &img, &tm)
    };
    if let Err(e) = written_png {
        remove_written(&written);
        return Err(e.into());
    }
    written.push(&png);
    times.write = t.elapsed().as_secs_f64();
    times.total = t0.elapsed().as_secs_f64();
    let log_data = RenderLog {
        scene: &scene.name,
        scene_file: scene.path.display().to_string(),
        method: args.method,
        indirect_only: args.indirect_only,
        width,
        height,
        spp,
        seed,
        threads,
        triangles: scene.mesh.indices.len(),
        tonemap: tm.describe(),
        tonemap_on,
        seconds: times,
        reference: reference_log,
        sg: sg_log,
        prt: prt_log,
        vpl: vpl_log,
        memory: MemoryLog {
            estimate_bytes: estimate.total(),
            budget_bytes: budget.bytes,
            estimate: estimate.parts.iter().map(|&(n, b)| (n, b)).collect(),
            peak_bytes: memory::peak_rss(),
        },
    };
    let text = serde_json::to_string_pretty(&log_data)? + "\n";
    if let Err(e) = interreflect::fsutil::write_bytes_atomic(&json, text.as_bytes()) {
        remove_written(&written);
        return Err(anyhow::Error::new(e).context(format!("cannot write {}", json.display())));
    }
    log(format!(
        "wrote {} (linear), {} ({})",
        out.display(),
        png.display(),
        tm.describe()
    ));
    let speed = log_data
        .reference
        .as_ref()
        .map(|r| {
            format!(
                "; {:.2} M paths/s, {:.2} M rays/s",
                r.paths_per_second / 1e6,
                r.rays_per_second / 1e6
            )
        })
        .unwrap_or_default();
    log(format!(
        "time: load {:.2} s, BVH {:.2} s, render {:.2} s, write {:.2} s, total {:.2} s{speed}",
        times.load, times.bvh, times.render, times.write, times.total
    ));
    Ok(0)
}

/// The scene's sample count for `method`.
fn default_spp(method: Method, settings: &RenderSettings) -> u32 {
    match method {
        Method::Sg | Method::SgBrute => settings.sg.spp,
        Method::Vpl => settings.vpl.spp.unwrap_or(settings.sg.spp),
        Method::Prt => settings.prt.spp,
        Method::Reference | Method::Direct => settings.spp,
    }
}

/// What the memory estimate needs, from the flags and the scene's settings. Values that are
/// validated later (order, image size) are clamped here so that a bad one is reported by its
/// own check, not as a huge estimate.
fn workload(
    args: &RenderArgs,
    settings: &RenderSettings,
    triangles: u64,
    vertices: u64,
    pixels: u64,
    environment_texels: u64,
    lights: usize,
) -> Workload {
    let side = MAX_IMAGE_SIDE as u64;
    let pixels = pixels.min(side * side);
    let spp = args
        .spp
        .unwrap_or_else(|| default_spp(args.method, settings))
        .clamp(1, MAX_SPP) as u64;
    let cut_mode = args.cut.unwrap_or(settings.sg.cut);
    let max_cut = args.max_cut.unwrap_or(settings.sg.max_cut);
    Workload {
        method: args.method,
        visibility: args.visibility,
        triangles,
        vertices,
        pixels,
        samples: pixels * spp,
        environment_texels,
        vertex_cut_nodes: (args.method == Method::Sg && cut_mode == CutMode::Vertex).then_some(
            if max_cut == 0 {
                interreflect::sg::DEFAULT_MAX_CUT as u64
            } else {
                max_cut as u64
            },
        ),
        prt_order: args
            .order
            .unwrap_or(settings.prt.order)
            .clamp(1, interreflect::math::sh::MAX_ORDER) as u64,
        prt_gpu: args.device != Device::Cpu,
        lights: lights as u64,
        node_map_bytes: interreflect::memory::node_map_bytes(
            args.node_maps
                .unwrap_or(settings.ism.node_maps)
                .min(MAX_NODE_MAPS),
            settings.ism.resolution,
        ),
    }
}

/// With `--device gpu`, shadow maps made on the GPU need an adapter: fail before rendering.
fn shadow_map_device_check(args: &RenderArgs) -> anyhow::Result<()> {
    if args.device == Device::Gpu && args.visibility != Visibility::Exact {
        interreflect::render::gpu::Gpu::shared()
            .map_err(|e| anyhow::anyhow!("--device gpu: the shadow maps need the GPU: {e}"))?;
    }
    Ok(())
}

/// With `--device gpu --visibility approx`, imperfect shadow maps the GPU cannot splat (too many
/// points per map, buffers over the binding limit): fail before rendering.
fn ism_device_check(args: &RenderArgs, scene: &interreflect::scene::Scene) -> anyhow::Result<()> {
    if args.device == Device::Gpu && args.visibility == Visibility::Approx {
        let gpu = interreflect::render::gpu::Gpu::shared().map_err(|e| {
            anyhow::anyhow!("--device gpu: the imperfect shadow maps need the GPU: {e}")
        })?;
        interreflect::render::gpu::ism::maps_per_dispatch(&gpu, &scene.settings.ism)
            .map_err(|e| anyhow::anyhow!("--device gpu: {}: {e}", args.scene.display()))?;
    }
    Ok(())
}

/// Where the shadow maps were made ("cpu (why)" when the GPU was asked for and not used): an
/// error with `--device gpu`, a one-line notice with `--device auto`.
fn shadow_map_fallback(args: &RenderArgs, on: &str) -> anyhow::Result<()> {
    gpu_fallback(
        args,
        on,
        "the shadow maps could not be made on the GPU",
        "shadow maps made on the CPU",
    )
}

/// Where sg's or vpl's indirect light was shaded ("cpu (why)" when the GPU was asked for and
/// not used): an error with `--device gpu`, a notice with `--device auto`.
fn gpu_shading_fallback(args: &RenderArgs, on: &str) -> anyhow::Result<()> {
    gpu_fallback(
        args,
        on,
        "the indirect light could not be shaded on the GPU",
        "indirect light shaded on the CPU",
    )
}

/// Where the direct light was computed ("cpu (why)" when the GPU was asked for and failed).
fn gpu_direct_fallback(args: &RenderArgs, on: &str) -> anyhow::Result<()> {
    gpu_fallback(
        args,
        on,
        "the direct light could not be computed on the GPU",
        "direct light computed on the CPU",
    )
}

fn gpu_vpls_fallback(args: &RenderArgs, on: &str) -> anyhow::Result<()> {
    gpu_fallback(
        args,
        on,
        "the VPLs' weights could not be computed on the GPU",
        "VPLs' weights computed on the CPU",
    )
}

/// With `--device gpu`, imperfect shadow maps the GPU could not splat are an error.
fn gpu_ism_fallback(args: &RenderArgs, on: &str) -> anyhow::Result<()> {
    gpu_fallback(
        args,
        on,
        "the imperfect shadow maps could not be splatted on the GPU",
        "imperfect shadow maps splatted on the CPU",
    )
}

/// A stage's place `on` ("cpu (why)" when the GPU was not used): `failed: why` as an error
/// with `--device gpu`, `notice: why` on stderr otherwise.
fn gpu_fallback(args: &RenderArgs, on: &str, failed: &str, notice: &str) -> anyhow::Result<()> {
    let Some(why) = on.strip_prefix("cpu (") else {
        return Ok(());
    };
    let why = why.strip_suffix(')').unwrap_or(why);
    match args.device {
        Device::Gpu => anyhow::bail!("--device gpu: {failed}: {why}"),
        _ => {
            eprintln!("notice: {notice}: {why}");
            Ok(())
        }
    }
}

/// Reports an interrupted render (nothing written) and returns its exit status.
fn interrupted() -> i32 {
    eprintln!("interrupted: nothing was written");
    130
}
