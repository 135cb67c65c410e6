//! Ctrl-C: a render interrupted at any moment leaves no partial output.
//!
//! `render` installs its Ctrl-C handler before it reads the scene, polls the flag between its
//! stages and inside every parallel loop, and writes its three outputs (EXR, PNG, JSON log) only
//! after the last check, each atomically (a temporary file renamed into place). So the outcome of
//! a SIGINT is all three outputs, complete, or none at all (exit status 130 and the message
//! "interrupted: nothing was written") — never a partial or temporary file, and for prt never a
//! partial transfer-cache entry.
#![cfg(unix)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Root of the repository (for the scenes).
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every file under `dir`, recursively, relative to it.
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

fn sigint(child: &Child) {
    let pid = libc::pid_t::try_from(child.id()).expect("a pid");
    // SAFETY: kill(2) with a pid this test spawned and has not yet reaped, and a valid signal.
    let r = unsafe { libc::kill(pid, libc::SIGINT) };
    assert_eq!(r, 0, "kill(SIGINT) failed");
}

/// Waits for `child` at most `limit`; a render that ignores Ctrl-C fails the test (and is
/// killed) instead of hanging it.
fn wait(child: &mut Child, limit: Duration, what: &str) -> ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("{what}: the render did not stop within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Starts `interreflect render SCENE ARGS --output DIR/out.exr` with stderr piped; stderr lines
/// arrive on the returned channel.
fn spawn(scene: &str, args: &[&str], dir: &Path) -> (Child, mpsc::Receiver<String>) {
    let out = dir.join("out.exr");
    let mut child = Command::new(env!("CARGO_BIN_EXE_interreflect"))
        .arg("render")
        .arg(root().join(scene))
        .args(args)
        .arg("--output")
        .arg(&out)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    (child, rx)
}

/// Waits for a stderr line starting with `prefix` (at most `limit`); returns the lines so far.
fn wait_for_line(rx: &mpsc::Receiver<String>, prefix: &str, limit: Duration) -> Vec<String> {
    let start = Instant::now();
    let mut seen = Vec::new();
    while start.elapsed() < limit {
        if let Ok(line) = rx.recv_timeout(Duration::from_millis(50)) {
            let hit = line.starts_with(prefix);
            seen.push(line);
            if hit {
                return seen;
            }
        }
    }
    panic!("no line starting with {prefix:?} within {limit:?}; stderr so far: {seen:?}");
}

/// Interrupts renders that would run for minutes, once they are rendering: each must stop
/// within seconds with status 130, say so, and leave the output directory (and for prt the
/// transfer cache) empty.
#[test]
fn a_render_interrupted_mid_way_writes_nothing() {
    // Each would take well over a minute on two cores if not interrupted; `expect_line` is the
    // stderr line after which the case is inside the stage named.
    let cases: [(&str, &str, &[&str], &str); 4] = [
        (
            "reference, while path tracing",
            "scenes/ring.toml",
            &["--method", "reference", "--spp", "100000", "--width", "64"],
            "scene ",
        ),
        (
            "sg, while shading",
            "scenes/bunny.toml",
            &["--method", "sg", "--spp", "4096", "--width", "64"],
            "scene ",
        ),
        (
            "sg-brute, while shading",
            "scenes/dragon-11k.toml",
            &["--method", "sg-brute", "--spp", "64", "--width", "64"],
            "scene ",
        ),
        (
            "prt, while computing the transfer (cache enabled)",
            "scenes/prt/bunny-diffuse-env.toml",
            &[
                "--method",
                "prt",
                "--device",
                "cpu",
                "--bounces",
                "8",
                "--prt-cache",
                "cache",
            ],
            "scene ",
        ),
    ];
    for (what, scene, args, line) in cases {
        let dir = tempfile::tempdir().unwrap();
        let (mut child, rx) = spawn(scene, args, dir.path());
        wait_for_line(&rx, line, Duration::from_secs(120));
        // Past loading, into the BVH build and the method's first stage.
        std::thread::sleep(Duration::from_millis(1500));
        assert!(
            child.try_wait().unwrap().is_none(),
            "{what}: finished before it could be interrupted (make the case longer)"
        );
        sigint(&child);
        let status = wait(&mut child, Duration::from_secs(30), what);
        let stderr: Vec<String> = rx.try_iter().collect();
        assert_eq!(
            status.code(),
            Some(130),
            "{what}: status {status}; {stderr:?}"
        );
        assert!(
            stderr
                .iter()
                .any(|l| l == "interrupted: nothing was written"),
            "{what}: {stderr:?}"
        );
        assert!(
            !stderr.iter().any(|l| l.contains("panicked")),
            "{what}: {stderr:?}"
        );
        let left = files(dir.path());
        assert!(left.is_empty(), "{what}: files left behind: {left:?}");
    }
}

/// Ctrl-C at moments spread over a short render's whole life (from before the handler exists to
/// after the outputs are written): every outcome is either all three outputs, complete and
/// readable, with status 0, or nothing at all.
#[test]
fn ctrl_c_at_any_moment_leaves_all_outputs_or_none() {
    let args = ["--method", "reference", "--spp", "16", "--width", "48"];
    // How long the render takes here, to spread the interrupts over it.
    let dir = tempfile::tempdir().unwrap();
    let start = Instant::now();
    let (mut child, _rx) = spawn("scenes/ring.toml", &args, dir.path());
    let status = wait(&mut child, Duration::from_secs(300), "uninterrupted");
    let full = start.elapsed();
    assert!(
        status.success(),
        "the uninterrupted render failed: {status}"
    );
    let complete = files(dir.path());
    assert_eq!(
        complete,
        [
            PathBuf::from("out.exr"),
            "out.json".into(),
            "out.png".into()
        ]
    );

    let (mut outputs, mut nothing) = (0, 0);
    for i in 0..12 {
        // Ten moments over the measured duration, then two well after it (2× and 3×), so that
        // some renders finish even when the machine is slower than during the measurement.
        let delay = if i < 10 {
            full.mul_f64(i as f64 / 10.0)
        } else {
            full.mul_f64(2.0 + (i - 10) as f64)
        };
        let dir = tempfile::tempdir().unwrap();
        let (mut child, rx) = spawn("scenes/ring.toml", &args, dir.path());
        std::thread::sleep(delay);
        if child.try_wait().unwrap().is_none() {
            sigint(&child);
        }
        let status = wait(
            &mut child,
            Duration::from_secs(30),
            &format!("after {delay:?}"),
        );
        let left = files(dir.path());
        let stderr: Vec<String> = rx.try_iter().collect();
        assert!(
            !stderr.iter().any(|l| l.contains("panicked")),
            "after {delay:?}: {stderr:?}"
        );
        if status.success() {
            assert_eq!(left, complete, "after {delay:?}: outputs incomplete");
            let img =
                interreflect::image::read_exr(&dir.path().join("out.exr")).expect("a complete EXR");
            assert_eq!(img.width, 48);
            outputs += 1;
        } else {
            // 130 once the handler is installed; killed by the signal before that.
            use std::os::unix::process::ExitStatusExt;
            assert!(
                status.code() == Some(130) || status.signal() == Some(libc::SIGINT),
                "after {delay:?}: status {status}; {stderr:?}"
            );
            assert!(left.is_empty(), "after {delay:?}: files left: {left:?}");
            nothing += 1;
        }
    }
    // The sweep must have caught the render both before and after it finished; otherwise it
    // tested only one of the two outcomes.
    assert!(
        nothing > 0 && outputs > 0,
        "{nothing} interrupted, {outputs} finished"
    );
}
