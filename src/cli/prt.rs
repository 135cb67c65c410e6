//! `interreflect render --method prt`: transfer (cached), SH lighting, relighting on the GPU or
//! the CPU, and the image pass.

use super::progress;
use super::render::RenderArgs;
use anyhow::bail;
use glam::{Mat3, Vec3};
use interreflect::accel::Accel;
use interreflect::image::Image;
use interreflect::math::sh;
use interreflect::precompute::prt::{
    CacheStatus, PrtOptions, TransferKind, WindowKind, load_or_compute, relight_cpu, sh_lighting,
    work_units,
};
use interreflect::render::Device;
use interreflect::render::cpu::prt::{PrtImageOptions, render_prt_image};
use interreflect::render::gpu::{Gpu, prt::Relighter};
use interreflect::scene::{MAX_PRT_BOUNCES, Scene};
use serde::Serialize;
use std::time::Instant;

/// PRT fields of the render log.
#[derive(Serialize)]
pub struct PrtLog {
    order: u32,
    coefficients: usize,
    transfer: TransferKind,
    bounces: u32,
    samples: u32,
    window: WindowKind,
    window_width: f32,
    lighting_rotation_deg: f32,
    vertices: usize,
    transfer_megabytes: f64,
    /// "hit", "stored" or "off".
    cache: &'static str,
    /// Vertices whose relit radiance is not finite (the image pass shows them black; should
    /// stay 0).
    nonfinite_vertices: u64,
    /// "gpu" or "cpu": where the relighting ran.
    relight_device: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    adapter: Option<String>,
    seconds: PrtTimings,
}

#[derive(Serialize, Default)]
struct PrtTimings {
    /// Transfer: computed, or read from the cache.
    transfer: f64,
    /// SH projection of the lighting (and its rotation).
    lighting: f64,
    /// Uploading the transfer to the GPU (once per scene; 0 on the CPU).
    upload: f64,
    /// One relighting: a dot product per vertex and channel (fastest of 3).
    relight: f64,
    /// Interpolating vertex radiance into pixels.
    image: f64,
}

/// The prt settings of a render: the command line over the scene's `[methods.prt]`, checked
/// before any work is done.
pub struct PrtSettings {
    opts: PrtOptions,
    rotation: f32,
    window: WindowKind,
    window_width: f32,
}

/// Resolves and checks the prt settings (errors name the flag).
pub fn settings(args: &RenderArgs, scene: &Scene, seed: u64) -> anyhow::Result<PrtSettings> {
    let ps = scene.settings.prt;
    let order = args.order.unwrap_or(ps.order);
    if !(1..=sh::MAX_ORDER).contains(&order) {
        bail!(
            "--order must be between 1 and {}, got {order}",
            sh::MAX_ORDER
        );
    }
    let bounces = args.bounces.unwrap_or(ps.bounces);
    if bounces > MAX_PRT_BOUNCES {
        bail!("--bounces must be between 0 and {MAX_PRT_BOUNCES}, got {bounces}");
    }
    let opts = PrtOptions {
        order,
        kind: args.transfer.unwrap_or(ps.transfer),
        bounces,
        samples: ps.samples,
        seed,
    };
    if args.indirect_only && opts.effective_bounces() == 0 {
        bail!(
            "--indirect-only with prt needs the interreflected transfer with at least one bounce (--transfer interreflected --bounces 1)"
        );
    }
    let rotation = args.rotate_lighting.unwrap_or(0.0);
    if !rotation.is_finite() {
        bail!("--rotate-lighting must be a finite angle in degrees, got {rotation}");
    }
    let window_width = args
        .window_width
        .or(ps.window_width)
        .unwrap_or(2.0 * order as f32);
    let max_width = 4.0 * sh::MAX_ORDER as f32;
    if !(window_width.is_finite() && window_width > 0.0 && window_width <= max_width) {
        bail!(
            "--window-width must be a band number > 0 and at most {max_width}, got {window_width}"
        );
    }
    Ok(PrtSettings {
        opts,
        rotation,
        window: args.window.unwrap_or(ps.window),
        window_width,
    })
}

/// Renders `scene` with PRT; `None` when interrupted.
pub fn render(
    args: &RenderArgs,
    scene: &Scene,
    accel: &Accel,
    pool: &rayon::ThreadPool,
    (width, height): (u32, u32),
    spp: u32,
    settings: &PrtSettings,
) -> anyhow::Result<Option<(Image, PrtLog)>> {
    let opts = settings.opts;
    let order = opts.order;
    let rotation = settings.rotation;
    let seed = opts.seed;
    let say = |s: String| {
        if !args.quiet {
            eprintln!("{s}");
        }
    };
    let mut secs = PrtTimings::default();

    // The device is opened first, so that `--device gpu` without an adapter fails before the
    // transfer is computed.
    let gpu = match args.device {
        Device::Cpu => None,
        Device::Gpu => Some(Gpu::shared()?),
        Device::Auto => match Gpu::shared() {
            Ok(g) => Some(g),
            Err(e) => {
                eprintln!("notice: relighting on the CPU: {e}");
                None
            }
        },
    };

    let t = Instant::now();
    let cache_dir = (!args.no_cache).then_some(args.prt_cache.as_path());
    let result = progress::run(work_units(scene, &opts), args.quiet, |prog| {
        pool.install(|| load_or_compute(scene, accel, &opts, cache_dir, prog))
    });
    let Some((transfer, status)) = result else {
        return Ok(None);
    };
    secs.transfer = t.elapsed().as_secs_f64();
    let cache = match &status {
        CacheStatus::Hit(p) => {
            say(format!("prt: transfer read from {}", p.display()));
            "hit"
        }
        CacheStatus::Stored(p) => {
            say(format!(
                "prt: transfer computed in {:.2} s, cached in {}",
                secs.transfer,
                p.display()
            ));
            "stored"
        }
        CacheStatus::Uncached(reason) => {
            if let Some(r) = reason {
                eprintln!("warning: prt: the transfer cache is not used: {r}");
            }
            "off"
        }
    };

    let t = Instant::now();
    let window = settings.window;
    let width_w = settings.window_width;
    let (mut lighting, warnings) = sh_lighting(scene, order, window.window(width_w));
    for w in warnings {
        eprintln!("warning: {}: {w}", scene.path.display());
    }
    if rotation != 0.0 {
        let r = sh::ShRotation::new(order, Mat3::from_rotation_y(rotation.to_radians()));
        lighting = r.apply(&lighting);
    }
    secs.lighting = t.elapsed().as_secs_f64();

    let n = transfer.coefficients();
    // The parts the image shows, summed once: relighting is linear.
    let total: Vec<Vec3> = if args.indirect_only {
        transfer.bounce.clone()
    } else {
        transfer.total()
    };
    // Relit RELIGHTS times (the lighting of an interactive session changes every frame); the
    // log keeps the fastest, the steady-state cost of one relighting.
    const RELIGHTS: usize = 3;
    let radiance;
    let mut best = f64::INFINITY;
    let relight_on_cpu = |best: &mut f64| {
        let mut radiance = Vec::new();
        for _ in 0..RELIGHTS {
            let t = Instant::now();
            radiance = pool.install(|| relight_cpu(&total, n, &lighting));
            *best = best.min(t.elapsed().as_secs_f64());
        }
        radiance
    };
    let mut gpu = gpu;
    if let Some(g) = &gpu {
        let on_gpu = (|| -> Result<Vec<Vec3>, interreflect::render::gpu::GpuError> {
            let t = Instant::now();
            let relighter = Relighter::new(g, &total, n)?;
            secs.upload = t.elapsed().as_secs_f64();
            let mut radiance = Vec::new();
            for _ in 0..RELIGHTS {
                let t = Instant::now();
                radiance = relighter.relight(&lighting)?;
                best = best.min(t.elapsed().as_secs_f64());
            }
            Ok(radiance)
        })();
        match on_gpu {
            Ok(r) => radiance = r,
            // With --device auto a failing GPU falls back to the CPU twin.
            Err(e) if args.device == Device::Auto => {
                eprintln!("notice: relighting on the CPU: the GPU failed: {e}");
                gpu = None;
                secs.upload = 0.0;
                best = f64::INFINITY;
                radiance = relight_on_cpu(&mut best);
            }
            Err(e) => return Err(e.into()),
        }
    } else {
        radiance = relight_on_cpu(&mut best);
    }
    drop(total);
    secs.relight = best;
    let nonfinite_vertices = radiance.iter().filter(|c| !c.is_finite()).count() as u64;
    if nonfinite_vertices > 0 {
        eprintln!(
            "warning: {}: prt: {nonfinite_vertices} vertices were relit to non-finite radiance; the image shows them black",
            scene.path.display()
        );
    }
    say(format!(
        "prt: order {order} ({n} coefficients), {:?} transfer, {} bounce(s), {} vertices ({:.1} MB); relit on the {} in {:.1} ms",
        opts.kind,
        opts.effective_bounces(),
        transfer.vertices,
        transfer.bytes() as f64 / 1e6,
        gpu.as_ref().map_or("CPU".to_string(), |g| format!(
            "GPU ({}; transfer uploaded in {:.1} ms)",
            g.adapter,
            1e3 * secs.upload
        )),
        1e3 * secs.relight
    ));

    let t = Instant::now();
    let image_opts = PrtImageOptions {
        width,
        height,
        spp,
        seed,
    };
    let img = progress::run(height as u64, args.quiet, |prog| {
        pool.install(|| render_prt_image(scene, accel, &radiance, &image_opts, prog))
    });
    let Some(img) = img else {
        return Ok(None);
    };
    secs.image = t.elapsed().as_secs_f64();
    Ok(Some((
        img,
        PrtLog {
            order,
            coefficients: n,
            transfer: opts.kind,
            bounces: opts.effective_bounces(),
            samples: opts.samples,
            window,
            window_width: width_w,
            lighting_rotation_deg: rotation,
            vertices: transfer.vertices,
            transfer_megabytes: transfer.bytes() as f64 / 1e6,
            cache,
            nonfinite_vertices,
            relight_device: if gpu.is_some() { "gpu" } else { "cpu" },
            adapter: gpu.map(|g| g.adapter.clone()),
            seconds: secs,
        },
    )))
}
