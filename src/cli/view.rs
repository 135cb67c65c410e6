//! `interreflect view`: the interactive viewer. A winit window presents, through wgpu, an egui
//! panel and the image that a worker thread renders with the same renderers as `render`
//! (`interreflect::viewer`); `docs/viewer.md` describes the controls and the scripts.

use anyhow::{Context, bail};
use interreflect::accel::Accel;
use interreflect::image::{Image, Tonemap, write_exr, write_png};
use interreflect::render::Device;
use interreflect::render::gpu::window::{Painted, WindowGpu};
use interreflect::scene::{Light, Scene};
use interreflect::viewer::camera::{
    MAX_LIGHT_ELEVATION, drag_light_direction, light_angles, light_direction, project,
};
use interreflect::viewer::script::{self, Command, MaterialField};
use interreflect::viewer::{Frame, FrameRenderer, Job, ViewMethod, ViewState};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Render N window frames, save the last full-quality image (with --screenshot) and exit.
    #[arg(long, allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// Where --frames saves the image (PNG; the EXR is written beside it).
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Run a script of viewer commands, then exit (docs/viewer.md lists them).
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Method shown first: sg, vpl, direct, prt or reference.
    #[arg(long, default_value = "sg")]
    pub method: String,
    /// Full-quality image width (default: the scene camera's, halved until at most 128).
    #[arg(long, allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Full-quality image height (default: the camera's aspect).
    #[arg(long, allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// Samples per pixel of a full-quality frame.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub spp: u32,
    /// A reference image (EXR) of the scene's camera view: the panel shows each frame's
    /// error against it when the sizes match (or the reference is an integer multiple).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Where the renderer's GPU stages run (as `render --device`).
    #[arg(long, value_enum, default_value_t = Device::Auto)]
    pub device: Device,
    /// Window size in logical pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x640")]
    pub window: String,
    /// prt: directory of the transfer cache (shared with `render --method prt`).
    #[arg(long, default_value = interreflect::viewer::prt::CACHE_DIR)]
    pub prt_cache: PathBuf,
    /// prt: neither read nor write the transfer cache.
    #[arg(long)]
    pub no_cache: bool,
}

/// Seconds of stillness after which the full-quality frame is rendered.
const SETTLE: f64 = 0.2;
/// Largest share of a full-quality frame's time that a frame while moving may take: a tenth,
/// less a margin for the frame-to-frame variation of times on a shared machine (±10 %).
const MOVING_SHARE: f64 = 0.08;
/// The smallest preview: 1/16 of the size.
const MAX_PREVIEW_FACTOR: u32 = 16;
/// Most window repaints per second (docs/viewer.md: each costs the renderer CPU time).
const REPAINT_FPS: f64 = 15.0;
/// Passes the progressive reference stops at.
const MAX_PASSES: u32 = 4096;
/// Deepest level of sg's tree whose node boxes the overlay can draw (2^8 boxes).
const MAX_BOX_DEPTH: u32 = 8;

pub fn run(args: ViewArgs) -> anyhow::Result<i32> {
    let method = ViewMethod::parse(&args.method).with_context(|| {
        format!(
            "--method {}: the viewer shows sg, vpl, direct, prt or reference",
            args.method
        )
    })?;
    let (win_w, win_h) = parse_window(&args.window)?;
    if let Some(p) = &args.screenshot {
        check_png(p, "--screenshot")?;
        if args.frames.is_none() {
            bail!("--screenshot needs --frames N (or use a script's `screenshot` command)");
        }
    }
    if let Some(0) = args.frames {
        bail!("--frames must be at least 1");
    }
    if !(1..=script::MAX_SPP).contains(&args.spp) {
        bail!(
            "--spp must be between 1 and {}, got {}",
            script::MAX_SPP,
            args.spp
        );
    }
    for (name, v) in [("--width", args.width), ("--height", args.height)] {
        if let Some(v) = v
            && !(1..=script::MAX_SIDE).contains(&v)
        {
            bail!("{name} must be between 1 and {}, got {v}", script::MAX_SIDE);
        }
    }
    let mut commands = match &args.script {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read the script {}", p.display()))?;
            script::parse(p, &text)?
        }
        None => Vec::new(),
    };
    if let Some(n) = args.frames {
        commands.push(Command::Frames(n));
        if let Some(p) = &args.screenshot {
            commands.push(Command::Screenshot(p.clone()));
        }
    }
    let scripted = !commands.is_empty();
    let reference = match &args.reference {
        Some(p) => Some(interreflect::image::read_exr(p)?),
        None => None,
    };
    // Without a display no window can open: say so before loading anything.
    if std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        bail!(
            "view needs a display, and DISPLAY is not set: run it in a desktop session or under \
             `xvfb-run -a interreflect view ...` (scripts/install-deps.sh installs xvfb), or render \
             images without a window with `interreflect render {}`",
            args.scene.display()
        );
    }
    let scene = Scene::load(&args.scene)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if scene.environment.is_some() {
        eprintln!(
            "warning: {}: environment: the viewer's sg and vpl ignore environment lighting, as `render` does",
            scene.path.display()
        );
    }
    let t = Instant::now();
    let accel = Arc::new(Accel::build(&scene.mesh.positions, &scene.mesh.indices));
    eprintln!(
        "scene {}: {} triangles, BVH {:.2} s",
        scene.name,
        scene.mesh.indices.len(),
        t.elapsed().as_secs_f64()
    );
    // The orbit's target: what the centre of the view looks at, or half the scene away.
    let cam = scene.camera;
    let focus = accel
        .intersect(cam.position, cam.forward, 0.0, f32::INFINITY)
        .map(|h| h.t)
        .unwrap_or(0.5 * scene.mesh.diagonal());
    let mut state = ViewState::new(&scene, focus);
    state.method = method;
    state.spp = args.spp;
    if let Some(w) = args.width {
        state.set_size(w, args.height.unwrap_or(0));
    } else if let Some(h) = args.height {
        let w = ((h as f64 * cam.width as f64 / cam.height.max(1) as f64).round() as u32).max(1);
        state.set_size(w, h);
    }
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow::anyhow!(
            "view cannot open a window ({e}): check DISPLAY, or run under `xvfb-run -a`, or render \
             without a window with `interreflect render {}`",
            args.scene.display()
        )
    })?;
    let prt_cache = (!args.no_cache).then(|| args.prt_cache.clone());
    let worker = Worker::start(
        scene.clone(),
        accel,
        args.device,
        prt_cache,
        event_loop.create_proxy(),
    );
    let mut app = App {
        scene,
        state,
        worker,
        window: None,
        gpu: None,
        egui: None,
        egui_state: None,
        size: (win_w, win_h),
        shown: [None, None],
        textures: [None, None],
        heatmap: None,
        version: 1,
        requested: None,
        in_flight: false,
        last_change: Instant::now(),
        last_tick: Instant::now(),
        redraw_pending: true,
        repaint_after: None,
        commands: commands.into(),
        frames_left: 0,
        scripted,
        screenshot_count: 0,
        status: String::new(),
        error: None,
        reference,
        exit_code: 0,
        moving_times: Vec::new(),
        still_times: Vec::new(),
        boxes: Vec::new(),
        fly_keys: [false; 6],
        drag_light: false,
        last_notices: Vec::new(),
        last_pending: false,
        dragging: false,
        auto_factor: 0,
        last_full: std::collections::HashMap::new(),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow::anyhow!("the viewer's event loop failed: {e}"))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    app.print_times();
    Ok(app.exit_code)
}

fn parse_window(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s
        .split_once('x')
        .with_context(|| format!("--window {s}: expected WIDTHxHEIGHT, e.g. 1024x640"))?;
    let p = |v: &str| -> anyhow::Result<u32> {
        let n: u32 = v
            .trim()
            .parse()
            .with_context(|| format!("--window {s}: {v:?} is not a whole number"))?;
        if !(200..=8192).contains(&n) {
            bail!("--window {s}: each side must be between 200 and 8192 pixels");
        }
        Ok(n)
    };
    Ok((p(w)?, p(h)?))
}

fn check_png(p: &Path, what: &str) -> anyhow::Result<()> {
    if p.extension().and_then(|e| e.to_str()) != Some("png") {
        bail!(
            "{what} {}: must end in .png (the EXR is written beside it)",
            p.display()
        );
    }
    Ok(())
}

/// A request for the worker: one job per image shown (two in split view).
struct Request {
    id: u64,
    /// Each job with its slot (0: left or the whole view, 1: right half).
    jobs: Vec<(usize, Job)>,
}

/// A frame back from the worker, for slot 0 (left, or the whole view) or 1 (right half).
struct Done {
    id: u64,
    slot: usize,
    frame: Frame,
    /// sg's tree node boxes at each depth 0..=MAX_BOX_DEPTH (empty for other methods).
    boxes: Vec<Vec<(glam::Vec3, glam::Vec3)>>,
}

/// The render thread. It renders the newest request, cancelling the one in progress when a
/// newer one arrives, and keeps refining a still progressive reference.
struct Worker {
    send: mpsc::Sender<Request>,
    recv: mpsc::Receiver<Done>,
    latest: Arc<AtomicU64>,
    cancel: Arc<AtomicBool>,
}

impl Worker {
    fn start(
        scene: Scene,
        accel: Arc<Accel>,
        device: Device,
        prt_cache: Option<PathBuf>,
        wake: winit::event_loop::EventLoopProxy<()>,
    ) -> Worker {
        let (send, jobs) = mpsc::channel::<Request>();
        let (done, recv) = mpsc::channel::<Done>();
        let latest = Arc::new(AtomicU64::new(0));
        let cancel = Arc::new(AtomicBool::new(false));
        let (l, c) = (latest.clone(), cancel.clone());
        std::thread::Builder::new()
            .name("render".into())
            .spawn(move || {
                let mut renderer = FrameRenderer::new(scene, accel, device);
                renderer.set_prt_cache(prt_cache);
                let mut next: Option<Request> = None;
                loop {
                    let mut req = match next.take() {
                        Some(r) => r,
                        None => match jobs.recv() {
                            Ok(r) => r,
                            Err(_) => return,
                        },
                    };
                    while let Ok(newer) = jobs.try_recv() {
                        req = newer;
                    }
                    c.store(false, Ordering::SeqCst);
                    if l.load(Ordering::SeqCst) != req.id {
                        continue;
                    }
                    let mut cancelled = false;
                    // The slots to render again: a still reference refines until something
                    // changes, a pending prt frame asks again until its transfer is ready.
                    let mut again = Vec::new();
                    for (slot, job) in &req.jobs {
                        let Some(frame) = renderer.render(job, &c) else {
                            cancelled = true;
                            break;
                        };
                        if frame.pending {
                            again.push((*slot, job.clone()));
                        } else if job.method == ViewMethod::Reference
                            && !job.preview
                            && job.pass + 1 < MAX_PASSES
                        {
                            let mut j = job.clone();
                            j.pass += 1;
                            again.push((*slot, j));
                        }
                        let boxes = if job.method == ViewMethod::Sg {
                            (0..=MAX_BOX_DEPTH)
                                .map(|d| renderer.node_boxes(d))
                                .collect()
                        } else {
                            Vec::new()
                        };
                        if done
                            .send(Done {
                                id: req.id,
                                slot: *slot,
                                frame,
                                boxes,
                            })
                            .is_err()
                        {
                            return;
                        }
                        let _ = wake.send_event(());
                    }
                    if !cancelled && let Ok(r) = jobs.try_recv() {
                        next = Some(r);
                    } else if !cancelled && !again.is_empty() {
                        req.jobs = again;
                        next = Some(req);
                    }
                }
            })
            .expect("the render thread starts");
        Worker {
            send,
            recv,
            latest,
            cancel,
        }
    }

    fn submit(&self, req: Request) {
        self.latest.store(req.id, Ordering::SeqCst);
        self.cancel.store(true, Ordering::SeqCst);
        let _ = self.send.send(req);
    }
}

struct Shown {
    frame: Frame,
    version: u64,
}

struct App {
    scene: Scene,
    state: ViewState,
    worker: Worker,
    window: Option<Arc<Window>>,
    gpu: Option<WindowGpu>,
    egui: Option<egui::Context>,
    egui_state: Option<egui_winit::State>,
    size: (u32, u32),
    shown: [Option<Shown>; 2],
    textures: [Option<egui::TextureHandle>; 2],
    /// The cut-size heatmap of slot 0's frame.
    heatmap: Option<egui::TextureHandle>,
    /// Bumped at every change of what is to be shown.
    version: u64,
    /// The version and quality last requested.
    requested: Option<(u64, bool)>,
    in_flight: bool,
    last_change: Instant,
    last_tick: Instant,
    /// Something asked for a repaint (input, a finished frame).
    redraw_pending: bool,
    /// egui's wish for the next repaint.
    repaint_after: Option<Duration>,
    commands: std::collections::VecDeque<Command>,
    frames_left: u32,
    scripted: bool,
    screenshot_count: u32,
    status: String,
    error: Option<anyhow::Error>,
    reference: Option<Image>,
    exit_code: i32,
    /// Frame times measured, preview (while moving) and full quality (still).
    moving_times: Vec<f64>,
    still_times: Vec<f64>,
    boxes: Vec<Vec<(glam::Vec3, glam::Vec3)>>,
    /// The preview factor the frame times call for (`adapt`), at least the panel's.
    auto_factor: u32,
    /// The last full-quality frame time of each method.
    last_full: std::collections::HashMap<ViewMethod, f64>,
    /// A mouse button is held on the image.
    dragging: bool,
    /// Left drag moves light 0 instead of the camera (the panel's toggle, or L).
    drag_light: bool,
    /// Fly keys held: W, S, D, A, E, Q.
    fly_keys: [bool; 6],
    /// The notices last written to the log (each is written when it first appears).
    last_notices: Vec<String>,
    /// The last frame back was pending.
    last_pending: bool,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attrs = Window::default_attributes()
            .with_title(format!("interreflect — {}", self.scene.name))
            .with_inner_size(winit::dpi::LogicalSize::new(self.size.0, self.size.1));
        let window = match event_loop.create_window(attrs) {
            Ok(w) => Arc::new(w),
            Err(e) => {
                self.fail(event_loop, anyhow::anyhow!("cannot open the window: {e}"));
                return;
            }
        };
        let gpu = match WindowGpu::new(window.clone()) {
            Ok(g) => g,
            Err(e) => {
                self.fail(
                    event_loop,
                    anyhow::anyhow!("the window cannot present with the GPU: {e}"),
                );
                return;
            }
        };
        eprintln!("view: window on {}", gpu.adapter);
        let ctx = egui::Context::default();
        let state = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.max_texture_side),
        );
        self.window = Some(window);
        self.gpu = Some(gpu);
        self.egui = Some(ctx);
        self.egui_state = Some(state);
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let (Some(window), Some(state)) = (self.window.clone(), self.egui_state.as_mut()) else {
            return;
        };
        let _ = state.on_window_event(&window, &event);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(s) => {
                if let Some(g) = self.gpu.as_mut() {
                    g.resize(s.width, s.height);
                }
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop, &window),
            _ => self.redraw_pending = true,
        }
    }

    fn user_event(&mut self, _event_loop: &ActiveEventLoop, _event: ()) {
        // The worker finished a frame.
        self.redraw_pending = true;
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        // Painting the window costs 50-150 ms of CPU on a software GPU (lavapipe), time the
        // renderer needs: the window is repainted only when something asks for it — input, a
        // finished frame, a damped motion or fly keys (at most REPAINT_FPS frames a second),
        // the script, egui's own animations, or the moment the view has been still long
        // enough for the full-quality frame.
        let now = Instant::now();
        let frame = self.last_tick + Duration::from_secs_f64(1.0 / REPAINT_FPS);
        let mut at: Option<Instant> = None;
        let mut want = |t: Instant| at = Some(at.map_or(t, |a: Instant| a.min(t)));
        if self.redraw_pending {
            want(frame);
        }
        if self.state.controller.moving()
            || (self.state.controller.fly && self.fly_keys.iter().any(|&k| k))
            || self.frames_left > 0
            || self.script_can_run()
        {
            want(frame);
        }
        if self.requested != Some((self.version, false)) {
            want(self.last_change + Duration::from_secs_f64(SETTLE));
        }
        if let Some(d) = self.repaint_after
            && d < Duration::from_secs(1)
        {
            want(self.last_tick + d.max(Duration::from_secs_f64(1.0 / REPAINT_FPS)));
        }
        match at {
            Some(t) if t <= now => {
                self.redraw_pending = false;
                if let Some(w) = &self.window {
                    w.request_redraw();
                }
                event_loop.set_control_flow(ControlFlow::Wait);
            }
            Some(t) => event_loop.set_control_flow(ControlFlow::WaitUntil(t)),
            None => event_loop.set_control_flow(ControlFlow::Wait),
        }
    }
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error = Some(e);
        event_loop.exit();
    }

    fn changed(&mut self) {
        self.version += 1;
        self.last_change = Instant::now();
    }

    fn methods(&self) -> Vec<ViewMethod> {
        let mut m = vec![self.state.method];
        if let Some(s) = self.state.split
            && s != self.state.method
        {
            m.push(s);
        }
        m
    }

    fn request(&mut self, preview: bool) {
        let mut st = self.state.clone();
        st.preview_factor = if self.interactive_at_full_quality() {
            1
        } else {
            st.preview_factor.max(self.auto_factor)
        };
        let jobs = self
            .methods()
            .into_iter()
            .enumerate()
            .map(|(slot, m)| (slot, st.job(self.version, m, preview)))
            .collect();
        self.worker.submit(Request {
            id: self.version * 2 + preview as u64,
            jobs,
        });
        self.requested = Some((self.version, preview));
        self.in_flight = true;
    }

    /// Frames back from the worker.
    fn receive(&mut self) {
        while let Ok(done) = self.worker.recv.try_recv() {
            let version = done.id / 2;
            let f = &done.frame;
            // A pending frame is logged once, by its notice.
            let repeated = f.pending && self.last_pending;
            self.last_pending = f.pending;
            if !f.pending {
                eprintln!(
                    "view: {} {}×{} at {} spp{}{}: {:.3} s ({})",
                    f.job.method.name(),
                    f.job.width,
                    f.job.height,
                    f.job.spp,
                    if f.job.preview { ", moving" } else { "" },
                    if f.passes > 1 {
                        format!(", pass {}", f.passes)
                    } else {
                        String::new()
                    },
                    f.seconds,
                    f.stages
                        .iter()
                        .filter(|(n, t)| *t >= 0.005 || n.contains("kept"))
                        .map(|(n, t)| format!("{n} {t:.2} s"))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            }
            if f.notices != self.last_notices && !repeated {
                for n in &f.notices {
                    eprintln!("view: {n}");
                }
                self.last_notices = f.notices.clone();
            }
            // A pending frame (prt's transfer being computed) measures nothing.
            if !f.pending {
                let (seconds, method) = (f.seconds, f.job.method);
                match (f.job.preview, done.slot) {
                    (false, slot) => {
                        self.last_full.insert(method, seconds);
                        if slot == 0 {
                            self.still_times.push(seconds);
                        }
                    }
                    (true, 0) => {
                        self.moving_times.push(seconds);
                        self.adapt(seconds, method);
                    }
                    (true, _) => {}
                }
            }
            if done.slot + 1 == self.methods().len() || done.frame.job.pass > 0 {
                self.in_flight = false;
            }
            if !done.boxes.is_empty() {
                self.boxes = done.boxes;
            }
            let slot = done.slot.min(1);
            self.shown[slot] = Some(Shown {
                frame: done.frame,
                version,
            });
            self.upload(slot);
        }
    }

    fn upload(&mut self, slot: usize) {
        let (Some(ctx), Some(shown)) = (&self.egui, &self.shown[slot]) else {
            return;
        };
        let img = &shown.frame.image;
        let tm = Tonemap::default();
        let rgb: Vec<u8> = img
            .data
            .iter()
            .flat_map(|&p| tm.to_srgb8_pixel(p))
            .collect();
        let color = egui::ColorImage::from_rgb([img.width as usize, img.height as usize], &rgb);
        let opts = egui::TextureOptions::LINEAR;
        let heat =
            (slot == 0 && !shown.frame.cut_sizes.is_empty()).then(|| heatmap_image(&shown.frame));
        match &mut self.textures[slot] {
            Some(t) => t.set(color, opts),
            None => {
                self.textures[slot] = Some(ctx.load_texture(format!("frame{slot}"), color, opts))
            }
        }
        if let Some(h) = heat {
            let opts = egui::TextureOptions::NEAREST;
            match &mut self.heatmap {
                Some(t) => t.set(h, opts),
                None => self.heatmap = Some(ctx.load_texture("heatmap", h, opts)),
            }
        } else if slot == 0 {
            self.heatmap = None;
        }
    }

    /// Whether every shown method's last full-quality frame fits in one repaint interval
    /// (prt's do): previews would then only blur frames the window can show as they are, so
    /// frames while moving keep the full size (at 1 spp).
    fn interactive_at_full_quality(&self) -> bool {
        self.methods().iter().all(|m| {
            self.last_full
                .get(m)
                .is_some_and(|&t| t <= 1.0 / REPAINT_FPS)
        })
    }

    /// Keeps frames while moving at most a tenth of a full-quality frame: a preview slower
    /// than that (against the last full frame of the same method) makes the next previews
    /// smaller, one much faster lets them grow back to the panel's factor.
    fn adapt(&mut self, seconds: f64, method: ViewMethod) {
        let Some(full) = self.last_full.get(&method).copied() else {
            return;
        };
        let base = self.state.preview_factor.max(1);
        let f = self.auto_factor.max(base);
        if seconds > MOVING_SHARE * full {
            self.auto_factor = (f + 1).min(MAX_PREVIEW_FACTOR);
        } else if seconds < 0.5 * MOVING_SHARE * full && f > base {
            self.auto_factor = f - 1;
        }
    }

    /// Whether the full-quality frames of the current version are all shown.
    fn settled(&self) -> bool {
        let n = self.methods().len();
        (0..n).all(|k| {
            self.shown[k].as_ref().is_some_and(|s| {
                s.version == self.version
                    && !s.frame.job.preview
                    && !s.frame.pending
                    && s.frame.job.method == self.methods()[k]
            })
        })
    }

    fn schedule(&mut self, moving: bool) {
        let still_for = self.last_change.elapsed().as_secs_f64();
        match self.requested {
            Some((v, false)) if v == self.version => {}
            Some((v, true)) if v == self.version && (moving || still_for < SETTLE) => {}
            _ => {
                if moving || (still_for < SETTLE && !self.scripted) {
                    // One preview at a time: the newest state when the last one is back.
                    if !self.in_flight || !matches!(self.requested, Some((_, true))) {
                        self.request(true);
                    }
                } else {
                    self.request(false);
                }
            }
        }
    }

    /// Whether the script's next command can run now (it waits for nothing, or for a frame
    /// that is shown).
    fn script_can_run(&self) -> bool {
        match self.commands.front() {
            None => false,
            Some(Command::Wait | Command::Screenshot(_)) => self.settled(),
            Some(_) => true,
        }
    }

    /// Runs script commands until one has to wait.
    fn step_script(&mut self, event_loop: &ActiveEventLoop) {
        if !self.scripted {
            return;
        }
        if self.frames_left > 0 {
            self.frames_left -= 1;
            return;
        }
        while let Some(cmd) = self.commands.front().cloned() {
            match &cmd {
                Command::Wait => {
                    if !self.settled() {
                        return;
                    }
                }
                Command::Frames(n) => {
                    self.commands.pop_front();
                    self.frames_left = *n;
                    return;
                }
                Command::Screenshot(p) => {
                    if !self.settled() {
                        return;
                    }
                    if let Err(e) = self.save(p) {
                        self.fail(event_loop, e);
                        return;
                    }
                }
                other => {
                    let before = self.state.clone();
                    if let Err(e) = self.state.apply(other) {
                        self.fail(event_loop, anyhow::anyhow!("script: {e}"));
                        return;
                    }
                    if state_differs(&before, &self.state) {
                        self.changed();
                    }
                }
            }
            self.commands.pop_front();
        }
        if self.commands.is_empty() {
            event_loop.exit();
        }
    }

    /// The image shown: slot 0, or its left half beside slot 1's right half in split view.
    fn composed(&self) -> Option<Image> {
        let a = &self.shown[0].as_ref()?.frame.image;
        let Some(b) = self.shown[1].as_ref().filter(|_| self.methods().len() > 1) else {
            return Some(a.clone());
        };
        let b = &b.frame.image;
        if (a.width, a.height) != (b.width, b.height) {
            return Some(a.clone());
        }
        let mut out = a.clone();
        for y in 0..a.height {
            for x in a.width / 2..a.width {
                let i = (y * a.width + x) as usize;
                out.data[i] = b.data[i];
            }
        }
        Some(out)
    }

    /// Writes the shown full-quality image as PNG and EXR (all or nothing).
    fn save(&mut self, png: &Path) -> anyhow::Result<()> {
        let img = self
            .composed()
            .context("screenshot: no frame has been rendered yet")?;
        if let Some(dir) = png.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        let exr = png.with_extension("exr");
        if self.scene.inputs.iter().any(|i| i == png || i == &exr) || png == self.scene.path {
            bail!(
                "screenshot {}: would overwrite one of the scene's input files",
                png.display()
            );
        }
        write_exr(&exr, &img)?;
        if let Err(e) = write_png(png, &img, &Tonemap::default()) {
            let _ = std::fs::remove_file(&exr);
            return Err(e.into());
        }
        self.screenshot_count += 1;
        self.status = format!("saved {} and {}", png.display(), exr.display());
        eprintln!("view: {}", self.status);
        Ok(())
    }

    fn default_screenshot(&self) -> PathBuf {
        let dir = PathBuf::from("results").join("renders");
        let mut k = self.screenshot_count + 1;
        loop {
            let p = dir.join(format!("{}-view-{k}.png", self.scene.name));
            if !p.exists() {
                return p;
            }
            k += 1;
        }
    }

    fn print_times(&self) {
        let med = |v: &[f64]| {
            let mut v = v.to_vec();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied()
        };
        if let Some(s) = med(&self.still_times) {
            let m = med(&self.moving_times)
                .map(|m| {
                    format!(
                        ", moving (preview) {m:.3} s ({} frames)",
                        self.moving_times.len()
                    )
                })
                .unwrap_or_default();
            eprintln!(
                "view: median frame time still {s:.3} s ({} frames){m}",
                self.still_times.len()
            );
        }
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop, window: &Arc<Window>) {
        let now = Instant::now();
        let dt = (now - self.last_tick).as_secs_f32().min(0.1);
        self.last_tick = now;
        self.receive();
        self.step_script(event_loop);
        // Fly keys move the eye while held.
        if self.state.controller.fly {
            let k = self.fly_keys;
            let dir = glam::Vec3::new(
                k[2] as i32 as f32 - k[3] as i32 as f32,
                k[4] as i32 as f32 - k[5] as i32 as f32,
                k[0] as i32 as f32 - k[1] as i32 as f32,
            );
            if dir != glam::Vec3::ZERO {
                self.state.controller.fly_move(dir, dt);
                self.changed();
            }
        }
        let moving = self.state.controller.update(dt);
        if moving {
            self.changed();
        }
        let (Some(ctx), Some(egui_state)) = (self.egui.clone(), self.egui_state.as_mut()) else {
            return;
        };
        let input = egui_state.take_egui_input(window);
        let before = self.state.clone();
        let mut save_requested = false;
        let output = ctx.run_ui(input, |ui| {
            save_requested |= self.panel(ui);
            self.central(ui);
        });
        if state_differs(&before, &self.state) {
            self.changed();
        }
        if save_requested {
            let p = self.default_screenshot();
            if let Err(e) = self.save(&p) {
                self.status = format!("screenshot failed: {e:#}");
            }
        }
        let moving = moving || self.dragging || self.last_change.elapsed().as_secs_f64() < 0.05;
        self.schedule(moving);
        if let Some(s) = self.egui_state.as_mut() {
            s.handle_platform_output(window, output.platform_output.clone());
        }
        self.repaint_after = output
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map(|v| v.repaint_delay);
        let size = window.inner_size();
        let primitives = ctx.tessellate(output.shapes, output.pixels_per_point);
        if let Some(gpu) = self.gpu.as_mut()
            && let Err(e) = gpu.paint(&Painted {
                primitives: &primitives,
                textures: &output.textures_delta,
                size: [size.width, size.height],
                pixels_per_point: output.pixels_per_point,
            })
        {
            self.fail(event_loop, anyhow::anyhow!("{e}"));
        }
    }

    /// The side panel; true when the screenshot button (or S) was pressed.
    fn panel(&mut self, ui: &mut egui::Ui) -> bool {
        let mut save = false;
        egui::Panel::left("controls")
            .resizable(true)
            .default_size(300.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    ui.heading(format!("interreflect — {}", self.scene.name));
                    ui.separator();
                    method_picker(ui, "Method", &mut self.state.method);
                    let mut split = self.state.split.is_some();
                    ui.horizontal(|ui| {
                        ui.checkbox(&mut split, "Split view, right half:");
                        let mut m = self.state.split.unwrap_or(ViewMethod::Direct);
                        if split {
                            method_picker(ui, "", &mut m);
                        }
                        self.state.split = split.then_some(m);
                    });
                    ui.checkbox(&mut self.state.indirect_only, "Indirect light only");
                    ui.horizontal(|ui| {
                        ui.label("Image");
                        let mut w = self.state.width;
                        if ui
                            .add(egui::DragValue::new(&mut w).range(16..=1024).suffix(" px"))
                            .changed()
                        {
                            self.state.set_size(w, 0);
                        }
                        ui.label(format!("× {}", self.state.height));
                        ui.add(
                            egui::DragValue::new(&mut self.state.spp)
                                .range(1..=256)
                                .suffix(" spp"),
                        );
                    });
                    ui.horizontal(|ui| {
                        ui.label("While moving: 1 /");
                        ui.add(egui::DragValue::new(&mut self.state.preview_factor).range(1..=16));
                        ui.label(if self.interactive_at_full_quality() {
                            "of the size, 1 spp (now full size: frames are fast)".to_string()
                        } else {
                            format!(
                                "of the size, 1 spp (now 1 / {})",
                                self.state.preview_factor.max(self.auto_factor)
                            )
                        });
                    });
                    ui.separator();
                    self.light_controls(ui);
                    ui.separator();
                    self.material_controls(ui);
                    ui.separator();
                    ui.label("Camera: drag to orbit, right-drag to pan, wheel to zoom at the cursor, Shift-drag (or L, then drag) moves light 0, F flies (WASD QE), R resets, S saves");
                    ui.horizontal(|ui| {
                        ui.label("Left drag moves");
                        ui.radio_value(&mut self.drag_light, false, "the camera");
                        ui.radio_value(&mut self.drag_light, true, "light 0 (L)");
                    });
                    ui.horizontal(|ui| {
                        if ui.button("Reset camera").clicked() {
                            self.state.controller.reset();
                        }
                        ui.checkbox(&mut self.state.controller.fly, "Fly");
                        ui.label("damping");
                        ui.add(
                            egui::DragValue::new(&mut self.state.controller.damping)
                                .range(0.0..=1.0)
                                .speed(0.01)
                                .suffix(" s"),
                        );
                    });
                    ui.separator();
                    ui.label("Overlays");
                    ui.checkbox(&mut self.state.overlays.vpls, "VPL positions (vpl)");
                    ui.horizontal(|ui| {
                        ui.checkbox(&mut self.state.overlays.boxes, "Tree node boxes (sg), depth");
                        ui.add(egui::DragValue::new(&mut self.state.overlays.box_depth).range(0..=8));
                    });
                    ui.checkbox(
                        &mut self.state.overlays.heatmap,
                        "Cut-size heatmap (sg, pixel cuts): dark blue 0 … yellow the cap",
                    );
                    ui.separator();
                    if ui.button("Save screenshot (S)").clicked() {
                        save = true;
                    }
                    if !self.status.is_empty() {
                        ui.label(&self.status);
                    }
                    ui.separator();
                    self.stats(ui);
                });
            });
        let keys = ui.ctx().egui_wants_keyboard_input();
        if !keys {
            ui.input(|i| {
                if i.key_pressed(egui::Key::S) && !self.state.controller.fly {
                    save = true;
                }
                if i.key_pressed(egui::Key::R) {
                    self.state.controller.reset();
                }
                if i.key_pressed(egui::Key::L) {
                    self.drag_light = !self.drag_light;
                }
                if i.key_pressed(egui::Key::F) {
                    self.state.controller.fly = !self.state.controller.fly;
                }
                use egui::Key::*;
                for (k, key) in [W, S, D, A, E, Q].into_iter().enumerate() {
                    self.fly_keys[k] = i.key_down(key);
                }
            });
        }
        save
    }

    fn light_controls(&mut self, ui: &mut egui::Ui) {
        ui.label("Lights");
        for (k, light) in self.state.lights.iter_mut().enumerate() {
            ui.push_id(k, |ui| {
                let (kind, pos, dir, power) = match light {
                    Light::Point {
                        position,
                        intensity,
                    } => ("point", Some(position), None, intensity),
                    Light::Spot {
                        position,
                        direction,
                        intensity,
                        ..
                    } => ("spot", Some(position), Some(direction), intensity),
                    Light::Directional {
                        direction,
                        irradiance,
                    } => ("directional", None, Some(direction), irradiance),
                };
                ui.label(format!("{k}: {kind}"));
                if let Some(p) = pos {
                    ui.horizontal(|ui| {
                        ui.label("position");
                        for c in [&mut p.x, &mut p.y, &mut p.z] {
                            ui.add(egui::DragValue::new(c).speed(0.02));
                        }
                    });
                }
                if let Some(dir) = dir {
                    // In degrees: where a directional light comes from, where a spot aims.
                    let sign = if kind == "spot" { -1.0 } else { 1.0 };
                    let (mut az, mut el) = light_angles(sign * *dir);
                    ui.horizontal(|ui| {
                        ui.label(if kind == "spot" { "aim" } else { "from" });
                        let a = ui
                            .add(egui::DragValue::new(&mut az).speed(0.5).suffix("° az"))
                            .changed();
                        let b = ui
                            .add(
                                egui::DragValue::new(&mut el)
                                    .range(-MAX_LIGHT_ELEVATION..=MAX_LIGHT_ELEVATION)
                                    .speed(0.5)
                                    .suffix("° el"),
                            )
                            .changed();
                        if a || b {
                            *dir = sign * light_direction(az, el);
                        }
                    });
                }
                let strength = power.max_element();
                let mut colour = if strength > 0.0 {
                    (*power / strength).to_array()
                } else {
                    [1.0; 3]
                };
                let mut s = strength;
                ui.horizontal(|ui| {
                    ui.label("intensity");
                    let a = ui
                        .add(egui::DragValue::new(&mut s).range(0.0..=1e6).speed(0.1))
                        .changed();
                    let b = ui.color_edit_button_rgb(&mut colour).changed();
                    if a || b {
                        *power = glam::Vec3::from_array(colour) * s;
                    }
                });
            });
        }
    }

    fn material_controls(&mut self, ui: &mut egui::Ui) {
        use interreflect::brdf::Brdf;
        ui.label("Materials");
        let mut edits: Vec<(String, MaterialField)> = Vec::new();
        for (k, m) in self.state.materials.iter().enumerate() {
            ui.push_id(("mat", k), |ui| {
                ui.horizontal(|ui| {
                    ui.label(format!("{} ({})", m.name, model_name(&m.brdf)));
                    match m.brdf {
                        Brdf::Ward { roughness, .. } | Brdf::CookTorrance { roughness, .. } => {
                            let mut r = roughness;
                            if ui
                                .add(
                                    egui::Slider::new(&mut r, 0.001..=1.0)
                                        .logarithmic(true)
                                        .text("roughness"),
                                )
                                .changed()
                            {
                                edits.push((m.name.clone(), MaterialField::Roughness(r)));
                            }
                        }
                        Brdf::Phong { exponent, .. } | Brdf::BlinnPhong { exponent, .. } => {
                            let mut e = exponent;
                            if ui
                                .add(
                                    egui::Slider::new(&mut e, 1.0..=10000.0)
                                        .logarithmic(true)
                                        .text("exponent"),
                                )
                                .changed()
                            {
                                edits.push((m.name.clone(), MaterialField::Exponent(e)));
                            }
                        }
                        Brdf::Lambert { .. } => {}
                    }
                });
                ui.horizontal(|ui| {
                    let mut d = m.brdf.diffuse().to_array();
                    ui.label("diffuse");
                    if ui.color_edit_button_rgb(&mut d).changed() {
                        edits.push((m.name.clone(), MaterialField::Diffuse(d)));
                    }
                    if !matches!(m.brdf, Brdf::Lambert { .. }) {
                        let mut s = m.brdf.specular().to_array();
                        ui.label("specular");
                        if ui.color_edit_button_rgb(&mut s).changed() {
                            edits.push((m.name.clone(), MaterialField::Specular(s)));
                        }
                    }
                });
            });
        }
        for (name, field) in edits {
            if let Err(e) = self.state.set_material(&name, &field) {
                self.status = e;
            }
        }
    }

    fn stats(&self, ui: &mut egui::Ui) {
        ui.label("Stats");
        if let Some(g) = &self.gpu {
            ui.label(format!("window adapter: {}", g.adapter));
        }
        ui.label(format!(
            "{} triangles, {} lights",
            self.scene.mesh.indices.len(),
            self.state.lights.len()
        ));
        for (k, s) in self.shown.iter().enumerate() {
            let Some(s) = s else { continue };
            if k == 1 && self.methods().len() < 2 {
                continue;
            }
            let f = &s.frame;
            ui.label(format!(
                "{}: {}×{} at {} spp{}, {:.3} s{}",
                f.job.method.name(),
                f.job.width,
                f.job.height,
                f.job.spp,
                if f.job.preview { " (moving)" } else { "" },
                f.seconds,
                if f.passes > 1 {
                    format!(", {} passes", f.passes)
                } else {
                    String::new()
                }
            ));
            for (name, t) in &f.stages {
                if *t > 0.0005 || name.contains("kept") {
                    ui.label(format!("    {name}: {t:.3} s"));
                }
            }
            if let Some(c) = f.cut_mean {
                ui.label(format!("    cut size mean {c:.1}"));
            }
            if !f.shadow_maps_on.is_empty() {
                ui.label(format!("    shadow maps on {}", f.shadow_maps_on));
            }
            for n in &f.notices {
                let colour = if f.pending || n.contains("ignored") || n.contains("needs") {
                    egui::Color32::from_rgb(240, 200, 80)
                } else {
                    ui.visuals().text_color()
                };
                ui.add(
                    egui::Label::new(egui::RichText::new(format!("    {n}")).color(colour)).wrap(),
                );
            }
            if let Some(r) = &self.reference {
                ui.label(format!("    {}", error_readout(&f.image, r)));
            }
        }
    }

    fn central(&mut self, ui: &mut egui::Ui) {
        // No frame: the window's clear colour is the background, one full-window fill less
        // for a software GPU to rasterise.
        egui::CentralPanel::no_frame().show(ui, |ui| {
            let avail = ui.available_rect_before_wrap();
            let aspect = self.state.width as f32 / self.state.height.max(1) as f32;
            let (w, h) = if avail.width() / avail.height().max(1.0) > aspect {
                (avail.height() * aspect, avail.height())
            } else {
                (avail.width(), avail.width() / aspect)
            };
            let rect = egui::Rect::from_center_size(avail.center(), egui::vec2(w, h));
            let resp = ui.allocate_rect(rect, egui::Sense::click_and_drag());
            let painter = ui.painter_at(rect);
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            let split = self.methods().len() > 1 && self.textures[1].is_some();
            if let Some(t) = &self.textures[0] {
                let r = if split {
                    egui::Rect::from_min_max(rect.min, egui::pos2(rect.center().x, rect.max.y))
                } else {
                    rect
                };
                let u = if split {
                    egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(0.5, 1.0))
                } else {
                    uv
                };
                painter.image(t.id(), r, u, egui::Color32::WHITE);
            }
            if split && let Some(t) = &self.textures[1] {
                let r = egui::Rect::from_min_max(egui::pos2(rect.center().x, rect.min.y), rect.max);
                let u = egui::Rect::from_min_max(egui::pos2(0.5, 0.0), egui::pos2(1.0, 1.0));
                painter.image(t.id(), r, u, egui::Color32::WHITE);
                painter.line_segment(
                    [
                        egui::pos2(rect.center().x, rect.min.y),
                        egui::pos2(rect.center().x, rect.max.y),
                    ],
                    egui::Stroke::new(1.0, egui::Color32::WHITE),
                );
            }
            if self.state.overlays.heatmap
                && let Some(t) = &self.heatmap
            {
                painter.image(t.id(), rect, uv, egui::Color32::WHITE);
            }
            self.overlays(&painter, rect);
            // A pending frame (prt's transfer) says what it waits for over its black image.
            if let Some(n) = self
                .shown
                .iter()
                .flatten()
                .find(|s| s.frame.pending)
                .and_then(|s| s.frame.notices.last())
            {
                let galley = painter.layout(
                    n.clone(),
                    egui::FontId::proportional(14.0),
                    egui::Color32::from_rgb(240, 200, 80),
                    0.8 * rect.width(),
                );
                let at = rect.center() - 0.5 * galley.size();
                painter.galley(at, galley, egui::Color32::WHITE);
            }
            // Camera and light input over the image. While a button is held the view counts
            // as moving, even when the pointer pauses.
            self.dragging = resp.dragged();
            let c = &mut self.state.controller;
            let d = resp.drag_delta();
            let scale = self.state.height as f32 / h.max(1.0);
            let shift = ui.input(|i| i.modifiers.shift) || self.drag_light;
            if resp.dragged_by(egui::PointerButton::Primary) && d != egui::Vec2::ZERO {
                if shift {
                    let cam = c.camera(self.state.width, self.state.height);
                    match self.state.lights.first_mut() {
                        Some(Light::Point { position, .. } | Light::Spot { position, .. }) => {
                            let depth = (*position - cam.position).dot(cam.forward).max(1e-3);
                            let per_px = 2.0 * depth * (0.5 * cam.fov_y).tan() / h.max(1.0);
                            *position += (cam.right * d.x - cam.up * d.y) * per_px;
                        }
                        // A directional light turns about the up axis and rises or sets.
                        Some(Light::Directional { direction, .. }) => {
                            *direction = drag_light_direction(*direction, d.x * scale, d.y * scale);
                        }
                        None => {}
                    }
                } else {
                    c.orbit(d.x * scale, d.y * scale);
                }
            }
            if (resp.dragged_by(egui::PointerButton::Secondary)
                || resp.dragged_by(egui::PointerButton::Middle))
                && d != egui::Vec2::ZERO
            {
                c.pan(d.x, d.y, h);
            }
            if resp.hovered() {
                let scroll = ui.input(|i| i.smooth_scroll_delta.y);
                if scroll != 0.0 {
                    let ndc = resp.hover_pos().map(|p| {
                        glam::Vec2::new(
                            2.0 * (p.x - rect.min.x) / w - 1.0,
                            1.0 - 2.0 * (p.y - rect.min.y) / h,
                        )
                    });
                    c.dolly(scroll / 50.0, ndc, aspect);
                }
            }
        });
    }

    fn overlays(&self, painter: &egui::Painter, rect: egui::Rect) {
        let o = self.state.overlays;
        let cam = self.state.camera(self.state.width, self.state.height);
        let to_screen = |p: glam::Vec3| {
            project(&cam, p).map(|n| {
                egui::pos2(
                    rect.min.x + (n.x + 1.0) * 0.5 * rect.width(),
                    rect.min.y + (1.0 - n.y) * 0.5 * rect.height(),
                )
            })
        };
        if o.vpls {
            for s in self.shown.iter().flatten() {
                for &p in &s.frame.vpls {
                    if let Some(q) = to_screen(p) {
                        painter.circle_filled(q, 2.5, egui::Color32::from_rgb(255, 80, 200));
                    }
                }
            }
        }
        if o.boxes {
            let boxes = self
                .boxes
                .get(o.box_depth.min(MAX_BOX_DEPTH) as usize)
                .map(Vec::as_slice)
                .unwrap_or_default();
            let stroke = egui::Stroke::new(1.0, egui::Color32::from_rgb(80, 220, 255));
            for &(lo, hi) in boxes {
                let corner = |i: u32| {
                    glam::Vec3::new(
                        if i & 1 == 0 { lo.x } else { hi.x },
                        if i & 2 == 0 { lo.y } else { hi.y },
                        if i & 4 == 0 { lo.z } else { hi.z },
                    )
                };
                for a in 0..8u32 {
                    for bit in [1u32, 2, 4] {
                        let b = a | bit;
                        if b != a
                            && let (Some(p), Some(q)) = (to_screen(corner(a)), to_screen(corner(b)))
                        {
                            painter.line_segment([p, q], stroke);
                        }
                    }
                }
            }
        }
        for (k, l) in self.state.lights.iter().enumerate() {
            if let Light::Point { position, .. } | Light::Spot { position, .. } = l
                && let Some(q) = to_screen(*position)
            {
                painter.circle_stroke(q, 6.0, egui::Stroke::new(2.0, egui::Color32::YELLOW));
                painter.text(
                    q + egui::vec2(8.0, -8.0),
                    egui::Align2::LEFT_BOTTOM,
                    format!("light {k}"),
                    egui::FontId::proportional(12.0),
                    egui::Color32::YELLOW,
                );
            }
        }
    }
}

/// sg's cut size per pixel as a translucent false-colour image: 0 is dark blue, the cap (or the
/// largest cut when there is none) yellow.
fn heatmap_image(f: &Frame) -> egui::ColorImage {
    let top = if f.max_cut > 0 {
        f.max_cut as f32
    } else {
        f.cut_sizes.iter().copied().fold(1.0, f32::max)
    };
    let rgba: Vec<u8> = f
        .cut_sizes
        .iter()
        .flat_map(|&c| {
            let t = (c / top).clamp(0.0, 1.0);
            // A short blue → magenta → yellow ramp.
            let r = (255.0 * (1.5 * t).min(1.0)) as u8;
            let g = (255.0 * (2.0 * t - 1.0).clamp(0.0, 1.0)) as u8;
            let b = (255.0 * (0.6 - t).clamp(0.0, 0.6) / 0.6 * 0.8 + 40.0 * (1.0 - t)) as u8;
            [r, g, b, 170]
        })
        .collect();
    egui::ColorImage::from_rgba_unmultiplied([f.job.width as usize, f.job.height as usize], &rgba)
}

fn method_picker(ui: &mut egui::Ui, label: &str, m: &mut ViewMethod) {
    egui::ComboBox::from_label(label)
        .selected_text(m.name())
        .show_ui(ui, |ui| {
            for v in ViewMethod::ALL {
                ui.selectable_value(m, v, v.name());
            }
        });
}

fn model_name(b: &interreflect::brdf::Brdf) -> &'static str {
    use interreflect::brdf::Brdf;
    match b {
        Brdf::Lambert { .. } => "lambert",
        Brdf::Phong { .. } => "phong",
        Brdf::BlinnPhong { .. } => "blinn_phong",
        Brdf::Ward { .. } => "ward",
        Brdf::CookTorrance { .. } => "cook_torrance",
    }
}

fn error_readout(img: &Image, reference: &Image) -> String {
    use interreflect::compare::{box_filter, integer_factor, metrics};
    let r = match integer_factor(img, reference) {
        Some(k) if k > 1 => box_filter(reference, k),
        _ => reference.clone(),
    };
    match metrics(img, &r) {
        Ok(m) => format!(
            "against the reference: rel_rmse {:.2} %",
            100.0 * m.rel_rmse
        ),
        Err(_) => format!(
            "the reference is {}×{}: no error for a {}×{} frame",
            reference.width, reference.height, img.width, img.height
        ),
    }
}

/// Whether two states render differently.
fn state_differs(a: &ViewState, b: &ViewState) -> bool {
    a.method != b.method
        || a.split != b.split
        || a.lights != b.lights
        || a.materials_version != b.materials_version
        || a.controller.orbit != b.controller.orbit
        || (a.width, a.height, a.spp, a.preview_factor)
            != (b.width, b.height, b.spp, b.preview_factor)
        || a.indirect_only != b.indirect_only
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_sizes_are_checked() {
        assert_eq!(parse_window("1280x760").unwrap(), (1280, 760));
        for bad in ["1280", "x", "10x10", "1280x-5", "axb"] {
            assert!(parse_window(bad).is_err(), "{bad}");
        }
    }
}
