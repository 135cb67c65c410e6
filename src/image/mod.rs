//! Linear RGB image buffers, EXR/PNG I/O and tonemapping.
//!
//! - [`read_exr`] / [`write_exr`]: linear float images (OpenEXR via the `exr` crate);
//!   [`read_exr_bytes`] decodes one held in memory.
//! - [`read_hdr`]: Radiance RGBE (`.hdr`) input, flat and run-length encoded;
//!   [`read_hdr_bytes`] decodes one held in memory.
//! - [`Tonemap`] / [`to_srgb8`]: exposure, a tone operator and the sRGB OETF to 8-bit display
//!   values.
//! - [`write_png`] / [`write_png_rgb8`]: 8-bit sRGB PNG output.
//!
//! Every file is written atomically through [`crate::fsutil::write_bytes_atomic`].
//! See `docs/images-and-metrics.md` for the exact conventions.

mod error;
mod exr_io;
mod hdr_io;
mod png_io;
mod tonemap;

pub use error::ImageError;
pub use exr_io::{
    HALF_MAX, MAX_EXR_PIXELS, read_exr, read_exr_bytes, read_exr_size, read_exr_size_bytes,
    write_exr, write_exr_half,
};
pub use hdr_io::{
    MAX_HDR_SIDE, decode_hdr, read_hdr, read_hdr_bytes, read_hdr_size, read_hdr_size_bytes,
    rgbe_to_rgb,
};
pub use png_io::{write_png, write_png_rgb8};
pub use tonemap::{ToneOperator, Tonemap, srgb_eotf, srgb_oetf, to_srgb8};

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

    /// An image whose pixel `(x, y)` is `f(x, y)`, evaluated in row-major order.
    pub fn from_fn(width: u32, height: u32, mut f: impl FnMut(u32, u32) -> Vec3) -> Image {
        let mut data = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Image {
            width,
            height,
            data,
        }
    }

    /// True when `data` holds exactly `width × height` pixels.
    pub fn has_consistent_size(&self) -> bool {
        self.data.len() as u64 == self.width as u64 * self.height as u64
    }

    /// The first pixel (row-major order) with a NaN or infinite channel, as `(x, y, value)`.
    pub fn first_non_finite(&self) -> Option<(u32, u32, Vec3)> {
        let w = self.width.max(1) as usize;
        self.data
            .iter()
            .position(|p| !p.is_finite())
            .map(|i| ((i % w) as u32, (i / w) as u32, self.data[i]))
    }
}

/// Rejects an image that cannot be written to `path`: zero width or height, or a pixel buffer
/// whose length is not `width × height`.
pub(crate) fn check_writable(
    path: &std::path::Path,
    width: u32,
    height: u32,
    len: usize,
) -> Result<(), ImageError> {
    let reason = if width == 0 || height == 0 {
        format!("image is empty ({width}x{height})")
    } else if len as u64 != width as u64 * height as u64 {
        format!(
            "pixel buffer holds {len} pixels but the image is {width}x{height} = {} pixels",
            width as u64 * height as u64
        )
    } else {
        return Ok(());
    };
    Err(ImageError::InvalidImage {
        path: path.to_path_buf(),
        reason,
    })
}

#[cfg(test)]
mod tests;
