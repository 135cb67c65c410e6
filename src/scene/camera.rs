//! Pinhole camera.

use glam::Vec3;

/// A pinhole camera looking from `position` towards `forward`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// Vertical field of view in radians.
    pub fov_y: f32,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// Camera from look-at parameters; `None` when the frame is degenerate
    /// (position = look_at, or `up` parallel to the view direction).
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        fov_y_deg: f32,
        width: u32,
        height: u32,
    ) -> Option<Camera> {
        let forward = (target - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        Some(Camera {
            position,
            forward,
            right,
            up,
            fov_y: fov_y_deg.to_radians(),
            width,
            height,
        })
    }

    /// Unit direction of the ray through image point (px, py), in pixels from the top-left corner.
    pub fn ray_dir(&self, px: f32, py: f32) -> Vec3 {
        let tan_half = (0.5 * self.fov_y).tan();
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * px / self.width as f32 - 1.0) * tan_half * aspect;
        let sy = (1.0 - 2.0 * py / self.height as f32) * tan_half;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }

    /// Copy with another resolution (same field of view).
    pub fn with_resolution(&self, width: u32, height: u32) -> Camera {
        Camera {
            width,
            height,
            ..*self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_is_forward_and_corners_match_fov() {
        let c = Camera::look_at(
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ZERO,
            Vec3::Y,
            90.0,
            200,
            100,
        )
        .unwrap();
        assert!((c.ray_dir(100.0, 50.0) - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // Top edge at 45° for a 90° vertical fov.
        let top = c.ray_dir(100.0, 0.0);
        assert!((top.y.atan2(-top.z).to_degrees() - 45.0).abs() < 1e-4);
        // Aspect 2: the right edge is at atan(2).
        let r = c.ray_dir(200.0, 50.0);
        assert!((r.x / -r.z - 2.0).abs() < 1e-5);
        assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 45.0, 1, 1).is_none());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 45.0, 1, 1).is_none());
    }
}
