//! A small line-plot renderer into an RGB8 buffer: axes, tick labels, axis labels, a title and
//! a legend, linear or logarithmic axes, solid or dashed lines, point markers. Text uses the 5×7 bitmap font of
//! the error-map legend ([`super::font`]), extended here with the remaining ASCII letters, a few
//! symbols and the Greek letters θ, α, λ, μ. Write the result with
//! [`crate::image::write_png_rgb8`].

use super::font::{Canvas, GLYPH_H, GLYPH_W, glyph};

/// One curve.
#[derive(Clone, Debug)]
pub struct Series {
    pub label: String,
    pub color: [u8; 3],
    pub dashed: bool,
    /// Draw a marker (a filled square) at every point, e.g. for measurements joined by a line
    /// or a single point.
    pub markers: bool,
    /// (x, y) points, drawn as a polyline in order. Non-finite points (and y ≤ 0 on a log
    /// axis) break the line.
    pub points: Vec<(f64, f64)>,
}

/// A plot: title, axis labels, ranges and curves.
#[derive(Clone, Debug, Default)]
pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Logarithmic y axis (base 10).
    pub log_y: bool,
    /// Logarithmic x axis (base 10); `x_ticks` are then ignored and powers of ten used.
    pub log_x: bool,
    /// x range; `None`: the data range.
    pub x_range: Option<(f64, f64)>,
    /// y range; `None`: the data range (on a log axis at most 6 decades below the maximum).
    pub y_range: Option<(f64, f64)>,
    /// Explicit x tick positions; empty: automatic.
    pub x_ticks: Vec<f64>,
    pub series: Vec<Series>,
}

/// An RGB8 raster, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[u8; 3]>,
}

/// Background colour of plots.
pub const BACKGROUND: [u8; 3] = [255, 255, 255];
/// Colour of axes, ticks and text.
pub const INK: [u8; 3] = [20, 20, 20];
const GRID: [u8; 3] = [228, 228, 228];

/// A colour-blind-friendly palette (Okabe & Ito 2008) for series.
pub const PALETTE: [[u8; 3]; 7] = [
    [0, 114, 178],
    [213, 94, 0],
    [0, 158, 115],
    [204, 121, 167],
    [230, 159, 0],
    [86, 180, 233],
    [0, 0, 0],
];

/// Text scale (font pixels → output pixels).
const TEXT_SCALE: usize = 2;

/// Rows of `c`: the error-map font first, then the extra glyphs below; `None` if neither has it.
fn glyph_ext(c: char) -> Option<[u8; GLYPH_H]> {
    glyph(c).or_else(|| extra_glyph(c))
}

#[rustfmt::skip]
fn extra_glyph(c: char) -> Option<[u8; GLYPH_H]> {
    Some(match c {
        'C' => [0b01110, 0b10001, 0b10000, 0b10000, 0b10000, 0b10001, 0b01110],
        'D' => [0b11100, 0b10010, 0b10001, 0b10001, 0b10001, 0b10010, 0b11100],
        'F' => [0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000],
        'G' => [0b01110, 0b10001, 0b10000, 0b10111, 0b10001, 0b10001, 0b01111],
        'H' => [0b10001, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b10001],
        'I' => [0b01110, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110],
        'J' => [0b00111, 0b00010, 0b00010, 0b00010, 0b00010, 0b10010, 0b01100],
        'K' => [0b10001, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b10001],
        'M' => [0b10001, 0b11011, 0b10101, 0b10101, 0b10001, 0b10001, 0b10001],
        'N' => [0b10001, 0b10001, 0b11001, 0b10101, 0b10011, 0b10001, 0b10001],
        'O' => [0b01110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110],
        'P' => [0b11110, 0b10001, 0b10001, 0b11110, 0b10000, 0b10000, 0b10000],
        'Q' => [0b01110, 0b10001, 0b10001, 0b10001, 0b10101, 0b10010, 0b01101],
        'T' => [0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100],
        'U' => [0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01110],
        'V' => [0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100],
        'W' => [0b10001, 0b10001, 0b10001, 0b10101, 0b10101, 0b10101, 0b01010],
        'X' => [0b10001, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001, 0b10001],
        'Y' => [0b10001, 0b10001, 0b10001, 0b01010, 0b00100, 0b00100, 0b00100],
        'Z' => [0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b11111],
        'a' => [0b00000, 0b00000, 0b01110, 0b00001, 0b01111, 0b10001, 0b01111],
        'b' => [0b10000, 0b10000, 0b10110, 0b11001, 0b10001, 0b10001, 0b11110],
        'c' => [0b00000, 0b00000, 0b01110, 0b10000, 0b10000, 0b10001, 0b01110],
        'd' => [0b00001, 0b00001, 0b01101, 0b10011, 0b10001, 0b10001, 0b01111],
        'f' => [0b00110, 0b01001, 0b01000, 0b11100, 0b01000, 0b01000, 0b01000],
        'g' => [0b00000, 0b01111, 0b10001, 0b10001, 0b01111, 0b00001, 0b01110],
        'h' => [0b10000, 0b10000, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001],
        'i' => [0b00100, 0b00000, 0b01100, 0b00100, 0b00100, 0b00100, 0b01110],
        'j' => [0b00010, 0b00000, 0b00110, 0b00010, 0b00010, 0b10010, 0b01100],
        'k' => [0b10000, 0b10000, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010],
        'l' => [0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110],
        'm' => [0b00000, 0b00000, 0b11010, 0b10101, 0b10101, 0b10001, 0b10001],
        'n' => [0b00000, 0b00000, 0b10110, 0b11001, 0b10001, 0b10001, 0b10001],
        'o' => [0b00000, 0b00000, 0b01110, 0b10001, 0b10001, 0b10001, 0b01110],
        'p' => [0b00000, 0b00000, 0b11110, 0b10001, 0b11110, 0b10000, 0b10000],
        'q' => [0b00000, 0b00000, 0b01101, 0b10011, 0b01111, 0b00001, 0b00001],
        'r' => [0b00000, 0b00000, 0b10110, 0b11001, 0b10000, 0b10000, 0b10000],
        's' => [0b00000, 0b00000, 0b01110, 0b10000, 0b01110, 0b00001, 0b11110],
        't' => [0b01000, 0b01000, 0b11100, 0b01000, 0b01000, 0b01001, 0b00110],
        'u' => [0b00000, 0b00000, 0b10001, 0b10001, 0b10001, 0b10011, 0b01101],
        'v' => [0b00000, 0b00000, 0b10001, 0b10001, 0b10001, 0b01010, 0b00100],
        'w' => [0b00000, 0b00000, 0b10001, 0b10001, 0b10101, 0b10101, 0b01010],
        'x' => [0b00000, 0b00000, 0b10001, 0b01010, 0b00100, 0b01010, 0b10001],
        'y' => [0b00000, 0b00000, 0b10001, 0b10001, 0b01111, 0b00001, 0b01110],
        'z' => [0b00000, 0b00000, 0b11111, 0b00010, 0b00100, 0b01000, 0b11111],
        '(' => [0b00010, 0b00100, 0b01000, 0b01000, 0b01000, 0b00100, 0b00010],
        ')' => [0b01000, 0b00100, 0b00010, 0b00010, 0b00010, 0b00100, 0b01000],
        '[' => [0b01110, 0b01000, 0b01000, 0b01000, 0b01000, 0b01000, 0b01110],
        ']' => [0b01110, 0b00010, 0b00010, 0b00010, 0b00010, 0b00010, 0b01110],
        '=' => [0b00000, 0b00000, 0b11111, 0b00000, 0b11111, 0b00000, 0b00000],
        ',' => [0b00000, 0b00000, 0b00000, 0b00000, 0b01100, 0b00100, 0b01000],
        ':' => [0b00000, 0b01100, 0b01100, 0b00000, 0b01100, 0b01100, 0b00000],
        '/' => [0b00000, 0b00001, 0b00010, 0b00100, 0b01000, 0b10000, 0b00000],
        '_' => [0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b00000, 0b11111],
        '*' => [0b00000, 0b00100, 0b10101, 0b01110, 0b10101, 0b00100, 0b00000],
        '<' => [0b00010, 0b00100, 0b01000, 0b10000, 0b01000, 0b00100, 0b00010],
        '>' => [0b01000, 0b00100, 0b00010, 0b00001, 0b00010, 0b00100, 0b01000],
        '\'' => [0b01100, 0b00100, 0b01000, 0b00000, 0b00000, 0b00000, 0b00000],
        '|' => [0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100],
        '°' => [0b01100, 0b10010, 0b10010, 0b01100, 0b00000, 0b00000, 0b00000],
        '·' => [0b00000, 0b00000, 0b00000, 0b01100, 0b01100, 0b00000, 0b00000],
        'θ' => [0b01110, 0b10001, 0b10001, 0b11111, 0b10001, 0b10001, 0b01110],
        'α' => [0b00000, 0b00000, 0b01001, 0b10101, 0b10010, 0b10010, 0b01101],
        'λ' => [0b01000, 0b00100, 0b00100, 0b01010, 0b01010, 0b10001, 0b10001],
        'μ' => [0b00000, 0b00000, 0b10001, 0b10001, 0b10011, 0b11101, 0b10000],
        _ => return None,
    })
}

/// Whether the plot font can draw `c` (other characters are drawn as filled boxes).
pub fn has_glyph(c: char) -> bool {
    glyph_ext(c).is_some()
}

/// Width in pixels of `text` at `scale`.
fn text_width(text: &str, scale: usize) -> usize {
    let n = text.chars().count();
    if n == 0 {
        0
    } else {
        (n * (GLYPH_W + 1) - 1) * scale
    }
}

/// Draws `text` with its top-left corner at `(x0, y0)`; missing glyphs become filled boxes.
fn draw_text(cv: &mut Canvas, x0: i64, y0: i64, text: &str, scale: usize, color: [u8; 3]) {
    for (ci, c) in text.chars().enumerate() {
        let rows = glyph_ext(c).unwrap_or([0b11111; GLYPH_H]);
        let gx = x0 + (ci * (GLYPH_W + 1) * scale) as i64;
        for (ry, bits) in rows.iter().enumerate() {
            for rx in 0..GLYPH_W {
                if bits & (1 << (GLYPH_W - 1 - rx)) != 0 {
                    for dy in 0..scale {
                        for dx in 0..scale {
                            put(
                                cv,
                                gx + (rx * scale + dx) as i64,
                                y0 + (ry * scale + dy) as i64,
                                color,
                            );
                        }
                    }
                }
            }
        }
    }
}

/// Draws `text` rotated 90° counter-clockwise (reading bottom to top), its bounding box's
/// top-left corner at `(x0, y0)`.
fn draw_text_vertical(cv: &mut Canvas, x0: i64, y0: i64, text: &str, scale: usize, c: [u8; 3]) {
    let len = text_width(text, scale) as i64;
    for (ci, ch) in text.chars().enumerate() {
        let rows = glyph_ext(ch).unwrap_or([0b11111; GLYPH_H]);
        let gx = (ci * (GLYPH_W + 1) * scale) as i64;
        for (ry, bits) in rows.iter().enumerate() {
            for rx in 0..GLYPH_W {
                if bits & (1 << (GLYPH_W - 1 - rx)) != 0 {
                    for dy in 0..scale {
                        for dx in 0..scale {
                            // Unrotated pixel (u, v) → (v, len − 1 − u).
                            let u = gx + (rx * scale + dx) as i64;
                            let v = (ry * scale + dy) as i64;
                            put(cv, x0 + v, y0 + len - 1 - u, c);
                        }
                    }
                }
            }
        }
    }
}

#[inline]
fn put(cv: &mut Canvas, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 {
        cv.put(x as usize, y as usize, c);
    }
}

/// Pixel-space rectangle of the plotting area.
#[derive(Clone, Copy)]
struct Area {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

/// A thick line from `a` to `b` (pixel coordinates), clipped to `area`; `dash` carries the
/// running arc length of a dashed polyline (dash 9 px, gap 6 px), `None` for solid.
fn line(
    cv: &mut Canvas,
    area: Area,
    a: (f64, f64),
    b: (f64, f64),
    color: [u8; 3],
    dash: Option<&mut f64>,
) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len = (dx * dx + dy * dy).sqrt();
    let steps = (len * 3.0).ceil().max(1.0) as usize;
    let mut run = dash;
    for i in 0..=steps {
        let t = i as f64 / steps as f64;
        let (x, y) = (a.0 + t * dx, a.1 + t * dy);
        if let Some(r) = run.as_deref_mut() {
            let s = *r + t * len;
            if s.rem_euclid(15.0) >= 9.0 {
                continue;
            }
        }
        if x < area.x0 - 0.5 || x > area.x1 + 0.5 || y < area.y0 - 0.5 || y > area.y1 + 0.5 {
            continue;
        }
        // 2×2-pixel pen.
        let (px, py) = (x.floor() as i64, y.floor() as i64);
        for (ox, oy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            put(cv, px + ox, py + oy, color);
        }
    }
    if let Some(r) = run {
        *r += len;
    }
}

/// "Nice" linear ticks covering [lo, hi] (steps 1, 2, 5 × 10^k, about 6 ticks).
fn linear_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(hi > lo) {
        return vec![lo];
    }
    let raw = (hi - lo) / 6.0;
    let p = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p);
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// Tick label: integers plainly, otherwise up to 3 significant digits; powers of ten on a log
/// axis as `1e-3`.
fn tick_label(v: f64, log: bool) -> String {
    if log {
        let e = v.log10().round() as i32;
        return match e {
            0 => "1".to_string(),
            1 => "10".to_string(),
            2 => "100".to_string(),
            _ => format!("1e{e}"),
        };
    }
    if v == v.round() && v.abs() < 1e6 {
        format!("{}", v as i64)
    } else {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

/// Renders `plot` into a `width × height` raster.
pub fn render(plot: &Plot, width: u32, height: u32) -> Raster {
    let (w, h) = (width as usize, height as usize);
    let mut cv = Canvas::new(w, h, BACKGROUND);
    let s = TEXT_SCALE;
    let ch = GLYPH_H * s;
    let tr = |v: f64| if plot.log_y { v.log10() } else { v };
    let trx = |v: f64| if plot.log_x { v.log10() } else { v };

    // Data ranges.
    let pts = || {
        plot.series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| {
                p.0.is_finite()
                    && p.1.is_finite()
                    && (!plot.log_y || p.1 > 0.0)
                    && (!plot.log_x || p.0 > 0.0)
            })
    };
    let (mut xlo, mut xhi) = plot.x_range.unwrap_or_else(|| {
        pts().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.min(p.0), a.1.max(p.0))
        })
    });
    if plot.log_x && xlo > 0.0 && xhi.is_finite() {
        xlo = 10f64.powf(xlo.log10().floor());
        xhi = 10f64.powf(xhi.log10().ceil());
        if xhi <= xlo {
            xhi = xlo * 10.0;
        }
    }
    let (mut ylo, mut yhi) = plot.y_range.unwrap_or_else(|| {
        let (lo, hi) = pts().fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
            (a.0.min(p.1), a.1.max(p.1))
        });
        if plot.log_y {
            let hi = 10f64.powf(hi.log10().ceil());
            (lo.max(hi * 1e-6), hi)
        } else {
            (lo.min(0.0), hi)
        }
    });
    if plot.log_y {
        ylo = 10f64.powf(ylo.log10().floor());
    }
    let (xlo, xhi) = if xlo.is_finite() && xhi > xlo && (!plot.log_x || xlo > 0.0) {
        (xlo, xhi)
    } else if plot.log_x {
        (0.1, 1.0)
    } else {
        (0.0, 1.0)
    };
    let (txlo, txhi) = (trx(xlo), trx(xhi));
    if !(ylo.is_finite() && yhi.is_finite() && yhi > ylo) {
        (ylo, yhi) = if plot.log_y { (0.1, 1.0) } else { (0.0, 1.0) };
    }
    let (tlo, thi) = (tr(ylo), tr(yhi));

    // Layout: title on top, x label at the bottom, y label and tick labels at the left.
    let y_ticks: Vec<f64> = if plot.log_y {
        let (a, b) = (tlo.ceil() as i32, thi.floor() as i32);
        let stride = ((b - a) / 7 + 1).max(1);
        (a..=b)
            .filter(|e| (e - a) % stride == 0)
            .map(|e| 10f64.powi(e))
            .collect()
    } else {
        linear_ticks(ylo, yhi)
    };
    let y_tick_w = y_ticks
        .iter()
        .map(|&v| text_width(&tick_label(v, plot.log_y), s))
        .max()
        .unwrap_or(0);
    let area = Area {
        x0: (ch + 12 + y_tick_w + 10) as f64,
        y0: (ch + 16) as f64,
        x1: (w as f64 - 16.0).max(1.0),
        y1: (h as f64 - (2 * ch + 26) as f64).max(1.0),
    };
    let px = |x: f64| area.x0 + (trx(x) - txlo) / (txhi - txlo) * (area.x1 - area.x0);
    let py = |y: f64| area.y1 - (tr(y) - tlo) / (thi - tlo) * (area.y1 - area.y0);

    // Grid, ticks and tick labels.
    let x_ticks = if plot.log_x {
        let (a, b) = (txlo.ceil() as i32, txhi.floor() as i32);
        let stride = ((b - a) / 7 + 1).max(1);
        (a..=b)
            .filter(|e| (e - a) % stride == 0)
            .map(|e| 10f64.powi(e))
            .collect()
    } else if plot.x_ticks.is_empty() {
        linear_ticks(xlo, xhi)
    } else {
        plot.x_ticks.clone()
    };
    for &t in &x_ticks {
        if t < xlo || t > xhi {
            continue;
        }
        let x = px(t).round() as i64;
        for y in area.y0 as i64..=area.y1 as i64 {
            put(&mut cv, x, y, GRID);
        }
        for y in 0..6 {
            put(&mut cv, x, area.y1 as i64 + y, INK);
        }
        let l = tick_label(t, plot.log_x);
        draw_text(
            &mut cv,
            x - text_width(&l, s) as i64 / 2,
            area.y1 as i64 + 9,
            &l,
            s,
            INK,
        );
    }
    for &t in &y_ticks {
        let y = py(t).round() as i64;
        if y < area.y0 as i64 - 1 || y > area.y1 as i64 + 1 {
            continue;
        }
        for x in area.x0 as i64..=area.x1 as i64 {
            put(&mut cv, x, y, GRID);
        }
        for x in 0..6 {
            put(&mut cv, area.x0 as i64 - x, y, INK);
        }
        let l = tick_label(t, plot.log_y);
        draw_text(
            &mut cv,
            area.x0 as i64 - 9 - text_width(&l, s) as i64,
            y - ch as i64 / 2,
            &l,
            s,
            INK,
        );
    }
    // Frame.
    for x in area.x0 as i64..=area.x1 as i64 {
        put(&mut cv, x, area.y0 as i64, INK);
        put(&mut cv, x, area.y1 as i64, INK);
    }
    for y in area.y0 as i64..=area.y1 as i64 {
        put(&mut cv, area.x0 as i64, y, INK);
        put(&mut cv, area.x1 as i64, y, INK);
    }

    // Curves (their pixel positions are kept for the legend placement).
    let mut drawn: Vec<(f64, f64)> = Vec::new();
    for sr in &plot.series {
        let mut run = 0.0;
        let mut prev: Option<(f64, f64)> = None;
        for &(x, y) in &sr.points {
            if !(x.is_finite() && y.is_finite())
                || (plot.log_y && !(y > 0.0))
                || (plot.log_x && !(x > 0.0))
            {
                prev = None;
                continue;
            }
            // Clamp to the y range so that steep curves leave the area at its edge.
            let yc = if plot.log_y {
                y.clamp(ylo * 0.5, yhi * 2.0)
            } else {
                y.clamp(ylo - (yhi - ylo), yhi + (yhi - ylo))
            };
            let p = (px(x), py(yc));
            drawn.push(p);
            if let Some(q) = prev {
                let dash = if sr.dashed { Some(&mut run) } else { None };
                line(&mut cv, area, q, p, sr.color, dash);
            }
            if sr.markers {
                let (cx, cy) = (p.0.round() as i64, p.1.round() as i64);
                for dy in -3..=3 {
                    for dx in -3..=3 {
                        let (mx, my) = (cx + dx, cy + dy);
                        if mx as f64 >= area.x0
                            && mx as f64 <= area.x1
                            && my as f64 >= area.y0
                            && my as f64 <= area.y1
                        {
                            put(&mut cv, mx, my, sr.color);
                        }
                    }
                }
            }
            prev = Some(p);
        }
    }

    // Title and axis labels.
    let tw = text_width(&plot.title, s) as i64;
    draw_text(&mut cv, (w as i64 - tw) / 2, 6, &plot.title, s, INK);
    let xw = text_width(&plot.x_label, s) as i64;
    let xc = ((area.x0 + area.x1) / 2.0) as i64;
    draw_text(
        &mut cv,
        xc - xw / 2,
        h as i64 - ch as i64 - 6,
        &plot.x_label,
        s,
        INK,
    );
    let yw = text_width(&plot.y_label, s) as i64;
    let yc = ((area.y0 + area.y1) / 2.0) as i64;
    draw_text_vertical(&mut cv, 6, yc - yw / 2, &plot.y_label, s, INK);

    // Legend: inside the plotting area on a white box, in the corner (top-right, top-left,
    // bottom-right, bottom-left, in this order of preference) that hides the fewest curve
    // points.
    let labelled: Vec<&Series> = plot.series.iter().filter(|s| !s.label.is_empty()).collect();
    if !labelled.is_empty() {
        let row_h = ch + 6;
        let swatch = 30usize;
        let lw = labelled
            .iter()
            .map(|s| text_width(&s.label, TEXT_SCALE))
            .max()
            .unwrap_or(0)
            + swatch
            + 24;
        let lh = labelled.len() * row_h + 10;
        let right = area.x1 as i64 - lw as i64 - 8;
        let left = area.x0 as i64 + 8;
        let top = area.y0 as i64 + 8;
        let bottom = area.y1 as i64 - lh as i64 - 8;
        let hidden = |x: i64, y: i64| {
            drawn
                .iter()
                .filter(|p| {
                    p.0 >= x as f64
                        && p.0 <= (x + lw as i64) as f64
                        && p.1 >= y as f64
                        && p.1 <= (y + lh as i64) as f64
                })
                .count()
        };
        let (lx, ly) = [(right, top), (left, top), (right, bottom), (left, bottom)]
            .into_iter()
            .min_by_key(|&(x, y)| hidden(x, y))
            .unwrap_or((right, top));
        for y in ly..ly + lh as i64 {
            for x in lx..lx + lw as i64 {
                let edge = y == ly || y == ly + lh as i64 - 1 || x == lx || x == lx + lw as i64 - 1;
                put(&mut cv, x, y, if edge { INK } else { BACKGROUND });
            }
        }
        let full = Area {
            x0: 0.0,
            y0: 0.0,
            x1: w as f64,
            y1: h as f64,
        };
        for (i, sr) in labelled.iter().enumerate() {
            let y = ly + 6 + (i * row_h) as i64;
            let ym = (y + ch as i64 / 2) as f64;
            let mut run = 0.0;
            let dash = if sr.dashed { Some(&mut run) } else { None };
            line(
                &mut cv,
                full,
                ((lx + 8) as f64, ym),
                ((lx + 8 + swatch as i64) as f64, ym),
                sr.color,
                dash,
            );
            if sr.markers {
                let cx = lx + 8 + swatch as i64 / 2;
                for dy in -3..=3 {
                    for dx in -3..=3 {
                        put(&mut cv, cx + dx, ym as i64 + dy, sr.color);
                    }
                }
            }
            draw_text(&mut cv, lx + 16 + swatch as i64, y, &sr.label, s, INK);
        }
    }

    Raster {
        width,
        height,
        pixels: cv.pixels,
    }
}

/// Places `panels` (all the same height) side by side.
pub fn hstack(panels: &[Raster]) -> Raster {
    let height = panels.iter().map(|p| p.height).max().unwrap_or(0);
    let width: u32 = panels.iter().map(|p| p.width).sum();
    let mut pixels = vec![BACKGROUND; width as usize * height as usize];
    let mut x0 = 0usize;
    for p in panels {
        for y in 0..p.height as usize {
            let src = &p.pixels[y * p.width as usize..(y + 1) * p.width as usize];
            let dst = y * width as usize + x0;
            pixels[dst..dst + p.width as usize].copy_from_slice(src);
        }
        x0 += p.width as usize;
    }
    Raster {
        width,
        height,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_plot(log_y: bool) -> Plot {
        let xs: Vec<f64> = (0..=100).map(|i| -90.0 + 1.8 * i as f64).collect();
        Plot {
            title: "Phong n=10 (θo=45°)".into(),
            x_label: "θi (deg)".into(),
            y_label: "f cos θi (1/sr)".into(),
            log_y,
            x_ticks: vec![-90.0, -45.0, 0.0, 45.0, 90.0],
            series: vec![
                Series {
                    label: "exact".into(),
                    color: PALETTE[0],
                    dashed: false,
                    markers: false,
                    points: xs
                        .iter()
                        .map(|&x| (x, (-(x / 30.0).powi(2)).exp()))
                        .collect(),
                },
                Series {
                    label: "SG".into(),
                    color: PALETTE[1],
                    dashed: true,
                    markers: false,
                    points: xs
                        .iter()
                        .map(|&x| (x, (-(x / 35.0).powi(2)).exp()))
                        .collect(),
                },
            ],
            ..Plot::default()
        }
    }

    fn count(
        r: &Raster,
        x: std::ops::Range<usize>,
        y: std::ops::Range<usize>,
        c: [u8; 3],
    ) -> usize {
        let mut n = 0;
        for yy in y {
            for xx in x.clone() {
                if r.pixels[yy * r.width as usize + xx] == c {
                    n += 1;
                }
            }
        }
        n
    }

    #[test]
    fn plot_draws_curves_axes_and_labels() {
        for log_y in [false, true] {
            let r = render(&sample_plot(log_y), 480, 360);
            assert_eq!(r.pixels.len(), 480 * 360);
            let (w, h) = (r.width as usize, r.height as usize);
            // Curves in both series colours.
            assert!(count(&r, 0..w, 0..h, PALETTE[0]) > 200, "log_y {log_y}");
            assert!(count(&r, 0..w, 0..h, PALETTE[1]) > 100, "log_y {log_y}");
            // Ink in the title band, the x-label band (bottom), the y-label band (left) and
            // left of the frame (tick labels).
            assert!(count(&r, 0..w, 0..20, INK) > 50, "title");
            assert!(count(&r, 0..w, h - 20..h, INK) > 50, "x label");
            assert!(count(&r, 0..20, 0..h, INK) > 50, "y label");
            assert!(count(&r, 20..60, 30..h - 60, INK) > 50, "y tick labels");
            // Not mostly ink: still a plot on a white background.
            assert!(count(&r, 0..w, 0..h, BACKGROUND) > w * h / 2);
        }
    }

    /// On a log-log plot a point lands where its logarithms say: (10, 0.01) on axes spanning
    /// [1, 100] × [1e-3, 1e-1] sits at the centre of the plotting area, drawn as a 7×7 marker.
    #[test]
    fn log_x_places_markers_by_their_logarithm() {
        let p = Plot {
            log_x: true,
            log_y: true,
            x_range: Some((1.0, 100.0)),
            y_range: Some((1e-3, 1e-1)),
            series: vec![Series {
                label: String::new(),
                color: PALETTE[2],
                dashed: false,
                markers: true,
                points: vec![(10.0, 0.01)],
            }],
            ..Plot::default()
        };
        let r = render(&p, 400, 300);
        let (w, h) = (r.width as usize, r.height as usize);
        assert_eq!(count(&r, 0..w, 0..h, PALETTE[2]), 49);
        let (mut sx, mut sy) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                if r.pixels[y * w + x] == PALETTE[2] {
                    (sx, sy) = (sx + x, sy + y);
                }
            }
        }
        let (cx, cy) = (sx as f64 / 49.0, sy as f64 / 49.0);
        // The frame: the columns and rows that are ink over more than half the image.
        let cols: Vec<usize> = (0..w)
            .filter(|&x| count(&r, x..x + 1, 0..h, INK) > h / 2)
            .collect();
        let rows: Vec<usize> = (0..h)
            .filter(|&y| count(&r, 0..w, y..y + 1, INK) > w / 2)
            .collect();
        let (x0, x1) = (cols[0] as f64, *cols.last().unwrap() as f64);
        let (y0, y1) = (rows[0] as f64, *rows.last().unwrap() as f64);
        // 2 px: the rounding of the frame and of the marker's centre.
        assert!(
            (cx - 0.5 * (x0 + x1)).abs() <= 2.0,
            "x {cx} in [{x0}, {x1}]"
        );
        assert!(
            (cy - 0.5 * (y0 + y1)).abs() <= 2.0,
            "y {cy} in [{y0}, {y1}]"
        );
        assert_eq!(tick_label(100.0, true), "100");
    }

    #[test]
    fn font_covers_plot_labels() {
        for c in "Blinn-Phong Ward Cook-Torrance GGX Beckmann exact SG n=100 α=0.05 θo=45° λ μ (1/sr) f cos θi [deg], K: 1e-3"
            .chars()
        {
            assert!(has_glyph(c), "missing glyph {c:?}");
        }
    }

    #[test]
    fn ticks_are_nice() {
        let t = linear_ticks(0.0, 1.0);
        let want = [0.0, 0.2, 0.4, 0.6, 0.8, 1.0];
        assert_eq!(t.len(), want.len());
        assert!(
            t.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12),
            "{t:?}"
        );
        assert_eq!(tick_label(1e-3, true), "1e-3");
        assert_eq!(tick_label(45.0, false), "45");
        assert_eq!(tick_label(0.25, false), "0.25");
        let s = hstack(&[
            render(&sample_plot(false), 100, 80),
            render(&sample_plot(true), 120, 80),
        ]);
        assert_eq!((s.width, s.height, s.pixels.len()), (220, 80, 220 * 80));
    }
}
