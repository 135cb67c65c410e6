//! `interreflect convert-envmap`: resample a lat-long environment map to a compact EXR.

use anyhow::{Context, bail};
use interreflect::fsutil::same_file;
use interreflect::image::{HALF_MAX, write_exr, write_exr_half};
use interreflect::scene::environment::{read_latlong, resample_latlong};
use std::f64::consts::PI;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct ConvertEnvmapArgs {
    /// Input lat-long map: .exr (OpenEXR) or .hdr (Radiance RGBE).
    pub input: PathBuf,
    /// Output .exr (half floats with PIZ compression; 32-bit floats with ZIP if a texel exceeds
    /// the half range or with --float).
    pub output: PathBuf,
    /// Output width in texels (even; the height is half of it). Default: the input's width
    /// rounded down to even.
    #[arg(long)]
    pub width: Option<u32>,
    /// Write 32-bit floats (ZIP) instead of half floats (PIZ).
    #[arg(long)]
    pub float: bool,
}

/// ∫ L dω per channel of a lat-long image (texel solid angles exact).
fn integral(img: &interreflect::image::Image) -> [f64; 3] {
    let (w, h) = (img.width as usize, img.height as usize);
    let mut s = [0.0; 3];
    for y in 0..h {
        let (t0, t1) = (PI * y as f64 / h as f64, PI * (y + 1) as f64 / h as f64);
        let omega = 2.0 * PI / w as f64 * (t0.cos() - t1.cos());
        for p in &img.data[y * w..(y + 1) * w] {
            for (c, v) in s.iter_mut().zip(p.to_array()) {
                *c += v as f64 * omega;
            }
        }
    }
    s
}

pub fn run(args: ConvertEnvmapArgs) -> anyhow::Result<i32> {
    if args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.eq_ignore_ascii_case("exr"))
        != Some(true)
    {
        bail!("{}: the output must be an .exr file", args.output.display());
    }
    if same_file(&args.output, &args.input) {
        bail!(
            "refusing to overwrite the input {} with the output",
            args.input.display()
        );
    }
    let mut img = read_latlong(&args.input)?;
    // Lossy codecs (DWA, and resampling with negative lobes) leave small negative values around
    // bright edges: clamp them to 0 (the scene loader refuses negative texels) and say so.
    let mut clamped = 0usize;
    let mut lowest = 0.0f32;
    for p in &mut img.data {
        if p.min_element() < 0.0 {
            clamped += 1;
            lowest = lowest.min(p.min_element());
            *p = p.max(glam::Vec3::ZERO);
        }
    }
    if clamped > 0 {
        eprintln!(
            "note: {clamped} of {} texels had negative channels (lowest {lowest:.3e}); clamped to 0",
            img.data.len()
        );
    }
    let width = args.width.unwrap_or(img.width & !1);
    if width < 2 || !width.is_multiple_of(2) || width > 16384 {
        bail!("--width must be even and between 2 and 16384, got {width}");
    }
    let out = resample_latlong(&img, width, width / 2);
    let (a, b) = (integral(&img), integral(&out));
    let half = !args.float && out.data.iter().all(|p| p.max_element() <= HALF_MAX);
    if half {
        write_exr_half(&args.output, &out)?;
    } else {
        if !args.float {
            eprintln!(
                "note: a texel exceeds the half-float range ({HALF_MAX}): writing 32-bit floats"
            );
        }
        write_exr(&args.output, &out)?;
    }
    let peak = out
        .data
        .iter()
        .map(|p| p.max_element())
        .fold(0.0f32, f32::max);
    let bytes = std::fs::metadata(&args.output)
        .with_context(|| format!("cannot stat {}", args.output.display()))?
        .len();
    eprintln!(
        "{}x{} -> {}x{} ({}), {} bytes; ∫ L dω (RGB) {:.4?} -> {:.4?}; peak texel {peak:.1}",
        img.width,
        img.height,
        out.width,
        out.height,
        if half { "half, PIZ" } else { "float, ZIP" },
        bytes,
        a,
        b
    );
    eprintln!("wrote {}", args.output.display());
    Ok(0)
}
