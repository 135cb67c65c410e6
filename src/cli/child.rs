//! `interreflect render` as a child process of this executable (for `report` and `bench`):
//! each render's time and peak memory are then its own, and its JSON log says what it did.

use anyhow::{Context, bail};
use serde_json::Value;
use std::ffi::OsStr;
use std::path::Path;
use std::process::Command;

/// Runs `EXE render ARGS --output OUTPUT` (with `--quiet` when asked; otherwise its progress
/// bar shows on stderr) and returns its JSON log, written beside `output`. A render stopped by
/// Ctrl-C is the error "interrupted".
pub fn render<S: AsRef<OsStr>>(
    exe: &Path,
    args: &[S],
    output: &Path,
    quiet: bool,
) -> anyhow::Result<Value> {
    let mut cmd = Command::new(exe);
    cmd.arg("render").args(args).arg("--output").arg(output);
    if quiet {
        cmd.arg("--quiet");
    }
    let status = cmd
        .status()
        .with_context(|| format!("cannot run {}", exe.display()))?;
    if !status.success() {
        if status.code() == Some(130) {
            bail!("interrupted");
        }
        let shown: Vec<String> = args
            .iter()
            .map(|a| a.as_ref().to_string_lossy().into_owned())
            .collect();
        bail!("`render {}` failed ({status})", shown.join(" "));
    }
    let json = output.with_extension("json");
    let text = std::fs::read_to_string(&json)
        .with_context(|| format!("cannot read {}", json.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: not a render log", json.display()))
}
