//! SH diffuse precomputed radiance transfer (Sloan, Kautz & Snyder 2002), the low-frequency
//! method the SG renderer is compared against (METHOD.md §8, `docs/prt.md`).
//!
//! Every vertex gets a transfer vector per colour channel, so that under distant lighting with
//! SH coefficients L_i its outgoing radiance is Σ_i T_i L_i (one dot product per vertex and
//! channel, [`relight_cpu`] and its GPU twin `render::gpu::prt::relight`). With the vertex's
//! Lambertian albedo ρ and normal n:
//!
//! - unshadowed: T_i = (ρ/π) ∫ max(n·ω, 0) y_i(ω) dω = (ρ/π) Â_l y_i(n), in closed form;
//! - shadowed: T⁰_i = (ρ/π) ∫ V(ω) max(n·ω, 0) y_i(ω) dω, by cosine-distributed rays;
//! - interreflected with B bounces: T = T⁰ + T¹ + … + Tᴮ with
//!   Tᵇ_x = (ρ_x/π) ∫ over directions that hit a reflector y of T^(b−1)_y max(n·ω, 0) dω,
//!   T^(b−1)_y interpolated from the vertices of y's triangle (the same rays, traced again).
//!
//! The one-bounce part (T¹ …) is kept apart from T⁰ so that `--indirect-only` images compare
//! with the reference's one-bounce light, and it follows the scene's flags like every other
//! method: only receivers gather it, only reflectors send it. Diffuse PRT sees every material as
//! Lambertian: a glossy material enters with its hemispherical albedo ([`lambertian_albedo`]),
//! which keeps its energy and loses its highlights and mirror images.
//!
//! Transfer depends on geometry, materials and these settings, never on the lighting: it is
//! cached on disk ([`load_or_compute`]) keyed by a hash of all of them, so that changing or
//! rotating the lighting re-runs only the relighting.

use crate::accel::Accel;
use crate::brdf::Brdf;
use crate::hash::Fnv;
use crate::math::sampling::cosine_hemisphere;
use crate::math::sh;
use crate::math::{Frame, Rng};
use crate::progress::Progress;
use crate::scene::{Environment, Light, Scene};
pub use crate::settings::{TransferKind, WindowKind};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

pub mod irradiance;

/// How to compute the transfer.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PrtOptions {
    /// SH order: bands l < order.
    pub order: u32,
    pub kind: TransferKind,
    /// Reflections (only with [`TransferKind::Interreflected`]).
    pub bounces: u32,
    /// Ray directions per vertex.
    pub samples: u32,
    /// Seed of the per-vertex direction streams.
    pub seed: u64,
}

impl PrtOptions {
    /// Reflections actually computed (0 unless the transfer is interreflected).
    pub fn effective_bounces(&self) -> u32 {
        if self.kind == TransferKind::Interreflected {
            self.bounces
        } else {
            0
        }
    }
}

/// Transfer vectors of every vertex of the scene mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Transfer {
    pub order: u32,
    pub vertices: usize,
    /// Light leaving each vertex without reflection off another surface: `[vertex][coefficient]`.
    pub direct: Vec<Vec3>,
    /// Light leaving each vertex after 1..=bounces reflections: `[vertex][coefficient]`, empty
    /// when no bounce was computed.
    pub bounce: Vec<Vec3>,
}

impl Transfer {
    /// Coefficients per vertex and channel (order²).
    pub fn coefficients(&self) -> usize {
        sh::sh_count(self.order)
    }

    /// The whole transfer, direct plus bounce (relighting is linear, so the two are summed
    /// once rather than relit apart): `[vertex][coefficient]`.
    pub fn total(&self) -> Vec<Vec3> {
        if self.bounce.is_empty() {
            return self.direct.clone();
        }
        self.direct
            .iter()
            .zip(&self.bounce)
            .map(|(a, b)| *a + *b)
            .collect()
    }

    /// Memory held by the transfer vectors, in bytes.
    pub fn bytes(&self) -> usize {
        (self.direct.len() + self.bounce.len()) * std::mem::size_of::<Vec3>()
    }
}

/// Per-vertex inputs of the precomputation.
#[derive(Clone, Copy, Debug)]
pub struct VertexInfo {
    pub position: Vec3,
    /// Unit normal (the mesh's vertex normal, or the area-weighted normal of its triangles).
    pub normal: Vec3,
    /// Lambertian albedo of the vertex's material.
    pub albedo: Vec3,
    /// Whether the vertex's object receives reflected light.
    pub receiver: bool,
    /// Whether any triangle uses the vertex (unused vertices keep zero transfer).
    pub used: bool,
}

/// Hemispherical (cosine-weighted, averaged over cosine-weighted view directions) albedo of a
/// BRDF: the Lambertian albedo diffuse PRT uses for it. Exact for Lambert; for the other models
/// a deterministic 16×16 × 16×16 stratified estimate with the BRDF's own importance sampling
/// (its noise is far below the differences PRT is measured on).
pub fn lambertian_albedo(brdf: &Brdf) -> Vec3 {
    if brdf.is_diffuse() {
        return brdf.diffuse();
    }
    const S: u32 = 16;
    let mut sum = glam::DVec3::ZERO;
    let mut rng = Rng::keyed(0x5eed, 0, 0);
    for i in 0..S * S {
        let uo = Vec2::new(
            ((i % S) as f32 + 0.5) / S as f32,
            ((i / S) as f32 + 0.5) / S as f32,
        );
        let wo = cosine_hemisphere(uo);
        if wo.z <= 1e-4 {
            continue;
        }
        let mut acc = glam::DVec3::ZERO;
        for j in 0..S * S {
            let u = [
                rng.f32(),
                ((j % S) as f32 + rng.f32()) / S as f32,
                ((j / S) as f32 + rng.f32()) / S as f32,
            ];
            let Some(wi) = brdf.sample(wo, u) else {
                continue;
            };
            let pdf = brdf.pdf(wo, wi);
            if !(pdf > 0.0) || wi.z <= 0.0 {
                continue;
            }
            let v = brdf.eval(wo, wi) * (wi.z / pdf);
            if v.is_finite() {
                acc += v.as_dvec3();
            }
        }
        sum += acc / (S * S) as f64;
    }
    (sum / (S * S) as f64).as_vec3().min(Vec3::ONE)
}

/// Position, normal, albedo and flags of every vertex.
pub fn vertex_info(scene: &Scene) -> Vec<VertexInfo> {
    let mesh = &scene.mesh;
    let albedo: Vec<Vec3> = scene
        .materials
        .iter()
        .map(|m| lambertian_albedo(&m.brdf))
        .collect();
    let mut info: Vec<VertexInfo> = mesh
        .positions
        .iter()
        .enumerate()
        .map(|(i, &p)| VertexInfo {
            position: p,
            normal: mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO),
            albedo: Vec3::ZERO,
            receiver: false,
            used: false,
        })
        .collect();
    let mut face_normal = vec![Vec3::ZERO; mesh.positions.len()];
    for (t, tri) in mesh.indices.iter().enumerate() {
        let obj = &scene.objects[mesh.tri_object[t] as usize];
        let cross = mesh.tri_cross(t as u32);
        for &v in tri {
            let vi = &mut info[v as usize];
            if !vi.used {
                vi.used = true;
                vi.albedo = albedo[obj.material as usize];
                vi.receiver = obj.receiver;
            }
            face_normal[v as usize] += cross;
        }
    }
    for (vi, fnrm) in info.iter_mut().zip(face_normal) {
        vi.normal = vi
            .normal
            .try_normalize()
            .filter(|n| n.is_finite())
            .or_else(|| fnrm.try_normalize())
            .unwrap_or(Vec3::Y);
    }
    info
}

/// Vertices per progress unit.
const CHUNK: usize = 512;

/// Progress units of [`precompute`]: one per chunk of vertices and pass.
pub fn work_units(scene: &Scene, opts: &PrtOptions) -> u64 {
    let passes = match opts.kind {
        TransferKind::Unshadowed => 1,
        _ => 1 + opts.effective_bounces() as u64,
    };
    passes * scene.mesh.positions.len().div_ceil(CHUNK) as u64
}

/// Computes the transfer of every vertex; `None` when cancelled.
pub fn precompute(
    scene: &Scene,
    accel: &Accel,
    opts: &PrtOptions,
    progress: &Progress,
) -> Option<Transfer> {
    let info = vertex_info(scene);
    let n = sh::sh_count(opts.order);
    let eps = crate::scene::ray_epsilon(scene);
    let pass = |f: &(dyn Fn(usize, &VertexInfo, &mut [Vec3]) + Sync)| -> Option<Vec<Vec3>> {
        let mut out = vec![Vec3::ZERO; info.len() * n];
        out.par_chunks_mut(CHUNK * n)
            .enumerate()
            .for_each(|(c, block)| {
                if progress.cancel.load(Ordering::Relaxed) {
                    return;
                }
                for (k, t) in block.chunks_mut(n).enumerate() {
                    let v = c * CHUNK + k;
                    if info[v].used {
                        f(v, &info[v], t);
                    }
                }
                (progress.done)(1);
            });
        (!progress.cancel.load(Ordering::Relaxed)).then_some(out)
    };
    let direct = match opts.kind {
        TransferKind::Unshadowed => pass(&|_, vi, t| {
            let mut y = vec![0.0f32; n];
            sh::eval_sh(opts.order, vi.normal, &mut y);
            for l in 0..opts.order {
                let a = sh::cosine_convolution_factor(l) / std::f32::consts::PI;
                for m in -(l as i32)..=(l as i32) {
                    let i = sh::sh_index(l, m);
                    t[i] = vi.albedo * (a * y[i]);
                }
            }
        })?,
        _ => pass(&|v, vi, t| {
            let mut y = vec![0.0f32; n];
            let mut acc = vec![0.0f64; n];
            let frame = Frame::from_normal(vi.normal);
            let origin = vi.position + vi.normal * eps;
            for_each_direction(opts, v, &frame, |dir| {
                if accel.unoccluded(origin, dir, 0.0, f32::INFINITY) {
                    sh::eval_sh(opts.order, dir, &mut y);
                    for (a, &yi) in acc.iter_mut().zip(&y) {
                        *a += yi as f64;
                    }
                }
            });
            let scale = 1.0 / opts.samples as f64;
            for (ti, a) in t.iter_mut().zip(&acc) {
                *ti = vi.albedo * (a * scale) as f32;
            }
        })?,
    };
    let mut bounce = Vec::new();
    let mut previous = direct.clone();
    for _ in 0..opts.effective_bounces() {
        let next = pass(&|v, vi, t| {
            if !vi.receiver {
                return;
            }
            let frame = Frame::from_normal(vi.normal);
            let origin = vi.position + vi.normal * eps;
            let mut acc = vec![glam::DVec3::ZERO; n];
            for_each_direction(opts, v, &frame, |dir| {
                let Some(hit) = accel.intersect(origin, dir, 0.0, f32::INFINITY) else {
                    return;
                };
                if !scene.tri_object(hit.tri).reflector {
                    return;
                }
                // The transfer of y describes its front side (the side its normals face).
                let ns = scene.mesh.shading_normal(hit.tri, hit.u, hit.v);
                if ns.dot(dir) >= 0.0 {
                    return;
                }
                let [a, b, c] = scene.mesh.indices[hit.tri as usize];
                let w = [1.0 - hit.u - hit.v, hit.u, hit.v];
                for (k, &vert) in [a, b, c].iter().enumerate() {
                    let src = &previous[vert as usize * n..(vert as usize + 1) * n];
                    for (ac, s) in acc.iter_mut().zip(src) {
                        *ac += (*s * w[k]).as_dvec3();
                    }
                }
            });
            let scale = 1.0 / opts.samples as f64;
            for (ti, a) in t.iter_mut().zip(&acc) {
                *ti = vi.albedo * (*a * scale).as_vec3();
            }
        })?;
        if bounce.is_empty() {
            bounce = next.clone();
        } else {
            for (b, x) in bounce.iter_mut().zip(&next) {
                *b += *x;
            }
        }
        previous = next;
    }
    Some(Transfer {
        order: opts.order,
        vertices: info.len(),
        direct,
        bounce,
    })
}

/// Calls `f` with the `opts.samples` cosine-distributed directions of vertex `v` around
/// `frame`'s normal: a jittered √N × √N grid on the square (the rest uniformly random), with a
/// random stream keyed by (seed, vertex), the same in every pass.
fn for_each_direction(opts: &PrtOptions, v: usize, frame: &Frame, mut f: impl FnMut(Vec3)) {
    let mut rng = Rng::keyed(opts.seed, v as u64, 0x9e37);
    let s = (opts.samples as f64).sqrt() as u32;
    for k in 0..opts.samples {
        let u = if k < s * s {
            Vec2::new(
                ((k % s) as f32 + rng.f32()) / s as f32,
                ((k / s) as f32 + rng.f32()) / s as f32,
            )
        } else {
            rng.vec2()
        };
        let d = frame.to_world(cosine_hemisphere(u.min(Vec2::splat(1.0 - f32::EPSILON))));
        f(d);
    }
}

/// Radiance of every vertex: Σ_i transfer[v][i] ⊙ lighting[i]. The CPU twin of
/// `render::gpu::prt::relight` (`shaders/prt_relight.wgsl`).
pub fn relight_cpu(transfer: &[Vec3], coefficients: usize, lighting: &[Vec3]) -> Vec<Vec3> {
    transfer
        .par_chunks(coefficients)
        .map(|t| t.iter().zip(lighting).map(|(a, b)| *a * *b).sum())
        .collect()
}

/// SH coefficients of the scene's distant lighting (radiance): its environment map, projected
/// with exact texel solid angles, plus its directional lights as deltas, windowed. Point and spot
/// lights are not distant and cannot be represented; they are listed in the returned warnings.
pub fn sh_lighting(scene: &Scene, order: u32, window: sh::Window) -> (Vec<Vec3>, Vec<String>) {
    let env = scene.environment.as_ref().map(|e| sh_environment(e, order));
    sh_lighting_with(env.as_deref(), &scene.lights, order, window)
}

/// The SH projection of an environment map (radiance, unwindowed), with exact texel solid
/// angles: the part of [`sh_lighting`] that does not change when the lights move.
pub fn sh_environment(env: &Environment, order: u32) -> Vec<Vec3> {
    let samples = (0..env.height()).flat_map(|y| {
        let w = env.texel_solid_angle(y);
        (0..env.width()).map(move |x| (env.texel_direction(x, y), w, env.texel(x, y)))
    });
    sh::project_samples(order, samples)
}

/// [`sh_lighting`] from an environment already projected by [`sh_environment`] (`None`: no
/// environment) and a list of lights.
pub fn sh_lighting_with(
    environment: Option<&[Vec3]>,
    lights: &[Light],
    order: u32,
    window: sh::Window,
) -> (Vec<Vec3>, Vec<String>) {
    let n = sh::sh_count(order);
    let mut coeffs = vec![Vec3::ZERO; n];
    let mut warnings = Vec::new();
    if let Some(c) = environment {
        for (a, b) in coeffs.iter_mut().zip(c) {
            *a += *b;
        }
    }
    let mut skipped = 0;
    for light in lights {
        match *light {
            Light::Directional {
                direction,
                irradiance,
            } => {
                let c = sh::project_directional(order, -direction, irradiance);
                for (a, b) in coeffs.iter_mut().zip(c) {
                    *a += b;
                }
            }
            _ => skipped += 1,
        }
    }
    if skipped > 0 {
        warnings.push(format!(
            "prt: {skipped} point/spot light(s) ignored: PRT relights with distant lighting only (environment maps and directional lights)"
        ));
    }
    if environment.is_none() && skipped == lights.len() {
        warnings.push(NO_DISTANT_LIGHTING.into());
    }
    sh::apply_window(&mut coeffs, order, window);
    (coeffs, warnings)
}

/// The warning of [`sh_lighting`] when nothing in the scene is distant lighting.
pub const NO_DISTANT_LIGHTING: &str = "prt: the scene has no distant lighting: the image is black";

/// Where a transfer came from.
#[derive(Clone, Debug, PartialEq)]
pub enum CacheStatus {
    /// Read from this cache file.
    Hit(PathBuf),
    /// Computed and written to this cache file.
    Stored(PathBuf),
    /// Computed; the cache was off or could not be written (the reason).
    Uncached(Option<String>),
}

/// Bumped whenever the transfer's definition or the file layout changes.
const CACHE_VERSION: &[u8] = b"interreflect-prt-v1";
const MAGIC: &[u8; 8] = b"IRPRT001";

/// Hash of everything the transfer depends on: geometry, normals, materials' albedos, the
/// objects' reflector/receiver flags and the options — except the order: the SH basis is nested,
/// so a transfer of order n holds every lower order's coefficients (the same estimates), and one
/// cache file serves them all.
pub fn cache_key(scene: &Scene, opts: &PrtOptions) -> u64 {
    let mut h = Fnv::new();
    h.bytes(CACHE_VERSION);
    h.u64(opts.kind as u64);
    h.u64(opts.effective_bounces() as u64);
    h.u64(opts.samples as u64);
    h.u64(opts.seed);
    let mesh = &scene.mesh;
    h.f32s(bytemuck::cast_slice(&mesh.positions));
    h.f32s(bytemuck::cast_slice(&mesh.normals));
    h.u64(mesh.indices.len() as u64);
    h.bytes(bytemuck::cast_slice(&mesh.indices));
    h.bytes(bytemuck::cast_slice(&mesh.tri_object));
    for o in &scene.objects {
        h.u64(o.material as u64);
        h.u64(o.reflector as u64 | (o.receiver as u64) << 1);
    }
    for m in &scene.materials {
        h.f32s(&lambertian_albedo(&m.brdf).to_array());
    }
    h.0
}

/// The cache file of a scene and options under `dir`.
pub fn cache_path(dir: &Path, scene: &Scene, opts: &PrtOptions) -> PathBuf {
    dir.join(format!(
        "{}-{:016x}.prt",
        scene.name,
        cache_key(scene, opts)
    ))
}

fn encode(t: &Transfer) -> Vec<u8> {
    let mut b = Vec::with_capacity(32 + t.bytes());
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&t.order.to_le_bytes());
    b.extend_from_slice(&(t.vertices as u64).to_le_bytes());
    b.extend_from_slice(&(!t.bounce.is_empty() as u32).to_le_bytes());
    for v in t.direct.iter().chain(&t.bounce) {
        for x in v.to_array() {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    b
}

fn decode(b: &[u8], order: u32, vertices: usize, bounce: bool) -> Option<Transfer> {
    let head = 8 + 4 + 8 + 4;
    if b.len() < head || &b[..8] != MAGIC {
        return None;
    }
    let rd32 = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let file_order = rd32(8);
    let file_vertices = u64::from_le_bytes(b[12..20].try_into().unwrap()) as usize;
    let file_bounce = rd32(20) != 0;
    if file_order < order
        || file_order > sh::MAX_ORDER
        || file_vertices != vertices
        || file_bounce != bounce
    {
        return None;
    }
    let n = sh::sh_count(file_order) * vertices;
    let arrays = if bounce { 2 } else { 1 };
    if b.len() != head + arrays * n * 12 {
        return None;
    }
    let floats: Vec<f32> = b[head..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    if floats.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let vecs: Vec<Vec3> = floats
        .chunks_exact(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    let (direct, rest) = vecs.split_at(n);
    // Keep the first order² coefficients of each vertex.
    let (stored, kept) = (sh::sh_count(file_order), sh::sh_count(order));
    let truncate = |v: &[Vec3]| -> Vec<Vec3> {
        v.chunks(stored)
            .flat_map(|c| c[..kept].iter().copied())
            .collect()
    };
    Some(Transfer {
        order,
        vertices,
        direct: truncate(direct),
        bounce: truncate(rest),
    })
}

/// The transfer from the cache under `cache_dir` when a valid file for this scene and these
/// options exists at this order or a higher one (truncated), otherwise computed (with
/// `progress`) and written there atomically.
/// A cache that cannot be read or written is never an error: the transfer is computed.
/// `None` when cancelled.
pub fn load_or_compute(
    scene: &Scene,
    accel: &Accel,
    opts: &PrtOptions,
    cache_dir: Option<&Path>,
    progress: &Progress,
) -> Option<(Transfer, CacheStatus)> {
    let path = cache_dir.map(|d| cache_path(d, scene, opts));
    load_or_compute_at(scene, accel, opts, path, progress)
}

/// [`load_or_compute`] with the cache file already named (`cache_path`; `None`: no cache).
pub fn load_or_compute_at(
    scene: &Scene,
    accel: &Accel,
    opts: &PrtOptions,
    path: Option<PathBuf>,
    progress: &Progress,
) -> Option<(Transfer, CacheStatus)> {
    let bounce = opts.effective_bounces() > 0;
    if let Some(p) = &path
        && let Ok(bytes) = std::fs::read(p)
        && let Some(t) = decode(&bytes, opts.order, scene.mesh.positions.len(), bounce)
    {
        return Some((t, CacheStatus::Hit(p.clone())));
    }
    let t = precompute(scene, accel, opts, progress)?;
    let status = match path {
        None => CacheStatus::Uncached(None),
        Some(p) => {
            let written = p
                .parent()
                .map_or(Ok(()), std::fs::create_dir_all)
                .and_then(|_| crate::fsutil::write_bytes_atomic(&p, &encode(&t)));
            match written {
                Ok(()) => CacheStatus::Stored(p),
                Err(e) => CacheStatus::Uncached(Some(format!("cannot write {}: {e}", p.display()))),
            }
        }
    };
    Some((t, status))
}

#[cfg(test)]
mod tests;
