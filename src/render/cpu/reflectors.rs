//! Light-side sampling of reflector points: for each light, a distribution over reflector
//! triangles proportional to the flux they receive (ignoring occlusion), and uniform area
//! sampling inside the chosen triangle. Used by the reference's second strategy, where a point
//! on a reflector is connected to the receiver; its pdf is evaluated for multiple importance
//! sampling against BRDF sampling at the receiver.

use crate::math::sampling::{Distribution1D, uniform_triangle};
use crate::scene::{Light, Scene};
use glam::{DVec3, Vec2, Vec3};

/// Per-light distributions over the scene's reflector triangles.
pub struct ReflectorSampler {
    /// Choice of light, ∝ the flux its reflectors receive.
    lights: Distribution1D,
    /// Per light, choice of triangle (index into `tris`).
    per_light: Vec<Distribution1D>,
    /// Reflector triangle ids.
    tris: Vec<u32>,
    /// Position in `tris` of each scene triangle (u32::MAX: not a reflector).
    slot: Vec<u32>,
    /// Triangle areas (of `tris`).
    areas: Vec<f32>,
}

/// A sampled reflector point.
#[derive(Clone, Copy, Debug)]
pub struct ReflectorSample {
    pub light: usize,
    pub tri: u32,
    pub u: f32,
    pub v: f32,
    /// Probability of the light times the area density of the point (1/m²).
    pub pdf_area: f32,
}

impl ReflectorSampler {
    pub fn new(scene: &Scene) -> ReflectorSampler {
        let mesh = &scene.mesh;
        let mut tris = Vec::new();
        let mut slot = vec![u32::MAX; mesh.indices.len()];
        for o in scene.objects.iter().filter(|o| o.reflector) {
            for t in o.first_tri..o.first_tri + o.tri_count {
                slot[t as usize] = tris.len() as u32;
                tris.push(t);
            }
        }
        let areas: Vec<f32> = tris
            .iter()
            .map(|&t| 0.5 * mesh.tri_cross(t).length())
            .collect();
        let per_light: Vec<Distribution1D> = scene
            .lights
            .iter()
            .map(|light| {
                let flux: Vec<f32> = tris
                    .iter()
                    .zip(&areas)
                    .map(|(&t, &a)| triangle_flux(light, mesh.tri(t), a))
                    .collect();
                Distribution1D::new(&balance_objects(scene, &tris, &flux))
            })
            .collect();
        let lw: Vec<f32> = per_light.iter().map(|d| d.total() as f32).collect();
        ReflectorSampler {
            lights: Distribution1D::new(&lw),
            per_light,
            tris,
            slot,
            areas,
        }
    }

    /// True when no light reaches any reflector.
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// Draws (light, reflector triangle, point); `None` when nothing can be sampled.
    pub fn sample(&self, u_light: f32, u_tri: f32, u_point: Vec2) -> Option<ReflectorSample> {
        let light = self.lights.sample(u_light)?;
        let dist = &self.per_light[light];
        let k = dist.sample(u_tri)?;
        let b = uniform_triangle(u_point);
        let area = self.areas[k];
        if !(area > 0.0) {
            return None;
        }
        Some(ReflectorSample {
            light,
            tri: self.tris[k],
            u: b[1],
            v: b[2],
            pdf_area: self.lights.pmf(light) * dist.pmf(k) / area,
        })
    }

    /// Area density (including the light's probability) with which `sample` produces a point
    /// on triangle `tri` for light `light`; 0 for non-reflectors.
    pub fn pdf_area(&self, light: usize, tri: u32) -> f32 {
        let s = self.slot[tri as usize];
        if s == u32::MAX {
            return 0.0;
        }
        let k = s as usize;
        let area = self.areas[k];
        if !(area > 0.0) {
            return 0.0;
        }
        self.lights.pmf(light) * self.per_light[light].pmf(k) / area
    }
}

/// Triangle weights that choose a reflector object half by its share of the flux and half
/// uniformly among the lit reflector objects, then a triangle ∝ its flux within the object.
///
/// Pure flux-proportional choice starves small glossy reflectors next to large diffuse ones (the
/// ring next to its floor gets ~3 % of the samples although its caustic is what this strategy
/// exists for); diffuse reflectors are handled well by BRDF sampling at the receiver anyway. Any
/// choice keeps the estimator unbiased: MIS evaluates exactly this pdf.
fn balance_objects(scene: &Scene, tris: &[u32], flux: &[f32]) -> Vec<f32> {
    let mut per_object = vec![0.0f64; scene.objects.len()];
    for (&t, &f) in tris.iter().zip(flux) {
        per_object[scene.mesh.tri_object[t as usize] as usize] += f as f64;
    }
    let total: f64 = per_object.iter().sum();
    let lit = per_object.iter().filter(|&&w| w > 0.0).count();
    if !(total > 0.0) {
        return vec![0.0; flux.len()];
    }
    tris.iter()
        .zip(flux)
        .map(|(&t, &f)| {
            let w_obj = per_object[scene.mesh.tri_object[t as usize] as usize];
            if !(w_obj > 0.0) || !(f > 0.0) {
                return 0.0;
            }
            let p_obj = 0.5 * w_obj / total + 0.5 / lit as f64;
            (p_obj * f as f64 / w_obj) as f32
        })
        .collect()
}

/// Flux (up to a constant) that `light` sends onto the triangle (either side), ignoring occlusion:
/// intensity × solid angle subtended at the light (× spot falloff), or irradiance × projected area.
fn triangle_flux(light: &Light, v: [Vec3; 3], area: f32) -> f32 {
    let strength = light.strength();
    match light.position() {
        Some(l) => {
            let d: Vec<DVec3> = v.iter().map(|p| (*p - l).as_dvec3()).collect();
            if d.iter().any(|x| x.length() == 0.0) {
                return 0.0;
            }
            let a = d[0].normalize();
            let b = d[1].normalize();
            let c = d[2].normalize();
            let omega = spherical_triangle_area64(a, b, c);
            let centroid = ((v[0] + v[1] + v[2]) / 3.0 - l).normalize_or_zero();
            let fall = v
                .iter()
                .map(|p| light.falloff((*p - l).normalize_or_zero()))
                .fold(light.falloff(centroid), f32::max);
            let w = strength as f64 * omega * fall as f64;
            // Keep far, tiny triangles samplable whatever the f32 range.
            if w > 0.0 { w.max(1e-30) as f32 } else { 0.0 }
        }
        None => {
            let Light::Directional { direction, .. } = light else {
                return 0.0;
            };
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            strength * area * n.dot(*direction).abs()
        }
    }
}

/// Solid angle of a spherical triangle (Van Oosterom & Strackee 1983) in f64: tiny triangles far
/// from a light need the precision.
fn spherical_triangle_area64(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let num = a.dot(b.cross(c)).abs();
    let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    let o = 2.0 * num.atan2(den);
    if o.is_finite() { o.max(0.0) } else { 0.0 }
}
