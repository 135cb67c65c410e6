//! Tests for mesh loading, cleaning and writing.
//!
//! Every bad-input test asserts that the message names the file and the problem (and the line,
//! element or index where the loader knows it).

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::*;

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

fn write_file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// Loads `path` expecting an error; checks the message names the file and contains `needles`.
fn load_err(path: &Path, needles: &[&str]) -> MeshError {
    let err = match load_mesh(path) {
        Ok(m) => panic!(
            "{} loaded ({} triangles) but should have failed",
            path.display(),
            m.indices.len()
        ),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert!(
        msg.contains(&path.display().to_string()),
        "error does not name the file: {msg}"
    );
    for n in needles {
        assert!(
            msg.contains(n),
            "expected {n:?} in the error message: {msg}"
        );
    }
    err
}

fn assert_vec_close(a: Vec3, b: Vec3, tol: f32, what: &str) {
    assert!(
        (a - b).abs().max_element() <= tol,
        "{what}: {a} vs {b} (tolerance {tol})"
    );
}

/// A regular octahedron with outward (counter-clockwise) winding. Every vertex is shared by
/// four congruent triangles, so its area-weighted normal is exactly radial by symmetry.
fn octahedron() -> MeshData {
    let positions = vec![
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    let mut indices = Vec::new();
    for sx in [0u32, 1] {
        for sy in [2u32, 3] {
            for sz in [4u32, 5] {
                // Outward when the sign product is positive, else swap to keep it outward.
                let negatives = sx + (sy - 2) + (sz - 4);
                if negatives % 2 == 0 {
                    indices.push([sx, sy, sz]);
                } else {
                    indices.push([sx, sz, sy]);
                }
            }
        }
    }
    MeshData {
        positions,
        normals: None,
        indices,
    }
}

/// An icosphere: an icosahedron subdivided `levels` times, vertices projected on the unit sphere.
fn icosphere(levels: u32) -> MeshData {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from_array(*p).normalize())
    .collect();
    let mut indices: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::new();
        for [a, b, c] in indices {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        indices = next;
    }
    MeshData {
        positions,
        normals: None,
        indices,
    }
}

/// A `w × h` grid of vertices in the z = 0 plane, two triangles per cell.
fn grid(w: u32, h: u32) -> MeshData {
    let mut positions = Vec::new();
    for y in 0..h {
        for x in 0..w {
            positions.push(Vec3::new(x as f32, y as f32, 0.0));
        }
    }
    let mut indices = Vec::new();
    for y in 0..h - 1 {
        for x in 0..w - 1 {
            let i = y * w + x;
            indices.push([i, i + 1, i + w + 1]);
            indices.push([i, i + w + 1, i + w]);
        }
    }
    MeshData {
        positions,
        normals: None,
        indices,
    }
}

fn base64(bytes: &[u8]) -> String {
    const T: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

const TRI_POSITIONS: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// Binary buffer for one triangle: positions (36 bytes), normals (36 bytes), u16 indices
/// (6 bytes + 2 padding).
fn triangle_buffer() -> Vec<u8> {
    let mut bin = Vec::new();
    for p in TRI_POSITIONS {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for _ in 0..3 {
        for c in [0f32, 0.0, 1.0] {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin.extend_from_slice(&[0, 0]);
    bin
}

/// glTF JSON for one indexed triangle with normals, instanced by three nodes: node 0
/// (translated by +10 x) with child node 2 (uniform scale 2 via a matrix), and node 1 (mirrored
/// in x). `buffer` is the JSON of the single buffer object; `mode` the primitive mode.
fn triangle_gltf_json(buffer: &str, mode: u32) -> String {
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": [
    {{"mesh": 0, "translation": [10, 0, 0], "children": [2]}},
    {{"mesh": 0, "scale": [-1, 1, 1]}},
    {{"mesh": 0, "matrix": [2,0,0,0, 0,2,0,0, 0,0,2,0, 0,0,0,1]}}
  ],
  "meshes": [{{"name": "tri", "primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1}}, "indices": 2, "mode": {mode}}}]}}],
  "buffers": [{buffer}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 72, "byteStride": 12}},
    {{"buffer": 0, "byteOffset": 72, "byteLength": 6}}
  ],
  "accessors": [
    {{"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
    {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}
  ]
}}"#
    )
}

fn glb(json: &str, bin: Option<&[u8]>) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut body = Vec::new();
    body.extend_from_slice(&(j.len() as u32).to_le_bytes());
    body.extend_from_slice(b"JSON");
    body.extend_from_slice(&j);
    if let Some(bin) = bin {
        let mut b = bin.to_vec();
        while !b.len().is_multiple_of(4) {
            b.push(0);
        }
        body.extend_from_slice(&(b.len() as u32).to_le_bytes());
        body.extend_from_slice(b"BIN\0");
        body.extend_from_slice(&b);
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(12 + body.len() as u32).to_le_bytes());
    out.extend_from_slice(&body);
    out
}

/// Checks the merged three-instance triangle scene of [`triangle_gltf_json`].
fn check_triangle_scene(mesh: &MeshData) {
    let p = |v: [f32; 3]| Vec3::from_array(v);
    let expected: Vec<Vec3> = TRI_POSITIONS
        .iter()
        .map(|&v| p(v) + Vec3::new(10.0, 0.0, 0.0))
        .chain(
            TRI_POSITIONS
                .iter()
                .map(|&v| 2.0 * p(v) + Vec3::new(10.0, 0.0, 0.0)),
        )
        .chain(
            TRI_POSITIONS
                .iter()
                .map(|&v| p(v) * Vec3::new(-1.0, 1.0, 1.0)),
        )
        .collect();
    assert_eq!(mesh.positions.len(), 9);
    for (a, b) in mesh.positions.iter().zip(&expected) {
        // The transforms are exact in f32 (small integers, scale 2, sign flips).
        assert_eq!(a, b);
    }
    // Node traversal order: node 0, its child node 2, then node 1 (mirrored: winding flipped).
    assert_eq!(mesh.indices, vec![[0, 1, 2], [3, 4, 5], [6, 8, 7]]);
    let normals = mesh.normals.as_ref().expect("normals");
    for n in normals {
        // Inverse-transpose of a translation, uniform scale or mirror in x keeps +z exactly.
        assert_vec_close(*n, Vec3::Z, 1e-6, "transformed normal");
    }
    // Winding and normals agree everywhere, so cleaning repairs nothing.
    let (_, report) = clean_mesh(mesh.clone(), "gltf scene").unwrap();
    assert_eq!(report.repaired_normals, 0, "{:?}", report.warnings);
}

/// A binary PLY with `double` coordinates, an extra `uchar` property, `int` indices with a `uchar`
/// count, an extra face list property and an extra element, in the given byte order.
fn binary_ply(big_endian: bool, positions: &[[f64; 3]], faces: &[Vec<i32>]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat {} 1.0\ncomment test\nelement vertex {}\nproperty double x\n\
         property double y\nproperty double z\nproperty uchar quality\nelement face {}\n\
         property list uchar int vertex_indices\nproperty list uchar float weights\n\
         element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n",
        if big_endian {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        },
        positions.len(),
        faces.len()
    )
    .into_bytes();
    for p in positions {
        for c in p {
            out.extend_from_slice(&if big_endian {
                c.to_be_bytes()
            } else {
                c.to_le_bytes()
            });
        }
        out.push(7);
    }
    for f in faces {
        out.push(f.len() as u8);
        for i in f {
            out.extend_from_slice(&if big_endian {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
        out.push(1);
        out.extend_from_slice(&[0, 0, 0, 0]);
    }
    for i in [0i32, 1] {
        out.extend_from_slice(&if big_endian {
            i.to_be_bytes()
        } else {
            i.to_le_bytes()
        });
    }
    out
}

const SQUARE: [[f64; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.5, 0.5, 1.0],
];

fn ascii_ply(body: &str, vertices: usize, faces: usize) -> String {
    format!(
        "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex {vertices}\n\
         property float x\nproperty float y\nproperty float z\nelement face {faces}\n\
         property list uchar int vertex_indices\nend_header\n{body}"
    )
}

// ---------------------------------------------------------------------------------------------
// Round trips and good files
// ---------------------------------------------------------------------------------------------

#[test]
fn ply_gz_round_trip_with_normals_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let (mesh, _) = clean_mesh(icosphere(1), "icosphere").unwrap();
    let path = dir.path().join("ico.ply.gz");
    write_ply_binary_gz(&path, &mesh).unwrap();
    // f32 values are stored bit for bit, so the round trip is exact.
    let back = load_mesh(&path).unwrap();
    assert_eq!(back, mesh);
    // The header says ushort indices for a small mesh.
    let raw = super::gunzip(&path, &std::fs::read(&path).unwrap()).unwrap();
    let text = String::from_utf8_lossy(&raw[..300]);
    assert!(
        text.contains("property list uchar ushort vertex_indices"),
        "{text}"
    );
    assert!(text.contains("property float nx"), "{text}");
}

#[test]
fn ply_gz_round_trip_large_mesh_uses_uint_indices() {
    let dir = tempfile::tempdir().unwrap();
    // 265 × 265 = 70,225 vertices: more than a ushort can index.
    let mesh = grid(265, 265);
    let path = dir.path().join("grid.ply.gz");
    write_ply_binary_gz(&path, &mesh).unwrap();
    let back = load_mesh(&path).unwrap();
    assert_eq!(back, mesh);
    let raw = super::gunzip(&path, &std::fs::read(&path).unwrap()).unwrap();
    assert!(String::from_utf8_lossy(&raw[..300]).contains("uchar uint vertex_indices"));
}

#[test]
fn write_is_reproducible_and_atomic() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.ply.gz");
    let b = dir.path().join("b.ply.gz");
    write_ply_binary_gz(&a, &octahedron()).unwrap();
    write_ply_binary_gz(&b, &octahedron()).unwrap();
    // No timestamp or name in the gzip header: identical bytes.
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    // An invalid mesh is refused and the existing file is left alone.
    let mut bad = octahedron();
    bad.indices.push([0, 1, 99]);
    let before = std::fs::read(&a).unwrap();
    let err = write_ply_binary_gz(&a, &bad).unwrap_err().to_string();
    assert!(
        err.contains("a.ply.gz") && err.contains("vertex 99"),
        "{err}"
    );
    assert_eq!(std::fs::read(&a).unwrap(), before);
    let leftovers = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(leftovers, 2, "temporary files left behind");
}

#[test]
fn ply_ascii_polygons_are_fan_triangulated() {
    let dir = tempfile::tempdir().unwrap();
    let text = "ply\r\nformat ascii 1.0\r\nobj_info scanned\r\nelement vertex 5\r\n\
                property float x\r\nproperty float y\r\nproperty float z\r\n\
                property uchar red\r\nproperty float nx\r\nproperty float ny\r\nproperty float nz\r\n\
                element face 3\r\nproperty list uchar uint vertex_index\r\n\
                property list uchar float texcoord\r\nend_header\r\n\
                0 0 0 255 0 0 1\r\n1 0 0 255 0 0 1\r\n1 1 0 255 0 0 1\r\n\r\n\
                0 1 0 255 0 0 1\r\n0.5 0.5 1e0 255 0 0 1\r\n\
                4 0 1 2 3 0\r\n3 0 1 4 2 0.5 0.5\r\n5 0 1 2 3 4 0\r\n\r\n";
    let path = write_file(dir.path(), "poly.ply", text.as_bytes());
    let mesh = load_mesh(&path).unwrap();
    assert_eq!(mesh.positions.len(), 5);
    assert_eq!(mesh.positions[4], Vec3::new(0.5, 0.5, 1.0));
    assert_eq!(
        mesh.indices,
        vec![
            [0, 1, 2],
            [0, 2, 3],
            [0, 1, 4],
            [0, 1, 2],
            [0, 2, 3],
            [0, 3, 4]
        ]
    );
    assert_eq!(mesh.normals.as_ref().unwrap()[3], Vec3::Z);
}

#[test]
fn ply_binary_big_and_little_endian() {
    let dir = tempfile::tempdir().unwrap();
    let faces = vec![vec![0, 1, 2, 3], vec![0, 1, 4]];
    for big in [true, false] {
        let name = if big { "be.ply" } else { "le.ply" };
        let path = write_file(dir.path(), name, &binary_ply(big, &SQUARE, &faces));
        let mesh = load_mesh(&path).unwrap();
        let expected: Vec<Vec3> = SQUARE
            .iter()
            .map(|p| Vec3::from(p.map(|c| c as f32)))
            .collect();
        assert_eq!(mesh.positions, expected, "{name}");
        assert_eq!(
            mesh.indices,
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]],
            "{name}"
        );
        assert!(mesh.normals.is_none());
    }
}

#[test]
fn ply_gz_ascii_and_gzip_named_ply() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 3, 1);
    let gz = gzip(text.as_bytes());
    for name in ["tri.ply.gz", "tri.PLY.GZ", "really-gzip.ply"] {
        let path = write_file(dir.path(), name, &gz);
        let mesh = load_mesh(&path).unwrap();
        assert_eq!(mesh.indices, vec![[0, 1, 2]], "{name}");
    }
}

#[test]
fn obj_quads_negative_indices_and_ignored_statements() {
    let dir = tempfile::tempdir().unwrap();
    let text = "# a quad and a triangle\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0 1.0\n\
                v 0 1 0 0.5 0.5 0.5\nvt 0 0\nvt 1 0\ng group\nusemtl red\ns off\n\
                f 1/1 2/2 3/2 4/1 # quad\nv 0.5 0.5 1\nf -5 -4 \\\n -1\nl 1 2\n";
    let path = write_file(dir.path(), "quad.obj", text.as_bytes());
    let mesh = load_mesh(&path).unwrap();
    assert_eq!(mesh.positions.len(), 5);
    assert_eq!(mesh.indices, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
    assert!(mesh.normals.is_none());
}

#[test]
fn obj_normals_split_vertices_per_position_normal_pair() {
    let dir = tempfile::tempdir().unwrap();
    // Two triangles sharing an edge, each with its own normal: the shared positions are split.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvn 0 0 -1\n\
                f 1//1 2//1 3//1\nf 2/ /2 4//2 3//2\n";
    let path = write_file(
        dir.path(),
        "split.obj",
        text.replace("/ /", "//").as_bytes(),
    );
    let mesh = load_mesh(&path).unwrap();
    assert_eq!(mesh.positions.len(), 6);
    assert_eq!(mesh.indices, vec![[0, 1, 2], [3, 4, 5]]);
    let n = mesh.normals.unwrap();
    assert_eq!(&n[..3], &[Vec3::Z; 3]);
    assert_eq!(&n[3..], &[Vec3::NEG_Z; 3]);
    assert_eq!(mesh.positions[3], Vec3::X);
}

#[test]
fn glb_with_node_transforms() {
    let dir = tempfile::tempdir().unwrap();
    let bin = triangle_buffer();
    let json = triangle_gltf_json(&format!(r#"{{"byteLength": {}}}"#, bin.len()), 4);
    let path = write_file(dir.path(), "tri.glb", &glb(&json, Some(&bin)));
    check_triangle_scene(&load_mesh(&path).unwrap());
}

#[test]
fn gltf_with_embedded_and_external_buffers() {
    let dir = tempfile::tempdir().unwrap();
    let bin = triangle_buffer();
    let embedded = format!(
        r#"{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}"#,
        bin.len(),
        base64(&bin)
    );
    let path = write_file(
        dir.path(),
        "embedded.gltf",
        triangle_gltf_json(&embedded, 4).as_bytes(),
    );
    check_triangle_scene(&load_mesh(&path).unwrap());

    // External buffer with a percent-encoded space in its name.
    write_file(dir.path(), "tri data.bin", &bin);
    let external = format!(
        r#"{{"byteLength": {}, "uri": "tri%20data.bin"}}"#,
        bin.len()
    );
    let path = write_file(
        dir.path(),
        "external.gltf",
        triangle_gltf_json(&external, 4).as_bytes(),
    );
    check_triangle_scene(&load_mesh(&path).unwrap());
}

#[test]
fn gltf_non_indexed_without_normals() {
    let dir = tempfile::tempdir().unwrap();
    let bin = triangle_buffer();
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}},
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "nodes": [{{"mesh": 0, "rotation": [0, 0, 0.7071068, 0.7071068]}}],
  "buffers": [{{"byteLength": {}}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}}]}}"#,
        bin.len()
    );
    let path = write_file(dir.path(), "nonindexed.glb", &glb(&json, Some(&bin)));
    let mesh = load_mesh(&path).unwrap();
    assert!(mesh.normals.is_none());
    assert_eq!(mesh.indices, vec![[0, 1, 2]]);
    // 90° about z (no scene: the root node is used): (1,0,0) -> (0,1,0). The quaternion is
    // rounded to f32, so allow a few ulps.
    assert_vec_close(mesh.positions[1], Vec3::Y, 1e-6, "rotated vertex");
}

// ---------------------------------------------------------------------------------------------
// Normals
// ---------------------------------------------------------------------------------------------

#[test]
fn computed_normals_of_an_octahedron_are_exactly_radial() {
    let (mesh, report) = clean_mesh(octahedron(), "octahedron").unwrap();
    assert!(report.computed_normals);
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    // By symmetry the four face normals around each vertex sum to the axis exactly; only the
    // f32 rounding of the final normalisation remains.
    for (p, n) in mesh.positions.iter().zip(mesh.normals.as_ref().unwrap()) {
        assert_vec_close(*n, *p, 1e-6, "octahedron normal");
    }
}

#[test]
fn computed_normals_of_an_icosphere_are_nearly_radial() {
    let (mesh, report) = clean_mesh(icosphere(3), "icosphere").unwrap();
    assert!(report.computed_normals);
    assert_eq!(mesh.indices.len(), 1280);
    let mut worst = 0f32;
    for (p, n) in mesh.positions.iter().zip(mesh.normals.as_ref().unwrap()) {
        assert!((n.length() - 1.0).abs() < 1e-6);
        worst = worst.max(n.dot(p.normalize()).clamp(-1.0, 1.0).acos().to_degrees());
    }
    // On an icosphere the fans around vertices are irregular (valence 5 and 6, unequal
    // triangles), so the area-weighted normal deviates from the radial direction to first
    // order in the edge length: measured worst cases 1.35°, 0.68° and 0.34° at levels 2, 3, 4
    // (halving with each subdivision). Level 3 (edge ≈ 9°) is bounded by 1°, which leaves
    // margin over 0.68° yet rejects misoriented or unnormalised normals.
    assert!(worst < 1.0, "worst deviation from radial: {worst}°");
}

#[test]
fn computed_normals_are_area_weighted() {
    // Vertex 0 is shared by a triangle of area 1 in the z = 0 plane (normal +z) and one of
    // area 1/4 in the x = 0 plane (normal +x): the area-weighted normal is (1/4, 0, 1)
    // normalised (an unweighted average would be (1, 0, 1)).
    let mesh = MeshData {
        positions: vec![
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 0.5),
        ],
        normals: None,
        indices: vec![[0, 1, 2], [0, 2, 3]],
    };
    let (clean, _) = clean_mesh(mesh, "tent").unwrap();
    let n = clean.normals.unwrap();
    assert_vec_close(
        n[0],
        Vec3::new(0.25, 0.0, 1.0).normalize(),
        1e-6,
        "weighted",
    );
    assert_vec_close(n[1], Vec3::Z, 1e-6, "single face");
    assert_vec_close(n[3], Vec3::X, 1e-6, "single face");
}

#[test]
fn clean_repairs_flipped_zero_and_nan_normals() {
    let mut mesh = octahedron();
    let mut normals = mesh.positions.clone();
    normals[0] = Vec3::NEG_X; // against all four adjacent faces
    normals[1] = Vec3::ZERO;
    normals[2] = Vec3::new(f32::NAN, 0.0, 1.0);
    normals[3] = Vec3::new(0.0, -2.0, 0.3); // tilted and unnormalised but valid: kept
    normals[4] = Vec3::new(1.0, 0.0, 0.1); // perpendicular-ish, agrees with two faces: kept
    mesh.normals = Some(normals);
    let label = r#"objects[2] "oct" (models/oct.ply.gz)"#;
    let (clean, report) = clean_mesh(mesh, label).unwrap();
    assert_eq!(report.repaired_normals, 3);
    assert!(!report.computed_normals);
    assert_eq!(report.warnings.len(), 1);
    let w = &report.warnings[0];
    assert!(
        w.starts_with(label) && w.contains("repaired 3 of 6 vertex normals"),
        "{w}"
    );
    let n = clean.normals.unwrap();
    for (nv, pv) in n.iter().zip(&clean.positions).take(3) {
        assert_vec_close(*nv, *pv, 1e-6, "repaired normal");
    }
    assert_vec_close(
        n[3],
        Vec3::new(0.0, -2.0, 0.3).normalize(),
        1e-6,
        "kept normal",
    );
    assert_vec_close(
        n[4],
        Vec3::new(1.0, 0.0, 0.1).normalize(),
        1e-6,
        "kept normal",
    );
}

#[test]
fn clean_removes_duplicates_with_warning() {
    let mut mesh = octahedron();
    let [a, b, c] = mesh.indices[0];
    mesh.indices.push([a, c, b]); // reversed winding
    mesh.indices.push(mesh.indices[1]); // exact copy
    // A copy of face 2 through duplicated vertices with identical positions.
    let f2 = mesh.indices[2];
    let base = mesh.positions.len() as u32;
    for &i in &f2 {
        mesh.positions.push(mesh.positions[i as usize]);
    }
    mesh.indices.push([base + 1, base + 2, base]);
    let (clean, report) = clean_mesh(mesh, "dups").unwrap();
    assert_eq!(report.removed_duplicate, 3);
    assert_eq!(report.removed_degenerate, 0);
    assert_eq!(report.removed_unused_vertices, 3);
    assert_eq!(clean.indices, octahedron().indices);
    assert_eq!(clean.positions, octahedron().positions);
    assert_eq!(report.warnings.len(), 1);
    assert!(
        report.warnings[0].starts_with("dups: removed 3 duplicate triangles"),
        "{:?}",
        report.warnings
    );
}

#[test]
fn clean_removes_degenerate_triangles_with_warning() {
    let mut mesh = octahedron();
    mesh.indices.push([0, 0, 1]); // repeated index
    mesh.positions.push(Vec3::new(0.5, 0.0, 0.0)); // on the segment between 0 (+x) and... 
    mesh.positions.push(Vec3::new(-0.5, 0.0, 0.0)); // ... 1 (-x): collinear with them
    mesh.indices.push([0, 6, 7]);
    // A sliver with area 1e-9 × diagonal²: far above the 1e-12 threshold, so it is kept.
    let diag2 = 12.0; // the octahedron's bounding box is [-1, 1]³
    let h = (2.0 * 1e-9 * diag2) as f32; // area = 1/2 × base 1 × h
    mesh.positions.push(Vec3::new(0.0, 0.0, 0.0));
    mesh.positions.push(Vec3::new(1.0, 0.0, 0.0));
    mesh.positions.push(Vec3::new(0.5, h, 0.0));
    mesh.indices.push([8, 9, 10]);
    let (clean, report) = clean_mesh(mesh, "degen").unwrap();
    assert_eq!(report.removed_degenerate, 2);
    assert_eq!(clean.indices.len(), 9, "the sliver must be kept");
    assert!(
        report.warnings[0].starts_with("degen: removed 2 of 11 triangles with (near-)zero area"),
        "{:?}",
        report.warnings
    );
}

#[test]
fn clean_all_degenerate_is_an_error() {
    let mesh = MeshData {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)],
        normals: None,
        indices: vec![[0, 1, 2], [0, 0, 1], [2, 1, 1]],
    };
    let err = clean_mesh(mesh, "flat (models/flat.ply)").unwrap_err();
    let msg = err.to_string();
    assert!(matches!(
        err,
        MeshError::NothingLeft {
            total: 3,
            degenerate: 3,
            ..
        }
    ));
    assert!(
        msg.contains("flat (models/flat.ply)") && msg.contains("no triangles left"),
        "{msg}"
    );
    // Invalid input to clean_mesh is an error too, not a panic.
    let bad = MeshData {
        positions: vec![Vec3::ZERO],
        normals: Some(vec![]),
        indices: vec![[0, 0, 0]],
    };
    let msg = clean_mesh(bad, "bad").unwrap_err().to_string();
    assert!(
        msg.contains("bad: invalid mesh data: 0 normals for 1 positions"),
        "{msg}"
    );
}

#[test]
fn convert_round_trip_and_refusals() {
    let dir = tempfile::tempdir().unwrap();
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 0\nf 1 2 3 4\nf 1 2 3\nf 1 5 2\n";
    let input = write_file(dir.path(), "in.obj", text.as_bytes());
    let output = dir.path().join("out.ply.gz");
    let report = convert(&input, &output).unwrap();
    assert_eq!(report.removed_duplicate, 1);
    assert_eq!(report.removed_degenerate, 1);
    assert_eq!(report.removed_unused_vertices, 1);
    assert!(report.computed_normals);
    // Computed normals are not stored...
    let stored = load_mesh(&output).unwrap();
    assert!(stored.normals.is_none());
    assert_eq!(stored.indices.len(), 2);
    // ...and cleaning the stored mesh again changes nothing and gives the same normals.
    let (first, _) = clean_mesh(load_mesh(&input).unwrap(), "in").unwrap();
    let (again, report2) = clean_mesh(stored, "out").unwrap();
    assert!(report2.warnings.is_empty(), "{:?}", report2.warnings);
    assert_eq!(again, first);

    let err = convert(&input, &input).unwrap_err().to_string();
    assert!(
        err.contains("in.obj") && err.contains("onto itself"),
        "{err}"
    );
    let err = convert(&output, &output).unwrap_err();
    assert!(matches!(err, MeshError::OutputIsInput { .. }));
    let err = convert(&input, &dir.path().join("out.ply"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("out.ply") && err.contains("must end in .ply.gz"),
        "{err}"
    );
}

// ---------------------------------------------------------------------------------------------
// Bad inputs: each error names the file and the problem
// ---------------------------------------------------------------------------------------------

#[test]
fn bad_ply_truncated_binary() {
    let dir = tempfile::tempdir().unwrap();
    let full = binary_ply(false, &SQUARE, &[vec![0, 1, 2, 3], vec![0, 1, 4]]);
    let header_len = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // Cut inside the third vertex (each vertex is 3 doubles + 1 uchar = 25 bytes).
    let path = write_file(dir.path(), "cut-vertex.ply", &full[..header_len + 60]);
    load_err(
        &path,
        &["truncated", "vertex 2", "5 'vertex' elements", "after 2"],
    );
    // Cut inside the second face's index list.
    let faces_start = header_len + 5 * 25;
    let first_face = 1 + 4 * 4 + 1 + 4;
    let path = write_file(
        dir.path(),
        "cut-face.ply",
        &full[..faces_start + first_face + 3],
    );
    load_err(&path, &["truncated", "face 1", "vertex_indices"]);
    // Cut inside the header.
    let path = write_file(dir.path(), "cut-header.ply", &full[..40]);
    load_err(&path, &["truncated", "end_header"]);
}

#[test]
fn bad_ply_ascii_non_number() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_ply("0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n", 3, 1);
    let path = write_file(dir.path(), "nan-text.ply", text.as_bytes());
    // Header: 10 lines, so the second vertex is on line 12.
    load_err(&path, &["line 12 (vertex 1)", "'zero' is not a number"]);
    let text = ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n", 3, 1);
    let path = write_file(dir.path(), "float-index.ply", text.as_bytes());
    load_err(&path, &["line 14 (face 0)", "'2.5' is not an integer"]);
}

#[test]
fn bad_ply_face_index_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 7\n", 3, 2);
    let path = write_file(dir.path(), "range.ply", text.as_bytes());
    load_err(
        &path,
        &[
            "line 15 (face 1)",
            "vertex index 7 is out of range",
            "there are 3 vertices",
        ],
    );
    let bin = binary_ply(true, &SQUARE, &[vec![0, 1, -1]]);
    let path = write_file(dir.path(), "negative.ply", &bin);
    load_err(
        &path,
        &["face 0 (byte offset", "vertex index -1 is out of range"],
    );
}

#[test]
fn bad_ply_nan_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_ply("0 0 0\n1 0 0\n0 nan 0\n3 0 1 2\n", 3, 1);
    let path = write_file(dir.path(), "nan.ply", text.as_bytes());
    load_err(
        &path,
        &[
            "line 13 (vertex 2)",
            "non-finite vertex position (0, NaN, 0)",
        ],
    );
    let mut square = SQUARE;
    square[3][2] = f64::INFINITY;
    let path = write_file(
        dir.path(),
        "inf.ply",
        &binary_ply(false, &square, &[vec![0, 1, 2]]),
    );
    load_err(&path, &["vertex 3 (byte offset", "non-finite", "inf"]);
}

#[test]
fn bad_ply_inconsistent_element_count() {
    let dir = tempfile::tempdir().unwrap();
    // The header promises 4 vertices but the file has 3, so a face line is read as a vertex.
    let text = ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 4, 1);
    let path = write_file(dir.path(), "too-few-vertices.ply", text.as_bytes());
    load_err(
        &path,
        &[
            "element counts do not match",
            "line 14 (vertex 3)",
            "extra value '2'",
        ],
    );
    // The header promises 1 face but the file has 2.
    let text = ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n", 3, 1);
    let path = write_file(dir.path(), "too-many-faces.ply", text.as_bytes());
    load_err(
        &path,
        &[
            "element counts do not match",
            "line 15",
            "extra data",
            "1 face",
        ],
    );
    // Promises 2 faces, has 1.
    let text = ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 3, 2);
    let path = write_file(dir.path(), "missing-face.ply", text.as_bytes());
    load_err(&path, &["truncated", "after 1 of the 2 'face' elements"]);
    // Binary with data left over after the declared elements.
    let mut bin = binary_ply(false, &SQUARE, &[vec![0, 1, 2]]);
    bin.extend_from_slice(&[1, 2, 3, 4, 5]);
    let path = write_file(dir.path(), "trailing.ply", &bin);
    load_err(
        &path,
        &["element counts do not match", "5 bytes of data after"],
    );
}

#[test]
fn bad_ply_empty_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(
        dir.path(),
        "no-faces.ply",
        ascii_ply("0 0 0\n1 0 0\n0 1 0\n", 3, 0).as_bytes(),
    );
    load_err(&path, &["empty mesh", "0 faces"]);
    let path = write_file(
        dir.path(),
        "no-vertices.ply",
        ascii_ply("", 0, 0).as_bytes(),
    );
    load_err(&path, &["empty mesh", "0 vertices"]);
    let cloud = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                 property float z\nend_header\n0 0 0\n";
    let path = write_file(dir.path(), "cloud.ply", cloud.as_bytes());
    load_err(&path, &["empty mesh", "no 'face' element"]);
    // A huge element without properties occupies no bytes and is skipped instantly.
    let mut bin = binary_ply(false, &SQUARE, &[vec![0, 1, 2]]);
    let at = bin.windows(11).position(|w| w == b"end_header\n").unwrap();
    bin.splice(at..at, b"element nothing 1000000000000\n".iter().copied());
    let path = write_file(dir.path(), "nothing.ply", &bin);
    assert_eq!(load_mesh(&path).unwrap().indices.len(), 1);
    let path = write_file(dir.path(), "empty.obj", b"# nothing\n\n");
    load_err(&path, &["empty mesh", "no vertices"]);
    let path = write_file(dir.path(), "empty.ply", b"");
    load_err(&path, &["truncated"]);
}

#[test]
fn bad_ply_face_with_two_vertices() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0 1\n", 3, 2);
    let path = write_file(dir.path(), "edge.ply", text.as_bytes());
    load_err(&path, &["line 15 (face 1)", "face has 2 vertices"]);
    let path = write_file(dir.path(), "edge.obj", b"v 0 0 0\nv 1 0 0\nf 1 2\n");
    load_err(&path, &["line 3 (face 1)", "face has 2 vertices"]);
}

#[test]
fn bad_gzip_corrupt_truncated_or_not_gzip() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 3, 1);
    let gz = gzip(text.as_bytes());
    let mut corrupt = gz.clone();
    let mid = corrupt.len() / 2;
    corrupt[mid] ^= 0x55;
    corrupt[mid + 1] ^= 0xaa;
    let path = write_file(dir.path(), "corrupt.ply.gz", &corrupt);
    load_err(&path, &["corrupt or truncated gzip data"]);
    let path = write_file(dir.path(), "short.ply.gz", &gz[..gz.len() - 6]);
    load_err(&path, &["corrupt or truncated gzip data"]);
    let path = write_file(dir.path(), "plain.ply.gz", text.as_bytes());
    load_err(&path, &["corrupt or truncated gzip data", "not gzip data"]);
}

#[test]
fn bad_garbage_and_non_utf8() {
    let dir = tempfile::tempdir().unwrap();
    let garbage: Vec<u8> = (0..2000u32).map(|i| (i * 7919 % 251) as u8).collect();
    let path = write_file(dir.path(), "garbage.ply", &garbage);
    load_err(&path, &["header line 1", "not a PLY file"]);
    let path = write_file(dir.path(), "garbage.obj", &garbage);
    load_err(&path, &["line 1", "is this really an OBJ file"]);
    let path = write_file(dir.path(), "latin1.obj", b"v 0 0 0\n# caf\xe9\nv 1 0 0\n");
    load_err(&path, &["line 2", "not valid UTF-8"]);
    let path = write_file(dir.path(), "garbage.glb", &garbage);
    load_err(&path, &["invalid glTF"]);
    let path = write_file(dir.path(), "word.obj", b"v 0 0 0\nvertex 1 2 3\n");
    load_err(&path, &["line 2", "unknown statement 'vertex'"]);
    let path = write_file(
        dir.path(),
        "header.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float32 x\nproperty vec3 y\nend_header\n",
    );
    load_err(&path, &["header line 5", "unknown property type 'vec3'"]);
}

#[test]
fn bad_obj_missing_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_file(
        dir.path(),
        "missing.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n",
    );
    load_err(
        &path,
        &[
            "line 5",
            "'4'",
            "vertex index 4 is out of range",
            "there are 3 vertices",
        ],
    );
    let path = write_file(
        dir.path(),
        "relative.obj",
        b"v 0 0 0\nv 1 0 0\nf -1 -2 -3\n",
    );
    load_err(&path, &["line 3", "vertex index -3 is out of range"]);
    let path = write_file(
        dir.path(),
        "zero.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
    );
    load_err(
        &path,
        &[
            "line 4",
            "vertex index 0 is invalid: OBJ indices start at 1",
        ],
    );
    // A directory named like a mesh.
    let path = dir.path().join("folder.ply");
    std::fs::create_dir(&path).unwrap();
    load_err(&path, &["is a directory, not a mesh file"]);
    let path = write_file(
        dir.path(),
        "normal.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n",
    );
    load_err(&path, &["line 5", "normal index 2 is out of range"]);
    let path = write_file(dir.path(), "nan.obj", b"v 0 0 0\nv 1 inf 0\n");
    load_err(&path, &["line 2 (vertex 2)", "non-finite"]);
}

#[test]
fn bad_gltf_missing_buffer() {
    let dir = tempfile::tempdir().unwrap();
    let json = triangle_gltf_json(r#"{"byteLength": 80, "uri": "missing.bin"}"#, 4);
    let path = write_file(dir.path(), "missing.gltf", json.as_bytes());
    load_err(&path, &["buffer 0", "'missing.bin'", "cannot be read"]);
    // A GLB whose buffer refers to a BIN chunk that is not there.
    let json = triangle_gltf_json(r#"{"byteLength": 80}"#, 4);
    let path = write_file(dir.path(), "nobin.glb", &glb(&json, None));
    load_err(&path, &["buffer 0", "GLB binary chunk", "has none"]);
    // A buffer shorter than it says.
    let bin = triangle_buffer();
    let path = write_file(dir.path(), "short.glb", &glb(&json, Some(&bin[..40])));
    load_err(&path, &["truncated", "buffer 0", "80 bytes"]);
}

#[test]
fn bad_gltf_structure() {
    let dir = tempfile::tempdir().unwrap();
    let bin = triangle_buffer();
    let buffer = format!(r#"{{"byteLength": {}}}"#, bin.len());
    // Lines instead of triangles.
    let path = write_file(
        dir.path(),
        "lines.glb",
        &glb(&triangle_gltf_json(&buffer, 1), Some(&bin)),
    );
    load_err(
        &path,
        &[
            "unsupported",
            "mesh 0 'tri' primitive 0",
            "Lines",
            "TRIANGLES",
        ],
    );
    // An index out of range.
    let mut bad = bin.clone();
    bad[72..74].copy_from_slice(&9u16.to_le_bytes());
    let path = write_file(
        dir.path(),
        "index.glb",
        &glb(&triangle_gltf_json(&buffer, 4), Some(&bad)),
    );
    load_err(
        &path,
        &["index 0 (triangle 0)", "vertex index 9 is out of range"],
    );
    // An accessor reaching past its buffer view.
    let json = triangle_gltf_json(&buffer, 4).replace(
        r#""count": 3, "type": "SCALAR""#,
        r#""count": 6, "type": "SCALAR""#,
    );
    let path = write_file(dir.path(), "overrun.glb", &glb(&json, Some(&bin)));
    load_err(&path, &["accessor 2", "does not fit in bufferView 1"]);
    // Invalid JSON and a reference to a missing accessor.
    let path = write_file(
        dir.path(),
        "broken.gltf",
        b"{\"asset\": {\"version\": \"2.0\"",
    );
    load_err(&path, &["invalid glTF"]);
    let json = triangle_gltf_json(&buffer, 4).replace(r#""POSITION": 0"#, r#""POSITION": 7"#);
    let path = write_file(dir.path(), "dangling.glb", &glb(&json, Some(&bin)));
    load_err(&path, &["invalid glTF"]);
    // A truncated GLB.
    let full = glb(&triangle_gltf_json(&buffer, 4), Some(&bin));
    let path = write_file(dir.path(), "cut.glb", &full[..full.len() - 10]);
    load_err(&path, &["truncated", "GLB header"]);
    // A node cycle.
    let json = triangle_gltf_json(&buffer, 4).replace(
        r#""matrix": [2,0,0,0, 0,2,0,0, 0,0,2,0, 0,0,0,1]"#,
        r#""children": [0]"#,
    );
    let path = write_file(dir.path(), "cycle.glb", &glb(&json, Some(&bin)));
    load_err(&path, &["invalid glTF", "node 0 is reached twice", "cycle"]);
    // A node with two parents.
    let json = triangle_gltf_json(&buffer, 4).replace(
        r#"{"mesh": 0, "scale": [-1, 1, 1]}"#,
        r#"{"mesh": 0, "scale": [-1, 1, 1], "children": [2]}"#,
    );
    let path = write_file(dir.path(), "dag.glb", &glb(&json, Some(&bin)));
    load_err(&path, &["node 2 is a child of both node 0 and node 1"]);
}

#[test]
fn bad_unknown_extension() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["mesh.stl", "mesh", "mesh.gltf.gz", "mesh.ply.zip"] {
        let path = write_file(dir.path(), name, b"solid x\n");
        load_err(&path, &["unknown mesh file extension", ".ply.gz"]);
    }
    let path = dir.path().join("does-not-exist.ply");
    load_err(&path, &["cannot read the file"]);
}

/// Truncating or corrupting valid files anywhere gives an error or a valid mesh, never a panic.
#[test]
fn truncated_and_corrupted_files_never_panic() {
    let bin = triangle_buffer();
    let gltf_json = triangle_gltf_json(&format!(r#"{{"byteLength": {}}}"#, bin.len()), 4);
    let samples: Vec<(&str, Vec<u8>)> = vec![
        (
            "x.ply",
            binary_ply(false, &SQUARE, &[vec![0, 1, 2, 3], vec![0, 1, 4]]),
        ),
        (
            "x.ply",
            binary_ply(true, &SQUARE, &[vec![0, 1, 2, 3], vec![0, 1, 4]]),
        ),
        (
            "x.ply",
            ascii_ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", 3, 1).into_bytes(),
        ),
        (
            "x.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n".to_vec(),
        ),
        ("x.glb", glb(&gltf_json, Some(&bin))),
    ];
    let path = Path::new("fuzz");
    let check = |name: &str, data: &[u8]| {
        let result = match name {
            "x.ply" => super::ply::parse_ply(path, data),
            "x.obj" => super::obj::parse_obj(path, data),
            _ => super::gltf_io::parse_gltf(path, data, super::gltf_io::Buffers::Embedded),
        };
        if let Ok(mesh) = result {
            validate(&mesh, "fuzz").expect("a loaded mesh must be valid");
        }
    };
    for (name, data) in &samples {
        for len in 0..data.len() {
            check(name, &data[..len]);
        }
        for i in 0..data.len() {
            for flip in [0x01u8, 0x80, 0xff] {
                let mut d = data.clone();
                d[i] ^= flip;
                check(name, &d);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Committed models
// ---------------------------------------------------------------------------------------------

/// The models in `scenes/models/` load, are already clean (cleaning again changes nothing),
/// have the triangle and vertex counts of the README's table, and are +y up (their bounding
/// boxes match the README's to the printed precision).
#[test]
fn committed_models_load_clean_and_match_readme() {
    let models = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/models");
    // (file, triangles, vertices, bbox min, bbox max)
    let expected = [
        (
            "bunny.ply.gz",
            3_674usize,
            1_839usize,
            [-4.958475, -0.003149, -3.729833],
            [4.94885, 9.654748, 3.810639],
        ),
        (
            "teapot.ply.gz",
            992,
            529,
            [-16.070313, -7.875, -10.0],
            [16.070313, 7.875, 10.0],
        ),
        (
            "dragon-11k.ply.gz",
            10_600,
            5_203,
            [-0.107585, 0.0528441, -0.049836],
            [0.0952357, 0.196343, 0.0408262],
        ),
        (
            "dragon-48k.ply.gz",
            46_540,
            22_982,
            [-0.107673, 0.0527743, -0.050051],
            [0.0959825, 0.196644, 0.0408262],
        ),
        (
            "dragon-202k.ply.gz",
            201_031,
            100_207,
            [-0.108188, 0.0527392, -0.0503454],
            [0.0964062, 0.197139, 0.0411367],
        ),
    ];
    let readme =
        std::fs::read_to_string(models.join("README.md")).expect("scenes/models/README.md");
    for (name, triangles, vertices, lo, hi) in expected {
        let path = models.join(name);
        let mesh = load_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(mesh.indices.len(), triangles, "{name}");
        assert_eq!(mesh.positions.len(), vertices, "{name}");
        // Computed normals are not stored (see `convert`).
        assert!(mesh.normals.is_none(), "{name}");
        let (bmin, bmax) = mesh.bounds().unwrap();
        // The README prints 6-7 significant digits; 1e-6 relative to the extent covers that.
        let tol = (bmax - bmin).max_element() * 1e-6;
        assert_vec_close(bmin, Vec3::from_array(lo), tol, name);
        assert_vec_close(bmax, Vec3::from_array(hi), tol, name);
        let (clean, report) = clean_mesh(mesh.clone(), name).unwrap();
        assert!(report.warnings.is_empty(), "{name}: {:?}", report.warnings);
        assert_eq!(clean.indices, mesh.indices, "{name}");
        let row = readme
            .lines()
            .find(|l| l.starts_with(&format!("| `{name}`")))
            .unwrap_or_else(|| panic!("{name} has no row in scenes/models/README.md"));
        for n in [triangles, vertices] {
            let n = format_thousands(n);
            assert!(row.contains(&n), "{name}: README row {row:?} lacks {n}");
        }
    }
}

fn format_thousands(n: usize) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// Conversion driver for the committed models (not part of the normal test run):
/// `MESH_CONVERT='in1=>out1;in2=>out2' cargo test --release --lib scene::mesh::tests::convert_models -- --ignored --nocapture`
#[test]
#[ignore]
fn convert_models() {
    let spec = std::env::var("MESH_CONVERT").expect("set MESH_CONVERT='in=>out;...'");
    for pair in spec.split(';').filter(|s| !s.trim().is_empty()) {
        let (input, output) = pair.split_once("=>").expect("in=>out");
        let (input, output) = (Path::new(input.trim()), Path::new(output.trim()));
        let report = convert(input, output).unwrap_or_else(|e| panic!("{e}"));
        let mesh = load_mesh(output).unwrap();
        let (lo, hi) = mesh.bounds().unwrap();
        println!(
            "{} -> {}: {} vertices, {} triangles, bbox min {lo} max {hi} extent {}, {} bytes\n  report: {report:?}",
            input.display(),
            output.display(),
            mesh.positions.len(),
            mesh.indices.len(),
            hi - lo,
            std::fs::metadata(output).unwrap().len()
        );
    }
}

// ---------------------------------------------------------------------------------------------
// parse_mesh_bytes
// ---------------------------------------------------------------------------------------------

#[test]
fn parse_mesh_bytes_agrees_with_load_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let ply = ascii_ply("0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n", 4, 2);
    let bin = triangle_buffer();
    let embedded = format!(
        r#"{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}"#,
        bin.len(),
        base64(&bin)
    );
    let glb_json = triangle_gltf_json(&format!(r#"{{"byteLength": {}}}"#, bin.len()), 4);
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("a.ply", ply.as_bytes().to_vec()),
        ("a.ply.gz", gzip(ply.as_bytes())),
        ("gzipped-anyway.ply", gzip(ply.as_bytes())),
        (
            "a.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n".to_vec(),
        ),
        ("a.OBJ.GZ", gzip(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n")),
        ("a.gltf", triangle_gltf_json(&embedded, 4).into_bytes()),
        ("a.glb", glb(&glb_json, Some(&bin))),
    ];
    for (name, bytes) in cases {
        let path = write_file(dir.path(), name, &bytes);
        let from_file = load_mesh(&path).unwrap();
        let from_bytes = parse_mesh_bytes(&bytes, name).unwrap();
        assert_eq!(from_file, from_bytes, "{name}");
    }
}

#[test]
fn parse_mesh_bytes_errors_name_the_input() {
    let cases: &[(&str, &[u8], &str)] = &[
        ("m.stl", b"solid", "unknown mesh file extension"),
        (
            "m.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\n",
            "truncated",
        ),
        ("m.ply.gz", b"not gzip", "gzip"),
        ("m.obj", b"v 0 0 0\nf 1 2 3\n", "out of range"),
        ("m.glb", b"glTF\x02\0\0\0", "GLB header"),
    ];
    for (name, bytes, needle) in cases {
        let msg = parse_mesh_bytes(bytes, name).unwrap_err().to_string();
        assert!(msg.starts_with(name), "{msg}");
        assert!(msg.contains(needle), "{needle:?} not in {msg}");
    }
}

#[test]
fn parse_mesh_bytes_refuses_external_gltf_buffers() {
    let bin = triangle_buffer();
    let external = format!(
        r#"{{"byteLength": {}, "uri": "tri%20data.bin"}}"#,
        bin.len()
    );
    let json = triangle_gltf_json(&external, 4);
    let msg = parse_mesh_bytes(json.as_bytes(), "scene/x.gltf")
        .unwrap_err()
        .to_string();
    assert!(
        msg.starts_with("scene/x.gltf: unsupported: buffer 0"),
        "{msg}"
    );
    assert!(msg.contains("external URI 'tri%20data.bin'"), "{msg}");
    assert!(
        msg.contains("GLB binary chunk and base64 data URIs"),
        "{msg}"
    );
}

/// `peek_counts` reads sizes without loading: a PLY's header (plain or gzip), a counting pass
/// over an OBJ (fan triangulation: an n-gon is n − 2 triangles), nothing for glTF or a
/// missing file; and a header that claims more than its bytes could hold is capped.
#[test]
fn peek_counts_reads_headers_and_caps_what_the_bytes_cannot_hold() {
    let dir = tempfile::tempdir().unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
    let p = write_file(dir.path(), "a.ply", ply.as_bytes());
    let expect = MeshCounts {
        vertices: 4,
        triangles: 2,
    };
    assert_eq!(peek_counts(&p), Some(expect));
    // The same counts as the loader finds.
    let m = load_mesh(&p).unwrap();
    assert_eq!((m.positions.len(), m.indices.len()), (4, 2));
    let gz = write_file(dir.path(), "a.ply.gz", &gzip(ply.as_bytes()));
    assert_eq!(peek_counts(&gz), Some(expect));

    let obj =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3 4\nf 2 5 3\n# f 1 2 3\nvn 0 0 1\n";
    let p = write_file(dir.path(), "b.obj", obj.as_bytes());
    assert_eq!(
        peek_counts(&p),
        Some(MeshCounts {
            vertices: 5,
            triangles: 3
        })
    );
    assert_eq!(load_mesh(&p).unwrap().indices.len(), 3);

    // A 200-byte header claiming 10⁹ faces and 10⁹ vertices: capped at what 200 bytes hold.
    let liar = "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1000000000\nproperty list uchar int vertex_indices\nend_header\n";
    let p = write_file(dir.path(), "c.ply", liar.as_bytes());
    let len = liar.len() as u64;
    assert_eq!(
        peek_counts(&p),
        Some(MeshCounts {
            vertices: len / 3,
            triangles: len / 4
        })
    );

    assert_eq!(peek_counts(&dir.path().join("missing.ply")), None);
    let gltf = write_file(dir.path(), "d.gltf", b"{}");
    assert_eq!(peek_counts(&gltf), None);
    let garbage = write_file(dir.path(), "e.ply", b"not a ply at all\n");
    assert_eq!(peek_counts(&garbage), None);
}
