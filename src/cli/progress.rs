//! Progress bars (hidden with --quiet or when stderr is not a terminal) and Ctrl-C handling.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use interreflect::render::cpu::Progress;
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};

/// A progress bar over `len` units, or a hidden one.
pub fn bar(len: u64, what: &str, quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden());
    }
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template(
            "{msg} [{bar:40.cyan/blue}] {pos}/{len} {elapsed_precise} (ETA {eta})",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    pb.set_message(what.to_string());
    pb
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Installs a Ctrl-C handler that sets a flag the renderers poll; returns the flag.
pub fn interrupt_flag() -> &'static AtomicBool {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // If a handler cannot be installed, Ctrl-C keeps its default behaviour (outputs are
        // written atomically either way).
        let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));
    });
    &INTERRUPTED
}

/// Runs `work` with a progress bar over `units` work units and the Ctrl-C flag; `None` when it
/// was interrupted (whatever `work` returned).
pub fn run<T>(units: u64, quiet: bool, work: impl FnOnce(&Progress) -> Option<T>) -> Option<T> {
    let pb = bar(units, "rendering", quiet);
    let cancel = interrupt_flag();
    let done = |n: u64| pb.inc(n);
    let result = work(&Progress {
        done: &done,
        cancel,
    });
    pb.finish_and_clear();
    result.filter(|_| !cancel.load(Ordering::SeqCst))
}
