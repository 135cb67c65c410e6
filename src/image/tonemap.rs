//! Tonemapping: exposure, a tone operator, the sRGB OETF and 8-bit quantization.

use glam::Vec3;
use rayon::prelude::*;

use super::Image;

/// The tone curve applied per channel after exposure, mapping linear `[0, ∞)` to display-linear
/// `[0, 1]`. Negative values and NaN map to 0, +∞ to 1.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum ToneOperator {
    /// `clamp(x, 0, 1)`: exact for values in `[0, 1]`, clips highlights. The default, so that
    /// PNGs of renders show the stored radiance unaltered wherever it is displayable.
    #[default]
    Clamp,
    /// Per-channel Reinhard `x / (1 + x)`.
    Reinhard,
    /// Narkowicz's ACES filmic fit `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`, clamped to
    /// `[0, 1]`, applied per channel to the exposed value (no extra 0.6 pre-scale).
    Aces,
}

impl ToneOperator {
    /// All operators, in declaration order.
    pub const ALL: [ToneOperator; 3] = [
        ToneOperator::Clamp,
        ToneOperator::Reinhard,
        ToneOperator::Aces,
    ];

    /// The lower-case name used in logs, CLIs and JSON: `clamp`, `reinhard`, `aces`.
    pub fn name(self) -> &'static str {
        match self {
            ToneOperator::Clamp => "clamp",
            ToneOperator::Reinhard => "reinhard",
            ToneOperator::Aces => "aces",
        }
    }

    /// Applies the curve to one exposed linear value; the result is in `[0, 1]`.
    #[inline]
    pub fn apply(self, x: f32) -> f32 {
        if x.is_nan() || x <= 0.0 {
            return 0.0;
        }
        if x == f32::INFINITY {
            return 1.0;
        }
        let y = match self {
            ToneOperator::Clamp => x,
            ToneOperator::Reinhard => x / (1.0 + x),
            ToneOperator::Aces => {
                // Written to avoid overflow for huge x: divide numerator and denominator by x.
                (2.51 * x + 0.03) / (2.43 * x + 0.59 + 0.14 / x)
            }
        };
        y.clamp(0.0, 1.0)
    }
}

impl std::fmt::Display for ToneOperator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ToneOperator {
    type Err = String;
    /// Parses `clamp`, `reinhard` or `aces` (case-insensitive).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ToneOperator::ALL
            .into_iter()
            .find(|op| op.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| {
                format!("unknown tone operator {s:?} (expected clamp, reinhard or aces)")
            })
    }
}

/// How linear radiance becomes display values: `v ↦ OETF(operator(2^exposure · v))` per channel,
/// where OETF is the sRGB transfer function ([`srgb_oetf`]). The default is exposure 0 EV with
/// the [`ToneOperator::Clamp`] operator.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Tonemap {
    /// Exposure in stops (EV): linear values are multiplied by `2^exposure` first.
    pub exposure: f32,
    pub operator: ToneOperator,
}

impl Tonemap {
    pub fn new(exposure: f32, operator: ToneOperator) -> Tonemap {
        Tonemap { exposure, operator }
    }

    /// One line for the render log, e.g. `exposure +0.0 EV, operator clamp, sRGB OETF`.
    pub fn describe(&self) -> String {
        // `+ 0.0` turns -0.0 into +0.0.
        let e = self.exposure + 0.0;
        let ev = if (e * 10.0).fract() == 0.0 {
            format!("{e:+.1}")
        } else {
            format!("{e:+}")
        };
        format!("exposure {ev} EV, operator {}, sRGB OETF", self.operator)
    }

    /// Exposure and tone curve: linear RGB to display-linear RGB in `[0, 1]` (before the OETF).
    #[inline]
    pub fn tone(&self, v: Vec3) -> Vec3 {
        let k = self.exposure.exp2();
        let op = self.operator;
        Vec3::new(op.apply(v.x * k), op.apply(v.y * k), op.apply(v.z * k))
    }

    /// The full display transform to sRGB-encoded values in `[0, 1]` (not quantized).
    #[inline]
    pub fn display(&self, v: Vec3) -> Vec3 {
        let t = self.tone(v);
        Vec3::new(srgb_oetf(t.x), srgb_oetf(t.y), srgb_oetf(t.z))
    }

    /// The full display transform quantized to 8 bits (round to nearest).
    #[inline]
    pub fn to_srgb8_pixel(&self, v: Vec3) -> [u8; 3] {
        let d = self.display(v);
        [quantize8(d.x), quantize8(d.y), quantize8(d.z)]
    }
}

/// The sRGB opto-electronic transfer function (IEC 61966-2-1) for `x` in `[0, 1]`:
/// `12.92 x` for `x ≤ 0.0031308`, else `1.055 x^(1/2.4) − 0.055`. Input is clamped to `[0, 1]`.
#[inline]
pub fn srgb_oetf(x: f32) -> f32 {
    // Evaluated in f64 so that the end points are exact (oetf(1) = 1).
    let x = if x.is_nan() {
        0.0
    } else {
        x.clamp(0.0, 1.0) as f64
    };
    let v = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    v as f32
}

/// The inverse of [`srgb_oetf`]: `v / 12.92` for `v ≤ 0.04045`, else `((v + 0.055) / 1.055)^2.4`.
#[inline]
pub fn srgb_eotf(v: f32) -> f32 {
    let v = if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, 1.0) as f64
    };
    let x = if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    };
    x as f32
}

#[inline]
fn quantize8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Tonemaps `img` to 8-bit sRGB, row-major from the top-left like the image.
pub fn to_srgb8(img: &Image, tm: &Tonemap) -> Vec<[u8; 3]> {
    img.data
        .par_iter()
        .with_min_len(4096)
        .map(|&v| tm.to_srgb8_pixel(v))
        .collect()
}
