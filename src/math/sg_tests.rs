use glam::DVec3;

use super::*;
use crate::math::spherical_triangle::quadrature::sphere_integral;

#[test]
fn placeholder() {
    let _ = sphere_integral(|_| 1.0, DVec3::Z, 1e-10);
}
