//! Scenes: the TOML schema, validation, mesh loading, procedural shapes, camera and lights.
//!
//! A [`Scene`] is immutable once loaded: every object is transformed to world space and merged
//! into one [`SceneMesh`], with a per-triangle object index.

pub mod camera;
pub mod environment;
pub mod light;
pub mod mesh;
pub mod schema;
pub mod shapes;

pub use camera::Camera;
pub use environment::Environment;
pub use light::{Incident, Light};

use crate::brdf::{Brdf, Distribution};
use glam::{Mat3, Mat4, Quat, Vec3};
use mesh::MeshData;
use schema::*;
use std::path::{Path, PathBuf};

/// Largest accepted image side, triangle count per procedural shape and similar sanity limits.
pub const MAX_IMAGE_SIDE: u32 = 16384;
pub const MAX_SEGMENTS: u32 = 65536;
pub const MAX_SUBDIVISIONS: u32 = 4096;
/// Most triangles a scene may have in all (procedural shapes and mesh files together): 2²⁴,
/// about 16.8 million. A procedural shape is checked against it before it is generated, so a
/// sphere with `segments = 65536` (4.3 billion triangles) is refused instead of exhausting
/// memory; a plane may have up to 2896 subdivisions.
pub const MAX_SCENE_TRIANGLES: u64 = 1 << 24;
/// Upper bound on samples per pixel accepted from scene files and the command line.
pub const MAX_SPP: u32 = 1 << 20;
/// Largest accepted `visibility.shadow_map_resolution` (a point light's cube of 6 faces at this
/// size holds 6 × 4096² × 8 bytes = 805 MB).
pub const MAX_SHADOW_MAP: u32 = 4096;

/// Largest accepted `methods.prt.bounces`.
pub const MAX_PRT_BOUNCES: u32 = 8;
/// Largest accepted `methods.prt.samples` (ray directions per vertex).
pub const MAX_PRT_SAMPLES: u32 = 1 << 16;

/// Largest accepted world-space coordinate, in either direction, of the camera and of every
/// vertex after its object's transform. f32's spacing there is already 8 units, so a scene that
/// reaches it keeps no usable precision; beyond it squared lengths (the scene's diagonal, the
/// areas of triangles, 1/d² falloffs) and their squares would overflow f32 to ∞ and turn the
/// renderers' arithmetic into NaN.
pub const MAX_COORDINATE: f32 = 1e8;

/// Largest accepted emission, per RGB channel: a light's intensity (W/sr) or irradiance (W/m²),
/// and an environment map's radiance after its `intensity` scale. The sun's radiance is about
/// 1e9 in these units; 1e20 leaves eleven orders of magnitude for unit choices, while the
/// products the renderers form with it (BRDF peaks up to ~1e6 for the sharpest accepted lobes,
/// 1/d² falloffs, sums over texels and coefficients) stay far below f32's 3.4e38. Above it a map
/// scaled by its intensity overflowed to ∞ and prt relit vertices to NaN.
pub const MAX_EMISSION: f32 = 1e20;

/// Largest accepted `methods.sg.max_cut`.
pub const MAX_CUT: u32 = 1 << 24;

/// Most VPLs per light (`[visibility] vpl_count`, `render --vpls`).
pub const MAX_VPLS: u32 = 100_000;
/// Most visibility maps at tree nodes per light (`[visibility] node_maps`): 100,000 maps of 32²
/// texels are 0.8 GB, which the memory budget then weighs.
pub const MAX_NODE_MAPS: u32 = 100_000;

/// Why a scene could not be loaded. Every message names the file and, where it applies, the field.
#[derive(thiserror::Error, Debug)]
pub enum SceneError {
    #[error("{path}: cannot read the scene file: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    #[error("{path}: {field}: {message}")]
    Invalid {
        path: PathBuf,
        field: String,
        message: String,
    },
    #[error("{path}: {field}: {source}")]
    Mesh {
        path: PathBuf,
        field: String,
        source: Box<mesh::MeshError>,
    },
}

/// A named material.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub brdf: Brdf,
}

/// An object: a range of triangles in the merged mesh.
#[derive(Clone, Debug)]
pub struct Object {
    pub name: String,
    pub material: u32,
    pub first_tri: u32,
    pub tri_count: u32,
    pub reflector: bool,
    pub receiver: bool,
    /// "plane", "ring", or the mesh file as written in the scene.
    pub source: String,
}

/// All triangles of the scene in world space.
#[derive(Clone, Debug, Default)]
pub struct SceneMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
    /// Object index of each triangle.
    pub tri_object: Vec<u32>,
}

impl SceneMesh {
    /// Corner positions of triangle `t`.
    #[inline]
    pub fn tri(&self, t: u32) -> [Vec3; 3] {
        self.indices[t as usize].map(|i| self.positions[i as usize])
    }

    /// Unnormalised geometric normal (twice the area) of triangle `t`, following the winding.
    #[inline]
    pub fn tri_cross(&self, t: u32) -> Vec3 {
        let [a, b, c] = self.tri(t);
        (b - a).cross(c - a)
    }

    /// Interpolated shading normal (unit) at barycentrics (u, v).
    #[inline]
    pub fn shading_normal(&self, t: u32, u: f32, v: f32) -> Vec3 {
        let [i0, i1, i2] = self.indices[t as usize];
        let n = self.normals[i0 as usize] * (1.0 - u - v)
            + self.normals[i1 as usize] * u
            + self.normals[i2 as usize] * v;
        n.try_normalize()
            .unwrap_or_else(|| self.tri_cross(t).normalize_or_zero())
    }

    /// Point at barycentrics (u, v).
    #[inline]
    pub fn point(&self, t: u32, u: f32, v: f32) -> Vec3 {
        let [a, b, c] = self.tri(t);
        a * (1.0 - u - v) + b * u + c * v
    }

    /// Length of the bounding-box diagonal (0 for an empty mesh).
    pub fn diagonal(&self) -> f32 {
        let (lo, hi) = self.bounds();
        (hi - lo).length()
    }

    /// Axis-aligned bounds (min, max); zero box for an empty mesh.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.positions.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &self.indices {
            for &i in t {
                lo = lo.min(self.positions[i as usize]);
                hi = hi.max(self.positions[i as usize]);
            }
        }
        (lo, hi)
    }
}

/// The render defaults of the scene file.
#[derive(Clone, Copy, Debug)]
pub struct RenderSettings {
    pub spp: u32,
    pub seed: u64,
    pub reference: ReferenceSpec,
    pub sg: SgSpec,
    /// Variance shadow maps (`[visibility]`).
    pub vsm: crate::settings::VsmOptions,
    /// Virtual point lights per light and their imperfect shadow maps (`[visibility]`).
    pub vpl_count: u32,
    pub ism: crate::settings::IsmOptions,
    /// SH diffuse PRT (`[methods.prt]`).
    pub prt: PrtSpec,
    /// The VPL baseline (`[methods.vpl]`).
    pub vpl: VplSpec,
}

/// What a scene will hold, known before its meshes are loaded: shape sizes come from their
/// parameters, mesh sizes from [`mesh::peek_counts`] (a PLY header, a pass over an OBJ).
#[derive(Clone, Debug)]
pub struct ScenePreview {
    pub camera_width: u32,
    pub camera_height: u32,
    pub settings: RenderSettings,
    /// Point, spot and directional lights.
    pub lights: usize,
    /// Texels of the environment map (already loaded), 0 without one.
    pub environment_texels: u64,
    /// Triangles and vertices of every object whose size is known.
    pub triangles: u64,
    pub vertices: u64,
    /// Mesh files whose size cannot be known without loading them (glTF/GLB, unreadable files):
    /// the check after loading covers them.
    pub unknown: Vec<String>,
    /// The field of the object with the most triangles (`objects[i].shape.file` for a mesh).
    pub largest_field: String,
}

/// A check run on a [`ScenePreview`] before the meshes are loaded; `Err(message)` refuses the
/// scene.
pub type PreviewCheck<'a> = &'a mut dyn FnMut(&ScenePreview) -> Result<(), String>;

/// A loaded, validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    /// The scene file.
    pub path: PathBuf,
    pub camera: Camera,
    pub lights: Vec<Light>,
    /// Environment lighting (`[environment]`), if any. The reference, direct and prt methods
    /// render it.
    pub environment: Option<Environment>,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    pub mesh: SceneMesh,
    pub settings: RenderSettings,
    /// Mesh and environment-map files the scene reads (so outputs never overwrite them).
    pub inputs: Vec<PathBuf>,
    /// Problems that do not stop rendering (repaired normals, removed triangles, ...).
    pub warnings: Vec<String>,
}

impl Scene {
    /// Loads and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_checked(path, None)
    }

    /// Loads a scene like [`Scene::load`], calling `check` with a [`ScenePreview`] after the
    /// settings are validated and before any mesh is loaded; an `Err(message)` from it stops
    /// loading with an error naming the scene file and its largest object (this is how
    /// `render` refuses a scene over its memory budget up front).
    pub fn load_checked(path: &Path, check: Option<PreviewCheck>) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Scene::from_str_checked(&text, path, check)
    }

    /// Parses scene text; `path` names the file in messages and anchors relative mesh paths.
    pub fn from_str_at(text: &str, path: &Path) -> Result<Scene, SceneError> {
        Scene::from_str_checked(text, path, None)
    }

    /// [`Scene::from_str_at`] with a [`PreviewCheck`] (see [`Scene::load_checked`]).
    pub fn from_str_checked(
        text: &str,
        path: &Path,
        check: Option<PreviewCheck>,
    ) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
            path: path.to_path_buf(),
            message: format!("malformed scene file: {}", e.to_string().trim_end()),
        })?;
        Builder::new(path).build(file, check)
    }

    /// Material of triangle `t`.
    #[inline]
    pub fn tri_material(&self, t: u32) -> &Brdf {
        &self.materials[self.tri_material_index(t) as usize].brdf
    }

    /// Index into `materials` of triangle `t`'s material.
    #[inline]
    pub fn tri_material_index(&self, t: u32) -> u32 {
        let o = self.mesh.tri_object[t as usize] as usize;
        self.objects[o].material
    }

    /// Object of triangle `t`.
    #[inline]
    pub fn tri_object(&self, t: u32) -> &Object {
        &self.objects[self.mesh.tri_object[t as usize] as usize]
    }
}

struct Builder {
    path: PathBuf,
    dir: PathBuf,
    warnings: Vec<String>,
}

impl Builder {
    fn new(path: &Path) -> Builder {
        let dir = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        Builder {
            path: path.to_path_buf(),
            dir,
            warnings: Vec::new(),
        }
    }

    fn err(&self, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.path.clone(),
            field: field.into(),
            message: message.into(),
        }
    }

    fn finite3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(Vec3::from(v))
        } else {
            Err(self.err(field, format!("expected finite numbers, got {v:?}")))
        }
    }

    /// A point within ±[`MAX_COORDINATE`] in every coordinate.
    fn coordinate3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let x = self.finite3(field, v)?;
        if !(x.abs().max_element() <= MAX_COORDINATE) {
            return Err(self.err(
                field,
                format!("must lie within ±{MAX_COORDINATE:e} in every coordinate, got {v:?}"),
            ));
        }
        Ok(x)
    }

    /// An emission: finite, ≥ 0 and at most [`MAX_EMISSION`] per channel.
    fn emission3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let x = self.finite3(field, v)?;
        if x.min_element() < 0.0 {
            return Err(self.err(field, format!("must not be negative, got {v:?}")));
        }
        if x.max_element() > MAX_EMISSION {
            return Err(self.err(
                field,
                format!("must be at most {MAX_EMISSION:e} per channel, got {v:?}"),
            ));
        }
        Ok(x)
    }

    fn unit3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
        let x = self.finite3(field, v)?;
        x.try_normalize()
            .ok_or_else(|| self.err(field, "must be a non-zero direction"))
    }

    fn positive(&self, field: &str, x: f32) -> Result<f32, SceneError> {
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(field, format!("must be a finite number > 0, got {x}")))
        }
    }

    fn build(mut self, file: SceneFile, check: Option<PreviewCheck>) -> Result<Scene, SceneError> {
        let name = match &file.name {
            Some(n) if n.trim().is_empty() => return Err(self.err("name", "must not be empty")),
            Some(n) => n.clone(),
            None => self
                .path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into()),
        };
        if name.contains(['/', '\\']) || name == "." || name == ".." {
            return Err(self.err("name", "must not contain path separators"));
        }
        let camera = self.camera(&file.camera)?;
        let lights = file
            .lights
            .iter()
            .enumerate()
            .map(|(i, l)| self.light(i, l))
            .collect::<Result<Vec<_>, _>>()?;
        let mut inputs = Vec::new();
        let environment = match &file.environment {
            Some(spec) => Some(self.environment(spec, &mut inputs)?),
            None => None,
        };
        if lights.is_empty() && environment.is_none() {
            self.warnings.push(format!(
                "{}: lights: no lights and no [environment]: every method will render a black image",
                self.path.display()
            ));
        }
        let mut materials = Vec::new();
        for (mname, spec) in &file.materials {
            let brdf = material_brdf(spec);
            brdf.validate()
                .map_err(|m| self.err(format!("materials.{mname}"), m))?;
            materials.push(Material {
                name: mname.clone(),
                brdf,
            });
        }
        if file.objects.is_empty() {
            return Err(self.err("objects", "the scene has no objects"));
        }
        let settings = self.settings(&file, environment.is_some())?;
        if let Some(check) = check {
            let preview = self.preview(&file, &camera, &settings, &lights, environment.as_ref());
            // Past the triangle cap, loading stops with that (more specific) error.
            if preview.triangles <= MAX_SCENE_TRIANGLES
                && let Err(message) = check(&preview)
            {
                return Err(self.err(preview.largest_field.clone(), message));
            }
        }
        let mut mesh = SceneMesh::default();
        let mut objects = Vec::new();
        for (i, o) in file.objects.iter().enumerate() {
            let field = format!("objects[{i}]");
            let oname = o.name.clone().unwrap_or_else(|| format!("object{i}"));
            let material = materials
                .iter()
                .position(|m| m.name == o.material)
                .ok_or_else(|| {
                    let known: Vec<_> = materials.iter().map(|m| m.name.as_str()).collect();
                    self.err(
                        format!("{field}.material"),
                        format!(
                            "material \"{}\" is not defined (defined: {})",
                            o.material,
                            if known.is_empty() {
                                "none".to_string()
                            } else {
                                known.join(", ")
                            }
                        ),
                    )
                })? as u32;
            let used = mesh.indices.len() as u64;
            let (data, source) = self.shape(&field, &oname, &o.shape, &mut inputs, used)?;
            let xf = self.transform(&field, &o.transform)?;
            let first_tri = mesh.indices.len() as u32;
            let first_vertex = mesh.positions.len();
            append_transformed(&mut mesh, &data, xf, objects.len() as u32);
            if let Some((v, p)) = mesh.positions[first_vertex..]
                .iter()
                .enumerate()
                .find(|(_, p)| !(p.abs().max_element() <= MAX_COORDINATE))
            {
                let axis = (0..3)
                    .max_by(|&a, &b| p[a].abs().total_cmp(&p[b].abs()))
                    .unwrap_or(0);
                let is_mesh = matches!(o.shape, ShapeSpec::Mesh { .. });
                let (at, of) = match (o.transform.is_identity(), is_mesh) {
                    (true, true) => (format!("{field}.shape.file"), format!(" of {source}")),
                    (true, false) => (format!("{field}.shape"), String::new()),
                    (false, true) => (format!("{field}.transform"), format!(" of {source}")),
                    (false, false) => (format!("{field}.transform"), String::new()),
                };
                return Err(self.err(
                    at,
                    format!(
                        "vertex {v}{of} has world-space {} = {:e}, beyond ±{MAX_COORDINATE:e}: scale the object down",
                        ["x", "y", "z"][axis],
                        p[axis]
                    ),
                ));
            }
            let tri_count = mesh.indices.len() as u32 - first_tri;
            objects.push(Object {
                name: oname,
                material,
                first_tri,
                tri_count,
                reflector: o.reflector,
                receiver: o.receiver,
                source,
            });
        }
        Ok(Scene {
            name,
            path: self.path.clone(),
            camera,
            lights,
            environment,
            materials,
            objects,
            mesh,
            settings,
            inputs,
            warnings: self.warnings,
        })
    }

    /// Sizes of everything the scene will hold, without loading a mesh.
    fn preview(
        &self,
        file: &SceneFile,
        camera: &Camera,
        settings: &RenderSettings,
        lights: &[Light],
        environment: Option<&Environment>,
    ) -> ScenePreview {
        let (mut triangles, mut vertices) = (0u64, 0u64);
        let mut unknown = Vec::new();
        let mut largest = (0u64, "objects".to_string());
        for (i, o) in file.objects.iter().enumerate() {
            let field = format!("objects[{i}].shape");
            let (t, v, field) = match &o.shape {
                ShapeSpec::Mesh { file } => match mesh::peek_counts(&self.dir.join(file)) {
                    Some(c) => (c.triangles, c.vertices, format!("{field}.file")),
                    None => {
                        unknown.push(file.clone());
                        continue;
                    }
                },
                // Shapes with parameters out of range are left out: loading reports them.
                ShapeSpec::Plane { subdivisions, .. }
                    if !(1..=MAX_SUBDIVISIONS).contains(subdivisions) =>
                {
                    continue;
                }
                ShapeSpec::Sphere { segments, .. } | ShapeSpec::Ring { segments, .. }
                    if !(3..=MAX_SEGMENTS).contains(segments) =>
                {
                    continue;
                }
                ShapeSpec::Plane { subdivisions, .. } => {
                    let n = u64::from((*subdivisions).max(1));
                    (
                        shapes::plane_triangles(*subdivisions),
                        (n + 1) * (n + 1),
                        field,
                    )
                }
                ShapeSpec::Box { .. } => (shapes::CUBOID_TRIANGLES, 24, field),
                // Flat-shaded parts make up to one vertex per triangle corner; count one per
                // triangle (a sphere has about half that).
                ShapeSpec::Sphere { segments, .. } => {
                    let t = shapes::sphere_triangles(*segments);
                    (t, t, field)
                }
                ShapeSpec::Ring { segments, .. } => {
                    let t = shapes::ring_triangles(*segments);
                    (t, t, field)
                }
            };
            triangles += t;
            vertices += v;
            if t > largest.0 {
                largest = (t, field);
            }
        }
        ScenePreview {
            camera_width: camera.width,
            camera_height: camera.height,
            settings: *settings,
            lights: lights.len(),
            environment_texels: environment
                .map(|e| e.width() as u64 * e.height() as u64)
                .unwrap_or(0),
            triangles,
            vertices,
            unknown,
            largest_field: largest.1,
        }
    }

    /// Validates `[render]`, `[methods.*]` and `[visibility]`.
    fn settings(
        &self,
        file: &SceneFile,
        has_environment: bool,
    ) -> Result<RenderSettings, SceneError> {
        let render = &file.render;
        if render.spp == 0 || render.spp > MAX_SPP {
            return Err(self.err(
                "render.spp",
                format!("must be between 1 and {MAX_SPP}, got {}", render.spp),
            ));
        }
        let r = file.methods.reference;
        for (f, v) in [
            ("methods.reference.reflector_samples", r.reflector_samples),
            ("methods.reference.bsdf_samples", r.bsdf_samples),
            ("methods.reference.light_paths", r.light_paths),
        ] {
            if v > 64 {
                return Err(self.err(f, format!("must be between 0 and 64, got {v}")));
            }
        }
        if has_environment && r.bsdf_samples == 0 {
            return Err(self.err(
                "methods.reference.bsdf_samples",
                "must be at least 1 in a scene with an [environment]: BRDF sampling at the receiver is the only strategy that finds the one-bounce light of the environment",
            ));
        }
        if r.reflector_samples == 0 && r.bsdf_samples == 0 && r.light_paths == 0 {
            return Err(self.err(
                "methods.reference",
                "reflector_samples, bsdf_samples and light_paths cannot all be 0",
            ));
        }
        let sg = file.methods.sg;
        if !(sg.threshold.is_finite() && (0.0..=1.0).contains(&sg.threshold)) {
            return Err(self.err(
                "methods.sg.threshold",
                format!(
                    "must be between 0 and 1 (a fraction of the estimate), got {}",
                    sg.threshold
                ),
            ));
        }
        if sg.max_cut > MAX_CUT {
            return Err(self.err(
                "methods.sg.max_cut",
                format!(
                    "must be between 0 (no cap) and {MAX_CUT}, got {}",
                    sg.max_cut
                ),
            ));
        }
        if let Some(e) = sg.max_edge
            && !(e.is_finite() && e >= 0.0)
        {
            return Err(self.err(
                "methods.sg.max_edge",
                format!("must be a length ≥ 0 (0 = never split), got {e}"),
            ));
        }
        if sg.spp == 0 || sg.spp > MAX_SPP {
            return Err(self.err(
                "methods.sg.spp",
                format!("must be between 1 and {MAX_SPP}, got {}", sg.spp),
            ));
        }
        let p = file.methods.prt;
        if !(1..=crate::math::sh::MAX_ORDER).contains(&p.order) {
            return Err(self.err(
                "methods.prt.order",
                format!(
                    "must be between 1 and {}, got {}",
                    crate::math::sh::MAX_ORDER,
                    p.order
                ),
            ));
        }
        if p.bounces > MAX_PRT_BOUNCES {
            return Err(self.err(
                "methods.prt.bounces",
                format!("must be between 0 and {MAX_PRT_BOUNCES}, got {}", p.bounces),
            ));
        }
        if !(1..=MAX_PRT_SAMPLES).contains(&p.samples) {
            return Err(self.err(
                "methods.prt.samples",
                format!("must be between 1 and {MAX_PRT_SAMPLES}, got {}", p.samples),
            ));
        }
        if let Some(w) = p.window_width
            && !(w.is_finite() && w > 0.0 && w <= 4.0 * crate::math::sh::MAX_ORDER as f32)
        {
            return Err(self.err(
                "methods.prt.window_width",
                format!(
                    "must be a band number > 0 and at most {}, got {w}",
                    4 * crate::math::sh::MAX_ORDER
                ),
            ));
        }
        if p.spp == 0 || p.spp > MAX_SPP {
            return Err(self.err(
                "methods.prt.spp",
                format!("must be between 1 and {MAX_SPP}, got {}", p.spp),
            ));
        }
        let vp = file.methods.vpl;
        if let Some(d) = vp.clamp_distance
            && !(d.is_finite() && (0.0..=MAX_COORDINATE).contains(&d))
        {
            return Err(self.err(
                "methods.vpl.clamp_distance",
                format!("must be a length between 0 (no clamp) and {MAX_COORDINATE:e}, got {d}"),
            ));
        }
        if let Some(n) = vp.spp
            && (n == 0 || n > MAX_SPP)
        {
            return Err(self.err(
                "methods.vpl.spp",
                format!("must be between 1 and {MAX_SPP}, got {n}"),
            ));
        }
        let v = file.visibility;
        if !(16..=MAX_SHADOW_MAP).contains(&v.shadow_map_resolution) {
            return Err(self.err(
                "visibility.shadow_map_resolution",
                format!(
                    "must be between 16 and {MAX_SHADOW_MAP} texels, got {}",
                    v.shadow_map_resolution
                ),
            ));
        }
        if v.vsm_blur > 32 {
            return Err(self.err(
                "visibility.vsm_blur",
                format!("must be between 0 and 32 texels, got {}", v.vsm_blur),
            ));
        }
        if !(v.light_bleeding.is_finite() && (0.0..1.0).contains(&v.light_bleeding)) {
            return Err(self.err(
                "visibility.light_bleeding",
                format!("must be in [0, 1), got {}", v.light_bleeding),
            ));
        }
        for (field, value, lo, hi) in [
            ("visibility.vpl_count", v.vpl_count, 1, MAX_VPLS),
            ("visibility.ism_resolution", v.ism_resolution, 4, 1024),
            ("visibility.ism_points", v.ism_points, 1, 10_000_000),
            ("visibility.node_maps", v.node_maps, 0, MAX_NODE_MAPS),
        ] {
            if !(lo..=hi).contains(&value) {
                return Err(self.err(field, format!("must be between {lo} and {hi}, got {value}")));
            }
        }
        if !(v.ism_bias.is_finite() && (0.0..=10.0).contains(&v.ism_bias)) {
            return Err(self.err(
                "visibility.ism_bias",
                format!(
                    "must be between 0 and 10 (a fraction of the distance), got {}",
                    v.ism_bias
                ),
            ));
        }
        Ok(RenderSettings {
            spp: render.spp,
            seed: render.seed,
            reference: r,
            sg,
            vsm: crate::settings::VsmOptions {
                resolution: v.shadow_map_resolution,
                blur: v.vsm_blur,
                light_bleeding: v.light_bleeding,
            },
            vpl_count: v.vpl_count,
            ism: crate::settings::IsmOptions {
                resolution: v.ism_resolution,
                points_per_map: v.ism_points,
                bias: v.ism_bias,
                blur: true,
                node_maps: v.node_maps,
            },
            prt: p,
            vpl: vp,
        })
    }

    fn camera(&self, c: &CameraSpec) -> Result<Camera, SceneError> {
        let pos = self.coordinate3("camera.position", c.position)?;
        let at = self.coordinate3("camera.look_at", c.look_at)?;
        let up = self.unit3("camera.up", c.up)?;
        if !(c.fov_y.is_finite() && c.fov_y > 0.0 && c.fov_y < 180.0) {
            return Err(self.err(
                "camera.fov_y",
                format!("must be in (0, 180) degrees, got {}", c.fov_y),
            ));
        }
        for (f, v) in [("camera.width", c.width), ("camera.height", c.height)] {
            if v == 0 || v > MAX_IMAGE_SIDE {
                return Err(self.err(
                    f,
                    format!("must be between 1 and {MAX_IMAGE_SIDE}, got {v}"),
                ));
            }
        }
        if (at - pos).length() == 0.0 {
            return Err(self.err("camera.look_at", "equals camera.position"));
        }
        Camera::look_at(pos, at, up, c.fov_y, c.width, c.height)
            .ok_or_else(|| self.err("camera.up", "is parallel to the viewing direction"))
    }

    fn environment(
        &mut self,
        spec: &EnvironmentSpec,
        inputs: &mut Vec<PathBuf>,
    ) -> Result<Environment, SceneError> {
        if !spec.rotation.is_finite() {
            return Err(self.err(
                "environment.rotation",
                format!("must be a finite angle in degrees, got {}", spec.rotation),
            ));
        }
        if !(spec.intensity.is_finite() && spec.intensity >= 0.0) {
            return Err(self.err(
                "environment.intensity",
                format!("must be a finite number ≥ 0, got {}", spec.intensity),
            ));
        }
        if spec.file.trim().is_empty() {
            return Err(self.err("environment.file", "must name a .exr or .hdr file"));
        }
        let p = self.dir.join(&spec.file);
        let env = Environment::load(&p, spec.rotation, spec.intensity)
            .map_err(|e| self.err("environment.file", e.to_string()))?;
        let (w, h) = (env.width(), env.height());
        if w != 2 * h {
            self.warnings.push(format!(
                "{}: environment.file: {} is {w}x{h}, not 2:1 — lat-long maps are twice as wide as high; it is stretched over the sphere as is",
                self.path.display(),
                spec.file
            ));
        }
        if env.is_black() {
            self.warnings.push(format!(
                "{}: environment: {} is black{}: it lights nothing",
                self.path.display(),
                spec.file,
                if spec.intensity == 0.0 {
                    " (intensity = 0)"
                } else {
                    ""
                }
            ));
        }
        inputs.push(p);
        Ok(env)
    }

    fn light(&self, i: usize, l: &LightSpec) -> Result<Light, SceneError> {
        let f = |s: &str| format!("lights[{i}].{s}");
        Ok(match l {
            LightSpec::Point {
                position,
                intensity,
            } => Light::Point {
                position: self.finite3(&f("position"), *position)?,
                intensity: self.emission3(&f("intensity"), *intensity)?,
            },
            LightSpec::Spot {
                position,
                direction,
                intensity,
                cone_angle,
                falloff_angle,
            } => {
                if !(cone_angle.is_finite() && *cone_angle > 0.0 && *cone_angle <= 180.0) {
                    return Err(self.err(
                        f("cone_angle"),
                        format!("must be in (0, 180] degrees, got {cone_angle}"),
                    ));
                }
                let fall = falloff_angle.unwrap_or(*cone_angle);
                if !(fall.is_finite() && fall >= 0.0 && fall <= *cone_angle) {
                    return Err(self.err(
                        f("falloff_angle"),
                        format!("must be in [0, cone_angle = {cone_angle}] degrees, got {fall}"),
                    ));
                }
                Light::Spot {
                    position: self.finite3(&f("position"), *position)?,
                    direction: self.unit3(&f("direction"), *direction)?,
                    intensity: self.emission3(&f("intensity"), *intensity)?,
                    cos_cone: cone_angle.to_radians().cos(),
                    cos_falloff: fall.to_radians().cos(),
                }
            }
            LightSpec::Directional {
                direction,
                irradiance,
            } => Light::Directional {
                direction: self.unit3(&f("direction"), *direction)?,
                irradiance: self.emission3(&f("irradiance"), *irradiance)?,
            },
        })
    }

    fn shape(
        &mut self,
        field: &str,
        oname: &str,
        s: &ShapeSpec,
        inputs: &mut Vec<PathBuf>,
        used: u64,
    ) -> Result<(MeshData, String), SceneError> {
        let sf = |x: &str| format!("{field}.shape.{x}");
        // Refuses a shape that would take the scene past MAX_SCENE_TRIANGLES.
        let budget = |what: &str, field: String, triangles: u64| {
            if used + triangles > MAX_SCENE_TRIANGLES {
                let before = if used > 0 {
                    format!(" ({used} already used by earlier objects)")
                } else {
                    String::new()
                };
                return Err(self.err(
                    field,
                    format!(
                        "{what} has {triangles} triangles; a scene may have at most \
                         {MAX_SCENE_TRIANGLES} in all{before}"
                    ),
                ));
            }
            Ok(())
        };
        Ok(match s {
            ShapeSpec::Mesh { file } => {
                if file.trim().is_empty() {
                    return Err(self.err(
                        sf("file"),
                        "must name a mesh file (.ply, .ply.gz, .obj, .obj.gz, .gltf or .glb)",
                    ));
                }
                let p = self.dir.join(file);
                let data = mesh::load_mesh(&p).map_err(|source| SceneError::Mesh {
                    path: self.path.clone(),
                    field: sf("file"),
                    source: Box::new(source),
                })?;
                let label = format!("{field} \"{oname}\" ({file})");
                let (data, report) =
                    mesh::clean_mesh(data, &label).map_err(|source| SceneError::Mesh {
                        path: self.path.clone(),
                        field: sf("file"),
                        source: Box::new(source),
                    })?;
                budget(
                    "the mesh (after cleaning)",
                    sf("file"),
                    data.indices.len() as u64,
                )?;
                let scene_file = self.path.display().to_string();
                self.warnings.extend(
                    report
                        .warnings
                        .into_iter()
                        .map(|w| format!("{scene_file}: {w}")),
                );
                inputs.push(p);
                (data, file.clone())
            }
            ShapeSpec::Plane { size, subdivisions } => {
                self.positive(&sf("size[0]"), size[0])?;
                self.positive(&sf("size[1]"), size[1])?;
                self.count(&sf("subdivisions"), *subdivisions, 1, MAX_SUBDIVISIONS)?;
                budget(
                    &format!("a plane with {subdivisions} subdivisions"),
                    sf("subdivisions"),
                    shapes::plane_triangles(*subdivisions),
                )?;
                (shapes::plane(*size, *subdivisions), "plane".into())
            }
            ShapeSpec::Box { size } => {
                for (k, v) in size.iter().enumerate() {
                    self.positive(&sf(&format!("size[{k}]")), *v)?;
                }
                budget("a box", sf("type"), shapes::CUBOID_TRIANGLES)?;
                (shapes::cuboid(*size), "box".into())
            }
            ShapeSpec::Sphere { radius, segments } => {
                self.positive(&sf("radius"), *radius)?;
                self.count(&sf("segments"), *segments, 3, MAX_SEGMENTS)?;
                budget(
                    &format!("a sphere with {segments} segments"),
                    sf("segments"),
                    shapes::sphere_triangles(*segments),
                )?;
                (shapes::sphere(*radius, *segments), "sphere".into())
            }
            ShapeSpec::Ring {
                radius,
                height,
                thickness,
                segments,
            } => {
                self.positive(&sf("radius"), *radius)?;
                self.positive(&sf("height"), *height)?;
                self.positive(&sf("thickness"), *thickness)?;
                self.count(&sf("segments"), *segments, 3, MAX_SEGMENTS)?;
                budget(
                    &format!("a ring with {segments} segments"),
                    sf("segments"),
                    shapes::ring_triangles(*segments),
                )?;
                (
                    shapes::ring(*radius, *height, *thickness, *segments),
                    "ring".into(),
                )
            }
        })
    }

    fn count(&self, field: &str, v: u32, lo: u32, hi: u32) -> Result<u32, SceneError> {
        if v < lo || v > hi {
            return Err(self.err(field, format!("must be between {lo} and {hi}, got {v}")));
        }
        Ok(v)
    }

    fn transform(&self, field: &str, t: &TransformSpec) -> Result<Mat4, SceneError> {
        let translate = match t.translate {
            Some(v) => self.finite3(&format!("{field}.transform.translate"), v)?,
            None => Vec3::ZERO,
        };
        let rot = match t.rotate {
            Some(v) => {
                let r = self.finite3(&format!("{field}.transform.rotate"), v)?;
                Quat::from_rotation_z(r.z.to_radians())
                    * Quat::from_rotation_y(r.y.to_radians())
                    * Quat::from_rotation_x(r.x.to_radians())
            }
            None => Quat::IDENTITY,
        };
        let sfield = format!("{field}.transform.scale");
        let scale = match t.scale {
            None => Vec3::ONE,
            Some(ScaleSpec::Uniform(s)) => Vec3::splat(s),
            Some(ScaleSpec::PerAxis(v)) => Vec3::from(v),
        };
        if !scale.is_finite() || scale.abs().min_element() < 1e-12 {
            return Err(self.err(sfield, format!("must be finite and non-zero, got {scale}")));
        }
        Ok(Mat4::from_scale_rotation_translation(scale, rot, translate))
    }
}

fn rgb(v: [f32; 3]) -> Vec3 {
    Vec3::from(v)
}

/// The exact BRDF of a material spec (validated by the caller).
pub fn material_brdf(spec: &MaterialSpec) -> Brdf {
    match *spec {
        MaterialSpec::Lambert { diffuse } => Brdf::Lambert {
            diffuse: rgb(diffuse),
        },
        MaterialSpec::Phong {
            diffuse,
            specular,
            exponent,
        } => Brdf::Phong {
            diffuse: rgb(diffuse),
            specular: rgb(specular),
            exponent,
        },
        MaterialSpec::BlinnPhong {
            diffuse,
            specular,
            exponent,
        } => Brdf::BlinnPhong {
            diffuse: rgb(diffuse),
            specular: rgb(specular),
            exponent,
        },
        MaterialSpec::Ward {
            diffuse,
            specular,
            roughness,
        } => Brdf::Ward {
            diffuse: rgb(diffuse),
            specular: rgb(specular),
            roughness,
        },
        MaterialSpec::CookTorrance {
            diffuse,
            specular,
            roughness,
            distribution,
        } => Brdf::CookTorrance {
            diffuse: rgb(diffuse),
            specular: rgb(specular),
            roughness,
            distribution: match distribution {
                DistributionSpec::Beckmann => Distribution::Beckmann,
                DistributionSpec::Ggx => Distribution::Ggx,
            },
        },
    }
}

/// Appends `data` transformed by `xf` (normals by the inverse transpose; winding flipped for
/// mirroring transforms so that it keeps agreeing with the normals).
fn append_transformed(mesh: &mut SceneMesh, data: &MeshData, xf: Mat4, object: u32) {
    let base = mesh.positions.len() as u32;
    let nmat = Mat3::from_mat4(xf).inverse().transpose();
    let mirror = Mat3::from_mat4(xf).determinant() < 0.0;
    mesh.positions
        .extend(data.positions.iter().map(|p| xf.transform_point3(*p)));
    match &data.normals {
        Some(ns) => mesh
            .normals
            .extend(ns.iter().map(|n| (nmat * *n).normalize_or_zero())),
        None => mesh
            .normals
            .extend(std::iter::repeat_n(Vec3::ZERO, data.positions.len())),
    }
    for t in &data.indices {
        let t = if mirror { [t[0], t[2], t[1]] } else { *t };
        mesh.indices.push(t.map(|i| i + base));
        mesh.tri_object.push(object);
    }
}

/// Scene-wide ray epsilon: 1e-5 of the bounding-box diagonal (at least 1e-6).
pub fn ray_epsilon(scene: &Scene) -> f32 {
    let (lo, hi) = scene.mesh.bounds();
    ((hi - lo).length() * 1e-5).max(1e-6)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = r#"
[camera]
position = [0.0, 2.0, 4.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
width = 8
height = 8
[materials.white]
model = "lambert"
diffuse = [0.5, 0.5, 0.5]
"#;

    fn load(text: &str) -> Result<Scene, SceneError> {
        Scene::from_str_at(text, Path::new("s.toml"))
    }

    /// Geometry or a camera beyond ±MAX_COORDINATE is refused with the field named; before,
    /// an object scaled by 1e25 overflowed the scene's diagonal to ∞ (reported as a bad
    /// `--max-edge` the user never gave), and a camera at 1e30 as "camera.up is parallel to the
    /// viewing direction".
    #[test]
    fn coordinates_beyond_the_limit_are_refused() {
        let sphere =
            "[[objects]]\nmaterial = \"white\"\nshape = { type = \"sphere\", radius = 0.5 }\n";
        for (extra, field) in [
            ("transform = { scale = 1e25 }", "objects[0].transform"),
            (
                "transform = { translate = [3e38, 0.0, 0.0] }",
                "objects[0].transform",
            ),
            ("transform = { scale = 2.1e8 }", "objects[0].transform"),
        ] {
            let e = load(&format!("{HEAD}{sphere}{extra}\n"))
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with(&format!("s.toml: {field}: vertex "))
                    && e.contains(", beyond ±1e8: "),
                "{e}"
            );
        }
        let e = load(&format!("{}{sphere}", HEAD.replace("4.0]", "1e30]")))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s.toml: camera.position: must lie within ±1e8"),
            "{e}"
        );
        // Up to the limit is fine, and the diagonal stays finite.
        let s = load(&format!("{HEAD}{sphere}transform = {{ scale = 1.9e8 }}\n")).unwrap();
        assert!(s.mesh.diagonal().is_finite());
        let far = load(&format!(
            "{HEAD}{sphere}transform = {{ translate = [9.9e7, -9.9e7, 9.9e7] }}\n"
        ))
        .unwrap();
        assert!(far.mesh.diagonal().is_finite());
    }
}
