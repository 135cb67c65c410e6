use glam::Vec3;

use super::errormap::{format_number, nice_ceil};
use super::*;
use crate::image::{Image, ToneOperator, Tonemap};

/// A smooth, textured image in [0.05, 0.95] (so clamp tonemapping keeps everything).
fn textured(w: u32, h: u32) -> Image {
    Image::from_fn(w, h, |x, y| {
        let (fx, fy) = (x as f32 / w as f32, y as f32 / h as f32);
        Vec3::new(
            0.5 + 0.4 * (fx * 9.0).sin() * (fy * 5.0).cos(),
            0.1 + 0.8 * fx * fy,
            0.5 + 0.3 * ((fx + fy) * 13.0).sin(),
        )
    })
}

/// Deterministic pseudo-random values in [-1, 1) (a 32-bit integer hash).
fn noise(i: u32) -> f32 {
    let mut z = i.wrapping_mul(0x9E37_79B9).wrapping_add(0x7F4A_7C15);
    z = (z ^ (z >> 16)).wrapping_mul(0x85EB_CA6B);
    z = (z ^ (z >> 13)).wrapping_mul(0xC2B2_AE35);
    z ^= z >> 16;
    (z as f64 / 2f64.powi(31) - 1.0) as f32
}

fn with_noise(img: &Image, amp: f32) -> Image {
    let mut out = img.clone();
    for (i, p) in out.data.iter_mut().enumerate() {
        let i = i as u32 * 3;
        *p += amp * Vec3::new(noise(i), noise(i + 1), noise(i + 2));
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Metrics

#[test]
fn identical_images_have_zero_error_and_unit_ssim() {
    let img = textured(40, 24);
    let m = metrics(&img, &img).unwrap();
    assert_eq!(m.rmse, 0.0);
    assert_eq!(m.rel_rmse, 0.0);
    assert_eq!(m.relmse, 0.0);
    // Equal inputs give numerator == denominator exactly (see ssim()).
    assert_eq!(m.ssim, 1.0);
    assert_eq!(m.flip, 0.0);
}

#[test]
fn constant_offset_known_answers() {
    // Values and offset are exact binary fractions, so f32 storage and the f64 sums are exact.
    let reference = Image::from_fn(8, 6, |_, _| Vec3::new(0.5, 0.25, 1.0));
    let test = Image::from_fn(8, 6, |_, _| Vec3::new(0.625, 0.375, 1.125));
    let m = metrics(&test, &reference).unwrap();
    assert_eq!(m.rmse, 0.125);
    // Reference mean (0.5 + 0.25 + 1) / 3; 1e-15: one f64 division of rounding.
    assert!(
        (m.rel_rmse - 0.125 / (1.75 / 3.0)).abs() < 1e-15,
        "{}",
        m.rel_rmse
    );
    // relMSE by hand: d² = 1/64 in every channel, y² + ε = 0.26, 0.0725, 1.01.
    let by_hand = (0.015_625 / 0.26 + 0.015_625 / 0.0725 + 0.015_625 / 1.01) / 3.0;
    assert!(
        (m.relmse - by_hand).abs() < 1e-15,
        "{} vs {by_hand}",
        m.relmse
    );
    // A negative offset of the same size gives the same RMSE.
    let below = Image::from_fn(8, 6, |_, _| Vec3::new(0.375, 0.125, 0.875));
    assert_eq!(rmse(&below, &reference).unwrap(), 0.125);
}

#[test]
fn relmse_and_rmse_by_hand_on_mixed_pixels() {
    let reference = Image {
        width: 2,
        height: 1,
        data: vec![Vec3::new(0.0, 1.0, 2.0), Vec3::new(0.5, 0.0, 4.0)],
    };
    let test = Image {
        width: 2,
        height: 1,
        data: vec![Vec3::new(0.25, 1.0, 1.0), Vec3::new(0.5, 0.5, 4.0)],
    };
    // Squared differences: 1/16, 0, 1, 0, 1/4, 0 → mean 1.3125 / 6.
    let rmse_hand = (1.3125f64 / 6.0).sqrt();
    let relmse_hand = (0.0625 / 0.01 + 0.0 + 1.0 / 4.01 + 0.0 + 0.25 / 0.01 + 0.0) / 6.0;
    assert!((rmse(&test, &reference).unwrap() - rmse_hand).abs() < 1e-15);
    assert!((relmse(&test, &reference).unwrap() - relmse_hand).abs() < 1e-12);
    let m = metrics(&test, &reference).unwrap();
    assert!((m.rel_rmse - rmse_hand / (7.5 / 6.0)).abs() < 1e-15);
}

#[test]
fn ssim_of_constant_images_matches_the_formula() {
    // Constant images: σ = 0, so SSIM = (2 μx μy + C1) / (μx² + μy² + C1), μ = sRGB OETF of the
    // grey value (the luma weights sum to 1).
    let a = Image::from_fn(16, 16, |_, _| Vec3::splat(0.2));
    let b = Image::from_fn(16, 16, |_, _| Vec3::splat(0.4));
    let (mx, my) = (
        crate::image::srgb_oetf(0.4) as f64,
        crate::image::srgb_oetf(0.2) as f64,
    );
    let expected = (2.0 * mx * my + SSIM_C1) / (mx * mx + my * my + SSIM_C1);
    // 1e-9: the luma weights sum to 1 only up to f64 rounding, and the Gaussian weights too.
    assert!((ssim(&b, &a).unwrap() - expected).abs() < 1e-9);
    assert_eq!(SSIM_C1, 1e-4);
    assert!((SSIM_C2 - 9e-4).abs() < 1e-18);
}

#[test]
fn ssim_decreases_as_noise_increases() {
    let reference = textured(48, 32);
    let mut prev = ssim(&reference, &reference).unwrap();
    assert_eq!(prev, 1.0);
    for amp in [0.005, 0.02, 0.05, 0.15] {
        let s = ssim(&with_noise(&reference, amp), &reference).unwrap();
        assert!(
            s < prev && s > -1.0,
            "noise {amp}: ssim {s} not below {prev}"
        );
        prev = s;
    }
    assert!(prev < 0.8, "heavy noise should give a low SSIM, got {prev}");
    // Symmetric in its arguments.
    let noisy = with_noise(&reference, 0.05);
    let (s1, s2) = (
        ssim(&noisy, &reference).unwrap(),
        ssim(&reference, &noisy).unwrap(),
    );
    assert!((s1 - s2).abs() < 1e-12);
}

#[test]
fn ssim_works_on_images_smaller_than_the_window() {
    let a = textured(5, 3);
    assert_eq!(ssim(&a, &a).unwrap(), 1.0);
    let s = ssim(&with_noise(&a, 0.1), &a).unwrap();
    assert!(s < 1.0 && s > -1.0, "{s}");
    // One axis long enough for valid filtering, one not.
    let b = textured(30, 4);
    assert!(ssim(&with_noise(&b, 0.1), &b).unwrap() < 1.0);
}

#[test]
fn flip_is_zero_for_equal_images_and_grows_with_the_difference() {
    let reference = textured(32, 32);
    let small = flip(
        &with_noise(&reference, 0.02),
        &reference,
        &Tonemap::default(),
    )
    .unwrap();
    let large = flip(
        &with_noise(&reference, 0.2),
        &reference,
        &Tonemap::default(),
    )
    .unwrap();
    assert!(
        0.0 < small && small < large && large <= 1.0,
        "{small} {large}"
    );
    // Values above 1 are clipped by the default tonemap, so a brighter white does not count...
    let white = Image::from_fn(16, 16, |_, _| Vec3::splat(1.0));
    let whiter = Image::from_fn(16, 16, |_, _| Vec3::splat(3.0));
    assert_eq!(flip(&whiter, &white, &Tonemap::default()).unwrap(), 0.0);
    // ...but does with a tonemap that keeps highlights.
    let tm = Tonemap::new(0.0, ToneOperator::Reinhard);
    assert!(flip(&whiter, &white, &tm).unwrap() > 0.0);
    let m = metrics_with_tonemap(&whiter, &white, &tm).unwrap();
    assert!(m.flip > 0.0 && m.ssim == 1.0); // SSIM always uses clamp
}

#[test]
fn size_mismatch_is_an_error_naming_both_sizes() {
    let err = metrics(&Image::new(4, 3), &Image::new(5, 3)).unwrap_err();
    assert!(matches!(err, CompareError::SizeMismatch { .. }));
    let msg = err.to_string();
    assert!(
        msg.contains("test image is 4x3") && msg.contains("reference image is 5x3"),
        "{msg}"
    );
    let opts = ErrorMapOptions::default();
    assert!(error_map(&Image::new(4, 3), &Image::new(4, 2), &opts).is_err());
}

#[test]
fn invalid_inputs_are_errors() {
    let good = textured(4, 4);
    // Reference mean 0: rel_rmse undefined.
    let err = metrics(&good, &Image::new(4, 4)).unwrap_err();
    assert!(
        matches!(err, CompareError::NonPositiveReferenceMean { .. }),
        "{err}"
    );
    // NaN in the test image, named by position.
    let mut nan = good.clone();
    nan.set(1, 2, Vec3::new(0.0, f32::NAN, 0.0));
    let msg = metrics(&nan, &good).unwrap_err().to_string();
    assert!(
        msg.contains("test image") && msg.contains("x 1, y 2"),
        "{msg}"
    );
    // Empty images and inconsistent buffers.
    assert!(matches!(
        metrics(&Image::new(0, 0), &Image::new(0, 0)),
        Err(CompareError::Empty { .. })
    ));
    let broken = Image {
        width: 4,
        height: 4,
        data: vec![Vec3::ONE; 3],
    };
    assert!(matches!(
        metrics(&broken, &good),
        Err(CompareError::BadBuffer { .. })
    ));
}

#[test]
fn metrics_serialize_with_the_cli_keys() {
    let m = Metrics {
        rmse: 1.0,
        rel_rmse: 2.0,
        relmse: 3.0,
        ssim: 0.5,
        flip: 0.25,
    };
    let v: serde_json::Value = serde_json::to_value(m).unwrap();
    let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    keys.sort();
    assert_eq!(keys, ["flip", "rel_rmse", "relmse", "rmse", "ssim"]);
}

// ---------------------------------------------------------------------------------------------
// Error maps

fn distinct(pixels: &[[u8; 3]]) -> usize {
    let mut v = pixels.to_vec();
    v.sort();
    v.dedup();
    v.len()
}

#[test]
fn error_map_has_the_documented_size_and_a_legend() {
    let reference = textured(16, 8);
    let test = with_noise(&reference, 0.05);
    let (w, h, px) = error_map(&test, &reference, &ErrorMapOptions::default()).unwrap();
    assert_eq!((w, h), (200, 8 + 42)); // narrow image: padded to the minimum width
    assert_eq!(px.len(), (w * h) as usize);
    let legend = &px[(8 * w) as usize..];
    assert!(
        distinct(legend) > 50,
        "legend must hold a colour bar and labels"
    );
    // Every legend row band is not all one colour: caption, bar and label bands all drawn.
    let rows: Vec<&[[u8; 3]]> = legend.chunks(w as usize).collect();
    let drawn = rows.iter().filter(|r| distinct(r) > 1).count();
    assert!(
        drawn >= 7 + 10 + 3 + 7,
        "only {drawn} legend rows have content"
    );
    // Wide image: double-size legend, no padding.
    let wide = textured(512, 4);
    let m = render_error_map(&with_noise(&wide, 0.05), &wide, &ErrorMapOptions::default()).unwrap();
    assert_eq!((m.width, m.height, m.map_x), (512, 4 + 82, 0));
    assert_eq!(m.ticks.len(), 5);
}

#[test]
fn error_map_colours_follow_the_scale() {
    let reference = Image::from_fn(10, 4, |_, _| Vec3::splat(0.99));
    let mut test = reference.clone();
    test.set(2, 1, Vec3::splat(1.99)); // relative error 1 / (0.99 + 0.01) = 1
    test.set(3, 1, Vec3::splat(1.39)); // ≈ 0.4
    test.set(4, 1, Vec3::splat(5.0)); // ≈ 4.01, above the scale: saturates
    let opts = ErrorMapOptions {
        scale_max: Some(1.0),
        ..Default::default()
    };
    let m = render_error_map(&test, &reference, &opts).unwrap();
    assert_eq!((m.map_x, m.map_width, m.map_height), (95, 10, 4));
    let at = |x: u32, y: u32| m.pixels[(y * m.width + m.map_x + x) as usize];
    assert_eq!(at(0, 0), MAGMA[0]);
    assert_eq!(at(2, 1), MAGMA[255]);
    assert_eq!(at(3, 1), MAGMA[102]); // round(0.4 · 255)
    assert_eq!(at(4, 1), MAGMA[255]);
    let labels: Vec<&str> = m.ticks.iter().map(|(_, l)| l.as_str()).collect();
    assert_eq!(labels, ["0%", "25%", "50%", "75%", "100%"]);
    // Absolute mode: mean over channels of |x − y|.
    let abs = ErrorMapOptions {
        mode: ErrorMapMode::Absolute,
        scale_max: Some(2.0),
        ..Default::default()
    };
    let e = per_pixel_error(&test, &reference, ErrorMapMode::Absolute).unwrap();
    assert!((e[12] - 1.0).abs() < 1e-6);
    let m = render_error_map(&test, &reference, &abs).unwrap();
    assert_eq!(m.pixels[(m.width + m.map_x + 2) as usize], magma(0.5));
}

#[test]
fn error_map_auto_scale_uses_the_99th_percentile() {
    // 100 pixels with absolute errors 0, 0.01, …, 0.99: nearest-rank 99th percentile is 0.98,
    // rounded up to the nice value 1.
    let reference = Image::new(10, 10);
    let test = Image::from_fn(10, 10, |x, y| Vec3::splat((y * 10 + x) as f32 * 0.01));
    let opts = ErrorMapOptions {
        mode: ErrorMapMode::Absolute,
        ..Default::default()
    };
    let m = render_error_map(&test, &reference, &opts).unwrap();
    assert_eq!(m.scale_max, 1.0);
    let labels: Vec<&str> = m.ticks.iter().map(|(_, l)| l.as_str()).collect();
    assert_eq!(labels, ["0", "0.25", "0.5", "0.75", "1"]);
    // Identical images: scale falls back to 1, map is uniformly the lowest colour.
    let m = render_error_map(&reference, &reference, &ErrorMapOptions::default()).unwrap();
    assert_eq!(m.scale_max, 1.0);
    assert_eq!(m.pixels[m.map_x as usize], MAGMA[0]);
    // Bad options are errors.
    for bad in [
        ErrorMapOptions {
            percentile: 0.0,
            ..Default::default()
        },
        ErrorMapOptions {
            scale_max: Some(-1.0),
            ..Default::default()
        },
        ErrorMapOptions {
            scale_max: Some(f64::NAN),
            ..Default::default()
        },
    ] {
        assert!(matches!(
            render_error_map(&test, &reference, &bad),
            Err(CompareError::InvalidOption(_))
        ));
    }
}

#[test]
fn tick_labels_and_nice_numbers() {
    for (v, s) in [
        (0.0, "0"),
        (0.05, "0.05"),
        (12.5, "12.5"),
        (33.333, "33.3"),
        (100.0, "100"),
        (0.000_15, "1.5e-4"),
        (12_345.0, "1.23e4"),
        (0.012_345, "0.0123"),
    ] {
        assert_eq!(format_number(v), s, "{v}");
    }
    for (v, n) in [
        (0.0873, 0.1),
        (0.011, 0.015),
        (0.98, 1.0),
        (3.2, 4.0),
        (1.0, 1.0),
        (7.0, 8.0),
    ] {
        assert!(
            (nice_ceil(v) - n).abs() < 1e-12,
            "nice_ceil({v}) = {}",
            nice_ceil(v)
        );
    }
    // Every character a label or caption can contain is in the font.
    for c in "0123456789.e-+% ABELRS".chars() {
        assert!(
            super::font::glyph(c).is_some(),
            "{c:?} missing from the font"
        );
    }
    assert!("relative".parse::<ErrorMapMode>().unwrap() == ErrorMapMode::Relative);
    assert!("abs".parse::<ErrorMapMode>().unwrap() == ErrorMapMode::Absolute);
}
