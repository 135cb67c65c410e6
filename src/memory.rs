//! The memory budget: an up-front estimate of a render's peak memory, checked before the
//! meshes are loaded, so that a scene too large for the machine is refused with a clear
//! message instead of being killed by the out-of-memory killer half-way.
//!
//! The estimate is a sum of parts (scene arrays, BVH, the method's own data, the image), each
//! a per-triangle, per-vertex or per-pixel cost measured on the dragon at 11k to 871k triangles
//! (`scripts/memory-results.sh`, `results/memory.md`) and rounded up. It is meant to be an upper
//! bound within about a factor of two of what is measured, not an exact prediction;
//! `docs/robustness.md` lists the costs and how they were found.

use crate::render::{Method, Visibility};

/// One mebibyte.
pub const MIB: u64 = 1 << 20;
/// One gibibyte.
pub const GIB: u64 = 1 << 30;

/// The budget used when neither `--memory-budget` nor `INTERREFLECT_MEMORY_BUDGET` sets one:
/// this fraction of the machine's physical memory.
pub const DEFAULT_FRACTION: f64 = 0.75;

/// The budget assumed when the physical memory cannot be read (`/proc/meminfo`).
pub const FALLBACK_BUDGET: u64 = 8 * GIB;

/// The environment variable that sets the budget when the command line does not.
pub const BUDGET_ENV: &str = "INTERREFLECT_MEMORY_BUDGET";

/// A memory budget in bytes, or none (`off`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    pub bytes: Option<u64>,
    /// Where the budget came from, for messages.
    pub source: BudgetSource,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BudgetSource {
    /// `--memory-budget`.
    Flag,
    /// `INTERREFLECT_MEMORY_BUDGET`.
    Env,
    /// The default fraction of the physical memory (or the fallback).
    Default,
}

impl Budget {
    /// The budget from `--memory-budget` (if given), else `INTERREFLECT_MEMORY_BUDGET` (if set),
    /// else [`DEFAULT_FRACTION`] of the physical memory. A malformed value is an error naming
    /// where it came from.
    pub fn resolve(flag: Option<&str>) -> Result<Budget, String> {
        if let Some(f) = flag {
            return parse_size(f)
                .map(|bytes| Budget {
                    bytes,
                    source: BudgetSource::Flag,
                })
                .map_err(|e| format!("--memory-budget: {e}"));
        }
        if let Some(v) = std::env::var_os(BUDGET_ENV) {
            let v = v.to_string_lossy();
            return parse_size(&v)
                .map(|bytes| Budget {
                    bytes,
                    source: BudgetSource::Env,
                })
                .map_err(|e| format!("{BUDGET_ENV}: {e}"));
        }
        Ok(Budget {
            bytes: Some(default_budget()),
            source: BudgetSource::Default,
        })
    }

    /// How the user changes the budget, for messages.
    pub fn describe(&self) -> String {
        let b = match self.bytes {
            Some(b) => format_bytes(b),
            None => "off".into(),
        };
        match self.source {
            BudgetSource::Flag => format!("{b} (--memory-budget)"),
            BudgetSource::Env => format!("{b} ({BUDGET_ENV})"),
            BudgetSource::Default => format!(
                "{b} ({:.0} % of the physical memory; set --memory-budget or {BUDGET_ENV})",
                DEFAULT_FRACTION * 100.0
            ),
        }
    }

    /// `Err(message)` when `estimate` exceeds the budget.
    pub fn check(&self, estimate: &Estimate, what: &str) -> Result<(), String> {
        match self.bytes {
            Some(b) if estimate.total() > b => Err(format!(
                "{what} need an estimated {} ({}), more than the memory budget of {}",
                format_bytes(estimate.total()),
                estimate.breakdown(),
                self.describe()
            )),
            _ => Ok(()),
        }
    }
}

/// [`DEFAULT_FRACTION`] of the physical memory, or [`FALLBACK_BUDGET`].
pub fn default_budget() -> u64 {
    physical_memory()
        .map(|m| (m as f64 * DEFAULT_FRACTION) as u64)
        .unwrap_or(FALLBACK_BUDGET)
}

/// Total physical memory from `/proc/meminfo` (Linux), if readable.
pub fn physical_memory() -> Option<u64> {
    proc_kib("/proc/meminfo", "MemTotal:")
}

/// This process's peak resident memory (`VmHWM` in `/proc/self/status`, Linux), if readable.
pub fn peak_rss() -> Option<u64> {
    proc_kib("/proc/self/status", "VmHWM:")
}

/// The bytes of a `KEY  N kB` line of a `/proc` file.
fn proc_kib(file: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(file).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Parses a size: `off` (no budget), or a number with an optional unit — `B`, `K`/`KB`/`KiB`,
/// `M`/`MB`/`MiB`, `G`/`GB`/`GiB`, `T`/`TB`/`TiB`, case-insensitive, all powers of 1024 (a
/// memory budget is about RAM). A bare number is in bytes. `Some(bytes)`, or `None` for `off`.
pub fn parse_size(text: &str) -> Result<Option<u64>, String> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("off") || t.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let unit = unit.trim().to_ascii_lowercase();
    let value: f64 = num.parse().map_err(|_| {
        format!("'{text}' is not a size (use a size such as 512MiB, 4GiB or 16G, or 'off')")
    })?;
    let scale = match unit.as_str() {
        "" | "b" => 1,
        "k" | "kb" | "kib" => 1 << 10,
        "m" | "mb" | "mib" => MIB,
        "g" | "gb" | "gib" => GIB,
        "t" | "tb" | "tib" => 1 << 40,
        _ => {
            return Err(format!(
                "'{text}' has an unknown unit '{unit}' (use a size such as 512MiB, 4GiB or 16G, or 'off')"
            ));
        }
    };
    let bytes = value * scale as f64;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < 2f64.powi(63)) {
        return Err(format!(
            "'{text}' must be at least 1 byte and below 8 EiB (or 'off')"
        ));
    }
    Ok(Some(bytes as u64))
}

/// Describes a render for [`Budget::check`]'s message (which continues "need an estimated ...").
pub fn describe_workload(w: &Workload, method: &str, width: u32, height: u32) -> String {
    format!(
        "{} triangles and {} vertices rendered with --method {method} at {width}x{height}",
        thousands(w.triangles),
        thousands(w.vertices)
    )
}

/// 1234567 → "1,234,567".
pub fn thousands(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `1536 MiB` → "1.50 GiB"; below a mebibyte, in KiB.
pub fn format_bytes(b: u64) -> String {
    if b >= GIB {
        format!("{:.2} GiB", b as f64 / GIB as f64)
    } else if b >= MIB {
        format!("{:.0} MiB", b as f64 / MIB as f64)
    } else {
        format!("{:.0} KiB", (b as f64 / 1024.0).ceil())
    }
}

/// What a render will hold in memory, as far as the estimate needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Workload {
    pub method: Method,
    pub visibility: Visibility,
    /// All triangles and vertices of the scene.
    pub triangles: u64,
    pub vertices: u64,
    /// Image pixels (width × height).
    pub pixels: u64,
    /// Pixel samples (pixels × spp): sg keeps every sample's primary hit.
    pub samples: u64,
    /// Texels of the environment map (0 without one).
    pub environment_texels: u64,
    /// sg with a cut per receiver vertex: the nodes a cut may hold (the cap, or 1000 without one).
    pub vertex_cut_nodes: Option<u64>,
    /// prt: SH order (coefficients per channel = order²).
    pub prt_order: u64,
    /// prt: whether the relighting runs on the GPU (the transfer is uploaded, and staged).
    pub prt_gpu: bool,
    /// Light sources whose reflector lighting sg computes (point, spot, directional).
    pub lights: u64,
    /// sg `--visibility approx`: bytes of one light's visibility maps at tree nodes
    /// ([`node_map_bytes`]; 0 otherwise).
    pub node_map_bytes: u64,
}

/// Bytes of one light's visibility maps at tree nodes: at most `node_maps` maps of
/// `resolution`² texels of two f32 moments.
pub fn node_map_bytes(node_maps: u32, resolution: u32) -> u64 {
    node_maps as u64 * (resolution as u64).pow(2) * 8
}

/// An estimate of peak memory: named parts in bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    pub parts: Vec<(&'static str, u64)>,
}

impl Estimate {
    pub fn total(&self) -> u64 {
        self.parts.iter().map(|p| p.1).sum()
    }

    /// "scene 120 MiB + BVH 80 MiB + ...", largest first, parts under 1 % of the total left out.
    pub fn breakdown(&self) -> String {
        let total = self.total().max(1);
        let mut parts: Vec<_> = self.parts.iter().filter(|p| p.1 * 100 >= total).collect();
        parts.sort_by_key(|p| std::cmp::Reverse(p.1));
        parts
            .iter()
            .map(|(n, b)| format!("{n} {}", format_bytes(*b)))
            .collect::<Vec<_>>()
            .join(" + ")
    }
}

/// The estimated peak memory of a render (see the module documentation).
pub fn estimate(w: &Workload) -> Estimate {
    let t = w.triangles;
    let v = w.vertices;
    let mut parts = vec![
        // The process itself, thread stacks, the allocator's slack.
        ("runtime", costs::RUNTIME),
        // Positions, normals, indices, per-triangle object ids, and the meshes as loaded
        // (freed once merged, but alive at the same time).
        (
            "scene",
            t * costs::SCENE_PER_TRIANGLE + v * costs::SCENE_PER_VERTEX,
        ),
        ("BVH", t * costs::BVH_PER_TRIANGLE),
        ("image", w.pixels * costs::IMAGE_PER_PIXEL),
    ];
    if w.environment_texels > 0 {
        parts.push((
            "environment map",
            w.environment_texels * costs::ENVIRONMENT_PER_TEXEL,
        ));
    }
    match w.method {
        Method::Reference | Method::Direct => {}
        Method::Sg | Method::SgBrute => {
            parts.push((
                "SG reflectors",
                costs::SG_FIXED + t * costs::SG_PER_TRIANGLE,
            ));
            parts.push(("primary hits", w.samples * costs::SG_PER_SAMPLE));
            if let Some(n) = w.vertex_cut_nodes {
                // One cut (node ids, u32) per receiver vertex seen by some pixel, per light.
                let vertices = v.min(w.pixels);
                parts.push(("vertex cuts", vertices * n * 4 * w.lights.max(1)));
            }
            if w.visibility != Visibility::Exact {
                parts.push(("shadow maps", costs::SHADOW_MAPS));
            }
            if w.visibility == Visibility::Approx && w.node_map_bytes > 0 {
                parts.push(("node visibility maps", w.node_map_bytes * w.lights.max(1)));
            }
        }
        Method::Vpl => {
            parts.push(("primary hits", w.samples * costs::SG_PER_SAMPLE));
            if w.visibility != Visibility::Exact {
                parts.push(("shadow maps", costs::SHADOW_MAPS));
            }
        }
        Method::Prt => {
            let coeffs = w.prt_order * w.prt_order;
            // RGB f32 transfer per vertex, once while it is computed and once as the result.
            parts.push((
                "PRT transfer",
                v * coeffs * 3 * 4 * costs::PRT_TRANSFER_COPIES,
            ));
            parts.push(("PRT rays", v * costs::PRT_PER_VERTEX));
            if w.prt_gpu {
                parts.push(("GPU device", costs::GPU_DEVICE + v * coeffs * 3 * 4));
            }
        }
    }
    Estimate { parts }
}

/// The measured costs the estimate adds up (bytes), each rounded up from the fits in
/// `results/memory.md` (dragon 13k–874k triangles; about 15 % above what was measured).
pub mod costs {
    use super::MIB;
    /// The process, thread stacks, the allocator's slack (11–12 MiB measured at 13k triangles).
    pub const RUNTIME: u64 = 16 * MIB;
    /// Loading (the decompressed file, the parsed and the cleaned mesh alive together) and the
    /// merged scene arrays.
    pub const SCENE_PER_TRIANGLE: u64 = 160;
    pub const SCENE_PER_VERTEX: u64 = 64;
    /// obvhs's BVH and the triangle copies it traverses. Together with the scene: 416 bytes a
    /// triangle at 2 triangles a vertex, against 391 measured (reference and direct).
    pub const BVH_PER_TRIANGLE: u64 = 224;
    /// The image (RGB f32), its tonemapped copy and the encoders' buffers.
    pub const IMAGE_PER_PIXEL: u64 = 64;
    /// An environment map: RGB f32 texels and the sampling tables.
    pub const ENVIRONMENT_PER_TEXEL: u64 = 32;
    /// sg, sg-brute: the split reflector pieces, their lighting and lobes, and the tree (sg).
    /// Measured: 1000 bytes a triangle above the reference, plus 80 MiB for the floor and wall
    /// pieces of the dragon scenes.
    pub const SG_FIXED: u64 = 96 * MIB;
    pub const SG_PER_TRIANGLE: u64 = 1088;
    /// sg: each pixel sample's primary hit (20 bytes) and its share of the image.
    pub const SG_PER_SAMPLE: u64 = 32;
    /// vsm / approx: the shadow maps and imperfect shadow maps at their default sizes.
    pub const SHADOW_MAPS: u64 = 64 * MIB;
    /// prt: copies of the transfer alive at once (direct, bounce, their sum for relighting,
    /// and the encoded cache file).
    pub const PRT_TRANSFER_COPIES: u64 = 4;
    /// prt: per-vertex ray and sample state while the transfer is computed.
    pub const PRT_PER_VERTEX: u64 = 64;
    /// The wgpu device on lavapipe (about 105 MiB measured) and its staging buffers.
    pub const GPU_DEVICE: u64 = 128 * MIB;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_powers_of_1024() {
        assert_eq!(parse_size("off"), Ok(None));
        assert_eq!(parse_size(" OFF "), Ok(None));
        assert_eq!(parse_size("4GiB"), Ok(Some(4 * GIB)));
        assert_eq!(parse_size("4 gb"), Ok(Some(4 * GIB)));
        assert_eq!(parse_size("16G"), Ok(Some(16 * GIB)));
        assert_eq!(parse_size("512MiB"), Ok(Some(512 * MIB)));
        assert_eq!(parse_size("1.5G"), Ok(Some(3 * GIB / 2)));
        assert_eq!(parse_size("64k"), Ok(Some(64 * 1024)));
        assert_eq!(parse_size("1000"), Ok(Some(1000)));
        for bad in [
            "",
            "G",
            "4 parsecs",
            "-1G",
            "0",
            "0.1",
            "nan",
            "1e3",
            "1.2.3G",
            "99999999T",
        ] {
            let e = parse_size(bad).expect_err(bad);
            assert!(e.contains(&format!("'{bad}'")), "{bad}: {e}");
        }
    }

    #[test]
    fn bytes_are_formatted_readably() {
        assert_eq!(format_bytes(3 * GIB / 2), "1.50 GiB");
        assert_eq!(format_bytes(300 * MIB), "300 MiB");
        assert_eq!(format_bytes(1000), "1 KiB");
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1000), "1,000");
        assert_eq!(thousands(873_607), "873,607");
    }

    fn workload(method: Method) -> Workload {
        Workload {
            method,
            visibility: Visibility::Exact,
            triangles: 100_000,
            vertices: 50_000,
            pixels: 512 * 384,
            samples: 512 * 384 * 4,
            environment_texels: 0,
            vertex_cut_nodes: None,
            prt_order: 8,
            prt_gpu: false,
            lights: 1,
            node_map_bytes: node_map_bytes(8000, 32),
        }
    }

    #[test]
    fn the_estimate_grows_with_every_input_it_depends_on() {
        for method in [
            Method::Reference,
            Method::Direct,
            Method::Sg,
            Method::SgBrute,
            Method::Vpl,
            Method::Prt,
        ] {
            let w = workload(method);
            let base = estimate(&w).total();
            let more = |f: &dyn Fn(&mut Workload)| {
                let mut w2 = w;
                f(&mut w2);
                estimate(&w2).total()
            };
            assert!(more(&|w| w.triangles *= 2) > base, "{method:?} triangles");
            assert!(more(&|w| w.pixels *= 2) > base, "{method:?} pixels");
            if matches!(method, Method::Sg | Method::SgBrute | Method::Vpl) {
                assert!(more(&|w| w.samples *= 2) > base, "{method:?} samples");
            }
            assert!(
                more(&|w| w.environment_texels = 1 << 20) > base,
                "{method:?} env"
            );
            if method == Method::Prt {
                assert!(more(&|w| w.vertices *= 2) > base);
                assert!(more(&|w| w.prt_order = 16) > base);
                assert!(more(&|w| w.prt_gpu = true) > base);
            }
            if method == Method::Sg {
                assert!(more(&|w| w.vertex_cut_nodes = Some(1000)) > base);
                assert!(more(&|w| w.visibility = Visibility::Approx) > base);
                let approx = more(&|w| w.visibility = Visibility::Approx);
                assert!(
                    more(&|w| {
                        w.visibility = Visibility::Approx;
                        w.node_map_bytes *= 4;
                    }) > approx
                );
            }
        }
    }

    #[test]
    fn the_budget_check_names_the_total_the_parts_and_the_budget() {
        let e = estimate(&workload(Method::Prt));
        let b = Budget {
            bytes: Some(e.total() - 1),
            source: BudgetSource::Flag,
        };
        let msg = b.check(&e, "the triangles of --method prt").unwrap_err();
        assert!(msg.contains("--method prt need an estimated"), "{msg}");
        assert!(msg.contains("PRT transfer"), "{msg}");
        assert!(msg.contains("(--memory-budget)"), "{msg}");
        let fits = Budget {
            bytes: Some(e.total()),
            source: BudgetSource::Flag,
        };
        assert_eq!(fits.check(&e, "x"), Ok(()));
        let off = Budget {
            bytes: None,
            source: BudgetSource::Flag,
        };
        assert_eq!(off.check(&e, "x"), Ok(()));
    }
}
