//! Exact analytic BRDF models: evaluation, importance sampling and pdf.
//!
//! All directions are in the local shading frame (z = normal), unit length, pointing away from
//! the surface; `wo` towards the viewer, `wi` towards the light.

use glam::Vec3;

/// Microfacet normal distribution of the Cook-Torrance model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distribution {
    Beckmann,
    Ggx,
}

/// A reflection-only BRDF. `diffuse` and `specular` are linear RGB albedos/reflectances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Brdf {
    Lambert {
        diffuse: Vec3,
    },
    Phong {
        diffuse: Vec3,
        specular: Vec3,
        exponent: f32,
    },
    BlinnPhong {
        diffuse: Vec3,
        specular: Vec3,
        exponent: f32,
    },
    Ward {
        diffuse: Vec3,
        specular: Vec3,
        roughness: f32,
    },
    CookTorrance {
        diffuse: Vec3,
        specular: Vec3,
        roughness: f32,
        distribution: Distribution,
    },
}

impl Brdf {
    /// Checks parameters; the error names the offending parameter and the valid range.
    pub fn validate(&self) -> Result<(), String> {
        todo!("brdf helper")
    }
    /// f(wo, wi) in 1/sr, without the cosine; zero when either direction is below the horizon.
    pub fn eval(&self, _wo: Vec3, _wi: Vec3) -> Vec3 {
        todo!("brdf helper")
    }
    /// Samples wi given wo and three uniform numbers; `None` when the sample is invalid.
    pub fn sample(&self, _wo: Vec3, _u: [f32; 3]) -> Option<Vec3> {
        todo!("brdf helper")
    }
    /// Solid-angle pdf of `sample` producing wi.
    pub fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        todo!("brdf helper")
    }
    /// True for a purely Lambertian BRDF.
    pub fn is_diffuse(&self) -> bool {
        matches!(self, Brdf::Lambert { .. })
    }
}
