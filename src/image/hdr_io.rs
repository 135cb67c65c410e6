//! Radiance RGBE (`.hdr`, `.pic`) input: flat, old-style and new-style run-length encoded
//! scanlines (Ward, "Real Pixels", Graphics Gems II, 1991; the Radiance file-format notes).
//!
//! - Header: a `#?` magic line (`#?RADIANCE`, `#?RGBE`, ...), variable lines up to an empty
//!   line, then the resolution line. `FORMAT=32-bit_rle_rgbe` (or no `FORMAT`) is read;
//!   `32-bit_rle_xyze` is refused. `EXPOSURE` and `COLORCORR` are ignored, as most readers do
//!   (stb_image, Blender), so values come out as stored.
//! - Resolution: `-Y H +X W` (rows top to bottom, the usual form) and the mirrored `+Y`/`-X`
//!   forms, which are flipped into top-to-bottom, left-to-right order. Column-major forms
//!   (`+X W -Y H`, ...) are refused.
//! - Pixel (r, g, b, e) decodes as ((c + 0.5) · 2^(e − 136)) per channel, 0 when e = 0 —
//!   Radiance's own `colr_color`.

use std::path::Path;

use glam::Vec3;

use super::{Image, ImageError};

/// Largest side accepted from an RGBE header (the new-style RLE cannot encode wider lines).
pub const MAX_HDR_SIDE: u32 = 32767;

/// Reads a Radiance RGBE file as linear RGB, rows from the top. Errors name the file and what is
/// wrong (unreadable file, bad header, unsupported format or orientation, truncated or
/// inconsistent run-length data).
pub fn read_hdr(path: &Path) -> Result<Image, ImageError> {
    let bytes = std::fs::read(path).map_err(|source| ImageError::Read {
        path: path.to_path_buf(),
        format: "Radiance HDR",
        source,
    })?;
    read_hdr_bytes_at(&bytes, path)
}

/// [`read_hdr`] for a file held in memory: `name` stands for the file in error messages.
pub fn read_hdr_bytes(bytes: &[u8], name: &str) -> Result<Image, ImageError> {
    read_hdr_bytes_at(bytes, Path::new(name))
}

fn read_hdr_bytes_at(bytes: &[u8], path: &Path) -> Result<Image, ImageError> {
    decode_hdr(bytes).map_err(|reason| ImageError::HdrDecode {
        path: path.to_path_buf(),
        reason,
    })
}

/// Width and height from the header alone (for size checks before decoding).
pub fn read_hdr_size(path: &Path) -> Result<(u32, u32), ImageError> {
    let bytes = std::fs::read(path).map_err(|source| ImageError::Read {
        path: path.to_path_buf(),
        format: "Radiance HDR",
        source,
    })?;
    size_at(&bytes, path)
}

/// [`read_hdr_size`] for a file held in memory: `name` stands for the file in error messages.
pub fn read_hdr_size_bytes(bytes: &[u8], name: &str) -> Result<(u32, u32), ImageError> {
    size_at(bytes, Path::new(name))
}

fn size_at(bytes: &[u8], path: &Path) -> Result<(u32, u32), ImageError> {
    parse_header(bytes)
        .map(|h| (h.width, h.height))
        .map_err(|reason| ImageError::HdrDecode {
            path: path.to_path_buf(),
            reason,
        })
}

struct Header {
    width: u32,
    height: u32,
    /// Rows are stored bottom to top (`+Y`).
    flip_y: bool,
    /// Columns are stored right to left (`-X`).
    flip_x: bool,
    /// Offset of the first pixel byte.
    data: usize,
}

/// Reads one header line (without the newline) starting at `*pos`.
fn line<'a>(bytes: &'a [u8], pos: &mut usize) -> Option<&'a [u8]> {
    let rest = &bytes[*pos..];
    let end = rest.iter().position(|&b| b == b'\n')?;
    *pos += end + 1;
    let l = &rest[..end];
    Some(l.strip_suffix(b"\r").unwrap_or(l))
}

fn parse_header(bytes: &[u8]) -> Result<Header, String> {
    let mut pos = 0;
    if !bytes.starts_with(b"#?") {
        return Err("not a Radiance HDR file: it does not start with \"#?\"".into());
    }
    line(bytes, &mut pos).ok_or("the header does not end")?;
    loop {
        let l = line(bytes, &mut pos)
            .ok_or("the header does not end (no empty line before the resolution line)")?;
        if l.is_empty() {
            break;
        }
        if let Some(f) = l.strip_prefix(b"FORMAT=") {
            let f = String::from_utf8_lossy(f);
            let f = f.trim();
            if f != "32-bit_rle_rgbe" {
                return Err(format!(
                    "FORMAT={f} is not supported (only 32-bit_rle_rgbe is read)"
                ));
            }
        }
    }
    let res = line(bytes, &mut pos).ok_or("no resolution line after the header")?;
    let res = String::from_utf8_lossy(res).into_owned();
    let parts: Vec<&str> = res.split_whitespace().collect();
    let bad = || format!("resolution line \"{res}\" is not of the form \"-Y height +X width\"");
    if parts.len() != 4 {
        return Err(bad());
    }
    let (flip_y, flip_x) = match (parts[0], parts[2]) {
        ("-Y", "+X") => (false, false),
        ("+Y", "+X") => (true, false),
        ("-Y", "-X") => (false, true),
        ("+Y", "-X") => (true, true),
        (a, _) if a.ends_with('X') => {
            return Err(format!(
                "resolution line \"{res}\": column-major orientations are not supported"
            ));
        }
        _ => return Err(bad()),
    };
    let height: u32 = parts[1].parse().map_err(|_| bad())?;
    let width: u32 = parts[3].parse().map_err(|_| bad())?;
    if width == 0 || height == 0 || width > MAX_HDR_SIDE || height > MAX_HDR_SIDE {
        return Err(format!(
            "image size {width}x{height} is outside 1 … {MAX_HDR_SIDE} per side"
        ));
    }
    Ok(Header {
        width,
        height,
        flip_y,
        flip_x,
        data: pos,
    })
}

/// Decodes a whole RGBE file held in memory.
pub fn decode_hdr(bytes: &[u8]) -> Result<Image, String> {
    let h = parse_header(bytes)?;
    let (w, ht) = (h.width as usize, h.height as usize);
    let mut data = &bytes[h.data..];
    let mut rgbe = vec![[0u8; 4]; w];
    // Reserve no more than the data could describe without runs: a header declaring a large
    // image over a few bytes fails on its first scanlines, not after a huge allocation.
    let mut out = Vec::with_capacity((w * ht).min(bytes.len()));
    for row in 0..ht {
        read_scanline(&mut data, &mut rgbe)
            .map_err(|e| format!("scanline {row} (of {ht}): {e}"))?;
        out.extend(rgbe.iter().map(|&p| rgbe_to_rgb(p)));
    }
    let mut img = Image {
        width: h.width,
        height: h.height,
        data: out,
    };
    if h.flip_y {
        let mut flipped = Vec::with_capacity(img.data.len());
        for row in img.data.chunks(w).rev() {
            flipped.extend_from_slice(row);
        }
        img.data = flipped;
    }
    if h.flip_x {
        for row in img.data.chunks_mut(w) {
            row.reverse();
        }
    }
    Ok(img)
}

/// Radiance's `colr_color`: (c + 0.5) · 2^(e − 136); e = 0 is black.
pub fn rgbe_to_rgb(p: [u8; 4]) -> Vec3 {
    if p[3] == 0 {
        return Vec3::ZERO;
    }
    let f = 2f32.powi(p[3] as i32 - 136);
    Vec3::new(
        (p[0] as f32 + 0.5) * f,
        (p[1] as f32 + 0.5) * f,
        (p[2] as f32 + 0.5) * f,
    )
}

fn take<'a>(data: &mut &'a [u8], n: usize) -> Result<&'a [u8], String> {
    if data.len() < n {
        return Err("the file ends early (truncated pixel data)".into());
    }
    let (a, b) = data.split_at(n);
    *data = b;
    Ok(a)
}

/// Reads one scanline into `out` (its length is the width), detecting the encoding.
fn read_scanline(data: &mut &[u8], out: &mut [[u8; 4]]) -> Result<(), String> {
    let w = out.len();
    // New-style RLE: 2, 2, width (big-endian, high bit clear), for widths 8 … 32767.
    if (8..=0x7fff).contains(&w)
        && data.len() >= 4
        && data[0] == 2
        && data[1] == 2
        && data[2] & 0x80 == 0
    {
        let head = take(data, 4)?;
        let lw = ((head[2] as usize) << 8) | head[3] as usize;
        if lw != w {
            return Err(format!(
                "run-length scanline declares width {lw}, the image is {w} wide"
            ));
        }
        for c in 0..4 {
            let mut x = 0;
            while x < w {
                let n = take(data, 1)?[0] as usize;
                if n > 128 {
                    let count = n - 128;
                    if x + count > w {
                        return Err(format!(
                            "a run of {count} overruns the scanline at x {x} (width {w})"
                        ));
                    }
                    let v = take(data, 1)?[0];
                    for p in &mut out[x..x + count] {
                        p[c] = v;
                    }
                    x += count;
                } else {
                    if n == 0 {
                        return Err("a run-length count of 0".into());
                    }
                    if x + n > w {
                        return Err(format!(
                            "{n} literal bytes overrun the scanline at x {x} (width {w})"
                        ));
                    }
                    let src = take(data, n)?;
                    for (p, &v) in out[x..x + n].iter_mut().zip(src) {
                        p[c] = v;
                    }
                    x += n;
                }
            }
        }
        return Ok(());
    }
    // Flat pixels with old-style runs: (1, 1, 1, n) repeats the previous pixel n << shift times.
    let mut x = 0;
    let mut shift = 0u32;
    while x < w {
        let p = take(data, 4)?;
        let p = [p[0], p[1], p[2], p[3]];
        if p[0] == 1 && p[1] == 1 && p[2] == 1 {
            if x == 0 {
                return Err("an old-style run at the start of a scanline".into());
            }
            if shift > 24 {
                return Err("an old-style run is too long".into());
            }
            let count = (p[3] as usize) << shift;
            if x + count > w {
                return Err(format!(
                    "an old-style run of {count} overruns the scanline at x {x} (width {w})"
                ));
            }
            let prev = out[x - 1];
            for q in &mut out[x..x + count] {
                *q = prev;
            }
            x += count;
            shift += 8;
        } else {
            out[x] = p;
            x += 1;
            shift = 0;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Encodes `f32` RGB as RGBE the way Radiance's `setcolr` does (mantissa truncated).
    fn to_rgbe(c: Vec3) -> [u8; 4] {
        let m = c.max_element();
        if m < 1e-32 {
            return [0; 4];
        }
        let e = m.log2().floor() as i32 + 1;
        let s = 256.0 / 2f32.powi(e);
        [
            (c.x * s) as u8,
            (c.y * s) as u8,
            (c.z * s) as u8,
            (e + 128) as u8,
        ]
    }

    /// New-style RLE of one scanline: runs where ≥ 3 equal bytes follow, literals elsewhere.
    fn rle_line(px: &[[u8; 4]]) -> Vec<u8> {
        let w = px.len();
        let mut out = vec![2, 2, (w >> 8) as u8, (w & 0xff) as u8];
        for c in 0..4 {
            let col: Vec<u8> = px.iter().map(|p| p[c]).collect();
            let mut i = 0;
            while i < w {
                let mut run = 1;
                while i + run < w && run < 127 && col[i + run] == col[i] {
                    run += 1;
                }
                if run >= 3 {
                    out.push(128 + run as u8);
                    out.push(col[i]);
                    i += run;
                } else {
                    let start = i;
                    let mut n = 0;
                    while i < w && n < 128 {
                        let mut r = 1;
                        while i + r < w && r < 3 && col[i + r] == col[i] {
                            r += 1;
                        }
                        if r >= 3 {
                            break;
                        }
                        i += 1;
                        n += 1;
                    }
                    out.push(n as u8);
                    out.extend_from_slice(&col[start..start + n]);
                }
            }
        }
        out
    }

    fn file(header: &str, body: &[u8]) -> Vec<u8> {
        let mut b = header.as_bytes().to_vec();
        b.extend_from_slice(body);
        b
    }

    fn pattern(w: usize, h: usize) -> Vec<Vec<[u8; 4]>> {
        (0..h)
            .map(|y| {
                (0..w)
                    .map(|x| {
                        if x % 5 < 3 {
                            to_rgbe(Vec3::new(1.0 + y as f32, 0.25, 3.0))
                        } else {
                            to_rgbe(Vec3::new(x as f32 * 0.1, 100.0, 0.0))
                        }
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn rle_and_flat_files_decode_to_the_same_values() {
        let (w, h) = (37, 4);
        let px = pattern(w, h);
        let head = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y {h} +X {w}\n");
        let rle: Vec<u8> = px.iter().flat_map(|l| rle_line(l)).collect();
        let flat: Vec<u8> = px
            .iter()
            .flat_map(|l| l.iter().flatten().copied())
            .collect();
        let a = decode_hdr(&file(&head, &rle)).unwrap();
        let b = decode_hdr(&file(&head, &flat)).unwrap();
        assert_eq!(a, b);
        assert_eq!((a.width, a.height), (w as u32, h as u32));
        // Row 2, column 0: (3, 0.25, 3) within the 8-bit mantissa's resolution (1/256 of 4).
        let v = a.get(0, 2);
        assert!(
            (v - Vec3::new(3.0, 0.25, 3.0)).abs().max_element() < 4.0 / 256.0,
            "{v}"
        );
        let v = a.get(4, 0);
        assert!(
            (v - Vec3::new(0.4, 100.0, 0.0)).abs().max_element() < 128.0 / 256.0,
            "{v}"
        );
        assert_eq!(rgbe_to_rgb([9, 9, 9, 0]), Vec3::ZERO);
    }

    #[test]
    fn old_style_runs_and_flipped_orientations() {
        let p = to_rgbe(Vec3::new(2.0, 1.0, 0.5));
        let q = to_rgbe(Vec3::new(0.5, 1.0, 2.0));
        // Width 4 (< 8: never new-style): p, then a run of 2, then q.
        let body = [p, [1, 1, 1, 2], q, q, p, p, p].concat();
        let img = decode_hdr(&file("#?RGBE\n\n+Y 2 -X 4\n", &body)).unwrap();
        // Stored bottom row first, right to left: the top row is the second stored one, reversed.
        assert_eq!(img.get(0, 0), rgbe_to_rgb(p));
        assert_eq!(img.get(3, 0), rgbe_to_rgb(q));
        assert_eq!(img.get(3, 1), rgbe_to_rgb(p));
        assert_eq!(img.get(0, 1), rgbe_to_rgb(q));
    }

    #[test]
    fn bad_files_give_clear_errors() {
        let px = pattern(16, 2);
        let rle: Vec<u8> = px.iter().flat_map(|l| rle_line(l)).collect();
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (b"P6\n".to_vec(), "#?"),
            (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n".to_vec(), "header"),
            (
                file("#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 2 +X 16\n", &rle),
                "xyze",
            ),
            (file("#?RADIANCE\n\n-Y 2 +Y 16\n", &rle), "resolution"),
            (file("#?RADIANCE\n\n+X 16 -Y 2\n", &rle), "column-major"),
            (file("#?RADIANCE\n\n-Y 0 +X 16\n", &rle), "size"),
            (file("#?RADIANCE\n\n-Y 99999 +X 16\n", &rle), "size"),
            (
                file("#?RADIANCE\n\n-Y 2 +X 16\n", &rle[..rle.len() - 3]),
                "truncated",
            ),
            (file("#?RADIANCE\n\n-Y 2 +X 17\n", &rle), "width"),
            (
                file("#?RADIANCE\n\n-Y 1 +X 8\n", &[2, 2, 0, 8, 200, 1]),
                "overruns",
            ),
            (
                file("#?RADIANCE\n\n-Y 1 +X 4\n", &[1, 1, 1, 4]),
                "start of a scanline",
            ),
        ];
        for (bytes, needle) in cases {
            let e = decode_hdr(&bytes).unwrap_err();
            assert!(e.contains(needle), "{needle:?} not in {e:?}");
        }
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.hdr");
        std::fs::write(&p, b"garbage").unwrap();
        let e = read_hdr(&p).unwrap_err().to_string();
        assert!(e.contains("x.hdr") && e.contains("#?"), "{e}");
        let e = read_hdr(&dir.path().join("missing.hdr"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.hdr"), "{e}");
    }
}
