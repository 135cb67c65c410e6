//! The VPL baseline (`--method vpl`, METHOD §7): instant radiosity with the same virtual point
//! lights the SG method's approximate visibility uses — the method the paper improves on.
//!
//! Direct light is computed as by `direct` and `sg`. The one-bounce light at a receiver point x
//! is the sum over the VPLs: a VPL at y on a reflector holds the light's incident power Φ there
//! (`precompute::vpl`) and re-emits it through its material's exact BRDF,
//!
//! L(x → eye) = Σ_k f_x(y_k → x → eye) · f_y(light → y_k → x) · Φ_k · G_k · V(y_k, x),
//! G_k = cos θ_x cos θ_y / max(d², d_c²),
//!
//! with the shading normals at both ends and the usual clamp of the geometry term at the
//! distance d_c (`[methods.vpl] clamp_distance`, default 1/50 of the scene's diagonal): without
//! it, a VPL next to a receiver makes a bright splotch. The clamp removes energy near contact
//! and the VPLs' discreteness stays: on glossy receivers every VPL's highlight is a spike, and
//! highlights between VPLs are missing — what the SG method's continuous lobes avoid.
//!
//! Visibility, like `sg`'s: `exact` — shadow rays for the light and between VPLs and receivers;
//! `vsm` — the light's variance shadow maps, rays between VPLs and receivers; `approx` — the
//! variance shadow maps and each VPL's imperfect shadow map.
//!
//! With `approx` and `--device gpu`, the one-bounce sum runs on the GPU (`render::gpu::vpl`);
//! this module's loop is its twin. `auto` runs it there from [`AUTO_GPU_MIN_PAIRS`] sample–VPL
//! pairs (up to [`AUTO_GPU_MAX_SAMPLES`] samples), where lavapipe is measured faster; smaller
//! sums stay here (docs/gpu.md).

use super::reference::Progress;
use super::sg::{
    direct_light, direct_on_gpu, imperfect_shadow_maps, merge_place, primary_hit, primary_hits,
    scene_vpls, shadow_maps,
};
use super::surface::{SurfacePoint, gpu_points, ray_epsilon, scatter};
use crate::accel::{Accel, Hit};
use crate::brdf::Brdf;
use crate::image::Image;
use crate::math::{Frame, triangle_barycentrics};
use crate::precompute::vpl::Vpl;
use crate::render::Device;
use crate::render::Visibility;
use crate::render::gpu::layout::GpuVpl;
use crate::render::gpu::vpl::{MapAtlas, VplShaded};
use crate::scene::Scene;
use crate::visibility::ism::ImperfectShadowMaps;
use crate::visibility::vsm::VarianceShadowMap;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Settings of a VPL render.
#[derive(Clone, Copy, Debug)]
pub struct VplOptions {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel (as for sg: the pixel centre, or a stratified grid).
    pub spp: u32,
    pub seed: u64,
    pub direct: bool,
    pub indirect: bool,
    pub visibility: Visibility,
    /// VPLs per light.
    pub vpl_count: u32,
    /// The geometry term's distance clamp d_c (scene units; 0 = no clamp).
    pub clamp_distance: f32,
    /// Where the stages with a GPU pass run: point lights' shadow maps (`auto` or `gpu`) and,
    /// with `gpu` only, the one-bounce sum over the VPLs (`approx`) and the direct light (with
    /// a shadow map for every light).
    pub device: Device,
    /// Sum the VPLs on the CPU even with `device` gpu: the GPU pass's twin with the same
    /// shadow maps (and so the same VPLs), for the tests.
    pub cpu_sum: bool,
}

/// Seconds per stage.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct VplTimes {
    /// Variance shadow maps (`vsm`, `approx`).
    pub shadow_maps: f64,
    /// VPL sampling.
    pub vpls: f64,
    /// Imperfect shadow maps (`approx`).
    pub ism: f64,
    /// The one-bounce sum on the GPU with the primary rays (`indirect_on` "gpu …"); 0
    /// otherwise.
    pub gpu_shading: f64,
    /// The direct light on the GPU (`direct_on` "gpu …"); 0 otherwise.
    pub gpu_direct: f64,
    /// The pixel loop: primary hits (unless the GPU pass cast them), direct light, and the
    /// one-bounce sum when it runs on the CPU.
    pub shading: f64,
}

/// What a VPL render did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct VplStats {
    /// Where the shadow maps were made ("cpu", "gpu (adapter)", or why the GPU was not used);
    /// empty without shadow maps.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub shadow_maps_on: String,
    /// Where the one-bounce sum ran: "cpu", "gpu (adapter)", or "cpu (why the GPU was not
    /// used)"; empty without indirect light.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub indirect_on: String,
    /// Where the direct light was computed: "cpu", "gpu (adapter)" (`--device gpu` with a
    /// shadow map for every light), or "cpu (why the GPU failed)"; empty without direct light.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub direct_on: String,
    /// Where the VPLs' sampling weights were computed: "cpu", "gpu (adapter)" (`--device gpu`
    /// with shadow maps), or "cpu (why the GPU failed)"; empty without indirect light.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub vpls_on: String,
    /// Where the VPLs' imperfect shadow maps were splatted (`--visibility approx`): "cpu", "gpu
    /// (adapter)" (`--device gpu`), or "cpu (why the GPU failed)"; empty otherwise.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub ism_on: String,
    /// `--device auto` put the sum and the direct light on the GPU (at least
    /// [`AUTO_GPU_MIN_PAIRS`] sample–VPL pairs, at most [`AUTO_GPU_MAX_SAMPLES`] samples, and
    /// an adapter).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub auto_gpu: bool,
    /// VPLs of all lights.
    pub vpls: usize,
    pub clamp_distance: f32,
    /// VPL–receiver pairs whose geometry term the clamp reduced.
    pub clamped_pairs: u64,
    /// VPL–receiver pairs evaluated (both facing each other).
    pub pairs: u64,
    /// Shadow rays between VPLs and receivers.
    pub visibility_rays: u64,
    pub nonfinite_samples: u64,
    pub seconds: VplTimes,
    /// Where the VPLs are, for the viewer's overlay (not in the JSON log).
    #[serde(skip)]
    pub positions: Vec<glam::Vec3>,
}

/// A VPL ready to shade with: its frame (shading normal) and its material.
struct Emitter<'a> {
    /// Index of the VPL among its light's VPLs (its imperfect shadow map).
    index: usize,
    vpl: Vpl,
    frame: Frame,
    /// Direction to the light in the VPL's frame.
    wi_local: Vec3,
    brdf: &'a Brdf,
    /// Index of `brdf` among the scene's materials.
    material: u32,
}

/// One light's VPLs and their visibility.
struct LightVpls<'a> {
    emitters: Vec<Emitter<'a>>,
    ism: Option<ImperfectShadowMaps>,
}

/// The default clamp distance: 1/50 of the scene's bounding-box diagonal.
pub fn default_clamp_distance(scene: &Scene) -> f32 {
    scene.mesh.diagonal() / 50.0
}

/// Convenience: [`render_vpl`] with no progress reporting or cancellation.
pub fn render_vpl_quiet(scene: &Scene, accel: &Accel, opts: &VplOptions) -> (Image, VplStats) {
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let p = Progress {
        done: &super::reference::no_progress,
        cancel: &cancel,
    };
    render_vpl(scene, accel, opts, &p).expect("not cancelled")
}

/// Sample–VPL pairs from which `--device auto` sums the VPLs (and computes the direct light) on
/// the GPU when an adapter exists. Measured on lavapipe (2 cores; 256 px, 4 spp, 200 VPLs:
/// 52 million pairs): the GPU's sum 1.0× the CPU's on the ring, 1.4× on the bunny, 1.6× on the
/// dragons; at 128 px and 4 spp (13 million) the ring's is at parity and the dragon's 1.5×, at
/// 64 px and 1 spp (0.8 million) the GPU's fixed costs make it 0.5–0.6× (`docs/gpu.md`).
pub const AUTO_GPU_MIN_PAIRS: u64 = 10_000_000;

/// Pixel samples up to which `--device auto` takes the GPU path: it keeps every sample's primary
/// hit and surface point in memory (about 300 bytes a sample, measured: 60 MB more peak memory
/// for the dragon's 196,608), where the CPU path streams them; beyond it (600 MB) auto stays
/// on the CPU.
pub const AUTO_GPU_MAX_SAMPLES: u64 = 2_000_000;

/// Renders `scene` with the VPL baseline. `None` when cancelled.
pub fn render_vpl(
    scene: &Scene,
    accel: &Accel,
    opts: &VplOptions,
    progress: &Progress,
) -> Option<(Image, VplStats)> {
    let mut stats = VplStats {
        clamp_distance: opts.clamp_distance,
        ..VplStats::default()
    };
    let eps = ray_epsilon(scene);

    let t = Instant::now();
    let (maps, place) = shadow_maps(scene, accel, opts.visibility, opts.device);
    stats.shadow_maps_on = place;
    stats.seconds.shadow_maps = t.elapsed().as_secs_f64();
    if progress.cancel.load(Ordering::Relaxed) {
        return None;
    }

    // The same VPLs as sg's approximate visibility (same sources, count and seeds).
    let mut lights: Vec<LightVpls> = Vec::new();
    if opts.indirect {
        let t = Instant::now();
        let (vpls, place) = scene_vpls(
            scene,
            accel,
            &maps,
            opts.vpl_count as usize,
            opts.seed,
            eps,
            opts.device,
        );
        stats.vpls_on = place;
        stats.seconds.vpls = t.elapsed().as_secs_f64();
        let t = Instant::now();
        for (k, vs) in vpls.into_iter().enumerate() {
            let ism = (opts.visibility == Visibility::Approx).then(|| {
                let (maps, place) =
                    imperfect_shadow_maps(scene, &vs, opts.seed ^ k as u64, opts.device);
                merge_place(&mut stats.ism_on, place);
                maps
            });
            let emitters = vs
                .iter()
                .enumerate()
                .filter_map(|(index, v)| {
                    let [a, b, c] = scene.mesh.tri(v.tri);
                    let (u, w) = triangle_barycentrics(a, b, c, v.position);
                    // Oriented to the lit side (the VPL's normal points there).
                    let sp = SurfacePoint::at(scene, v.tri, u, w, v.normal)?;
                    let wi_local = sp.frame.to_local(v.wi);
                    (wi_local.z > 0.0).then(|| Emitter {
                        index,
                        vpl: *v,
                        frame: sp.frame,
                        wi_local,
                        brdf: scene.tri_material(v.tri),
                        material: scene.tri_material_index(v.tri),
                    })
                })
                .collect::<Vec<_>>();
            stats.vpls += emitters.len();
            stats
                .positions
                .extend(emitters.iter().map(|e| e.vpl.position));
            lights.push(LightVpls { emitters, ism });
        }
        stats.seconds.ism = t.elapsed().as_secs_f64();
    }
    if progress.cancel.load(Ordering::Relaxed) {
        return None;
    }

    let camera = scene.camera.with_resolution(opts.width, opts.height);
    let w = opts.width as usize;
    let spp = opts.spp.max(1);
    let dc2 = opts.clamp_distance * opts.clamp_distance;
    let (pairs, clamped, rays, bad) = (
        AtomicU64::new(0),
        AtomicU64::new(0),
        AtomicU64::new(0),
        AtomicU64::new(0),
    );

    // The stages on the GPU (--device gpu, or auto for a sum large enough to be faster there):
    // primary hits cast first, for every sample; then the one-bounce sum (with `approx`) and the
    // direct light (with a shadow map for every light).
    let t = Instant::now();
    let samples = u64::from(opts.width) * u64::from(opts.height) * u64::from(spp);
    let gpu_stages = match opts.device {
        Device::Gpu => true,
        Device::Cpu => false,
        Device::Auto => {
            opts.indirect
                && opts.visibility == Visibility::Approx
                && !opts.cpu_sum
                && samples * stats.vpls as u64 >= AUTO_GPU_MIN_PAIRS
                && samples <= AUTO_GPU_MAX_SAMPLES
                && crate::render::gpu::Gpu::shared().is_ok()
        }
    };
    stats.auto_gpu = opts.device == Device::Auto && gpu_stages;
    let hits = gpu_stages.then(|| primary_hits(accel, &camera, spp, opts.seed));
    let mut gpu_sums: Option<Vec<VplShaded>> = None;
    if opts.indirect {
        stats.indirect_on = "cpu".into();
    }
    if let Some(all) = hits
        .as_ref()
        .filter(|_| opts.indirect && opts.visibility == Visibility::Approx && !opts.cpu_sum)
    {
        match gpu_indirect(scene, &lights, all, opts.clamp_distance, progress.cancel) {
            Ok(Some((sums, adapter))) => {
                stats.indirect_on = format!("gpu ({adapter})");
                gpu_sums = Some(sums);
            }
            Ok(None) => return None,
            Err(e) => stats.indirect_on = format!("cpu (the GPU failed: {e})"),
        }
    }
    stats.seconds.gpu_shading = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let (on, gpu_direct) = direct_on_gpu(
        scene,
        if gpu_stages { Device::Gpu } else { Device::Cpu },
        opts.direct,
        &maps,
        hits.as_deref().unwrap_or_default(),
        eps,
        progress.cancel,
    )?;
    stats.direct_on = on;
    stats.seconds.gpu_direct = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut img = Image::new(opts.width, opts.height);
    img.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        if progress.cancel.load(Ordering::Relaxed) {
            return;
        }
        let mut c = [0u64; 3];
        for (x, out) in row.iter_mut().enumerate() {
            if progress.cancel.load(Ordering::Relaxed) {
                return;
            }
            let pixel = (y * w + x) as u64;
            let mut sum = DVec3::ZERO;
            for s in 0..spp {
                let i = pixel as usize * spp as usize + s as usize;
                let hit = match &hits {
                    Some(h) => h[i],
                    None => primary_hit(accel, &camera, spp, opts.seed, pixel as usize, s),
                };
                let direct = gpu_direct.as_ref().map(|g| g[i]);
                let indirect = match &gpu_sums {
                    Some(g) => Indirect::Gpu(g[i]),
                    None => Indirect::Cpu(&lights),
                };
                let v = shade(
                    scene,
                    accel,
                    opts,
                    &maps,
                    direct,
                    indirect,
                    hit.as_ref(),
                    eps,
                    dc2,
                    &mut c,
                );
                if v.is_finite() {
                    sum += v.as_dvec3();
                } else {
                    bad.fetch_add(1, Ordering::Relaxed);
                }
            }
            *out = (sum / spp as f64).as_vec3();
        }
        pairs.fetch_add(c[0], Ordering::Relaxed);
        clamped.fetch_add(c[1], Ordering::Relaxed);
        rays.fetch_add(c[2], Ordering::Relaxed);
        (progress.done)(1);
    });
    stats.seconds.shading = t.elapsed().as_secs_f64();
    if progress.cancel.load(Ordering::Relaxed) {
        return None;
    }
    stats.pairs = pairs.into_inner();
    stats.clamped_pairs = clamped.into_inner();
    stats.visibility_rays = rays.into_inner();
    stats.nonfinite_samples = bad.into_inner();
    Some((img, stats))
}

/// A sample's one-bounce light: summed here over the lights' VPLs, or already by the GPU.
#[derive(Clone, Copy)]
enum Indirect<'l, 'a> {
    Cpu(&'l [LightVpls<'a>]),
    Gpu(VplShaded),
}

/// Radiance of one pixel sample; `c` counts (pairs, clamped pairs, rays).
#[allow(clippy::too_many_arguments)]
fn shade(
    scene: &Scene,
    accel: &Accel,
    opts: &VplOptions,
    maps: &[Option<VarianceShadowMap>],
    direct: Option<Vec3>,
    indirect: Indirect,
    hit: Option<&Hit>,
    eps: f32,
    dc2: f32,
    c: &mut [u64; 3],
) -> Vec3 {
    let Some(hit) = hit else {
        return Vec3::ZERO;
    };
    let camera = scene.camera.position;
    let wo = (camera - scene.mesh.point(hit.tri, hit.u, hit.v)).normalize();
    let Some(sp) = SurfacePoint::from_hit(scene, hit, wo) else {
        return Vec3::ZERO;
    };
    let brdf = scene.tri_material(hit.tri);
    let mut l = Vec3::ZERO;
    if opts.direct {
        l += match direct {
            Some(d) => d,
            None => direct_light(scene, accel, maps, brdf, &sp, wo, eps),
        };
    }
    if !opts.indirect || !scene.tri_object(hit.tri).receiver {
        return l;
    }
    let lights = match indirect {
        Indirect::Cpu(lights) => lights,
        Indirect::Gpu(g) => {
            c[0] += u64::from(g.pairs);
            c[1] += u64::from(g.clamped);
            return l + g.radiance;
        }
    };
    let wo_l = sp.frame.to_local(wo);
    if !(wo_l.z > 0.0) {
        return l;
    }
    let xo = sp.offset(eps);
    for lv in lights {
        for e in &lv.emitters {
            let d = e.vpl.position - sp.p;
            let d2 = d.length_squared();
            if !(d2 > 0.0) {
                continue;
            }
            let dist = d2.sqrt();
            let to_vpl = d / dist;
            // Both ends must face each other (geometric and shading normals).
            if sp.ng.dot(to_vpl) <= 0.0 || e.vpl.normal.dot(-to_vpl) <= 0.0 {
                continue;
            }
            let wi_x = sp.frame.to_local(to_vpl);
            let wo_y = e.frame.to_local(-to_vpl);
            if wi_x.z <= 0.0 || wo_y.z <= 0.0 {
                continue;
            }
            let fx = brdf.eval(wo_l, wi_x);
            let fy = e.brdf.eval(wo_y, e.wi_local);
            if fx == Vec3::ZERO || fy == Vec3::ZERO {
                continue;
            }
            c[0] += 1;
            if d2 < dc2 {
                c[1] += 1;
            }
            let g = wi_x.z * wo_y.z / d2.max(dc2);
            let v = match &lv.ism {
                Some(ism) => ism.visibility(e.index, sp.p),
                None => {
                    c[2] += 1;
                    let tmax = dist * (1.0 - 1e-5) - eps;
                    f32::from(u8::from(accel.unoccluded(xo, to_vpl, 0.0, tmax)))
                }
            };
            if v > 0.0 {
                l += fx * fy * e.vpl.power * (g * v);
            }
        }
    }
    l
}

/// The one-bounce sum of every sample (`hits`, sample-major within pixels) on the GPU, with
/// the adapter's name; `None` when cancelled. The points are those `shade` sums at: receivers
/// seen from their front.
fn gpu_indirect(
    scene: &Scene,
    lights: &[LightVpls],
    hits: &[Option<Hit>],
    clamp_distance: f32,
    cancel: &std::sync::atomic::AtomicBool,
) -> Result<Option<(Vec<VplShaded>, String)>, crate::render::gpu::GpuError> {
    let gpu = crate::render::gpu::Gpu::shared()?;
    let (index, points) = gpu_points(scene, hits, scene.camera.position, |hit, _, _, wo_l| {
        scene.tri_object(hit.tri).receiver && wo_l.z > 0.0
    });
    let mut atlas = MapAtlas::default();
    let mut vpls = Vec::new();
    for lv in lights {
        let first = match &lv.ism {
            Some(ism) => Some(atlas.push(ism)?),
            None => None,
        };
        for e in &lv.emitters {
            vpls.push(GpuVpl {
                position: e.vpl.position.to_array(),
                material: e.material,
                normal: e.vpl.normal.to_array(),
                map: first.map_or(u32::MAX, |f| f + e.index as u32),
                t: e.frame.t.to_array(),
                b: e.frame.b.to_array(),
                n: e.frame.n.to_array(),
                wi: e.wi_local.to_array(),
                power: e.vpl.power.to_array(),
                ..GpuVpl::default()
            });
        }
    }
    let materials: Vec<Brdf> = scene.materials.iter().map(|m| m.brdf).collect();
    let Some(sums) = crate::render::gpu::vpl::shade(
        &gpu,
        &materials,
        &points,
        &vpls,
        &atlas,
        clamp_distance,
        cancel,
    )?
    else {
        return Ok(None);
    };
    let per_sample = scatter(&index, &sums);
    Ok(Some((per_sample, gpu.adapter.clone())))
}
