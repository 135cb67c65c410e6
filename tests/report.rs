//! `interreflect report` end to end, in its quick form: the pages are written, their numbers are
//! the ones `interreflect compare` gives for the same images, the reference is cached, and bad
//! input is refused before anything is rendered or written.

use std::path::Path;
use std::process::{Command, Output};

fn interreflect(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_interreflect"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("XDG_RUNTIME_DIR", dir)
        .output()
        .expect("run interreflect")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn a_quick_report_writes_pages_whose_numbers_compare_reproduces() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("results");
    let out_s = out.to_str().unwrap();
    let args = [
        "report",
        "scenes/ring.toml",
        "--quick",
        "--out",
        out_s,
        "--methods",
        "sg,vpl,path-tracing,prt",
    ];
    let o = interreflect(&args, tmp.path());
    assert!(o.status.success(), "report failed: {}", text(&o.stderr));

    let page = out.join("ring");
    for f in [
        "report.md",
        "report.json",
        "scene.png",
        "reference.png",
        "sg.png",
        "sg-error.png",
        "vpl.png",
        "vpl-error.png",
        "path-tracing.png",
        "error-vs-time.png",
    ] {
        let p = page.join(f);
        assert!(
            p.is_file() && p.metadata().unwrap().len() > 100,
            "{} missing or empty",
            p.display()
        );
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(page.join("report.json")).unwrap()).unwrap();
    let runs = report["runs"].as_array().unwrap();
    // 2 sg caps, 2 VPL counts, 2 path-tracing sample counts; prt is skipped (point light).
    assert_eq!(runs.len(), 6, "{runs:?}");
    let skipped = report["skipped"].to_string();
    assert!(skipped.contains("point or spot lights"), "{skipped}");

    // Every run's rel_rmse and SSIM are what `compare` measures on its image against the
    // box-filtered reference: the same images through the same code, so equal up to the JSON's
    // decimal round trip (1e-12 relative).
    let work = out.join("cache").join("report").join("ring");
    for r in runs {
        let name = match (r["family"].as_str().unwrap(), r["param"].as_u64()) {
            ("path-tracing", Some(p)) => format!("path-tracing-{p}"),
            (f, Some(p)) => format!("{f}-{p}"),
            (f, None) => f.to_string(),
        };
        let img = work.join(format!("{name}.exr"));
        let c = interreflect(
            &[
                "compare",
                img.to_str().unwrap(),
                work.join("reference.exr").to_str().unwrap(),
                "--json",
            ],
            tmp.path(),
        );
        assert!(c.status.success(), "{}", text(&c.stderr));
        let m: serde_json::Value = serde_json::from_str(&text(&c.stdout)).unwrap();
        for k in ["rel_rmse", "ssim"] {
            let (a, b) = (r[k].as_f64().unwrap(), m[k].as_f64().unwrap());
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1e-30),
                "{name} {k}: report {a}, compare {b}"
            );
        }
        assert!(r["seconds"].as_f64().unwrap() > 0.0);
    }

    // The page holds the tables, and the summary links it.
    let md = std::fs::read_to_string(page.join("report.md")).unwrap();
    for h in [
        "## Metrics",
        "## Equal time",
        "## Equal quality",
        "## Error against time",
        "**prt skipped:**",
    ] {
        assert!(md.contains(h), "{h} missing from the page:\n{md}");
    }
    assert!(
        !out.join(".ring.partial").exists(),
        "the staging directory was left behind"
    );
    let summary = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(summary.contains("[ring](ring/report.md)"), "{summary}");

    // --summary-only rewrites the summary from the reports alone, identically.
    std::fs::remove_file(out.join("README.md")).unwrap();
    let o = interreflect(&["report", "--summary-only", "--out", out_s], tmp.path());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(
        std::fs::read_to_string(out.join("README.md")).unwrap(),
        summary
    );

    // A second run reads the reference from the cache and gives the same reference image.
    let before = std::fs::read(work.join("reference.exr")).unwrap();
    let o = interreflect(&args, tmp.path());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("reference from the cache"),
        "{}",
        text(&o.stderr)
    );
    assert_eq!(std::fs::read(work.join("reference.exr")).unwrap(), before);
}

#[test]
fn bad_input_is_refused_before_anything_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("results");
    let out_s = out.to_str().unwrap();
    let cases: [(&[&str], &str); 4] = [
        (
            &[
                "report",
                "scenes/ring.toml",
                "scenes/no-such-scene.toml",
                "--out",
                out_s,
            ],
            "scenes/no-such-scene.toml",
        ),
        (
            &["report", "scenes/ring.toml", "--width", "2", "--out", out_s],
            "--width 2",
        ),
        (
            &[
                "report",
                "scenes/ring.toml",
                "--brute-budget=-1",
                "--out",
                out_s,
            ],
            "--brute-budget",
        ),
        (
            &[
                "report",
                "scenes/ring.toml",
                "scenes/ring.toml",
                "--out",
                out_s,
            ],
            "also named \"ring\"",
        ),
    ];
    for (args, needle) in cases {
        let o = interreflect(args, tmp.path());
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        let err = text(&o.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
    // An unknown method is clap's error (exit 2), naming the choices.
    let o = interreflect(
        &["report", "--methods", "sg,magic", "--out", out_s],
        tmp.path(),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("path-tracing"),
        "{}",
        text(&o.stderr)
    );
    assert!(!out.exists());
}
