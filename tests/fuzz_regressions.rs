//! Replays every stored fuzzing input: `tests/data/fuzz/<target>/*` goes through the body of
//! fuzz target `<target>` (`fuzz/harness.rs`, shared with the fuzz targets), which must return
//! `Ok` or an `Err` whose message is non-empty and names the input — never panic, and never
//! accept data that breaks the mesh/scene/image invariants the harness checks.
//!
//! A panic counts even when something catches it (the glTF loader runs the `gltf` crate under
//! `catch_unwind` as a last resort): libFuzzer aborts on any panic, and so does this test.
//!
//! The inputs are crashes found by `cargo fuzz` (fixed since) and hand-made nasty inputs
//! (truncated headers, huge declared counts, NaN coordinates, out-of-range indices, ...);
//! see docs/robustness.md, "Fuzzing".

#[path = "../fuzz/harness.rs"]
mod harness;

use std::cell::Cell;
use std::path::Path;
use std::sync::Once;

thread_local! {
    /// Panics on this thread so far, caught or not.
    static PANICS: Cell<usize> = const { Cell::new(0) };
}

/// Counts every panic on the thread where it happens, then prints it as usual.
fn count_panics() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            PANICS.with(|p| p.set(p.get() + 1));
            previous(info);
        }));
    });
}

/// Feeds every file of `tests/data/fuzz/<target>/` to `run`; returns how many were accepted.
fn replay(target: &str, run: fn(&[u8]) -> Result<(), String>) -> usize {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/fuzz")
        .join(target);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no inputs in {}", dir.display());
    count_panics();
    let mut accepted = 0;
    for file in &files {
        let bytes = std::fs::read(file).unwrap();
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let panics = PANICS.with(Cell::get);
        let result = std::panic::catch_unwind(|| run(&bytes));
        assert_eq!(
            PANICS.with(Cell::get),
            panics,
            "{target}/{name}: panicked, even if the panic was caught (see the message above)"
        );
        match result {
            Ok(Ok(())) => {
                eprintln!("{target}/{name}: accepted");
                accepted += 1;
            }
            Ok(Err(msg)) => {
                // Shown with --nocapture: what the library says about each input.
                eprintln!("{target}/{name}: {msg}");
                assert!(!msg.trim().is_empty(), "{target}/{name}: empty error");
            }
            Err(_) => unreachable!("a panic is counted above"),
        }
    }
    accepted
}

#[test]
fn scene_toml_inputs() {
    replay("scene_toml", harness::scene_toml);
}

#[test]
fn ply_inputs() {
    replay("ply", harness::ply);
}

#[test]
fn obj_inputs() {
    replay("obj", harness::obj);
}

#[test]
fn gltf_inputs() {
    replay("gltf", harness::gltf);
}

#[test]
fn exr_inputs() {
    replay("exr", harness::exr);
}

#[test]
fn hdr_inputs() {
    replay("hdr", harness::hdr);
}

#[test]
fn mesh_clean_inputs() {
    replay("mesh_clean", harness::mesh_clean);
}
