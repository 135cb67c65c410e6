//! Command-line interface (clap). Exit codes: 0 success, 1 a `compare --fail-above` threshold
//! was exceeded, 2 any error (bad input, I/O), 130 interrupted.

/// `writeln!` into a `String` (which cannot fail).
macro_rules! outln {
    ($($t:tt)*) => {{
        let _ = writeln!($($t)*);
    }};
}

mod bench;
mod child;
mod compare;
mod envmap;
mod fit;
mod info;
mod mitsuba;
mod progress;
mod prt;
mod render;
mod report;
mod sh_irradiance;
mod single_triangle;
mod view;

use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "interreflect",
    version,
    about = "Glossy one-bounce interreflections with spherical Gaussians, and the path-traced reference they are measured against"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to OUT.exr (linear) and OUT.png (tonemapped) beside it.
    Render(render::RenderArgs),
    /// Compare a test image with a reference: RMSE, rel_rmse, relMSE, SSIM, FLIP.
    Compare(compare::CompareArgs),
    /// Measure the SG transport of one reflector triangle against the exact integral over
    /// materials from Lambertian to near-mirror; writes results/single-triangle.md.
    SingleTriangle(single_triangle::SingleTriangleArgs),
    /// Describe a scene: triangles per object, bounds, lights, materials.
    Info {
        /// Scene file (TOML).
        scene: PathBuf,
    },
    /// Convert a mesh (PLY, PLY.gz, OBJ, glTF/GLB) to the compact binary PLY.gz used in scenes/.
    ConvertMesh { input: PathBuf, output: PathBuf },
    /// Resample a lat-long environment map (EXR or Radiance HDR) to a compact EXR of a given
    /// width, by an area-weighted box filter that preserves ∫ L dω.
    ConvertEnvmap(envmap::ConvertEnvmapArgs),
    /// Fit spherical Gaussians to every BRDF model: lobes, relative L2 errors, report and plots.
    Fit(fit::FitArgs),
    /// Irradiance of an environment map from its SH projection next to brute force, per order
    /// (a table, and images: environment | brute force | SH | relative error).
    ShIrradiance(sh_irradiance::ShIrradianceArgs),
    /// Write a Mitsuba 3 scene (XML + PLY meshes) with the same camera, lights and materials,
    /// rendering direct light plus one bounce, to check the reference against (docs/mitsuba.md).
    ExportMitsuba(mitsuba::ExportMitsubaArgs),
    /// Render scenes with every method against a cached reference and write comparison
    /// reports: RESULTS/<scene>/report.md (images, error maps, metrics, equal time, equal
    /// quality, error against time) and RESULTS/README.md (docs/report.md).
    Report(report::ReportArgs),
    /// The performance suite: tree build and frame time against triangle count, cut against
    /// brute force, the SG integral against the machine's exp, the reference's paths per
    /// second, GPU against its CPU twin; writes RESULTS/bench.md (docs/bench.md).
    Bench(bench::BenchArgs),
    /// The interactive viewer: a window with the image, an egui panel (method, light,
    /// materials, overlays, stats), camera controls, screenshots and scripts (docs/viewer.md).
    View(view::ViewArgs),
}

/// Writes `text` to standard output; a closed pipe (`interreflect info ... | head`) is not an
/// error.
pub fn print_stdout(text: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = out.write_all(text.as_bytes()).and_then(|_| out.flush());
}

pub fn run(cli: Cli) -> anyhow::Result<i32> {
    match cli.command {
        Command::Render(a) => render::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Info { scene } => info::run(&scene),
        Command::SingleTriangle(a) => single_triangle::run(a),
        Command::ConvertMesh { input, output } => {
            let report = interreflect::scene::mesh::convert(&input, &output)?;
            for w in &report.warnings {
                eprintln!("warning: {w}");
            }
            eprintln!("wrote {}", output.display());
            Ok(0)
        }
        Command::Fit(a) => fit::run(a),
        Command::ShIrradiance(a) => sh_irradiance::run(a),
        Command::ConvertEnvmap(a) => envmap::run(a),
        Command::ExportMitsuba(a) => mitsuba::run(a),
        Command::Report(a) => report::run(a),
        Command::Bench(a) => bench::run(a),
        Command::View(a) => view::run(a),
    }
}
