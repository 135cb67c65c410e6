//! Sanity checks that need ray queries (run once before rendering).

use crate::accel::Accel;
use crate::math::sampling::{Rng, uniform_sphere};
use crate::scene::Scene;

/// Warns when the camera appears to sit inside closed geometry: most of 256 rays shot from the
/// camera in all directions hit something, and most of those hits see the back of a triangle
/// (by winding). Returns the warning, naming the object hit most often from behind.
pub fn camera_inside_geometry(scene: &Scene, accel: &Accel) -> Option<String> {
    let n = 256;
    let mut rng = Rng::keyed(0x0ca3e7a, 0, 0);
    let mut hits = 0;
    let mut back = 0;
    let mut back_per_object = vec![0u32; scene.objects.len()];
    let o = scene.camera.position;
    for _ in 0..n {
        let d = uniform_sphere(rng.vec2());
        if let Some(h) = accel.intersect(o, d, 0.0, f32::INFINITY) {
            hits += 1;
            if scene.mesh.tri_cross(h.tri).dot(d) > 0.0 {
                back += 1;
                back_per_object[scene.mesh.tri_object[h.tri as usize] as usize] += 1;
            }
        }
    }
    if hits * 10 >= n * 9 && back * 2 > hits {
        let (obj, _) = back_per_object
            .iter()
            .enumerate()
            .max_by_key(|(_, c)| **c)
            .expect("at least one object");
        let p = scene.camera.position;
        Some(format!(
            "camera.position [{}, {}, {}] appears to be inside object \"{}\" ({} of {} rays from the camera hit the back of its surface): the image will show its inside",
            p.x, p.y, p.z, scene.objects[obj].name, back, n
        ))
    } else {
        None
    }
}
