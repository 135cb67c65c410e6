//! Helpers shared by the integration tests (`mod common;` in each).

use interreflect::render::gpu::{Gpu, adapter_required};

/// The GPU for a GPU test: `None` (the test skips, with a note) when no adapter exists, unless
/// `CI=true` asks for one, in which case the test fails.
pub fn gpu() -> Option<Gpu> {
    match Gpu::new() {
        Ok(g) => Some(g),
        Err(e) if adapter_required() => panic!("CI=true requires a GPU adapter: {e}"),
        Err(e) => {
            eprintln!("skipped (no GPU adapter): {e}");
            None
        }
    }
}
