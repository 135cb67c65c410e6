//! The bodies of the fuzz targets, shared with the regression test `tests/fuzz_regressions.rs`
//! (which includes this file with `#[path]`), so a stored crash input is replayed through
//! exactly the code the fuzzer ran.
//!
//! Each function takes the raw input and returns `Ok(())` when it was accepted or `Err(message)`
//! with the library's error message when it was refused. It panics (a fuzzer crash) when the
//! library panics, or when an accepted result breaks an invariant the rest of the renderer
//! relies on (indices in range, finite positions, unit normals, ...), or when an error message
//! does not name the input.

#![allow(dead_code)] // each fuzz target uses one function

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use glam::{Vec2, Vec3};
use interreflect::scene::Scene;
use interreflect::scene::environment::{Environment, read_latlong_bytes};
use interreflect::scene::mesh::{MeshData, clean_mesh, parse_mesh_bytes};

/// The error message, checked to be non-empty and to name `name` (the file or label).
fn message(e: impl std::fmt::Display, name: &str) -> String {
    let msg = e.to_string();
    assert!(!msg.trim().is_empty(), "empty error message");
    assert!(
        msg.contains(name),
        "error message does not name {name:?}: {msg}"
    );
    msg
}

/// Indices in range, finite positions, normals (if any) one per position.
fn check_mesh(mesh: &MeshData) {
    let n = mesh.positions.len();
    assert!(n > 0 && !mesh.indices.is_empty(), "accepted an empty mesh");
    assert!(
        mesh.positions.iter().all(|p| p.is_finite()),
        "non-finite position accepted"
    );
    if let Some(normals) = &mesh.normals {
        assert_eq!(normals.len(), n, "normals and positions differ in number");
    }
    for t in &mesh.indices {
        assert!(
            t.iter().all(|&i| (i as usize) < n),
            "index out of range: {t:?} of {n}"
        );
    }
}

/// What `clean_mesh` promises: a valid mesh with unit normals, no unused vertices.
fn check_clean(before: usize, mesh: &MeshData, removed: usize) {
    check_mesh(mesh);
    assert_eq!(
        mesh.indices.len() + removed,
        before,
        "triangle count does not add up"
    );
    let normals = mesh
        .normals
        .as_ref()
        .expect("clean_mesh always returns normals");
    for n in normals {
        assert!(
            (n.length() - 1.0).abs() < 1e-3,
            "normal {n} is not unit length"
        );
    }
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.indices {
        for &i in t {
            used[i as usize] = true;
        }
    }
    assert!(used.iter().all(|&u| u), "unused vertex left after cleaning");
}

/// A mesh file through `parse_mesh_bytes` and then `clean_mesh`, as the scene loader does.
fn mesh_file(data: &[u8], name: &str) -> Result<(), String> {
    let mesh = parse_mesh_bytes(data, name).map_err(|e| message(e, name))?;
    check_mesh(&mesh);
    let before = mesh.indices.len();
    let (clean, report) = clean_mesh(mesh, name).map_err(|e| message(e, name))?;
    check_clean(
        before,
        &clean,
        report.removed_degenerate + report.removed_duplicate,
    );
    Ok(())
}

/// PLY (ASCII, binary little/big-endian; gzip-compressed data is detected by its signature).
pub fn ply(data: &[u8]) -> Result<(), String> {
    mesh_file(data, "fuzz.ply")
}

/// Wavefront OBJ.
pub fn obj(data: &[u8]) -> Result<(), String> {
    mesh_file(data, "fuzz.obj")
}

/// glTF: a GLB container (starts with `glTF`) or a JSON `.gltf` with embedded buffers.
pub fn gltf(data: &[u8]) -> Result<(), String> {
    let name = if data.starts_with(b"glTF") {
        "fuzz.glb"
    } else {
        "fuzz.gltf"
    };
    mesh_file(data, name)
}

/// Reads `n` values of 3 numbers: small integers (1 byte each, so duplicates and degenerate
/// triangles are common) or raw little-endian f32 (NaN, infinities, huge and tiny values).
fn vec3s(data: &mut &[u8], n: usize, small: bool) -> Vec<Vec3> {
    let mut out = Vec::new();
    for _ in 0..n {
        let v = if small {
            let Some((b, rest)) = data.split_first_chunk::<3>() else {
                break;
            };
            *data = rest;
            Vec3::new(b[0] as i8 as f32, b[1] as i8 as f32, b[2] as i8 as f32)
        } else {
            let Some((b, rest)) = data.split_first_chunk::<12>() else {
                break;
            };
            *data = rest;
            let f = |k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
            Vec3::new(f(0), f(4), f(8))
        };
        out.push(v);
    }
    out
}

/// `clean_mesh` on arbitrary mesh data: byte 0 holds flags (bit 0: normals, bit 1: f32
/// coordinates rather than small integers), byte 1 the vertex count, then positions, normals,
/// and triangles as three bytes each (indices may be out of range).
pub fn mesh_clean(data: &[u8]) -> Result<(), String> {
    let [flags, count, rest @ ..] = data else {
        return Ok(());
    };
    let mut rest = rest;
    let small = flags & 2 == 0;
    let positions = vec3s(&mut rest, *count as usize, small);
    let normals = (flags & 1 != 0).then(|| vec3s(&mut rest, positions.len(), small));
    let indices: Vec<[u32; 3]> = rest
        .chunks_exact(3)
        .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
        .collect();
    let mesh = MeshData {
        positions,
        normals,
        indices,
    };
    let before = mesh.indices.len();
    let (clean, report) = clean_mesh(mesh, "fuzz-mesh").map_err(|e| message(e, "fuzz-mesh"))?;
    check_clean(
        before,
        &clean,
        report.removed_degenerate + report.removed_duplicate,
    );
    Ok(())
}

/// An empty directory of this process: scene files "live" there, so every mesh or environment
/// map they name is a missing file (no file system content is ever read).
fn empty_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("interreflect-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("cannot create the fuzzing directory");
        dir
    })
}

/// A scene file through `Scene::from_str_at`, then the invariants of the merged scene mesh.
pub fn scene_toml(data: &[u8]) -> Result<(), String> {
    let Ok(text) = std::str::from_utf8(data) else {
        return Ok(()); // scene files are read as UTF-8 text: nothing to test
    };
    let path = empty_dir().join("fuzz.toml");
    let scene = Scene::from_str_at(text, &path).map_err(|e| message(e, "fuzz.toml"))?;
    let m = &scene.mesh;
    let n = m.positions.len();
    assert_eq!(m.normals.len(), n);
    assert_eq!(m.tri_object.len(), m.indices.len());
    assert!(
        m.positions.iter().all(|p| p.is_finite()),
        "non-finite scene position"
    );
    assert!(
        m.normals.iter().all(|p| p.is_finite()),
        "non-finite scene normal"
    );
    for t in &m.indices {
        assert!(
            t.iter().all(|&i| (i as usize) < n),
            "scene index out of range"
        );
    }
    let mut next = 0u64;
    for o in &scene.objects {
        assert_eq!(
            u64::from(o.first_tri),
            next,
            "object triangle ranges not contiguous"
        );
        next += u64::from(o.tri_count);
        assert!((o.material as usize) < scene.materials.len());
    }
    assert_eq!(next, m.indices.len() as u64);
    Ok(())
}

/// An environment map (through the size check of `read_latlong_bytes`), then the sampling
/// distribution `Environment::from_image` builds and a few samples of it.
fn envmap(data: &[u8], name: &str) -> Result<(), String> {
    let img = read_latlong_bytes(data, name).map_err(|e| message(e, name))?;
    assert!(
        img.has_consistent_size(),
        "image buffer does not match its size"
    );
    assert!(img.width > 0 && img.height > 0, "empty image accepted");
    let env = Environment::from_image(img, 30.0, 1.0)
        .map_err(|e| message(format!("{name}: {e}"), name))?;
    for u in [
        Vec2::new(0.1, 0.2),
        Vec2::new(0.999, 0.5),
        Vec2::new(0.0, 0.0),
    ] {
        if let Some((d, pdf)) = env.sample(u) {
            assert!(
                d.is_finite() && pdf.is_finite() && pdf > 0.0,
                "bad sample {d} {pdf}"
            );
            assert!(env.pdf(d).is_finite());
            assert!(env.radiance(d).is_finite());
        }
    }
    Ok(())
}

/// OpenEXR.
pub fn exr(data: &[u8]) -> Result<(), String> {
    envmap(data, "fuzz.exr")
}

/// Radiance RGBE.
pub fn hdr(data: &[u8]) -> Result<(), String> {
    envmap(data, "fuzz.hdr")
}
