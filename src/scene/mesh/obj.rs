//! Wavefront OBJ reading: `v`, `vn`, `vt` and polygonal `f` statements.
//!
//! Hand-written (rather than a generic OBJ crate) so every error names its line. Faces accept
//! `v`, `v/vt`, `v//vn` and `v/vt/vn` corners with 1-based or negative (relative) indices; an
//! index must refer to an element defined *before* the face (as the OBJ format specifies).
//! Polygons are fan-triangulated. Normals are used when every face corner has one; vertices
//! are then split per distinct (position, normal) pair. Materials, groups, texture
//! coordinates, lines and points are ignored; free-form surfaces are rejected.

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use super::{MeshData, MeshError};

/// One face corner: position index, optional normal index (both 0-based, validated).
#[derive(Clone, Copy)]
struct Corner {
    v: u32,
    n: Option<u32>,
}

/// Statements that carry no surface geometry and are skipped.
const IGNORED: &[&str] = &[
    "vp",
    "l",
    "p",
    "o",
    "g",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "usemap",
    "maplib",
    "lod",
    "bevel",
    "c_interp",
    "d_interp",
    "shadow_obj",
    "trace_obj",
    "call",
    "csh",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "ctech",
    "stech",
];

fn parse_f32(token: &str) -> Option<f32> {
    token.parse::<f32>().ok()
}

pub(super) fn parse_obj(path: &Path, data: &[u8]) -> Result<MeshData, MeshError> {
    let syntax = |line: usize, detail: String| MeshError::Syntax {
        path: path.to_path_buf(),
        at: format!("line {line}"),
        detail,
    };
    let mut positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut texcoords = 0usize;
    // Polygons as ranges into `corners`.
    let mut corners: Vec<Corner> = Vec::new();
    let mut polygons: Vec<(usize, usize)> = Vec::new();
    let mut all_have_normals = true;

    let mut pending = String::new(); // a statement continued with a trailing backslash
    let mut pending_start = 0usize;
    let mut poly: Vec<Corner> = Vec::new();
    for (i, raw) in data.split(|&b| b == b'\n').enumerate() {
        let line_no = i + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(syntax(
                line_no,
                "not valid UTF-8 text (is this really an OBJ file?)".into(),
            ));
        };
        if text.contains('\0') {
            return Err(syntax(
                line_no,
                "contains NUL bytes (is this really an OBJ file?)".into(),
            ));
        }
        let text = match text.find('#') {
            Some(c) => &text[..c],
            None => text,
        };
        if pending.is_empty() {
            pending_start = line_no;
        }
        if let Some(cont) = text.trim_end().strip_suffix('\\') {
            pending.push_str(cont);
            pending.push(' ');
            continue;
        }
        pending.push_str(text);
        let statement = std::mem::take(&mut pending);
        let line_no = pending_start;
        let mut words = statement.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        match keyword {
            "v" => {
                let vals: Vec<&str> = words.collect();
                if !(3..=7).contains(&vals.len()) {
                    return Err(syntax(
                        line_no,
                        format!("'v' needs 3 coordinates, found {} values", vals.len()),
                    ));
                }
                let mut xyz = [0f32; 3];
                for (k, tok) in vals.iter().enumerate() {
                    let Some(x) = parse_f32(tok) else {
                        return Err(syntax(
                            line_no,
                            format!("'v' value '{}' is not a number", clip(tok)),
                        ));
                    };
                    if k < 3 {
                        xyz[k] = x;
                    }
                }
                let p = Vec3::from_array(xyz);
                if !p.is_finite() {
                    return Err(MeshError::NonFinite {
                        path: path.to_path_buf(),
                        at: format!("line {line_no} (vertex {})", positions.len() + 1),
                        value: format!("({}, {}, {})", p.x, p.y, p.z),
                    });
                }
                positions.push(p);
            }
            "vn" => {
                let vals: Vec<&str> = words.collect();
                if vals.len() != 3 {
                    return Err(syntax(
                        line_no,
                        format!("'vn' needs 3 components, found {} values", vals.len()),
                    ));
                }
                let mut n = [0f32; 3];
                for (k, tok) in vals.iter().enumerate() {
                    n[k] = parse_f32(tok).ok_or_else(|| {
                        syntax(
                            line_no,
                            format!("'vn' value '{}' is not a number", clip(tok)),
                        )
                    })?;
                }
                // Non-finite normals are kept; clean_mesh repairs them.
                normals.push(Vec3::from_array(n));
            }
            "vt" => {
                let vals: Vec<&str> = words.collect();
                if vals.is_empty() || vals.len() > 3 || vals.iter().any(|t| parse_f32(t).is_none())
                {
                    return Err(syntax(line_no, "'vt' needs 1 to 3 numbers".to_string()));
                }
                texcoords += 1;
            }
            "f" | "fo" => {
                poly.clear();
                for tok in words {
                    let c = parse_corner(
                        path,
                        line_no,
                        tok,
                        positions.len(),
                        texcoords,
                        normals.len(),
                    )?;
                    poly.push(c);
                }
                if poly.len() < 3 {
                    return Err(MeshError::FaceTooSmall {
                        path: path.to_path_buf(),
                        at: format!("line {line_no} (face {})", polygons.len() + 1),
                        vertices: poly.len(),
                    });
                }
                all_have_normals &= poly.iter().all(|c| c.n.is_some());
                let start = corners.len();
                corners.extend_from_slice(&poly);
                polygons.push((start, corners.len()));
            }
            "surf" => {
                return Err(MeshError::Unsupported {
                    path: path.to_path_buf(),
                    detail: format!(
                        "line {line_no}: free-form surfaces ('surf') are not supported"
                    ),
                });
            }
            k if IGNORED.contains(&k) => {}
            other => {
                return Err(syntax(
                    line_no,
                    format!(
                        "unknown statement '{}' (is this really an OBJ file?)",
                        clip(other)
                    ),
                ));
            }
        }
    }
    if !pending.trim().is_empty() {
        return Err(MeshError::Truncated {
            path: path.to_path_buf(),
            at: format!("line {pending_start}"),
            detail: "the file ends inside a statement continued with '\\'".into(),
        });
    }
    if positions.is_empty() {
        return Err(MeshError::Empty {
            path: path.to_path_buf(),
            detail: "no vertices ('v' statements)".into(),
        });
    }
    if polygons.is_empty() {
        return Err(MeshError::Empty {
            path: path.to_path_buf(),
            detail: "no faces ('f' statements)".into(),
        });
    }
    if u32::try_from(positions.len()).is_err() {
        return Err(MeshError::Unsupported {
            path: path.to_path_buf(),
            detail: format!(
                "{} vertices (at most {} supported)",
                positions.len(),
                u32::MAX
            ),
        });
    }

    let mut indices = Vec::with_capacity(corners.len().saturating_sub(2 * polygons.len()));
    let mesh_normals;
    let out_positions;
    if all_have_normals && !normals.is_empty() {
        // Split vertices per distinct (position, normal) pair.
        let mut map: HashMap<(u32, u32), u32> = HashMap::new();
        let mut pos_out = Vec::new();
        let mut nrm_out = Vec::new();
        let mut remap = |c: Corner| -> Result<u32, MeshError> {
            let key = (c.v, c.n.unwrap_or(0));
            if let Some(&i) = map.get(&key) {
                return Ok(i);
            }
            let i = u32::try_from(pos_out.len()).map_err(|_| MeshError::Unsupported {
                path: path.to_path_buf(),
                detail: "more than 2^32 distinct (position, normal) pairs".into(),
            })?;
            pos_out.push(positions[c.v as usize]);
            nrm_out.push(normals[key.1 as usize]);
            map.insert(key, i);
            Ok(i)
        };
        for &(s, e) in &polygons {
            let first = remap(corners[s])?;
            let mut prev = remap(corners[s + 1])?;
            for &c in &corners[s + 2..e] {
                let cur = remap(c)?;
                indices.push([first, prev, cur]);
                prev = cur;
            }
        }
        out_positions = pos_out;
        mesh_normals = Some(nrm_out);
    } else {
        for &(s, e) in &polygons {
            let v0 = corners[s].v;
            for w in corners[s + 1..e].windows(2) {
                indices.push([v0, w[0].v, w[1].v]);
            }
        }
        out_positions = positions;
        mesh_normals = None;
    }
    Ok(MeshData {
        positions: out_positions,
        normals: mesh_normals,
        indices,
    })
}

fn clip(s: &str) -> String {
    if s.chars().count() > 40 {
        format!("{}...", s.chars().take(40).collect::<String>())
    } else {
        s.to_string()
    }
}

/// Resolves a 1-based or negative OBJ index against the `count` elements defined so far.
fn resolve(
    path: &Path,
    line_no: usize,
    tok: &str,
    field: &str,
    kind: &'static str,
    count: usize,
) -> Result<u32, MeshError> {
    let Ok(i) = field.parse::<i64>() else {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            at: format!("line {line_no}"),
            detail: format!("face corner '{}' has a non-integer {kind} index", clip(tok)),
        });
    };
    if i == 0 {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            at: format!("line {line_no} (face corner '{}')", clip(tok)),
            detail: format!(
                "{kind} index 0 is invalid: OBJ indices start at 1 (negative ones count back from the last {kind} defined)"
            ),
        });
    }
    let resolved = if i > 0 {
        i - 1
    } else if i < 0 {
        count as i64 + i
    } else {
        -1
    };
    if resolved < 0 || resolved >= count as i64 {
        return Err(MeshError::IndexOutOfRange {
            path: path.to_path_buf(),
            at: format!("line {line_no} (face corner '{}')", clip(tok)),
            kind,
            index: i,
            available: count,
        });
    }
    Ok(resolved as u32)
}

fn parse_corner(
    path: &Path,
    line_no: usize,
    tok: &str,
    n_pos: usize,
    n_tex: usize,
    n_nrm: usize,
) -> Result<Corner, MeshError> {
    let mut parts = tok.split('/');
    let v = resolve(
        path,
        line_no,
        tok,
        parts.next().unwrap_or(""),
        "vertex",
        n_pos,
    )?;
    let vt = parts.next();
    let vn = parts.next();
    if parts.next().is_some() {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            at: format!("line {line_no}"),
            detail: format!(
                "face corner '{}' has more than 3 '/'-separated parts",
                clip(tok)
            ),
        });
    }
    if let Some(t) = vt.filter(|t| !t.is_empty()) {
        resolve(path, line_no, tok, t, "texture coordinate", n_tex)?;
    }
    let n = match vn {
        Some(n) if !n.is_empty() => Some(resolve(path, line_no, tok, n, "normal", n_nrm)?),
        Some(_) => {
            return Err(MeshError::Syntax {
                path: path.to_path_buf(),
                at: format!("line {line_no}"),
                detail: format!("face corner '{}' has an empty normal index", clip(tok)),
            });
        }
        None => None,
    };
    Ok(Corner { v, n })
}
