//! Progress reporting and cancellation for long work (renders, precomputation): the work
//! counts units as it finishes them, and stops early when asked to.

use std::sync::atomic::AtomicBool;

/// Progress reporting and cancellation, shared by the worker threads.
pub struct Progress<'a> {
    /// Called with the number of work units just finished (each long job defines its units, e.g.
    /// `render::cpu::reference::work_units`).
    pub done: &'a (dyn Fn(u64) + Sync),
    /// When set, the work stops early and returns `None`.
    pub cancel: &'a AtomicBool,
}

/// A progress sink that ignores everything (library use, tests).
pub fn no_progress(_: u64) {}
