use super::*;
use crate::math::Rng;
use crate::math::sampling::uniform_sphere;
use std::f64::consts::PI;

/// A deterministic map with smooth variation, a few black texels and a bright patch.
fn varied(w: u32, h: u32) -> Image {
    Image::from_fn(w, h, |x, y| {
        if (x + 3 * y) % 11 == 0 {
            return Vec3::ZERO;
        }
        let base = Vec3::new(
            0.2 + 0.1 * (x as f32 * 0.7).sin().abs(),
            0.3 + 0.05 * y as f32,
            0.1,
        );
        if (2..4).contains(&x) && y == 1 {
            base * 40.0
        } else {
            base
        }
    })
}

fn constant(w: u32, h: u32, v: f32) -> Environment {
    Environment::from_image(Image::from_fn(w, h, |_, _| Vec3::splat(v)), 0.0, 1.0).unwrap()
}

#[test]
fn solid_angles_sum_to_four_pi() {
    for (w, h) in [(1, 1), (2, 1), (7, 3), (64, 32), (512, 256), (1024, 512)] {
        let e = constant(w, h, 1.0);
        let s: f64 = (0..h)
            .map(|y| e.texel_solid_angle(y) as f64 * w as f64)
            .sum();
        // f32 solid angles summed in f64: relative error ≲ 1e-7 per row.
        assert!((s - 4.0 * PI).abs() < 1e-5 * 4.0 * PI, "{w}x{h}: {s}");
        // Each texel's solid angle against a direct quadrature of sin θ dθ dφ (2000 steps).
        let y = h / 3;
        let (t0, t1) = (PI * y as f64 / h as f64, PI * (y + 1) as f64 / h as f64);
        let n = 2000;
        let q: f64 = (0..n)
            .map(|i| (t0 + (t1 - t0) * (i as f64 + 0.5) / n as f64).sin() * (t1 - t0) / n as f64)
            .sum::<f64>()
            * 2.0
            * PI
            / w as f64;
        let got = e.texel_solid_angle(y) as f64;
        assert!((got - q).abs() <= 1e-5 * q, "{w}x{h} row {y}: {got} vs {q}");
    }
}

/// The orientation convention, written out independently of the code: Mitsuba 3's
/// u = atan2(x, −z)/2π, v = acos(y)/π, row 0 up.
#[test]
fn orientation_follows_mitsuba() {
    let e = constant(8, 4, 1.0);
    assert_eq!(e.texel_of(Vec3::Y), (e.texel_of(Vec3::Y).0, 0));
    assert_eq!(e.texel_of(-Vec3::Y).1, 3);
    // Horizon directions: −z at u = 0, +x at ¼, +z at ½, −x at ¾ (just past each, to stay off
    // the texel edges).
    let tilt = |d: Vec3, across: Vec3| (d + 0.01 * across + 0.01 * Vec3::Y).normalize();
    assert_eq!(e.texel_of(tilt(-Vec3::Z, Vec3::X)), (0, 1));
    assert_eq!(e.texel_of(tilt(Vec3::X, Vec3::Z)), (2, 1));
    assert_eq!(e.texel_of(tilt(Vec3::Z, -Vec3::X)), (4, 1));
    assert_eq!(e.texel_of(tilt(-Vec3::X, -Vec3::Z)), (6, 1));
    // Texel centres: (x = 2, y = 0) has u = 5/16, v = 1/8.
    let d = e.texel_direction(2, 0);
    let (phi, theta) = (2.0 * PI * 5.0 / 16.0, PI / 8.0);
    let expect = Vec3::new(
        (phi.sin() * theta.sin()) as f32,
        theta.cos() as f32,
        (-phi.cos() * theta.sin()) as f32,
    );
    assert!((d - expect).length() < 1e-6, "{d} vs {expect}");
}

#[test]
fn texel_centres_round_trip() {
    for rot in [0.0, 37.0, -90.0, 720.5] {
        let e = Environment::from_image(varied(16, 8), rot, 1.0).unwrap();
        for y in 0..8 {
            for x in 0..16 {
                let d = e.texel_direction(x, y);
                assert!((d.length() - 1.0).abs() < 1e-6);
                assert_eq!(e.texel_of(d), (x, y), "rotation {rot}");
                assert_eq!(e.radiance(d), e.texel(x, y));
            }
        }
    }
}

/// Rotating by 90° about +y moves a feature from the map's +z to world +x (and its +x to −z).
#[test]
fn rotation_moves_features_about_up() {
    // Bright texel at u ∈ [½, ½ + 1/16): the map's +z horizon, just past it.
    let img = Image::from_fn(16, 8, |x, y| {
        if x == 8 && (y == 3 || y == 4) {
            Vec3::splat(10.0)
        } else {
            Vec3::splat(0.1)
        }
    });
    let probe = |e: &Environment, d: Vec3| e.radiance(d).x;
    let e0 = Environment::from_image(img.clone(), 0.0, 1.0).unwrap();
    let just = |d: Vec3, across: Vec3| (d + 0.05 * across).normalize();
    assert_eq!(probe(&e0, just(Vec3::Z, -Vec3::X)), 10.0);
    assert_eq!(probe(&e0, just(Vec3::X, Vec3::Z)), 0.1);
    let e90 = Environment::from_image(img, 90.0, 1.0).unwrap();
    // R_y(90°) takes (−0.05, 0, 1) to (1, 0, 0.05): world +x, slightly towards +z.
    assert_eq!(probe(&e90, just(Vec3::X, Vec3::Z)), 10.0);
    assert_eq!(probe(&e90, just(Vec3::Z, -Vec3::X)), 0.1);
    assert!((e90.texel_direction(8, 3).x - e0.texel_direction(8, 3).z).abs() < 1e-6);
}

#[test]
fn constant_map_has_uniform_pdf() {
    let e = constant(32, 16, 2.5);
    let mut rng = Rng::keyed(5, 0, 0);
    let inv4pi = (1.0 / (4.0 * PI)) as f32;
    for _ in 0..10_000 {
        let (d, p) = e.sample(rng.vec2()).unwrap();
        assert!((d.length() - 1.0).abs() < 1e-5);
        assert!((p - inv4pi).abs() < 1e-6 * inv4pi * 10.0, "{p}");
        let q = e.pdf(uniform_sphere(rng.vec2()));
        assert!((q - inv4pi).abs() < 1e-5 * inv4pi, "{q}");
    }
    assert!((e.integrated_luminance() - 2.5 * 4.0 * PI).abs() < 1e-4);
}

#[test]
fn pdf_integrates_to_one() {
    let e = Environment::from_image(varied(24, 12), 30.0, 2.0).unwrap();
    // Exactly, texel by texel (the pdf is constant over each texel).
    let mut s = 0.0f64;
    for y in 0..12 {
        for x in 0..24 {
            s += e.pdf(e.texel_direction(x, y)) as f64 * e.texel_solid_angle(y) as f64;
        }
    }
    assert!((s - 1.0).abs() < 1e-5, "{s}");
    // And by Monte Carlo with uniform directions: mean of 4π·pdf is 1 (5 standard errors).
    let mut rng = Rng::keyed(9, 1, 0);
    let n = 400_000;
    let vals: Vec<f64> = (0..n)
        .map(|_| 4.0 * PI * e.pdf(uniform_sphere(rng.vec2())) as f64)
        .collect();
    let mean = vals.iter().sum::<f64>() / n as f64;
    let var = vals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    assert!(
        (mean - 1.0).abs() < 5.0 * (var / n as f64).sqrt(),
        "mean {mean}"
    );
}

/// Wilson–Hilferty upper quantile of χ² with k degrees of freedom at z standard deviations.
fn chi2_quantile(k: f64, z: f64) -> f64 {
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// `sample` follows `pdf`: a χ² test over cells of half a texel in φ and in cos θ (so the
/// within-texel placement is tested too), and `pdf(d)` equals the returned pdf.
#[test]
fn sampling_follows_pdf_chi_square() {
    let (w, h) = (12u32, 6u32);
    let e = Environment::from_image(varied(w, h), 15.0, 1.0).unwrap();
    let n = 400_000usize;
    let mut counts = vec![0u64; (4 * w * h) as usize];
    let mut rng = Rng::keyed(21, 0, 0);
    let mut mismatched = 0;
    let inv = Quat::from_rotation_y(15f32.to_radians()).inverse();
    for _ in 0..n {
        let (d, p) = e.sample(rng.vec2()).unwrap();
        let q = e.pdf(d);
        if (p - q).abs() > 1e-6 * p {
            mismatched += 1;
        }
        // Cell: which half of the texel in φ and in cos θ.
        let m = (inv * d).as_dvec3();
        let mut u = m.x.atan2(-m.z) / (2.0 * PI);
        if u < 0.0 {
            u += 1.0;
        }
        let fx = u * w as f64;
        let y = ((m.x * m.x + m.z * m.z).sqrt().atan2(m.y) / PI * h as f64) as usize;
        let y = y.min(h as usize - 1);
        let x = (fx as usize).min(w as usize - 1);
        let c0 = (PI * y as f64 / h as f64).cos();
        let c1 = (PI * (y + 1) as f64 / h as f64).cos();
        let hy = usize::from(m.y < 0.5 * (c0 + c1));
        let hx = usize::from(fx - x as f64 >= 0.5);
        counts[(2 * y + hy) * 2 * w as usize + 2 * x + hx] += 1;
    }
    // Texel-edge round-off may move a sample to the neighbouring texel: allow 1e-4.
    assert!(mismatched <= n / 10_000, "{mismatched} pdf mismatches");
    let mut chi2 = 0.0;
    let mut dof = 0;
    let mut zero_cells_hit = 0;
    for y in 0..2 * h {
        for x in 0..2 * w {
            let p = e.pdf(e.texel_direction(x / 2, y / 2)) as f64
                * e.texel_solid_angle(y / 2) as f64
                / 4.0;
            let obs = counts[(y * 2 * w + x) as usize] as f64;
            let exp = p * n as f64;
            if exp == 0.0 {
                zero_cells_hit += obs as u64;
                continue;
            }
            chi2 += (obs - exp).powi(2) / exp;
            dof += 1;
        }
    }
    assert_eq!(zero_cells_hit, 0, "black texels were sampled");
    let limit = chi2_quantile((dof - 1) as f64, 4.26); // p ≈ 1e-5
    assert!(chi2 < limit, "χ² = {chi2:.1} > {limit:.1} ({dof} cells)");
}

#[test]
fn black_map_samples_nothing() {
    let e = constant(8, 4, 0.0);
    assert!(e.is_black());
    assert!(e.sample(Vec2::new(0.3, 0.7)).is_none());
    assert_eq!(e.pdf(Vec3::Y), 0.0);
    let e = Environment::from_image(varied(8, 4), 0.0, 0.0).unwrap();
    assert!(e.is_black());
}

#[test]
fn intensity_scales_texels() {
    let a = Environment::from_image(varied(8, 4), 0.0, 1.0).unwrap();
    let b = Environment::from_image(varied(8, 4), 0.0, 3.0).unwrap();
    assert_eq!(b.texel(2, 1), a.texel(2, 1) * 3.0);
    // The pdf does not depend on the scale.
    let d = a.texel_direction(2, 1);
    assert!((a.pdf(d) - b.pdf(d)).abs() < 1e-6 * a.pdf(d));
}

#[test]
fn bad_maps_are_refused() {
    let ok = varied(8, 4);
    let cases: Vec<(Image, f32, f32, &str)> = vec![
        (Image::new(0, 4), 0.0, 1.0, "empty"),
        (
            Image {
                width: 8,
                height: 4,
                data: vec![Vec3::ONE; 5],
            },
            0.0,
            1.0,
            "buffer",
        ),
        (ok.clone(), f32::NAN, 1.0, "rotation"),
        (ok.clone(), f32::INFINITY, 1.0, "rotation"),
        (ok.clone(), 0.0, -1.0, "intensity"),
        (ok.clone(), 0.0, f32::NAN, "intensity"),
        (
            Image::from_fn(8, 4, |x, y| {
                if (x, y) == (3, 2) {
                    Vec3::new(1.0, -0.5, 0.0)
                } else {
                    Vec3::ONE
                }
            }),
            0.0,
            1.0,
            "texel (x 3, y 2) is negative",
        ),
        (
            Image::from_fn(8, 4, |x, _| {
                if x == 5 {
                    Vec3::splat(f32::NAN)
                } else {
                    Vec3::ONE
                }
            }),
            0.0,
            1.0,
            "not finite",
        ),
        (
            Image {
                width: 16384,
                height: 8192,
                data: Vec::new(),
            },
            0.0,
            1.0,
            "too large",
        ),
    ];
    for (img, rot, int, needle) in cases {
        let e = Environment::from_image(img, rot, int).unwrap_err();
        assert!(e.contains(needle), "{needle:?} not in {e:?}");
    }
}

#[test]
fn load_reads_exr_and_hdr_and_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let img = varied(16, 8);
    let exr = dir.path().join("m.exr");
    crate::image::write_exr(&exr, &img).unwrap();
    let e = Environment::load(&exr, 10.0, 2.0).unwrap();
    assert_eq!((e.width(), e.height()), (16, 8));
    assert_eq!(e.texel(3, 1), img.get(3, 1) * 2.0);
    // A flat RGBE file: every texel (0.5, 1, 2).
    let hdr = dir.path().join("m.HDR");
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n".to_vec();
    for _ in 0..8 {
        bytes.extend_from_slice(&[32, 64, 128, 130]); // (c + ½)/64
    }
    std::fs::write(&hdr, &bytes).unwrap();
    let e = Environment::load(&hdr, 0.0, 1.0).unwrap();
    assert_eq!(e.texel(1, 1), Vec3::new(32.5, 64.5, 128.5) / 64.0);
    for (name, bytes, needle) in [
        ("missing.exr", None, "missing.exr"),
        ("broken.exr", Some(&b"not an exr"[..]), "broken.exr"),
        (
            "broken.hdr",
            Some(&b"#?RADIANCE\n\n-Y 2 +X 4\n\x01"[..]),
            "truncated",
        ),
        ("map.png", Some(&b"x"[..]), "extension"),
    ] {
        let p = dir.path().join(name);
        if let Some(b) = bytes {
            std::fs::write(&p, b).unwrap();
        }
        let e = Environment::load(&p, 0.0, 1.0).unwrap_err().to_string();
        assert!(e.contains(needle), "{needle:?} not in {e:?}");
        assert!(e.contains(name), "{name:?} not in {e:?}");
    }
    let neg = dir.path().join("neg.exr");
    crate::image::write_exr(
        &neg,
        &Image::from_fn(4, 2, |x, _| Vec3::splat(if x == 1 { -1.0 } else { 1.0 })),
    )
    .unwrap();
    let e = Environment::load(&neg, 0.0, 1.0).unwrap_err().to_string();
    assert!(e.contains("neg.exr") && e.contains("negative"), "{e}");
}

/// Resampling preserves ∫ L dω, keeps a constant map constant, and a 2× reduction is the
/// solid-angle-weighted mean of each 2 × 2 block.
#[test]
fn resampling_preserves_the_integral() {
    let img = varied(24, 12);
    let integral = |im: &Image| {
        let e = Environment::from_image(im.clone(), 0.0, 1.0).unwrap();
        let mut s = DVec3::ZERO;
        for y in 0..im.height {
            for x in 0..im.width {
                s += e.texel(x, y).as_dvec3() * e.texel_solid_angle(y) as f64;
            }
        }
        s
    };
    let before = integral(&img);
    for (w, h) in [(12, 6), (8, 4), (10, 5), (48, 24), (7, 3), (1, 1)] {
        let r = resample_latlong(&img, w, h);
        assert_eq!((r.width, r.height, r.data.len()), (w, h, (w * h) as usize));
        let after = integral(&r);
        assert!(
            (after - before).abs().max_element() < 1e-5 * before.max_element(),
            "{w}x{h}: {after} vs {before}"
        );
    }
    let c = resample_latlong(&Image::from_fn(20, 10, |_, _| Vec3::splat(0.7)), 6, 3);
    assert!(
        c.data
            .iter()
            .all(|p| (*p - Vec3::splat(0.7)).abs().max_element() < 1e-6)
    );
    let e = Environment::from_image(img.clone(), 0.0, 1.0).unwrap();
    let r = resample_latlong(&img, 12, 6);
    let (x, y) = (3u32, 2u32);
    let (wa, wb) = (
        e.texel_solid_angle(2 * y) as f64,
        e.texel_solid_angle(2 * y + 1) as f64,
    );
    let v = |xx: u32, yy: u32| img.get(xx, yy).as_dvec3();
    let expect = ((v(2 * x, 2 * y) + v(2 * x + 1, 2 * y)) * wa
        + (v(2 * x, 2 * y + 1) + v(2 * x + 1, 2 * y + 1)) * wb)
        / (2.0 * (wa + wb));
    assert!((r.get(x, y).as_dvec3() - expect).abs().max_element() < 1e-5);
}

/// A bright texel times a large intensity used to overflow to ∞ (prt then relit vertices to
/// NaN, the reference dropped non-finite samples): radiance above MAX_EMISSION after the scale
/// is refused, naming the texel; up to it the map loads and its integral stays finite.
#[test]
fn scaled_radiance_beyond_the_limit_is_refused() {
    let img = Image::from_fn(8, 4, |x, y| {
        Vec3::splat(if (x, y) == (3, 1) { 4e36 } else { 1.0 })
    });
    let e = Environment::from_image(img.clone(), 0.0, 1e20).unwrap_err();
    assert!(
        e.starts_with(
            "texel (x 3, y 1) scaled by intensity 100000000000000000000 is (inf, inf, inf)"
        ) && e.ends_with("at most 1e20 per channel"),
        "{e}"
    );
    let e = Environment::from_image(img, 0.0, 1.0).unwrap_err();
    assert!(
        e.starts_with("texel (x 3, y 1) scaled by intensity 1 is (4e36"),
        "{e}"
    );
    let ok =
        Environment::from_image(Image::from_fn(8, 4, |_, _| Vec3::splat(1e10)), 0.0, 1e10).unwrap();
    assert!(ok.integrated_luminance().is_finite() && ok.integrated_luminance() > 0.0);
}

#[test]
fn read_latlong_bytes_checks_extension_and_size_like_the_file_reader() {
    // 4 x 2 flat RGBE texels.
    let mut hdr = b"#?RADIANCE\n\n-Y 2 +X 4\n".to_vec();
    hdr.extend(std::iter::repeat_n([128u8, 128, 128, 129], 8).flatten());
    let img = read_latlong_bytes(&hdr, "sky.hdr").unwrap();
    assert_eq!((img.width, img.height), (4, 2));
    assert_eq!(img.get(3, 1), Vec3::splat(128.5 / 128.0));
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("sky.pic");
    std::fs::write(&p, &hdr).unwrap();
    assert_eq!(read_latlong(&p).unwrap(), img);

    let msg = read_latlong_bytes(&hdr, "sky.png").unwrap_err().to_string();
    assert!(
        msg.starts_with("sky.png: unknown environment-map extension"),
        "{msg}"
    );
    // Refused from the header, before decoding: 16384 x 8192 > MAX_TEXELS.
    let msg = read_latlong_bytes(b"#?RADIANCE\n\n-Y 8192 +X 16384\n", "big.hdr")
        .unwrap_err()
        .to_string();
    assert!(
        msg.starts_with("big.hdr: the map is too large: 16384x8192"),
        "{msg}"
    );
}
