//! Bad input through the command line, checked as snapshots (insta, `tests/snapshots/`): each
//! case records the command, the exact exit status and the complete standard error, with the
//! case's temporary directory written `<dir>`. Every message must name the file and the field
//! (or line, element, texel, flag) and say what is expected.
//!
//! Besides its snapshot every case asserts in code what holds for all of them, so that an
//! accepted snapshot can never hide a broken guarantee:
//! - never a panic: status 2 for refused input, 0 for input that renders with a warning;
//! - refused input writes nothing: afterwards the directory holds exactly the files it held
//!   before, byte for byte (no output, no partial output, no temporary file, no input changed);
//! - input that renders writes its EXR, PNG and JSON and changes no input.
//!
//! After an intended change of a message: `INSTA_UPDATE=always cargo test --release --test
//! bad_input`, then read every changed `.snap` (`git diff tests/snapshots`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

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

/// The usual command: `render <dir>/scene.toml --spp 1 --quiet --output <dir>/out.exr`.
const RENDER: &[&str] = &[
    "render",
    "<dir>/scene.toml",
    "--spp",
    "1",
    "--quiet",
    "--output",
    "<dir>/out.exr",
];

/// What a case must do.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Expect {
    /// Status 2 and nothing written.
    Refused,
    /// Status 0, a `warning:` on stderr, and the EXR (path relative to the case's directory)
    /// with its PNG and JSON written.
    Warned(&'static str),
    /// Status 0, nothing on stderr, the EXR (relative path), PNG and JSON written.
    Rendered(&'static str),
}

/// One case: a temporary directory with its input files.
struct Case {
    dir: tempfile::TempDir,
}

/// Every file and directory under `root`: relative path → contents (None for a directory).
fn inventory(root: &Path) -> BTreeMap<PathBuf, Option<Vec<u8>>> {
    fn walk(root: &Path, at: &Path, out: &mut BTreeMap<PathBuf, Option<Vec<u8>>>) {
        for e in std::fs::read_dir(at).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(root).unwrap().to_path_buf();
            if p.is_dir() {
                out.insert(rel, None);
                walk(root, &p, out);
            } else {
                out.insert(rel, Some(std::fs::read(&p).unwrap()));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(root, root, &mut out);
    out
}

impl Case {
    fn new() -> Case {
        Case {
            dir: tempfile::tempdir().unwrap(),
        }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// Writes `name` (creating its directory) and returns its path.
    fn file(&self, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
        let p = self.path(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, bytes).unwrap();
        p
    }

    /// Writes `scene.toml`.
    fn scene(&self, body: &str) -> &Case {
        self.file("scene.toml", body);
        self
    }

    /// Runs `interreflect ARGS` (`<dir>` in an argument stands for the case's directory) in the
    /// case's directory, checks the guarantees of `expect`, and snapshots the command, the status
    /// and stderr as `bad_input__NAME.snap`.
    fn check(&self, name: &str, args: &[&str], expect: Expect) {
        let dir = self
            .dir
            .path()
            .to_str()
            .expect("a UTF-8 temporary directory");
        let before = inventory(self.dir.path());
        let out = Command::new(env!("CARGO_BIN_EXE_interreflect"))
            .args(args.iter().map(|a| a.replace("<dir>", dir)))
            .current_dir(self.dir.path())
            .env_remove("RUST_BACKTRACE")
            .env_remove("RUST_LOG")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).replace(dir, "<dir>");
        let stdout = String::from_utf8_lossy(&out.stdout);
        let status = out.status.code();
        assert!(!stderr.contains("panicked"), "{name}: panic:\n{stderr}");
        assert!(stdout.is_empty(), "{name}: unexpected stdout:\n{stdout}");
        let after = inventory(self.dir.path());
        let written: Vec<&PathBuf> = after.keys().filter(|k| !before.contains_key(*k)).collect();
        for (k, v) in &before {
            assert!(
                after.get(k) == Some(v),
                "{name}: the input {} was changed or removed",
                k.display()
            );
        }
        match expect {
            Expect::Refused => {
                assert_eq!(status, Some(2), "{name}: expected status 2:\n{stderr}");
                assert!(written.is_empty(), "{name}: files written: {written:?}");
            }
            Expect::Warned(exr) | Expect::Rendered(exr) => {
                assert_eq!(status, Some(0), "{name}: expected status 0:\n{stderr}");
                if matches!(expect, Expect::Warned(_)) {
                    assert!(stderr.contains("warning: "), "{name}: no warning");
                } else {
                    assert!(stderr.is_empty(), "{name}: unexpected stderr:\n{stderr}");
                }
                let exr = PathBuf::from(exr);
                let mut expected = vec![
                    exr.clone(),
                    exr.with_extension("png"),
                    exr.with_extension("json"),
                ];
                // Directories the output created.
                let mut d = exr.parent();
                while let Some(p) = d.filter(|p| !p.as_os_str().is_empty()) {
                    if !before.contains_key(p) {
                        expected.push(p.to_path_buf());
                    }
                    d = p.parent();
                }
                expected.sort();
                let mut got: Vec<PathBuf> = written.into_iter().cloned().collect();
                got.sort();
                assert_eq!(got, expected, "{name}: files written");
            }
        }
        let shown: Vec<String> = args
            .iter()
            .map(|a| {
                if a.is_empty() || a.contains([' ', '\n', '"']) {
                    format!("{a:?}")
                } else {
                    a.to_string()
                }
            })
            .collect();
        let text = format!(
            "$ interreflect {}\nstatus: {}\n{stderr}",
            shown.join(" "),
            status.map_or("killed by a signal".into(), |s| s.to_string()),
        );
        insta::assert_snapshot!(name, text);
    }

    /// `scene.toml` = `body`, rendered with [`RENDER`].
    fn render(name: &str, body: &str, expect: Expect) {
        Case::new().scene(body).check(name, RENDER, expect);
    }
}

/// `GOOD_HEAD` with `from` replaced by `to` (which must occur), then `tail`.
fn head_with(from: &str, to: &str, tail: &str) -> String {
    assert!(GOOD_HEAD.contains(from), "{from:?} not in the scene");
    format!("{}{tail}", GOOD_HEAD.replace(from, to))
}

// ---------------------------------------------------------------------------------------------
// Scene files.

#[test]
fn scene_files() {
    let c = Case::new();
    c.check("scene_missing_file", RENDER, Expect::Refused);
    Case::new()
        .scene("")
        .check("scene_empty_file", RENDER, Expect::Refused);
    Case::new().scene("This is a README, not a scene.\n").check(
        "scene_not_toml",
        RENDER,
        Expect::Refused,
    );
    // A file that is not UTF-8 at all.
    let c = Case::new();
    c.file("scene.toml", b"[camera]\nposition = \xff\xfe\n");
    c.check("scene_not_utf8", RENDER, Expect::Refused);
    let c = Case::new();
    std::fs::create_dir(c.path("scene.toml")).unwrap();
    c.check("scene_is_a_directory", RENDER, Expect::Refused);

    let table = [
        (
            "scene_malformed_toml",
            format!("{GOOD_HEAD}\n[[objects]\nmaterial = \"white\"\n"),
        ),
        (
            "scene_unknown_top_level_field",
            format!("{GOOD_HEAD}{PLANE}\nroughnes = 3\n"),
        ),
        (
            "scene_unknown_field_in_camera",
            head_with("fov_y", "fovy", PLANE),
        ),
        ("scene_missing_field", head_with("fov_y = 40.0", "", PLANE)),
        (
            "scene_wrong_type",
            head_with("width = 16", "width = \"wide\"", PLANE),
        ),
        (
            "scene_duplicate_material_name",
            format!(
                "{GOOD_HEAD}\n[materials.white]\nmodel = \"lambert\"\ndiffuse = [1.0, 1.0, 1.0]\n{PLANE}"
            ),
        ),
        (
            "scene_unknown_material_model",
            head_with("model = \"lambert\"", "model = \"disney\"", PLANE),
        ),
        (
            "scene_unknown_light_type",
            head_with("type = \"point\"", "type = \"area\"", PLANE),
        ),
        (
            "scene_negative_intensity",
            head_with("[5.0, 5.0, 5.0]", "[-5.0, 5.0, 5.0]", PLANE),
        ),
        (
            "scene_light_intensity_beyond_the_limit",
            head_with("[5.0, 5.0, 5.0]", "[5.0, 1e30, 5.0]", PLANE),
        ),
        (
            "scene_nan_light_position",
            head_with(
                "position = [0.0, 3.0, 0.0]",
                "position = [0.0, nan, 0.0]",
                PLANE,
            ),
        ),
        (
            "scene_nan_material_parameter",
            head_with("[0.5, 0.5, 0.5]", "[0.5, nan, 0.5]", PLANE),
        ),
        (
            "scene_albedo_above_one",
            head_with("[0.5, 0.5, 0.5]", "[0.5, 1.5, 0.5]", PLANE),
        ),
        (
            "scene_zero_roughness",
            head_with(
                "model = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]",
                "model = \"cook_torrance\"\nspecular = [0.5, 0.5, 0.5]\nroughness = 0.0\ndistribution = \"ggx\"",
                PLANE,
            ),
        ),
        (
            "scene_negative_phong_exponent",
            head_with(
                "model = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]",
                "model = \"phong\"\nspecular = [0.5, 0.5, 0.5]\nexponent = -1.0",
                PLANE,
            ),
        ),
        (
            "scene_absurd_fov",
            head_with("fov_y = 40.0", "fov_y = 400.0", PLANE),
        ),
        (
            "scene_zero_resolution",
            head_with("height = 12", "height = 0", PLANE),
        ),
        (
            "scene_absurd_resolution",
            head_with("width = 16", "width = 100000", PLANE),
        ),
        (
            "scene_resolution_beyond_u32",
            head_with("width = 16", "width = 99999999999", PLANE),
        ),
        (
            "scene_camera_looks_at_itself",
            head_with(
                "look_at = [0.0, 0.0, 0.0]",
                "look_at = [0.0, 2.0, 4.0]",
                PLANE,
            ),
        ),
        (
            "scene_undefined_material",
            format!("{GOOD_HEAD}{}", PLANE.replace("\"white\"", "\"whte\"")),
        ),
        (
            "scene_negative_shape_size",
            format!("{GOOD_HEAD}{}", PLANE.replace("[4.0, 4.0]", "[4.0, -4.0]")),
        ),
        (
            "scene_zero_scale",
            format!("{GOOD_HEAD}{PLANE}transform = {{ scale = 0.0 }}\n"),
        ),
        (
            "scene_object_scaled_beyond_the_coordinate_limit",
            format!("{GOOD_HEAD}{PLANE}transform = {{ scale = 1e25 }}\n"),
        ),
        (
            "scene_camera_beyond_the_coordinate_limit",
            head_with(
                "position = [0.0, 2.0, 4.0]",
                "position = [0.0, 2.0, 1e30]",
                PLANE,
            ),
        ),
        (
            "scene_absurd_subdivisions",
            format!(
                "{GOOD_HEAD}{}",
                PLANE.replace(
                    "size = [4.0, 4.0]",
                    "size = [4.0, 4.0], subdivisions = 1000000"
                )
            ),
        ),
        ("scene_no_objects", GOOD_HEAD.to_string()),
        (
            "scene_spp_zero",
            format!("{GOOD_HEAD}{PLANE}\n[render]\nspp = 0\n"),
        ),
        (
            "scene_spp_above_limit",
            format!("{GOOD_HEAD}{PLANE}\n[render]\nspp = 2000000\n"),
        ),
        (
            "scene_negative_seed",
            format!("{GOOD_HEAD}{PLANE}\n[render]\nseed = -1\n"),
        ),
    ];
    for (name, body) in table {
        Case::render(name, &body, Expect::Refused);
    }
}

// ---------------------------------------------------------------------------------------------
// Mesh files.

/// `GOOD_HEAD`, a plane and an object `m` made of the mesh `file`.
fn mesh_scene(file: &str) -> String {
    format!(
        "{GOOD_HEAD}{PLANE}\n[[objects]]\nname = \"m\"\nmaterial = \"white\"\nshape = {{ type = \"mesh\", file = \"{file}\" }}\n"
    )
}

const PLY_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

/// Renders a scene with the mesh `file` holding `bytes`.
fn mesh_case(name: &str, file: &str, bytes: &[u8], expect: Expect) {
    let c = Case::new();
    c.file(file, bytes);
    c.scene(&mesh_scene(file)).check(name, RENDER, expect);
}

#[test]
fn mesh_files() {
    Case::new().scene(&mesh_scene("models/missing.ply")).check(
        "mesh_missing_file",
        RENDER,
        Expect::Refused,
    );
    let c = Case::new();
    std::fs::create_dir_all(c.path("models/bunny.ply")).unwrap();
    c.scene(&mesh_scene("models/bunny.ply"))
        .check("mesh_is_a_directory", RENDER, Expect::Refused);
    Case::new()
        .scene(&mesh_scene(""))
        .check("mesh_empty_file_name", RENDER, Expect::Refused);

    // A binary PLY of 200k vertices and 400k (degenerate) faces, 7.6 MB: with a 32 MiB budget it
    // is refused from its header, before it is loaded, naming the mesh's field.
    let c = Case::new();
    let mut big = PLY_HEAD
        .replace("ascii", "binary_little_endian")
        .replace("vertex 3", "vertex 200000")
        .replace("face 1", "face 400000")
        .into_bytes();
    big.resize(big.len() + 200_000 * 12, 0);
    for _ in 0..400_000 {
        big.extend_from_slice(&[3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    }
    c.file("models/big.ply", &big);
    let mut args = RENDER.to_vec();
    args.extend_from_slice(&["--memory-budget", "32MiB"]);
    c.scene(&mesh_scene("models/big.ply")).check(
        "mesh_over_the_memory_budget",
        &args,
        Expect::Refused,
    );

    let mut binary = PLY_HEAD
        .replace("ascii", "binary_little_endian")
        .into_bytes();
    binary.extend_from_slice(&[0u8; 20]); // 3 vertices need 36 bytes
    let gltf_missing_bin = r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"gone.bin","byteLength":36}],
      "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
      "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#;
    let refused: [(&str, &str, Vec<u8>); 16] = [
        (
            "mesh_ply_truncated",
            "m.ply",
            format!("{PLY_HEAD}0 0 0\n1 0 0\n").into_bytes(),
        ),
        ("mesh_ply_truncated_binary", "m.ply", binary),
        (
            "mesh_ply_face_index_out_of_range",
            "m.ply",
            format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").into_bytes(),
        ),
        (
            "mesh_ply_nan_coordinate",
            "m.ply",
            format!("{PLY_HEAD}0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").into_bytes(),
        ),
        (
            "mesh_ply_huge_face_count",
            "m.ply",
            format!(
                "{}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
                PLY_HEAD.replace("element face 1", "element face 4000000000")
            )
            .into_bytes(),
        ),
        (
            "mesh_ply_huge_vertex_count_binary",
            "m.ply",
            PLY_HEAD
                .replace("ascii", "binary_little_endian")
                .replace("element vertex 3", "element vertex 4000000000")
                .into_bytes(),
        ),
        (
            "mesh_ply_bad_magic",
            "m.ply",
            b"plyx\nformat ascii 1.0\nend_header\n".to_vec(),
        ),
        (
            "mesh_corrupt_gzip",
            "m.ply.gz",
            b"\x1f\x8b\x08\x00garbage-not-deflate".to_vec(),
        ),
        (
            "mesh_obj_missing_vertex",
            "m.obj",
            b"v 0 0 0\nv 1 0 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "mesh_obj_face_index_zero",
            "m.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n".to_vec(),
        ),
        (
            "mesh_obj_nan_coordinate",
            "m.obj",
            b"v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "mesh_obj_overflowing_coordinate",
            "m.obj",
            b"v 0 0 0\nv 1 1e39 0\nv 0 1 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "mesh_obj_coordinate_beyond_the_limit",
            "m.obj",
            b"v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nf 1 2 3\n".to_vec(),
        ),
        (
            "mesh_gltf_missing_bin",
            "m.gltf",
            gltf_missing_bin.as_bytes().to_vec(),
        ),
        (
            "mesh_unknown_extension",
            "m.stl",
            b"solid x\nendsolid x\n".to_vec(),
        ),
        (
            "mesh_all_triangles_degenerate",
            "m.ply",
            format!("{PLY_HEAD}0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n").into_bytes(),
        ),
    ];
    for (name, file, bytes) in refused {
        mesh_case(name, file, &bytes, Expect::Refused);
    }
    // Zero-area and duplicate triangles are removed with a warning; the rest renders.
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n0 0.5 0\n1 0.5 0\n0 0.5 1\n2 0.5 0\n3 0 1 2\n3 0 2 1\n3 0 1 3\n";
    mesh_case(
        "warn_mesh_zero_area_and_duplicate_triangles",
        "m.ply",
        ply.as_bytes(),
        Expect::Warned("out.exr"),
    );
}

#[test]
fn camera_inside_geometry_is_warned() {
    Case::render(
        "warn_camera_inside_geometry",
        &format!(
            "{GOOD_HEAD}{PLANE}\n[[objects]]\nname = \"cage\"\nmaterial = \"white\"\nshape = {{ type = \"box\", size = [20.0, 20.0, 20.0] }}\n"
        ),
        Expect::Warned("out.exr"),
    );
}

#[test]
fn no_lights_is_warned() {
    let body = head_with(
        "[[lights]]\ntype = \"point\"\nposition = [0.0, 3.0, 0.0]\nintensity = [5.0, 5.0, 5.0]\n",
        "",
        PLANE,
    );
    Case::render("warn_no_lights", &body, Expect::Warned("out.exr"));
}

// ---------------------------------------------------------------------------------------------
// Environment maps.

/// A valid 8 × 4 environment map `env.exr` in the case's directory.
fn env_map(c: &Case, name: &str) {
    use glam::Vec3;
    use interreflect::image::{Image, write_exr};
    let img = Image::from_fn(8, 4, |x, y| {
        Vec3::new(0.5 + x as f32 * 0.1, 0.5, 0.2 * y as f32)
    });
    write_exr(&c.path(name), &img).unwrap();
}

/// An 8 × 4 EXR written with the `exr` crate directly (the project's writer refuses NaN and ∞),
/// radiance 1 but for texel (3, 2), which is `bad`.
fn raw_exr(c: &Case, name: &str, bad: f32) {
    exr::prelude::write_rgb_file(c.path(name), 8, 4, |x, y| {
        if (x, y) == (3, 2) {
            (1.0f32, bad, 1.0f32)
        } else {
            (1.0, 1.0, 1.0)
        }
    })
    .unwrap();
}

fn env_scene(table: &str) -> String {
    format!("{GOOD_HEAD}{PLANE}\n[environment]\n{table}\n")
}

#[test]
fn environment_maps() {
    // (name, the [environment] table, the files beside the scene)
    type Setup = fn(&Case);
    let none: Setup = |_| {};
    let refused: [(&str, &str, Setup); 17] = [
        ("env_missing_file", "file = \"envmaps/missing.exr\"", none),
        ("env_file_name_empty", "file = \"\"", none),
        ("env_no_file_field", "rotation = 10.0", none),
        ("env_garbage_exr", "file = \"broken.exr\"", |c| {
            c.file("broken.exr", b"\x76\x2f\x31\x01 this is not an EXR");
        }),
        ("env_truncated_exr", "file = \"cut.exr\"", |c| {
            env_map(c, "whole.exr");
            let bytes = std::fs::read(c.path("whole.exr")).unwrap();
            std::fs::remove_file(c.path("whole.exr")).unwrap();
            c.file("cut.exr", &bytes[..bytes.len() / 2]);
        }),
        ("env_nan_texel", "file = \"nan.exr\"", |c| {
            raw_exr(c, "nan.exr", f32::NAN)
        }),
        ("env_infinite_texel", "file = \"inf.exr\"", |c| {
            raw_exr(c, "inf.exr", f32::INFINITY)
        }),
        ("env_negative_texel", "file = \"negative.exr\"", |c| {
            raw_exr(c, "negative.exr", -0.5)
        }),
        ("env_hdr_truncated_pixels", "file = \"broken.hdr\"", |c| {
            c.file(
                "broken.hdr",
                b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n\x02\x02",
            );
        }),
        ("env_hdr_bad_magic", "file = \"bad.hdr\"", |c| {
            c.file(
                "bad.hdr",
                b"RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n",
            );
        }),
        ("env_hdr_unsupported_format", "file = \"xyz.hdr\"", |c| {
            c.file(
                "xyz.hdr",
                b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 4 +X 8\n",
            );
        }),
        ("env_hdr_bad_resolution_line", "file = \"res.hdr\"", |c| {
            c.file(
                "res.hdr",
                b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y four +X 8\n",
            );
        }),
        (
            "env_scaled_radiance_beyond_the_limit",
            "file = \"bright.exr\"\nintensity = 1e10",
            |c| raw_exr(c, "bright.exr", 1e15),
        ),
        ("env_png_extension", "file = \"env.png\"", |c| {
            c.file("env.png", b"\x89PNG");
        }),
        (
            "env_negative_intensity",
            "file = \"env.exr\"\nintensity = -1.0",
            |c| env_map(c, "env.exr"),
        ),
        (
            "env_nan_rotation",
            "file = \"env.exr\"\nrotation = nan",
            |c| env_map(c, "env.exr"),
        ),
        (
            "env_unknown_field",
            "file = \"env.exr\"\nrotaton = 90.0",
            |c| env_map(c, "env.exr"),
        ),
    ];
    for (name, table, setup) in refused {
        let c = Case::new();
        setup(&c);
        c.scene(&env_scene(table))
            .check(name, RENDER, Expect::Refused);
    }

    // The reference needs BRDF samples to find the environment's one-bounce light.
    let c = Case::new();
    env_map(&c, "env.exr");
    c.scene(&format!(
        "{GOOD_HEAD}{PLANE}\n[environment]\nfile = \"env.exr\"\n[methods.reference]\nbsdf_samples = 0\n"
    ))
    .check("env_needs_bsdf_samples", RENDER, Expect::Refused);

    // A 1 × 1 map is a constant sky: it renders, with the warning that it is not 2:1.
    let c = Case::new();
    interreflect::image::write_exr(
        &c.path("tiny.exr"),
        &interreflect::image::Image::from_fn(1, 1, |_, _| glam::Vec3::splat(0.7)),
    )
    .unwrap();
    c.scene(&env_scene("file = \"tiny.exr\"")).check(
        "warn_env_one_by_one",
        RENDER,
        Expect::Warned("out.exr"),
    );

    // A square map renders with the same warning.
    let c = Case::new();
    interreflect::image::write_exr(
        &c.path("square.exr"),
        &interreflect::image::Image::from_fn(4, 4, |_, _| glam::Vec3::ONE),
    )
    .unwrap();
    c.scene(&env_scene("file = \"square.exr\"")).check(
        "warn_env_not_two_to_one",
        RENDER,
        Expect::Warned("out.exr"),
    );

    // A black map lights nothing: a warning.
    let c = Case::new();
    env_map(&c, "env.exr");
    c.scene(&env_scene("file = \"env.exr\"\nintensity = 0.0"))
        .check("warn_env_black", RENDER, Expect::Warned("out.exr"));

    // sg ignores the environment: a warning says so.
    let c = Case::new();
    env_map(&c, "env.exr");
    c.scene(&env_scene("file = \"env.exr\"")).check(
        "warn_env_ignored_by_sg",
        &[
            "render",
            "<dir>/scene.toml",
            "--quiet",
            "--method",
            "sg",
            "--visibility",
            "exact",
            "--output",
            "<dir>/out.exr",
        ],
        Expect::Warned("out.exr"),
    );

    // A valid map renders without a word.
    let c = Case::new();
    env_map(&c, "env.exr");
    c.scene(&env_scene(
        "file = \"env.exr\"\nrotation = 30.0\nintensity = 2.0",
    ))
    .check(
        "env_valid_renders_silently",
        RENDER,
        Expect::Rendered("out.exr"),
    );
}

// ---------------------------------------------------------------------------------------------
// Method settings in the scene file.

#[test]
fn method_settings() {
    let tables: [(&str, &str, &str); 41] = [
        (
            "vpl_clamp_distance_negative",
            "methods.vpl",
            "clamp_distance = -0.5",
        ),
        (
            "vpl_clamp_distance_nan",
            "methods.vpl",
            "clamp_distance = nan",
        ),
        ("vpl_spp_zero", "methods.vpl", "spp = 0"),
        ("vpl_unknown_field", "methods.vpl", "clamp = 0.1"),
        (
            "vis_shadow_map_too_small",
            "visibility",
            "shadow_map_resolution = 8",
        ),
        (
            "vis_shadow_map_too_large",
            "visibility",
            "shadow_map_resolution = 100000",
        ),
        ("vis_vsm_blur_too_large", "visibility", "vsm_blur = 99"),
        (
            "vis_light_bleeding_one",
            "visibility",
            "light_bleeding = 1.0",
        ),
        (
            "vis_light_bleeding_negative",
            "visibility",
            "light_bleeding = -0.1",
        ),
        (
            "vis_light_bleeding_nan",
            "visibility",
            "light_bleeding = nan",
        ),
        ("vis_unknown_field", "visibility", "shadowmap = 512"),
        ("vis_vpl_count_zero", "visibility", "vpl_count = 0"),
        (
            "vis_ism_resolution_too_small",
            "visibility",
            "ism_resolution = 2",
        ),
        ("vis_ism_points_zero", "visibility", "ism_points = 0"),
        ("vis_ism_bias_negative", "visibility", "ism_bias = -1"),
        ("vis_ism_bias_infinite", "visibility", "ism_bias = inf"),
        (
            "vis_node_maps_too_many",
            "visibility",
            "node_maps = 1000000",
        ),
        ("sg_threshold_negative", "methods.sg", "threshold = -0.5"),
        ("sg_threshold_nan", "methods.sg", "threshold = nan"),
        ("sg_max_cut_too_large", "methods.sg", "max_cut = 100000000"),
        ("sg_max_edge_negative", "methods.sg", "max_edge = -1.0"),
        ("sg_spp_zero", "methods.sg", "spp = 0"),
        ("sg_spp_above_limit", "methods.sg", "spp = 2000000"),
        ("sg_unknown_cut_mode", "methods.sg", "cut = \"node\""),
        ("sg_unknown_field", "methods.sg", "treshold = 0.1"),
        (
            "ref_reflector_samples_too_many",
            "methods.reference",
            "reflector_samples = 65",
        ),
        (
            "ref_all_strategies_off",
            "methods.reference",
            "reflector_samples = 0\nbsdf_samples = 0\nlight_paths = 0",
        ),
        ("prt_order_zero", "methods.prt", "order = 0"),
        ("prt_order_too_high", "methods.prt", "order = 17"),
        ("prt_order_not_an_integer", "methods.prt", "order = 2.5"),
        ("prt_bounces_too_many", "methods.prt", "bounces = 9"),
        ("prt_samples_zero", "methods.prt", "samples = 0"),
        ("prt_samples_too_many", "methods.prt", "samples = 100000000"),
        (
            "prt_window_width_negative",
            "methods.prt",
            "window_width = -1.0",
        ),
        ("prt_window_width_nan", "methods.prt", "window_width = nan"),
        (
            "prt_window_width_too_large",
            "methods.prt",
            "window_width = 1000.0",
        ),
        ("prt_spp_zero", "methods.prt", "spp = 0"),
        ("prt_spp_above_limit", "methods.prt", "spp = 2000000"),
        (
            "prt_unknown_transfer",
            "methods.prt",
            "transfer = \"glossy\"",
        ),
        ("prt_unknown_window", "methods.prt", "window = \"hamming\""),
        ("prt_unknown_field", "methods.prt", "oder = 3"),
    ];
    for (name, table, body) in tables {
        Case::render(
            name,
            &format!("{GOOD_HEAD}{PLANE}\n[{table}]\n{body}\n"),
            Expect::Refused,
        );
    }
}

/// prt relights distant light only: with nothing but a point light the image is black, and it
/// says so (status 0). On the CPU (`--device cpu`): no GPU is needed, and no adapter message
/// enters the snapshot.
#[test]
fn prt_with_point_lights_only_is_warned() {
    Case::new().scene(&format!("{GOOD_HEAD}{PLANE}")).check(
        "warn_prt_point_lights_only",
        &[
            "render",
            "<dir>/scene.toml",
            "--quiet",
            "--method",
            "prt",
            "--device",
            "cpu",
            "--no-cache",
            "--output",
            "<dir>/out.exr",
        ],
        Expect::Warned("out.exr"),
    );
}

// ---------------------------------------------------------------------------------------------
// Command-line arguments.

#[test]
fn output_paths() {
    let good = format!("{GOOD_HEAD}{PLANE}");
    let render_to = |out: &'static str| -> Vec<&'static str> {
        vec![
            "render",
            "<dir>/scene.toml",
            "--spp",
            "1",
            "--quiet",
            "--output",
            out,
        ]
    };
    Case::new().scene(&good).check(
        "out_over_the_scene_file",
        &render_to("<dir>/scene.toml"),
        Expect::Refused,
    );
    // A mesh can never be named by an .exr output, nor by its .png or .json sibling.
    let c = Case::new();
    c.file("m.ply", format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    c.scene(&mesh_scene("m.ply")).check(
        "out_over_the_mesh_file",
        &render_to("<dir>/m.ply"),
        Expect::Refused,
    );
    let c = Case::new();
    env_map(&c, "env.exr");
    c.scene(&env_scene("file = \"env.exr\"")).check(
        "out_over_the_environment_map",
        &render_to("<dir>/env.exr"),
        Expect::Refused,
    );
    // The .json log written beside the output would replace the scene file.
    let c = Case::new();
    c.file("render.json", &good);
    c.check(
        "out_json_sibling_over_the_scene_file",
        &[
            "render",
            "<dir>/render.json",
            "--spp",
            "1",
            "--quiet",
            "--output",
            "<dir>/render.exr",
        ],
        Expect::Refused,
    );
    let c = Case::new();
    std::fs::create_dir(c.path("out.png")).unwrap();
    c.scene(&good).check(
        "out_png_sibling_is_a_directory",
        &render_to("<dir>/out.exr"),
        Expect::Refused,
    );
    let c = Case::new();
    std::fs::create_dir(c.path("out.exr")).unwrap();
    c.scene(&good).check(
        "out_is_a_directory",
        &render_to("<dir>/out.exr"),
        Expect::Refused,
    );
    Case::new().scene(&good).check(
        "out_under_a_file",
        &render_to("<dir>/scene.toml/renders/out.exr"),
        Expect::Refused,
    );
    // Missing directories of the output are created (documented in docs/images-and-metrics.md).
    Case::new().scene(&good).check(
        "out_into_a_missing_directory_creates_it",
        &render_to("<dir>/new/renders/out.exr"),
        Expect::Rendered("new/renders/out.exr"),
    );
    Case::new()
        .scene(&good)
        .check("out_not_exr", &render_to("<dir>/out.png"), Expect::Refused);
}

#[test]
fn command_line_arguments() {
    let cases: [(&str, &[&str]); 36] = [
        ("cli_unknown_flag", &["--frobnicate"]),
        ("cli_unknown_flag_close_to_a_known_one", &["--thread", "2"]),
        ("cli_flag_without_value", &["--spp"]),
        ("cli_spp_not_a_number", &["--spp", "many"]),
        ("cli_spp_zero", &["--spp", "0"]),
        ("cli_spp_above_limit", &["--spp", "2000000"]),
        ("cli_spp_negative", &["--spp", "-1"]),
        ("cli_threads_zero", &["--threads", "0"]),
        ("cli_width_zero", &["--width", "0"]),
        ("cli_width_absurd", &["--width", "100000"]),
        ("cli_unknown_method", &["--method", "radiosity"]),
        (
            "cli_direct_indirect_only",
            &["--method", "direct", "--indirect-only"],
        ),
        (
            "cli_sg_threshold_above_one",
            &["--method", "sg", "--threshold", "2"],
        ),
        (
            "cli_sg_threshold_nan",
            &["--method", "sg", "--threshold", "NaN"],
        ),
        (
            "cli_sg_max_edge_negative",
            &["--method", "sg", "--max-edge", "-1"],
        ),
        (
            "cli_sg_unknown_cut",
            &["--method", "sg", "--cut", "triangle"],
        ),
        (
            "cli_sg_unknown_visibility",
            &["--method", "sg", "--visibility", "rays"],
        ),
        ("cli_prt_order_zero", &["--method", "prt", "--order", "0"]),
        (
            "cli_prt_order_too_high",
            &["--method", "prt", "--order", "40"],
        ),
        (
            "cli_prt_bounces_too_many",
            &["--method", "prt", "--bounces", "99"],
        ),
        (
            "cli_prt_indirect_only_without_bounces",
            &["--method", "prt", "--bounces", "0", "--indirect-only"],
        ),
        (
            "cli_prt_rotate_lighting_nan",
            &["--method", "prt", "--rotate-lighting", "NaN"],
        ),
        (
            "cli_prt_unknown_transfer",
            &["--method", "prt", "--transfer", "glossy"],
        ),
        (
            "cli_prt_unknown_device",
            &["--method", "prt", "--device", "tpu"],
        ),
        (
            "cli_prt_window_width_negative",
            &["--method", "prt", "--window-width", "-2"],
        ),
        (
            "cli_prt_window_width_nan",
            &["--method", "prt", "--window-width", "nan"],
        ),
        (
            "cli_prt_unknown_window",
            &["--method", "prt", "--window", "hamming"],
        ),
        ("cli_exposure_nan", &["--exposure", "nan"]),
        // The scene (a plane and a light) needs about 20 MiB: refused before loading.
        ("cli_memory_budget_exceeded", &["--memory-budget", "1MiB"]),
        ("cli_memory_budget_not_a_size", &["--memory-budget", "lots"]),
        (
            "cli_memory_budget_unknown_unit",
            &["--memory-budget", "4parsecs"],
        ),
        ("cli_memory_budget_zero", &["--memory-budget", "0"]),
        ("cli_vpls_zero", &["--method", "vpl", "--vpls", "0"]),
        (
            "cli_node_maps_too_many",
            &[
                "--method",
                "sg",
                "--visibility",
                "approx",
                "--node-maps",
                "200000",
            ],
        ),
        (
            "cli_vpl_clamp_distance_negative",
            &["--method", "vpl", "--clamp-distance", "-1"],
        ),
        (
            "cli_vpl_clamp_distance_nan",
            &["--method", "vpl", "--clamp-distance", "nan"],
        ),
    ];
    for (name, extra) in cases {
        let mut args = vec![
            "render",
            "<dir>/scene.toml",
            "--quiet",
            "--output",
            "<dir>/out.exr",
        ];
        args.extend_from_slice(extra);
        // prt runs on the CPU here: a case must not depend on whether a GPU exists.
        if extra.contains(&"prt") && !extra.contains(&"--device") {
            args.extend_from_slice(&["--device", "cpu", "--no-cache"]);
        }
        Case::new()
            .scene(&format!("{GOOD_HEAD}{PLANE}"))
            .check(name, &args, Expect::Refused);
    }
    // Malformed command lines, before any scene is read. (No subcommand at all prints the whole
    // help, which every new subcommand changes: not snapshotted.)
    for (name, args) in [
        ("cli_unknown_subcommand", &["draw", "<dir>/scene.toml"][..]),
        ("cli_render_without_scene", &["render", "--quiet"][..]),
    ] {
        Case::new().check(name, args, Expect::Refused);
    }
}
