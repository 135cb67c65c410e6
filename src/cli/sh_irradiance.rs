//! `interreflect sh-irradiance ENV`: an environment map's irradiance from its SH projection next
//! to the brute-force irradiance, per order, as a table and as images.

use anyhow::{Context, bail};
use interreflect::compare::metrics;
use interreflect::compare::plot::{Raster, hstack};
use interreflect::compare::{ErrorMapOptions, render_error_map};
use interreflect::image::{Image, Tonemap, to_srgb8, write_exr, write_png_rgb8};
use interreflect::math::sh;
use interreflect::precompute::prt::WindowKind;
use interreflect::precompute::prt::irradiance::{brute_force, from_sh, radiance_coefficients};
use interreflect::scene::environment::Environment;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub struct ShIrradianceArgs {
    /// Lat-long environment map (EXR or Radiance HDR).
    pub env: PathBuf,
    /// Highest SH order measured (orders 1..=ORDER are tabulated); the images show this one.
    #[arg(long, default_value_t = 3)]
    pub order: u32,
    /// Width of the irradiance maps (height = width / 2).
    #[arg(long, default_value_t = 128)]
    pub width: u32,
    /// Window applied to the SH irradiance.
    #[arg(long, value_enum, default_value_t = WindowKind::None)]
    pub window: WindowKind,
    /// Rotation of the map about the up axis, degrees (as `[environment] rotation`).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub rotation: f32,
    /// Output PNG (environment | brute force | SH | relative error); EXRs of both irradiance
    /// maps are written beside it (default: results/sh-irradiance/<map>.png).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Print the table as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct Row {
    order: u32,
    coefficients: usize,
    rel_rmse: f64,
    max_rel_error: f64,
}

pub fn run(a: ShIrradianceArgs) -> anyhow::Result<i32> {
    if !(1..=sh::MAX_ORDER).contains(&a.order) {
        bail!(
            "--order must be between 1 and {}, got {}",
            sh::MAX_ORDER,
            a.order
        );
    }
    if !(4..=2048).contains(&a.width) || !a.width.is_multiple_of(2) {
        bail!(
            "--width must be an even number between 4 and 2048, got {}",
            a.width
        );
    }
    if !a.rotation.is_finite() {
        bail!(
            "--rotation must be a finite angle in degrees, got {}",
            a.rotation
        );
    }
    let env = Environment::load(&a.env, a.rotation, 1.0)?;
    let out = a.output.clone().unwrap_or_else(|| {
        let stem = a
            .env
            .file_stem()
            .map(|s| s.to_string_lossy().trim_end_matches(".exr").to_string())
            .unwrap_or_else(|| "env".into());
        Path::new("results/sh-irradiance").join(format!("{stem}.png"))
    });
    if out.extension().and_then(|e| e.to_str()) != Some("png") {
        bail!("--output {}: must be a .png file", out.display());
    }
    if interreflect::fsutil::same_file(&out, &a.env) {
        bail!("refusing to overwrite the input {}", a.env.display());
    }
    let (w, h) = (a.width, a.width / 2);
    let brute = brute_force(&env, w, h);
    let coeffs = radiance_coefficients(&env, a.order);
    let window = |order: u32| a.window.window(order as f32);
    let mut rows = Vec::new();
    let mut shown = None;
    for order in 1..=a.order {
        let approx = from_sh(&coeffs, order, window(order), &env, w, h);
        let m = metrics(&approx, &brute)?;
        let max_rel_error = approx
            .data
            .iter()
            .zip(&brute.data)
            .map(|(x, y)| ((*x - *y).abs() / y.abs().max(glam::Vec3::splat(1e-12))).max_element())
            .fold(0.0f32, f32::max) as f64;
        rows.push(Row {
            order,
            coefficients: sh::sh_count(order),
            rel_rmse: m.rel_rmse,
            max_rel_error,
        });
        if order == a.order {
            shown = Some(approx);
        }
    }
    let shown = shown.expect("order ≥ 1");

    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    // One exposure for the three panels: irradiance / π is the radiance of a white Lambertian
    // surface, on the environment's own scale.
    let dirs = interreflect::precompute::prt::irradiance::directions(&env, w, h);
    let env_img = Image::from_fn(w, h, |x, y| env.radiance(dirs[(y * w + x) as usize]));
    let mean = brute.mean().max(1e-12) / std::f64::consts::PI;
    let tm = Tonemap {
        exposure: (0.18 / mean).log2() as f32,
        ..Tonemap::default()
    };
    let to_raster = |img: &Image, scale: f32| {
        let scaled = Image::from_fn(img.width, img.height, |x, y| img.get(x, y) * scale);
        Raster {
            width: img.width,
            height: img.height,
            pixels: to_srgb8(&scaled, &tm),
        }
    };
    let inv_pi = 1.0 / std::f32::consts::PI;
    let err = render_error_map(&shown, &brute, &ErrorMapOptions::default())?;
    let err_raster = Raster {
        width: err.width,
        height: err.height,
        pixels: err.pixels,
    };
    let strip = hstack(&[
        to_raster(&env_img, 1.0),
        to_raster(&brute, inv_pi),
        to_raster(&shown, inv_pi),
        err_raster,
    ]);
    write_png_rgb8(&out, strip.width, strip.height, &strip.pixels)?;
    let brute_exr = out.with_file_name(format!(
        "{}-brute.exr",
        out.file_stem().unwrap_or_default().to_string_lossy()
    ));
    let sh_exr = out.with_file_name(format!(
        "{}-sh{}.exr",
        out.file_stem().unwrap_or_default().to_string_lossy(),
        a.order
    ));
    write_exr(&brute_exr, &brute)?;
    write_exr(&sh_exr, &shown)?;

    if a.json {
        super::print_stdout(&(serde_json::to_string_pretty(&rows)? + "\n"));
    } else {
        let mut t = String::new();
        outln!(
            t,
            "SH irradiance of {} ({}×{} map, window {:?}) against brute force:",
            a.env.display(),
            env.width(),
            env.height(),
            a.window
        );
        outln!(
            t,
            "| order | coefficients | rel_rmse | max relative error |"
        );
        outln!(t, "|---|---|---|---|");
        for r in &rows {
            outln!(
                t,
                "| {} | {} | {:.2} % | {:.2} % |",
                r.order,
                r.coefficients,
                100.0 * r.rel_rmse,
                100.0 * r.max_rel_error
            );
        }
        super::print_stdout(&t);
    }
    eprintln!(
        "wrote {} (environment | brute-force irradiance | SH order {} | relative error), {}, {}",
        out.display(),
        a.order,
        brute_exr.display(),
        sh_exr.display()
    );
    Ok(0)
}
