//! Point, spot and directional lights (all delta lights).

use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// `intensity` in W/sr.
    Point { position: Vec3, intensity: Vec3 },
    /// `intensity` in W/sr on the axis; full inside `cos_falloff`, smoothstep to 0 at `cos_cone`.
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        cos_cone: f32,
        cos_falloff: f32,
    },
    /// Light travelling along `direction`; `irradiance` in W/m² on a surface facing it.
    Directional { direction: Vec3, irradiance: Vec3 },
}

/// What a light delivers at a point.
#[derive(Clone, Copy, Debug)]
pub struct Incident {
    /// Unit direction from the point towards the light.
    pub wi: Vec3,
    /// Distance to the light (infinite for directional lights).
    pub dist: f32,
    /// Irradiance on a surface facing the light (W/m²): I/d² or E.
    pub irradiance: Vec3,
}

impl Light {
    /// Incident light at `p` (ignoring visibility); `None` when the light cannot reach `p`.
    pub fn incident(&self, p: Vec3) -> Option<Incident> {
        match *self {
            Light::Point {
                position,
                intensity,
            } => {
                let d = position - p;
                let d2 = d.length_squared();
                if !(d2 > 0.0) {
                    return None;
                }
                let dist = d2.sqrt();
                Some(Incident {
                    wi: d / dist,
                    dist,
                    irradiance: intensity / d2,
                })
            }
            Light::Spot {
                position,
                direction,
                intensity,
                cos_cone,
                cos_falloff,
            } => {
                let d = position - p;
                let d2 = d.length_squared();
                if !(d2 > 0.0) {
                    return None;
                }
                let dist = d2.sqrt();
                let wi = d / dist;
                let f = spot_falloff((-wi).dot(direction), cos_cone, cos_falloff);
                if f <= 0.0 {
                    return None;
                }
                Some(Incident {
                    wi,
                    dist,
                    irradiance: intensity * (f / d2),
                })
            }
            Light::Directional {
                direction,
                irradiance,
            } => Some(Incident {
                wi: -direction,
                dist: f32::INFINITY,
                irradiance,
            }),
        }
    }

    /// Position of a positional light; `None` for directional lights.
    pub fn position(&self) -> Option<Vec3> {
        match *self {
            Light::Point { position, .. } | Light::Spot { position, .. } => Some(position),
            Light::Directional { .. } => None,
        }
    }

    /// Spot falloff factor in the direction `dir` (unit, from the light); 1 for other lights.
    pub fn falloff(&self, dir: Vec3) -> f32 {
        match *self {
            Light::Spot {
                direction,
                cos_cone,
                cos_falloff,
                ..
            } => spot_falloff(dir.dot(direction), cos_cone, cos_falloff),
            _ => 1.0,
        }
    }

    /// Mean of the RGB intensity (W/sr) or irradiance (W/m²): the light's weight when choosing lights.
    pub fn strength(&self) -> f32 {
        let v = match *self {
            Light::Point { intensity, .. } | Light::Spot { intensity, .. } => intensity,
            Light::Directional { irradiance, .. } => irradiance,
        };
        (v.x + v.y + v.z) / 3.0
    }
}

/// pbrt-v4's spot falloff: smoothstep from the cone edge to the start of the falloff.
pub fn spot_falloff(cos_theta: f32, cos_cone: f32, cos_falloff: f32) -> f32 {
    if cos_theta >= cos_falloff {
        return 1.0;
    }
    if cos_theta <= cos_cone {
        return 0.0;
    }
    let t = ((cos_theta - cos_cone) / (cos_falloff - cos_cone)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_light_inverse_square() {
        let l = Light::Point {
            position: Vec3::new(0.0, 2.0, 0.0),
            intensity: Vec3::splat(8.0),
        };
        let inc = l.incident(Vec3::ZERO).unwrap();
        assert_eq!(inc.wi, Vec3::Y);
        assert_eq!(inc.irradiance, Vec3::splat(2.0));
    }

    #[test]
    fn spot_falloff_edges() {
        let c30 = 30f32.to_radians().cos();
        let c20 = 20f32.to_radians().cos();
        assert_eq!(spot_falloff(1.0, c30, c20), 1.0);
        assert_eq!(spot_falloff(c30 - 1e-3, c30, c20), 0.0);
        let mid = spot_falloff(0.5 * (c30 + c20), c30, c20);
        assert!((mid - 0.5).abs() < 1e-4);
    }
}
