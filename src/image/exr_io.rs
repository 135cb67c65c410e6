//! OpenEXR input and output (via the `exr` crate).

use std::io::Cursor;
use std::path::Path;

use exr::prelude::{self as x, ReadChannels, ReadLayers, WritableImage};
use glam::Vec3;

use super::{Image, ImageError};
use crate::fsutil::write_bytes_atomic;

/// Reads the first layer of an OpenEXR file that has `R`, `G` and `B` channels, as linear RGB.
///
/// - Any sample type (half, float, uint) is converted to `f32`; any compression the `exr` crate
///   reads is accepted (none, RLE, ZIP, PIZ, PXR24, B44, DWAA/B as supported by `exr`).
/// - An `A` channel, if present, is ignored (RGB is taken as stored, i.e. premultiplied).
/// - Mip/rip-mapped files: the largest level is read. The layer's data window becomes the image.
/// - Decoding is pedantic: truncated or inconsistent files are errors, not partially black images.
///
/// Errors: unreadable file ([`ImageError::Read`]), invalid/truncated data or a layer of more than
/// [`MAX_EXR_PIXELS`] pixels ([`ImageError::ExrDecode`]), no layer with R, G and B ([`ImageError::MissingChannels`], listing
/// the channels that exist), a NaN or infinite sample ([`ImageError::NonFinitePixel`], naming the
/// first such pixel in row-major order).
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let bytes = std::fs::read(path).map_err(|source| ImageError::Read {
        path: path.to_path_buf(),
        format: "EXR",
        source,
    })?;
    decode_exr(&bytes, path)
}

/// [`read_exr`] for a file held in memory: `name` stands for the file in error messages.
pub fn read_exr_bytes(bytes: &[u8], name: &str) -> Result<Image, ImageError> {
    decode_exr(bytes, Path::new(name))
}

/// Most pixels [`read_exr`] accepts in the layer it reads: 2²⁸ = 16384 × 16384, the largest
/// image the renderer writes. A header declaring more is refused before decoding.
pub const MAX_EXR_PIXELS: u64 = 1 << 28;

/// Files at least this large are decompressed in parallel (see [`decode_exr`]).
pub(crate) const PARALLEL_EXR_BYTES: usize = 256 << 10;

/// Decodes an OpenEXR file held in memory (see [`read_exr`]); `path` names it in errors.
fn decode_exr(bytes: &[u8], path: &Path) -> Result<Image, ImageError> {
    let decode_err = |e: exr::error::Error| ImageError::ExrDecode {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };

    // Check the channels first so that a file without RGB gets a message listing what it has.
    let meta =
        exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), true).map_err(decode_err)?;
    let rgb_layer = meta.headers.iter().find(|h| {
        let has = |n: &str| h.channels.list.iter().any(|c| c.name.eq(n));
        has("R") && has("G") && has("B")
    });
    let Some(rgb_layer) = rgb_layer else {
        let found: Vec<String> = meta
            .headers
            .iter()
            .flat_map(|h| h.channels.list.iter().map(|c| c.name.to_string()))
            .collect();
        return Err(ImageError::MissingChannels {
            path: path.to_path_buf(),
            found: if found.is_empty() {
                "none".to_string()
            } else {
                found.join(", ")
            },
        });
    };
    // Refuse an absurd size from the header alone, before anything is allocated for it.
    let size = rgb_layer.layer_size;
    if size.width() as u64 * size.height() as u64 > MAX_EXR_PIXELS {
        return Err(ImageError::ExrDecode {
            path: path.to_path_buf(),
            reason: format!(
                "image size {}x{} is larger than the {MAX_EXR_PIXELS} pixels accepted",
                size.width(),
                size.height()
            ),
        });
    }

    // The pixel buffer grows as decoded pixels arrive (rather than being allocated from the
    // header's size up front), so a file that declares a large image but holds little or no
    // pixel data fails before it costs memory.
    let reader = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size: x::Vec2<usize>, _| (size.width(), size.area(), Vec::new()),
            |(w, _, px): &mut (usize, usize, Vec<Vec3>),
             pos: x::Vec2<usize>,
             (r, g, b): (f32, f32, f32)| {
                let i = pos.y() * *w + pos.x();
                if i >= px.len() {
                    px.resize(i + 1, Vec3::ZERO);
                }
                px[i] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .pedantic();
    // The exr crate builds a thread pool per file to decompress blocks in parallel; for a small
    // file that costs more than it saves, so it is decoded on the calling thread.
    let reader = if bytes.len() < PARALLEL_EXR_BYTES {
        reader.non_parallel()
    } else {
        reader
    };
    let image = reader
        .from_buffered(Cursor::new(bytes))
        .map_err(decode_err)?;

    let size = image.layer_data.size;
    let (width, height) = (size.width(), size.height());
    let (w32, h32) = match (u32::try_from(width), u32::try_from(height)) {
        (Ok(w), Ok(h)) => (w, h),
        _ => {
            return Err(ImageError::ExrDecode {
                path: path.to_path_buf(),
                reason: format!("image size {width}x{height} is too large"),
            });
        }
    };
    let (_, area, mut data) = image.layer_data.channel_data.pixels;
    data.resize(area, Vec3::ZERO);
    let img = Image {
        width: w32,
        height: h32,
        data,
    };
    if let Some((px, py, v)) = img.first_non_finite() {
        return Err(ImageError::non_finite(path, px, py, v));
    }
    Ok(img)
}

/// Width and height of the layer [`read_exr`] would read, from the header alone (so a caller can
/// refuse an absurd size before decoding).
pub fn read_exr_size(path: &Path) -> Result<(u32, u32), ImageError> {
    let file = std::fs::File::open(path).map_err(|source| ImageError::Read {
        path: path.to_path_buf(),
        format: "EXR",
        source,
    })?;
    size_from_header(std::io::BufReader::new(file), path)
}

/// [`read_exr_size`] for a file held in memory: `name` stands for the file in error messages.
pub fn read_exr_size_bytes(bytes: &[u8], name: &str) -> Result<(u32, u32), ImageError> {
    size_from_header(Cursor::new(bytes), Path::new(name))
}

fn size_from_header(
    read: impl std::io::Read + std::io::Seek,
    path: &Path,
) -> Result<(u32, u32), ImageError> {
    let meta =
        exr::meta::MetaData::read_from_buffered(read, true).map_err(|e| ImageError::ExrDecode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
    let has = |h: &exr::meta::header::Header, n: &str| h.channels.list.iter().any(|c| c.name.eq(n));
    let h = meta
        .headers
        .iter()
        .find(|h| has(h, "R") && has(h, "G") && has(h, "B"))
        .or(meta.headers.first())
        .ok_or_else(|| ImageError::ExrDecode {
            path: path.to_path_buf(),
            reason: "no layers".into(),
        })?;
    let size = h.layer_size;
    Ok((
        u32::try_from(size.width()).unwrap_or(u32::MAX),
        u32::try_from(size.height()).unwrap_or(u32::MAX),
    ))
}

/// Largest finite half-float value: [`write_exr_half`] refuses pixels above it.
pub const HALF_MAX: f32 = 65504.0;

/// Writes `img` like [`write_exr`] but with 16-bit half-float channels (about 3 significant
/// digits, relative precision 2⁻¹¹) and PIZ compression: half the size or less, for data that
/// does not need f32 (environment maps). Refuses pixels that are not finite or exceed
/// [`HALF_MAX`] ([`ImageError::InvalidImage`]).
pub fn write_exr_half(path: &Path, img: &Image) -> Result<(), ImageError> {
    super::check_writable(path, img.width, img.height, img.data.len())?;
    if let Some((px, py, v)) = img.first_non_finite() {
        return Err(ImageError::non_finite(path, px, py, v));
    }
    if let Some(i) = img
        .data
        .iter()
        .position(|p| p.abs().max_element() > HALF_MAX)
    {
        return Err(ImageError::InvalidImage {
            path: path.to_path_buf(),
            reason: format!(
                "pixel (x {}, y {}) = {} exceeds the half-float range (±{HALF_MAX})",
                i % img.width as usize,
                i / img.width as usize,
                img.data[i]
            ),
        });
    }
    let w = img.width as usize;
    let data = &img.data;
    let channels = x::SpecificChannels::rgb(|pos: x::Vec2<usize>| {
        let p = data[pos.y() * w + pos.x()];
        (
            x::f16::from_f32(p.x),
            x::f16::from_f32(p.y),
            x::f16::from_f32(p.z),
        )
    });
    let exr_image = x::Image::from_encoded_channels(
        (w, img.height as usize),
        x::Encoding {
            compression: x::Compression::PIZ,
            blocks: x::Blocks::ScanLines,
            line_order: x::LineOrder::Increasing,
        },
        channels,
    );
    let mut bytes = Vec::new();
    exr_image
        .write()
        .to_buffered(Cursor::new(&mut bytes))
        .map_err(|e| ImageError::Encode {
            path: path.to_path_buf(),
            format: "OpenEXR",
            reason: e.to_string(),
        })?;
    write_bytes_atomic(path, &bytes).map_err(|source| ImageError::Write {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `img` as a single-layer OpenEXR file: channels R, G, B as 32-bit float (linear, no
/// alpha), ZIP compression in blocks of 16 scan lines (lossless), increasing line order.
/// The file is written atomically (temporary file + rename).
///
/// Refuses (with [`ImageError::InvalidImage`] / [`ImageError::NonFinitePixel`]) an empty image,
/// a buffer whose length is not `width × height`, and NaN/infinite pixels, so every file written
/// here can be read back by [`read_exr`] bit-exactly.
pub fn write_exr(path: &Path, img: &Image) -> Result<(), ImageError> {
    super::check_writable(path, img.width, img.height, img.data.len())?;
    if let Some((px, py, v)) = img.first_non_finite() {
        return Err(ImageError::non_finite(path, px, py, v));
    }
    let w = img.width as usize;
    let data = &img.data;
    let channels = x::SpecificChannels::rgb(|pos: x::Vec2<usize>| {
        let p = data[pos.y() * w + pos.x()];
        (p.x, p.y, p.z)
    });
    let exr_image = x::Image::from_encoded_channels(
        (w, img.height as usize),
        x::Encoding {
            compression: x::Compression::ZIP16,
            blocks: x::Blocks::ScanLines,
            line_order: x::LineOrder::Increasing,
        },
        channels,
    );
    let mut bytes = Vec::new();
    exr_image
        .write()
        .to_buffered(Cursor::new(&mut bytes))
        .map_err(|e| ImageError::Encode {
            path: path.to_path_buf(),
            format: "OpenEXR",
            reason: e.to_string(),
        })?;
    write_bytes_atomic(path, &bytes).map_err(|source| ImageError::Write {
        path: path.to_path_buf(),
        source,
    })
}
