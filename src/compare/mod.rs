//! Error metrics between images and false-colour error maps.
//!
//! [`metrics`] computes RMSE, relative RMSE, relMSE, SSIM and FLIP of a test image against a
//! reference; [`error_map`] renders a per-pixel false-colour error image with a legend strip.
//! The exact definitions are in `docs/images-and-metrics.md` and on each function.

mod colormap;
mod errormap;
mod font;
pub mod plot;
mod ssim;

pub use colormap::{MAGMA, magma};
pub use errormap::{
    ERROR_MAP_EPSILON, ERROR_MAP_MIN_WIDTH, ErrorMap, ErrorMapMode, ErrorMapOptions, error_map,
    per_pixel_error, render_error_map,
};
pub use ssim::{
    SSIM_C1, SSIM_C2, SSIM_K1, SSIM_K2, SSIM_L, SSIM_SIGMA, SSIM_WINDOW, ssim, ssim_luma,
};

use crate::image::{Image, Tonemap, to_srgb8};

/// ε in relMSE = mean((x − y)² / (y² + ε)).
pub const RELMSE_EPSILON: f64 = 0.01;

/// Pixels per degree of visual angle used for FLIP: nv-flip's default (67, a 0.7 m viewing
/// distance from a 0.7 m wide 4K monitor).
pub const FLIP_PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

/// Why two images cannot be compared.
#[derive(thiserror::Error, Debug)]
pub enum CompareError {
    /// The images differ in size.
    #[error(
        "image sizes differ: test image is {test_width}x{test_height}, reference image is {ref_width}x{ref_height}"
    )]
    SizeMismatch {
        test_width: u32,
        test_height: u32,
        ref_width: u32,
        ref_height: u32,
    },
    /// An image has no pixels.
    #[error("{which} image is empty ({width}x{height})")]
    Empty {
        which: &'static str,
        width: u32,
        height: u32,
    },
    /// An image's pixel buffer does not hold `width × height` pixels.
    #[error("{which} image: pixel buffer holds {len} pixels but the image is {width}x{height}")]
    BadBuffer {
        which: &'static str,
        width: u32,
        height: u32,
        len: usize,
    },
    /// An image holds NaN or an infinity (the first such pixel in row-major order).
    #[error("{which} image: pixel (x {x}, y {y}) is not finite: ({}, {}, {})", .value[0], .value[1], .value[2])]
    NonFinite {
        which: &'static str,
        x: u32,
        y: u32,
        value: [f32; 3],
    },
    /// rel_rmse divides by the reference mean, which must be positive.
    #[error("reference image mean is {mean}; rel_rmse needs a positive reference mean")]
    NonPositiveReferenceMean { mean: f64 },
    /// An option is out of range.
    #[error("invalid error-map option: {0}")]
    InvalidOption(String),
}

/// Image-comparison metrics of a test image against a reference. JSON keys are the field names.
#[derive(Clone, Copy, Debug, serde::Serialize, PartialEq)]
pub struct Metrics {
    /// sqrt(mean over pixels and channels of (x − y)²), linear radiance.
    pub rmse: f64,
    /// `rmse` / (mean of the reference over pixels and channels).
    pub rel_rmse: f64,
    /// mean over pixels and channels of (x − y)² / (y² + 0.01).
    pub relmse: f64,
    /// Mean SSIM (Wang et al. 2004) of the luma of the clamp/sRGB tonemapped images; 1 = equal.
    pub ssim: f64,
    /// Mean LDR FLIP (nv-flip, 67 px/degree) of the 8-bit sRGB tonemapped images; 0 = equal.
    pub flip: f64,
}

/// Checks that `test` and `reference` are comparable: consistent buffers, same non-zero size,
/// all pixels finite.
pub(crate) fn validate(test: &Image, reference: &Image) -> Result<(), CompareError> {
    for (which, img) in [("test", test), ("reference", reference)] {
        if !img.has_consistent_size() {
            return Err(CompareError::BadBuffer {
                which,
                width: img.width,
                height: img.height,
                len: img.data.len(),
            });
        }
    }
    if test.width != reference.width || test.height != reference.height {
        return Err(CompareError::SizeMismatch {
            test_width: test.width,
            test_height: test.height,
            ref_width: reference.width,
            ref_height: reference.height,
        });
    }
    for (which, img) in [("test", test), ("reference", reference)] {
        if img.data.is_empty() {
            return Err(CompareError::Empty {
                which,
                width: img.width,
                height: img.height,
            });
        }
        if let Some((x, y, v)) = img.first_non_finite() {
            return Err(CompareError::NonFinite {
                which,
                x,
                y,
                value: v.to_array(),
            });
        }
    }
    Ok(())
}

/// All metrics of `test` against `reference`; FLIP uses the default [`Tonemap`]
/// (exposure 0 EV, clamp, sRGB). See [`metrics_with_tonemap`].
///
/// Errors: size mismatch (naming both sizes), empty images, NaN/∞ pixels, reference mean ≤ 0.
pub fn metrics(test: &Image, reference: &Image) -> Result<Metrics, CompareError> {
    metrics_with_tonemap(test, reference, &Tonemap::default())
}

/// All metrics; `tm` is the tonemap applied identically to both images for FLIP. (SSIM always
/// uses exposure 0 EV, clamp, sRGB, see [`ssim`].)
pub fn metrics_with_tonemap(
    test: &Image,
    reference: &Image,
    tm: &Tonemap,
) -> Result<Metrics, CompareError> {
    validate(test, reference)?;
    let (rmse, relmse) = rmse_relmse(test, reference);
    let mean = reference_mean(reference);
    if mean.is_nan() || mean <= 0.0 {
        return Err(CompareError::NonPositiveReferenceMean { mean });
    }
    Ok(Metrics {
        rmse,
        rel_rmse: rmse / mean,
        relmse,
        ssim: ssim(test, reference)?,
        flip: flip(test, reference, tm)?,
    })
}

/// (RMSE, relMSE) over all pixels and channels, accumulated in f64. Inputs must be validated.
fn rmse_relmse(test: &Image, reference: &Image) -> (f64, f64) {
    let mut se = 0.0f64;
    let mut rel = 0.0f64;
    for (a, b) in test.data.iter().zip(&reference.data) {
        for c in 0..3 {
            let x = a[c] as f64;
            let y = b[c] as f64;
            let d2 = (x - y) * (x - y);
            se += d2;
            rel += d2 / (y * y + RELMSE_EPSILON);
        }
    }
    let n = 3.0 * test.data.len() as f64;
    ((se / n).sqrt(), rel / n)
}

/// Mean of `img` over all pixels and channels, every sample converted to f64 before summing.
fn reference_mean(img: &Image) -> f64 {
    let s: f64 = img
        .data
        .iter()
        .map(|p| p.x as f64 + p.y as f64 + p.z as f64)
        .sum();
    s / (3.0 * img.data.len() as f64)
}

/// Root-mean-square error over all pixels and channels.
pub fn rmse(test: &Image, reference: &Image) -> Result<f64, CompareError> {
    validate(test, reference)?;
    Ok(rmse_relmse(test, reference).0)
}

/// relMSE: mean over pixels and channels of (x − y)² / (y² + [`RELMSE_EPSILON`]).
pub fn relmse(test: &Image, reference: &Image) -> Result<f64, CompareError> {
    validate(test, reference)?;
    Ok(rmse_relmse(test, reference).1)
}

/// Mean LDR FLIP (Andersson et al. 2020, via NVIDIA's implementation in `nv-flip`) between the
/// two images, each tonemapped with `tm` to 8-bit sRGB, at [`FLIP_PIXELS_PER_DEGREE`].
/// The arithmetic mean of the per-pixel FLIP error map, in `[0, 1]`.
pub fn flip(test: &Image, reference: &Image, tm: &Tonemap) -> Result<f64, CompareError> {
    validate(test, reference)?;
    let (w, h) = (test.width, test.height);
    let t8 = to_srgb8(test, tm);
    let r8 = to_srgb8(reference, tm);
    let timg = nv_flip::FlipImageRgb8::with_data(w, h, t8.as_flattened());
    let rimg = nv_flip::FlipImageRgb8::with_data(w, h, r8.as_flattened());
    let map = nv_flip::flip(rimg, timg, FLIP_PIXELS_PER_DEGREE);
    let values = map.to_vec();
    let sum: f64 = values.iter().map(|&v| v as f64).sum();
    Ok(sum / values.len() as f64)
}

/// k > 1 when the reference is exactly k times the test image in both directions.
pub fn integer_factor(test: &Image, reference: &Image) -> Option<u32> {
    if test.width == 0 || test.height == 0 || reference.width <= test.width {
        return None;
    }
    let k = reference.width / test.width;
    (reference.width == k * test.width && reference.height == k * test.height).then_some(k)
}

/// Mean of each k×k block: the box-filtered image at 1/k the resolution (a box-filtered
/// render's pixels average into the box-filtered pixels of the coarser image exactly).
pub fn box_filter(img: &Image, k: u32) -> Image {
    Image::from_fn(img.width / k, img.height / k, |x, y| {
        let mut s = glam::DVec3::ZERO;
        for j in 0..k {
            for i in 0..k {
                s += img.get(x * k + i, y * k + j).as_dvec3();
            }
        }
        (s / f64::from(k * k)).as_vec3()
    })
}

#[cfg(test)]
mod tests;
