//! Surface interactions: hit points with their frames, two-sided orientation and the light a
//! surface point reflects.

use crate::accel::{Accel, Hit};
use crate::brdf::Brdf;
use crate::math::Frame;
use crate::scene::{Incident, Light, Scene};
use glam::Vec3;

pub use crate::scene::ray_epsilon;

/// A point on a surface, oriented towards the side it is seen from.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub p: Vec3,
    pub tri: u32,
    /// Unit geometric normal, flipped to the viewing side.
    pub ng: Vec3,
    /// Shading frame (interpolated normal, flipped with `ng`).
    pub frame: Frame,
}

impl SurfacePoint {
    /// The hit point of `hit`, oriented so that `ng · towards ≥ 0` (`towards` points away from
    /// the surface, e.g. to the viewer).
    pub fn from_hit(scene: &Scene, hit: &Hit, towards: Vec3) -> Option<SurfacePoint> {
        Self::at(scene, hit.tri, hit.u, hit.v, towards)
    }

    /// The point at barycentrics (u, v) of triangle `tri`, oriented towards `towards`.
    pub fn at(scene: &Scene, tri: u32, u: f32, v: f32, towards: Vec3) -> Option<SurfacePoint> {
        let mesh = &scene.mesh;
        let mut ng = mesh.tri_cross(tri).try_normalize()?;
        let mut ns = mesh.shading_normal(tri, u, v);
        if ng.dot(towards) < 0.0 {
            ng = -ng;
            ns = -ns;
        }
        // A shading normal that points into the surface (bad input that survived cleaning)
        // falls back to the geometric normal.
        if ns.dot(ng) <= 0.0 {
            ns = ng;
        }
        Some(SurfacePoint {
            p: mesh.point(tri, u, v),
            tri,
            ng,
            frame: Frame::from_normal(ns),
        })
    }

    /// Ray origin offset off the surface on the oriented side.
    #[inline]
    pub fn offset(&self, eps: f32) -> Vec3 {
        self.p + self.ng * eps
    }
}

/// Radiance that the light `light` reflects at `sp` towards the unit direction `w_out` (which
/// must point to the side `sp` is oriented to), with exact light visibility:
/// f(w_out, ω_l) · cos θ_l · E_l · V(l, p).
pub fn reflected_light(
    accel: &Accel,
    brdf: &Brdf,
    sp: &SurfacePoint,
    w_out: Vec3,
    light: &Light,
    eps: f32,
) -> Vec3 {
    reflected_light_with(brdf, sp, w_out, light, |inc| {
        if shadow_ray_clear(accel, sp.offset(eps), inc, eps) {
            1.0
        } else {
            0.0
        }
    })
}

/// [`reflected_light`] with the light's visibility given by `visibility` (called only when the
/// light reflects something towards `w_out`), e.g. from a shadow map.
pub fn reflected_light_with(
    brdf: &Brdf,
    sp: &SurfacePoint,
    w_out: Vec3,
    light: &Light,
    visibility: impl FnOnce(&Incident) -> f32,
) -> Vec3 {
    let Some(inc) = light.incident(sp.p) else {
        return Vec3::ZERO;
    };
    if sp.ng.dot(inc.wi) <= 0.0 || sp.ng.dot(w_out) <= 0.0 {
        return Vec3::ZERO;
    }
    let wi_l = sp.frame.to_local(inc.wi);
    let wo_l = sp.frame.to_local(w_out);
    if wi_l.z <= 0.0 || wo_l.z <= 0.0 {
        return Vec3::ZERO;
    }
    let f = brdf.eval(wo_l, wi_l);
    if f == Vec3::ZERO || inc.irradiance == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let v = visibility(&inc);
    if !(v > 0.0) {
        return Vec3::ZERO;
    }
    f * wi_l.z * inc.irradiance * v
}

/// Whether the shadow ray from `origin` (already offset off its surface) towards the light that
/// delivers `inc` reaches it: stopped `eps` (and 1e-5 relative) short of a positional light.
pub fn shadow_ray_clear(accel: &Accel, origin: Vec3, inc: &Incident, eps: f32) -> bool {
    let tmax = if inc.dist.is_finite() {
        inc.dist * (1.0 - 1e-5) - eps
    } else {
        f32::INFINITY
    };
    accel.unoccluded(origin, inc.wi, 0.0, tmax)
}

/// Whether `light` reaches the surface point `p`, offset by `eps` along the light direction (for
/// points that lie on their triangle but have no oriented frame, e.g. points of a reflector).
pub fn light_visible(accel: &Accel, light: &Light, p: Vec3, eps: f32) -> bool {
    light
        .incident(p)
        .is_some_and(|inc| shadow_ray_clear(accel, p + inc.wi * eps, &inc, eps))
}

/// The pixel samples' points for a GPU pass: `index[i]` is the point `make` built for
/// `hits[i]` (`u32::MAX` where there is no hit, no surface point, or `make` returns `None`),
/// each surface point seen from `camera`; `make(hit, sp, wo, wo_local)`.
pub(crate) fn sample_points<P: Send>(
    scene: &Scene,
    hits: &[Option<Hit>],
    camera: Vec3,
    make: impl Fn(&Hit, &SurfacePoint, Vec3, Vec3) -> Option<P> + Sync,
) -> (Vec<u32>, Vec<P>) {
    use rayon::prelude::*;
    let found: Vec<Option<P>> = hits
        .par_iter()
        .map(|h| {
            let hit = h.as_ref()?;
            let wo = (camera - scene.mesh.point(hit.tri, hit.u, hit.v)).normalize();
            let sp = SurfacePoint::from_hit(scene, hit, wo)?;
            make(hit, &sp, wo, sp.frame.to_local(wo))
        })
        .collect();
    let mut index = vec![u32::MAX; hits.len()];
    let mut points = Vec::new();
    for (i, p) in found.into_iter().enumerate() {
        if let Some(p) = p {
            index[i] = points.len() as u32;
            points.push(p);
        }
    }
    (index, points)
}

/// [`sample_points`] as the `vpl` and `direct` passes read them, where `keep(hit, sp, wo,
/// wo_local)`.
pub(crate) fn gpu_points(
    scene: &Scene,
    hits: &[Option<Hit>],
    camera: Vec3,
    keep: impl Fn(&Hit, &SurfacePoint, Vec3, Vec3) -> bool + Sync,
) -> (Vec<u32>, Vec<crate::render::gpu::layout::GpuSurfacePoint>) {
    sample_points(scene, hits, camera, |hit, sp, wo, wo_l| {
        keep(hit, sp, wo, wo_l).then(|| {
            crate::render::gpu::layout::GpuSurfacePoint::new(
                sp.p,
                sp.ng,
                &sp.frame,
                wo_l,
                scene.tri_material_index(hit.tri),
            )
        })
    })
}

/// `values` of a GPU pass's points spread back over the samples (`index` from
/// [`gpu_points`]), `T::default()` where a sample has no point.
pub(crate) fn scatter<T: Copy + Default>(index: &[u32], values: &[T]) -> Vec<T> {
    index
        .iter()
        .map(|&i| {
            if i == u32::MAX {
                T::default()
            } else {
                values[i as usize]
            }
        })
        .collect()
}
