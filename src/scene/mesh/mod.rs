//! Triangle meshes: loading (PLY, OBJ, glTF), validation, cleaning and compact PLY output.
//!
//! - [`load_mesh`] reads `.ply`, `.ply.gz`, `.obj`, `.obj.gz`, `.gltf` and `.glb` files into a
//!   [`MeshData`]. Every malformed input (truncation, bad counts, out-of-range indices,
//!   non-finite coordinates, garbage, corrupt gzip, ...) is a [`MeshError`] whose message names
//!   the file and the place (line, element, byte offset, accessor) where known; loading never
//!   panics.
//! - [`clean_mesh`] removes zero-area and duplicate triangles, drops unused vertices, computes or
//!   repairs vertex normals and reports what it did in a [`CleanReport`].
//! - [`write_ply_binary_gz`] writes a compact binary little-endian PLY, gzip-compressed, atomically.
//! - [`convert`] is load + clean + write (the `convert-mesh` command).
//!
//! See `docs/meshes.md` for the formats and the exact rules.

mod clean;
mod gltf_io;
mod obj;
mod ply;
#[cfg(test)]
mod tests;

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::Vec3;

pub use clean::{AREA_EPSILON, clean_mesh};
pub use ply::write_ply_binary_gz;

/// An indexed triangle mesh.
///
/// `indices` index `positions` (and `normals`, which has the same length when present). By
/// convention triangles are counter-clockwise seen from the side their normals point to;
/// [`clean_mesh`] repairs normals that disagree with every adjacent triangle's winding.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub indices: Vec<[u32; 3]>,
}

impl MeshData {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// Axis-aligned bounding box `(min, max)` of all positions, or `None` when there are none.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }
}

/// What [`clean_mesh`] changed. Every non-zero removal or repair also appears in `warnings`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CleanReport {
    /// Human-readable warnings, each starting with the label passed to [`clean_mesh`].
    pub warnings: Vec<String>,
    /// Triangles removed because their area was at most [`AREA_EPSILON`] × bbox diagonal².
    pub removed_degenerate: usize,
    /// Triangles removed because an earlier triangle had the same three vertex positions.
    pub removed_duplicate: usize,
    /// Vertex normals replaced (zero length, NaN/infinite, or facing away from every adjacent
    /// triangle).
    pub repaired_normals: usize,
    /// True when the mesh had no normals and area-weighted normals were computed.
    pub computed_normals: bool,
    /// Vertices dropped because no remaining triangle uses them (not a warning: harmless).
    pub removed_unused_vertices: usize,
}

/// Everything that can go wrong loading, cleaning or writing a mesh. Every message starts with
/// the file path (or the caller's label) and says what is wrong and where.
#[derive(thiserror::Error, Debug)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("{}: cannot read the file: {error}", path.display())]
    Read {
        path: PathBuf,
        error: std::io::Error,
    },

    /// The path names a directory.
    #[error(
        "{}: is a directory, not a mesh file (.ply, .ply.gz, .obj, .obj.gz, .gltf or .glb)",
        path.display()
    )]
    IsDirectory { path: PathBuf },

    /// The file name has no supported extension.
    #[error(
        "{}: unknown mesh file extension (supported: .ply, .ply.gz, .obj, .obj.gz, .gltf, .glb)",
        path.display()
    )]
    UnknownExtension { path: PathBuf },

    /// The gzip stream is corrupt, truncated or not gzip at all.
    #[error("{}: corrupt or truncated gzip data: {detail}", path.display())]
    Gzip { path: PathBuf, detail: String },

    /// Malformed content: bad header, a non-number, an unknown statement, non-text bytes...
    #[error("{}: {at}: {detail}", path.display())]
    Syntax {
        path: PathBuf,
        at: String,
        detail: String,
    },

    /// The file ends before all the data its header (or structure) announces.
    #[error("{}: truncated file: {at}: {detail}", path.display())]
    Truncated {
        path: PathBuf,
        at: String,
        detail: String,
    },

    /// The element counts in the header disagree with the data that follows.
    #[error("{}: element counts do not match the data: {detail}", path.display())]
    CountMismatch { path: PathBuf, detail: String },

    /// A face (or glTF index) refers to a vertex, normal or texture coordinate that does not exist.
    #[error(
        "{}: {at}: {kind} index {index} is out of range (there are {available} {})",
        path.display(),
        plural(kind)
    )]
    IndexOutOfRange {
        path: PathBuf,
        at: String,
        kind: &'static str,
        index: i64,
        available: usize,
    },

    /// A vertex position is NaN or infinite.
    #[error("{}: {at}: non-finite vertex position {value}", path.display())]
    NonFinite {
        path: PathBuf,
        at: String,
        value: String,
    },

    /// A face with fewer than three vertices.
    #[error("{}: {at}: face has {vertices} vertices (a face needs at least 3)", path.display())]
    FaceTooSmall {
        path: PathBuf,
        at: String,
        vertices: usize,
    },

    /// No vertices or no faces.
    #[error("{}: empty mesh: {detail}", path.display())]
    Empty { path: PathBuf, detail: String },

    /// Valid input using a feature this loader does not support.
    #[error("{}: unsupported: {detail}", path.display())]
    Unsupported { path: PathBuf, detail: String },

    /// A glTF-specific problem (invalid JSON/document, unreadable buffer, bad accessor, ...).
    #[error("{}: invalid glTF: {detail}", path.display())]
    Gltf { path: PathBuf, detail: String },

    /// A [`MeshData`] given to [`clean_mesh`] or [`write_ply_binary_gz`] is inconsistent.
    #[error("{label}: invalid mesh data: {detail}")]
    InvalidMesh { label: String, detail: String },

    /// Cleaning removed every triangle.
    #[error(
        "{label}: no triangles left after cleaning: of {total} triangles, {degenerate} had \
         (near-)zero area and {duplicate} were duplicates"
    )]
    NothingLeft {
        label: String,
        total: usize,
        degenerate: usize,
        duplicate: usize,
    },

    /// [`convert`] was asked to write over its own input.
    #[error("{}: refusing to convert a mesh onto itself (the output is the input file)", path.display())]
    OutputIsInput { path: PathBuf },

    /// [`convert`] writes gzip-compressed PLY only, so the output name must say so.
    #[error("{}: output file name must end in .ply.gz", path.display())]
    BadOutputName { path: PathBuf },

    /// The output could not be written.
    #[error("{}: cannot write the file: {error}", path.display())]
    Write {
        path: PathBuf,
        error: std::io::Error,
    },
}

/// "vertex" -> "vertices", "normal" -> "normals", ...
fn plural(kind: &str) -> String {
    match kind {
        "vertex" => "vertices".to_string(),
        other => format!("{other}s"),
    }
}

/// The mesh file formats [`load_mesh`] understands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ply,
    Obj,
    Gltf,
}

/// Picks the format from the file name: `(format, gzip-compressed)`.
fn format_of(path: &Path) -> Result<(Format, bool), MeshError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let (stem, gz) = match name.strip_suffix(".gz") {
        Some(stem) => (stem, true),
        None => (name.as_str(), false),
    };
    let format = if stem.ends_with(".ply") {
        Format::Ply
    } else if stem.ends_with(".obj") {
        Format::Obj
    } else if !gz && (stem.ends_with(".gltf") || stem.ends_with(".glb")) {
        Format::Gltf
    } else {
        return Err(MeshError::UnknownExtension {
            path: path.to_path_buf(),
        });
    };
    Ok((format, gz))
}

/// Largest decompressed size accepted from a `.gz` file (a guard against gzip bombs).
const MAX_DECOMPRESSED_BYTES: u64 = 4 << 30;

/// Decompresses a whole gzip file (all members).
fn gunzip(path: &Path, raw: &[u8]) -> Result<Vec<u8>, MeshError> {
    if !raw.starts_with(&[0x1f, 0x8b]) {
        return Err(MeshError::Gzip {
            path: path.to_path_buf(),
            detail: "not gzip data (the file does not start with the gzip signature 1f 8b)".into(),
        });
    }
    let mut out = Vec::with_capacity(raw.len().saturating_mul(4));
    let decoder = flate2::read::MultiGzDecoder::new(raw);
    decoder
        .take(MAX_DECOMPRESSED_BYTES + 1)
        .read_to_end(&mut out)
        .map_err(|e| MeshError::Gzip {
            path: path.to_path_buf(),
            detail: e.to_string(),
        })?;
    if out.len() as u64 > MAX_DECOMPRESSED_BYTES {
        return Err(MeshError::Unsupported {
            path: path.to_path_buf(),
            detail: format!("decompressed data exceeds {MAX_DECOMPRESSED_BYTES} bytes"),
        });
    }
    Ok(out)
}

/// Loads a triangle mesh, choosing the format by extension: `.ply`, `.ply.gz` (ASCII, binary
/// little- or big-endian), `.obj`, `.obj.gz`, `.gltf`, `.glb`. Polygons are fan-triangulated.
///
/// Validates everything (see `docs/meshes.md`); non-finite *positions* are errors, while
/// non-finite or zero *normals* are passed through for [`clean_mesh`] to repair.
pub fn load_mesh(path: &Path) -> Result<MeshData, MeshError> {
    if path.is_dir() {
        return Err(MeshError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let (format, gz) = format_of(path)?;
    let raw = std::fs::read(path).map_err(|error| MeshError::Read {
        path: path.to_path_buf(),
        error,
    })?;
    parse_loaded(path, &raw, format, gz, gltf_io::Buffers::Files)
}

/// Sizes of a mesh file read from its header without loading it (see [`peek_counts`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshCounts {
    pub vertices: u64,
    /// Triangles after fan triangulation (for PLY: the face count, as if every face were a
    /// triangle; polygons make the loaded mesh larger, which the check after loading sees).
    pub triangles: u64,
}

/// The vertex and triangle counts of a mesh file, found cheaply: a PLY's header (only its first
/// 64 KiB are read, decompressed if needed), or one streaming pass over an OBJ that counts
/// `v` and `f` lines without storing them. `None` for glTF/GLB, for a file that cannot be read
/// or parsed (loading it reports the error properly), and for unknown extensions.
///
/// Used to refuse a scene that would not fit the memory budget before its meshes are loaded.
pub fn peek_counts(path: &Path) -> Option<MeshCounts> {
    use std::io::BufRead;
    let (format, gz) = format_of(path).ok()?;
    let file = std::fs::File::open(path).ok()?;
    let file_len = file.metadata().ok()?.len();
    let mut raw = std::io::BufReader::new(file);
    let gz = gz || (format != Format::Gltf && raw.fill_buf().ok()?.starts_with(&[0x1f, 0x8b]));
    let reader: Box<dyn BufRead> = if gz {
        Box::new(std::io::BufReader::new(
            flate2::bufread::MultiGzDecoder::new(raw),
        ))
    } else {
        Box::new(raw)
    };
    match format {
        Format::Ply => {
            let mut head = Vec::new();
            reader.take(64 << 10).read_to_end(&mut head).ok()?;
            let (vertices, faces) = ply::header_counts(path, &head)?;
            // A header may claim more than the file holds (a truncated or hostile file): the
            // counts are capped by what the bytes could encode, at least 3 bytes a vertex and
            // 4 a face in binary PLY, and deflate's largest ratio (1032:1) for gzip, so that
            // such a file reaches the loader and its real error.
            let data_len = if gz {
                file_len.saturating_mul(1032)
            } else {
                file_len
            };
            Some(MeshCounts {
                vertices: vertices.min(data_len / 3),
                triangles: faces.min(data_len / 4),
            })
        }
        Format::Obj => {
            let mut counts = MeshCounts {
                vertices: 0,
                triangles: 0,
            };
            for line in reader.take(MAX_DECOMPRESSED_BYTES).split(b'\n') {
                let line = line.ok()?;
                let mut words = line
                    .split(|b| b.is_ascii_whitespace())
                    .filter(|w| !w.is_empty());
                match words.next() {
                    Some(b"v") => counts.vertices += 1,
                    Some(b"f") => counts.triangles += (words.count() as u64).saturating_sub(2),
                    _ => {}
                }
            }
            Some(counts)
        }
        Format::Gltf => None,
    }
}

/// Parses a mesh held in memory, like [`load_mesh`] without the file system: `name` is used in
/// error messages and its extension decides the format (`.ply`, `.ply.gz`, `.obj`, `.obj.gz`,
/// `.gltf`, `.glb`).
///
/// A glTF read from memory can only use its GLB binary chunk and base64 `data:` URIs; a buffer
/// that refers to an external file is an error naming the URI. Everything else (validation,
/// transparent gzip, messages) is exactly as for [`load_mesh`].
pub fn parse_mesh_bytes(bytes: &[u8], name: &str) -> Result<MeshData, MeshError> {
    let path = Path::new(name);
    let (format, gz) = format_of(path)?;
    parse_loaded(path, bytes, format, gz, gltf_io::Buffers::Embedded)
}

/// The format-independent part of loading: transparent gzip, then the format's parser.
fn parse_loaded(
    path: &Path,
    raw: &[u8],
    format: Format,
    gz: bool,
    buffers: gltf_io::Buffers,
) -> Result<MeshData, MeshError> {
    // A `.ply`/`.obj` that is really gzip-compressed is decompressed transparently.
    let gunzipped;
    let data: &[u8] = if gz || (format != Format::Gltf && raw.starts_with(&[0x1f, 0x8b])) {
        gunzipped = gunzip(path, raw)?;
        &gunzipped
    } else {
        raw
    };
    let mesh = match format {
        Format::Ply => ply::parse_ply(path, data)?,
        Format::Obj => obj::parse_obj(path, data)?,
        Format::Gltf => gltf_io::parse_gltf(path, data, buffers)?,
    };
    debug_assert!(validate(&mesh, &path.display().to_string()).is_ok());
    Ok(mesh)
}

/// Checks the invariants of a [`MeshData`]: indices in range, finite positions, normals (if any)
/// as many as positions, at most `u32::MAX` vertices.
pub(crate) fn validate(mesh: &MeshData, label: &str) -> Result<(), MeshError> {
    let invalid = |detail: String| MeshError::InvalidMesh {
        label: label.to_string(),
        detail,
    };
    let n = mesh.positions.len();
    if u32::try_from(n).is_err() {
        return Err(invalid(format!(
            "{n} vertices (at most {} supported)",
            u32::MAX
        )));
    }
    if let Some(normals) = &mesh.normals
        && normals.len() != n
    {
        return Err(invalid(format!(
            "{} normals for {n} positions",
            normals.len()
        )));
    }
    if let Some(v) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(invalid(format!(
            "vertex {v} has a non-finite position {}",
            mesh.positions[v]
        )));
    }
    for (t, tri) in mesh.indices.iter().enumerate() {
        if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
            return Err(invalid(format!(
                "triangle {t} refers to vertex {i}, but there are {n} vertices"
            )));
        }
    }
    Ok(())
}

/// Loads `input`, cleans it ([`clean_mesh`], labelled with the input path) and writes it to
/// `output` as gzip-compressed binary PLY ([`write_ply_binary_gz`]).
///
/// Normals are stored only when the input had its own normals: computed area-weighted normals
/// are a pure function of the cleaned geometry and are recomputed identically on load, so
/// storing them would only make the file bigger. Refuses `output == input` and an output name
/// not ending in `.ply.gz`.
pub fn convert(input: &Path, output: &Path) -> Result<CleanReport, MeshError> {
    if crate::fsutil::same_file(input, output) {
        return Err(MeshError::OutputIsInput {
            path: output.to_path_buf(),
        });
    }
    let out_name = output
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if !out_name.ends_with(".ply.gz") || out_name == ".ply.gz" {
        return Err(MeshError::BadOutputName {
            path: output.to_path_buf(),
        });
    }
    let mesh = load_mesh(input)?;
    let (mut cleaned, report) = clean_mesh(mesh, &input.display().to_string())?;
    if report.computed_normals {
        cleaned.normals = None;
    }
    write_ply_binary_gz(output, &cleaned)?;
    Ok(report)
}
