//! Environment lighting: a latitude-longitude radiance map at infinity, with importance sampling.
//!
//! **Orientation** (Mitsuba 3's `envmap` mapping, `src/emitters/envmap.cpp`, so a scene exported
//! to Mitsuba with `to_world = rotate([0, 1, 0], rotation)` sees the same sky): in the map's own
//! frame a unit direction d = (x, y, z) has
//!
//! ```text
//! u = atan2(x, −z) / 2π  (wrapped into [0, 1)),   v = acos(y) / π,
//! ```
//!
//! and conversely d(u, v) = (sin φ sin θ, cos θ, −cos φ sin θ) with φ = 2πu, θ = πv. So row 0
//! (v = 0) is straight up (+y), the last row straight down; the left edge (u = 0) looks along −z,
//! a quarter across (u = ¼) along +x, the middle (u = ½) along +z, three quarters along −x. Texel
//! (x, y) of a W × H map covers u ∈ [x/W, (x+1)/W), v ∈ [y/H, (y+1)/H). The map is then rotated
//! by `rotation` degrees about +y, right-handed (world = R_y(rotation) · map): +90° takes the
//! map's +z to world +x and its +x to world −z.
//!
//! Mitsuba interpolates bilinearly with its rows at θ = πy/(H − 1); here radiance is **nearest
//! texel** (piecewise constant over each texel's exact solid angle), the one choice that makes
//! [`Environment::radiance`], [`Environment::sample`] and [`Environment::pdf`] describe the same
//! function, so an estimator L/p is exact per texel. The two differ below a texel's size.

use crate::image::{Image, ImageError};
use crate::math::sampling::Distribution1D;
use glam::{DVec3, Quat, Vec2, Vec3};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Most texels an environment map may have (8192 × 4096 = 2²⁵ fits; 16384 × 8192 does not):
/// larger maps are refused before decoding, with a pointer to `interreflect convert-envmap`.
pub const MAX_TEXELS: u64 = 1 << 26;

/// Rec. 709 / sRGB luminance, the sampling weight of a texel.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Why an environment map could not be loaded. Messages name the file.
#[derive(thiserror::Error, Debug)]
pub enum EnvironmentError {
    /// Reading or decoding the file failed (missing, not an image, truncated, NaN pixels, ...).
    #[error(transparent)]
    Image(#[from] ImageError),
    /// The file decoded but is not a usable map (unknown extension, negative texels, size).
    #[error("{}: {reason}", .path.display())]
    Invalid { path: PathBuf, reason: String },
}

/// A lat-long environment map (see the module doc for the orientation), with intensity applied,
/// and its sampling distribution: rows by marginal, texels within a row by conditional
/// probability, ∝ luminance × solid angle.
#[derive(Clone)]
pub struct Environment {
    width: u32,
    height: u32,
    /// Radiance per texel, row-major from the top (intensity applied).
    texels: Vec<Vec3>,
    rotation_deg: f32,
    /// Map → world.
    rot: Quat,
    /// Rows, weight Σₓ luminance · Ω(y).
    rows: Distribution1D,
    /// Per row, texels by luminance.
    cols: Vec<Distribution1D>,
    /// Σ luminance · Ω over all texels (0 for a black map).
    total: f64,
    /// Per row: Ω(y) (f64), and cos θ at the top edge of the row.
    solid_angle: Vec<f64>,
    cos_top: Vec<f64>,
    /// The file it was loaded from (None from [`Environment::from_image`]).
    path: Option<PathBuf>,
}

impl std::fmt::Debug for Environment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Environment")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("rotation_deg", &self.rotation_deg)
            .field("weighted_luminance", &self.total)
            .finish_non_exhaustive()
    }
}

impl Environment {
    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Rotation about +y in degrees, as given.
    pub fn rotation_deg(&self) -> f32 {
        self.rotation_deg
    }

    /// ∫ luminance(L(ω)) dω over the sphere (W/m² of "luminance irradiance" from all around; 0
    /// for a black map).
    pub fn integrated_luminance(&self) -> f64 {
        self.total
    }

    /// Whether the map is black everywhere (it lights nothing; [`sample`](Self::sample) is None).
    pub fn is_black(&self) -> bool {
        !(self.total > 0.0)
    }

    /// Constructs from an image (rows from the top): checks the size (1 … [`MAX_TEXELS`]
    /// texels, the buffer length), that every texel is finite and ≥ 0, that `rotation_deg` is
    /// finite and `intensity` finite and ≥ 0; applies `intensity` (every texel must then be at
    /// most [`MAX_EMISSION`](super::MAX_EMISSION)); builds the sampling
    /// distribution. Any width × height is accepted (each texel spans 2π/W × π/H); lat-long maps
    /// are 2:1 and the scene loader warns otherwise.
    pub fn from_image(
        img: Image,
        rotation_deg: f32,
        intensity: f32,
    ) -> Result<Environment, String> {
        let (w, h) = (img.width, img.height);
        if w == 0 || h == 0 {
            return Err(format!("the map is empty ({w}x{h} texels)"));
        }
        if w as u64 * h as u64 > MAX_TEXELS {
            return Err(too_large(w, h));
        }
        if !img.has_consistent_size() {
            return Err(format!(
                "the texel buffer holds {} texels but the map is {w}x{h}",
                img.data.len()
            ));
        }
        if !rotation_deg.is_finite() {
            return Err(format!(
                "rotation must be a finite angle in degrees, got {rotation_deg}"
            ));
        }
        if !(intensity.is_finite() && intensity >= 0.0) {
            return Err(format!(
                "intensity must be a finite number ≥ 0, got {intensity}"
            ));
        }
        if let Some((x, y, v)) = img.first_non_finite() {
            return Err(format!(
                "texel (x {x}, y {y}) is not finite: ({}, {}, {})",
                v.x, v.y, v.z
            ));
        }
        if let Some(i) = img.data.iter().position(|p| p.min_element() < 0.0) {
            let v = img.data[i];
            return Err(format!(
                "texel (x {}, y {}) is negative: ({}, {}, {}) (radiance must be ≥ 0; first such texel in row-major order)",
                i % w as usize,
                i / w as usize,
                v.x,
                v.y,
                v.z
            ));
        }
        let texels: Vec<Vec3> = img.data.into_iter().map(|p| p * intensity).collect();
        // Checked after the scale: a bright texel times a large intensity overflows f32.
        if let Some(i) = texels
            .iter()
            .position(|p| !(p.max_element() <= super::MAX_EMISSION))
        {
            let v = texels[i];
            return Err(format!(
                "texel (x {}, y {}) scaled by intensity {intensity} is ({:e}, {:e}, {:e}): radiance must be at most {:e} per channel",
                i % w as usize,
                i / w as usize,
                v.x,
                v.y,
                v.z,
                super::MAX_EMISSION
            ));
        }
        let mut solid_angle = Vec::with_capacity(h as usize);
        let mut cos_top = Vec::with_capacity(h as usize);
        for y in 0..h {
            let (t0, t1) = (PI * y as f64 / h as f64, PI * (y + 1) as f64 / h as f64);
            cos_top.push(t0.cos());
            // cos θ₀ − cos θ₁ = 2 sin((θ₀+θ₁)/2) sin((θ₁−θ₀)/2), stable for thin rows.
            let band = 2.0 * (0.5 * (t0 + t1)).sin() * (0.5 * (t1 - t0)).sin();
            solid_angle.push(2.0 * PI / w as f64 * band);
        }
        let mut cols = Vec::with_capacity(h as usize);
        let mut row_w = Vec::with_capacity(h as usize);
        let mut total = 0.0f64;
        for (y, row) in texels.chunks(w as usize).enumerate() {
            let lum: Vec<f32> = row.iter().map(|&c| luminance(c)).collect();
            let d = Distribution1D::new(&lum);
            let rw = d.total() * solid_angle[y];
            total += rw;
            row_w.push(rw as f32);
            cols.push(d);
        }
        Ok(Environment {
            width: w,
            height: h,
            texels,
            rotation_deg,
            rot: Quat::from_rotation_y(rotation_deg.to_radians()),
            rows: Distribution1D::new(&row_w),
            cols,
            total,
            solid_angle,
            cos_top,
            path: None,
        })
    }

    /// Loads a lat-long map, OpenEXR (`.exr`, via [`crate::image::read_exr`]) or Radiance RGBE
    /// (`.hdr`, `.pic`), chosen by extension; the size is checked from the header before
    /// decoding. Errors name the file.
    pub fn load(
        path: &Path,
        rotation_deg: f32,
        intensity: f32,
    ) -> Result<Environment, EnvironmentError> {
        let img = read_latlong(path)?;
        let mut env = Environment::from_image(img, rotation_deg, intensity).map_err(|reason| {
            EnvironmentError::Invalid {
                path: path.to_path_buf(),
                reason,
            }
        })?;
        env.path = Some(path.to_path_buf());
        Ok(env)
    }

    /// The file the map was loaded from (None when built with [`from_image`](Self::from_image)).
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// Radiance of texel (x, y) (intensity applied).
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> Vec3 {
        self.texels[y as usize * self.width as usize + x as usize]
    }

    /// Exact solid angle of a texel in row y: (2π/W)(cos(πy/H) − cos(π(y+1)/H)).
    #[inline]
    pub fn texel_solid_angle(&self, y: u32) -> f32 {
        self.solid_angle[y as usize] as f32
    }

    /// World direction of texel (x, y)'s centre (u = (x + ½)/W, v = (y + ½)/H; rotation applied).
    pub fn texel_direction(&self, x: u32, y: u32) -> Vec3 {
        let u = (x as f64 + 0.5) / self.width as f64;
        let v = (y as f64 + 0.5) / self.height as f64;
        let (st, ct) = (PI * v).sin_cos();
        self.to_world(uv_dir(2.0 * PI * u, st, ct))
    }

    /// The texel (x, y) that world direction `d` (unit, from the scene towards the sky) falls in.
    pub fn texel_of(&self, d: Vec3) -> (u32, u32) {
        let m = (self.rot.inverse() * d).as_dvec3();
        let mut u = m.x.atan2(-m.z) / (2.0 * PI);
        if u < 0.0 {
            u += 1.0;
        }
        // atan2 of (sin θ, cos θ) is better conditioned than acos near the poles.
        let v = (m.x * m.x + m.z * m.z).sqrt().atan2(m.y) / PI;
        let x = ((u * self.width as f64) as u32).min(self.width - 1);
        let y = ((v * self.height as f64) as u32).min(self.height - 1);
        (x, y)
    }

    /// Radiance arriving from world direction `d` (unit; pointing from the scene towards the sky):
    /// the **nearest texel** (piecewise constant), the same function [`sample`](Self::sample)
    /// and [`pdf`](Self::pdf) describe.
    #[inline]
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let (x, y) = self.texel_of(d);
        self.texel(x, y)
    }

    /// Importance sampling ∝ luminance × solid angle, piecewise constant over texels: a row by
    /// its marginal, a texel by its luminance, then a uniform point of the texel in solid angle
    /// (uniform in φ and in cos θ), all from the two numbers of `u` (re-used within each choice).
    /// Returns the world direction and its solid-angle pdf, luminance(texel) / ∫ luminance dω;
    /// `None` for a black map.
    pub fn sample(&self, u: Vec2) -> Option<(Vec3, f32)> {
        let (y, sv) = self.rows.sample_remapped(u.y)?;
        let (x, su) = self.cols[y].sample_remapped(u.x)?;
        let phi = 2.0 * PI * (x as f64 + su as f64) / self.width as f64;
        let c0 = self.cos_top[y];
        let c1 = c0 - self.solid_angle[y] * self.width as f64 / (2.0 * PI);
        let ct = (c0 + (c1 - c0) * sv as f64).clamp(-1.0, 1.0);
        let st = (1.0 - ct * ct).max(0.0).sqrt();
        let d = self.to_world(uv_dir(phi, st, ct));
        let pdf = (luminance(self.texel(x as u32, y as u32)) as f64 / self.total) as f32;
        (pdf > 0.0).then_some((d, pdf))
    }

    /// Solid-angle density of [`sample`](Self::sample) in world direction `d`:
    /// luminance(texel of d) / ∫ luminance dω (0 for a black map).
    pub fn pdf(&self, d: Vec3) -> f32 {
        if !(self.total > 0.0) {
            return 0.0;
        }
        let (x, y) = self.texel_of(d);
        (luminance(self.texel(x, y)) as f64 / self.total) as f32
    }

    fn to_world(&self, m: DVec3) -> Vec3 {
        (self.rot * m.as_vec3()).normalize()
    }
}

/// The map-frame direction at azimuth φ with sin θ, cos θ: (sin φ sin θ, cos θ, −cos φ sin θ).
fn uv_dir(phi: f64, sin_theta: f64, cos_theta: f64) -> DVec3 {
    let (sp, cp) = phi.sin_cos();
    DVec3::new(sp * sin_theta, cos_theta, -cp * sin_theta)
}

fn too_large(w: u32, h: u32) -> String {
    format!(
        "the map is too large: {w}x{h} = {} texels, more than the {MAX_TEXELS} accepted (8192x4096 fits); downsample it with `interreflect convert-envmap IN OUT --width 2048`",
        w as u64 * h as u64
    )
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default()
}

/// Reads a lat-long image, OpenEXR or Radiance RGBE by extension, refusing sizes above
/// [`MAX_TEXELS`] from the header before decoding.
pub fn read_latlong(path: &Path) -> Result<Image, EnvironmentError> {
    latlong(
        path,
        || crate::image::read_exr_size(path),
        || crate::image::read_hdr_size(path),
        || crate::image::read_exr(path),
        || crate::image::read_hdr(path),
    )
}

/// [`read_latlong`] for a file held in memory: `name` stands for the file in error messages and
/// its extension chooses the format.
pub fn read_latlong_bytes(bytes: &[u8], name: &str) -> Result<Image, EnvironmentError> {
    latlong(
        Path::new(name),
        || crate::image::read_exr_size_bytes(bytes, name),
        || crate::image::read_hdr_size_bytes(bytes, name),
        || crate::image::read_exr_bytes(bytes, name),
        || crate::image::read_hdr_bytes(bytes, name),
    )
}

type ImageResult<T> = Result<T, ImageError>;

/// The extension dispatch and size check shared by [`read_latlong`] and [`read_latlong_bytes`].
fn latlong(
    path: &Path,
    exr_size: impl FnOnce() -> ImageResult<(u32, u32)>,
    hdr_size: impl FnOnce() -> ImageResult<(u32, u32)>,
    exr: impl FnOnce() -> ImageResult<Image>,
    hdr: impl FnOnce() -> ImageResult<Image>,
) -> Result<Image, EnvironmentError> {
    let ext = extension(path);
    let invalid = |reason: String| EnvironmentError::Invalid {
        path: path.to_path_buf(),
        reason,
    };
    let (w, h) = match ext.as_str() {
        "exr" => exr_size()?,
        "hdr" | "pic" => hdr_size()?,
        _ => {
            return Err(invalid(format!(
                "unknown environment-map extension \"{ext}\": expected .exr (OpenEXR) or .hdr (Radiance RGBE)"
            )));
        }
    };
    if w as u64 * h as u64 > MAX_TEXELS {
        return Err(invalid(too_large(w, h)));
    }
    Ok(match ext.as_str() {
        "exr" => exr()?,
        _ => hdr()?,
    })
}

/// Resamples a lat-long map to `width` × `height` with an area-weighted box filter: each output
/// texel is the solid-angle-weighted mean of the input texels it overlaps (overlaps measured
/// exactly in φ and in cos θ), so ∫ L dω over any union of output texels — and over the whole
/// sphere — is preserved. Used by `interreflect convert-envmap`.
pub fn resample_latlong(img: &Image, width: u32, height: u32) -> Image {
    let (wi, hi) = (img.width as usize, img.height as usize);
    let (wo, ho) = (width as usize, height as usize);
    // Overlap weights of input cells with output cells along one axis, given the cell edges
    // mapped to a common measure (φ: linear; θ: cos θ).
    fn overlaps(edges_in: &[f64], edges_out: &[f64]) -> Vec<Vec<(usize, f64)>> {
        let n_out = edges_out.len() - 1;
        let mut out = vec![Vec::new(); n_out];
        let mut i = 0;
        for (o, ov) in out.iter_mut().enumerate() {
            let (a, b) = (edges_out[o], edges_out[o + 1]);
            while i + 1 < edges_in.len() && edges_in[i + 1] <= a {
                i += 1;
            }
            let mut k = i;
            while k + 1 < edges_in.len() && edges_in[k] < b {
                let lo = edges_in[k].max(a);
                let hi = edges_in[k + 1].min(b);
                if hi > lo {
                    ov.push((k, hi - lo));
                }
                k += 1;
            }
        }
        out
    }
    // Edges in increasing measure: φ fraction, and 1 − cos θ (0 at the top pole, 2 at the bottom).
    let phi_edges = |n: usize| (0..=n).map(|i| i as f64 / n as f64).collect::<Vec<_>>();
    let z_edges = |n: usize| {
        (0..=n)
            .map(|i| 1.0 - (PI * i as f64 / n as f64).cos())
            .collect::<Vec<_>>()
    };
    let ox = overlaps(&phi_edges(wi), &phi_edges(wo));
    let oy = overlaps(&z_edges(hi), &z_edges(ho));
    let mut data = Vec::with_capacity(wo * ho);
    for ys in &oy {
        for xs in &ox {
            let mut sum = DVec3::ZERO;
            let mut wsum = 0.0;
            for &(yi, wy) in ys {
                for &(xi, wx) in xs {
                    let w = wy * wx;
                    sum += img.data[yi * wi + xi].as_dvec3() * w;
                    wsum += w;
                }
            }
            data.push(if wsum > 0.0 {
                (sum / wsum).as_vec3()
            } else {
                Vec3::ZERO
            });
        }
    }
    Image {
        width,
        height,
        data,
    }
}

#[cfg(test)]
#[path = "environment_tests.rs"]
mod tests;
