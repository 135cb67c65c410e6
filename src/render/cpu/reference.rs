//! The reference renderer: direct light plus exactly one indirect bounce, exact visibility.
//!
//! The one-bounce term L₁(x, o) = ∫ L_r(y → x) f_x(ω, o) cos θ_x V(x, y) dω is estimated with two
//! strategies combined by the balance heuristic (Veach 1997, multi-sample MIS):
//! 1. BRDF sampling at the receiver x: sample ω from f_x, trace to y, light y with next-event
//!    estimation for every light;
//! 2. light-side sampling of reflector points: pick a light and a reflector triangle ∝ the flux
//!    it receives, a uniform point y on it, and connect x ↔ y.
//!
//! Strategy 2 makes glossy caustics (light → glossy reflector → diffuse receiver, e.g. the ring's
//! cardioid) converge; strategy 1 handles glossy receivers. Random streams are keyed by
//! (seed, pixel, sample), so the image does not depend on the thread count.

use super::reflectors::ReflectorSampler;
use super::surface::{SurfacePoint, ray_epsilon, reflected_light};
use crate::accel::Accel;
use crate::image::Image;
use crate::math::Rng;
use crate::scene::Scene;
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
}

/// Counters of a finished render.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct RenderStats {
    /// Camera paths traced (pixels × spp).
    pub paths: u64,
    /// Rays traced (camera, continuation, connection and shadow rays).
    pub rays: u64,
    /// Samples dropped because they were not finite (should stay 0).
    pub nonfinite_samples: u64,
}

/// Progress reporting and cancellation, shared by the worker threads.
pub struct Progress<'a> {
    /// Called with the number of image rows just finished.
    pub rows_done: &'a (dyn Fn(u64) + Sync),
    /// When set, rendering stops early and `render` returns `None`.
    pub cancel: &'a AtomicBool,
}

/// Renders `scene` with the reference estimator (or direct light only with
/// `indirect = false`). Returns `None` when cancelled.
pub fn render(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    progress: &Progress,
) -> Option<(Image, RenderStats)> {
    let ctx = Ctx {
        scene,
        accel,
        eps: ray_epsilon(scene),
        sampler: if opts.indirect && opts.reflector_samples > 0 {
            Some(ReflectorSampler::new(scene))
        } else {
            None
        },
        opts: *opts,
        camera: scene.camera.with_resolution(opts.width, opts.height),
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
            *out = ctx.pixel(x as u32, y as u32, &mut counters);
        }
        rays.fetch_add(counters.rays, Ordering::Relaxed);
        bad.fetch_add(counters.bad, Ordering::Relaxed);
        (progress.rows_done)(1);
    });
    if progress.cancel.load(Ordering::Relaxed) {
        return None;
    }
    let stats = RenderStats {
        paths: opts.width as u64 * opts.height as u64 * opts.spp as u64,
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
    sampler: Option<ReflectorSampler>,
    opts: RenderOptions,
    camera: crate::scene::Camera,
}

impl Ctx<'_> {
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
        }
        if self.opts.indirect && self.scene.tri_object(hit.tri).receiver {
            l += self.indirect(&sp, wo, rng, c);
        }
        l
    }

    /// The one-bounce term at receiver `x` towards `wo`, both strategies under MIS.
    fn indirect(&self, x: &SurfacePoint, wo: Vec3, rng: &mut Rng, c: &mut Counters) -> Vec3 {
        let brdf = self.scene.tri_material(x.tri);
        let wo_l = x.frame.to_local(wo);
        if wo_l.z <= 0.0 {
            return Vec3::ZERO;
        }
        let nb = self.opts.bsdf_samples as f32;
        let sampler = self.sampler.as_ref().filter(|s| !s.is_empty());
        let nr = if sampler.is_some() {
            self.opts.reflector_samples as f32
        } else {
            0.0
        };
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
            let cos_y = yp.ng.dot(-wi).abs();
            let g = hit.t * hit.t / cos_y.max(1e-12);
            for (k, light) in self.scene.lights.iter().enumerate() {
                c.rays += 1;
                let lr = reflected_light(self.accel, ybrdf, &yp, -wi, light, self.eps);
                if lr == Vec3::ZERO {
                    continue;
                }
                let p3 = match sampler {
                    Some(s) => nr * s.pdf_area(k, hit.tri) * g,
                    None => 0.0,
                };
                l += f * lr / (nb * pdf_b + p3);
            }
        }
        // Strategy 2: light-side sampling of reflector points, connected to x.
        if let Some(s) = sampler {
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
                let lr = reflected_light(
                    self.accel,
                    ybrdf,
                    &yp,
                    -wi,
                    &self.scene.lights[rs.light],
                    self.eps,
                );
                if lr == Vec3::ZERO {
                    continue;
                }
                c.rays += 1;
                let tmax = dist * (1.0 - 1e-5) - 2.0 * self.eps;
                if !self.accel.unoccluded(x.offset(self.eps), wi, 0.0, tmax) {
                    continue;
                }
                let p3 = nr * rs.pdf_area * dist2 / cos_y;
                let pb = if nb > 0.0 {
                    nb * brdf.pdf(wo_l, wi_l)
                } else {
                    0.0
                };
                l += f * lr / (pb + p3);
            }
        }
        l
    }
}

/// A progress sink that ignores everything (library use, tests).
pub fn no_progress(_: u64) {}

/// Convenience: render with no progress reporting or cancellation.
pub fn render_quiet(scene: &Scene, accel: &Accel, opts: &RenderOptions) -> (Image, RenderStats) {
    let cancel = AtomicBool::new(false);
    let p = Progress {
        rows_done: &no_progress,
        cancel: &cancel,
    };
    render(scene, accel, opts, &p).expect("not cancelled")
}
