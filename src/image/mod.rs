//! Linear RGB image buffers, EXR/PNG I/O and tonemapping.

use glam::Vec3;

/// A linear-RGB float image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub data: Vec<Vec3>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            data: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.data[y as usize * self.width as usize + x as usize]
    }

    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: Vec3) {
        let w = self.width as usize;
        self.data[y as usize * w + x as usize] = v;
    }

    /// Mean over all pixels and channels.
    pub fn mean(&self) -> f64 {
        if self.data.is_empty() {
            return 0.0;
        }
        let s: f64 = self.data.iter().map(|p| (p.x + p.y + p.z) as f64).sum();
        s / (3.0 * self.data.len() as f64)
    }
}
