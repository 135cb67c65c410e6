//! Bad input through the command line: every case gets a clear message naming the file and the
//! field (or line/column), exit status 2 — never a panic (status 101) — and no output file.
//! Cases where the scene can still render produce a warning and status 0.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const GOOD_HEAD: &str = r#"
[camera]
position = [0.0, 2.0, 4.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
width = 16
height = 12

[[lights]]
type = "point"
position = [0.0, 3.0, 0.0]
intensity = [5.0, 5.0, 5.0]

[materials.white]
model = "lambert"
diffuse = [0.5, 0.5, 0.5]
"#;

const PLANE: &str = r#"
[[objects]]
material = "white"
shape = { type = "plane", size = [4.0, 4.0] }
"#;

struct Case {
    dir: tempfile::TempDir,
}

impl Case {
    fn new() -> Case {
        Case {
            dir: tempfile::tempdir().unwrap(),
        }
    }
    fn file(&self, name: &str, bytes: &[u8]) -> PathBuf {
        let p = self.dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }
    fn out(&self) -> PathBuf {
        self.dir.path().join("out.exr")
    }
    /// `render SCENE --spp 1 --quiet --output out.exr`
    fn render(&self, scene: &Path) -> Output {
        Command::new(env!("CARGO_BIN_EXE_interreflect"))
            .arg("render")
            .arg(scene)
            .args(["--spp", "1", "--quiet", "--output"])
            .arg(self.out())
            .output()
            .unwrap()
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Fails with status 2, a message containing every needle, and no output written.
fn assert_rejected(case: &Case, scene: &Path, needles: &[&str]) {
    let o = case.render(scene);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "expected exit 2, stderr:\n{err}");
    assert!(!err.contains("panicked"), "panic:\n{err}");
    for n in needles {
        assert!(err.contains(n), "message lacks {n:?}:\n{err}");
    }
    assert!(
        !case.out().exists(),
        "an output was written despite the error"
    );
    let leftovers: Vec<_> = std::fs::read_dir(case.dir.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

fn scene_with(case: &Case, body: &str) -> PathBuf {
    case.file("scene.toml", body.as_bytes())
}

#[test]
fn malformed_toml_reports_line_and_column() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!("{GOOD_HEAD}\n[[objects]\nmaterial = \"white\"\n"),
    );
    assert_rejected(&c, &s, &["scene.toml", "line 18", "column 11"]);
}

#[test]
fn unknown_field_is_named() {
    let c = Case::new();
    let s = scene_with(&c, &format!("{GOOD_HEAD}{PLANE}\nroughnes = 3\n"));
    assert_rejected(&c, &s, &["scene.toml", "roughnes"]);
}

#[test]
fn unknown_field_in_nested_table_is_named() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!("{}{PLANE}", GOOD_HEAD.replace("fov_y", "fovy")),
    );
    assert_rejected(&c, &s, &["scene.toml", "fovy"]);
}

#[test]
fn missing_field_is_named() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!("{}{PLANE}", GOOD_HEAD.replace("fov_y = 40.0", "")),
    );
    assert_rejected(&c, &s, &["scene.toml", "fov_y"]);
}

#[test]
fn wrong_type_is_reported() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!(
            "{}{PLANE}",
            GOOD_HEAD.replace("width = 16", "width = \"wide\"")
        ),
    );
    assert_rejected(&c, &s, &["scene.toml", "line 6"]);
}

#[test]
fn negative_intensity_is_rejected() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!(
            "{}{PLANE}",
            GOOD_HEAD.replace("[5.0, 5.0, 5.0]", "[-5.0, 5.0, 5.0]")
        ),
    );
    assert_rejected(&c, &s, &["scene.toml", "lights[0].intensity", "negative"]);
}

#[test]
fn nan_parameter_is_rejected() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!(
            "{}{PLANE}",
            GOOD_HEAD.replace("position = [0.0, 3.0, 0.0]", "position = [0.0, nan, 0.0]")
        ),
    );
    assert_rejected(&c, &s, &["scene.toml", "lights[0].position", "finite"]);
}

#[test]
fn nan_material_parameter_is_rejected() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!(
            "{}{PLANE}",
            GOOD_HEAD.replace("[0.5, 0.5, 0.5]", "[0.5, nan, 0.5]")
        ),
    );
    assert_rejected(&c, &s, &["scene.toml", "materials.white"]);
}

#[test]
fn absurd_fov_is_rejected() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!(
            "{}{PLANE}",
            GOOD_HEAD.replace("fov_y = 40.0", "fov_y = 400.0")
        ),
    );
    assert_rejected(&c, &s, &["scene.toml", "camera.fov_y"]);
}

#[test]
fn zero_resolution_is_rejected() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!("{}{PLANE}", GOOD_HEAD.replace("height = 12", "height = 0")),
    );
    assert_rejected(&c, &s, &["scene.toml", "camera.height"]);
}

#[test]
fn undefined_material_is_named() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!("{GOOD_HEAD}{}", PLANE.replace("\"white\"", "\"whte\"")),
    );
    assert_rejected(
        &c,
        &s,
        &["scene.toml", "objects[0].material", "whte", "white"],
    );
}

#[test]
fn negative_shape_size_is_rejected() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!("{GOOD_HEAD}{}", PLANE.replace("[4.0, 4.0]", "[4.0, -4.0]")),
    );
    assert_rejected(&c, &s, &["scene.toml", "objects[0].shape.size[1]"]);
}

#[test]
fn zero_scale_is_rejected() {
    let c = Case::new();
    let s = scene_with(
        &c,
        &format!("{GOOD_HEAD}{PLANE}transform = {{ scale = 0.0 }}\n"),
    );
    assert_rejected(&c, &s, &["scene.toml", "objects[0].transform.scale"]);
}

#[test]
fn no_objects_is_rejected() {
    let c = Case::new();
    let s = scene_with(&c, GOOD_HEAD);
    assert_rejected(&c, &s, &["scene.toml", "objects"]);
}

#[test]
fn missing_scene_file_is_reported() {
    let c = Case::new();
    assert_rejected(
        &c,
        &c.dir.path().join("nope.toml"),
        &["nope.toml", "cannot read"],
    );
}

fn mesh_scene(c: &Case, file: &str) -> PathBuf {
    scene_with(
        c,
        &format!(
            "{GOOD_HEAD}{PLANE}\n[[objects]]\nname = \"m\"\nmaterial = \"white\"\nshape = {{ type = \"mesh\", file = \"{file}\" }}\n"
        ),
    )
}

#[test]
fn missing_mesh_file_is_named() {
    let c = Case::new();
    let s = mesh_scene(&c, "models/missing.ply");
    assert_rejected(
        &c,
        &s,
        &["scene.toml", "objects[1].shape.file", "missing.ply"],
    );
}

const PLY_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn truncated_ply_is_reported() {
    let c = Case::new();
    c.file("m.ply", format!("{PLY_HEAD}0 0 0\n1 0 0\n").as_bytes());
    let s = mesh_scene(&c, "m.ply");
    assert_rejected(&c, &s, &["scene.toml", "objects[1].shape.file", "m.ply"]);
}

#[test]
fn truncated_binary_ply_is_reported() {
    let c = Case::new();
    let mut bytes = PLY_HEAD
        .replace("ascii", "binary_little_endian")
        .into_bytes();
    bytes.extend_from_slice(&[0u8; 20]); // 3 vertices need 36 bytes
    c.file("m.ply", &bytes);
    let s = mesh_scene(&c, "m.ply");
    assert_rejected(&c, &s, &["scene.toml", "objects[1].shape.file", "m.ply"]);
}

#[test]
fn ply_face_index_out_of_range_is_reported() {
    let c = Case::new();
    c.file(
        "m.ply",
        format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").as_bytes(),
    );
    let s = mesh_scene(&c, "m.ply");
    assert_rejected(&c, &s, &["scene.toml", "m.ply", "7"]);
}

#[test]
fn corrupt_gzip_is_reported() {
    let c = Case::new();
    c.file("m.ply.gz", b"\x1f\x8b\x08\x00garbage-not-deflate");
    let s = mesh_scene(&c, "m.ply.gz");
    assert_rejected(&c, &s, &["scene.toml", "m.ply.gz"]);
}

#[test]
fn obj_with_missing_vertex_is_reported() {
    let c = Case::new();
    c.file("m.obj", b"v 0 0 0\nv 1 0 0\nf 1 2 3\n");
    let s = mesh_scene(&c, "m.obj");
    assert_rejected(&c, &s, &["scene.toml", "m.obj"]);
}

#[test]
fn gltf_with_missing_buffer_is_reported() {
    let c = Case::new();
    let json = r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"gone.bin","byteLength":36}],
      "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
      "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#;
    c.file("m.gltf", json.as_bytes());
    let s = mesh_scene(&c, "m.gltf");
    assert_rejected(&c, &s, &["scene.toml", "m.gltf"]);
}

#[test]
fn unknown_mesh_extension_is_reported() {
    let c = Case::new();
    c.file("m.stl", b"solid x\nendsolid x\n");
    let s = mesh_scene(&c, "m.stl");
    assert_rejected(&c, &s, &["scene.toml", "m.stl"]);
}

#[test]
fn all_degenerate_mesh_is_reported() {
    let c = Case::new();
    c.file(
        "m.ply",
        format!("{PLY_HEAD}0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n").as_bytes(),
    );
    let s = mesh_scene(&c, "m.ply");
    assert_rejected(&c, &s, &["scene.toml", "m.ply"]);
}

/// Renders fine (status 0) with a warning containing every needle.
fn assert_warned(c: &Case, scene: &Path, needles: &[&str]) {
    let o = c.render(scene);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "expected success, stderr:\n{err}");
    assert!(err.contains("warning"), "no warning:\n{err}");
    for n in needles {
        assert!(err.contains(n), "warning lacks {n:?}:\n{err}");
    }
    assert!(c.out().exists() && c.out().with_extension("png").exists());
}

#[test]
fn zero_area_and_duplicate_triangles_are_removed_with_a_warning() {
    let c = Case::new();
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n0 0.5 0\n1 0.5 0\n0 0.5 1\n2 0.5 0\n3 0 1 2\n3 0 2 1\n3 0 1 3\n";
    c.file("m.ply", ply.as_bytes());
    let s = mesh_scene(&c, "m.ply");
    assert_warned(&c, &s, &["objects[1]", "m.ply"]);
}

#[test]
fn camera_inside_geometry_is_warned() {
    let c = Case::new();
    let body = format!(
        "{}{PLANE}\n[[objects]]\nname = \"cage\"\nmaterial = \"white\"\nshape = {{ type = \"box\", size = [20.0, 20.0, 20.0] }}\n",
        GOOD_HEAD
    );
    let s = scene_with(&c, &body);
    assert_warned(&c, &s, &["camera.position", "inside", "cage"]);
}

#[test]
fn output_over_the_scene_file_is_refused() {
    let c = Case::new();
    let s = scene_with(&c, &format!("{GOOD_HEAD}{PLANE}"));
    let before = std::fs::read(&s).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_interreflect"))
        .args(["render", "--quiet", "--spp", "1", "--output"])
        .arg(&s)
        .arg(&s)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains(".exr"));
    assert_eq!(std::fs::read(&s).unwrap(), before, "the input was modified");
}

#[test]
fn bad_cli_arguments_fail_cleanly() {
    let c = Case::new();
    let s = scene_with(&c, &format!("{GOOD_HEAD}{PLANE}"));
    for args in [
        vec!["--spp", "0"],
        vec!["--threads", "0"],
        vec!["--width", "0"],
        vec!["--method", "direct", "--indirect-only"],
        vec!["--method", "sg", "--threshold", "2"],
        vec!["--method", "sg", "--threshold", "NaN"],
        vec!["--method", "sg", "--cut", "triangle"],
        vec!["--method", "sg", "--visibility", "rays"],
        vec!["--method", "prt", "--order", "0"],
        vec!["--method", "prt", "--order", "40"],
        vec!["--method", "prt", "--bounces", "99"],
        vec!["--method", "prt", "--bounces", "0", "--indirect-only"],
        vec!["--method", "prt", "--rotate-lighting", "NaN"],
        vec!["--method", "prt", "--transfer", "glossy"],
        vec!["--method", "prt", "--device", "tpu"],
        vec!["--method", "prt", "--window-width", "-2"],
        vec!["--method", "prt", "--window", "hamming"],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_interreflect"))
            .arg("render")
            .arg(&s)
            .args(["--quiet", "--output"])
            .arg(c.out())
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
        assert!(!c.out().exists());
    }
}

#[test]
fn bad_visibility_settings_are_named() {
    for (body, field) in [
        (
            "shadow_map_resolution = 8",
            "visibility.shadow_map_resolution",
        ),
        (
            "shadow_map_resolution = 100000",
            "visibility.shadow_map_resolution",
        ),
        ("vsm_blur = 99", "visibility.vsm_blur"),
        ("light_bleeding = 1.0", "visibility.light_bleeding"),
        ("light_bleeding = -0.1", "visibility.light_bleeding"),
        ("light_bleeding = nan", "visibility.light_bleeding"),
        ("shadowmap = 512", "shadowmap"),
        ("vpl_count = 0", "visibility.vpl_count"),
        ("ism_resolution = 2", "visibility.ism_resolution"),
        ("ism_points = 0", "visibility.ism_points"),
        ("ism_bias = -1", "visibility.ism_bias"),
        ("ism_bias = inf", "visibility.ism_bias"),
    ] {
        let c = Case::new();
        let s = scene_with(&c, &format!("{GOOD_HEAD}{PLANE}\n[visibility]\n{body}\n"));
        assert_rejected(&c, &s, &["scene.toml", field]);
    }
}

#[test]
fn bad_sg_settings_are_named() {
    for (body, field) in [
        ("threshold = -0.5", "methods.sg.threshold"),
        ("threshold = nan", "methods.sg.threshold"),
        ("max_cut = 100000000", "methods.sg.max_cut"),
        ("spp = 0", "methods.sg.spp"),
        ("cut = \"node\"", "cut"),
        ("treshold = 0.1", "treshold"),
    ] {
        let c = Case::new();
        let s = scene_with(&c, &format!("{GOOD_HEAD}{PLANE}\n[methods.sg]\n{body}\n"));
        assert_rejected(&c, &s, &["scene.toml", field]);
    }
}

/// A valid 8 × 4 environment map `env.exr` in the case's directory.
fn env_map(c: &Case) {
    use glam::Vec3;
    use interreflect::image::{Image, write_exr};
    let img = Image::from_fn(8, 4, |x, y| {
        Vec3::new(0.5 + x as f32 * 0.1, 0.5, 0.2 * y as f32)
    });
    write_exr(&c.dir.path().join("env.exr"), &img).unwrap();
}

fn env_scene(c: &Case, table: &str) -> PathBuf {
    scene_with(c, &format!("{GOOD_HEAD}{PLANE}\n[environment]\n{table}\n"))
}

#[test]
fn bad_environment_settings_are_named() {
    for (table, needles) in [
        (
            "file = \"envmaps/missing.exr\"",
            &["scene.toml", "environment.file", "missing.exr"][..],
        ),
        (
            "file = \"broken.exr\"",
            &["scene.toml", "environment.file", "broken.exr"],
        ),
        (
            "file = \"broken.hdr\"",
            &["scene.toml", "environment.file", "broken.hdr", "Radiance"],
        ),
        (
            "file = \"env.exr\"\nintensity = -1.0",
            &["scene.toml", "environment.intensity", "≥ 0"],
        ),
        (
            "file = \"env.exr\"\nrotation = nan",
            &["scene.toml", "environment.rotation", "finite"],
        ),
        (
            "file = \"env.exr\"\nrotaton = 90.0",
            &["scene.toml", "rotaton"],
        ),
        ("rotation = 10.0", &["scene.toml", "file"]),
        (
            "file = \"negative.exr\"",
            &["scene.toml", "environment.file", "negative.exr", "negative"],
        ),
        (
            "file = \"env.png\"",
            &["scene.toml", "environment.file", "env.png", "extension"],
        ),
    ] {
        let c = Case::new();
        env_map(&c);
        c.file("broken.exr", b"\x76\x2f\x31\x01 this is not an EXR");
        c.file(
            "broken.hdr",
            b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n\x02\x02",
        );
        c.file("env.png", b"\x89PNG");
        interreflect::image::write_exr(
            &c.dir.path().join("negative.exr"),
            &interreflect::image::Image::from_fn(8, 4, |x, _| {
                glam::Vec3::splat(if x == 3 { -0.5 } else { 1.0 })
            }),
        )
        .unwrap();
        let s = env_scene(&c, table);
        assert_rejected(&c, &s, needles);
    }
}

#[test]
fn environment_needs_brdf_samples() {
    let c = Case::new();
    env_map(&c);
    let s = scene_with(
        &c,
        &format!(
            "{GOOD_HEAD}{PLANE}\n[environment]\nfile = \"env.exr\"\n[methods.reference]\nbsdf_samples = 0\n"
        ),
    );
    assert_rejected(&c, &s, &["scene.toml", "methods.reference.bsdf_samples"]);
}

#[test]
fn environment_renders_and_warns_where_it_should() {
    // A valid map renders (status 0), and is protected from being overwritten by an output.
    let c = Case::new();
    env_map(&c);
    let s = env_scene(&c, "file = \"env.exr\"\nrotation = 30.0\nintensity = 2.0");
    let o = c.render(&s);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let o = Command::new(env!("CARGO_BIN_EXE_interreflect"))
        .arg("render")
        .arg(&s)
        .args(["--quiet", "--spp", "1", "--output"])
        .arg(c.dir.path().join("env.exr"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("refusing to overwrite"),
        "{}",
        stderr(&o)
    );
    // A map that is not 2:1 renders with a warning.
    let c = Case::new();
    interreflect::image::write_exr(
        &c.dir.path().join("square.exr"),
        &interreflect::image::Image::from_fn(4, 4, |_, _| glam::Vec3::ONE),
    )
    .unwrap();
    let s = env_scene(&c, "file = \"square.exr\"");
    assert_warned(&c, &s, &["environment.file", "square.exr", "2:1"]);
    // sg ignores the environment: a warning says so.
    let c = Case::new();
    env_map(&c);
    let s = env_scene(&c, "file = \"env.exr\"");
    let o = Command::new(env!("CARGO_BIN_EXE_interreflect"))
        .arg("render")
        .arg(&s)
        .args(["--quiet", "--method", "sg", "--output"])
        .arg(c.out())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("warning") && err.contains("sg ignores environment lighting"),
        "{err}"
    );
}

#[test]
fn bad_prt_settings_are_named() {
    for (body, field) in [
        ("order = 0", "methods.prt.order"),
        ("order = 17", "methods.prt.order"),
        ("bounces = 9", "methods.prt.bounces"),
        ("samples = 0", "methods.prt.samples"),
        ("samples = 100000000", "methods.prt.samples"),
        ("window_width = -1.0", "methods.prt.window_width"),
        ("window_width = nan", "methods.prt.window_width"),
        ("spp = 0", "methods.prt.spp"),
        ("transfer = \"glossy\"", "transfer"),
        ("window = \"hamming\"", "window"),
        ("oder = 3", "oder"),
    ] {
        let c = Case::new();
        let s = scene_with(&c, &format!("{GOOD_HEAD}{PLANE}\n[methods.prt]\n{body}\n"));
        assert_rejected(&c, &s, &["scene.toml", field]);
    }
}
