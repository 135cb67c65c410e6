//! SSIM (Wang, Bovik, Sheikh, Simoncelli 2004, "Image quality assessment: from error visibility
//! to structural similarity"), implemented here.

use crate::image::{Image, ToneOperator, Tonemap};

use super::{CompareError, validate};

/// Side of the square Gaussian window.
pub const SSIM_WINDOW: usize = 11;
/// Standard deviation of the Gaussian window, in pixels.
pub const SSIM_SIGMA: f64 = 1.5;
/// Dynamic range of the luma values (sRGB-encoded values in `[0, 1]`).
pub const SSIM_L: f64 = 1.0;
pub const SSIM_K1: f64 = 0.01;
pub const SSIM_K2: f64 = 0.03;
/// C1 = (K1 L)².
pub const SSIM_C1: f64 = (SSIM_K1 * SSIM_L) * (SSIM_K1 * SSIM_L);
/// C2 = (K2 L)².
pub const SSIM_C2: f64 = (SSIM_K2 * SSIM_L) * (SSIM_K2 * SSIM_L);

/// Luma used by SSIM: each channel is tonemapped with exposure 0 EV, clamp to `[0, 1]` and the
/// sRGB OETF (not quantized), then `Y' = 0.2126 R' + 0.7152 G' + 0.0722 B'` (Rec. 709 weights
/// applied to the encoded values). Row-major, one value per pixel, in `[0, 1]`.
pub fn ssim_luma(img: &Image) -> Vec<f64> {
    let tm = Tonemap::new(0.0, ToneOperator::Clamp);
    img.data
        .iter()
        .map(|&v| {
            let d = tm.display(v);
            0.2126 * d.x as f64 + 0.7152 * d.y as f64 + 0.0722 * d.z as f64
        })
        .collect()
}

/// The normalized 1-D Gaussian (the 2-D window is its outer product, so it sums to 1).
fn gaussian_1d() -> [f64; SSIM_WINDOW] {
    let r = (SSIM_WINDOW / 2) as f64;
    let mut k = [0.0; SSIM_WINDOW];
    for (i, w) in k.iter_mut().enumerate() {
        let d = i as f64 - r;
        *w = (-d * d / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
    }
    let s: f64 = k.iter().sum();
    k.iter_mut().for_each(|w| *w /= s);
    k
}

/// Filters the row-major `width × height` map `src` along one axis (rows if `horizontal`, else
/// columns) with the Gaussian. An axis at least as long as the window uses "valid" positions only
/// (its length shrinks by 10); a shorter axis keeps its length and uses the window clipped to the
/// image, its weights renormalized to sum 1. Returns the output and its width and height.
fn filter_axis(
    src: &[f64],
    width: usize,
    height: usize,
    horizontal: bool,
) -> (Vec<f64>, usize, usize) {
    let k = gaussian_1d();
    let r = SSIM_WINDOW / 2;
    let len = if horizontal { width } else { height };
    let valid = len >= SSIM_WINDOW;
    let out_len = if valid { len - 2 * r } else { len };
    let (ow, oh) = if horizontal {
        (out_len, height)
    } else {
        (width, out_len)
    };
    let mut out = vec![0.0; ow * oh];
    let at = |x: usize, y: usize| src[y * width + x];
    for oy in 0..oh {
        for ox in 0..ow {
            let (o, fixed) = if horizontal { (ox, oy) } else { (oy, ox) };
            let mut acc = 0.0;
            let mut wsum = 0.0;
            for (j, &w) in k.iter().enumerate() {
                // Input coordinate along the axis.
                let i = if valid {
                    o + j
                } else {
                    match (o + j).checked_sub(r) {
                        Some(i) if i < len => i,
                        _ => continue,
                    }
                };
                let v = if horizontal {
                    at(i, fixed)
                } else {
                    at(fixed, i)
                };
                acc += w * v;
                wsum += w;
            }
            out[oy * ow + ox] = if valid { acc } else { acc / wsum };
        }
    }
    (out, ow, oh)
}

/// Gaussian-weighted local mean of a `width × height` map (separable; see [`filter_axis`]).
fn local_mean(src: &[f64], width: usize, height: usize) -> (Vec<f64>, usize, usize) {
    let (h, w1, h1) = filter_axis(src, width, height, true);
    filter_axis(&h, w1, h1, false)
}

/// Mean SSIM of `test` against `reference`, on the luma of [`ssim_luma`], with an 11×11 Gaussian
/// window (σ = 1.5, normalized), C1 = (0.01·1)², C2 = (0.03·1)²:
///
/// `SSIM = (2 μx μy + C1)(2 σxy + C2) / ((μx² + μy² + C1)(σx² + σy² + C2))`
///
/// with μ, σ², σxy the Gaussian-weighted local means, variances (E[x²] − μ²) and covariance.
/// The SSIM map is evaluated where the window lies wholly inside the image ("valid", as in
/// Wang's `ssim_index.m`, giving (W − 10) × (H − 10) values) and averaged. Along an image axis
/// shorter than 11 pixels the window is clipped to the image and renormalized instead.
/// No downsampling is applied. Identical images give exactly 1.
pub fn ssim(test: &Image, reference: &Image) -> Result<f64, CompareError> {
    validate(test, reference)?;
    let (w, h) = (test.width as usize, test.height as usize);
    let x = ssim_luma(test);
    let y = ssim_luma(reference);
    let xx: Vec<f64> = x.iter().map(|v| v * v).collect();
    let yy: Vec<f64> = y.iter().map(|v| v * v).collect();
    let xy: Vec<f64> = x.iter().zip(&y).map(|(a, b)| a * b).collect();
    let (mx, ..) = local_mean(&x, w, h);
    let (my, ..) = local_mean(&y, w, h);
    let (mxx, ..) = local_mean(&xx, w, h);
    let (myy, ..) = local_mean(&yy, w, h);
    let (mxy, ..) = local_mean(&xy, w, h);
    let mut sum = 0.0;
    for i in 0..mx.len() {
        let (ux, uy) = (mx[i], my[i]);
        let sxx = mxx[i] - ux * ux;
        let syy = myy[i] - uy * uy;
        let sxy = mxy[i] - ux * uy;
        let num = (2.0 * ux * uy + SSIM_C1) * (2.0 * sxy + SSIM_C2);
        let den = (ux * ux + uy * uy + SSIM_C1) * (sxx + syy + SSIM_C2);
        sum += num / den;
    }
    Ok(sum / mx.len() as f64)
}
