//! False-colour per-pixel error maps with a legend strip (colour bar + numeric tick labels).

use crate::image::Image;

use super::colormap::magma;
use super::font::{Canvas, GLYPH_H, text_width};
use super::{CompareError, validate};

/// ε in the relative error |x − y| / (|y| + ε) of error maps.
pub const ERROR_MAP_EPSILON: f64 = 0.01;

/// Minimum output width of an error map, so the legend always fits; narrower images are
/// centred on a white background.
pub const ERROR_MAP_MIN_WIDTH: u32 = 200;

const WHITE: [u8; 3] = [255, 255, 255];
const BLACK: [u8; 3] = [0, 0, 0];

/// Which per-pixel error an error map shows.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum ErrorMapMode {
    /// Mean over channels of |x − y| / (|y| + 0.01); legend labels in percent.
    #[default]
    Relative,
    /// Mean over channels of |x − y| (linear radiance units).
    Absolute,
}

impl ErrorMapMode {
    /// `relative` or `absolute`.
    pub fn name(self) -> &'static str {
        match self {
            ErrorMapMode::Relative => "relative",
            ErrorMapMode::Absolute => "absolute",
        }
    }
}

impl std::fmt::Display for ErrorMapMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ErrorMapMode {
    type Err = String;
    /// Parses `relative` / `rel` or `absolute` / `abs` (case-insensitive).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "relative" | "rel" => Ok(ErrorMapMode::Relative),
            "absolute" | "abs" => Ok(ErrorMapMode::Absolute),
            _ => Err(format!(
                "unknown error-map mode {s:?} (expected relative or absolute)"
            )),
        }
    }
}

/// Options of [`error_map`]. The default is relative error, automatic scale from the 99th
/// percentile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMapOptions {
    pub mode: ErrorMapMode,
    /// The error shown by the top colour of the map (larger errors saturate). `None`: automatic,
    /// the `percentile` of the per-pixel errors rounded up to a "nice" number.
    pub scale_max: Option<f64>,
    /// Percentile (in `(0, 1]`) for the automatic scale; 0.99 by default.
    pub percentile: f64,
}

impl Default for ErrorMapOptions {
    fn default() -> Self {
        ErrorMapOptions {
            mode: ErrorMapMode::Relative,
            scale_max: None,
            percentile: 0.99,
        }
    }
}

/// A rendered error map: the false-colour image of the per-pixel error (top, centred), with the
/// legend strip below it.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorMap {
    /// Size of the whole picture (map + legend).
    pub width: u32,
    pub height: u32,
    /// Row-major 8-bit sRGB pixels, `width × height`.
    pub pixels: Vec<[u8; 3]>,
    /// Horizontal offset of the map inside the picture (non-zero when the image is narrower than
    /// [`ERROR_MAP_MIN_WIDTH`]); the map occupies rows `0..map_height`.
    pub map_x: u32,
    pub map_width: u32,
    pub map_height: u32,
    /// The error value shown by the top colour of the scale.
    pub scale_max: f64,
    pub mode: ErrorMapMode,
    /// The legend's tick values and their labels, left to right.
    pub ticks: Vec<(f64, String)>,
}

/// The per-pixel error (row-major, one value per pixel): for [`ErrorMapMode::Relative`] the mean
/// over the three channels of |x − y| / (|y| + [`ERROR_MAP_EPSILON`]), for
/// [`ErrorMapMode::Absolute`] the mean over channels of |x − y|.
pub fn per_pixel_error(
    test: &Image,
    reference: &Image,
    mode: ErrorMapMode,
) -> Result<Vec<f64>, CompareError> {
    validate(test, reference)?;
    Ok(test
        .data
        .iter()
        .zip(&reference.data)
        .map(|(a, b)| {
            let mut s = 0.0;
            for c in 0..3 {
                let (x, y) = (a[c] as f64, b[c] as f64);
                s += match mode {
                    ErrorMapMode::Relative => (x - y).abs() / (y.abs() + ERROR_MAP_EPSILON),
                    ErrorMapMode::Absolute => (x - y).abs(),
                };
            }
            s / 3.0
        })
        .collect())
}

/// The false-colour error map of `test` against `reference` with its legend, as
/// `(width, height, row-major sRGB8 pixels)`. See [`render_error_map`].
pub fn error_map(
    test: &Image,
    reference: &Image,
    opts: &ErrorMapOptions,
) -> Result<(u32, u32, Vec<[u8; 3]>), CompareError> {
    let m = render_error_map(test, reference, opts)?;
    Ok((m.width, m.height, m.pixels))
}

/// Renders the error map: each pixel's error `e` ([`per_pixel_error`]) is shown as the magma
/// colour of `e / scale_max` (clamped to `[0, 1]`); below the map a legend strip holds a caption
/// (`REL ERR` / `ABS ERR`), the colour bar from 0 to `scale_max`, and 3 or 5 tick labels
/// (percent for relative error).
///
/// The output is `max(W, 200)` wide and `H + legend` high (legend 42 px, or 82 px when the image
/// is at least 480 px wide and the legend is drawn at double size).
pub fn render_error_map(
    test: &Image,
    reference: &Image,
    opts: &ErrorMapOptions,
) -> Result<ErrorMap, CompareError> {
    if opts.percentile.is_nan() || opts.percentile <= 0.0 || opts.percentile > 1.0 {
        return Err(CompareError::InvalidOption(format!(
            "percentile {} is not in (0, 1]",
            opts.percentile
        )));
    }
    if let Some(m) = opts.scale_max
        && (!m.is_finite() || m <= 0.0)
    {
        return Err(CompareError::InvalidOption(format!(
            "scale maximum {m} is not a positive finite number"
        )));
    }
    let err = per_pixel_error(test, reference, opts.mode)?;
    let scale_max = match opts.scale_max {
        Some(m) => m,
        None => auto_scale(&err, opts.percentile),
    };

    let (w, h) = (test.width as usize, test.height as usize);
    let s = if w >= 480 { 2 } else { 1 };
    let out_w = w.max(ERROR_MAP_MIN_WIDTH as usize);
    let map_x = (out_w - w) / 2;

    // Legend layout (top to bottom), in pixels at scale s.
    let y_caption = h + 4 * s;
    let y_bar = y_caption + GLYPH_H * s + 3 * s + 1; // + 1: bar border
    let bar_h = 10 * s;
    let y_tick = y_bar + bar_h + 1;
    let y_label = y_tick + 3 * s + 2 * s;
    let out_h = y_label + GLYPH_H * s + 4 * s;

    let mut canvas = Canvas::new(out_w, out_h, WHITE);
    for y in 0..h {
        for x in 0..w {
            let e = err[y * w + x];
            canvas.put(map_x + x, y, magma(e / scale_max));
        }
    }

    let caption = match opts.mode {
        ErrorMapMode::Relative => "REL ERR",
        ErrorMapMode::Absolute => "ABS ERR",
    };
    canvas.draw_text(4 * s, y_caption, caption, s, BLACK);

    // Tick labels: try 5 ticks, fall back to 3 if the labels would touch.
    let make_ticks = |n: usize| -> Vec<(f64, String)> {
        (0..n)
            .map(|i| {
                let v = scale_max * i as f64 / (n - 1) as f64;
                (v, format_tick(v, opts.mode))
            })
            .collect()
    };
    let layout = |ticks: &[(f64, String)]| {
        let max_lw = ticks
            .iter()
            .map(|(_, l)| text_width(l, s))
            .max()
            .unwrap_or(0);
        let margin = max_lw / 2 + 4 * s;
        let bar_w = out_w - 2 * margin;
        (margin, bar_w, max_lw)
    };
    let mut ticks = make_ticks(5);
    let (mut x0, mut bar_w, max_lw) = layout(&ticks);
    if (bar_w - 1) / 4 < max_lw + 3 * s {
        ticks = make_ticks(3);
        (x0, bar_w, _) = layout(&ticks);
    }

    // Colour bar with a 1-pixel black border.
    canvas.fill_rect(x0 - 1, y_bar - 1, bar_w + 2, bar_h + 2, BLACK);
    for x in 0..bar_w {
        let c = magma(x as f64 / (bar_w - 1) as f64);
        canvas.fill_rect(x0 + x, y_bar, 1, bar_h, c);
    }
    let n = ticks.len();
    for (i, (_, label)) in ticks.iter().enumerate() {
        let tx = x0 + (i * (bar_w - 1) + (n - 1) / 2) / (n - 1);
        canvas.fill_rect(tx - (s - 1) / 2, y_tick, s, 3 * s, BLACK);
        let lw = text_width(label, s);
        let lx = tx.saturating_sub(lw / 2).min(out_w - lw);
        canvas.draw_text(lx, y_label, label, s, BLACK);
    }

    Ok(ErrorMap {
        width: out_w as u32,
        height: out_h as u32,
        pixels: canvas.pixels,
        map_x: map_x as u32,
        map_width: test.width,
        map_height: test.height,
        scale_max,
        mode: opts.mode,
        ticks,
    })
}

/// The automatic scale: the `p`-quantile (nearest rank) of `err`, rounded up to a nice number
/// ([`nice_ceil`]). If that is 0, the maximum error is used; if all errors are 0, 1.
fn auto_scale(err: &[f64], p: f64) -> f64 {
    let mut v = err.to_vec();
    let n = v.len();
    let rank = ((p * n as f64).ceil() as usize).clamp(1, n) - 1;
    let (_, q, _) = v.select_nth_unstable_by(rank, f64::total_cmp);
    let mut m = *q;
    if m <= 0.0 {
        m = err.iter().copied().fold(0.0, f64::max);
    }
    if m <= 0.0 { 1.0 } else { nice_ceil(m) }
}

/// The smallest number of the form `m · 10^k`, m ∈ {1, 1.5, 2, 2.5, 3, 4, 5, 6, 8}, that is
/// ≥ `v` (> 0).
pub(crate) fn nice_ceil(v: f64) -> f64 {
    let k = v.log10().floor() as i32;
    let base = 10f64.powi(k);
    for m in [1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 15.0] {
        let c = m * base;
        if c >= v * (1.0 - 1e-12) {
            return c;
        }
    }
    v
}

/// A tick label: relative errors in percent (`12.5%`), absolute errors as numbers; at most three
/// significant digits, scientific notation (`1.5e-4`) outside `[0.01, 10000)`.
pub(crate) fn format_tick(v: f64, mode: ErrorMapMode) -> String {
    match mode {
        ErrorMapMode::Relative => format!("{}%", format_number(v * 100.0)),
        ErrorMapMode::Absolute => format_number(v),
    }
}

/// At most three significant digits, trailing zeros trimmed: `0`, `0.05`, `12.5`, `1.5e-4`.
pub(crate) fn format_number(x: f64) -> String {
    fn trim(s: &str) -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let a = x.abs();
    if (1e-2..1e4).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        trim(&format!("{x:.decimals$}"))
    } else {
        let s = format!("{x:.2e}");
        let (mant, exp) = s.split_once('e').unwrap_or((&s, "0"));
        format!("{}e{exp}", trim(mant))
    }
}
