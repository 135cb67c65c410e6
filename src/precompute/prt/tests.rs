use super::*;
use crate::render::cpu::reference::no_progress;
use crate::scene::environment::Environment;
use std::sync::atomic::AtomicBool;

fn quiet<T>(f: impl FnOnce(&Progress) -> T) -> T {
    let cancel = AtomicBool::new(false);
    f(&Progress {
        done: &no_progress,
        cancel: &cancel,
    })
}

fn load(text: &str) -> Scene {
    Scene::from_str_at(text, Path::new("inline.toml")).expect("valid test scene")
}

const CAMERA: &str = r#"
[camera]
position = [0.0, 4.0, 0.1]
look_at = [0.0, 0.0, 0.0]
fov_y = 50.0
width = 32
height = 32
"#;

fn plane_scene() -> Scene {
    load(&format!(
        r#"{CAMERA}
[materials.white]
model = "lambert"
diffuse = [0.6, 0.5, 0.4]
[[objects]]
material = "white"
shape = {{ type = "plane", size = [2.0, 2.0], subdivisions = 4 }}
"#
    ))
}

/// A floor with a lid floating above its middle: the lid shadows the floor and reflects light
/// back onto it.
fn lid_scene() -> Scene {
    load(&format!(
        r#"{CAMERA}
[materials.floor]
model = "lambert"
diffuse = [0.5, 0.5, 0.5]
[materials.lid]
model = "lambert"
diffuse = [0.9, 0.3, 0.2]
[[objects]]
name = "floor"
material = "floor"
shape = {{ type = "plane", size = [4.0, 4.0], subdivisions = 16 }}
[[objects]]
name = "lid"
material = "lid"
shape = {{ type = "box", size = [1.5, 0.1, 1.5] }}
transform = {{ translate = [0.0, 0.6, 0.0] }}
"#
    ))
}

fn opts(kind: TransferKind, order: u32, bounces: u32) -> PrtOptions {
    PrtOptions {
        order,
        kind,
        bounces,
        samples: 1024,
        seed: 3,
    }
}

fn transfer(scene: &Scene, o: &PrtOptions) -> Transfer {
    let accel = Accel::build(&scene.mesh.positions, &scene.mesh.indices);
    quiet(|p| precompute(scene, &accel, o, p)).expect("not cancelled")
}

/// SH coefficients of a constant radiance `l`: only y₀₀ = 1/√(4π), so c₀ = l·√(4π).
fn constant_lighting(order: u32, l: Vec3) -> Vec<Vec3> {
    let mut c = vec![Vec3::ZERO; sh::sh_count(order)];
    c[0] = l * (4.0 * std::f32::consts::PI).sqrt();
    c
}

#[test]
fn unshadowed_transfer_under_constant_light_is_albedo_times_radiance() {
    let scene = plane_scene();
    let t = transfer(&scene, &opts(TransferKind::Unshadowed, 4, 0));
    let l = Vec3::new(1.0, 2.0, 3.0);
    let rad = relight_cpu(&t.direct, t.coefficients(), &constant_lighting(4, l));
    let expect = Vec3::new(0.6, 0.5, 0.4) * l;
    // Closed-form transfer and lighting: only float rounding separates them.
    for r in &rad {
        assert!(
            (*r - expect).abs().max_element() < 1e-5 * expect.max_element(),
            "{r} vs {expect}"
        );
    }
}

#[test]
fn constant_environment_map_relights_to_albedo_times_radiance() {
    let mut scene = plane_scene();
    let l = Vec3::new(0.5, 1.0, 2.0);
    let img = crate::image::Image::from_fn(64, 32, |_, _| l);
    scene.environment = Some(Environment::from_image(img, 0.0, 1.0).expect("valid map"));
    let t = transfer(&scene, &opts(TransferKind::Unshadowed, 6, 0));
    let (lighting, warnings) = sh_lighting(&scene, 6, sh::Window::None);
    assert!(warnings.is_empty(), "{warnings:?}");
    let rad = relight_cpu(&t.direct, t.coefficients(), &lighting);
    let expect = Vec3::new(0.6, 0.5, 0.4) * l;
    // The projection sums texel-centre values times exact texel solid angles: exact for the
    // constant band, a midpoint rule for the zonal bands l ≥ 1, whose residue on 32 rows is
    // below 1e-3 of the constant.
    for r in &rad {
        assert!(
            (*r - expect).abs().max_element() < 2e-3 * expect.max_element(),
            "{r} vs {expect}"
        );
    }
}

#[test]
fn shadowed_transfer_without_occluders_matches_the_closed_form() {
    let scene = plane_scene();
    let o = opts(TransferKind::Shadowed, 3, 0);
    let shadowed = transfer(&scene, &o);
    let closed = transfer(&scene, &opts(TransferKind::Unshadowed, 3, 0));
    let n = shadowed.coefficients();
    let y00 = 0.5 / std::f32::consts::PI.sqrt();
    for (v, (s, c)) in shadowed
        .direct
        .chunks(n)
        .zip(closed.direct.chunks(n))
        .enumerate()
    {
        // Coefficient 0 integrates a constant over rays that are all unoccluded: exact.
        assert!(
            (s[0] - c[0]).abs().max_element() < 1e-5,
            "vertex {v}: {} vs {}",
            s[0],
            c[0]
        );
        // Bands 1 and 2 by 32×32 jittered cosine-distributed rays: the stratified estimate's
        // error is well under 1 % of the constant coefficient ρ·y₀₀.
        for i in 1..n {
            assert!(
                (s[i] - c[i]).abs().max_element() < 0.01 * 0.6 * y00,
                "vertex {v}, coefficient {i}: {} vs {}",
                s[i],
                c[i]
            );
        }
    }
}

#[test]
fn the_lid_shadows_and_lights_the_floor_below_it() {
    let scene = lid_scene();
    let t = transfer(&scene, &opts(TransferKind::Interreflected, 3, 1));
    let n = t.coefficients();
    let l = constant_lighting(3, Vec3::ONE);
    let direct = relight_cpu(&t.direct, n, &l);
    let bounce = relight_cpu(&t.bounce, n, &l);
    let floor = &scene.objects[0];
    let tris = floor.first_tri as usize..(floor.first_tri + floor.tri_count) as usize;
    let mut floor_vertices: Vec<usize> = tris
        .flat_map(|t| scene.mesh.indices[t].map(|v| v as usize))
        .collect();
    floor_vertices.sort_unstable();
    floor_vertices.dedup();
    let dist = |v: &usize| scene.mesh.positions[*v].length();
    let by = |a: &usize, b: &usize| dist(a).partial_cmp(&dist(b)).unwrap();
    let centre = *floor_vertices.iter().min_by(|a, b| by(a, b)).unwrap();
    let corner = *floor_vertices.iter().max_by(|a, b| by(a, b)).unwrap();
    // Under constant light of radiance 1 the floor's direct radiance is ρ = 0.5 times its
    // vertex's cosine-weighted unoccluded fraction. At the centre the lid (half-width 0.75 at
    // height 0.55, X = Y = 1.36) has the form factor 4 · (1/2π)(2 · X/√(1+X²) · atan(Y/√(1+X²)))
    // = 0.70 (from below its centre the lid's sides are hidden, so its silhouette is its bottom
    // face), so the radiance is 0.5 · 0.30 = 0.15; at the far corner the lid hides almost
    // nothing.
    let x = 0.75f32 / 0.55;
    let r = (1.0 + x * x).sqrt();
    let form_factor = 4.0 / (2.0 * std::f32::consts::PI) * 2.0 * (x / r) * (x / r).atan();
    let expect = 0.5 * (1.0 - form_factor);
    // 1024 stratified rays estimate the unoccluded fraction to a few tenths of a percent; 0.01
    // is 2 % of the unshadowed radiance.
    assert!(
        (direct[centre].x - expect).abs() < 0.01,
        "centre {} vs {expect}",
        direct[centre]
    );
    assert!(direct[corner].x > 0.45, "corner {}", direct[corner]);
    // The red lid reflects red light down: the centre's bounce is red, the corner's is weak.
    assert!(
        bounce[centre].x > 2.0 * bounce[centre].z,
        "centre bounce {}",
        bounce[centre]
    );
    assert!(
        bounce[centre].x > 5.0 * bounce[corner].x,
        "{} vs {}",
        bounce[centre],
        bounce[corner]
    );
    assert!(t.bounce.iter().all(|c| c.is_finite()));
}

#[test]
fn the_cache_returns_the_same_transfer_and_rejects_other_settings() {
    let scene = lid_scene();
    let accel = Accel::build(&scene.mesh.positions, &scene.mesh.indices);
    let dir = tempfile::tempdir().unwrap();
    let o = opts(TransferKind::Interreflected, 3, 1);
    let (a, sa) = quiet(|p| load_or_compute(&scene, &accel, &o, Some(dir.path()), p)).unwrap();
    assert!(matches!(sa, CacheStatus::Stored(_)), "{sa:?}");
    let (b, sb) = quiet(|p| load_or_compute(&scene, &accel, &o, Some(dir.path()), p)).unwrap();
    assert!(matches!(sb, CacheStatus::Hit(_)), "{sb:?}");
    assert_eq!(a, b);
    // A lower order is served from the same file, truncated: the basis is nested.
    let low = PrtOptions { order: 2, ..o };
    let (d, sd) = quiet(|p| load_or_compute(&scene, &accel, &low, Some(dir.path()), p)).unwrap();
    assert!(matches!(sd, CacheStatus::Hit(_)), "{sd:?}");
    assert_eq!(d, transfer(&scene, &low));
    // Other settings, or other materials, make another key.
    let o2 = PrtOptions { samples: 256, ..o };
    assert_ne!(cache_key(&scene, &o), cache_key(&scene, &o2));
    let mut other = scene.clone();
    other.materials[1].brdf = Brdf::Lambert {
        diffuse: Vec3::splat(0.2),
    };
    assert_ne!(cache_key(&scene, &o), cache_key(&other, &o));
    // A damaged cache file is recomputed, not trusted and not an error.
    let CacheStatus::Hit(path) = sb else {
        unreachable!()
    };
    let mut bytes = std::fs::read(&path).unwrap();
    bytes.truncate(bytes.len() - 7);
    std::fs::write(&path, &bytes).unwrap();
    let (c, sc) = quiet(|p| load_or_compute(&scene, &accel, &o, Some(dir.path()), p)).unwrap();
    assert!(matches!(sc, CacheStatus::Stored(_)), "{sc:?}");
    assert_eq!(a, c);
}

#[test]
fn transfer_does_not_depend_on_the_thread_count() {
    let scene = lid_scene();
    let o = PrtOptions {
        samples: 64,
        ..opts(TransferKind::Interreflected, 4, 2)
    };
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| transfer(&scene, &o))
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn lambertian_albedo_of_a_glossy_material_keeps_its_energy() {
    let lambert = Brdf::Lambert {
        diffuse: Vec3::new(0.2, 0.4, 0.6),
    };
    assert_eq!(lambertian_albedo(&lambert), Vec3::new(0.2, 0.4, 0.6));
    // A white GGX conductor (F0 = 1) loses only what its masking-shadowing term removes: its
    // hemispherical albedo lies between 0.8 and 1 at roughness 0.3.
    let ggx = Brdf::CookTorrance {
        diffuse: Vec3::ZERO,
        specular: Vec3::ONE,
        roughness: 0.3,
        distribution: crate::brdf::Distribution::Ggx,
    };
    let a = lambertian_albedo(&ggx);
    assert!(a.x > 0.8 && a.x <= 1.0, "{a}");
}
