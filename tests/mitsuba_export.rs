//! `interreflect export-mitsuba` through the binary: exports `scenes/ring.toml` into a temporary
//! directory and checks the files, the XML (well-formed, every referenced file present, the
//! geometry's triangle count) and the messages; bad input exits with status 2 and writes nothing.

use interreflect::export::xml::parse;
use std::path::Path;
use std::process::Command;

fn export(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_interreflect"))
        .arg("export-mitsuba")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

#[test]
fn ring_exports_to_a_well_formed_mitsuba_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ring");
    let o = export(&["scenes/ring.toml", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{stderr}");
    // The gold Cook-Torrance GGX material is approximate (masking), the Lambert floor exact.
    assert!(
        stderr.contains("warning: scenes/ring.toml: materials.gold: approximate"),
        "{stderr}"
    );
    assert!(!stderr.contains("materials.floor"), "{stderr}");
    assert!(stderr.contains("10240 triangles"), "{stderr}");

    let xml = std::fs::read_to_string(out.join("scene.xml")).unwrap();
    let root = parse(&xml).unwrap_or_else(|e| panic!("scene.xml is not well-formed: {e}"));
    assert_eq!(root.tag, "scene");
    assert_eq!(root.get("version"), Some("3.0.0"));
    let mut triangles = 0;
    let shapes: Vec<_> = root.children_named("shape").collect();
    assert_eq!(shapes.len(), 2);
    for s in shapes {
        let file = s
            .property("string", "filename")
            .unwrap()
            .get("value")
            .unwrap();
        let bytes = std::fs::read(out.join(file)).unwrap();
        let mesh = interreflect::scene::mesh::parse_mesh_bytes(&bytes, file).unwrap();
        triangles += mesh.indices.len();
        assert!(mesh.normals.is_some(), "{file} has no normals");
    }
    // The ring (8 × 256 segments) and the floor (2 × 64²): the triangles the renderer loads.
    assert_eq!(triangles, 8 * 256 + 2 * 64 * 64);
    let emitter = root.children_named("emitter").next().unwrap();
    assert_eq!(emitter.get("type"), Some("point"));
    let sensor = root.children_named("sensor").next().unwrap();
    assert_eq!(
        sensor.property("float", "fov").unwrap().get("value"),
        Some("38")
    );
    // Nothing else beside the export.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 1);
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let o = export(&["scenes/no-such-scene.toml", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("scenes/no-such-scene.toml"), "{stderr}");
    assert!(!out.exists());

    // A non-empty directory that is not a previous export.
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "mine").unwrap();
    let o = export(&["scenes/ring.toml", out.to_str().unwrap(), "--force"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no scene.xml"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(out.join("keep.txt")).unwrap(),
        "mine"
    );
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);

    // The scene's own directory (it holds the scene file) is refused, even with --force.
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let o = export(&["scenes/ring.toml", scenes.to_str().unwrap(), "--force"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("holds the scene's input"), "{stderr}");
}
