//! Mesh cleaning: degenerate and duplicate triangles, unused vertices, vertex normals.

use std::collections::{HashMap, HashSet};

use glam::{DVec3, Vec3};

use super::{CleanReport, MeshData, MeshError, validate};

/// A triangle is degenerate (and removed) when its area is at most
/// `AREA_EPSILON × (bounding-box diagonal)²`.
///
/// 1e-12 is far below any real triangle: a mesh of a million triangles covering its bounding
/// box has a typical triangle area around 1e-6 × diagonal², six orders of magnitude above the
/// threshold. It sits at the level of f32 rounding (positions carry a relative precision of
/// about 6e-8 of the box, so a collinear or collapsed triangle computes an area of roughly
/// (6e-8)² ≈ 4e-15 × diagonal²), so it removes collapsed and collinear triangles without
/// touching thin but genuine slivers. Areas are computed in f64.
pub const AREA_EPSILON: f64 = 1e-12;

/// A stored normal shorter than this is "zero length" and gets repaired.
const MIN_NORMAL_LENGTH: f64 = 1e-12;

/// Accumulated area-weighted normals cancelling below this fraction of the summed face
/// weights (e.g. a vertex shared by two back-to-back triangles) fall back to the normal of the
/// largest adjacent triangle.
const CANCELLATION: f64 = 1e-6;

/// Exact position key: bit patterns, with -0.0 folded into +0.0.
fn position_key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Cleans a mesh for rendering and returns it with normals always present and unit length.
///
/// In order:
/// 1. validates the input (indices in range, finite positions, normals count);
/// 2. removes degenerate triangles: area ≤ [`AREA_EPSILON`] × bbox diagonal²;
/// 3. removes exact duplicate triangles: the same three vertex *positions* (bitwise) as an
///    earlier triangle, in any order or winding (the first one is kept);
/// 4. errors if no triangle is left ([`MeshError::NothingLeft`]);
/// 5. drops vertices no remaining triangle uses (indices are remapped, order kept);
/// 6. computes area-weighted vertex normals if the mesh has none; otherwise repairs each normal
///    that is NaN/infinite, zero length, or points against (negative dot product with) the face
///    normal of every adjacent triangle, replacing it by the area-weighted normal;
/// 7. normalises all normals.
///
/// Each non-zero removal or repair adds a warning that starts with `label`.
pub fn clean_mesh(mesh: MeshData, label: &str) -> Result<(MeshData, CleanReport), MeshError> {
    validate(&mesh, label)?;
    let MeshData {
        positions,
        normals,
        indices,
    } = mesh;
    let total = indices.len();
    if total == 0 {
        return Err(MeshError::InvalidMesh {
            label: label.to_string(),
            detail: "the mesh has no triangles".into(),
        });
    }
    let mut report = CleanReport::default();

    // Degenerate and duplicate triangles.
    let (lo, hi) = positions
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.as_dvec3()), hi.max(p.as_dvec3()))
        });
    let threshold = AREA_EPSILON * (hi - lo).length_squared();
    let mut canon_map: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    let canon: Vec<u32> = positions
        .iter()
        .map(|&p| {
            let next = canon_map.len() as u32;
            *canon_map.entry(position_key(p)).or_insert(next)
        })
        .collect();
    drop(canon_map);
    let mut seen: HashSet<[u32; 3]> = HashSet::with_capacity(total);
    let mut kept: Vec<[u32; 3]> = Vec::with_capacity(total);
    for tri in indices {
        let [a, b, c] = tri.map(|i| positions[i as usize].as_dvec3());
        let area = 0.5 * (b - a).cross(c - a).length();
        if area.is_nan() || area <= threshold {
            report.removed_degenerate += 1;
            continue;
        }
        let mut key = tri.map(|i| canon[i as usize]);
        key.sort_unstable();
        if !seen.insert(key) {
            report.removed_duplicate += 1;
            continue;
        }
        kept.push(tri);
    }
    drop(seen);
    if kept.is_empty() {
        return Err(MeshError::NothingLeft {
            label: label.to_string(),
            total,
            degenerate: report.removed_degenerate,
            duplicate: report.removed_duplicate,
        });
    }
    if report.removed_degenerate > 0 {
        report.warnings.push(format!(
            "{label}: removed {} of {total} triangles with (near-)zero area \
             (area <= {AREA_EPSILON:e} x bounding-box diagonal^2)",
            report.removed_degenerate
        ));
    }
    if report.removed_duplicate > 0 {
        report.warnings.push(format!(
            "{label}: removed {} duplicate triangles (same three vertex positions as an earlier \
             triangle, in any order or winding)",
            report.removed_duplicate
        ));
    }

    // Drop unused vertices (the remaining ones keep their order).
    let mut used = vec![false; positions.len()];
    for tri in &kept {
        for &i in tri {
            used[i as usize] = true;
        }
    }
    let mut remap = vec![u32::MAX; positions.len()];
    let mut old_index: Vec<usize> = Vec::with_capacity(positions.len());
    for (old, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        remap[old] = old_index.len() as u32;
        old_index.push(old);
    }
    for tri in &mut kept {
        *tri = tri.map(|i| remap[i as usize]);
    }
    let removed_unused = positions.len() - old_index.len();
    let positions: Vec<Vec3> = old_index.iter().map(|&o| positions[o]).collect();
    report.removed_unused_vertices = removed_unused;
    let normals: Option<Vec<Vec3>> = normals.map(|n| old_index.iter().map(|&o| n[o]).collect());

    // Area-weighted normals (and, for existing normals, whether any adjacent face agrees).
    let m = positions.len();
    let mut sum = vec![DVec3::ZERO; m];
    let mut weight = vec![0f64; m];
    let mut largest = vec![(0f64, DVec3::ZERO); m];
    let mut agrees = vec![false; m];
    for tri in &kept {
        let [a, b, c] = tri.map(|i| positions[i as usize].as_dvec3());
        let cross = (b - a).cross(c - a);
        let len = cross.length();
        for &v in tri {
            let v = v as usize;
            sum[v] += cross;
            weight[v] += len;
            if len > largest[v].0 {
                largest[v] = (len, cross);
            }
            if let Some(n) = &normals
                && n[v].as_dvec3().dot(cross) >= 0.0
            {
                agrees[v] = true;
            }
        }
    }
    let area_weighted = |v: usize| -> Vec3 {
        let s = sum[v];
        let dir = if s.length() > CANCELLATION * weight[v] {
            s
        } else {
            largest[v].1
        };
        dir.normalize().as_vec3()
    };
    let out_normals: Vec<Vec3> = match normals {
        None => {
            report.computed_normals = true;
            (0..m).map(area_weighted).collect()
        }
        Some(n) => n
            .iter()
            .enumerate()
            .map(|(v, &nv)| {
                let d = nv.as_dvec3();
                let len = d.length();
                let bad = !d.is_finite() || len < MIN_NORMAL_LENGTH || !agrees[v];
                if bad {
                    report.repaired_normals += 1;
                    area_weighted(v)
                } else {
                    (d / len).as_vec3()
                }
            })
            .collect(),
    };
    if report.repaired_normals > 0 {
        let mut w = format!(
            "{label}: repaired {} of {m} vertex normals (NaN/infinite, zero length, or facing \
             away from every adjacent triangle); replaced by area-weighted face normals",
            report.repaired_normals
        );
        if report.repaired_normals * 2 > m {
            w.push_str(
                "; most normals disagree with the triangle winding, so the file probably \
                 uses clockwise winding",
            );
        }
        report.warnings.push(w);
    }
    Ok((
        MeshData {
            positions,
            normals: Some(out_normals),
            indices: kept,
        },
        report,
    ))
}
