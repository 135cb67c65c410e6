//! PLY reading (ASCII, binary little- and big-endian) and compact binary writing.
//!
//! A hand-written reader rather than a generic PLY crate: it reads only what a mesh needs
//! (`vertex` x/y/z and optional nx/ny/nz, `face` vertex_indices), skips other elements and
//! properties, and reports every problem with the line (ASCII) or element and byte offset
//! (binary) where it happens. It never panics and never allocates more than the data can hold.

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{MeshData, MeshError};

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    /// Inclusive range of an integer type.
    fn int_range(self) -> (i64, i64) {
        match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            Scalar::U32 => (0, u32::MAX.into()),
            Scalar::F32 | Scalar::F64 => (i64::MIN, i64::MAX),
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: PropKind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

impl Element {
    /// Smallest possible size of one binary instance (lists counted as empty).
    fn min_binary_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                PropKind::Scalar(s) => s.size(),
                PropKind::List { count, .. } => count.size(),
            })
            .sum()
    }

    fn has_lists(&self) -> bool {
        self.props
            .iter()
            .any(|p| matches!(p.kind, PropKind::List { .. }))
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    LittleEndian,
    BigEndian,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first byte after the `end_header` line.
    body_start: usize,
    /// Number of header lines (the body starts on line `lines + 1`).
    lines: usize,
}

/// What each property of the `vertex` element feeds: x, y, z, nx, ny, nz, or nothing.
const SLOT_NONE: usize = usize::MAX;

/// Where the `vertex` and `face` data we need live in their elements.
struct Layout {
    vertex_element: usize,
    /// For each vertex property, its slot 0..6 (x, y, z, nx, ny, nz) or `SLOT_NONE`.
    vertex_slots: Vec<usize>,
    has_normals: bool,
    face_element: usize,
    /// Index of the vertex-index list among the face properties.
    face_list: usize,
}

fn syntax(path: &Path, at: impl Into<String>, detail: impl Into<String>) -> MeshError {
    MeshError::Syntax {
        path: path.to_path_buf(),
        at: at.into(),
        detail: detail.into(),
    }
}

/// Splits off one line (without `\n` / `\r\n`) starting at `pos`; returns it and the next offset.
fn next_line(data: &[u8], pos: usize) -> Option<(&[u8], usize)> {
    if pos >= data.len() {
        return None;
    }
    let rest = &data[pos..];
    let (line, next) = match rest.iter().position(|&b| b == b'\n') {
        Some(i) => (&rest[..i], pos + i + 1),
        None => (rest, data.len()),
    };
    let line = line.strip_suffix(b"\r").unwrap_or(line);
    Some((line, next))
}

/// `(vertices, faces)` declared by the header at the start of `data`, if it parses.
pub(super) fn header_counts(path: &Path, data: &[u8]) -> Option<(u64, u64)> {
    let header = parse_header(path, data).ok()?;
    let count = |name: &str| {
        header
            .elements
            .iter()
            .find(|e| e.name == name)
            .map(|e| e.count as u64)
    };
    Some((count("vertex")?, count("face").unwrap_or(0)))
}

fn parse_header(path: &Path, data: &[u8]) -> Result<Header, MeshError> {
    let mut pos = 0;
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some((raw, next)) = next_line(data, pos) else {
            return Err(MeshError::Truncated {
                path: path.to_path_buf(),
                at: format!("header line {}", line_no + 1),
                detail: "the file ends before the 'end_header' line".into(),
            });
        };
        line_no += 1;
        if next == data.len() && !data.ends_with(b"\n") {
            return Err(MeshError::Truncated {
                path: path.to_path_buf(),
                at: format!("header line {line_no}"),
                detail: "the file ends inside the header, before the 'end_header' line".into(),
            });
        }
        pos = next;
        let at = format!("header line {line_no}");
        let Ok(line) = std::str::from_utf8(raw) else {
            return Err(syntax(
                path,
                at,
                if line_no == 1 {
                    "not a PLY file (the first line must be 'ply'; found binary data)"
                } else {
                    "the header line is not text"
                },
            ));
        };
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        if line_no == 1 {
            if words != ["ply"] {
                return Err(syntax(
                    path,
                    at,
                    format!(
                        "not a PLY file (the first line must be 'ply', found '{}')",
                        truncate(line, 40)
                    ),
                ));
            }
            continue;
        }
        match words.first().copied() {
            None => continue,
            Some("comment" | "obj_info") => continue,
            Some("end_header") => break,
            Some("format") => {
                if words.len() != 3 {
                    return Err(syntax(
                        path,
                        at,
                        "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'",
                    ));
                }
                encoding = Some(match words[1] {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::LittleEndian,
                    "binary_big_endian" => Encoding::BigEndian,
                    other => {
                        return Err(syntax(path, at, format!("unknown PLY format '{other}'")));
                    }
                });
                if !words[2].starts_with('1') {
                    return Err(syntax(
                        path,
                        at,
                        format!("unsupported PLY version '{}'", words[2]),
                    ));
                }
            }
            Some("element") => {
                if words.len() != 3 {
                    return Err(syntax(path, at, "expected 'element <name> <count>'"));
                }
                let count: usize = words[2].parse().map_err(|_| {
                    syntax(
                        path,
                        &at,
                        format!(
                            "element '{}' count '{}' is not a non-negative integer",
                            words[1], words[2]
                        ),
                    )
                })?;
                if elements.iter().any(|e| e.name == words[1]) {
                    return Err(syntax(
                        path,
                        at,
                        format!("element '{}' is declared twice", words[1]),
                    ));
                }
                elements.push(Element {
                    name: words[1].to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let Some(element) = elements.last_mut() else {
                    return Err(syntax(path, at, "'property' before any 'element'"));
                };
                let bad_type = |t: &str| syntax(path, &at, format!("unknown property type '{t}'"));
                let (name, kind) = match words.as_slice() {
                    ["property", "list", count, item, name] => {
                        let count = Scalar::parse(count).ok_or_else(|| bad_type(count))?;
                        let item = Scalar::parse(item).ok_or_else(|| bad_type(item))?;
                        if !count.is_integer() {
                            return Err(syntax(
                                path,
                                at,
                                format!("list '{name}' has a non-integer count type"),
                            ));
                        }
                        (*name, PropKind::List { count, item })
                    }
                    ["property", ty, name] if *ty != "list" => (
                        *name,
                        PropKind::Scalar(Scalar::parse(ty).ok_or_else(|| bad_type(ty))?),
                    ),
                    _ => {
                        return Err(syntax(
                            path,
                            at,
                            "expected 'property <type> <name>' or 'property list <count type> <item type> <name>'",
                        ));
                    }
                };
                element.props.push(Property {
                    name: name.to_string(),
                    kind,
                });
            }
            Some(other) => {
                return Err(syntax(
                    path,
                    at,
                    format!("unknown header keyword '{}'", truncate(other, 40)),
                ));
            }
        }
    }
    let Some(encoding) = encoding else {
        return Err(syntax(path, "header", "no 'format' line"));
    };
    Ok(Header {
        encoding,
        elements,
        body_start: pos,
        lines: line_no,
    })
}

fn truncate(s: &str, max: usize) -> String {
    if s.chars().count() <= max {
        s.to_string()
    } else {
        let cut: String = s.chars().take(max).collect();
        format!("{cut}...")
    }
}

fn layout(path: &Path, header: &Header) -> Result<Layout, MeshError> {
    let empty = |detail: &str| MeshError::Empty {
        path: path.to_path_buf(),
        detail: detail.to_string(),
    };
    let Some(vertex_element) = header.elements.iter().position(|e| e.name == "vertex") else {
        return Err(empty("the header declares no 'vertex' element"));
    };
    let Some(face_element) = header.elements.iter().position(|e| e.name == "face") else {
        return Err(empty(
            "the header declares no 'face' element (point clouds are not meshes)",
        ));
    };
    let vertex = &header.elements[vertex_element];
    let names = ["x", "y", "z", "nx", "ny", "nz"];
    let mut found = [false; 6];
    let mut vertex_slots = Vec::with_capacity(vertex.props.len());
    for p in &vertex.props {
        let slot = names.iter().position(|n| *n == p.name);
        if let Some(slot) = slot {
            if matches!(p.kind, PropKind::List { .. }) {
                return Err(syntax(
                    path,
                    "header",
                    format!("vertex property '{}' is a list, expected a number", p.name),
                ));
            }
            if found[slot] {
                return Err(syntax(
                    path,
                    "header",
                    format!("vertex property '{}' is declared twice", p.name),
                ));
            }
            found[slot] = true;
        }
        vertex_slots.push(slot.unwrap_or(SLOT_NONE));
    }
    if let Some(missing) = (0..3).find(|&i| !found[i]) {
        return Err(syntax(
            path,
            "header",
            format!("the vertex element has no '{}' property", names[missing]),
        ));
    }
    // Normals are used only when all three components are present.
    let has_normals = found[3] && found[4] && found[5];
    if !has_normals {
        for s in &mut vertex_slots {
            if *s >= 3 {
                *s = SLOT_NONE;
            }
        }
    }
    let face = &header.elements[face_element];
    let Some(face_list) = face
        .props
        .iter()
        .position(|p| p.name == "vertex_indices" || p.name == "vertex_index")
    else {
        return Err(syntax(
            path,
            "header",
            "the face element has no 'vertex_indices' (or 'vertex_index') property",
        ));
    };
    match face.props[face_list].kind {
        PropKind::List { item, .. } if item.is_integer() => {}
        _ => {
            return Err(syntax(
                path,
                "header",
                format!(
                    "face property '{}' must be a list of integers",
                    face.props[face_list].name
                ),
            ));
        }
    }
    if u32::try_from(vertex.count).is_err() {
        return Err(MeshError::Unsupported {
            path: path.to_path_buf(),
            detail: format!("{} vertices (at most {} supported)", vertex.count, u32::MAX),
        });
    }
    if vertex.count == 0 {
        return Err(empty("the vertex element has 0 vertices"));
    }
    if face.count == 0 {
        return Err(empty("the face element has 0 faces"));
    }
    Ok(Layout {
        vertex_element,
        vertex_slots,
        has_normals,
        face_element,
        face_list,
    })
}

/// Accumulates the mesh as elements are read.
struct Builder {
    path: PathBuf,
    vertex_count: usize,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    has_normals: bool,
    indices: Vec<[u32; 3]>,
}

impl Builder {
    /// `vals` holds x, y, z, nx, ny, nz.
    fn vertex(&mut self, vals: &[f64; 6], at: impl FnOnce() -> String) -> Result<(), MeshError> {
        let p = Vec3::new(vals[0] as f32, vals[1] as f32, vals[2] as f32);
        if !p.is_finite() {
            return Err(MeshError::NonFinite {
                path: self.path.clone(),
                at: at(),
                value: format!("({}, {}, {})", vals[0], vals[1], vals[2]),
            });
        }
        self.positions.push(p);
        if self.has_normals {
            self.normals
                .push(Vec3::new(vals[3] as f32, vals[4] as f32, vals[5] as f32));
        }
        Ok(())
    }

    /// Fan-triangulates one polygon after checking its size and indices.
    fn face(&mut self, poly: &[i64], at: impl Fn() -> String) -> Result<(), MeshError> {
        if poly.len() < 3 {
            return Err(MeshError::FaceTooSmall {
                path: self.path.clone(),
                at: at(),
                vertices: poly.len(),
            });
        }
        if let Some(&bad) = poly
            .iter()
            .find(|&&i| i < 0 || i as u64 >= self.vertex_count as u64)
        {
            return Err(MeshError::IndexOutOfRange {
                path: self.path.clone(),
                at: at(),
                kind: "vertex",
                index: bad,
                available: self.vertex_count,
            });
        }
        // In range of a u32-sized vertex count, so the casts are exact.
        let v0 = poly[0] as u32;
        for w in poly[1..].windows(2) {
            self.indices.push([v0, w[0] as u32, w[1] as u32]);
        }
        Ok(())
    }

    fn finish(self) -> MeshData {
        MeshData {
            positions: self.positions,
            normals: self.has_normals.then_some(self.normals),
            indices: self.indices,
        }
    }
}

/// Parses a (decompressed) PLY file.
pub(super) fn parse_ply(path: &Path, data: &[u8]) -> Result<MeshData, MeshError> {
    let header = parse_header(path, data)?;
    let layout = layout(path, &header)?;
    let vertex_count = header.elements[layout.vertex_element].count;
    let face_count = header.elements[layout.face_element].count;
    let body = &data[header.body_start..];
    // Never reserve more than the body could possibly hold.
    let cap = |n: usize, min_size: usize| n.min(body.len() / min_size.max(1) + 1);
    let mut builder = Builder {
        path: path.to_path_buf(),
        vertex_count,
        positions: Vec::with_capacity(cap(vertex_count, 2)),
        normals: Vec::new(),
        has_normals: layout.has_normals,
        indices: Vec::with_capacity(cap(face_count, 4)),
    };
    if layout.has_normals {
        builder.normals.reserve(builder.positions.capacity());
    }
    match header.encoding {
        Encoding::Ascii => read_ascii(path, &header, &layout, body, &mut builder)?,
        Encoding::LittleEndian | Encoding::BigEndian => {
            read_binary(path, &header, &layout, body, &mut builder)?
        }
    }
    Ok(builder.finish())
}

fn parse_ascii_number(token: &[u8], ty: Scalar) -> Result<f64, String> {
    let show = || String::from_utf8_lossy(token).into_owned();
    let Ok(s) = std::str::from_utf8(token) else {
        return Err(format!("'{}' is not a number", truncate(&show(), 40)));
    };
    match ty {
        Scalar::F32 => s.parse::<f32>().map(f64::from),
        Scalar::F64 => s.parse::<f64>(),
        _ => {
            let v: i64 = s.parse().map_err(|_| {
                format!(
                    "'{}' is not an integer ({} expected)",
                    truncate(s, 40),
                    ty.name()
                )
            })?;
            let (lo, hi) = ty.int_range();
            if v < lo || v > hi {
                return Err(format!("{v} is out of range for {}", ty.name()));
            }
            return Ok(v as f64);
        }
    }
    .map_err(|_| {
        format!(
            "'{}' is not a number ({} expected)",
            truncate(s, 40),
            ty.name()
        )
    })
}

fn read_ascii(
    path: &Path,
    header: &Header,
    layout: &Layout,
    body: &[u8],
    b: &mut Builder,
) -> Result<(), MeshError> {
    let mut pos = 0;
    let mut line_no = header.lines;
    let mut poly: Vec<i64> = Vec::with_capacity(16);
    for (ei, element) in header.elements.iter().enumerate() {
        if element.props.is_empty() {
            continue; // nothing to read (and blank lines are skipped anyway)
        }
        for k in 0..element.count {
            // Next non-blank line.
            let line = loop {
                let Some((line, next)) = next_line(body, pos) else {
                    return Err(MeshError::Truncated {
                        path: path.to_path_buf(),
                        at: format!("line {}", line_no + 1),
                        detail: format!(
                            "the file ends after {k} of the {} '{}' elements the header declares",
                            element.count, element.name
                        ),
                    });
                };
                pos = next;
                line_no += 1;
                if line.iter().any(|c| !c.is_ascii_whitespace()) {
                    break line;
                }
            };
            let at = || format!("line {line_no} ({} {k})", element.name);
            let mut tokens = line
                .split(|c| c.is_ascii_whitespace())
                .filter(|t| !t.is_empty());
            let mut taken = 0usize;
            let mut next_value = |ty: Scalar, what: &str| -> Result<f64, MeshError> {
                let Some(tok) = tokens.next() else {
                    return Err(syntax(
                        path,
                        at(),
                        format!(
                            "the line ends after {taken} values, but '{what}' is still expected"
                        ),
                    ));
                };
                taken += 1;
                parse_ascii_number(tok, ty).map_err(|e| syntax(path, at(), format!("{what}: {e}")))
            };
            let mut vals = [0f64; 6];
            poly.clear();
            for (pi, prop) in element.props.iter().enumerate() {
                match prop.kind {
                    PropKind::Scalar(ty) => {
                        let v = next_value(ty, &prop.name)?;
                        if ei == layout.vertex_element && layout.vertex_slots[pi] != SLOT_NONE {
                            vals[layout.vertex_slots[pi]] = v;
                        }
                    }
                    PropKind::List { count, item } => {
                        let n = next_value(count, &format!("{} count", prop.name))?;
                        if n < 0.0 {
                            return Err(syntax(
                                path,
                                at(),
                                format!("{} has a negative count {n}", prop.name),
                            ));
                        }
                        let is_face_list = ei == layout.face_element && pi == layout.face_list;
                        for _ in 0..n as u64 {
                            let v = next_value(item, &prop.name)?;
                            if is_face_list {
                                poly.push(v as i64);
                            }
                        }
                    }
                }
            }
            if let Some(extra) = tokens.next() {
                return Err(MeshError::CountMismatch {
                    path: path.to_path_buf(),
                    detail: format!(
                        "line {line_no} ({} {k}): unexpected extra value '{}' after the {} \
                         declared properties (do the header's element counts match the data?)",
                        element.name,
                        truncate(&String::from_utf8_lossy(extra), 40),
                        element.props.len()
                    ),
                });
            }
            if ei == layout.vertex_element {
                b.vertex(&vals, at)?;
            } else if ei == layout.face_element {
                b.face(&poly, at)?;
            }
        }
    }
    // Anything but blank lines after the last element means the counts are wrong.
    while let Some((line, next)) = next_line(body, pos) {
        pos = next;
        line_no += 1;
        if line.iter().any(|c| !c.is_ascii_whitespace()) {
            let counts: Vec<String> = header
                .elements
                .iter()
                .map(|e| format!("{} {}", e.count, e.name))
                .collect();
            return Err(MeshError::CountMismatch {
                path: path.to_path_buf(),
                detail: format!(
                    "line {line_no}: extra data after the last element (the header declares {})",
                    counts.join(", ")
                ),
            });
        }
    }
    Ok(())
}

struct BinReader<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl BinReader<'_> {
    fn read(&mut self, ty: Scalar) -> Option<f64> {
        let n = ty.size();
        let bytes = self.data.get(self.pos..self.pos + n)?;
        self.pos += n;
        let mut buf = [0u8; 8];
        buf[..n].copy_from_slice(bytes);
        if self.big_endian {
            buf[..n].reverse();
        }
        let v = match ty {
            Scalar::I8 => f64::from(buf[0] as i8),
            Scalar::U8 => f64::from(buf[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([buf[0], buf[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([buf[0], buf[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([buf[0], buf[1], buf[2], buf[3]])),
            Scalar::F64 => f64::from_le_bytes(buf),
        };
        Some(v)
    }
}

fn read_binary(
    path: &Path,
    header: &Header,
    layout: &Layout,
    body: &[u8],
    b: &mut Builder,
) -> Result<(), MeshError> {
    let mut r = BinReader {
        data: body,
        pos: 0,
        big_endian: header.encoding == Encoding::BigEndian,
    };
    let mut poly: Vec<i64> = Vec::with_capacity(16);
    for (ei, element) in header.elements.iter().enumerate() {
        if element.props.is_empty() {
            continue; // zero bytes per element: nothing to read, however large the count
        }
        // Fixed-size elements: check the whole block up front for a precise message.
        if !element.has_lists() {
            let size = element.min_binary_size();
            let need = size.checked_mul(element.count);
            let left = body.len() - r.pos;
            if need.is_none_or(|need| need > left) {
                let complete = left / size.max(1);
                return Err(MeshError::Truncated {
                    path: path.to_path_buf(),
                    at: format!(
                        "{} {complete} (byte offset {})",
                        element.name,
                        header.body_start + r.pos + complete * size
                    ),
                    detail: format!(
                        "the header declares {} '{}' elements of {size} bytes, but the file \
                         ends after {complete} of them",
                        element.count, element.name
                    ),
                });
            }
        }
        for k in 0..element.count {
            let start = r.pos;
            let truncated = |r: &BinReader, what: &str| MeshError::Truncated {
                path: path.to_path_buf(),
                at: format!(
                    "{} {k} (byte offset {})",
                    element.name,
                    header.body_start + start
                ),
                detail: format!(
                    "the file ends inside property '{what}' ({} bytes left); the header declares {} '{}' elements",
                    body.len() - r.pos,
                    element.count,
                    element.name
                ),
            };
            let at = || {
                format!(
                    "{} {k} (byte offset {})",
                    element.name,
                    header.body_start + start
                )
            };
            let mut vals = [0f64; 6];
            poly.clear();
            for (pi, prop) in element.props.iter().enumerate() {
                match prop.kind {
                    PropKind::Scalar(ty) => {
                        let v = r.read(ty).ok_or_else(|| truncated(&r, &prop.name))?;
                        if ei == layout.vertex_element && layout.vertex_slots[pi] != SLOT_NONE {
                            vals[layout.vertex_slots[pi]] = v;
                        }
                    }
                    PropKind::List { count, item } => {
                        let n = r.read(count).ok_or_else(|| truncated(&r, &prop.name))?;
                        if n < 0.0 {
                            return Err(syntax(
                                path,
                                at(),
                                format!("{} has a negative count {n}", prop.name),
                            ));
                        }
                        let n = n as usize;
                        let is_face_list = ei == layout.face_element && pi == layout.face_list;
                        if !is_face_list {
                            // Skip without reading item by item.
                            let skip = n.saturating_mul(item.size());
                            if skip > body.len() - r.pos {
                                return Err(truncated(&r, &prop.name));
                            }
                            r.pos += skip;
                            continue;
                        }
                        for _ in 0..n {
                            let v = r.read(item).ok_or_else(|| truncated(&r, &prop.name))?;
                            poly.push(v as i64);
                        }
                    }
                }
            }
            if ei == layout.vertex_element {
                b.vertex(&vals, at)?;
            } else if ei == layout.face_element {
                b.face(&poly, at)?;
            }
        }
    }
    if r.pos < body.len() {
        let counts: Vec<String> = header
            .elements
            .iter()
            .map(|e| format!("{} {}", e.count, e.name))
            .collect();
        return Err(MeshError::CountMismatch {
            path: path.to_path_buf(),
            detail: format!(
                "{} bytes of data after the last element at byte offset {} (the header declares {})",
                body.len() - r.pos,
                header.body_start + r.pos,
                counts.join(", ")
            ),
        });
    }
    Ok(())
}

/// Serialises `mesh` as a binary little-endian PLY (uncompressed). Vertex indices are stored as
/// `ushort` when there are at most 65,536 vertices and as `uint` otherwise; normals only when
/// `mesh.normals` is `Some`.
pub(super) fn encode_ply_binary(mesh: &MeshData) -> Vec<u8> {
    let has_normals = mesh.normals.is_some();
    let small = mesh.positions.len() <= 1 << 16;
    let mut out = Vec::with_capacity(
        256 + mesh.positions.len() * if has_normals { 24 } else { 12 }
            + mesh.indices.len() * if small { 7 } else { 13 },
    );
    let mut head = String::new();
    head.push_str("ply\nformat binary_little_endian 1.0\ncomment written by interreflect\n");
    head.push_str(&format!("element vertex {}\n", mesh.positions.len()));
    head.push_str("property float x\nproperty float y\nproperty float z\n");
    if has_normals {
        head.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    head.push_str(&format!("element face {}\n", mesh.indices.len()));
    head.push_str(if small {
        "property list uchar ushort vertex_indices\n"
    } else {
        "property list uchar uint vertex_indices\n"
    });
    head.push_str("end_header\n");
    out.extend_from_slice(head.as_bytes());
    for (i, p) in mesh.positions.iter().enumerate() {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        if let Some(normals) = &mesh.normals {
            for c in normals[i].to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    for tri in &mesh.indices {
        out.push(3);
        for &i in tri {
            if small {
                // Indices are < 65,536 here (validated against the vertex count).
                out.extend_from_slice(&(i as u16).to_le_bytes());
            } else {
                out.extend_from_slice(&i.to_le_bytes());
            }
        }
    }
    out
}

/// Writes `mesh` as a compact binary little-endian PLY, gzip-compressed (best compression,
/// reproducible: no timestamp or file name in the gzip header), atomically: a failed write
/// leaves any previous file untouched. Writes normals when `mesh.normals` is `Some`.
pub fn write_ply_binary_gz(path: &Path, mesh: &MeshData) -> Result<(), MeshError> {
    super::validate(mesh, &path.display().to_string())?;
    if mesh.positions.is_empty() || mesh.indices.is_empty() {
        return Err(MeshError::InvalidMesh {
            label: path.display().to_string(),
            detail: format!(
                "refusing to write an empty mesh ({} vertices, {} triangles)",
                mesh.positions.len(),
                mesh.indices.len()
            ),
        });
    }
    let bytes = encode_ply_binary(mesh);
    crate::fsutil::write_atomic(path, |w| {
        let mut gz = flate2::GzBuilder::new().write(w, flate2::Compression::best());
        gz.write_all(&bytes)?;
        gz.finish()?;
        Ok(())
    })
    .map_err(|error| MeshError::Write {
        path: path.to_path_buf(),
        error,
    })
}
