//! Unit tests of the Mitsuba export: the conversions, the XML read back, the PLY files read
//! back by our own loader, and the output directory's guarantees.

use super::*;
use crate::brdf::microfacet::{beckmann_d, blinn_phong_d};
use crate::export::xml::parse;
use crate::scene::Scene;
use std::path::Path;

const SCENE: &str = r#"
name = "t"
[camera]
position = [0.5, 2.0, 4.0]
look_at = [0.0, 0.25, 0.0]
fov_y = 38.0
width = 40
height = 30

[[lights]]
type = "point"
position = [1.0, 3.0, 0.5]
intensity = [5.0, 4.0, 3.0]

[[lights]]
type = "spot"
position = [0.0, 3.0, 0.0]
direction = [0.0, -1.0, 0.2]
intensity = [9.0, 9.0, 9.0]
cone_angle = 30.0
falloff_angle = 20.0

[[lights]]
type = "directional"
direction = [0.3, -1.0, 0.1]
irradiance = [1.5, 1.0, 0.5]

[materials.matte]
model = "lambert"
diffuse = [0.5, 0.6, 0.7]

[materials.glossy]
model = "blinn_phong"
diffuse = [0.3, 0.3, 0.3]
specular = [0.5, 0.4, 0.3]
exponent = 60.0

[materials.metal]
model = "cook_torrance"
distribution = "ggx"
specular = [0.9, 0.6, 0.5]
roughness = 0.09

[[objects]]
name = "floor plane"
material = "matte"
shape = { type = "plane", size = [4.0, 4.0], subdivisions = 3 }

[[objects]]
name = "ball"
material = "glossy"
shape = { type = "sphere", radius = 0.5, segments = 12 }
transform = { scale = [1.0, 2.0, 1.0], rotate = [10.0, 20.0, 30.0], translate = [0.0, 0.5, 0.0] }
receiver = false

[[objects]]
name = "ring"
material = "metal"
shape = { type = "ring", radius = 1.0, height = 0.3, thickness = 0.05, segments = 16 }
reflector = false
"#;

fn scene_at(dir: &Path) -> Scene {
    let p = dir.join("t.toml");
    std::fs::write(&p, SCENE).unwrap();
    Scene::load(&p).unwrap()
}

fn floats(s: &str) -> Vec<f32> {
    s.split(',').map(|x| x.trim().parse().unwrap()).collect()
}

fn scene_xml(scene: &Scene) -> Element {
    parse(&plan(scene).xml).expect("the exported XML is well-formed")
}

#[test]
fn alpha_from_blinn_phong_matches_the_peak_and_its_width() {
    for n in [0.0f32, 1.0, 20.0, 60.0, 1000.0, 1e6] {
        let a = beckmann_alpha_from_blinn_phong(n);
        // Same peak: D_Beckmann(0) = 1/(π α²) = (n + 2)/(2π) = D_BlinnPhong(0). 1e-5: f32
        // rounding of α² and of the two constants.
        let (db, dp) = (beckmann_d(Vec3::Z, a), blinn_phong_d(Vec3::Z, n));
        assert!((db / dp - 1.0).abs() < 1e-5, "n = {n}: {db} vs {dp}");
        if n >= 20.0 {
            // Same width: at θh with n θh² = 1 (where D has fallen to 1/√e) the ratio is
            // exp(θ² − (3n+4)θ⁴/12 + O(θ⁶)) ≈ 1 + 0.75/n; allowed 1/n, plus 1e-5 for the f32
            // evaluation of both NDFs at n = 1e6 (θh = 1e-3).
            let t = (1.0 / n).sqrt();
            let h = Vec3::new(t.sin(), 0.0, t.cos());
            let r = beckmann_d(h, a) / blinn_phong_d(h, n);
            assert!(
                (r - 1.0).abs() <= 1.0 / n + 1e-5,
                "n = {n}: ratio {r} at θh = {t}"
            );
            assert!(
                r >= 1.0 - 1e-5,
                "n = {n}: Beckmann is the wider one, ratio {r}"
            );
        }
    }
    assert!((beckmann_alpha_from_blinn_phong(60.0) - (2.0f32 / 62.0).sqrt()).abs() < 1e-7);
    // The Phong mapping is the Blinn-Phong one at 4n: 1/√(2n + 1).
    for n in [1.0f32, 400.0, 1e5] {
        let a = beckmann_alpha_from_phong(n);
        assert!(
            (a - 1.0 / (2.0 * n + 1.0).sqrt()).abs() < 1e-6 * a,
            "{n}: {a}"
        );
    }
}

#[test]
fn blend_weights_reproduce_diffuse_plus_specular() {
    let cases = [
        (Vec3::new(0.35, 0.35, 0.38), Vec3::splat(0.4)),
        (Vec3::new(0.1, 0.15, 0.3), Vec3::splat(0.5)),
        (Vec3::new(0.05, 0.04, 0.02), Vec3::new(0.9, 0.65, 0.3)),
        (Vec3::splat(0.7), Vec3::splat(0.3)),
        (Vec3::splat(1e-4), Vec3::splat(0.999)),
    ];
    for (kd, ks) in cases {
        let b = blend_weights(kd, ks);
        assert!(b.exact, "{kd} {ks}");
        assert!(b.weight > 0.0 && b.weight < 1.0);
        // Mitsuba refuses reflectances above 1.
        assert!(b.diffuse.max_element() <= 1.0 && b.specular.max_element() <= 1.0);
        // (1 − w)·kd' = kd and w·ks' = ks as Mitsuba computes them (f32), per channel within
        // 1e-6 relative: a few f32 roundings of the rescaling and the product.
        let d = (1.0 - b.weight) * b.diffuse - kd;
        let s = b.weight * b.specular - ks;
        for c in 0..3 {
            assert!(d[c].abs() <= 1e-6 * kd[c], "kd {kd} → {d}");
            assert!(s[c].abs() <= 1e-6 * ks[c], "ks {ks} → {s}");
        }
    }
    // Maxima in different channels that sum above 1: not representable, flagged and clipped.
    let b = blend_weights(Vec3::new(0.8, 0.0, 0.0), Vec3::new(0.0, 0.8, 0.0));
    assert!(!b.exact);
    assert!(b.diffuse.max_element() <= 1.0 && b.specular.max_element() <= 1.0);
}

#[test]
fn every_material_model_converts_to_the_documented_plugins() {
    let lambert = convert_brdf(&Brdf::Lambert {
        diffuse: Vec3::new(0.5, 0.6, 0.7),
    });
    assert!(lambert.exact && lambert.notes.is_empty());
    assert_eq!(lambert.node.get("type"), Some("diffuse"));
    assert_eq!(
        floats(
            lambert
                .node
                .property("rgb", "reflectance")
                .unwrap()
                .get("value")
                .unwrap()
        ),
        vec![0.5, 0.6, 0.7]
    );

    let metal = convert_brdf(&Brdf::CookTorrance {
        diffuse: Vec3::ZERO,
        specular: Vec3::new(0.9, 0.6, 0.5),
        roughness: 0.09,
        distribution: Distribution::Ggx,
    });
    assert!(!metal.exact);
    assert_eq!(metal.node.get("type"), Some("principled"));
    let rough: f32 = metal
        .node
        .property("float", "roughness")
        .unwrap()
        .get("value")
        .unwrap()
        .parse()
        .unwrap();
    // Mitsuba's principled squares its roughness: α = 0.09 ↔ 0.3 (f32 rounding).
    assert!((rough * rough - 0.09).abs() < 1e-6, "{rough}");
    assert_eq!(
        metal
            .node
            .property("float", "metallic")
            .unwrap()
            .get("value"),
        Some("1")
    );
    assert_eq!(
        metal
            .node
            .property("float", "spec_tint")
            .unwrap()
            .get("value"),
        Some("0")
    );

    let bp = convert_brdf(&Brdf::BlinnPhong {
        diffuse: Vec3::splat(0.3),
        specular: Vec3::splat(0.5),
        exponent: 60.0,
    });
    assert!(!bp.exact);
    assert_eq!(bp.node.get("type"), Some("blendbsdf"));
    let kinds: Vec<_> = bp
        .node
        .children_named("bsdf")
        .map(|c| c.get("type").unwrap())
        .collect();
    // blendbsdf's weight selects the second component: diffuse first, the lobe second.
    assert_eq!(kinds, ["diffuse", "roughconductor"]);
    let lobe = bp.node.children_named("bsdf").nth(1).unwrap();
    assert_eq!(
        lobe.property("string", "distribution")
            .unwrap()
            .get("value"),
        Some("beckmann")
    );
    assert_eq!(
        lobe.property("string", "material").unwrap().get("value"),
        Some("none")
    );
    let a: f32 = lobe
        .property("float", "alpha")
        .unwrap()
        .get("value")
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(a, beckmann_alpha_from_blinn_phong(60.0));
    let w: f32 = bp
        .node
        .property("float", "weight")
        .unwrap()
        .get("value")
        .unwrap()
        .parse()
        .unwrap();
    assert!((w - 0.5 / 0.8).abs() < 1e-6, "{w}");

    let ward = convert_brdf(&Brdf::Ward {
        diffuse: Vec3::ZERO,
        specular: Vec3::splat(0.8),
        roughness: 0.12,
    });
    assert!(!ward.exact);
    // No diffuse: the lobe alone, α unchanged.
    assert_eq!(ward.node.get("type"), Some("roughconductor"));
    assert_eq!(
        ward.node.property("float", "alpha").unwrap().get("value"),
        Some("0.12")
    );

    let phong = convert_brdf(&Brdf::Phong {
        diffuse: Vec3::splat(0.1),
        specular: Vec3::ZERO,
        exponent: 400.0,
    });
    // Without a lobe a Phong material is Lambertian, and that converts exactly.
    assert!(phong.exact);
    assert_eq!(phong.node.get("type"), Some("diffuse"));
    let phong = convert_brdf(&Brdf::Phong {
        diffuse: Vec3::splat(0.1),
        specular: Vec3::splat(0.5),
        exponent: 400.0,
    });
    assert!(!phong.exact && phong.notes[0].contains("Phong"));

    let beck = convert_brdf(&Brdf::CookTorrance {
        diffuse: Vec3::splat(0.2),
        specular: Vec3::splat(0.04),
        roughness: 0.3,
        distribution: Distribution::Beckmann,
    });
    assert!(!beck.exact);
    assert_eq!(beck.node.get("type"), Some("blendbsdf"));
    assert!(beck.notes.iter().any(|n| n.contains("Schlick")));
    assert!(beck.notes.iter().any(|n| n.contains("coupled diffuse")));
}

#[test]
fn lights_convert_with_their_parameters() {
    let (p, note) = light_emitter(&Light::Point {
        position: Vec3::new(1.0, 2.0, -3.5),
        intensity: Vec3::new(60.0, 50.0, 0.25),
    });
    assert!(note.is_none());
    assert_eq!(p.get("type"), Some("point"));
    let pos = p.children_named("point").next().unwrap();
    assert_eq!(
        (pos.get("x"), pos.get("y"), pos.get("z")),
        (Some("1"), Some("2"), Some("-3.5"))
    );
    assert_eq!(
        floats(
            p.property("rgb", "intensity")
                .unwrap()
                .get("value")
                .unwrap()
        ),
        [60.0, 50.0, 0.25]
    );

    let dir = Vec3::new(0.0, -1.0, 0.2).normalize();
    let spot = Light::Spot {
        position: Vec3::new(0.0, 3.0, 0.0),
        direction: dir,
        intensity: Vec3::splat(9.0),
        cos_cone: 30f32.to_radians().cos(),
        cos_falloff: 20f32.to_radians().cos(),
    };
    let (s, note) = light_emitter(&spot);
    assert!(note.unwrap().contains("linear in the angle"));
    let angle = |n: &str| -> f32 {
        s.property("float", n)
            .unwrap()
            .get("value")
            .unwrap()
            .parse()
            .unwrap()
    };
    // Degrees back from the cosines: within 1e-3° (f32 acos near 1).
    assert!((angle("cutoff_angle") - 30.0).abs() < 1e-3);
    assert!((angle("beam_width") - 20.0).abs() < 1e-3);
    let look = s
        .children_named("transform")
        .next()
        .unwrap()
        .children_named("lookat")
        .next()
        .unwrap();
    let (o, t) = (
        Vec3::from_slice(&floats(look.get("origin").unwrap())),
        Vec3::from_slice(&floats(look.get("target").unwrap())),
    );
    assert!(((t - o).normalize() - dir).length() < 1e-6);
    let up = Vec3::from_slice(&floats(look.get("up").unwrap()));
    assert!(up.cross(dir).length() > 0.1, "up parallel to the axis");
    // A hard-edged spot (falloff = cone) is exact.
    let hard = Light::Spot {
        position: Vec3::new(0.0, 3.0, 0.0),
        direction: dir,
        intensity: Vec3::splat(9.0),
        cos_cone: 30f32.to_radians().cos(),
        cos_falloff: 30f32.to_radians().cos(),
    };
    assert!(light_emitter(&hard).1.is_none());

    let (d, note) = light_emitter(&Light::Directional {
        direction: Vec3::new(0.0, -1.0, 0.0),
        irradiance: Vec3::new(3.0, 2.0, 1.0),
    });
    assert!(note.is_none());
    assert_eq!(d.get("type"), Some("directional"));
    let v = d.children_named("vector").next().unwrap();
    assert_eq!(
        (v.get("x"), v.get("y"), v.get("z")),
        (Some("0"), Some("-1"), Some("0"))
    );
    assert_eq!(
        floats(
            d.property("rgb", "irradiance")
                .unwrap()
                .get("value")
                .unwrap()
        ),
        [3.0, 2.0, 1.0]
    );
}

#[test]
fn the_xml_holds_camera_integrator_lights_materials_and_shapes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path());
    let root = scene_xml(&scene);
    assert_eq!(root.tag, "scene");
    assert_eq!(root.get("version"), Some("3.0.0"));
    let default = |n: &str| {
        root.children_named("default")
            .find(|d| d.get("name") == Some(n))
            .unwrap()
            .get("value")
            .unwrap()
            .to_string()
    };
    assert_eq!(
        (default("width"), default("height")),
        ("40".into(), "30".into())
    );
    assert_eq!(default("max_depth"), "3");
    assert_eq!(default("spp"), "64");

    let integ = root.children_named("integrator").next().unwrap();
    assert_eq!(integ.get("type"), Some("path"));
    assert_eq!(
        integ.property("integer", "max_depth").unwrap().get("value"),
        Some("$max_depth")
    );
    assert_eq!(
        integ
            .property("boolean", "hide_emitters")
            .unwrap()
            .get("value"),
        Some("true")
    );

    let sensor = root.children_named("sensor").next().unwrap();
    assert_eq!(sensor.get("type"), Some("perspective"));
    assert_eq!(
        sensor.property("string", "fov_axis").unwrap().get("value"),
        Some("y")
    );
    let fov: f32 = sensor
        .property("float", "fov")
        .unwrap()
        .get("value")
        .unwrap()
        .parse()
        .unwrap();
    assert!((fov - 38.0).abs() < 1e-4, "{fov}");
    let look = sensor
        .children_named("transform")
        .next()
        .unwrap()
        .children_named("lookat")
        .next()
        .unwrap();
    let origin = Vec3::from_slice(&floats(look.get("origin").unwrap()));
    let target = Vec3::from_slice(&floats(look.get("target").unwrap()));
    let up = Vec3::from_slice(&floats(look.get("up").unwrap()));
    assert_eq!(origin, Vec3::new(0.5, 2.0, 4.0));
    // Same view direction as the scene's look_at (1e-6: f32 normalisation), and an up vector in
    // the plane of the scene's up and the view direction, on the same side.
    let fwd = (Vec3::new(0.0, 0.25, 0.0) - origin).normalize();
    assert!(((target - origin).normalize() - fwd).length() < 1e-6);
    assert!(up.dot(fwd).abs() < 1e-6 && up.dot(Vec3::Y) > 0.0);
    assert!(up.cross(fwd).dot(Vec3::Y.cross(fwd)).abs() > 0.0);
    let film = sensor.children_named("film").next().unwrap();
    assert_eq!(
        film.children_named("rfilter").next().unwrap().get("type"),
        Some("box")
    );
    let far: f32 = sensor
        .property("float", "far_clip")
        .unwrap()
        .get("value")
        .unwrap()
        .parse()
        .unwrap();
    let near: f32 = sensor
        .property("float", "near_clip")
        .unwrap()
        .get("value")
        .unwrap()
        .parse()
        .unwrap();
    assert!(near > 0.0 && near <= 1e-2 && far >= 1e4);

    let emitters: Vec<_> = root
        .children_named("emitter")
        .map(|e| e.get("type").unwrap())
        .collect();
    assert_eq!(emitters, ["point", "spot", "directional"]);

    // Every shape refers to a BSDF that is defined, every BSDF is two-sided, each object is one
    // shape with its own PLY file.
    let ids: Vec<_> = root
        .children_named("bsdf")
        .map(|b| {
            assert_eq!(b.get("type"), Some("twosided"));
            b.get("id").unwrap().to_string()
        })
        .collect();
    assert_eq!(ids.len(), 3);
    let shapes: Vec<_> = root.children_named("shape").collect();
    assert_eq!(shapes.len(), scene.objects.len());
    let mut files = Vec::new();
    for s in &shapes {
        assert_eq!(s.get("type"), Some("ply"));
        let r = s.children_named("ref").next().unwrap().get("id").unwrap();
        assert!(ids.iter().any(|i| i == r), "undefined BSDF {r}");
        files.push(
            s.property("string", "filename")
                .unwrap()
                .get("value")
                .unwrap()
                .to_string(),
        );
    }
    assert_eq!(
        files,
        [
            "meshes/00-floor_plane.ply",
            "meshes/01-ball.ply",
            "meshes/02-ring.ply"
        ]
    );
}

#[test]
fn approximations_and_unsupported_flags_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path());
    let w = plan(&scene).warnings;
    let has = |s: &str| w.iter().any(|x| x.contains(s));
    assert!(has("lights[1] (spot): approximate"), "{w:#?}");
    assert!(has("materials.glossy: approximate"), "{w:#?}");
    assert!(has("materials.metal: approximate"), "{w:#?}");
    assert!(!has("materials.matte"), "{w:#?}");
    assert!(has("objects[1] \"ball\": receiver = false"), "{w:#?}");
    assert!(has("objects[2] \"ring\": reflector = false"), "{w:#?}");
    // Every warning names the scene file.
    assert!(w.iter().all(|x| x.contains("t.toml")), "{w:#?}");
}

#[test]
fn ply_files_hold_exactly_the_scene_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path());
    for (i, o) in scene.objects.iter().enumerate() {
        let bytes = object_ply(&scene, i);
        let m = crate::scene::mesh::parse_mesh_bytes(&bytes, "x.ply").unwrap();
        assert_eq!(m.indices.len(), o.tri_count as usize);
        let normals = m.normals.as_ref().unwrap();
        for (k, t) in m.indices.iter().enumerate() {
            let g = scene.mesh.indices[o.first_tri as usize + k];
            for c in 0..3 {
                // Bit-identical f32 positions and normals (world space, after the transform).
                assert_eq!(
                    m.positions[t[c] as usize],
                    scene.mesh.positions[g[c] as usize]
                );
                assert_eq!(normals[t[c] as usize], scene.mesh.normals[g[c] as usize]);
            }
        }
    }
}

#[test]
fn albedo_estimate_is_exact_for_lambert_and_below_one_for_glossy() {
    let (a, se) = albedo(
        &Brdf::Lambert {
            diffuse: Vec3::new(0.25, 0.5, 0.75),
        },
        0.3,
        1000,
    );
    // Cosine sampling makes every sample's weight exactly kd (up to f32 rounding).
    assert!(
        (a - Vec3::new(0.25, 0.5, 0.75)).abs().max_element() < 1e-6,
        "{a}"
    );
    assert!(se.max_element() < 1e-6);
    let (a, se) = albedo(
        &Brdf::BlinnPhong {
            diffuse: Vec3::ZERO,
            specular: Vec3::ONE,
            exponent: 20.0,
        },
        0.5,
        1 << 16,
    );
    // docs/brdf.md's albedo table: 0.92308 at cos θo = 0.5 (quadrature); 5 standard errors.
    assert!((a.x - 0.92308).abs() < 5.0 * se.x.max(1e-4), "{a} ± {se}");
}

#[test]
fn export_writes_a_complete_directory_and_protects_what_is_there() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_at(dir.path());
    let out = dir.path().join("out");
    let opts = ExportOptions {
        force: false,
        brdf_check: true,
    };
    let report = export(&scene, &out, opts, None).unwrap();
    for f in &report.files {
        assert!(out.join(f).is_file(), "{f}");
    }
    assert!(report.files.contains(&"scene.xml".to_string()));
    assert!(report.files.contains(&"brdf-check.json".to_string()));
    let check: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("brdf-check.json")).unwrap())
            .unwrap();
    assert_eq!(check["materials"].as_object().unwrap().len(), 3);
    // No temporary directory is left beside it.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");

    // A second export into the same directory is refused without --force, and replaces it with.
    let again = export(&scene, &out, ExportOptions::default(), None)
        .unwrap_err()
        .to_string();
    assert!(
        again.contains("not empty") && again.contains("--force"),
        "{again}"
    );
    std::fs::write(out.join("stale.txt"), "x").unwrap();
    export(
        &scene,
        &out,
        ExportOptions {
            force: true,
            brdf_check: false,
        },
        None,
    )
    .unwrap();
    assert!(!out.join("stale.txt").exists() && !out.join("brdf-check.json").exists());

    // --force never replaces a directory that is not an export, nor one holding the scene.
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "keep").unwrap();
    let e = export(
        &scene,
        &other,
        ExportOptions {
            force: true,
            brdf_check: false,
        },
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("no scene.xml"), "{e}");
    assert_eq!(
        std::fs::read_to_string(other.join("notes.txt")).unwrap(),
        "keep"
    );
    let e = export(
        &scene,
        dir.path(),
        ExportOptions {
            force: true,
            brdf_check: false,
        },
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("holds the scene's input"), "{e}");
    // A file is not a directory.
    let e = export(
        &scene,
        &dir.path().join("t.toml"),
        ExportOptions::default(),
        None,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("t.toml"), "{e}");
    assert_eq!(
        std::fs::read_to_string(dir.path().join("t.toml")).unwrap(),
        SCENE
    );

    // Interrupted: nothing written, no temporary directory.
    let stop = AtomicBool::new(true);
    let cut = dir.path().join("cut");
    assert!(matches!(
        export(&scene, &cut, ExportOptions::default(), Some(&stop)),
        Err(ExportError::Interrupted)
    ));
    assert!(!cut.exists());
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");
}

#[test]
fn the_environment_map_is_written_as_the_renderer_holds_it() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = format!(
        "{}\n[environment]\nfile = \"{}\"\nrotation = 90.0\nintensity = 2.0\n",
        SCENE,
        root.join("scenes/envmaps/sunrise.exr").display()
    );
    let p = dir.path().join("env.toml");
    std::fs::write(&p, text).unwrap();
    let scene = Scene::load(&p).unwrap();
    let out = dir.path().join("out");
    export(&scene, &out, ExportOptions::default(), None).unwrap();
    let xml = scene_xml(&scene);
    let env = xml
        .children_named("emitter")
        .find(|e| e.get("type") == Some("envmap"))
        .unwrap();
    assert_eq!(
        env.property("string", "filename").unwrap().get("value"),
        Some("envmap.exr")
    );
    assert_eq!(
        env.property("float", "scale").unwrap().get("value"),
        Some("1")
    );
    let rot = env
        .children_named("transform")
        .next()
        .unwrap()
        .children_named("rotate")
        .next()
        .unwrap();
    assert_eq!((rot.get("y"), rot.get("angle")), (Some("1"), Some("90")));
    // The texels, intensity applied, bit for bit.
    let img = crate::image::read_exr(&out.join("envmap.exr")).unwrap();
    let e = scene.environment.as_ref().unwrap();
    assert_eq!((img.width, img.height), (e.width(), e.height()));
    for (y, x) in [
        (0, 0),
        (e.height() / 2, e.width() / 3),
        (e.height() - 1, e.width() - 1),
    ] {
        assert_eq!(img.get(x, y), e.texel(x, y));
    }
    assert!(
        plan(&scene)
            .warnings
            .iter()
            .any(|w| w.contains("environment: approximate"))
    );
}
