//! glTF 2.0 reading (`.gltf` with external or embedded buffers, and `.glb`).
//!
//! The `gltf` crate parses and validates the JSON document; the GLB container, buffer loading
//! and accessor reading are done here with explicit bounds checks, so malformed files give
//! precise errors instead of panics. (The whole load still runs under `catch_unwind` as a last
//! resort against a panic inside the dependency.)
//!
//! All triangle primitives of all nodes reachable from the default scene (else the first scene,
//! else every root node) are merged with their world transforms applied; normals use the
//! inverse-transpose, and triangles under a mirroring transform (negative determinant) have
//! their winding flipped so they keep facing outwards. Primitives in other modes (points,
//! lines, strips, fans) are rejected, as are sparse and quantized accessors.

use std::path::{Path, PathBuf};

use glam::{Mat3, Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};

use super::{MeshData, MeshError};

/// Where a glTF's buffers may come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Buffers {
    /// GLB binary chunk, data URIs and files relative to the glTF file (a file on disk).
    Files,
    /// GLB binary chunk and data URIs only (a glTF held in memory: there is no directory to
    /// resolve relative URIs against).
    Embedded,
}

fn gltf_err(path: &Path, detail: impl Into<String>) -> MeshError {
    MeshError::Gltf {
        path: path.to_path_buf(),
        detail: detail.into(),
    }
}

fn read_u32(data: &[u8], at: usize) -> Option<u32> {
    let b = data.get(at..at + 4)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk.
fn split_glb<'a>(path: &Path, data: &'a [u8]) -> Result<(&'a [u8], Option<&'a [u8]>), MeshError> {
    let truncated = |at: String, detail: String| MeshError::Truncated {
        path: path.to_path_buf(),
        at,
        detail,
    };
    let (Some(version), Some(length)) = (read_u32(data, 4), read_u32(data, 8)) else {
        return Err(truncated(
            "GLB header".into(),
            format!("{} bytes, the GLB header needs 12", data.len()),
        ));
    };
    if version != 2 {
        return Err(MeshError::Unsupported {
            path: path.to_path_buf(),
            detail: format!("GLB version {version} (only glTF 2.0 is supported)"),
        });
    }
    let length = length as usize;
    if length > data.len() {
        return Err(truncated(
            "GLB header".into(),
            format!(
                "the header declares {length} bytes, but the file has {}",
                data.len()
            ),
        ));
    }
    if length < 20 {
        return Err(gltf_err(
            path,
            format!("GLB length {length} is too small to hold a JSON chunk"),
        ));
    }
    let data = &data[..length];
    let mut pos = 12;
    let mut json = None;
    let mut bin = None;
    let mut chunk = 0;
    while pos < data.len() {
        let (Some(len), Some(ty)) = (read_u32(data, pos), data.get(pos + 4..pos + 8)) else {
            return Err(truncated(
                format!("GLB chunk {chunk} (byte offset {pos})"),
                "the file ends inside the chunk header".into(),
            ));
        };
        let start = pos + 8;
        let end = start.checked_add(len as usize).filter(|&e| e <= data.len());
        let Some(end) = end else {
            return Err(truncated(
                format!("GLB chunk {chunk} (byte offset {pos})"),
                format!(
                    "the chunk declares {len} bytes, but only {} remain",
                    data.len() - start
                ),
            ));
        };
        match (chunk, ty) {
            (0, b"JSON") => json = Some(&data[start..end]),
            (0, _) => {
                return Err(gltf_err(
                    path,
                    "the first GLB chunk is not a JSON chunk".to_string(),
                ));
            }
            (1, b"BIN\0") => bin = Some(&data[start..end]),
            _ => {} // unknown chunks are ignored, as the specification requires
        }
        chunk += 1;
        // Chunks are 4-byte aligned.
        pos = end.next_multiple_of(4);
    }
    let Some(json) = json else {
        return Err(gltf_err(path, "the GLB has no JSON chunk"));
    };
    Ok((json, bin))
}

/// Decodes `%XX` escapes in a relative URI (invalid escapes are kept literally).
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && let Some(h) = bytes.get(i + 1..i + 3)
            && h.iter().all(u8::is_ascii_hexdigit)
            && let Ok(v) = u8::from_str_radix(&String::from_utf8_lossy(h), 16)
        {
            out.push(v);
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn load_buffers(
    path: &Path,
    doc: &gltf::Document,
    mut blob: Option<&[u8]>,
    sources: Buffers,
) -> Result<Vec<Vec<u8>>, MeshError> {
    let base = path.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => match blob.take() {
                Some(b) => b.to_vec(),
                None => {
                    return Err(gltf_err(
                        path,
                        format!("buffer {i} refers to the GLB binary chunk, but the file has none"),
                    ));
                }
            },
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                if !uri.contains(";base64,") {
                    return Err(MeshError::Unsupported {
                        path: path.to_path_buf(),
                        detail: format!("buffer {i}: only base64 data URIs are supported"),
                    });
                }
                gltf::buffer::Data::from_source(buffer.source(), None)
                    .map_err(|e| gltf_err(path, format!("buffer {i}: bad base64 data URI: {e}")))?
                    .0
            }
            gltf::buffer::Source::Uri(uri) => {
                if uri.contains("://") || uri.starts_with("file:") {
                    return Err(MeshError::Unsupported {
                        path: path.to_path_buf(),
                        detail: format!(
                            "buffer {i}: URI '{uri}' (only relative file paths and data URIs are supported)"
                        ),
                    });
                }
                if sources == Buffers::Embedded {
                    return Err(MeshError::Unsupported {
                        path: path.to_path_buf(),
                        detail: format!(
                            "buffer {i}: external URI '{uri}' (a glTF parsed from memory can only use \
                             its GLB binary chunk and base64 data URIs)"
                        ),
                    });
                }
                let file: PathBuf = base.join(percent_decode(uri));
                std::fs::read(&file).map_err(|e| {
                    gltf_err(
                        path,
                        format!(
                            "buffer {i} ('{uri}', resolved to {}) cannot be read: {e}",
                            file.display()
                        ),
                    )
                })?
            }
        };
        if data.len() < buffer.length() {
            return Err(MeshError::Truncated {
                path: path.to_path_buf(),
                at: format!("buffer {i}"),
                detail: format!(
                    "the buffer declares {} bytes, but its data has only {}",
                    buffer.length(),
                    data.len()
                ),
            });
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes of each element of an accessor, bounds-checked: `(data, offset, stride, count)`.
fn accessor_bytes<'b>(
    path: &Path,
    acc: &gltf::Accessor,
    buffers: &'b [Vec<u8>],
    what: &str,
) -> Result<(&'b [u8], usize, usize), MeshError> {
    let i = acc.index();
    if acc.sparse().is_some() {
        return Err(MeshError::Unsupported {
            path: path.to_path_buf(),
            detail: format!("{what}: accessor {i} is sparse"),
        });
    }
    let Some(view) = acc.view() else {
        return Err(gltf_err(
            path,
            format!("{what}: accessor {i} has no bufferView"),
        ));
    };
    let buffer = &buffers[view.buffer().index()];
    let view_end = view.offset().checked_add(view.length());
    let Some(view_bytes) = view_end.and_then(|e| buffer.get(view.offset()..e)) else {
        return Err(gltf_err(
            path,
            format!(
                "{what}: bufferView {} (offset {}, length {}) lies outside buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            ),
        ));
    };
    let size = acc.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(gltf_err(
            path,
            format!(
                "{what}: bufferView {} has byteStride {stride}, smaller than accessor {i}'s element size {size}",
                view.index()
            ),
        ));
    }
    let count = acc.count();
    if count > 0 {
        let need = stride
            .checked_mul(count - 1)
            .and_then(|x| x.checked_add(size))
            .and_then(|x| x.checked_add(acc.offset()));
        if need.is_none_or(|n| n > view_bytes.len()) {
            return Err(gltf_err(
                path,
                format!(
                    "{what}: accessor {i} ({count} elements of {size} bytes, stride {stride}, offset {}) \
                     does not fit in bufferView {} ({} bytes)",
                    acc.offset(),
                    view.index(),
                    view_bytes.len()
                ),
            ));
        }
    }
    Ok((view_bytes, acc.offset(), stride))
}

fn read_vec3s(
    path: &Path,
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<Vec3>, MeshError> {
    if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 {
        return Err(MeshError::Unsupported {
            path: path.to_path_buf(),
            detail: format!(
                "{what}: accessor {} is {:?} {:?}, expected float VEC3 (quantized attributes are not supported)",
                acc.index(),
                acc.data_type(),
                acc.dimensions()
            ),
        });
    }
    let (bytes, offset, stride) = accessor_bytes(path, acc, buffers, what)?;
    let f = |b: &[u8], at: usize| f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
    Ok((0..acc.count())
        .map(|k| {
            let at = offset + k * stride;
            Vec3::new(f(bytes, at), f(bytes, at + 4), f(bytes, at + 8))
        })
        .collect())
}

fn read_indices(
    path: &Path,
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<u32>, MeshError> {
    if acc.dimensions() != Dimensions::Scalar
        || !matches!(
            acc.data_type(),
            DataType::U8 | DataType::U16 | DataType::U32
        )
    {
        return Err(gltf_err(
            path,
            format!(
                "{what}: index accessor {} is {:?} {:?}, expected an unsigned integer SCALAR",
                acc.index(),
                acc.data_type(),
                acc.dimensions()
            ),
        ));
    }
    let (bytes, offset, stride) = accessor_bytes(path, acc, buffers, what)?;
    let ty = acc.data_type();
    Ok((0..acc.count())
        .map(|k| {
            let at = offset + k * stride;
            match ty {
                DataType::U8 => u32::from(bytes[at]),
                DataType::U16 => u32::from(u16::from_le_bytes([bytes[at], bytes[at + 1]])),
                _ => u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]),
            }
        })
        .collect())
}

struct Merged {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    all_normals: bool,
    indices: Vec<[u32; 3]>,
    primitives: usize,
}

fn add_mesh(
    path: &Path,
    mesh: &gltf::Mesh,
    world: Mat4,
    node: Option<usize>,
    buffers: &[Vec<u8>],
    out: &mut Merged,
) -> Result<(), MeshError> {
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let flip = Mat3::from_mat4(world).determinant() < 0.0;
    for prim in mesh.primitives() {
        let what = format!(
            "{}mesh {}{} primitive {}",
            node.map(|n| format!("node {n} ")).unwrap_or_default(),
            mesh.index(),
            mesh.name().map(|n| format!(" '{n}'")).unwrap_or_default(),
            prim.index()
        );
        if prim.mode() != gltf::mesh::Mode::Triangles {
            return Err(MeshError::Unsupported {
                path: path.to_path_buf(),
                detail: format!(
                    "{what}: mode {:?} (only TRIANGLES primitives are supported)",
                    prim.mode()
                ),
            });
        }
        let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
            return Err(gltf_err(path, format!("{what}: no POSITION attribute")));
        };
        let positions = read_vec3s(path, &pos_acc, buffers, &format!("{what} POSITION"))?;
        let normals = match prim.get(&gltf::Semantic::Normals) {
            Some(acc) => {
                let n = read_vec3s(path, &acc, buffers, &format!("{what} NORMAL"))?;
                if n.len() != positions.len() {
                    return Err(gltf_err(
                        path,
                        format!(
                            "{what}: {} normals for {} positions",
                            n.len(),
                            positions.len()
                        ),
                    ));
                }
                Some(n)
            }
            None => None,
        };
        let local: Vec<u32> = match prim.indices() {
            Some(acc) => read_indices(path, &acc, buffers, &format!("{what} indices"))?,
            None => (0..positions.len() as u32).collect(),
        };
        if !local.len().is_multiple_of(3) {
            return Err(gltf_err(
                path,
                format!(
                    "{what}: {} indices is not a multiple of 3 (TRIANGLES)",
                    local.len()
                ),
            ));
        }
        if let Some((k, &bad)) = local
            .iter()
            .enumerate()
            .find(|&(_, &i)| i as usize >= positions.len())
        {
            return Err(MeshError::IndexOutOfRange {
                path: path.to_path_buf(),
                at: format!("{what}, index {k} (triangle {})", k / 3),
                kind: "vertex",
                index: i64::from(bad),
                available: positions.len(),
            });
        }
        let base = out.positions.len();
        if base + positions.len() > u32::MAX as usize {
            return Err(MeshError::Unsupported {
                path: path.to_path_buf(),
                detail: format!("more than {} vertices in total", u32::MAX),
            });
        }
        for (k, p) in positions.iter().enumerate() {
            let w = world.transform_point3(*p);
            if !w.is_finite() {
                return Err(MeshError::NonFinite {
                    path: path.to_path_buf(),
                    at: format!("{what}, vertex {k} (after the node transform)"),
                    value: format!("({}, {}, {})", w.x, w.y, w.z),
                });
            }
            out.positions.push(w);
        }
        match normals {
            Some(n) => out
                .normals
                .extend(n.iter().map(|n| (normal_matrix * *n).normalize_or_zero())),
            None => {
                out.all_normals = false;
                out.normals
                    .extend(std::iter::repeat_n(Vec3::ZERO, positions.len()));
            }
        }
        let base = base as u32;
        out.indices.extend(local.chunks_exact(3).map(|t| {
            if flip {
                [base + t[0], base + t[2], base + t[1]]
            } else {
                [base + t[0], base + t[1], base + t[2]]
            }
        }));
        out.primitives += 1;
    }
    Ok(())
}

/// Merges the meshes of the trees under `roots`, iteratively (no recursion, so a deep hierarchy
/// cannot overflow the stack). The hierarchy must be a forest: a node with two parents, a cycle
/// or a root listed twice is an error, which also bounds the work by the number of nodes.
fn visit_roots(
    path: &Path,
    doc: &gltf::Document,
    roots: Vec<gltf::Node>,
    buffers: &[Vec<u8>],
    out: &mut Merged,
) -> Result<(), MeshError> {
    let n = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; n];
    for node in doc.nodes() {
        for child in node.children() {
            let c = child.index();
            if let Some(p) = parent[c] {
                return Err(gltf_err(
                    path,
                    format!(
                        "node {c} is a child of both node {p} and node {} (the node hierarchy must be a tree)",
                        node.index()
                    ),
                ));
            }
            parent[c] = Some(node.index());
        }
    }
    let mut visited = vec![false; n];
    let mut stack: Vec<(gltf::Node, Mat4)> = roots
        .into_iter()
        .rev()
        .map(|r| (r, Mat4::IDENTITY))
        .collect();
    while let Some((node, parent_world)) = stack.pop() {
        let i = node.index();
        if visited[i] {
            return Err(gltf_err(
                path,
                format!(
                    "node {i} is reached twice (the node hierarchy has a cycle, or a scene lists a node twice)"
                ),
            ));
        }
        visited[i] = true;
        let world = parent_world * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            add_mesh(path, &mesh, world, Some(i), buffers, out)?;
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(())
}

/// Parses and validates the JSON document.
///
/// The `gltf` crate's validation (gltf-json 1.4.1, `mesh.rs`, `primitive_validate_hook`) indexes
/// the accessor array with each primitive's `POSITION` index before that index is checked, and
/// panics when it is out of range (found by fuzzing: `tests/data/fuzz/gltf/position-accessor-
/// out-of-range`). That index is therefore checked here first, on the unvalidated document.
fn parse_document(path: &Path, json: &[u8]) -> Result<gltf::Document, MeshError> {
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;

    let unchecked = gltf::Gltf::from_slice_without_validation(json)
        .map_err(|e| gltf_err(path, e.to_string()))?
        .document
        .into_json();
    let accessors = unchecked.accessors.len();
    for (m, mesh) in unchecked.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(i) = prim.attributes.get(&Checked::Valid(Semantic::Positions))
                && i.value() >= accessors
            {
                return Err(gltf_err(
                    path,
                    format!(
                        "meshes[{m}].primitives[{p}].attributes[\"POSITION\"]: accessor {} does \
                         not exist (there are {accessors} accessors)",
                        i.value()
                    ),
                ));
            }
        }
    }
    gltf::Document::from_json(unchecked).map_err(|e| gltf_err(path, e.to_string()))
}

fn parse_inner(path: &Path, data: &[u8], sources: Buffers) -> Result<MeshData, MeshError> {
    let (json, blob) = if data.starts_with(b"glTF") {
        split_glb(path, data)?
    } else {
        (data, None)
    };
    let doc = parse_document(path, json)?;
    let doc = &doc;
    if let Some(ext) = doc.extensions_required().next() {
        return Err(MeshError::Unsupported {
            path: path.to_path_buf(),
            detail: format!("the file requires the glTF extension {ext}"),
        });
    }
    let buffers = load_buffers(path, doc, blob, sources)?;
    let mut out = Merged {
        positions: Vec::new(),
        normals: Vec::new(),
        all_normals: true,
        indices: Vec::new(),
        primitives: 0,
    };
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    match scene {
        Some(scene) => {
            visit_roots(path, doc, scene.nodes().collect(), &buffers, &mut out)?;
        }
        None if doc.nodes().len() > 0 => {
            // No scene: every node that is nobody's child is a root.
            let mut is_child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            let roots = doc.nodes().filter(|n| !is_child[n.index()]).collect();
            visit_roots(path, doc, roots, &buffers, &mut out)?;
        }
        None => {
            // No nodes at all: the meshes as they are.
            for mesh in doc.meshes() {
                add_mesh(path, &mesh, Mat4::IDENTITY, None, &buffers, &mut out)?;
            }
        }
    }
    if out.primitives == 0 || out.indices.is_empty() {
        return Err(MeshError::Empty {
            path: path.to_path_buf(),
            detail: format!(
                "no triangles in the scene ({} mesh primitives reached)",
                out.primitives
            ),
        });
    }
    Ok(MeshData {
        positions: out.positions,
        normals: out.all_normals.then_some(out.normals),
        indices: out.indices,
    })
}

/// Parses a `.gltf` (JSON) or `.glb` (binary) file; with [`Buffers::Files`], external buffers
/// are resolved relative to `path`'s directory, with [`Buffers::Embedded`] they are an error.
pub(super) fn parse_gltf(
    path: &Path,
    data: &[u8],
    sources: Buffers,
) -> Result<MeshData, MeshError> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        parse_inner(path, data, sources)
    })) {
        Ok(result) => result,
        Err(panic) => {
            let msg = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(gltf_err(
                path,
                format!("the glTF parser failed on malformed data ({msg})"),
            ))
        }
    }
}
