//! Parameter validation: the ranges for which every model is energy conserving and robust.

use super::Brdf;
use glam::Vec3;

/// Smallest accepted roughness α: the lower end of the range the energy, χ² and robustness tests
/// cover. Narrower lobes (NDF peak above 3e5 / sr, width below 1e-3 rad) approach the angular
/// resolution of f32 directions near grazing and are better modelled as a mirror.
pub const MIN_ROUGHNESS: f32 = 1e-3;
/// Largest accepted roughness α (α = 1 is already a very rough surface; the energy tests
/// cover [MIN_ROUGHNESS, 1]).
pub const MAX_ROUGHNESS: f32 = 1.0;
/// Largest accepted Phong / Blinn-Phong exponent.
pub const MAX_EXPONENT: f32 = 1e6;
/// Slack on diffuse + specular ≤ 1 for decimal inputs such as 0.7 + 0.3 that round above 1 in
/// f32. It allows at most 1e-6 of extra energy, far below any test or render tolerance.
pub const SUM_SLACK: f64 = 1e-6;

const CHANNELS: [&str; 3] = ["r", "g", "b"];

fn model_name(b: &Brdf) -> &'static str {
    match b {
        Brdf::Lambert { .. } => "Lambert",
        Brdf::Phong { .. } => "Phong",
        Brdf::BlinnPhong { .. } => "BlinnPhong",
        Brdf::Ward { .. } => "Ward",
        Brdf::CookTorrance { .. } => "CookTorrance",
    }
}

fn check_colour(model: &str, name: &str, c: Vec3) -> Result<(), String> {
    for (i, ch) in CHANNELS.iter().enumerate() {
        let v = c[i];
        if !v.is_finite() || !(0.0..=1.0).contains(&v) {
            return Err(format!(
                "{model}: {name}.{ch} = {v} is invalid; each channel must be finite and in [0, 1]"
            ));
        }
    }
    Ok(())
}

fn check_sum(model: &str, kd: Vec3, ks: Vec3) -> Result<(), String> {
    for (i, ch) in CHANNELS.iter().enumerate() {
        let s = kd[i] as f64 + ks[i] as f64;
        if s > 1.0 + SUM_SLACK {
            return Err(format!(
                "{model}: diffuse + specular exceeds 1 in channel {ch} ({} + {} = {s}); \
                 it must be ≤ 1 so the model cannot create energy",
                kd[i], ks[i]
            ));
        }
    }
    Ok(())
}

fn check_exponent(model: &str, n: f32) -> Result<(), String> {
    if !n.is_finite() || !(0.0..=MAX_EXPONENT).contains(&n) {
        return Err(format!(
            "{model}: exponent = {n} is invalid; it must be finite and in [0, 1e6]"
        ));
    }
    Ok(())
}

fn check_roughness(model: &str, a: f32) -> Result<(), String> {
    if !a.is_finite() || !(MIN_ROUGHNESS..=MAX_ROUGHNESS).contains(&a) {
        return Err(format!(
            "{model}: roughness = {a} is invalid; it must be finite and in [0.001, 1] (alpha)"
        ));
    }
    Ok(())
}

/// See [`Brdf::validate`].
pub fn validate(b: &Brdf) -> Result<(), String> {
    let m = model_name(b);
    match *b {
        Brdf::Lambert { diffuse } => check_colour(m, "diffuse", diffuse),
        Brdf::Phong {
            diffuse,
            specular,
            exponent,
        }
        | Brdf::BlinnPhong {
            diffuse,
            specular,
            exponent,
        } => {
            check_colour(m, "diffuse", diffuse)?;
            check_colour(m, "specular", specular)?;
            check_sum(m, diffuse, specular)?;
            check_exponent(m, exponent)
        }
        Brdf::Ward {
            diffuse,
            specular,
            roughness,
        }
        | Brdf::CookTorrance {
            diffuse,
            specular,
            roughness,
            ..
        } => {
            check_colour(m, "diffuse", diffuse)?;
            check_colour(m, "specular", specular)?;
            check_sum(m, diffuse, specular)?;
            check_roughness(m, roughness)
        }
    }
}
