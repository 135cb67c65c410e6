//! The reference renderer: direct light plus exactly one indirect bounce, exact visibility.
//!
//! The one-bounce term L₁(x, o) = ∫ L_r(y → x) f_x(ω, o) cos θ_x V(x, y) dω is estimated with
//! three strategies combined by the balance heuristic (Veach 1997, multi-sample MIS):
//! 1. BRDF sampling at the receiver x: sample ω from f_x, trace to y, light y with next-event
//!    estimation for every light;
//! 2. light-side sampling of reflector points: pick a light and a reflector triangle ∝ the flux
//!    it receives, a uniform point y on it, and connect x ↔ y;
//! 3. light tracing: pick y as in 2, sample the reflected direction from f_y, trace to x and
//!    connect x to the camera, splatting into the pixel that sees x.
//!
//! An environment map (`[environment]`) adds, with its own estimators: direct light at x (one
//! environment sample and one BRDF sample, power heuristic, shadow rays to infinity) and the
//! one-bounce path environment → y → x, found only by strategy 1 (weight 1 there): at the y it
//! hits, the environment's direct light is estimated the same way. Strategies 2 and 3 and their
//! MIS denominators stay delta-light-only. Camera rays that miss the geometry return black.
//!
//! Strategy 3 makes glossy caustics (light → glossy reflector → diffuse receiver, e.g. the ring's
//! cardioid) converge; strategy 1 handles glossy receivers; strategy 2 covers the paths in
//! between. Random streams are keyed by (seed, pixel, sample) for camera paths and by
//! (seed, light-path index) for light paths, and splats are summed in a fixed order, so the
//! image does not depend on the thread count.

use super::env_light::EnvLight;
use super::reflectors::ReflectorSampler;
use super::surface::{SurfacePoint, ray_epsilon, reflected_light};
use crate::accel::Accel;
use crate::image::Image;
use crate::math::Rng;
pub use crate::progress::{Progress, no_progress};
use crate::scene::{Camera, Scene};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// What to render.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u64,
    /// Include direct light.
    pub direct: bool,
    /// Include the one-bounce indirect light.
    pub indirect: bool,
    /// Reflector points per camera sample (strategy 2).
    pub reflector_samples: u32,
    /// BRDF directions per camera sample (strategy 1).
    pub bsdf_samples: u32,
    /// Light paths per camera sample (strategy 3, light tracing).
    pub light_paths: u32,
}

/// Counters of a finished render.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct RenderStats {
    /// Camera paths traced (pixels × spp).
    pub camera_paths: u64,
    /// Light paths traced (pixels × spp × light_paths).
    pub light_paths: u64,
    /// Rays traced (camera, continuation, connection and shadow rays).
    pub rays: u64,
    /// Samples dropped because they were not finite (should stay 0).
    pub nonfinite_samples: u64,
}

/// Light paths per work unit of the light-tracing pass.
const LIGHT_CHUNK: u64 = 1 << 14;
/// Work units processed (in parallel) before their splats are added in order.
const CHUNKS_PER_BATCH: u64 = 64;

/// Total work units of a render: one per image row plus one per chunk of light paths.
pub fn work_units(opts: &RenderOptions) -> u64 {
    opts.height as u64 + light_chunks(opts)
}

fn light_path_count(opts: &RenderOptions) -> u64 {
    if opts.indirect {
        opts.width as u64 * opts.height as u64 * opts.spp as u64 * opts.light_paths as u64
    } else {
        0
    }
}

fn light_chunks(opts: &RenderOptions) -> u64 {
    light_path_count(opts).div_ceil(LIGHT_CHUNK)
}

/// Renders `scene` with the reference estimator (or direct light only with
/// `indirect = false`). Returns `None` when cancelled.
pub fn render(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    progress: &Progress,
) -> Option<(Image, RenderStats)> {
    let sampler = if opts.indirect && (opts.reflector_samples > 0 || opts.light_paths > 0) {
        Some(ReflectorSampler::new(scene)).filter(|s| !s.is_empty())
    } else {
        None
    };
    let camera = scene.camera.with_resolution(opts.width, opts.height);
    let tan_half = (0.5 * camera.fov_y).tan();
    let n_light = if sampler.is_some() {
        light_path_count(opts)
    } else {
        0
    };
    let eps = ray_epsilon(scene);
    let ctx = Ctx {
        scene,
        accel,
        eps,
        env: scene
            .environment
            .as_ref()
            .map(|env| EnvLight { accel, env, eps }),
        sampler,
        opts: *opts,
        camera,
        tan_half,
        pixel_area: (2.0 * tan_half / opts.height as f32).powi(2),
        n_light: n_light as f32,
    };
    let rays = AtomicU64::new(0);
    let bad = AtomicU64::new(0);
    let mut img = Image::new(opts.width, opts.height);
    let w = opts.width as usize;
    img.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        if progress.cancel.load(Ordering::Relaxed) {
            return;
        }
        let mut counters = Counters::default();
        for (x, out) in row.iter_mut().enumerate() {
            // Per pixel as well as per row: a row at a high spp can take many seconds.
            if progress.cancel.load(Ordering::Relaxed) {
                return;
            }
            *out = ctx.pixel(x as u32, y as u32, &mut counters);
        }
        rays.fetch_add(counters.rays, Ordering::Relaxed);
        bad.fetch_add(counters.bad, Ordering::Relaxed);
        (progress.done)(1);
    });
    if n_light > 0 {
        ctx.light_pass(n_light, &mut img, progress, &rays, &bad);
    }
    if progress.cancel.load(Ordering::Relaxed) {
        return None;
    }
    let stats = RenderStats {
        camera_paths: opts.width as u64 * opts.height as u64 * opts.spp as u64,
        light_paths: n_light,
        rays: rays.into_inner(),
        nonfinite_samples: bad.into_inner(),
    };
    Some((img, stats))
}

#[derive(Default)]
struct Counters {
    rays: u64,
    bad: u64,
}

struct Ctx<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    eps: f32,
    /// The scene's environment map, if any.
    env: Option<EnvLight<'a>>,
    sampler: Option<ReflectorSampler>,
    opts: RenderOptions,
    camera: Camera,
    tan_half: f32,
    /// Area of a pixel on the image plane at distance 1.
    pixel_area: f32,
    /// Light paths in the whole render (0: no light tracing).
    n_light: f32,
}

/// The geometry of a one-bounce path light → y → x → camera that the MIS weights need.
struct PathTerms {
    /// Receiver BRDF pdf of the direction x → y (solid angle).
    pdf_bsdf_x: f32,
    /// Probability of the light times area density of y under light-side sampling.
    pdf_area_y: f32,
    /// Reflector BRDF pdf of y → x given the light direction (solid angle).
    pdf_bsdf_y: f32,
    /// |x − y|².
    dist2: f32,
    /// |cos| at y and (geometric) at x of the segment x–y.
    cos_y: f32,
    cos_x: f32,
    /// Area density with which the camera's pixel sampling produces x.
    pdf_camera_x: f32,
}

impl Ctx<'_> {
    /// Balance-heuristic denominator D of a path for the three strategies, so that a camera
    /// sample contributes spp·f·L/D and a light path f·L/D (f·L: receiver BRDF × cosine ×
    /// radiance leaving y). Written in solid angle at x times spp:
    /// D = spp·n₁·p₁ + spp·n₂·p₂(y)·d²/cos_y + N_L·p₂(y)·p_y·cos_x/(p_cam(x)·cos_y).
    fn mis_denominator(&self, t: &PathTerms) -> f32 {
        let spp = self.opts.spp as f32;
        let n1 = self.opts.bsdf_samples as f32;
        let n2 = if self.sampler.is_some() {
            self.opts.reflector_samples as f32
        } else {
            0.0
        };
        let cos_y = t.cos_y.max(1e-12);
        let mut d = spp * n1 * t.pdf_bsdf_x + spp * n2 * t.pdf_area_y * t.dist2 / cos_y;
        if self.n_light > 0.0 && t.pdf_camera_x > 0.0 {
            d += self.n_light * t.pdf_area_y * t.pdf_bsdf_y * t.cos_x / (t.pdf_camera_x * cos_y);
        }
        d
    }

    /// Area density of x under the camera's pixel sampling (box filter): cos at x over
    /// (r² · pixel area · cos³ of the angle to the optical axis).
    fn pdf_camera(&self, x: &SurfacePoint, to_camera: Vec3, r: f32) -> f32 {
        let cos_axis = (-to_camera).dot(self.camera.forward);
        if !(cos_axis > 0.0) {
            return 0.0;
        }
        x.ng.dot(to_camera).abs() / (r * r * self.pixel_area * cos_axis.powi(3))
    }

    /// Light-side pdfs of reaching y (on `tri`, oriented `yp`) and leaving it towards x along
    /// `w_yx` for light `k`.
    fn light_side_pdfs(&self, k: usize, yp: &SurfacePoint, w_yx: Vec3) -> (f32, f32) {
        let Some(s) = self.sampler.as_ref() else {
            return (0.0, 0.0);
        };
        let pa = s.pdf_area(k, yp.tri);
        if pa == 0.0 || self.n_light == 0.0 {
            return (pa, 0.0);
        }
        let Some(inc) = self.scene.lights[k].incident(yp.p) else {
            return (pa, 0.0);
        };
        let wl = yp.frame.to_local(inc.wi);
        let wo = yp.frame.to_local(w_yx);
        if wl.z <= 0.0 || wo.z <= 0.0 {
            return (pa, 0.0);
        }
        (pa, self.scene.tri_material(yp.tri).pdf(wl, wo))
    }

    fn pixel(&self, x: u32, y: u32, c: &mut Counters) -> Vec3 {
        let pixel = y as u64 * self.opts.width as u64 + x as u64;
        let mut sum = DVec3::ZERO;
        for s in 0..self.opts.spp {
            let mut rng = Rng::keyed(self.opts.seed, pixel, s as u64);
            let v = self.sample(x, y, &mut rng, c);
            if v.is_finite() {
                sum += v.as_dvec3();
            } else {
                c.bad += 1;
            }
        }
        (sum / self.opts.spp as f64).as_vec3()
    }

    /// One camera path through pixel (x, y) (box filter).
    fn sample(&self, x: u32, y: u32, rng: &mut Rng, c: &mut Counters) -> Vec3 {
        let j = rng.vec2();
        let dir = self.camera.ray_dir(x as f32 + j.x, y as f32 + j.y);
        c.rays += 1;
        let Some(hit) = self
            .accel
            .intersect(self.camera.position, dir, 0.0, f32::INFINITY)
        else {
            return Vec3::ZERO;
        };
        let wo = -dir;
        let Some(sp) = SurfacePoint::from_hit(self.scene, &hit, wo) else {
            return Vec3::ZERO;
        };
        let brdf = self.scene.tri_material(hit.tri);
        let mut l = Vec3::ZERO;
        if self.opts.direct {
            for light in &self.scene.lights {
                c.rays += 1;
                l += reflected_light(self.accel, brdf, &sp, wo, light, self.eps);
            }
            if let Some(env) = &self.env {
                l += env.reflected(brdf, &sp, wo, rng, &mut c.rays);
            }
        }
        if self.opts.indirect && self.scene.tri_object(hit.tri).receiver {
            let pdf_cam = self.pdf_camera(&sp, wo, hit.t);
            l += self.indirect(&sp, wo, pdf_cam, rng, c);
        }
        l
    }

    /// The one-bounce term at receiver `x` towards `wo` from the two camera-side strategies,
    /// weighted against each other and against light tracing.
    fn indirect(
        &self,
        x: &SurfacePoint,
        wo: Vec3,
        pdf_cam: f32,
        rng: &mut Rng,
        c: &mut Counters,
    ) -> Vec3 {
        let brdf = self.scene.tri_material(x.tri);
        let wo_l = x.frame.to_local(wo);
        if wo_l.z <= 0.0 {
            return Vec3::ZERO;
        }
        let spp = self.opts.spp as f32;
        let mut l = Vec3::ZERO;
        // Strategy 1: BRDF sampling at the receiver.
        for _ in 0..self.opts.bsdf_samples {
            let u = rng.arr3();
            let Some(wi_l) = brdf.sample(wo_l, u) else {
                continue;
            };
            let pdf_b = brdf.pdf(wo_l, wi_l);
            let wi = x.frame.to_world(wi_l);
            if !(pdf_b > 0.0) || x.ng.dot(wi) <= 0.0 || wi_l.z <= 0.0 {
                continue;
            }
            let f = brdf.eval(wo_l, wi_l) * wi_l.z;
            if f == Vec3::ZERO {
                continue;
            }
            c.rays += 1;
            let Some(hit) = self
                .accel
                .intersect(x.offset(self.eps), wi, 0.0, f32::INFINITY)
            else {
                continue;
            };
            if !self.scene.tri_object(hit.tri).reflector {
                continue;
            }
            let Some(yp) = SurfacePoint::from_hit(self.scene, &hit, -wi) else {
                continue;
            };
            let ybrdf = self.scene.tri_material(hit.tri);
            for (k, light) in self.scene.lights.iter().enumerate() {
                c.rays += 1;
                let lr = reflected_light(self.accel, ybrdf, &yp, -wi, light, self.eps);
                if lr == Vec3::ZERO {
                    continue;
                }
                let (pdf_area_y, pdf_bsdf_y) = self.light_side_pdfs(k, &yp, -wi);
                let d = self.mis_denominator(&PathTerms {
                    pdf_bsdf_x: pdf_b,
                    pdf_area_y,
                    pdf_bsdf_y,
                    dist2: hit.t * hit.t,
                    cos_y: yp.ng.dot(-wi).abs(),
                    cos_x: x.ng.dot(wi).abs(),
                    pdf_camera_x: pdf_cam,
                });
                l += spp * f * lr / d;
            }
            // The environment's light reflected at y: BRDF sampling at x is the only strategy
            // for these paths, so its weight is 1 (the estimate is f·L / (n₁ p₁)).
            if let Some(env) = &self.env {
                let lr = env.reflected(ybrdf, &yp, -wi, rng, &mut c.rays);
                if lr != Vec3::ZERO {
                    l += f * lr / (self.opts.bsdf_samples as f32 * pdf_b);
                }
            }
        }
        // Strategy 2: light-side sampling of reflector points, connected to x.
        if let Some(s) = self.sampler.as_ref() {
            for _ in 0..self.opts.reflector_samples {
                let (ul, ut, up) = (rng.f32(), rng.f32(), rng.vec2());
                let Some(rs) = s.sample(ul, ut, up) else {
                    continue;
                };
                let yp_pos = self.scene.mesh.point(rs.tri, rs.u, rs.v);
                let d = yp_pos - x.p;
                let dist2 = d.length_squared();
                if !(dist2 > 0.0) {
                    continue;
                }
                let dist = dist2.sqrt();
                let wi = d / dist;
                if x.ng.dot(wi) <= 0.0 {
                    continue;
                }
                let wi_l = x.frame.to_local(wi);
                if wi_l.z <= 0.0 {
                    continue;
                }
                let f = brdf.eval(wo_l, wi_l) * wi_l.z;
                if f == Vec3::ZERO {
                    continue;
                }
                let Some(yp) = SurfacePoint::at(self.scene, rs.tri, rs.u, rs.v, -wi) else {
                    continue;
                };
                let cos_y = yp.ng.dot(-wi);
                if cos_y <= 1e-7 {
                    continue;
                }
                let ybrdf = self.scene.tri_material(rs.tri);
                c.rays += 1;
                let light = &self.scene.lights[rs.light];
                let lr = reflected_light(self.accel, ybrdf, &yp, -wi, light, self.eps);
                if lr == Vec3::ZERO {
                    continue;
                }
                c.rays += 1;
                let tmax = dist * (1.0 - 1e-5) - 2.0 * self.eps;
                if !self.accel.unoccluded(x.offset(self.eps), wi, 0.0, tmax) {
                    continue;
                }
                let (_, pdf_bsdf_y) = self.light_side_pdfs(rs.light, &yp, -wi);
                let den = self.mis_denominator(&PathTerms {
                    pdf_bsdf_x: brdf.pdf(wo_l, wi_l),
                    pdf_area_y: rs.pdf_area,
                    pdf_bsdf_y,
                    dist2,
                    cos_y,
                    cos_x: x.ng.dot(wi),
                    pdf_camera_x: pdf_cam,
                });
                l += spp * f * lr / den;
            }
        }
        l
    }

    /// Strategy 3, light tracing: `n` light paths light → y (light-side sampling) → BRDF
    /// sample at y → x → splat into the pixel that sees x. Chunks of paths run in parallel and
    /// their splats are added in chunk order, so the sum does not depend on the thread count.
    fn light_pass(
        &self,
        n: u64,
        img: &mut Image,
        progress: &Progress,
        rays: &AtomicU64,
        bad: &AtomicU64,
    ) {
        let chunks = n.div_ceil(LIGHT_CHUNK);
        let mut acc: Vec<DVec3> = img.data.iter().map(|p| p.as_dvec3()).collect();
        let mut start = 0;
        while start < chunks {
            if progress.cancel.load(Ordering::Relaxed) {
                return;
            }
            let end = (start + CHUNKS_PER_BATCH).min(chunks);
            let splats: Vec<Vec<(u32, Vec3)>> = (start..end)
                .into_par_iter()
                .map(|chunk| {
                    let mut out = Vec::new();
                    let mut c = Counters::default();
                    let lo = chunk * LIGHT_CHUNK;
                    let hi = (lo + LIGHT_CHUNK).min(n);
                    for i in lo..hi {
                        let mut rng = Rng::keyed(self.opts.seed, LIGHT_STREAM, i);
                        if let Some((px, v)) = self.light_path(&mut rng, &mut c) {
                            if v.is_finite() {
                                out.push((px, v));
                            } else {
                                c.bad += 1;
                            }
                        }
                    }
                    rays.fetch_add(c.rays, Ordering::Relaxed);
                    bad.fetch_add(c.bad, Ordering::Relaxed);
                    (progress.done)(1);
                    out
                })
                .collect();
            for list in &splats {
                for &(px, v) in list {
                    acc[px as usize] += v.as_dvec3();
                }
            }
            start = end;
        }
        for (p, a) in img.data.iter_mut().zip(acc) {
            *p = a.as_vec3();
        }
    }

    /// One light path; returns the pixel it lands in and its (MIS-weighted) contribution.
    fn light_path(&self, rng: &mut Rng, c: &mut Counters) -> Option<(u32, Vec3)> {
        let s = self.sampler.as_ref()?;
        let (ul, ut, up) = (rng.f32(), rng.f32(), rng.vec2());
        let rs = s.sample(ul, ut, up)?;
        let light = &self.scene.lights[rs.light];
        let y_pos = self.scene.mesh.point(rs.tri, rs.u, rs.v);
        let inc = light.incident(y_pos)?;
        let yp = SurfacePoint::at(self.scene, rs.tri, rs.u, rs.v, inc.wi)?;
        let wl = yp.frame.to_local(inc.wi);
        if wl.z <= 0.0 {
            return None;
        }
        let ybrdf = self.scene.tri_material(rs.tri);
        let w_out_l = ybrdf.sample(wl, rng.arr3())?;
        let pdf_bsdf_y = ybrdf.pdf(wl, w_out_l);
        let w_out = yp.frame.to_world(w_out_l);
        if !(pdf_bsdf_y > 0.0) || w_out_l.z <= 0.0 || yp.ng.dot(w_out) <= 0.0 {
            return None;
        }
        let lr = ybrdf.eval(w_out_l, wl) * wl.z * inc.irradiance;
        if lr == Vec3::ZERO {
            return None;
        }
        c.rays += 1;
        let tmax = if inc.dist.is_finite() {
            inc.dist * (1.0 - 1e-5) - self.eps
        } else {
            f32::INFINITY
        };
        if !self
            .accel
            .unoccluded(yp.offset(self.eps), inc.wi, 0.0, tmax)
        {
            return None;
        }
        c.rays += 1;
        let hit = self
            .accel
            .intersect(yp.offset(self.eps), w_out, 0.0, f32::INFINITY)?;
        if !self.scene.tri_object(hit.tri).receiver {
            return None;
        }
        let xp = SurfacePoint::from_hit(self.scene, &hit, -w_out)?;
        // Connect x to the camera.
        let to_cam = self.camera.position - xp.p;
        let r = to_cam.length();
        if !(r > 0.0) {
            return None;
        }
        let wc = to_cam / r;
        if xp.ng.dot(wc) <= 0.0 {
            return None;
        }
        let (px, py) = self.project(-wc)?;
        let xbrdf = self.scene.tri_material(hit.tri);
        let wo_l = xp.frame.to_local(wc);
        let wi_l = xp.frame.to_local(-w_out);
        if wo_l.z <= 0.0 || wi_l.z <= 0.0 {
            return None;
        }
        let f = xbrdf.eval(wo_l, wi_l) * wi_l.z;
        if f == Vec3::ZERO {
            return None;
        }
        c.rays += 1;
        if !self
            .accel
            .unoccluded(xp.offset(self.eps), wc, 0.0, r * (1.0 - 1e-5))
        {
            return None;
        }
        let d = self.mis_denominator(&PathTerms {
            pdf_bsdf_x: xbrdf.pdf(wo_l, wi_l),
            pdf_area_y: rs.pdf_area,
            pdf_bsdf_y,
            dist2: hit.t * hit.t,
            cos_y: yp.ng.dot(w_out).abs(),
            cos_x: xp.ng.dot(w_out).abs(),
            pdf_camera_x: self.pdf_camera(&xp, wc, r),
        });
        if !(d > 0.0) {
            return None;
        }
        Some((py * self.opts.width + px, f * lr / d))
    }

    /// Pixel hit by the camera ray along unit `dir` (from the camera), if inside the image.
    fn project(&self, dir: Vec3) -> Option<(u32, u32)> {
        let cam = &self.camera;
        let z = dir.dot(cam.forward);
        if !(z > 0.0) {
            return None;
        }
        let aspect = self.opts.width as f32 / self.opts.height as f32;
        let sx = dir.dot(cam.right) / z / (self.tan_half * aspect);
        let sy = dir.dot(cam.up) / z / self.tan_half;
        let fx = (sx + 1.0) * 0.5 * self.opts.width as f32;
        let fy = (1.0 - sy) * 0.5 * self.opts.height as f32;
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (px, py) = (fx as u32, fy as u32);
        (px < self.opts.width && py < self.opts.height).then_some((px, py))
    }
}

/// Key of the light-tracing random streams (camera streams use the pixel index there).
const LIGHT_STREAM: u64 = u64::MAX;

/// Convenience: render with no progress reporting or cancellation.
pub fn render_quiet(scene: &Scene, accel: &Accel, opts: &RenderOptions) -> (Image, RenderStats) {
    let cancel = AtomicBool::new(false);
    let p = Progress {
        done: &no_progress,
        cancel: &cancel,
    };
    render(scene, accel, opts, &p).expect("not cancelled")
}
