//! `interreflect compare`.

use anyhow::{Context, bail};
use interreflect::compare::{
    ErrorMapOptions, Metrics, box_filter, error_map, integer_factor, metrics,
};
use interreflect::image::{read_exr, write_png_rgb8};
use std::fmt::Write as _;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// The image under test (EXR).
    pub test: PathBuf,
    /// The reference image (EXR).
    pub reference: PathBuf,
    /// Print one JSON object with the keys rmse, rel_rmse, relmse, ssim, flip.
    #[arg(long)]
    pub json: bool,
    /// Write a false-colour relative-error map with a legend (PNG).
    #[arg(long)]
    pub error_map: Option<PathBuf>,
    /// Exit with status 1 when METRIC exceeds VALUE (repeatable), e.g. rel_rmse=0.05.
    #[arg(long, value_name = "METRIC=VALUE")]
    pub fail_above: Vec<String>,
}

fn parse_threshold(s: &str) -> anyhow::Result<(String, f64)> {
    let (k, v) = s
        .split_once('=')
        .with_context(|| format!("--fail-above {s}: expected METRIC=VALUE, e.g. rel_rmse=0.05"))?;
    let k = k.trim().to_ascii_lowercase();
    if !["rmse", "rel_rmse", "relmse", "ssim", "flip"].contains(&k.as_str()) {
        bail!("--fail-above {s}: unknown metric {k:?} (known: rmse, rel_rmse, relmse, ssim, flip)");
    }
    let v: f64 = v
        .trim()
        .parse()
        .with_context(|| format!("--fail-above {s}: {v:?} is not a number"))?;
    if !v.is_finite() {
        bail!("--fail-above {s}: the threshold must be finite");
    }
    Ok((k, v))
}

fn value(m: &Metrics, k: &str) -> f64 {
    match k {
        "rmse" => m.rmse,
        "rel_rmse" => m.rel_rmse,
        "relmse" => m.relmse,
        "ssim" => m.ssim,
        _ => m.flip,
    }
}

pub fn run(args: CompareArgs) -> anyhow::Result<i32> {
    let thresholds = args
        .fail_above
        .iter()
        .map(|s| parse_threshold(s))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let test = read_exr(&args.test)?;
    let mut reference = read_exr(&args.reference)?;
    if let Some(k) = integer_factor(&test, &reference) {
        eprintln!(
            "note: the reference ({}x{}) is {k}x the test's size: box-filtered to {}x{} before comparing",
            reference.width, reference.height, test.width, test.height
        );
        reference = box_filter(&reference, k);
    }
    let m = metrics(&test, &reference)?;
    let mut out = String::new();
    if args.json {
        outln!(out, "{}", serde_json::to_string(&m)?);
    } else {
        outln!(out, "test:      {}", args.test.display());
        outln!(out, "reference: {}", args.reference.display());
        outln!(out, "RMSE      {:.6e}", m.rmse);
        outln!(out, "rel_rmse  {:.6}  (RMSE / reference mean)", m.rel_rmse);
        outln!(
            out,
            "relMSE    {:.6e}  (mean (x-y)^2 / (y^2 + 0.01))",
            m.relmse
        );
        outln!(out, "SSIM      {:.6}", m.ssim);
        outln!(out, "FLIP      {:.6}  (mean LDR FLIP)", m.flip);
    }
    if let Some(p) = &args.error_map {
        let (w, h, px) = error_map(&test, &reference, &ErrorMapOptions::default())?;
        write_png_rgb8(p, w, h, &px)?;
        if !args.json {
            outln!(out, "error map: {}", p.display());
        }
    }
    super::print_stdout(&out);
    let mut failed = false;
    for (k, v) in &thresholds {
        let x = value(&m, k);
        if x > *v {
            eprintln!("{k} = {x:.6} exceeds {v}");
            failed = true;
        }
    }
    Ok(if failed { 1 } else { 0 })
}
