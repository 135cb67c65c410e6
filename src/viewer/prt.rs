//! PRT in the viewer. The transfer depends on the geometry and the materials' albedos, not on
//! the light or the camera: it is computed once per material state on a thread of its own (or
//! read from `render`'s cache), so that moving the camera while it is computed does not start
//! it again. A frame is a relighting (one dot product per vertex) and the image pass.

use crate::accel::Accel;
use crate::image::Image;
use crate::precompute::prt::{
    CacheStatus, NO_DISTANT_LIGHTING, PrtOptions, cache_path, load_or_compute_at, relight_cpu,
    sh_environment, sh_lighting_with, work_units,
};
use crate::progress::Progress;
use crate::render::cpu::prt::{PrtImageOptions, render_prt_image};
use crate::scene::Scene;
use glam::Vec3;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Where the viewer reads and writes transfers: `render --method prt`'s default cache, so that
/// a transfer computed by one is read by the other.
pub const CACHE_DIR: &str = "results/cache/prt";

/// How long a frame waits for a transfer being computed before it returns a pending frame that
/// shows the progress.
const POLL: Duration = Duration::from_millis(500);

/// A transfer ready for relighting.
struct Ready {
    /// Direct plus bounce transfer, summed once (relighting is linear).
    total: Vec<Vec3>,
    /// The bounce transfer alone (indirect only); empty without bounces.
    bounce: Vec<Vec3>,
    coefficients: usize,
    vertices: usize,
    /// "read from …" or "computed in … s, cached in …".
    origin: String,
}

/// The transfer of one material state: being computed, or ready.
struct Task {
    materials_version: u64,
    done: Arc<AtomicU64>,
    total: u64,
    cancel: Arc<AtomicBool>,
    /// Set while the transfer is being read from the cache rather than computed.
    reading: Arc<AtomicBool>,
    handle: Option<JoinHandle<Option<Ready>>>,
    ready: Option<Ready>,
}

impl Drop for Task {
    fn drop(&mut self) {
        // A transfer nobody will use stops at its next work unit.
        self.cancel.store(true, Ordering::SeqCst);
    }
}

/// What a PRT frame gives back.
pub struct PrtFrame {
    pub image: Image,
    /// The transfer is still being computed: the image is black and the frame is to be asked
    /// for again.
    pub pending: bool,
    pub stages: Vec<(&'static str, f64)>,
    /// Seconds this frame waited for the transfer: not the frame's own cost.
    pub waited: f64,
    /// Shown in the panel: the transfer's progress or origin, lights PRT ignores.
    pub notices: Vec<String>,
}

impl PrtFrame {
    fn black(
        image: &PrtImageOptions,
        stages: Vec<(&'static str, f64)>,
        notices: Vec<String>,
        pending: bool,
    ) -> PrtFrame {
        PrtFrame {
            image: Image::new(image.width, image.height),
            pending,
            stages,
            notices,
            waited: 0.0,
        }
    }
}

/// The viewer's PRT state: the transfer task and the environment's SH projection.
#[derive(Default)]
pub struct PrtView {
    task: Option<Task>,
    environment: Option<Vec<Vec3>>,
    cache_dir: Option<PathBuf>,
}

impl PrtView {
    /// `cache_dir`: where transfers are read and written (`None`: never cached).
    pub fn new(cache_dir: Option<PathBuf>) -> PrtView {
        PrtView {
            cache_dir,
            ..PrtView::default()
        }
    }

    /// The transfer options of `scene`, as `render --method prt` chooses them by default.
    pub fn options(scene: &Scene) -> PrtOptions {
        let ps = scene.settings.prt;
        PrtOptions {
            order: ps.order,
            kind: ps.transfer,
            bounces: ps.bounces,
            samples: ps.samples,
            seed: scene.settings.seed,
        }
    }

    /// Renders one frame of `scene` (whose lights, materials and camera are the job's);
    /// `None` when `cancel` was set. While the transfer is computed, a frame waits at most
    /// [`POLL`] and comes back pending.
    #[allow(clippy::too_many_arguments)]
    pub fn frame(
        &mut self,
        scene: &Scene,
        accel: &Arc<Accel>,
        materials_version: u64,
        image: PrtImageOptions,
        indirect_only: bool,
        cancel: &AtomicBool,
    ) -> Option<PrtFrame> {
        let t = Instant::now();
        let opts = Self::options(scene);
        let ps = scene.settings.prt;
        let window = ps
            .window
            .window(ps.window_width.unwrap_or(2.0 * ps.order as f32));
        if self.environment.is_none()
            && let Some(env) = &scene.environment
        {
            self.environment = Some(sh_environment(env, opts.order));
        }
        let (lighting, mut notices) = sh_lighting_with(
            self.environment.as_deref(),
            &scene.lights,
            opts.order,
            window,
        );
        let mut stages = vec![("SH lighting", t.elapsed().as_secs_f64())];
        // Nothing PRT can relight: no transfer is computed for a black image.
        if notices.iter().any(|n| n == NO_DISTANT_LIGHTING) {
            notices.push(
                "prt: open a scene with a directional light or an environment map, such as scenes/prt/ring-glossy-sun.toml".into(),
            );
            return Some(PrtFrame::black(&image, stages, notices, false));
        }
        if indirect_only && opts.effective_bounces() == 0 {
            notices.push(
                "prt: indirect only needs the interreflected transfer with at least one bounce ([methods.prt] transfer = \"interreflected\", bounces ≥ 1)".into(),
            );
            return Some(PrtFrame::black(&image, stages, notices, false));
        }
        if self
            .task
            .as_ref()
            .is_none_or(|t| t.materials_version != materials_version)
        {
            self.task = Some(self.spawn(scene, accel, &opts, materials_version));
        }
        let task = self.task.as_mut().expect("spawned above");
        let waited = Instant::now();
        while task.ready.is_none() {
            let finished = task.handle.as_ref().is_none_or(|h| h.is_finished());
            if finished {
                let h = task.handle.take();
                match h.map(|h| h.join()) {
                    Some(Ok(Some(r))) => task.ready = Some(r),
                    // Cancelled (only by its own flag, which nothing else sets) or failed.
                    _ => {
                        self.task = None;
                        notices.push("prt: the transfer could not be computed".into());
                        return Some(PrtFrame::black(&image, stages, notices, false));
                    }
                }
                break;
            }
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            if waited.elapsed() >= POLL {
                let done = task.done.load(Ordering::Relaxed);
                notices.push(if task.reading.load(Ordering::Relaxed) {
                    "prt: reading the transfer from the cache".to_string()
                } else {
                    format!(
                    "prt: computing the transfer ({} rays per vertex, order {}): {:.0} %; it is cached in {} for the next time",
                    opts.samples,
                    opts.order,
                    100.0 * done as f64 / task.total.max(1) as f64,
                    self.cache_dir
                        .as_ref()
                        .map_or("no cache".into(), |d| d.display().to_string())
                    )
                });
                return Some(PrtFrame::black(&image, stages, notices, true));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let wait = waited.elapsed().as_secs_f64();
        let ready = task.ready.as_ref().expect("ready above");
        notices.insert(0, ready.origin.clone());
        let t = Instant::now();
        let transfer = if indirect_only {
            &ready.bounce
        } else {
            &ready.total
        };
        let radiance = relight_cpu(transfer, ready.coefficients, &lighting);
        debug_assert_eq!(radiance.len(), ready.vertices);
        stages.push(("relighting", t.elapsed().as_secs_f64()));
        let t = Instant::now();
        let progress = Progress {
            done: &crate::render::cpu::reference::no_progress,
            cancel,
        };
        let img = render_prt_image(scene, accel, &radiance, &image, &progress)?;
        stages.push(("image pass", t.elapsed().as_secs_f64()));
        Some(PrtFrame {
            image: img,
            pending: false,
            stages,
            notices,
            waited: wait,
        })
    }

    /// Starts computing (or reading) the transfer of `scene`'s current materials.
    fn spawn(
        &self,
        scene: &Scene,
        accel: &Arc<Accel>,
        opts: &PrtOptions,
        materials_version: u64,
    ) -> Task {
        let done = Arc::new(AtomicU64::new(0));
        let cancel = Arc::new(AtomicBool::new(false));
        let total = work_units(scene, opts);
        let (scene, accel, opts) = (scene.clone(), accel.clone(), *opts);
        let reading = Arc::new(AtomicBool::new(false));
        let (d, c, r) = (done.clone(), cancel.clone(), reading.clone());
        let cache_dir = self.cache_dir.clone();
        let handle = std::thread::Builder::new()
            .name("prt transfer".into())
            .spawn(move || {
                let t = Instant::now();
                let r2 = r.clone();
                // Work done means the cached file was unusable and the transfer is computed.
                let add = move |n: u64| {
                    r2.store(false, Ordering::Relaxed);
                    d.fetch_add(n, Ordering::Relaxed);
                };
                let progress = Progress {
                    done: &add,
                    cancel: &c,
                };
                let path = cache_dir.map(|d| cache_path(&d, &scene, &opts));
                r.store(path.as_ref().is_some_and(|p| p.exists()), Ordering::Relaxed);
                let (transfer, status) =
                    load_or_compute_at(&scene, &accel, &opts, path, &progress)?;
                let secs = t.elapsed().as_secs_f64();
                let origin = match status {
                    CacheStatus::Hit(p) => format!("prt: transfer read from {}", p.display()),
                    CacheStatus::Stored(p) => format!(
                        "prt: transfer computed in {secs:.1} s, cached in {}",
                        p.display()
                    ),
                    CacheStatus::Uncached(None) => {
                        format!("prt: transfer computed in {secs:.1} s (not cached)")
                    }
                    CacheStatus::Uncached(Some(r)) => {
                        format!("prt: transfer computed in {secs:.1} s, not cached: {r}")
                    }
                };
                let coefficients = transfer.coefficients();
                let total = transfer.total();
                Some(Ready {
                    total,
                    bounce: transfer.bounce,
                    coefficients,
                    vertices: transfer.vertices,
                    origin,
                })
            });
        Task {
            materials_version,
            done,
            total,
            cancel,
            reading,
            // A thread that cannot start leaves no handle: the frame reports the failure.
            handle: handle.ok(),
            ready: None,
        }
    }
}
