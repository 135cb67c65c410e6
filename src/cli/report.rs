//! `interreflect report`: renders each scene with every method (each render a child process
//! of this executable, so that its time and peak memory are its own), measures them against a
//! cached reference and writes `<out>/<scene>/report.md` and `<out>/README.md`.

use anyhow::{Context, bail};
use interreflect::compare::plot;
use interreflect::compare::{ErrorMapOptions, box_filter, error_map, metrics};
use interreflect::fsutil::write_bytes_atomic;
use interreflect::hash::Fnv;
use interreflect::image::{
    Image, ToneOperator, Tonemap, read_exr, write_exr, write_png, write_png_rgb8,
};
use interreflect::report::{
    Defaults, Family, Run, RunSpec, SceneReport, Settings, brute_estimate, plan, summary,
};
use interreflect::scene::Scene;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The scenes reported when none is named: the three evaluation scenes, then the others.
pub const DEFAULT_SCENES: [&str; 8] = [
    "scenes/ring.toml",
    "scenes/bunny.toml",
    "scenes/dragon.toml",
    "scenes/teapot.toml",
    "scenes/magic-cube.toml",
    "scenes/table.toml",
    // Under a directional light, so that PRT takes part: Lambertian, then glossy.
    "scenes/prt/bunny-diffuse-sun.toml",
    "scenes/prt/bunny-glossy-sun.toml",
];

/// Bumped whenever the reference renderer's output changes, so cached references are redone.
const REFERENCE_VERSION: &[u8] = b"interreflect-reference-v1";

#[derive(clap::Args, Debug)]
pub struct ReportArgs {
    /// Scene files (default: ring, bunny, dragon, teapot, magic-cube, table, and the bunny
    /// under a directional light, Lambertian and glossy, where PRT takes part).
    pub scenes: Vec<PathBuf>,
    /// Where the pages go: OUT/<scene>/report.md and OUT/README.md.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Where references are cached (default: OUT/cache/reference).
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Image width of the methods (default 96; 24 with --quick).
    #[arg(long)]
    pub width: Option<u32>,
    /// The reference's samples per pixel (default 4096; 64 with --quick).
    #[arg(long)]
    pub reference_spp: Option<u32>,
    /// Only these methods (comma-separated): sg, sg-brute, vpl, path-tracing, prt.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub methods: Vec<Family>,
    /// Run sg-brute only when its estimated time is at most this many seconds (default 300).
    #[arg(long)]
    pub brute_budget: Option<f64>,
    /// A fast smoke version: small images, a short reference, short sweeps.
    #[arg(long)]
    pub quick: bool,
    /// Render threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Render nothing: rewrite OUT/README.md from the scene reports already in OUT.
    #[arg(long, conflicts_with_all = ["scenes", "quick", "methods", "width", "reference_spp", "brute_budget"])]
    pub summary_only: bool,
}

pub fn run(args: ReportArgs) -> anyhow::Result<i32> {
    if args.summary_only {
        write_summary(&args.out)?;
        eprintln!("wrote {}", args.out.join("README.md").display());
        return Ok(0);
    }
    let mut settings = if args.quick {
        Settings::quick()
    } else {
        Settings::full()
    };
    if let Some(w) = args.width {
        settings.width = w;
    }
    if let Some(n) = args.reference_spp {
        settings.reference_spp = n;
    }
    if let Some(b) = args.brute_budget {
        settings.brute_budget = b;
    }
    if !args.methods.is_empty() {
        settings.families = args.methods.clone();
    }
    settings.validate().map_err(anyhow::Error::msg)?;
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if threads == 0 || threads > 1024 {
        bail!("--threads {threads}: must be 1 to 1024");
    }
    let scenes: Vec<PathBuf> = if args.scenes.is_empty() {
        DEFAULT_SCENES.iter().map(PathBuf::from).collect()
    } else {
        args.scenes.clone()
    };
    // Every scene is loaded (and so validated) before anything is rendered.
    let mut loaded = Vec::new();
    for path in &scenes {
        let scene = Scene::load(path).map_err(anyhow::Error::new)?;
        loaded.push(scene);
    }
    let mut names = std::collections::HashSet::new();
    for s in &loaded {
        if !names.insert(s.name.clone()) {
            bail!(
                "{}: another scene given is also named {:?}; their reports would overwrite each other",
                s.path.display(),
                s.name
            );
        }
    }
    let exe = std::env::current_exe().context("cannot find this executable to run renders")?;
    let cache = args
        .cache
        .clone()
        .unwrap_or_else(|| args.out.join("cache").join("reference"));
    let t0 = Instant::now();
    for scene in &loaded {
        let r = report_scene(&exe, scene, &settings, threads, &args.out, &cache)?;
        eprintln!(
            "{}: wrote {}",
            scene.name,
            args.out.join(&r.scene).join("report.md").display()
        );
    }
    write_summary(&args.out)?;
    eprintln!(
        "wrote {} ({:.0} s in all)",
        args.out.join("README.md").display(),
        t0.elapsed().as_secs_f64()
    );
    Ok(0)
}

/// The summary from every `<out>/*/report.json`, and links to the other pages in `<out>`.
fn write_summary(out: &Path) -> anyhow::Result<()> {
    let mut reports = Vec::new();
    let mut pages = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(out)
        .with_context(|| format!("cannot read {}", out.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for p in entries {
        // Staging directories of pages being written (".<scene>.partial") are not reports.
        if p.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        {
            continue;
        }
        let json = p.join("report.json");
        if p.is_dir() && json.is_file() {
            let text = std::fs::read_to_string(&json)
                .with_context(|| format!("cannot read {}", json.display()))?;
            let r: SceneReport = serde_json::from_str(&text).with_context(|| {
                format!("{}: not a report written by this version", json.display())
            })?;
            reports.push(r);
        } else if p.extension().is_some_and(|e| e == "md")
            && p.file_name().is_some_and(|n| n != "README.md")
        {
            let text = std::fs::read_to_string(&p).unwrap_or_default();
            let title = text
                .lines()
                .find_map(|l| l.strip_prefix("# "))
                .unwrap_or_default()
                .to_string();
            let file = p.file_name().expect("a file").to_string_lossy().to_string();
            pages.push((file.clone(), if title.is_empty() { file } else { title }));
        }
    }
    // The evaluation scenes first, in their usual order, then the others by name.
    let rank = |s: &str| {
        ["ring", "bunny", "dragon", "teapot", "magic-cube", "table"]
            .iter()
            .position(|n| *n == s)
            .unwrap_or(usize::MAX)
    };
    reports.sort_by(|a, b| {
        rank(&a.scene)
            .cmp(&rank(&b.scene))
            .then(a.scene.cmp(&b.scene))
    });
    let text = summary(&reports, &pages);
    write_bytes_atomic(&out.join("README.md"), text.as_bytes())
        .with_context(|| format!("cannot write {}", out.join("README.md").display()))
}

/// What one render reported.
struct Rendered {
    image: Image,
    seconds: f64,
    peak_bytes: Option<u64>,
    log: Value,
}

/// Runs `interreflect render` as a child process; its stderr passes through (progress bars
/// unless `quiet`).
#[allow(clippy::too_many_arguments)]
fn render(
    exe: &Path,
    scene: &Scene,
    method: &str,
    size: (u32, u32),
    spp: u32,
    threads: usize,
    extra: &[String],
    indirect: bool,
    output: &Path,
    quiet: bool,
) -> anyhow::Result<Rendered> {
    let mut args: Vec<std::ffi::OsString> = vec![scene.path.clone().into()];
    for a in [
        "--method",
        method,
        "--width",
        &size.0.to_string(),
        "--height",
        &size.1.to_string(),
        "--threads",
        &threads.to_string(),
    ] {
        args.push(a.into());
    }
    if !extra.iter().any(|a| a == "--spp") {
        args.extend(["--spp".into(), spp.to_string().into()]);
    }
    args.extend(extra.iter().map(Into::into));
    if indirect {
        args.push("--indirect-only".into());
    }
    let log = super::child::render(exe, &args, output, quiet)
        .with_context(|| format!("{}: the report stops here", scene.path.display()))?;
    let image = read_exr(output)?;
    let json = output.with_extension("json");
    let seconds = log["seconds"]["render"]
        .as_f64()
        .with_context(|| format!("{}: no seconds.render", json.display()))?;
    let peak_bytes = log["memory"]["peak_bytes"].as_u64();
    Ok(Rendered {
        image,
        seconds,
        peak_bytes,
        log,
    })
}

/// The reference's cache key: everything its image depends on.
fn reference_key(scene: &Scene, size: (u32, u32), spp: u32, seed: u64) -> anyhow::Result<u64> {
    let mut h = Fnv::new();
    h.bytes(REFERENCE_VERSION);
    for p in std::iter::once(&scene.path).chain(&scene.inputs) {
        let bytes = std::fs::read(p).with_context(|| format!("cannot read {}", p.display()))?;
        h.u64(bytes.len() as u64);
        h.bytes(&bytes);
    }
    h.u64(size.0 as u64);
    h.u64(size.1 as u64);
    h.u64(spp as u64);
    h.u64(seed);
    Ok(h.0)
}

fn report_scene(
    exe: &Path,
    scene: &Scene,
    s: &Settings,
    threads: usize,
    out: &Path,
    cache: &Path,
) -> anyhow::Result<SceneReport> {
    let name = &scene.name;
    let (cw, ch) = (scene.camera.width.max(1), scene.camera.height.max(1));
    let size = (
        s.width,
        ((s.width as f64 * ch as f64 / cw as f64).round() as u32).max(1),
    );
    let ref_size = (size.0 * s.reference_scale, size.1 * s.reference_scale);
    let work = out.join("cache").join("report").join(name);
    // The page is written into a staging directory and moved into place once complete, so an
    // interrupted or failed report leaves the previous page as it was.
    let final_page = out.join(name);
    let page = out.join(format!(".{name}.partial"));
    if page.exists() {
        std::fs::remove_dir_all(&page)
            .with_context(|| format!("cannot remove the stale {}", page.display()))?;
    }
    for d in [&work, &cache.to_path_buf()] {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }

    // The reference, cached.
    let key = reference_key(scene, ref_size, s.reference_spp, s.reference_seed)?;
    let ref_path = cache.join(format!("{name}-{key:016x}.exr"));
    let ref_log = ref_path.with_extension("json");
    if !(ref_path.is_file() && ref_log.is_file()) {
        eprintln!(
            "{name}: reference at {}x{}, {} spp (cached afterwards in {})",
            ref_size.0,
            ref_size.1,
            s.reference_spp,
            cache.display()
        );
        render(
            exe,
            scene,
            "reference",
            ref_size,
            s.reference_spp,
            threads,
            &["--seed".into(), s.reference_seed.to_string()],
            true,
            &ref_path,
            false,
        )?;
    } else {
        eprintln!("{name}: reference from the cache ({})", ref_path.display());
    }
    let reference_full = read_exr(&ref_path)?;
    let reference_seconds = serde_json::from_str::<Value>(&std::fs::read_to_string(&ref_log)?)
        .ok()
        .and_then(|v| v["seconds"]["render"].as_f64())
        .unwrap_or(f64::NAN);
    if (reference_full.width, reference_full.height) != ref_size {
        bail!(
            "{}: the cached reference is {}x{}, expected {}x{}",
            ref_path.display(),
            reference_full.width,
            reference_full.height,
            ref_size.0,
            ref_size.1
        );
    }
    let reference = box_filter(&reference_full, s.reference_scale);

    // The direct light, for the whole image shown for orientation and the bounce's share.
    eprintln!("{name}: direct light");
    let direct = render(
        exe,
        scene,
        "direct",
        size,
        s.spp,
        threads,
        &[],
        false,
        &work.join("direct.exr"),
        true,
    )?
    .image;
    let whole = Image::from_fn(size.0, size.1, |x, y| {
        direct.get(x, y) + reference.get(x, y)
    });
    let indirect_share = reference.mean() / whole.mean().max(1e-30);

    // One exposure for every one-bounce image: the reference's 99th-percentile luminance at 1.
    let mut lum: Vec<f32> = reference
        .data
        .iter()
        .map(|v| 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2])
        .filter(|l| l.is_finite())
        .collect();
    lum.sort_by(f32::total_cmp);
    let p99 = lum
        .get(((lum.len() as f64 * 0.99) as usize).min(lum.len().saturating_sub(1)))
        .copied()
        .unwrap_or(1.0);
    let exposure = if p99 > 0.0 {
        (-(p99.log2()) * 10.0).round() / 10.0
    } else {
        0.0
    };
    let tm = Tonemap::new(exposure, ToneOperator::Clamp);
    std::fs::create_dir_all(&page).with_context(|| format!("cannot create {}", page.display()))?;
    write_png(&page.join("reference.png"), &reference, &tm)?;
    write_png(
        &page.join("scene.png"),
        &whole,
        &Tonemap::new(0.0, ToneOperator::Clamp),
    )?;

    let defaults = Defaults {
        max_cut: scene.settings.sg.max_cut,
        vpls: scene.settings.vpl_count,
    };
    let mut specs = plan(s, defaults);
    let mut runs: Vec<Run> = Vec::new();
    let mut skipped = Vec::new();
    let distant = scene.environment.is_some()
        || scene
            .lights
            .iter()
            .any(|l| matches!(l, interreflect::scene::light::Light::Directional { .. }));
    if !distant && specs.iter().any(|r| r.family == Family::Prt) {
        specs.retain(|r| r.family != Family::Prt);
        skipped.push((
            Family::Prt,
            "PRT relights distant light only (environment maps, directional lights), and this \
             scene is lit by point or spot lights; the scenes under `scenes/prt/` compare it"
                .to_string(),
        ));
    }
    let mut images: Vec<(Family, Option<u32>, Image)> = Vec::new();
    let mut i = 0;
    while i < specs.len() {
        let spec = specs[i].clone();
        i += 1;
        let label = format!(
            "{name} [{i}/{}] {}{}",
            specs.len(),
            spec.family.name(),
            if spec.setting().is_empty() {
                String::new()
            } else {
                format!(" ({})", spec.setting())
            }
        );
        eprint!("{label} ... ");
        let r = render(
            exe,
            scene,
            spec.family.method(),
            size,
            s.spp,
            threads,
            &spec.args,
            true,
            &work.join(format!("{}.exr", spec.name())),
            true,
        )?;
        let m = metrics(&r.image, &reference)?;
        eprintln!("{:.2} s, rel_rmse {:.2} %", r.seconds, 100.0 * m.rel_rmse);
        runs.push(Run {
            family: spec.family,
            param: spec.param,
            default: spec.default,
            seconds: r.seconds,
            peak_bytes: r.peak_bytes,
            rel_rmse: m.rel_rmse,
            relmse: m.relmse,
            ssim: m.ssim,
            flip: m.flip,
        });
        // After sg's default: decide on sg-brute from its measured size.
        if spec.family == Family::Sg && spec.default && s.families.contains(&Family::SgBrute) {
            let pieces = r.log["sg"]["reflector_pieces"].as_u64().unwrap_or(0);
            let points = r.log["sg"]["shading_points"].as_u64().unwrap_or(0);
            let est = brute_estimate(pieces, points, threads);
            if est <= s.brute_budget {
                let at = specs
                    .iter()
                    .position(|x| x.family != Family::Sg)
                    .unwrap_or(specs.len());
                specs.insert(
                    at,
                    RunSpec {
                        family: Family::SgBrute,
                        param: None,
                        default: true,
                        args: vec!["--visibility".into(), "exact".into()],
                    },
                );
            } else {
                skipped.push((
                    Family::SgBrute,
                    format!(
                        "its estimated time, {:.0} s ({pieces} reflector pieces × {points} \
                         shading points), is over the budget of {:.0} s (`--brute-budget`)",
                        est, s.brute_budget
                    ),
                ));
            }
        }
        images.push((spec.family, spec.param, r.image));
    }

    let mut report = SceneReport {
        scene: name.clone(),
        scene_file: scene.path.display().to_string(),
        settings: s.clone(),
        width: size.0,
        height: size.1,
        threads,
        machine: interreflect::report::cpu_model(),
        reference_seconds,
        indirect_share,
        exposure,
        runs,
        skipped,
    };
    report.runs.sort_by_key(|r| (r.family, r.param));

    // The images of the shown runs, with error maps on one scale.
    let opts = ErrorMapOptions {
        scale_max: Some(0.5),
        ..ErrorMapOptions::default()
    };
    for f in report.families() {
        let Some(shown) = report.shown_run(f) else {
            continue;
        };
        let Some((_, _, img)) = images
            .iter()
            .find(|(fam, p, _)| *fam == f && *p == shown.param)
        else {
            continue;
        };
        write_png(&page.join(format!("{}.png", f.stem())), img, &tm)?;
        let (w, h, px) = error_map(img, &reference, &opts)?;
        write_png_rgb8(&page.join(format!("{}-error.png", f.stem())), w, h, &px)?;
    }
    let raster = plot::render(&report.plot(), 720, 480);
    write_png_rgb8(
        &page.join("error-vs-time.png"),
        raster.width,
        raster.height,
        &raster.pixels,
    )?;
    // The box-filtered reference, for anyone who wants to compare against it.
    write_exr(&work.join("reference.exr"), &reference)?;
    let json = serde_json::to_string_pretty(&report)? + "\n";
    write_bytes_atomic(&page.join("report.json"), json.as_bytes())?;
    let md = report.markdown();
    write_bytes_atomic(&page.join("report.md"), md.as_bytes())?;
    if final_page.exists() {
        std::fs::remove_dir_all(&final_page)
            .with_context(|| format!("cannot replace {}", final_page.display()))?;
    }
    std::fs::rename(&page, &final_page)
        .with_context(|| format!("cannot move {} to {}", page.display(), final_page.display()))?;
    Ok(report)
}
