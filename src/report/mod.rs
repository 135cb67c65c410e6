//! Comparison reports (`interreflect report`, `docs/report.md`): which renders a scene's report
//! needs, how its measurements are read (equal time, equal quality), and the pages. The CLI runs
//! the renders; everything here is pure and unit-tested.
//!
//! Every method renders the one-bounce (indirect) light alone: the light the methods
//! approximate. The direct light is exact and identical in all of them, and would only dilute
//! the differences.

use crate::compare::plot::{PALETTE, Plot, Series};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// A method, swept over at most one quality parameter.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    Serialize,
    Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
#[value(rename_all = "kebab-case")]
pub enum Family {
    /// The SG method over a per-pixel cut, swept over the cut's size cap.
    Sg,
    /// The SG method over every reflector triangle (only where its estimated time is affordable).
    SgBrute,
    /// Instant radiosity with clamped virtual point lights, swept over their number.
    Vpl,
    /// The path tracer at low sample counts: the reference's own method, run for less time.
    PathTracing,
    /// SH diffuse precomputed radiance transfer (time includes computing the transfer).
    Prt,
}

impl Family {
    pub const ALL: [Family; 5] = [
        Family::Sg,
        Family::SgBrute,
        Family::Vpl,
        Family::PathTracing,
        Family::Prt,
    ];

    /// Name in tables and file names.
    pub fn name(self) -> &'static str {
        match self {
            Family::Sg => "sg",
            Family::SgBrute => "sg-brute",
            Family::Vpl => "vpl",
            Family::PathTracing => "path tracing",
            Family::Prt => "prt",
        }
    }

    /// File-name stem.
    pub fn stem(self) -> &'static str {
        match self {
            Family::PathTracing => "path-tracing",
            f => f.name(),
        }
    }

    /// `render --method`.
    pub fn method(self) -> &'static str {
        match self {
            Family::PathTracing => "reference",
            f => f.name(),
        }
    }

    /// The swept parameter: its name in tables and its `render` flag.
    pub fn parameter(self) -> Option<(&'static str, &'static str)> {
        match self {
            Family::Sg => Some(("max_cut", "--max-cut")),
            Family::Vpl => Some(("VPLs", "--vpls")),
            Family::PathTracing => Some(("spp", "--spp")),
            Family::SgBrute | Family::Prt => None,
        }
    }

    fn color(self) -> [u8; 3] {
        match self {
            Family::Sg => PALETTE[0],
            Family::SgBrute => PALETTE[6],
            Family::Vpl => PALETTE[1],
            Family::PathTracing => PALETTE[2],
            Family::Prt => PALETTE[3],
        }
    }

    /// Whether its runs pass `--visibility exact`: the reports measure sg, sg-brute and vpl
    /// with shadow rays, so that their errors are those of the transport and of the cut, not
    /// of the approximate visibility (`render`'s default, measured in `results/visibility.md`).
    pub fn pins_exact_visibility(self) -> bool {
        matches!(self, Family::Sg | Family::SgBrute | Family::Vpl)
    }

    /// Whether its error keeps falling as 1/√time with more time (unbiased Monte Carlo), so
    /// that equal quality may be extrapolated beyond the measured runs.
    fn converges_as_monte_carlo(self) -> bool {
        self == Family::PathTracing
    }
}

/// What a report renders.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Image width of the methods (the height follows the scene camera's aspect).
    pub width: u32,
    /// Samples per pixel of sg, sg-brute, vpl and prt (anti-aliasing: the reference's pixels
    /// are box-filtered, and so must theirs be).
    pub spp: u32,
    /// The reference: the path tracer at `reference_scale` × the width, box-filtered down.
    pub reference_spp: u32,
    pub reference_scale: u32,
    pub reference_seed: u64,
    /// The sweeps; the default setting of each method is always included.
    pub sg_caps: Vec<u32>,
    pub vpl_counts: Vec<u32>,
    pub path_tracing_spp: Vec<u32>,
    /// sg-brute runs when its estimated time is at most this (seconds).
    pub brute_budget: f64,
    pub families: Vec<Family>,
}

impl Settings {
    /// The committed reports.
    pub fn full() -> Settings {
        Settings {
            width: 96,
            spp: 4,
            reference_spp: 4096,
            reference_scale: 2,
            reference_seed: 1,
            sg_caps: vec![100, 300, 1000],
            vpl_counts: vec![50, 200, 800, 3200, 12800],
            path_tracing_spp: vec![1, 4, 16, 64, 256, 1024],
            brute_budget: 300.0,
            families: Family::ALL.to_vec(),
        }
    }

    /// A fast smoke version (tests, trying the command out): small images, a short reference.
    pub fn quick() -> Settings {
        Settings {
            width: 24,
            spp: 1,
            reference_spp: 64,
            reference_scale: 2,
            reference_seed: 1,
            sg_caps: vec![100, 1000],
            vpl_counts: vec![50, 200],
            path_tracing_spp: vec![1, 16],
            brute_budget: 20.0,
            families: Family::ALL.to_vec(),
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if !(8..=4096).contains(&self.width) {
            return Err(format!("--width {}: must be 8 to 4096", self.width));
        }
        if !(1..=1 << 16).contains(&self.reference_spp) {
            return Err(format!(
                "--reference-spp {}: must be 1 to 65536",
                self.reference_spp
            ));
        }
        if !(self.brute_budget >= 0.0) {
            return Err(format!(
                "--brute-budget {}: must be a non-negative number of seconds",
                self.brute_budget
            ));
        }
        if self.families.is_empty() {
            return Err("--methods: nothing to compare".into());
        }
        Ok(())
    }
}

/// One render to run (besides the reference and the direct light).
#[derive(Clone, Debug, PartialEq)]
pub struct RunSpec {
    pub family: Family,
    /// The swept parameter's value, if the family has one.
    pub param: Option<u32>,
    /// The method's default setting (the one shown in the images and the metric table).
    pub default: bool,
    /// `render` flags beyond the scene, method, size, spp, indirect-only and output.
    pub args: Vec<String>,
}

impl RunSpec {
    /// A unique name within a report, e.g. `vpl-800`.
    pub fn name(&self) -> String {
        match self.param {
            Some(p) => format!("{}-{p}", self.family.stem()),
            None => self.family.stem().to_string(),
        }
    }

    /// e.g. "800 VPLs" or "" for families without a parameter.
    pub fn setting(&self) -> String {
        match (self.family.parameter(), self.param) {
            (Some((name, _)), Some(p)) => format!("{name} {p}"),
            _ => String::new(),
        }
    }
}

/// A scene's defaults of the swept parameters (`[methods.sg] max_cut`, the VPL count of
/// `[visibility]`). Path tracing has none: the report shows its run nearest sg's time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Defaults {
    pub max_cut: u32,
    pub vpls: u32,
}

impl Default for Defaults {
    fn default() -> Self {
        Defaults {
            max_cut: 1000,
            vpls: 200,
        }
    }
}

/// The runs of a report, in order: sg first (sg-brute's decision and the equal-time target
/// need it), then vpl, path tracing and prt. sg-brute is decided once sg's default has run.
pub fn plan(s: &Settings, d: Defaults) -> Vec<RunSpec> {
    let mut out = Vec::new();
    let sweep = |values: &[u32], default: Option<u32>| {
        let mut v: Vec<u32> = values.to_vec();
        if let Some(d) = default
            && !v.contains(&d)
        {
            v.push(d);
        }
        v.sort_unstable();
        v.dedup();
        v
    };
    for f in [Family::Sg, Family::Vpl, Family::PathTracing, Family::Prt] {
        if !s.families.contains(&f) {
            continue;
        }
        let (values, default): (&[u32], Option<u32>) = match f {
            Family::Sg => (&s.sg_caps, Some(d.max_cut)),
            Family::Vpl => (&s.vpl_counts, Some(d.vpls)),
            Family::PathTracing => (&s.path_tracing_spp, None),
            _ => {
                out.push(RunSpec {
                    family: f,
                    param: None,
                    default: true,
                    // prt: the transfer is computed, not read from a cache, so its time is
                    // part of prt's.
                    args: vec!["--no-cache".into()],
                });
                continue;
            }
        };
        let (_, flag) = f.parameter().expect("a swept family has a parameter");
        for v in sweep(values, default) {
            let mut args = vec![flag.to_string(), v.to_string()];
            if f.pins_exact_visibility() {
                args.extend(["--visibility".into(), "exact".into()]);
            }
            if f == Family::PathTracing {
                // A different seed from the reference's: independent noise.
                args.extend(["--seed".into(), (s.reference_seed + 1).to_string()]);
            }
            out.push(RunSpec {
                family: f,
                param: Some(v),
                default: Some(v) == default,
                args,
            });
        }
    }
    out
}

/// sg-brute's time, estimated from sg's run: one exact triangle integration and one shadow
/// ray per reflector piece and shading point, at `SECONDS_PER_INTEGRATION` each on 2 threads
/// (measured: 150 s for 266,567 pieces × 768 points on the 202k dragon).
pub fn brute_estimate(pieces: u64, shading_points: u64, threads: usize) -> f64 {
    const SECONDS_PER_INTEGRATION: f64 = 7.3e-7;
    pieces as f64 * shading_points as f64 * SECONDS_PER_INTEGRATION * 2.0 / threads.max(1) as f64
}

/// One measured run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Run {
    pub family: Family,
    pub param: Option<u32>,
    pub default: bool,
    /// The method's render time (scene loading and the BVH excluded; the method's own
    /// precomputation — tree, VPLs, transfer — included).
    pub seconds: f64,
    /// The render process's peak resident memory, when known.
    pub peak_bytes: Option<u64>,
    pub rel_rmse: f64,
    pub relmse: f64,
    pub ssim: f64,
    pub flip: f64,
}

impl Run {
    pub fn name(&self) -> String {
        RunSpec {
            family: self.family,
            param: self.param,
            default: self.default,
            args: vec![],
        }
        .name()
    }
}

/// A scene's report data (`report.json`), from which its page and the summary are written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SceneReport {
    pub scene: String,
    pub scene_file: String,
    pub settings: Settings,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    /// The CPU the report ran on (`/proc/cpuinfo`'s model name).
    #[serde(default)]
    pub machine: String,
    /// The reference's render time (it is cached: this is the time of the render that made it).
    pub reference_seconds: f64,
    /// Mean of the one-bounce light over the mean of the whole image (direct from `direct`).
    pub indirect_share: f64,
    /// The exposure (EV) of every one-bounce image on the page.
    pub exposure: f32,
    pub runs: Vec<Run>,
    /// Families left out, with the reason.
    pub skipped: Vec<(Family, String)>,
}

/// How long a method takes to reach an error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// Interpolated between two measured runs.
    Within(f64),
    /// Already reached by its fastest run: at most this long.
    AtMost(f64),
    /// Beyond the slowest run, extrapolated as 1/√time (Monte Carlo methods only).
    Extrapolated(f64),
    /// Not reached by any run; the best error measured.
    NotReached { best: f64 },
}

/// (seconds, error) of a family's runs, sorted by time.
pub fn curve(runs: &[Run], f: Family) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = runs
        .iter()
        .filter(|r| r.family == f && r.seconds > 0.0 && r.rel_rmse.is_finite())
        .map(|r| (r.seconds, r.rel_rmse))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    pts
}

/// Log-log interpolation of y at x between the two points around it; `None` outside.
pub fn interpolate_loglog(pts: &[(f64, f64)], x: f64) -> Option<f64> {
    if pts.len() == 1 && (pts[0].0 - x).abs() <= 1e-9 * x.abs() {
        return Some(pts[0].1);
    }
    for w in pts.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if x >= x0 && x <= x1 && x0 > 0.0 && x1 > 0.0 && y0 > 0.0 && y1 > 0.0 {
            if x1 == x0 {
                return Some(y0.min(y1));
            }
            let t = (x / x0).ln() / (x1 / x0).ln();
            return Some((y0.ln() + t * (y1 / y0).ln()).exp());
        }
    }
    None
}

/// The error of a family at `seconds` (equal time): interpolated between its runs; beyond
/// them only for Monte Carlo families (error ∝ 1/√time from the nearest run).
pub fn error_at(pts: &[(f64, f64)], f: Family, seconds: f64) -> Option<(f64, bool)> {
    if let Some(e) = interpolate_loglog(pts, seconds) {
        return Some((e, false));
    }
    if !f.converges_as_monte_carlo() || pts.is_empty() {
        return None;
    }
    let &(t, e) = if seconds < pts[0].0 {
        &pts[0]
    } else {
        pts.last().expect("non-empty")
    };
    Some((e * (t / seconds).sqrt(), true))
}

/// The time a family needs to reach `target` error (equal quality).
pub fn time_to_reach(pts: &[(f64, f64)], f: Family, target: f64) -> Option<Reach> {
    let &(t0, e0) = pts.first()?;
    if e0 <= target {
        return Some(Reach::AtMost(t0));
    }
    for w in pts.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if y0 > target && y1 <= target {
            // Interpolate time against error on log-log axes.
            let t = (target / y0).ln() / (y1 / y0).ln();
            return Some(Reach::Within((x0.ln() + t * (x1 / x0).ln()).exp()));
        }
    }
    let best = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    if f.converges_as_monte_carlo() {
        let &(t, e) = pts.last().expect("non-empty");
        return Some(Reach::Extrapolated(t * (e / target).powi(2)));
    }
    Some(Reach::NotReached { best })
}

fn pct(x: f64) -> String {
    if !x.is_finite() {
        "—".into()
    } else if x >= 0.1 {
        format!("{:.1} %", 100.0 * x)
    } else {
        format!("{:.2} %", 100.0 * x)
    }
}

fn secs(t: f64) -> String {
    if t >= 100.0 {
        format!("{t:.0} s")
    } else if t >= 10.0 {
        format!("{t:.1} s")
    } else if t >= 0.1 {
        format!("{t:.2} s")
    } else {
        format!("{:.1} ms", t * 1e3)
    }
}

fn mib(b: Option<u64>) -> String {
    b.map(|b| format!("{:.0} MiB", b as f64 / (1u64 << 20) as f64))
        .unwrap_or_else(|| "—".into())
}

fn describe_reach(r: Option<Reach>, sg_seconds: f64) -> (String, String) {
    let ratio = |t: f64| times(t / sg_seconds);
    match r {
        None => ("—".into(), "—".into()),
        Some(Reach::Within(t)) => (secs(t), ratio(t)),
        Some(Reach::AtMost(t)) => (format!("≤ {}", secs(t)), format!("≤ {}", ratio(t))),
        Some(Reach::Extrapolated(t)) => (
            format!("≈ {} (extrapolated as 1/√t)", secs(t)),
            format!("≈ {}", ratio(t)),
        ),
        Some(Reach::NotReached { best }) => {
            (format!("not reached (best {})", pct(best)), "never".into())
        }
    }
}

impl SceneReport {
    pub fn default_run(&self, f: Family) -> Option<&Run> {
        self.runs.iter().find(|r| r.family == f && r.default)
    }

    /// The run shown for a family: its default, or for path tracing the run closest to sg's
    /// time (on a log scale).
    pub fn shown_run(&self, f: Family) -> Option<&Run> {
        if let Some(r) = self.default_run(f) {
            return Some(r);
        }
        let target = self.default_run(Family::Sg).map(|r| r.seconds)?;
        self.runs.iter().filter(|r| r.family == f).min_by(|a, b| {
            (a.seconds / target)
                .ln()
                .abs()
                .total_cmp(&(b.seconds / target).ln().abs())
        })
    }

    /// The reference's own noise (rel_rmse), estimated from the path tracer's most sampled
    /// run: the reference is the same estimator with `reference_spp × scale²` samples per
    /// compared pixel, and Monte Carlo error falls as 1/√samples. (That run's error includes
    /// the reference's noise too, so this slightly overestimates it.)
    pub fn reference_noise(&self) -> Option<f64> {
        let r = self
            .runs
            .iter()
            .filter(|r| r.family == Family::PathTracing)
            .max_by_key(|r| r.param)?;
        let n = r.param? as f64;
        let s = &self.settings;
        let m = s.reference_spp as f64 * (s.reference_scale * s.reference_scale) as f64;
        Some(r.rel_rmse * (n / m).sqrt())
    }

    /// Families present, in report order.
    pub fn families(&self) -> Vec<Family> {
        Family::ALL
            .into_iter()
            .filter(|f| self.runs.iter().any(|r| r.family == *f))
            .collect()
    }

    /// The error-versus-time plot.
    pub fn plot(&self) -> Plot {
        let series = self
            .families()
            .into_iter()
            .map(|f| Series {
                label: f.name().to_string(),
                color: f.color(),
                dashed: false,
                markers: true,
                points: curve(&self.runs, f),
            })
            .collect();
        Plot {
            title: format!("{}: one-bounce error against render time", self.scene),
            x_label: "render time (s)".into(),
            y_label: "rel_rmse".into(),
            log_y: true,
            log_x: true,
            series,
            ..Plot::default()
        }
    }

    /// The scene's page (`report.md`); images are named `<stem>.png` and `<stem>-error.png`.
    pub fn markdown(&self) -> String {
        let s = &self.settings;
        let mut o = String::new();
        let sg = self.default_run(Family::Sg);
        let _ = writeln!(o, "# {}: every method against the reference\n", self.scene);
        let _ = writeln!(
            o,
            "Written by `interreflect report {}` (this page, its images and `report.json`; \
             `docs/report.md` explains every column). One-bounce (indirect) light only, the \
             light the methods approximate: the direct light is exact and the same in all of \
             them. It is {} of this image's light.\n",
            self.scene_file,
            pct(self.indirect_share)
        );
        let _ = writeln!(
            o,
            "- **Methods:** {}×{} pixels, {} sample{} per pixel (the path tracer: as many as \
             its sweep says), {} threads on {}, no GPU used.",
            self.width,
            self.height,
            s.spp,
            if s.spp == 1 { "" } else { "s" },
            self.threads,
            if self.machine.is_empty() {
                "the CPU"
            } else {
                &self.machine
            }
        );
        let _ = writeln!(
            o,
            "- **Reference:** the path tracer at {}×{} with {} spp (seed {}), box-filtered to \
             {}×{}; it took {} and is cached.",
            self.width * s.reference_scale,
            self.height * s.reference_scale,
            s.reference_spp,
            s.reference_seed,
            self.width,
            self.height,
            secs(self.reference_seconds)
        );
        if let Some(noise) = self.reference_noise() {
            let _ = writeln!(
                o,
                "- **The reference's own noise** is about {} rel_rmse (from the path tracer's \
                 runs: the same estimator with fewer samples); errors that close to it cannot \
                 be told apart.",
                pct(noise)
            );
        }
        let _ = writeln!(
            o,
            "- **Times** are render times on this machine (scene loading and BVH excluded; \
             each method's own precomputation included: the tree, the VPLs, prt's transfer).\n"
        );
        for (f, why) in &self.skipped {
            let _ = writeln!(o, "- **{} skipped:** {why}", f.name());
        }
        if !self.skipped.is_empty() {
            o.push('\n');
        }

        // Images.
        let shown: Vec<(Family, &Run)> = self
            .families()
            .into_iter()
            .filter_map(|f| self.shown_run(f).map(|r| (f, r)))
            .collect();
        let _ = writeln!(o, "## Images\n");
        let _ = writeln!(
            o,
            "One-bounce light at {:+.1} EV; below each, its relative error against the \
             reference (colour scale 0–50 %). The first column is the whole image (direct + \
             the reference's one bounce) for orientation.\n",
            self.exposure
        );
        let mut head = String::from("| scene | reference |");
        let mut sep = String::from("|---|---|");
        let mut row = String::from(
            "| <img src=\"scene.png\" width=\"192\"> | <img src=\"reference.png\" width=\"192\"> |",
        );
        let mut err = String::from("| | |");
        for (f, r) in &shown {
            let setting = if r.param.is_none() {
                String::new()
            } else {
                format!(", {}", run_setting(r))
            };
            let _ = write!(head, " {}{setting} |", f.name());
            sep.push_str("---|");
            let _ = write!(row, " <img src=\"{}.png\" width=\"192\"> |", f.stem());
            let _ = write!(err, " <img src=\"{}-error.png\" width=\"192\"> |", f.stem());
        }
        let _ = writeln!(o, "{head}\n{sep}\n{row}\n{err}\n");

        // Metrics.
        let _ = writeln!(o, "## Metrics\n");
        let _ = writeln!(
            o,
            "Each method at its default setting (path tracing: the run nearest sg's time).\n"
        );
        let _ = writeln!(o, "{METRIC_HEADER}");
        for (f, r) in &shown {
            let _ = writeln!(o, "{}", metric_row(f.name(), r));
        }
        o.push('\n');

        if let Some(sg) = sg {
            let _ = writeln!(o, "## Equal time\n");
            let _ = writeln!(
                o,
                "Each method's error at sg's time ({}), interpolated between its runs on \
                 log-log axes (path tracing also extrapolated as 1/√t); sg's rel_rmse is {}.\n",
                secs(sg.seconds),
                pct(sg.rel_rmse)
            );
            let _ = writeln!(
                o,
                "| method | rel_rmse at {} | its error ÷ sg's |\n|---|---|---|",
                secs(sg.seconds)
            );
            for f in self.families() {
                if f == Family::Sg {
                    continue;
                }
                let pts = curve(&self.runs, f);
                match error_at(&pts, f, sg.seconds) {
                    Some((e, extrapolated)) => {
                        let _ = writeln!(
                            o,
                            "| {} | {}{} | {} |",
                            f.name(),
                            pct(e),
                            if extrapolated { " (extrapolated)" } else { "" },
                            times(e / sg.rel_rmse)
                        );
                    }
                    None => {
                        let range = match (pts.first(), pts.last()) {
                            (Some(a), Some(b)) if pts.len() > 1 => {
                                format!("its runs took {} to {}", secs(a.0), secs(b.0))
                            }
                            (Some(a), _) => format!("its run took {}", secs(a.0)),
                            _ => "no runs".into(),
                        };
                        let _ = writeln!(o, "| {} | — ({range}) | — |", f.name());
                    }
                }
            }
            o.push('\n');

            let _ = writeln!(o, "## Equal quality\n");
            let _ = writeln!(
                o,
                "The time each method needs to reach sg's rel_rmse ({}), interpolated between its \
                 runs; \"never\" means no setting measured reached it (a bias that more \
                 samples do not remove, e.g. clamped VPLs or SH's low frequencies).\n",
                pct(sg.rel_rmse)
            );
            let _ = writeln!(
                o,
                "| method | time to reach {} | ÷ sg's time |\n|---|---|---|",
                pct(sg.rel_rmse)
            );
            for f in self.families() {
                if f == Family::Sg {
                    continue;
                }
                let (t, ratio) = describe_reach(
                    time_to_reach(&curve(&self.runs, f), f, sg.rel_rmse),
                    sg.seconds,
                );
                let _ = writeln!(o, "| {} | {t} | {ratio} |", f.name());
            }
            o.push('\n');
        }

        let _ = writeln!(o, "## Error against time\n");
        let _ = writeln!(o, "<img src=\"error-vs-time.png\" width=\"640\">\n");
        let _ = writeln!(o, "## Every run\n");
        let _ = writeln!(o, "{METRIC_HEADER}");
        for r in &self.runs {
            let method = format!(
                "{}{}",
                r.family.name(),
                if r.default { " (default)" } else { "" }
            );
            let _ = writeln!(o, "{}", metric_row(&method, r));
        }
        o
    }
}

/// A row of the metric tables (after [`METRIC_HEADER`]).
fn metric_row(method: &str, r: &Run) -> String {
    format!(
        "| {method} | {} | {} | {:.2e} | {:.3} | {:.3} | {} | {} |",
        run_setting(r),
        pct(r.rel_rmse),
        r.relmse,
        r.ssim,
        r.flip,
        secs(r.seconds),
        mib(r.peak_bytes)
    )
}

const METRIC_HEADER: &str = "| method | setting | rel_rmse | relMSE | SSIM | FLIP | time | peak memory |\n|---|---|---|---|---|---|---|---|";

fn run_setting(r: &Run) -> String {
    match (r.family, r.param) {
        (Family::Sg, Some(p)) => format!("max_cut {p}"),
        (Family::Vpl, Some(p)) => format!("{p} VPLs"),
        (Family::PathTracing, Some(p)) => format!("{p} spp"),
        _ => "default".into(),
    }
}

/// A ratio with two significant digits: 0.031×, 0.45×, 3.2×, 17×.
fn times(x: f64) -> String {
    if !x.is_finite() {
        "—".into()
    } else if x >= 10.0 {
        format!("{x:.0}×")
    } else if x >= 1.0 {
        format!("{x:.1}×")
    } else if x >= 0.1 {
        format!("{x:.2}×")
    } else {
        let digits = (-x.log10().floor()) as usize + 1;
        format!("{x:.digits$}×")
    }
}

/// The summary page (`results/README.md`): one row per scene report, then the other pages.
/// `pages` are (file name, title) of the other result pages.
pub fn summary(reports: &[SceneReport], pages: &[(String, String)]) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "# Results\n");
    let _ = writeln!(
        o,
        "Which method wins where, and by how much. Each scene's report (its link below) shows \
         the images, error maps, every metric and the error-against-time plot; this table is \
         written from them by `interreflect report` (`docs/report.md`). Errors are rel_rmse of \
         the one-bounce light against the path-traced reference; times are render times on \
         the machine that ran the report (the pages say which), CPU only.\n"
    );
    let _ = writeln!(
        o,
        "What the methods are here: **sg** is the spherical-Gaussian method on the CPU, with \
         exact visibility (`--visibility exact`: shadow rays to every cut node, so that its \
         error is the transport's and the cut's; `render`'s default, the approximate \
         visibility, adds 10–14 %: [`visibility.md`](visibility.md)); \
         **path tracing** is the reference's own estimator (BRDF sampling, reflector sampling \
         and light tracing under MIS) run for less time; **vpl** is instant radiosity with \
         clamped virtual point lights and shadow rays; **prt** is SH diffuse precomputed \
         radiance transfer, timed with its transfer computed afresh.\n"
    );
    let _ = writeln!(
        o,
        "| scene | sg (default): error, time | vpl at sg's time | path tracing at sg's time | prt | time path tracing needs to match sg | time vpl needs to match sg | the reference's own noise |\n|---|---|---|---|---|---|---|---|"
    );
    for r in reports {
        let Some(sg) = r.default_run(Family::Sg) else {
            let _ = writeln!(
                o,
                "| [{}]({}/report.md) | not measured | | | | | | |",
                r.scene, r.scene
            );
            continue;
        };
        let at = |f: Family| {
            let pts = curve(&r.runs, f);
            match error_at(&pts, f, sg.seconds) {
                Some((e, x)) => format!(
                    "{}{} ({} sg's)",
                    pct(e),
                    if x { "*" } else { "" },
                    times(e / sg.rel_rmse)
                ),
                None => "—".into(),
            }
        };
        let prt = r
            .default_run(Family::Prt)
            .map(|p| format!("{} in {}", pct(p.rel_rmse), secs(p.seconds)))
            .unwrap_or_else(|| "—".into());
        let reach = |f: Family| {
            describe_reach(
                time_to_reach(&curve(&r.runs, f), f, sg.rel_rmse),
                sg.seconds,
            )
            .1
        };
        let noise = r
            .reference_noise()
            .map(|n| format!("≈ {}", pct(n)))
            .unwrap_or_else(|| "—".into());
        let _ = writeln!(
            o,
            "| [{}]({}/report.md) | {} in {} | {} | {} | {} | {} | {} | {noise} |",
            r.scene,
            r.scene,
            pct(sg.rel_rmse),
            secs(sg.seconds),
            at(Family::Vpl),
            at(Family::PathTracing),
            prt,
            reach(Family::PathTracing),
            reach(Family::Vpl)
        );
    }
    let _ = writeln!(
        o,
        "\n(* extrapolated as 1/√t beyond the measured runs. \"never\": no measured setting \
         reached sg's error. Times are multiples of sg's. The last column estimates the \
         reference's own noise from the path tracer's runs: errors near it cannot be told \
         apart.)\n"
    );
    let verdicts: Vec<String> = reports.iter().filter_map(verdict).collect();
    if !verdicts.is_empty() {
        let _ = writeln!(
            o,
            "## At sg's time, per scene
"
        );
        for v in verdicts {
            let _ = writeln!(o, "- {v}");
        }
        o.push('\n');
    }
    if !pages.is_empty() {
        let _ = writeln!(o, "## Other pages\n");
        for (file, title) in pages {
            let _ = writeln!(o, "- [{title}]({file})");
        }
    }
    o
}

/// The CPU's model name (`/proc/cpuinfo`, Linux), or "an unknown CPU".
pub fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines().find_map(|l| {
                l.strip_prefix("model name")
                    .map(|r| r.trim_start_matches([' ', '\t', ':']).to_string())
            })
        })
        .unwrap_or_else(|| "an unknown CPU".into())
}

/// One sentence per scene: the lowest error at sg's time, and sg against each other method.
fn verdict(r: &SceneReport) -> Option<String> {
    let sg = r.default_run(Family::Sg)?;
    let mut at: Vec<(Family, f64, bool)> = vec![(Family::Sg, sg.rel_rmse, false)];
    for f in r.families() {
        if f == Family::Sg {
            continue;
        }
        if let Some((e, x)) = error_at(&curve(&r.runs, f), f, sg.seconds) {
            at.push((f, e, x));
        }
    }
    let (best, best_e, best_x) = at
        .iter()
        .copied()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("sg is in");
    let star = |x: bool| if x { "*" } else { "" };
    let others: Vec<String> = at
        .iter()
        .filter(|(f, _, _)| *f != Family::Sg)
        .map(|(f, e, x)| {
            let ratio = e / sg.rel_rmse;
            if ratio >= 1.0 {
                format!(
                    "{} {} worse ({}{})",
                    f.name(),
                    times(ratio),
                    pct(*e),
                    star(*x)
                )
            } else {
                format!(
                    "{} {} better ({}{})",
                    f.name(),
                    times(1.0 / ratio),
                    pct(*e),
                    star(*x)
                )
            }
        })
        .collect();
    let lead = if best == Family::Sg {
        format!("**sg has the lowest error** ({})", pct(best_e))
    } else {
        format!(
            "**{} has the lowest error** ({}{}; sg {})",
            best.name(),
            pct(best_e),
            star(best_x),
            pct(sg.rel_rmse)
        )
    };
    let rest = if others.is_empty() {
        String::new()
    } else {
        format!(": {}", others.join(", "))
    };
    Some(format!(
        "**{}** ({} per frame for sg): {lead}{rest}.",
        r.scene,
        secs(sg.seconds)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(f: Family, param: Option<u32>, default: bool, seconds: f64, err: f64) -> Run {
        Run {
            family: f,
            param,
            default,
            seconds,
            peak_bytes: Some(100 << 20),
            rel_rmse: err,
            relmse: err * err,
            ssim: 0.9,
            flip: 0.1,
        }
    }

    #[test]
    fn the_plan_includes_every_default_once_and_sweeps_in_order() {
        let mut s = Settings::quick();
        s.sg_caps = vec![3000, 100];
        s.vpl_counts = vec![200, 50];
        let p = plan(&s, Defaults::default());
        let names: Vec<String> = p.iter().map(RunSpec::name).collect();
        assert_eq!(
            names,
            [
                "sg-100",
                "sg-1000",
                "sg-3000",
                "vpl-50",
                "vpl-200",
                "path-tracing-1",
                "path-tracing-16",
                "prt"
            ]
        );
        let defaults: Vec<String> = p.iter().filter(|r| r.default).map(RunSpec::name).collect();
        assert_eq!(defaults, ["sg-1000", "vpl-200", "prt"]);
        s.families = vec![Family::Vpl];
        assert!(
            plan(&s, Defaults::default())
                .iter()
                .all(|r| r.family == Family::Vpl)
        );
    }

    #[test]
    fn loglog_interpolation_is_exact_on_power_laws() {
        // e = 0.4 t^-1/2: a power law is a straight line on log-log axes.
        let pts: Vec<(f64, f64)> = [1.0, 4.0, 16.0]
            .iter()
            .map(|&t: &f64| (t, 0.4 / t.sqrt()))
            .collect();
        let e = interpolate_loglog(&pts, 9.0).unwrap();
        assert!((e - 0.4 / 3.0).abs() < 1e-12, "{e}");
        assert_eq!(interpolate_loglog(&pts, 0.5), None);
        assert_eq!(interpolate_loglog(&pts, 17.0), None);
        // Equal quality inverts it.
        match time_to_reach(&pts, Family::Vpl, 0.1).unwrap() {
            Reach::Within(t) => assert!((t - 16.0).abs() < 1e-9, "{t}"),
            r => panic!("{r:?}"),
        }
        match time_to_reach(&pts, Family::Vpl, 0.4 / 2.0).unwrap() {
            Reach::Within(t) => assert!((t - 4.0).abs() < 1e-9, "{t}"),
            r => panic!("{r:?}"),
        }
    }

    #[test]
    fn only_monte_carlo_is_extrapolated() {
        let pts = vec![(1.0, 0.2), (4.0, 0.1)];
        // Path tracing: 1/√t beyond the last run, 4× the time halves the error.
        match time_to_reach(&pts, Family::PathTracing, 0.05).unwrap() {
            Reach::Extrapolated(t) => assert!((t - 16.0).abs() < 1e-9),
            r => panic!("{r:?}"),
        }
        let (e, x) = error_at(&pts, Family::PathTracing, 16.0).unwrap();
        assert!(x && (e - 0.05).abs() < 1e-12);
        // A biased method is not.
        assert_eq!(
            time_to_reach(&pts, Family::Vpl, 0.05),
            Some(Reach::NotReached { best: 0.1 })
        );
        assert_eq!(error_at(&pts, Family::Vpl, 16.0), None);
        // Reached by the fastest run already.
        assert_eq!(
            time_to_reach(&pts, Family::Vpl, 0.3),
            Some(Reach::AtMost(1.0))
        );
        assert_eq!(time_to_reach(&[], Family::Vpl, 0.3), None);
    }

    #[test]
    fn the_brute_force_estimate_matches_its_measurement() {
        // The dragon at 32×24, 1 spp: 150 s measured on 2 threads.
        let t = brute_estimate(266_567, 768, 2);
        assert!((t - 150.0).abs() < 5.0, "{t}");
        assert!((brute_estimate(266_567, 768, 4) - t / 2.0).abs() < 1e-9);
    }

    fn sample_report() -> SceneReport {
        SceneReport {
            scene: "ring".into(),
            scene_file: "scenes/ring.toml".into(),
            settings: Settings::quick(),
            width: 24,
            height: 24,
            threads: 2,
            machine: "a test CPU".into(),
            reference_seconds: 12.0,
            indirect_share: 0.2,
            exposure: 1.5,
            runs: vec![
                run(Family::Sg, Some(100), false, 1.0, 0.2),
                run(Family::Sg, Some(1000), true, 4.0, 0.1),
                run(Family::Vpl, Some(50), false, 1.0, 0.5),
                run(Family::Vpl, Some(200), true, 16.0, 0.2),
                run(Family::PathTracing, Some(1), false, 0.25, 1.6),
                run(Family::PathTracing, Some(16), false, 4.0, 0.4),
                run(Family::Prt, None, true, 2.0, 0.6),
            ],
            skipped: vec![(Family::SgBrute, "estimated 3 h".into())],
        }
    }

    #[test]
    fn the_page_reads_equal_time_and_equal_quality_off_the_runs() {
        let r = sample_report();
        let md = r.markdown();
        // vpl at sg's 4 s: between (1 s, 50 %) and (16 s, 20 %) on log-log axes: half-way in
        // log time, so the geometric mean of the errors, √(0.5 × 0.2) = 31.6 %.
        assert!(md.contains("| vpl | 31.6 % | 3.2× |"), "{md}");
        // Path tracing at 4 s is measured: 40 %. It reaches sg's 10 % at 4 s × (0.4/0.1)² = 64 s.
        assert!(md.contains("| path tracing | 40.0 % | 4.0× |"), "{md}");
        assert!(
            md.contains("| path tracing | ≈ 64.0 s (extrapolated as 1/√t) | ≈ 16× |"),
            "{md}"
        );
        // vpl never reaches 10 %; prt neither.
        assert!(
            md.contains("| vpl | not reached (best 20.0 %) | never |"),
            "{md}"
        );
        assert!(
            md.contains("| prt | not reached (best 60.0 %) | never |"),
            "{md}"
        );
        assert!(md.contains("**sg-brute skipped:** estimated 3 h"));
        // The most sampled path-tracing run, 16 spp at 40 %, against a reference of
        // 64 spp × 2² = 256 samples per pixel: 40 % × √(16/256) = 10 %.
        assert!((r.reference_noise().unwrap() - 0.1).abs() < 1e-12);
        assert!(md.contains("about 10.0 % rel_rmse"), "{md}");
        // The shown path-tracing run is the one nearest sg's time.
        assert_eq!(r.shown_run(Family::PathTracing).unwrap().param, Some(16));
        // The summary links the page and repeats the ratios.
        let s = summary(&[r], &[("memory.md".into(), "Memory".into())]);
        assert!(
            s.contains("[ring](ring/report.md) | 10.0 % in 4.00 s | 31.6 % (3.2× sg's)"),
            "{s}"
        );
        assert!(s.contains("- [Memory](memory.md)"));
        // At sg's 4 s: sg 10 %, vpl 31.6 %, path tracing 40 % (measured at 4 s): sg wins.
        assert!(
            s.contains(
                "**sg has the lowest error** (10.0 %): vpl 3.2× worse (31.6 %), path tracing 4.0× worse (40.0 %)"
            ),
            "{s}"
        );
    }

    #[test]
    fn ratios_keep_two_significant_digits() {
        assert_eq!(times(17.4), "17×");
        assert_eq!(times(3.24), "3.2×");
        assert_eq!(times(0.45), "0.45×");
        assert_eq!(times(0.031), "0.031×");
        assert_eq!(times(0.0034), "0.0034×");
    }

    #[test]
    fn the_report_round_trips_through_json() {
        let r = sample_report();
        let text = serde_json::to_string(&r).unwrap();
        let back: SceneReport = serde_json::from_str(&text).unwrap();
        assert_eq!(back, r);
    }

    #[test]
    fn settings_are_validated() {
        let mut s = Settings::full();
        assert!(s.validate().is_ok());
        s.width = 4;
        assert!(s.validate().unwrap_err().contains("--width"));
        let mut s = Settings::full();
        s.brute_budget = f64::NAN;
        assert!(s.validate().unwrap_err().contains("--brute-budget"));
        let mut s = Settings::full();
        s.families.clear();
        assert!(s.validate().unwrap_err().contains("--methods"));
    }
}
