use std::path::Path;

use exr::prelude::{self as x, WritableImage};
use glam::Vec3;

use super::*;

/// A deterministic test image with negative, tiny (subnormal), large and ordinary values.
fn varied_image(w: u32, h: u32) -> Image {
    Image::from_fn(w, h, |px, py| {
        let i = (py * w + px) as f32;
        Vec3::new(
            (i * 0.37).sin() * 3.0,
            1.0e-40 * (i + 1.0) + (px as f32) * 1.0e-3,
            if (px + py) % 7 == 0 {
                1.0e30
            } else {
                -0.0 + i * i * 1.0e-4
            },
        )
    })
}

fn bits(img: &Image) -> Vec<[u32; 3]> {
    img.data
        .iter()
        .map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
        .collect()
}

/// Writes a 3-channel f32 EXR with the exr crate directly (bypassing our NaN check).
fn write_raw_rgb_f32(
    path: &Path,
    w: usize,
    h: usize,
    f: impl Sync + Fn(usize, usize) -> (f32, f32, f32),
) {
    x::write_rgb_file(path, w, h, f).unwrap();
}

fn file_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

// ---------------------------------------------------------------------------------------------
// EXR

#[test]
fn exr_round_trip_is_bit_exact_for_f32() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.exr");
    // 19 × 37: odd sizes, more than two 16-line ZIP blocks.
    let img = varied_image(19, 37);
    write_exr(&p, &img).unwrap();
    let back = read_exr(&p).unwrap();
    assert_eq!((back.width, back.height), (19, 37));
    assert_eq!(
        bits(&back),
        bits(&img),
        "f32 EXR round trip must be bit exact"
    );
    // Atomic: only the final file is left in the directory.
    assert_eq!(file_names(dir.path()), vec!["a.exr".to_string()]);
}

#[test]
fn exr_written_is_zip_compressed_f32_rgb() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("z.exr");
    write_exr(&p, &Image::new(8, 8)).unwrap();
    let meta = exr::meta::MetaData::read_from_file(&p, true).unwrap();
    let h = &meta.headers[0];
    assert_eq!(h.compression, exr::compression::Compression::ZIP16);
    let names: Vec<String> = h.channels.list.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(names, ["B", "G", "R"]); // EXR stores channels sorted by name
    assert!(
        h.channels
            .list
            .iter()
            .all(|c| c.sample_type == exr::meta::attribute::SampleType::F32)
    );
}

#[test]
fn reads_half_float_rgba_exr_written_by_exr_crate() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("half.exr");
    // Values exactly representable in f16, so the expected result is exact.
    let val = |px: usize, py: usize| {
        (
            px as f32 * 0.25,
            py as f32 * 0.5 + 16.0,
            0.000_976_562_5 * (px + py) as f32,
        )
    };
    let channels = x::SpecificChannels::rgba(|pos: x::Vec2<usize>| {
        let (r, g, b) = val(pos.x(), pos.y());
        (
            x::f16::from_f32(r),
            x::f16::from_f32(g),
            x::f16::from_f32(b),
            x::f16::ONE,
        )
    });
    x::Image::from_encoded_channels((6, 5), x::Encoding::SMALL_FAST_LOSSLESS, channels)
        .write()
        .to_file(&p)
        .unwrap();
    let img = read_exr(&p).unwrap();
    assert_eq!((img.width, img.height), (6, 5));
    for py in 0..5 {
        for px in 0..6 {
            let (r, g, b) = val(px, py);
            assert_eq!(
                img.get(px as u32, py as u32),
                Vec3::new(r, g, b),
                "pixel ({px}, {py})"
            );
        }
    }
}

#[test]
fn reads_f32_exr_with_other_compressions_and_tiles() {
    let dir = tempfile::tempdir().unwrap();
    let img = varied_image(23, 11);
    let w = img.width as usize;
    for (i, enc) in [
        x::Encoding::UNCOMPRESSED,
        x::Encoding::FAST_LOSSLESS, // RLE, tiled
        x::Encoding {
            compression: x::Compression::PIZ,
            blocks: x::Blocks::ScanLines,
            line_order: x::LineOrder::Increasing,
        },
        // Bottom rows first: the reader's pixel buffer grows to full size on the first block.
        x::Encoding {
            compression: x::Compression::ZIP1,
            blocks: x::Blocks::ScanLines,
            line_order: x::LineOrder::Decreasing,
        },
    ]
    .into_iter()
    .enumerate()
    {
        let p = dir.path().join(format!("c{i}.exr"));
        let data = &img.data;
        let channels = x::SpecificChannels::rgb(|pos: x::Vec2<usize>| {
            let v = data[pos.y() * w + pos.x()];
            (v.x, v.y, v.z)
        });
        x::Image::from_encoded_channels((w, 11), enc, channels)
            .write()
            .to_file(&p)
            .unwrap();
        assert_eq!(bits(&read_exr(&p).unwrap()), bits(&img), "encoding {enc:?}");
    }
}

#[test]
fn small_and_large_exr_files_decode_alike() {
    // Below PARALLEL_EXR_BYTES a file is decoded on the calling thread, above it in parallel.
    let dir = tempfile::tempdir().unwrap();
    for (w, h) in [(7, 5), (256, 256)] {
        let p = dir.path().join(format!("{w}.exr"));
        let img = varied_image(w, h);
        write_exr(&p, &img).unwrap();
        let len = std::fs::metadata(&p).unwrap().len() as usize;
        assert_eq!(
            len >= super::exr_io::PARALLEL_EXR_BYTES,
            w == 256,
            "{len} bytes"
        );
        assert_eq!(bits(&read_exr(&p).unwrap()), bits(&img), "{w}x{h}");
    }
}

#[test]
fn exr_bytes_read_like_the_file_and_huge_headers_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.exr");
    let img = varied_image(5, 3);
    write_exr(&p, &img).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(
        bits(&read_exr_bytes(&bytes, "mem.exr").unwrap()),
        bits(&read_exr(&p).unwrap())
    );
    assert_eq!(read_exr_size_bytes(&bytes, "mem.exr").unwrap(), (5, 3));

    // The same header declaring a 2^28 × 3 data window (the offset table still matches: the
    // height, hence the number of blocks, is unchanged). Refused before anything is decoded.
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    let mut huge = bytes.clone();
    huge[at + 8..at + 12].copy_from_slice(&((1i32 << 28) - 1).to_le_bytes());
    assert_eq!(
        read_exr_size_bytes(&huge, "huge.exr").unwrap(),
        (1 << 28, 3)
    );
    let msg = read_exr_bytes(&huge, "huge.exr").unwrap_err().to_string();
    assert!(msg.contains("\"huge.exr\""), "{msg}");
    assert!(
        msg.contains("268435456x3 is larger than the 268435456 pixels"),
        "{msg}"
    );

    // Truncated pixel data: an error, not a partly black image.
    let msg = read_exr_bytes(&bytes[..bytes.len() - 10], "cut.exr")
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("\"cut.exr\" is not a readable OpenEXR file"),
        "{msg}"
    );
}

#[test]
fn hdr_bytes_read_like_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.hdr");
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n".to_vec();
    bytes.extend_from_slice(&[128, 64, 32, 129, 1, 2, 3, 130]);
    std::fs::write(&p, &bytes).unwrap();
    assert_eq!(
        read_hdr_bytes(&bytes, "mem.hdr").unwrap(),
        read_hdr(&p).unwrap()
    );
    assert_eq!(read_hdr_size_bytes(&bytes, "mem.hdr").unwrap(), (2, 1));
    let msg = read_hdr_bytes(&bytes[..bytes.len() - 1], "cut.hdr")
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("\"cut.hdr\" is not a readable Radiance HDR file"),
        "{msg}"
    );
    assert!(msg.contains("truncated"), "{msg}");
    // A header declaring the largest size over no data fails without a huge allocation.
    let msg = read_hdr_bytes(b"#?RADIANCE\n\n-Y 32767 +X 32767\n", "big.hdr")
        .unwrap_err()
        .to_string();
    assert!(msg.contains("scanline 0 (of 32767)"), "{msg}");
}

#[test]
fn nan_pixel_is_rejected_naming_the_first_bad_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("nan.exr");
    write_raw_rgb_f32(&p, 6, 4, |px, py| {
        if (px, py) == (3, 2) || (px, py) == (5, 3) {
            (0.5, f32::NAN, 0.25)
        } else {
            (0.5, 0.5, 0.5)
        }
    });
    let err = read_exr(&p).unwrap_err();
    match &err {
        ImageError::NonFinitePixel { x, y, kind, .. } => {
            assert_eq!((*x, *y, *kind), (3, 2, "NaN"));
        }
        other => panic!("expected NonFinitePixel, got {other:?}"),
    }
    let msg = err.to_string();
    assert!(
        msg.contains("nan.exr") && msg.contains("x 3, y 2") && msg.contains("NaN"),
        "{msg}"
    );
}

#[test]
fn infinite_pixel_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("inf.exr");
    write_raw_rgb_f32(&p, 3, 3, |px, py| {
        if (px, py) == (1, 0) {
            (0.0, 0.0, f32::INFINITY)
        } else {
            (0.0, 0.0, 0.0)
        }
    });
    let msg = read_exr(&p).unwrap_err().to_string();
    assert!(
        msg.contains("inf.exr") && msg.contains("x 1, y 0") && msg.contains("infinite"),
        "{msg}"
    );
}

#[test]
fn write_exr_refuses_non_finite_and_inconsistent_images() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.exr");
    let mut img = Image::new(4, 4);
    img.set(2, 1, Vec3::new(0.0, f32::NAN, 0.0));
    let msg = write_exr(&p, &img).unwrap_err().to_string();
    assert!(msg.contains("x 2, y 1") && msg.contains("NaN"), "{msg}");
    let bad = Image {
        width: 4,
        height: 4,
        data: vec![Vec3::ZERO; 15],
    };
    assert!(matches!(
        write_exr(&p, &bad),
        Err(ImageError::InvalidImage { .. })
    ));
    assert!(matches!(
        write_exr(&p, &Image::new(0, 3)),
        Err(ImageError::InvalidImage { .. })
    ));
    assert!(file_names(dir.path()).is_empty(), "nothing may be written");
}

#[test]
fn truncated_and_garbage_exr_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("good.exr");
    write_exr(&good, &varied_image(16, 40)).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    for (name, content) in [
        ("truncated_half.exr", bytes[..bytes.len() / 2].to_vec()),
        ("truncated_tail.exr", bytes[..bytes.len() - 7].to_vec()),
        ("truncated_header.exr", bytes[..40].to_vec()),
        (
            "garbage.exr",
            b"this is not an OpenEXR file at all, just text".to_vec(),
        ),
        ("empty.exr", Vec::new()),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, content).unwrap();
        let err = read_exr(&p).expect_err(name);
        assert!(
            matches!(err, ImageError::ExrDecode { .. }),
            "{name}: {err:?}"
        );
        assert!(err.to_string().contains(name), "{name}: {err}");
    }
}

#[test]
fn missing_file_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("does-not-exist.exr");
    let err = read_exr(&p).unwrap_err();
    match &err {
        ImageError::Read { source, .. } => assert_eq!(source.kind(), std::io::ErrorKind::NotFound),
        other => panic!("expected Read, got {other:?}"),
    }
    assert!(err.to_string().contains("does-not-exist.exr"), "{err}");
}

#[test]
fn exr_without_rgb_channels_is_an_error_listing_the_channels() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("luma.exr");
    let channels = x::SpecificChannels::build()
        .with_channel("Y")
        .with_pixel_fn(|_pos: x::Vec2<usize>| (0.5f32,));
    x::Image::from_channels((4, 4), channels)
        .write()
        .to_file(&p)
        .unwrap();
    let err = read_exr(&p).unwrap_err();
    assert!(matches!(err, ImageError::MissingChannels { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("luma.exr") && msg.contains("found: Y"),
        "{msg}"
    );
}

// ---------------------------------------------------------------------------------------------
// Tonemapping

#[test]
fn srgb_curve_at_known_points() {
    // Reference values from the IEC 61966-2-1 formulas, evaluated in f64.
    let cases = [
        (0.0f32, 0.0f32),
        (0.001, 0.01292),
        (0.003_130_8, 0.040_449_936),
        (0.18, 0.461_356_1),
        (0.215_860_5, 0.501_960_8), // 128/255
        (0.5, 0.735_356_7),
        (1.0, 1.0),
    ];
    for (lin, enc) in cases {
        // 2e-6: f32 powf rounding.
        assert!(
            (srgb_oetf(lin) - enc).abs() < 2e-6,
            "oetf({lin}) = {} ≠ {enc}",
            srgb_oetf(lin)
        );
        assert!(
            (srgb_eotf(enc) - lin).abs() < 2e-6,
            "eotf({enc}) = {} ≠ {lin}",
            srgb_eotf(enc)
        );
    }
    // Out-of-range inputs are clamped.
    assert_eq!(srgb_oetf(-1.0), 0.0);
    assert_eq!(srgb_oetf(7.0), 1.0);
    // 8-bit codes at known points (round to nearest).
    let tm = Tonemap::default();
    let img = Image {
        width: 6,
        height: 1,
        data: [0.0, 0.18, 0.215_860_5, 0.5, 1.0, 3.0]
            .map(Vec3::splat)
            .to_vec(),
    };
    let px: Vec<u8> = to_srgb8(&img, &tm).iter().map(|p| p[0]).collect();
    assert_eq!(px, [0, 118, 128, 188, 255, 255]);
}

#[test]
fn tone_operators_are_monotone_and_bounded() {
    for op in ToneOperator::ALL {
        for exposure in [-2.0f32, 0.0, 1.5] {
            let tm = Tonemap::new(exposure, op);
            let mut prev_t = 0.0f32;
            let mut prev_8 = 0u8;
            for i in 0..=2000 {
                let v = 1.0e-4f32 * 10f32.powf(i as f32 * 0.004); // 1e-4 … 1e4
                let t = tm.tone(Vec3::splat(v)).x;
                let c = tm.to_srgb8_pixel(Vec3::splat(v))[0];
                assert!((0.0..=1.0).contains(&t), "{op} {exposure}: {t}");
                assert!(
                    t >= prev_t && c >= prev_8,
                    "{op} {exposure}: not monotone at {v}"
                );
                (prev_t, prev_8) = (t, c);
            }
        }
    }
    // Known values.
    assert_eq!(ToneOperator::Clamp.apply(0.25), 0.25);
    assert_eq!(ToneOperator::Clamp.apply(2.0), 1.0);
    assert_eq!(ToneOperator::Reinhard.apply(1.0), 0.5);
    assert_eq!(ToneOperator::Reinhard.apply(3.0), 0.75);
    assert!((ToneOperator::Aces.apply(1.0) - 2.54 / 3.16).abs() < 1e-6);
    assert_eq!(ToneOperator::Aces.apply(1.0e30), 1.0);
    // Exposure is in stops.
    assert_eq!(
        Tonemap::new(1.0, ToneOperator::Clamp)
            .tone(Vec3::splat(0.25))
            .x,
        0.5
    );
    assert_eq!(
        Tonemap::new(-2.0, ToneOperator::Clamp)
            .tone(Vec3::splat(2.0))
            .x,
        0.5
    );
    // Negative, NaN and infinite radiance.
    for op in ToneOperator::ALL {
        assert_eq!(op.apply(-3.0), 0.0);
        assert_eq!(op.apply(f32::NAN), 0.0);
        assert_eq!(op.apply(f32::INFINITY), 1.0);
    }
}

#[test]
fn tonemap_describe_names_and_serde() {
    assert_eq!(
        Tonemap::default().describe(),
        "exposure +0.0 EV, operator clamp, sRGB OETF"
    );
    assert_eq!(
        Tonemap::new(-1.5, ToneOperator::Aces).describe(),
        "exposure -1.5 EV, operator aces, sRGB OETF"
    );
    assert_eq!(
        Tonemap::new(0.25, ToneOperator::Reinhard).describe(),
        "exposure +0.25 EV, operator reinhard, sRGB OETF"
    );
    assert_eq!(
        Tonemap::new(-0.0, ToneOperator::Clamp).describe(),
        Tonemap::default().describe()
    );
    for op in ToneOperator::ALL {
        assert_eq!(op.name().parse::<ToneOperator>().unwrap(), op);
    }
    assert_eq!("ACES".parse::<ToneOperator>().unwrap(), ToneOperator::Aces);
    assert!("filmic".parse::<ToneOperator>().is_err());
    let json = serde_json::to_string(&Tonemap::default()).unwrap();
    assert_eq!(json, r#"{"exposure":0.0,"operator":"clamp"}"#);
}

// ---------------------------------------------------------------------------------------------
// PNG

fn decode_png(p: &Path) -> (png::OutputInfo, Vec<u8>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).unwrap()));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info, buf)
}

#[test]
fn png_is_written_atomically_and_decodes_to_the_tonemapped_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("sub").join("out.png");
    let img = Image::from_fn(9, 5, |px, py| {
        Vec3::new(px as f32 * 0.1, py as f32 * 0.2, 0.5)
    });
    let tm = Tonemap::new(0.5, ToneOperator::Reinhard);
    write_png(&p, &img, &tm).unwrap();
    // Overwrite once more: the rename must replace the file.
    write_png(&p, &img, &tm).unwrap();
    assert_eq!(
        file_names(&dir.path().join("sub")),
        vec!["out.png".to_string()],
        "temp file left behind"
    );
    let (info, data) = decode_png(&p);
    assert_eq!((info.width, info.height), (9, 5));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    assert_eq!(data, to_srgb8(&img, &tm).as_flattened());
}

#[test]
fn png_rgb8_checks_the_buffer_size() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.png");
    let err = write_png_rgb8(&p, 3, 2, &[[0, 0, 0]; 5]).unwrap_err();
    assert!(
        err.to_string().contains("x.png") && err.to_string().contains("3x2"),
        "{err}"
    );
    assert!(file_names(dir.path()).is_empty());
    write_png_rgb8(&p, 3, 2, &[[1, 2, 3]; 6]).unwrap();
    assert_eq!(decode_png(&p).1, [1, 2, 3].repeat(6));
}

#[test]
fn image_helpers() {
    let mut img = Image::from_fn(3, 2, |px, py| Vec3::splat((px + 10 * py) as f32));
    assert_eq!(img.get(2, 1), Vec3::splat(12.0));
    assert!(img.has_consistent_size());
    assert_eq!(img.first_non_finite(), None);
    img.set(1, 1, Vec3::new(0.0, f32::INFINITY, 0.0));
    img.set(2, 1, Vec3::NAN);
    assert_eq!(
        img.first_non_finite().map(|(px, py, _)| (px, py)),
        Some((1, 1))
    );
}

/// Half-float EXR (PIZ): reads back within half precision; out-of-range pixels are refused.
#[test]
fn half_exr_round_trips_within_half_precision() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("h.exr");
    let img = Image::from_fn(33, 17, |x, y| {
        Vec3::new(
            x as f32 * 0.37,
            y as f32 * 100.0 + 0.01,
            60000.0 / (1.0 + x as f32),
        )
    });
    write_exr_half(&p, &img).unwrap();
    let back = read_exr(&p).unwrap();
    assert_eq!((back.width, back.height), (33, 17));
    for (a, b) in img.data.iter().zip(&back.data) {
        // Half floats: 11 significant bits, relative error ≤ 2⁻¹¹ (plus subnormal spacing).
        let excess = (*a - *b).abs() - a.abs() / 2048.0;
        assert!(excess.max_element() <= 1e-6, "{a} read back as {b}");
    }
    let too_big = Image::from_fn(2, 1, |x, _| Vec3::splat(if x == 1 { 7e4 } else { 1.0 }));
    let e = write_exr_half(&p, &too_big).unwrap_err().to_string();
    assert!(e.contains("half") && e.contains("x 1"), "{e}");
}
