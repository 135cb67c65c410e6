//! Errors of image input and output. Every message names the file concerned.

use std::path::PathBuf;

/// What went wrong reading or writing an image file. The `Display` text names the file and the
/// problem, e.g. `cannot read EXR file "a.exr": No such file or directory (os error 2)`.
#[derive(thiserror::Error, Debug)]
pub enum ImageError {
    /// The file could not be opened or read (missing, permissions, ...).
    #[error("cannot read {format} file {:?}: {source}", .path)]
    Read {
        path: PathBuf,
        format: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The bytes are not a valid (or not a supported) OpenEXR file: garbage, truncated, ...
    #[error("{:?} is not a readable OpenEXR file: {reason}", .path)]
    ExrDecode { path: PathBuf, reason: String },
    /// The bytes are not a valid (or not a supported) Radiance RGBE file.
    #[error("{:?} is not a readable Radiance HDR file: {reason}", .path)]
    HdrDecode { path: PathBuf, reason: String },
    /// No layer of the EXR file has all of the R, G and B channels.
    #[error(
        "{:?}: no layer of the OpenEXR file has all of the channels R, G and B (channels found: {found})",
        .path
    )]
    MissingChannels { path: PathBuf, found: String },
    /// A pixel holds NaN or an infinity (reported for the first such pixel in row-major order).
    #[error(
        "{:?}: pixel (x {x}, y {y}) is {kind}: ({}, {}, {}) (first non-finite pixel in row-major order from the top-left)",
        .path, .value[0], .value[1], .value[2]
    )]
    NonFinitePixel {
        path: PathBuf,
        x: u32,
        y: u32,
        /// `"NaN"` or `"infinite"`.
        kind: &'static str,
        value: [f32; 3],
    },
    /// The image handed to a writer is unusable (empty, or buffer length ≠ width × height).
    #[error("cannot write {:?}: {reason}", .path)]
    InvalidImage { path: PathBuf, reason: String },
    /// The encoder failed.
    #[error("cannot encode {format} for {:?}: {reason}", .path)]
    Encode {
        path: PathBuf,
        format: &'static str,
        reason: String,
    },
    /// Writing the file (atomically: temporary file + rename) failed.
    #[error("cannot write {:?}: {source}", .path)]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl ImageError {
    /// The non-finite-pixel error for `value` at `(x, y)` of `path`.
    pub(crate) fn non_finite(path: &std::path::Path, x: u32, y: u32, v: glam::Vec3) -> ImageError {
        let kind = if v.is_nan() { "NaN" } else { "infinite" };
        ImageError::NonFinitePixel {
            path: path.to_path_buf(),
            x,
            y,
            kind,
            value: v.to_array(),
        }
    }
}
