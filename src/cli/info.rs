//! `interreflect info`.

use interreflect::scene::{Light, Scene};
use std::fmt::Write as _;
use std::path::Path;

pub fn run(path: &Path) -> anyhow::Result<i32> {
    let scene = Scene::load(path)?;
    let mut out = String::new();
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let c = &scene.camera;
    outln!(out, "scene {} ({})", scene.name, scene.path.display());
    outln!(
        out,
        "camera: position {:?}, forward {:?}, vertical fov {:.1}°, {}x{}",
        c.position.to_array(),
        c.forward.to_array(),
        c.fov_y.to_degrees(),
        c.width,
        c.height
    );
    outln!(
        out,
        "objects ({} triangles in all):",
        scene.mesh.indices.len()
    );
    for o in &scene.objects {
        let tris = &scene.mesh.indices[o.first_tri as usize..(o.first_tri + o.tri_count) as usize];
        let mut lo = glam::Vec3::splat(f32::INFINITY);
        let mut hi = glam::Vec3::splat(f32::NEG_INFINITY);
        let mut area = 0.0f64;
        for (k, t) in tris.iter().enumerate() {
            for &i in t {
                lo = lo.min(scene.mesh.positions[i as usize]);
                hi = hi.max(scene.mesh.positions[i as usize]);
            }
            area += 0.5 * scene.mesh.tri_cross(o.first_tri + k as u32).length() as f64;
        }
        outln!(
            out,
            "  {:<12} {:>9} triangles  area {:>9.4}  bounds {:?} .. {:?}  material {}  {}{}  [{}]",
            o.name,
            o.tri_count,
            area,
            lo.to_array(),
            hi.to_array(),
            scene.materials[o.material as usize].name,
            if o.reflector { "reflector " } else { "" },
            if o.receiver { "receiver" } else { "" },
            o.source
        );
    }
    let (lo, hi) = scene.mesh.bounds();
    outln!(
        out,
        "scene bounds: {:?} .. {:?}",
        lo.to_array(),
        hi.to_array()
    );
    outln!(out, "lights:");
    for (i, l) in scene.lights.iter().enumerate() {
        match l {
            Light::Point {
                position,
                intensity,
            } => outln!(
                out,
                "  [{i}] point at {:?}, intensity {:?} W/sr",
                position.to_array(),
                intensity.to_array()
            ),
            Light::Spot {
                position,
                direction,
                intensity,
                cos_cone,
                cos_falloff,
            } => outln!(
                out,
                "  [{i}] spot at {:?} towards {:?}, intensity {:?} W/sr, cone {:.1}°, falloff from {:.1}°",
                position.to_array(),
                direction.to_array(),
                intensity.to_array(),
                cos_cone.acos().to_degrees(),
                cos_falloff.acos().to_degrees()
            ),
            Light::Directional {
                direction,
                irradiance,
            } => outln!(
                out,
                "  [{i}] directional along {:?}, irradiance {:?} W/m²",
                direction.to_array(),
                irradiance.to_array()
            ),
        }
    }
    if let Some(e) = &scene.environment {
        outln!(
            out,
            "environment: {}x{} lat-long map ({}), rotation {}° about +y, ∫ luminance dω = {:.4} (intensity applied)",
            e.width(),
            e.height(),
            e.path()
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            e.rotation_deg(),
            e.integrated_luminance()
        );
    }
    outln!(out, "materials:");
    for m in &scene.materials {
        outln!(out, "  {:<12} {:?}", m.name, m.brdf);
    }
    outln!(
        out,
        "render defaults: spp {}, seed {}; reference: {} BRDF sample(s), {} reflector sample(s) and {} light path(s) per camera sample",
        scene.settings.spp,
        scene.settings.seed,
        scene.settings.reference.bsdf_samples,
        scene.settings.reference.reflector_samples,
        scene.settings.reference.light_paths
    );
    super::print_stdout(&out);
    Ok(0)
}
