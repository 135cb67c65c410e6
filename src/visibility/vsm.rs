//! Variance shadow maps (Donnelly & Lauritzen 2006): the light's visibility at a point as the
//! one-sided Chebyshev bound of the depths a filtered shadow-map texel holds.
//!
//! A map stores, per texel, the first two moments (E[z], E[z²]) of the depth z of the nearest
//! surface seen from the light, blurred by a separable Gaussian. At a point at depth t,
//!
//! p_max(t) = 1 if t ≤ μ, else σ² / (σ² + (t − μ)²), with μ = E[z], σ² = E[z²] − μ²,
//!
//! which bounds from above the fraction of the texel footprint's depths that are ≥ t (Cantelli's
//! inequality): the lit fraction. Light bleeding — a too-high bound where two occluders overlap —
//! is reduced by rescaling p_max from [b, 1] to [0, 1] (`light_bleeding` = b; 0 keeps the bound
//! conservative).
//!
//! Projections: a cube of 6 perspective faces for point lights, one perspective frustum for
//! spot lights (a cube when the cone is wider than 120°), an orthographic box around the scene
//! for directional lights. Depth is the distance to the light (point, spot) or along the
//! light's direction (directional). On the CPU the map is made by casting one ray per texel
//! through the BVH (the GPU pipeline rasterises it, every projection: `render::gpu::vsm`); a
//! texel that sees nothing holds a far depth.

use crate::accel::Accel;
use crate::scene::Light;
pub use crate::settings::VsmOptions;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// One perspective or orthographic face: texel (i, j) looks along forward + right·u + up·v
/// (perspective) or from origin + right·u + up·v along forward (orthographic), u, v ∈ [−1, 1].
#[derive(Clone, Copy, Debug)]
struct Face {
    forward: Vec3,
    right: Vec3,
    up: Vec3,
}

#[derive(Clone, Copy, Debug)]
enum Projection {
    /// Point light (or a very wide spot): six 90° faces around `position`.
    Cube { position: Vec3 },
    /// Spot light: one face of half-angle atan(`tan_half`).
    Perspective { position: Vec3, tan_half: f32 },
    /// Directional light: a box of half-extent `half` across the light, starting at `origin`.
    Ortho { origin: Vec3, half: f32 },
}

/// A shadow map as the GPU reads it: projection 0 cube, 1 perspective (`scale` = tan of the
/// half-angle), 2 orthographic (`scale` = half-extent), each face's (forward, right, up), the
/// moments face after face.
pub(crate) struct ShadowMapParts<'a> {
    pub projection: u32,
    pub origin: Vec3,
    pub scale: f32,
    pub faces: Vec<[Vec3; 3]>,
    pub res: u32,
    pub moments: &'a [Vec2],
    pub bleeding: f32,
    pub min_variance: f32,
    pub margin: f32,
}

/// A variance shadow map of one light.
pub struct VarianceShadowMap {
    projection: Projection,
    faces: Vec<Face>,
    res: u32,
    /// (E[z], E[z²]) per texel, face after face, rows of `res`.
    moments: Vec<Vec2>,
    bleeding: f32,
    /// Floor of σ², against the rounding of E[z²] − μ² on lit surfaces.
    min_variance: f32,
    /// Face coordinates the texels span ([`margin_scale`]).
    margin: f32,
    /// Depth of texels that see nothing.
    far: f32,
}

/// A shadow-map rasteriser for [`VarianceShadowMap::build_with`]: the faces' moments of a
/// setup, blurred with the given radius, or `None` to fall back to casting rays.
pub type MapRaster<'a> = dyn Fn(&MapSetup, u32) -> Option<Vec<Vec2>> + 'a;

/// What a GPU needs to rasterise the same map as [`VarianceShadowMap::build`]: the projection,
/// each face's (forward, right, up), the face coordinates the texels span, the depth of empty
/// texels and the resolution. With u, v = ((2 (i, j) + 1)/res − 1) · `margin`, texel (i, j) of
/// a face sees, in perspective, along forward + (right·u + up·v) · `scale` from `position`
/// (a point light's cube: `scale` 1; a spot's one face: tan of its half-angle), depth the
/// distance to `position`; orthographically, along forward from position + (right·u + up·v) ·
/// `scale` (the box's half-extent), depth the distance along forward.
#[derive(Clone, Debug, PartialEq)]
pub struct MapSetup {
    pub orthographic: bool,
    pub position: Vec3,
    pub scale: f32,
    pub faces: Vec<(Vec3, Vec3, Vec3)>,
    pub margin: f32,
    pub far: f32,
    pub resolution: u32,
}

/// The one-sided Chebyshev (Cantelli) bound of the fraction of depths ≥ `t`, from their moments
/// (E[z], E[z²]); `min_variance` floors σ². Never below the true fraction when the moments are
/// exact (property test).
pub fn chebyshev_upper_bound(moments: Vec2, t: f32, min_variance: f32) -> f32 {
    let mu = moments.x;
    if !(t > mu) {
        return 1.0;
    }
    let var = (moments.y - mu * mu).max(min_variance);
    let d = t - mu;
    var / (var + d * d)
}

/// The σ² floor of a map whose depths reach `far`: (2·10⁻⁴ far)², above the f32 rounding of
/// E[z²] − μ² (about 10⁻⁷ far² after blurring) and far below the depth range of a texel on any
/// visible slope.
pub fn min_variance(far: f32) -> f32 {
    (2e-4 * far).powi(2)
}

/// Light-bleeding reduction: p rescaled from [b, 1] to [0, 1].
pub fn reduce_bleeding(p: f32, b: f32) -> f32 {
    if !(b > 0.0) {
        return p;
    }
    ((p - b) / (1.0 - b)).clamp(0.0, 1.0)
}

const CUBE: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Z, Vec3::Y),
    (Vec3::NEG_X, Vec3::Z, Vec3::Y),
    (Vec3::Y, Vec3::X, Vec3::NEG_Z),
    (Vec3::NEG_Y, Vec3::X, Vec3::Z),
    (Vec3::Z, Vec3::X, Vec3::Y),
    (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
];

fn basis(forward: Vec3) -> Face {
    let f = forward.normalize();
    let helper = if f.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
    let right = f.cross(helper).normalize();
    let up = right.cross(f);
    Face {
        forward: f,
        right,
        up,
    }
}

impl VarianceShadowMap {
    /// Renders the map of `light` over the scene in `accel` (bounding box `bounds`).
    pub fn build(accel: &Accel, bounds: (Vec3, Vec3), light: &Light, opts: &VsmOptions) -> Self {
        Self::build_with(accel, bounds, light, opts, None)
    }

    /// [`Self::build`], with the map rasterised by `raster` when given: it returns the faces'
    /// moments, already blurred with `opts.blur` (`render::gpu::vsm`), or `None` to fall back
    /// to casting rays.
    pub fn build_with(
        accel: &Accel,
        bounds: (Vec3, Vec3),
        light: &Light,
        opts: &VsmOptions,
        raster: Option<&MapRaster<'_>>,
    ) -> Self {
        let (lo, hi) = bounds;
        let centre = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(1e-3);
        let res = opts.resolution.max(1);
        let (projection, faces) = match *light {
            Light::Point { position, .. } => (Projection::Cube { position }, cube_faces()),
            Light::Spot {
                position,
                direction,
                cos_cone,
                ..
            } => {
                let half = cos_cone.clamp(-1.0, 1.0).acos();
                if half < 60f32.to_radians() {
                    let tan_half = half.tan();
                    (
                        Projection::Perspective { position, tan_half },
                        vec![basis(direction)],
                    )
                } else {
                    (Projection::Cube { position }, cube_faces())
                }
            }
            Light::Directional { direction, .. } => {
                let f = basis(direction);
                let origin = centre - f.forward * (2.0 * radius);
                (
                    Projection::Ortho {
                        origin,
                        half: radius,
                    },
                    vec![f],
                )
            }
        };
        let far = match projection {
            Projection::Cube { position } | Projection::Perspective { position, .. } => {
                (position - centre).length() + 2.0 * radius
            }
            Projection::Ortho { .. } => 5.0 * radius,
        };
        let n = res as usize;
        let mut map = VarianceShadowMap {
            projection,
            faces,
            res,
            moments: Vec::new(),
            bleeding: opts.light_bleeding,
            min_variance: min_variance(far),
            margin: margin_scale(res, opts.blur),
            far,
        };
        let rasterised = raster
            .and_then(|raster| raster(&map.setup(), opts.blur))
            .filter(|m| m.len() == map.faces.len() * n * n);
        map.moments = match rasterised {
            Some(m) => m,
            None => map.ray_cast(accel, opts.blur),
        };
        map
    }

    /// The moments by a ray per texel centre through the BVH, blurred with `blur` texels.
    fn ray_cast(&self, accel: &Accel, blur: u32) -> Vec<Vec2> {
        let (res, margin, far, projection) = (self.res, self.margin, self.far, self.projection);
        let n = res as usize;
        let mut moments: Vec<Vec2> = (0..self.faces.len() * n * n)
            .into_par_iter()
            .map(|k| {
                let face = &self.faces[k / (n * n)];
                let (j, i) = ((k % (n * n)) / n, k % n);
                let u = (2.0 * (i as f32 + 0.5) / res as f32 - 1.0) * margin;
                let v = (2.0 * (j as f32 + 0.5) / res as f32 - 1.0) * margin;
                let z = match projection {
                    Projection::Cube { position } => {
                        let d = (face.forward + face.right * u + face.up * v).normalize();
                        accel.intersect(position, d, 0.0, far).map(|h| h.t)
                    }
                    Projection::Perspective { position, tan_half } => {
                        let d =
                            (face.forward + (face.right * u + face.up * v) * tan_half).normalize();
                        accel.intersect(position, d, 0.0, far).map(|h| h.t)
                    }
                    Projection::Ortho { origin, half } => {
                        let o = origin + (face.right * u + face.up * v) * half;
                        accel.intersect(o, face.forward, 0.0, far).map(|h| h.t)
                    }
                };
                let z = z.unwrap_or(far);
                Vec2::new(z, z * z)
            })
            .collect();
        if blur > 0 {
            for face in moments.chunks_mut(n * n) {
                self::blur(face, n, blur);
            }
        }
        moments
    }

    /// (E[z], E[z²]) per texel, face after face, rows of [`Self::resolution`] texels from
    /// v = −1 up.
    pub fn moments(&self) -> &[Vec2] {
        &self.moments
    }

    pub fn resolution(&self) -> u32 {
        self.res
    }

    /// The map's geometry, for a rasteriser.
    pub fn setup(&self) -> MapSetup {
        let (orthographic, position, scale) = match self.projection {
            Projection::Cube { position } => (false, position, 1.0),
            Projection::Perspective { position, tan_half } => (false, position, tan_half),
            Projection::Ortho { origin, half } => (true, origin, half),
        };
        MapSetup {
            orthographic,
            position,
            scale,
            faces: self
                .faces
                .iter()
                .map(|f| (f.forward, f.right, f.up))
                .collect(),
            margin: self.margin,
            far: self.far,
            resolution: self.res,
        }
    }

    /// What the GPU reads (`render::gpu::direct`).
    pub(crate) fn parts(&self) -> ShadowMapParts<'_> {
        let (projection, origin, scale) = match self.projection {
            Projection::Cube { position } => (0, position, 0.0),
            Projection::Perspective { position, tan_half } => (1, position, tan_half),
            Projection::Ortho { origin, half } => (2, origin, half),
        };
        ShadowMapParts {
            projection,
            origin,
            scale,
            faces: self
                .faces
                .iter()
                .map(|f| [f.forward, f.right, f.up])
                .collect(),
            res: self.res,
            moments: &self.moments,
            bleeding: self.bleeding,
            min_variance: self.min_variance,
            margin: self.margin,
        }
    }

    /// The lit fraction at `p` in [0, 1] (1 outside the map, where the light's own falloff
    /// decides).
    pub fn lit(&self, p: Vec3) -> f32 {
        let Some((face, u, v, t)) = self.project(p) else {
            return 1.0;
        };
        let m = self.bilinear(face, u, v);
        reduce_bleeding(
            chebyshev_upper_bound(m, t, self.min_variance),
            self.bleeding,
        )
    }

    /// Face, face coordinates u, v ∈ [−1, 1] and depth of `p`.
    fn project(&self, p: Vec3) -> Option<(usize, f32, f32, f32)> {
        match self.projection {
            Projection::Cube { position } => {
                let d = p - position;
                let a = d.abs();
                let face = if a.x >= a.y && a.x >= a.z {
                    if d.x > 0.0 { 0 } else { 1 }
                } else if a.y >= a.z {
                    if d.y > 0.0 { 2 } else { 3 }
                } else if d.z > 0.0 {
                    4
                } else {
                    5
                };
                let f = &self.faces[face];
                let w = d.dot(f.forward);
                if !(w > 0.0) {
                    return None;
                }
                Some((face, d.dot(f.right) / w, d.dot(f.up) / w, d.length()))
            }
            Projection::Perspective { position, tan_half } => {
                let d = p - position;
                let f = &self.faces[0];
                let w = d.dot(f.forward);
                if !(w > 0.0) {
                    return None;
                }
                let (u, v) = (
                    d.dot(f.right) / (w * tan_half),
                    d.dot(f.up) / (w * tan_half),
                );
                (u.abs() <= 1.0 && v.abs() <= 1.0).then(|| (0, u, v, d.length()))
            }
            Projection::Ortho { origin, half } => {
                let d = p - origin;
                let f = &self.faces[0];
                let (u, v) = (d.dot(f.right) / half, d.dot(f.up) / half);
                (u.abs() <= 1.0 && v.abs() <= 1.0).then(|| (0, u, v, d.dot(f.forward)))
            }
        }
    }

    /// Bilinear interpolation of the moments at face coordinates (u, v) ∈ [−1, 1]², which the
    /// face's texels cover with a margin (`margin_scale`), so that lookups never clamp.
    fn bilinear(&self, face: usize, u: f32, v: f32) -> Vec2 {
        let n = self.res as usize;
        let s = self.margin;
        bilinear_moments(
            &self.moments[face * n * n..(face + 1) * n * n],
            n,
            u / s,
            v / s,
        )
    }
}

/// Bilinear interpolation of an n × n map of moments whose texels cover [−1, 1]² (texel
/// centres at (2i + 1)/n − 1), at (u, v), clamped to the outermost texel centres.
pub(crate) fn bilinear_moments(m: &[Vec2], n: usize, u: f32, v: f32) -> Vec2 {
    let max = (n - 1) as f32;
    let x = ((u + 1.0) * 0.5 * n as f32 - 0.5).clamp(0.0, max);
    let y = ((v + 1.0) * 0.5 * n as f32 - 0.5).clamp(0.0, max);
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(n - 1), (y0 + 1).min(n - 1));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let row = |y: usize| m[y * n + x0] * (1.0 - fx) + m[y * n + x1] * fx;
    row(y0) * (1.0 - fy) + row(y1) * fy
}

/// The faces' texels span [−s, s]² of face coordinates, s = 1 + 2(blur + 2)/res: blur + 2
/// texels of margin beyond each edge, so that bilinear lookups near a face's edge read depths of
/// the right surfaces, blurred over whole footprints, rather than clamped ones.
fn margin_scale(res: u32, blur: u32) -> f32 {
    1.0 + 2.0 * (blur + 2) as f32 / res as f32
}

fn cube_faces() -> Vec<Face> {
    CUBE.iter()
        .map(|&(forward, right, up)| Face { forward, right, up })
        .collect()
}

/// Separable Gaussian blur (σ = radius / 2) of an n × n face, clamped at the edges.
fn blur(face: &mut [Vec2], n: usize, radius: u32) {
    let r = radius as i64;
    let sigma = radius as f32 * 0.5;
    let w: Vec<f32> = (-r..=r)
        .map(|k| (-(k * k) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let total: f32 = w.iter().sum();
    let w: Vec<f32> = w.iter().map(|x| x / total).collect();
    let mut tmp = vec![Vec2::ZERO; n * n];
    let at = |i: i64| i.clamp(0, n as i64 - 1) as usize;
    for y in 0..n {
        for x in 0..n {
            tmp[y * n + x] = (-r..=r)
                .map(|k| face[y * n + at(x as i64 + k)] * w[(k + r) as usize])
                .sum();
        }
    }
    for y in 0..n {
        for x in 0..n {
            face[y * n + x] = (-r..=r)
                .map(|k| tmp[at(y as i64 + k) * n + x] * w[(k + r) as usize])
                .sum();
        }
    }
}

#[cfg(test)]
mod tests;
