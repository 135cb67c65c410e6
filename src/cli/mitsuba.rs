//! `interreflect export-mitsuba`: write a Mitsuba 3 scene (XML + PLY meshes) of a scene file.

use interreflect::export::mitsuba::{ExportError, ExportOptions, MAX_DEPTH_ONE_BOUNCE, export};
use interreflect::scene::Scene;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct ExportMitsubaArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output directory: scene.xml, meshes/*.ply, envmap.exr (written under a temporary name and
    /// renamed, so it is complete or absent).
    pub out_dir: PathBuf,
    /// Replace OUT_DIR if it holds a previous export (a scene.xml); without it a non-empty
    /// OUT_DIR is refused.
    #[arg(long)]
    pub force: bool,
    /// Also write brdf-check.json: each material's directional albedo and BRDF values from our
    /// models, for checking the converted materials inside Mitsuba (scripts/mitsuba-check.sh).
    #[arg(long)]
    pub brdf_check: bool,
}

pub fn run(args: ExportMitsubaArgs) -> anyhow::Result<i32> {
    let scene = Scene::load(&args.scene)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let opts = ExportOptions {
        force: args.force,
        brdf_check: args.brdf_check,
    };
    let cancel = super::progress::interrupt_flag();
    let report = match export(&scene, &args.out_dir, opts, Some(cancel)) {
        Ok(r) => r,
        Err(ExportError::Interrupted) => {
            eprintln!("interrupted: nothing was written");
            return Ok(130);
        }
        Err(e) => return Err(e.into()),
    };
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    eprintln!(
        "wrote {} ({} files: {} objects, {} triangles, {} lights{}; path tracer with max_depth = {MAX_DEPTH_ONE_BOUNCE}: direct light + one bounce)",
        args.out_dir.join("scene.xml").display(),
        report.files.len(),
        scene.objects.len(),
        report.triangles,
        scene.lights.len(),
        if scene.environment.is_some() {
            " + environment"
        } else {
            ""
        }
    );
    Ok(0)
}
