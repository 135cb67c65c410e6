//! The interactive viewer's state and frames, without a window (`interreflect view`, in the
//! binary, owns the window, the egui panel and the event loop; see `docs/viewer.md`).
//!
//! - [`camera`]: the camera controller (orbit, pan, dolly towards the cursor, fly, damping).
//! - [`script`]: the command language of `view --script`.
//! - [`ViewState`]: what the user edits — method, light, materials, image size, overlays —
//!   and the commands that change it.
//! - [`FrameRenderer`]: renders a [`Job`] (one state, at full or preview quality) with the
//!   same renderers and options as `interreflect render`, keeping what does not depend on the
//!   light or the camera (the BVH, and sg's reflector pieces and tree) between frames.

pub mod camera;
pub mod prt;
pub mod script;

use crate::accel::Accel;
use crate::image::Image;
use crate::render::cpu::reference::{Progress, RenderOptions, no_progress, render};
use crate::render::cpu::sg::{SgOptions, SgPrepared, render_sg_prepared};
use crate::render::cpu::vpl::{VplOptions, default_clamp_distance, render_vpl};
use crate::render::{Device, Visibility};
use crate::scene::{Camera, Light, Material, Scene};
use camera::CameraController;
use glam::Vec3;
use script::{Command, LightField, MaterialField};
use std::sync::atomic::AtomicBool;

/// The methods the viewer shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ViewMethod {
    /// The SG method with its default (approximate) visibility, as `render --method sg`.
    Sg,
    /// The VPL baseline, as `render --method vpl`.
    Vpl,
    /// Direct light only, as `render --method direct`.
    Direct,
    /// SH diffuse PRT, as `render --method prt` (distant lighting only: directional lights and
    /// the environment map).
    Prt,
    /// The path-traced reference, refined progressively while nothing changes.
    Reference,
}

impl ViewMethod {
    pub const ALL: [ViewMethod; 5] = [
        ViewMethod::Sg,
        ViewMethod::Vpl,
        ViewMethod::Direct,
        ViewMethod::Prt,
        ViewMethod::Reference,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ViewMethod::Sg => "sg",
            ViewMethod::Vpl => "vpl",
            ViewMethod::Direct => "direct",
            ViewMethod::Prt => "prt",
            ViewMethod::Reference => "reference",
        }
    }

    pub fn parse(s: &str) -> Option<ViewMethod> {
        ViewMethod::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// Overlays drawn over the image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overlays {
    /// The VPLs of the last vpl frame, as dots.
    pub vpls: bool,
    /// The bounding boxes of sg's reflector tree, `box_depth` levels below the root.
    pub boxes: bool,
    pub box_depth: u32,
    /// sg's cut size per pixel (nodes evaluated), as a false-colour heatmap.
    pub heatmap: bool,
}

/// Everything the user edits. The scene's lights and materials are copies: the scene file is
/// never written.
#[derive(Clone, Debug)]
pub struct ViewState {
    pub method: ViewMethod,
    /// A second method shown on the right half (split view).
    pub split: Option<ViewMethod>,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    /// Bumped whenever a material changes (sg's tree depends on the albedos).
    pub materials_version: u64,
    pub controller: CameraController,
    /// The scene file's camera, used exactly while the view has not moved from it.
    pub home_camera: Camera,
    /// Full-quality image size.
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of a full-quality frame.
    pub spp: u32,
    /// Divides the width and height of the frames shown while something moves.
    pub preview_factor: u32,
    pub indirect_only: bool,
    pub overlays: Overlays,
    pub seed: u64,
}

/// A preview frame under a moved light builds this many times fewer visibility maps.
pub const PREVIEW_MAP_DIVISOR: u32 = 8;

/// The default full-quality width: the scene camera's, halved until it is at most this.
pub const DEFAULT_MAX_WIDTH: u32 = 128;

impl ViewState {
    /// The state a session starts in: sg, the scene's camera, lights and materials, an image
    /// at most [`DEFAULT_MAX_WIDTH`] wide at 1 spp.
    pub fn new(scene: &Scene, focus: f32) -> ViewState {
        let cam = scene.camera;
        let mut w = cam.width.max(1);
        let mut h = cam.height.max(1);
        while w > DEFAULT_MAX_WIDTH {
            w = w.div_ceil(2);
            h = h.div_ceil(2);
        }
        ViewState {
            method: ViewMethod::Sg,
            split: None,
            lights: scene.lights.clone(),
            materials: scene.materials.clone(),
            materials_version: 0,
            controller: CameraController::new(&cam, focus, scene.mesh.diagonal()),
            home_camera: cam,
            width: w,
            height: h,
            spp: 1,
            preview_factor: 5,
            indirect_only: false,
            overlays: Overlays {
                box_depth: 4,
                ..Overlays::default()
            },
            seed: scene.settings.seed,
        }
    }

    /// The camera of a frame `width` × `height`: the scene file's own while the view is at
    /// home (so that a frame equals `render`'s image bit for bit), else the controller's.
    pub fn camera(&self, width: u32, height: u32) -> Camera {
        if self.controller.orbit == self.controller.home {
            self.home_camera.with_resolution(width, height)
        } else {
            self.controller.camera(width, height)
        }
    }

    /// Height of the full-quality frame (0 in a `size` command: the camera's aspect).
    pub fn set_size(&mut self, width: u32, height: u32) {
        self.width = width.max(1);
        self.height = if height == 0 {
            ((width as f64 * self.home_camera.height as f64 / self.home_camera.width.max(1) as f64)
                .round() as u32)
                .max(1)
        } else {
            height
        };
    }

    /// The job that renders this state; `preview` at `1/preview_factor` of the size, 1 spp.
    pub fn job(&self, id: u64, method: ViewMethod, preview: bool) -> Job {
        let (w, h, spp) = if preview {
            let f = self.preview_factor.max(1);
            (
                self.width.div_ceil(f).max(1),
                self.height.div_ceil(f).max(1),
                1,
            )
        } else {
            (self.width, self.height, self.spp)
        };
        Job {
            id,
            camera: self.camera(w, h),
            lights: self.lights.clone(),
            materials: self.materials.clone(),
            materials_version: self.materials_version,
            method,
            width: w,
            height: h,
            spp,
            seed: self.seed,
            indirect_only: self.indirect_only && method != ViewMethod::Direct,
            preview,
            pass: 0,
        }
    }

    /// Applies a state command of a script (the window's commands — wait, frames,
    /// screenshot — are the caller's); the error says what was wrong.
    pub fn apply(&mut self, cmd: &Command) -> Result<(), String> {
        match cmd {
            Command::Method(m) => {
                self.method = ViewMethod::parse(m).ok_or(format!("unknown method {m}"))?;
            }
            Command::Split(m) => {
                self.split = match m {
                    None => None,
                    Some(m) => Some(ViewMethod::parse(m).ok_or(format!("unknown method {m}"))?),
                };
            }
            Command::Size(w, h) => self.set_size(*w, *h),
            Command::Spp(n) => self.spp = *n,
            Command::Light(k, field) => self.set_light(*k, field)?,
            Command::Material(name, field) => self.set_material(name, field)?,
            Command::Orbit(yaw, pitch) => {
                let c = &mut self.controller;
                let damping = std::mem::replace(&mut c.damping, 0.0);
                c.orbit(
                    -yaw.to_radians() / camera::ORBIT_PER_PIXEL,
                    pitch.to_radians() / camera::ORBIT_PER_PIXEL,
                );
                c.damping = damping;
            }
            Command::Pan(right, up) => {
                let c = &mut self.controller;
                let cam = c.camera(1, 1);
                c.orbit.target += (cam.right * *right + cam.up * *up) * c.orbit.distance;
            }
            Command::Dolly(steps) => {
                let c = &mut self.controller;
                let damping = std::mem::replace(&mut c.damping, 0.0);
                c.dolly(*steps / camera::DOLLY_PER_STEP, None, 1.0);
                c.damping = damping;
            }
            Command::Reset => self.controller.reset(),
            Command::IndirectOnly(on) => self.indirect_only = *on,
            Command::Overlay(name, on) => match name.as_str() {
                "vpls" => self.overlays.vpls = *on,
                "boxes" => self.overlays.boxes = *on,
                _ => self.overlays.heatmap = *on,
            },
            Command::Wait | Command::Frames(_) | Command::Screenshot(_) => {}
        }
        Ok(())
    }

    /// Sets one field of light `k`.
    pub fn set_light(&mut self, k: usize, field: &LightField) -> Result<(), String> {
        let n = self.lights.len();
        let light = self
            .lights
            .get_mut(k)
            .ok_or(format!("light {k}: the scene has {n} light(s)"))?;
        let v = |a: &[f32; 3]| Vec3::from_array(*a);
        match (light, field) {
            (
                Light::Point { position, .. } | Light::Spot { position, .. },
                LightField::Position(p),
            ) => *position = v(p),
            (Light::Directional { .. }, LightField::Position(_)) => {
                return Err(format!("light {k}: a directional light has no position"));
            }
            (
                Light::Spot { direction, .. } | Light::Directional { direction, .. },
                LightField::Direction(d),
            ) => *direction = v(d).normalize(),
            (Light::Point { .. }, LightField::Direction(_)) => {
                return Err(format!("light {k}: a point light has no direction"));
            }
            (
                Light::Point { intensity, .. }
                | Light::Spot { intensity, .. }
                | Light::Directional {
                    irradiance: intensity,
                    ..
                },
                f,
            ) => match f {
                LightField::Intensity(c) => *intensity = v(c),
                LightField::Strength(s) => {
                    let m = intensity.max_element();
                    *intensity = if m > 0.0 {
                        *intensity * (*s / m)
                    } else {
                        Vec3::splat(*s)
                    };
                }
                _ => unreachable!("positions and directions are matched above"),
            },
        }
        Ok(())
    }

    /// Sets one parameter of the material called `name`, checked as the scene file's are.
    pub fn set_material(&mut self, name: &str, field: &MaterialField) -> Result<(), String> {
        let known: Vec<String> = self.materials.iter().map(|m| m.name.clone()).collect();
        let m = self
            .materials
            .iter_mut()
            .find(|m| m.name == name)
            .ok_or(format!(
                "material {name:?}: no such material (the scene has: {})",
                known.join(", ")
            ))?;
        let mut brdf = m.brdf;
        use crate::brdf::Brdf;
        let ok = match (&mut brdf, field) {
            (
                Brdf::Ward { roughness, .. } | Brdf::CookTorrance { roughness, .. },
                MaterialField::Roughness(r),
            ) => {
                *roughness = *r;
                true
            }
            (
                Brdf::Phong { exponent, .. } | Brdf::BlinnPhong { exponent, .. },
                MaterialField::Exponent(e),
            ) => {
                *exponent = *e;
                true
            }
            (
                Brdf::Lambert { diffuse }
                | Brdf::Phong { diffuse, .. }
                | Brdf::BlinnPhong { diffuse, .. }
                | Brdf::Ward { diffuse, .. }
                | Brdf::CookTorrance { diffuse, .. },
                MaterialField::Diffuse(c),
            ) => {
                *diffuse = Vec3::from_array(*c);
                true
            }
            (
                Brdf::Phong { specular, .. }
                | Brdf::BlinnPhong { specular, .. }
                | Brdf::Ward { specular, .. }
                | Brdf::CookTorrance { specular, .. },
                MaterialField::Specular(c),
            ) => {
                *specular = Vec3::from_array(*c);
                true
            }
            _ => false,
        };
        if !ok {
            return Err(format!(
                "material {name:?}: its model has no such parameter ({field:?})"
            ));
        }
        brdf.validate()
            .map_err(|e| format!("material {name:?}: {e}"))?;
        m.brdf = brdf;
        self.materials_version += 1;
        Ok(())
    }
}

/// One frame to render.
#[derive(Clone, Debug)]
pub struct Job {
    pub id: u64,
    pub camera: Camera,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub materials_version: u64,
    pub method: ViewMethod,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
    pub indirect_only: bool,
    pub preview: bool,
    /// The progressive reference's pass (its seed is `seed + pass`).
    pub pass: u32,
}

impl Job {
    /// Whether `other` renders the same image except for the progressive pass.
    pub fn same_view(&self, other: &Job) -> bool {
        self.camera == other.camera
            && self.lights == other.lights
            && self.materials_version == other.materials_version
            && self.method == other.method
            && (self.width, self.height, self.spp, self.seed)
                == (other.width, other.height, other.spp, other.seed)
            && self.indirect_only == other.indirect_only
            && self.preview == other.preview
    }
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    pub job: Job,
    pub image: Image,
    /// Stage times, in the order they ran (seconds).
    pub stages: Vec<(&'static str, f64)>,
    /// The whole frame, seconds.
    pub seconds: f64,
    /// sg: mean cut size.
    pub cut_mean: Option<f64>,
    /// sg: each pixel's mean cut size (row-major; zeros with vertex cuts), for the heatmap.
    pub cut_sizes: Vec<f32>,
    /// sg: the cut size cap (`[methods.sg] max_cut`, 0 = none), the heatmap's top.
    pub max_cut: u32,
    /// vpl: where the VPLs are.
    pub vpls: Vec<Vec3>,
    /// Passes averaged (the progressive reference; 1 otherwise).
    pub passes: u32,
    /// Where the GPU stages ran ("cpu", or "gpu (adapter)").
    pub shadow_maps_on: String,
    /// What the panel should say about this frame (prt: the transfer's progress or origin,
    /// lights it ignores).
    pub notices: Vec<String>,
    /// The frame is a placeholder (prt's transfer is being computed): the renderer is to be
    /// asked for it again.
    pub pending: bool,
}

/// Renders jobs with the renderers of `interreflect render` and the same settings as its
/// defaults, keeping sg's pieces and tree while the materials stay the same.
pub struct FrameRenderer {
    scene: Scene,
    accel: std::sync::Arc<Accel>,
    device: Device,
    prepared: Option<(u64, SgPrepared)>,
    /// The lights of the last full-quality sg frame (whose light stage `prepared` keeps).
    full_lights: Option<Vec<Light>>,
    /// The progressive reference: the job it accumulates and the sum so far.
    accumulated: Option<(Job, Vec<Vec3>, u32)>,
    prt: prt::PrtView,
}

impl FrameRenderer {
    pub fn new(scene: Scene, accel: std::sync::Arc<Accel>, device: Device) -> FrameRenderer {
        FrameRenderer {
            scene,
            accel,
            device,
            prepared: None,
            full_lights: None,
            accumulated: None,
            prt: prt::PrtView::new(Some(prt::CACHE_DIR.into())),
        }
    }

    /// Where prt's transfers are cached (`None`: they are not).
    pub fn set_prt_cache(&mut self, dir: Option<std::path::PathBuf>) {
        self.prt = prt::PrtView::new(dir);
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// sg's options for a job, as `render --method sg` would choose them for this scene.
    pub fn sg_options(&self, job: &Job) -> SgOptions {
        let s = &self.scene.settings.sg;
        SgOptions {
            width: job.width,
            height: job.height,
            spp: job.spp,
            seed: job.seed,
            direct: !job.indirect_only,
            indirect: true,
            brute: false,
            cut: crate::sg::CutOptions {
                threshold: s.threshold,
                max_cut: s.max_cut,
            },
            mode: s.cut,
            max_edge: s
                .max_edge
                .unwrap_or_else(|| self.scene.mesh.diagonal() / 128.0),
            visibility: Visibility::Approx,
            device: self.device,
        }
    }

    /// The bounding boxes of sg's tree `depth` levels down (empty until sg has rendered).
    pub fn node_boxes(&self, depth: u32) -> Vec<(Vec3, Vec3)> {
        self.prepared
            .as_ref()
            .map(|(_, p)| p.node_boxes(depth))
            .unwrap_or_default()
    }

    /// Renders `job`; `None` when `cancel` was set meanwhile.
    pub fn render(&mut self, job: &Job, cancel: &AtomicBool) -> Option<Frame> {
        let t = std::time::Instant::now();
        // prt's wait for its transfer, which the frame's time leaves out.
        let mut waited = 0.0;
        self.scene.camera = job.camera;
        self.scene.lights = job.lights.clone();
        self.scene.materials = job.materials.clone();
        let progress = Progress {
            done: &no_progress,
            cancel,
        };
        let mut frame = Frame {
            job: job.clone(),
            image: Image::new(job.width, job.height),
            stages: Vec::new(),
            seconds: 0.0,
            cut_mean: None,
            cut_sizes: Vec::new(),
            max_cut: 0,
            vpls: Vec::new(),
            passes: 1,
            shadow_maps_on: String::new(),
            notices: Vec::new(),
            pending: false,
        };
        match job.method {
            ViewMethod::Sg => {
                let opts = self.sg_options(job);
                let fresh = match &self.prepared {
                    Some((v, p)) => *v != job.materials_version || !p.fits(&opts),
                    None => true,
                };
                if fresh {
                    self.prepared =
                        Some((job.materials_version, SgPrepared::build(&self.scene, &opts)));
                }
                // A preview under a light that moved since the last full frame computes the
                // light stage at a lower cost (fewer visibility maps, smaller shadow maps);
                // under the same light it reuses the full frame's.
                let full = self.scene.settings;
                let reduce = job.preview && self.full_lights.as_ref() != Some(&job.lights);
                if reduce {
                    let s = &mut self.scene.settings;
                    s.ism.node_maps = (s.ism.node_maps / PREVIEW_MAP_DIVISOR)
                        .max(1)
                        .min(s.ism.node_maps);
                    s.vsm.resolution = (s.vsm.resolution / 4).max(16);
                }
                let (_, prepared) = self.prepared.as_mut().expect("built above");
                let result =
                    render_sg_prepared(&self.scene, &self.accel, &opts, prepared, &progress);
                self.scene.settings = full;
                let (img, stats) = result?;
                if !job.preview {
                    self.full_lights = Some(job.lights.clone());
                }
                frame.image = img;
                let s = stats.seconds;
                let kept = stats.light_stage_kept;
                frame.stages = vec![(
                    if fresh { "tree" } else { "tree (kept)" },
                    if fresh { s.tree } else { 0.0 },
                )];
                if kept {
                    frame.stages.push(("light stage (kept)", 0.0));
                } else {
                    frame.stages.extend([
                        ("shadow maps", s.shadow_maps),
                        ("lighting", s.lighting),
                        ("visibility maps", s.vpls),
                    ]);
                }
                frame.stages.extend([
                    ("primary hits", s.primary),
                    ("vertex cuts", s.vertex_cuts),
                    ("shading", s.shading),
                ]);
                frame.cut_mean = Some(stats.cut_size_mean);
                frame.cut_sizes = stats.pixel_cut_sizes;
                frame.max_cut = opts.cut.max_cut;
                frame.shadow_maps_on = stats.shadow_maps_on;
            }
            ViewMethod::Vpl => {
                let opts = VplOptions {
                    width: job.width,
                    height: job.height,
                    spp: job.spp,
                    seed: job.seed,
                    direct: !job.indirect_only,
                    indirect: true,
                    visibility: Visibility::Approx,
                    vpl_count: self.scene.settings.vpl_count,
                    clamp_distance: self
                        .scene
                        .settings
                        .vpl
                        .clamp_distance
                        .unwrap_or_else(|| default_clamp_distance(&self.scene)),
                    device: self.device,
                    cpu_sum: false,
                };
                let (img, stats) = render_vpl(&self.scene, &self.accel, &opts, &progress)?;
                frame.image = img;
                let s = stats.seconds;
                frame.stages = vec![
                    ("shadow maps", s.shadow_maps),
                    ("VPLs", s.vpls),
                    ("imperfect shadow maps", s.ism),
                    ("shading", s.shading),
                ];
                frame.vpls = stats.positions;
                frame.shadow_maps_on = stats.shadow_maps_on;
            }
            ViewMethod::Prt => {
                let image = crate::render::cpu::prt::PrtImageOptions {
                    width: job.width,
                    height: job.height,
                    spp: job.spp,
                    seed: job.seed,
                };
                let f = self.prt.frame(
                    &self.scene,
                    &self.accel,
                    job.materials_version,
                    image,
                    job.indirect_only,
                    cancel,
                )?;
                frame.image = f.image;
                frame.stages = f.stages;
                frame.notices = f.notices;
                frame.pending = f.pending;
                waited = f.waited;
            }
            ViewMethod::Direct | ViewMethod::Reference => {
                let r = self.scene.settings.reference;
                let reference = job.method == ViewMethod::Reference;
                let opts = RenderOptions {
                    width: job.width,
                    height: job.height,
                    spp: job.spp,
                    seed: job.seed.wrapping_add(job.pass as u64),
                    direct: !job.indirect_only,
                    indirect: reference,
                    reflector_samples: r.reflector_samples,
                    bsdf_samples: r.bsdf_samples,
                    light_paths: r.light_paths,
                };
                let (img, _) = render(&self.scene, &self.accel, &opts, &progress)?;
                frame.stages = vec![("path tracing", t.elapsed().as_secs_f64())];
                if reference {
                    let acc = match self.accumulated.take() {
                        Some((j, mut sum, n)) if j.same_view(job) && job.pass == n => {
                            for (s, p) in sum.iter_mut().zip(&img.data) {
                                *s += *p;
                            }
                            (sum, n + 1)
                        }
                        _ => (img.data.clone(), 1),
                    };
                    frame.passes = acc.1;
                    frame.image.data = acc.0.iter().map(|s| *s / acc.1 as f32).collect();
                    self.accumulated = Some((job.clone(), acc.0, acc.1));
                } else {
                    frame.image = img;
                }
            }
        }
        frame.seconds = t.elapsed().as_secs_f64() - waited;
        Some(frame)
    }
}
