//! Procedural shapes: plane, box, sphere and ring (a cylindrical band with thickness).
//! All are generated in object space with y up and outward-facing normals.

use super::mesh::MeshData;
use glam::Vec3;
use std::f32::consts::PI;

/// Square grid of `size[0]` × `size[1]` in the xz-plane centred at the origin, normal +y,
/// split into `n` × `n` quads.
pub fn plane(size: [f32; 2], n: u32) -> MeshData {
    let n = n.max(1);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let x = (i as f32 / n as f32 - 0.5) * size[0];
            let z = (j as f32 / n as f32 - 0.5) * size[1];
            positions.push(Vec3::new(x, 0.0, z));
        }
    }
    let row = n + 1;
    for j in 0..n {
        for i in 0..n {
            let a = j * row + i;
            let b = a + 1;
            let c = a + row;
            let d = c + 1;
            // Counter-clockwise seen from +y.
            indices.push([a, c, b]);
            indices.push([b, c, d]);
        }
    }
    let normals = vec![Vec3::Y; positions.len()];
    MeshData {
        positions,
        normals: Some(normals),
        indices,
    }
}

/// Number of triangles [`plane`] generates for `n` subdivisions (computed without generating).
pub fn plane_triangles(n: u32) -> u64 {
    let n = u64::from(n.max(1));
    2 * n * n
}

/// Number of triangles [`cuboid`] generates.
pub const CUBOID_TRIANGLES: u64 = 12;

/// Number of triangles [`sphere`] generates for `segments` (computed without generating).
pub fn sphere_triangles(segments: u32) -> u64 {
    let seg = segments.max(3);
    let rings = u64::from((seg / 2).max(2));
    u64::from(seg) * (2 * rings - 2)
}

/// Number of triangles [`ring`] generates for `segments` (computed without generating).
pub fn ring_triangles(segments: u32) -> u64 {
    8 * u64::from(segments.max(3))
}

/// Axis-aligned box of the given size centred at the origin, flat-shaded.
pub fn cuboid(size: [f32; 3]) -> MeshData {
    let h = Vec3::from(size) * 0.5;
    let mut m = MeshData {
        positions: Vec::new(),
        normals: Some(Vec::new()),
        indices: Vec::new(),
    };
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (-Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (-Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (-Vec3::Z, Vec3::Y, Vec3::X),
    ];
    for (n, u, v) in faces {
        // u × v = n for a counter-clockwise quad seen from outside.
        let (u, v) = if u.cross(v).dot(n) > 0.0 {
            (u, v)
        } else {
            (v, u)
        };
        let base = m.positions.len() as u32;
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            m.positions.push((n + u * su + v * sv) * h);
            m.normals.as_mut().unwrap().push(n);
        }
        m.indices.push([base, base + 1, base + 2]);
        m.indices.push([base, base + 2, base + 3]);
    }
    m
}

/// UV sphere of the given radius with `segments` around and `segments / 2` rings, smooth normals.
pub fn sphere(radius: f32, segments: u32) -> MeshData {
    let seg = segments.max(3);
    let rings = (seg / 2).max(2);
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for j in 0..=rings {
        let theta = PI * j as f32 / rings as f32;
        for i in 0..=seg {
            let phi = 2.0 * PI * i as f32 / seg as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            positions.push(n * radius);
            normals.push(n);
        }
    }
    let row = seg + 1;
    let mut indices = Vec::new();
    for j in 0..rings {
        for i in 0..seg {
            let a = j * row + i;
            let b = a + 1;
            let c = a + row;
            let d = c + 1;
            if j != 0 {
                indices.push([a, c, b]);
            }
            if j != rings - 1 {
                indices.push([b, c, d]);
            }
        }
    }
    MeshData {
        positions,
        normals: Some(normals),
        indices,
    }
}

/// A ring: a cylindrical band around the +y axis from y = 0 to `height`, inner radius `radius`,
/// outer radius `radius + thickness`, with flat annular caps. Inner and outer walls have smooth
/// normals (inner pointing towards the axis), so a glossy ring throws a clean cardioid caustic.
pub fn ring(radius: f32, height: f32, thickness: f32, segments: u32) -> MeshData {
    let seg = segments.max(3);
    let ro = radius + thickness;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    let dir = |i: u32| {
        let phi = 2.0 * PI * (i % seg) as f32 / seg as f32;
        Vec3::new(phi.cos(), 0.0, -phi.sin())
    };
    // Walls: outer (normal +radial) and inner (normal −radial).
    for (r, sign) in [(ro, 1.0f32), (radius, -1.0f32)] {
        let base = positions.len() as u32;
        for i in 0..seg {
            let d = dir(i);
            positions.push(d * r);
            positions.push(d * r + Vec3::Y * height);
            normals.push(d * sign);
            normals.push(d * sign);
        }
        for i in 0..seg {
            let a = base + 2 * i;
            let b = base + 2 * ((i + 1) % seg);
            // Outer wall: counter-clockwise seen from outside; inner wall reversed.
            if sign > 0.0 {
                indices.push([a, b, a + 1]);
                indices.push([b, b + 1, a + 1]);
            } else {
                indices.push([a, a + 1, b]);
                indices.push([b, a + 1, b + 1]);
            }
        }
    }
    // Caps: top (normal +y) and bottom (normal −y).
    for (y, n) in [(height, Vec3::Y), (0.0, -Vec3::Y)] {
        let base = positions.len() as u32;
        for i in 0..seg {
            let d = dir(i);
            positions.push(d * radius + Vec3::Y * y);
            positions.push(d * ro + Vec3::Y * y);
            normals.push(n);
            normals.push(n);
        }
        for i in 0..seg {
            let a = base + 2 * i;
            let b = base + 2 * ((i + 1) % seg);
            if n.y > 0.0 {
                indices.push([a, a + 1, b]);
                indices.push([b, a + 1, b + 1]);
            } else {
                indices.push([a, b, a + 1]);
                indices.push([b, b + 1, a + 1]);
            }
        }
    }
    MeshData {
        positions,
        normals: Some(normals),
        indices,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_counts_match_the_generated_shapes() {
        for n in [1, 2, 3, 7, 64] {
            assert_eq!(
                plane([1.0, 2.0], n).indices.len() as u64,
                plane_triangles(n)
            );
        }
        assert_eq!(cuboid([1.0; 3]).indices.len() as u64, CUBOID_TRIANGLES);
        for seg in [3, 4, 5, 8, 33, 256] {
            assert_eq!(sphere(1.0, seg).indices.len() as u64, sphere_triangles(seg));
            assert_eq!(
                ring(1.0, 0.5, 0.1, seg).indices.len() as u64,
                ring_triangles(seg)
            );
        }
    }

    /// Winding agrees with the given normals: every face normal points the same way as its
    /// vertices' normals.
    fn assert_consistent(m: &MeshData) {
        let ns = m.normals.as_ref().unwrap();
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let fnorm = (b - a).cross(c - a);
            if fnorm.length() < 1e-12 {
                continue;
            }
            for &i in t {
                assert!(
                    fnorm.dot(ns[i as usize]) > 0.0,
                    "face {t:?} winding against normal"
                );
            }
        }
    }

    fn area(m: &MeshData) -> f32 {
        m.indices
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    #[test]
    fn shapes_have_consistent_winding_and_expected_area() {
        let p = plane([2.0, 3.0], 4);
        assert_consistent(&p);
        assert!((area(&p) - 6.0).abs() < 1e-4);
        let b = cuboid([1.0, 2.0, 3.0]);
        assert_consistent(&b);
        assert!((area(&b) - 2.0 * (2.0 + 3.0 + 6.0)).abs() < 1e-4);
        let s = sphere(1.0, 128);
        assert_consistent(&s);
        // A 128-segment polyhedron has a little less area than the sphere (4π): within 0.2 %.
        assert!((area(&s) / (4.0 * PI) - 1.0).abs() < 2e-3);
        let r = ring(1.0, 0.5, 0.1, 512);
        assert_consistent(&r);
        let expect = 2.0 * PI * (1.0 + 1.1) * 0.5 + 2.0 * PI * (1.21 - 1.0);
        assert!((area(&r) / expect - 1.0).abs() < 1e-3);
    }
}
