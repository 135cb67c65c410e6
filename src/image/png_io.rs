//! 8-bit sRGB PNG output.

use std::path::Path;

use super::{Image, ImageError, Tonemap, to_srgb8};
use crate::fsutil::write_bytes_atomic;

/// Tonemaps `img` with `tm` ([`to_srgb8`]) and writes an 8-bit RGB PNG tagged sRGB, atomically.
pub fn write_png(path: &Path, img: &Image, tm: &Tonemap) -> Result<(), ImageError> {
    super::check_writable(path, img.width, img.height, img.data.len())?;
    write_png_rgb8(path, img.width, img.height, &to_srgb8(img, tm))
}

/// Writes already display-encoded 8-bit sRGB pixels (row-major from the top-left) as an RGB PNG
/// with an sRGB chunk, atomically (temporary file + rename). `pixels.len()` must be
/// `width × height`.
pub fn write_png_rgb8(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[[u8; 3]],
) -> Result<(), ImageError> {
    super::check_writable(path, width, height, pixels.len())?;
    let encode_err = |e: png::EncodingError| ImageError::Encode {
        path: path.to_path_buf(),
        format: "PNG",
        reason: e.to_string(),
    };
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = enc.write_header().map_err(encode_err)?;
        writer
            .write_image_data(pixels.as_flattened())
            .map_err(encode_err)?;
        writer.finish().map_err(encode_err)?;
    }
    write_bytes_atomic(path, &bytes).map_err(|source| ImageError::Write {
        path: path.to_path_buf(),
        source,
    })
}
