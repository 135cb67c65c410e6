//! `interreflect single-triangle`: the accuracy of the SG transport of one reflector triangle
//! against the exact integral, over a grid of materials and configurations; writes
//! `results/single-triangle.md`.

use interreflect::fsutil::write_bytes_atomic;
use interreflect::sg::transport::study::{self, Row};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct SingleTriangleArgs {
    /// Print the rows as JSON instead of writing the report.
    #[arg(long)]
    pub json: bool,
    /// Where to write the report.
    #[arg(long, default_value = "results/single-triangle.md")]
    pub output: PathBuf,
}

/// Exact values below this (W/(sr·m²) for a unit-intensity light) are too small for a
/// relative error to mean anything; those rows are counted but not scored.
const FLOOR: f64 = 1e-7;

fn percentile(mut xs: Vec<f64>, q: f64) -> f64 {
    if xs.is_empty() {
        return f64::NAN;
    }
    xs.sort_by(|a, b| a.total_cmp(b));
    xs[((xs.len() - 1) as f64 * q).round() as usize]
}

fn pct(x: f64) -> String {
    if x.is_nan() {
        "–".into()
    } else if x >= 10.0 {
        format!("{:.0}×", x)
    } else {
        format!("{:.1} %", 100.0 * x)
    }
}

pub fn run(args: SingleTriangleArgs) -> anyhow::Result<i32> {
    let t = Instant::now();
    let mats = study::materials();
    let geoms = study::geometries();
    let rows = study::run(&mats, &geoms);
    let secs = t.elapsed().as_secs_f64();
    if args.json {
        super::print_stdout(&(serde_json::to_string_pretty(&rows)? + "\n"));
        return Ok(0);
    }
    let variants = study::variants();
    let errs = |v: usize, filter: &dyn Fn(&Row) -> bool| -> Vec<f64> {
        rows.iter()
            .filter(|r| filter(r))
            .filter_map(|r| study::rel_error(r, v, FLOOR))
            .collect()
    };
    let all = |_: &Row| true;
    // The per-pair tables show the defaults: mirror-image aim with the default receiver options.
    let default_opts = interreflect::sg::transport::ReceiverOptions::default();
    let best = variants
        .iter()
        .position(|(aim, o, _)| *aim == study::Aim::MirrorImage && *o == default_opts)
        .unwrap_or(0);
    let lowest = (0..variants.len())
        .min_by(|&a, &b| study::median(errs(a, &all)).total_cmp(&study::median(errs(b, &all))))
        .unwrap_or(0);
    let mut md = String::new();
    outln!(
        md,
        "# Single-triangle transport: SG against the exact integral\n"
    );
    outln!(
        md,
        "Written by `interreflect single-triangle` ({} configurations in {secs:.0} s on 2 cores). \
It measures the one-bounce radiance that **one** reflector triangle, lit by a point light, sends to \
a receiver point towards the eye: the SG transport (`transport::reflected_sg` + \
`transport::one_bounce`, METHOD §4–5) against the exact integral over the triangle with the exact \
BRDFs (`transport::brute_force`, adaptive 7-point quadrature to 1e-4 relative). No visibility, no \
tree: this is the error of the spherical-Gaussian approximation alone, the paper's \"accurate for a \
wide range of BRDFs\" claim.\n",
        rows.len()
    );
    outln!(
        md,
        "- Materials (reflector × receiver, all pairs): {}.",
        mats.iter()
            .map(|m| format!("`{}`", m.name))
            .collect::<Vec<_>>()
            .join(", ")
    );
    outln!(
        md,
        "  Glossy ones have no diffuse term (ks = 0.9, Cook-Torrance F0 = 0.9), so their lobes are measured alone."
    );
    outln!(
        md,
        "- Configurations: {}. The receiver sits on the centroid's mirror direction and is viewed along the double-mirror direction (glossy-to-glossy transport at its strongest), except the last, viewed 10° away.",
        geoms
            .iter()
            .map(|g| format!("*{}*", g.name))
            .collect::<Vec<_>>()
            .join(", ")
    );
    outln!(
        md,
        "- Error: |SG − exact| / exact of the mean RGB radiance. Rows whose exact value is below {FLOOR:e} (unit-intensity light) are not scored; they are counted.\n"
    );
    outln!(md, "## Variants\n");
    outln!(md, "| variant | scored | median | mean | 90th pct | max |");
    outln!(md, "|---|---|---|---|---|---|");
    for (v, (_, _, label)) in variants.iter().enumerate() {
        let e = errs(v, &all);
        let mean = e.iter().sum::<f64>() / e.len().max(1) as f64;
        outln!(
            md,
            "| {}{label}{}{} | {} | {} | {} | {} | {} |",
            if v == best { "**" } else { "" },
            if v == best { "**" } else { "" },
            if v == lowest { " (lowest median)" } else { "" },
            e.len(),
            pct(study::median(e.clone())),
            pct(mean),
            pct(percentile(e.clone(), 0.9)),
            pct(percentile(e, 1.0))
        );
    }
    outln!(
        md,
        "\nThe variant in bold is what the defaults use (`ReceiverOptions::default()`, mirror-image aiming). Its exact cosine (`CosineMode::Moment`) equals the cosine at the lobe axis wherever the lobe sits well above the receiver's horizon; it differs for lobes near or across the horizon (receivers seen at grazing angles, wide lobes), where the axis cosine loses up to half the light (`docs/sg-renderer.md`) — here it lowers the mean and the 90th percentile at the same median. The anisotropic warp is described under *Reading the table*.\n"
    );
    outln!(
        md,
        "## Median error per material pair ({})\n",
        variants[best].2
    );
    outln!(
        md,
        "Rows: reflector; columns: receiver; median over the configurations that scored.\n"
    );
    let mut header = "| reflector \\ receiver |".to_string();
    let mut sep = "|---|".to_string();
    for m in &mats {
        let _ = write!(header, " {} |", m.name);
        sep.push_str("---|");
    }
    outln!(md, "{header}\n{sep}");
    for a in &mats {
        let mut line = format!("| {} |", a.name);
        for b in &mats {
            let e = errs(best, &|r: &Row| {
                r.reflector == a.name && r.receiver == b.name
            });
            let _ = write!(line, " {} |", pct(study::median(e)));
        }
        outln!(md, "{line}");
    }
    outln!(
        md,
        "\n## Median error per configuration ({})\n",
        variants[best].2
    );
    outln!(md, "| configuration | scored | median | 90th pct |");
    outln!(md, "|---|---|---|---|");
    for g in &geoms {
        let e = errs(best, &|r: &Row| r.geometry == g.name);
        outln!(
            md,
            "| {} | {} | {} | {} |",
            g.name,
            e.len(),
            pct(study::median(e.clone())),
            pct(percentile(e, 0.9))
        );
    }
    let unscored = rows.iter().filter(|r| r.exact <= FLOOR).count();
    outln!(
        md,
        "\n{unscored} of {} rows were below the floor and not scored.\n",
        rows.len()
    );
    outln!(md, "## Reading the table\n");
    outln!(md, "{}", NOTES);
    write_bytes_atomic(&args.output, md.as_bytes())?;
    eprintln!(
        "wrote {} ({} rows, {secs:.1} s)",
        args.output.display(),
        rows.len()
    );
    Ok(0)
}

const NOTES: &str = "\
- The mirror-image aim is what makes sharp reflectors work: with lobes built at the centroid, a \
receiver whose specular point on the triangle is not the centroid sees the lobe off its peak, and \
for exponents above ~100 the error runs to several hundred per cent.
- The anisotropic warp (the default) is the second step: the isotropic warp of a half-vector \
lobe (Blinn-Phong, Ward, Cook-Torrance) has the right energy but the wrong shape, since the true \
reflected lobe is wider by 1/cos θ in the plane of incidence than across it \
(`results/brdf-fits.md`: 17 % at 45°, 62 % at 75° for any sharp lobe). Giving the lobes of both \
the reflector and the receiver their anisotropy, and integrating it exactly through a linear \
change of directions (`docs/sg-renderer.md`), lowers the median from 1.8 % to 0.7 % and the \
90th percentile from 12.9 % to 7.2 %; the *grazing light* configuration (light 15° above the \
triangle), where the isotropic warp was worst, goes from 10.7 % to 2.8 % in median.
- The errors that remain have known causes: (1) the light's distance and the cosine at the \
reflector are taken at the centroid, which matters for large triangles close to the light; \
(2) GGX has long tails that a few Gaussians follow only near the peak, which shows when the \
view is off the double-mirror direction; (3) at views within ~10° of grazing, the BRDF's smooth \
factor taken at the lobe's peak is far from its value across a wide lobe. The receiver's cosine \
is not a source: the default integrates it exactly (the smooth-factor variants, at the lobe axis \
or at the triangle's centroid, agree with it to 0.1 % in median here, while the 1.17/2.133 SG \
fit of the cosine is measurably worse, as the variants table shows).
- Small triangles (the *small, far* configuration, like the leaves and deep nodes of the tree in \
a real scene) are where the method is most accurate across the whole range of materials.";
