//! The SG renderer on the CPU (Xu et al. 2014): direct light with exact shadows plus one bounce of
//! indirect light from spherical-Gaussian transport, either over a per-point cut of the reflector
//! tree (`sg`) or over every reflector triangle (`sg-brute`). Visibility between reflectors and
//! receivers is exact here: shadow rays per cut node (to the brightest triangles of its
//! descendants, [`NODE_VISIBILITY_DEPTH`]) or per triangle.
//!
//! Stages: tree build → per light, light every reflector triangle (exact shadow ray at its
//! centroid) and sum up the tree → primary hits → cut selection (per pixel sample, or per
//! receiver vertex) → shading. Each stage is timed; see [`SgStats`].

use super::reference::Progress;
use super::surface::{
    SurfacePoint, gpu_points, light_visible, ray_epsilon, reflected_light, reflected_light_with,
    sample_points, scatter,
};
use crate::accel::{Accel, Hit};
use crate::image::Image;
use crate::precompute::vpl::{self, Vpl};
use crate::render::{Device, Visibility};
use crate::scene::{Light, Scene};
pub use crate::settings::CutMode;
use crate::sg::node_maps::{NodeMaps, node_map_visibility};
use crate::sg::transport::receiver::{ReceiverLobes, ReceiverOptions};
use crate::sg::tree::{self, ReflectorTree};
use crate::sg::{
    CutCounters, CutEntry, CutOptions, LitScene, LitTriangle, ReflectorPiece, build_tree,
    light_anchor, light_triangles, reflector_pieces,
};
use crate::visibility::ism::{ImperfectShadowMaps, MapView, nearest_vpl_weights_among};
use crate::visibility::vsm::VarianceShadowMap;
use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Options of [`render_sg`].
#[derive(Clone, Copy, Debug)]
pub struct SgOptions {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel (1: the pixel centre; more: a stratified grid, or keyed random
    /// positions when not a square number).
    pub spp: u32,
    pub seed: u64,
    pub direct: bool,
    pub indirect: bool,
    /// Every reflector triangle instead of a cut (`sg-brute`).
    pub brute: bool,
    pub cut: CutOptions,
    pub mode: CutMode,
    /// Reflector triangles are split until their longest edge is at most this (0: never).
    pub max_edge: f32,
    /// Light visibility by shadow rays or by variance shadow maps (the scene's `[visibility]`).
    pub visibility: Visibility,
    /// Where the stages with a GPU pass run: point lights' shadow maps (`auto` or `gpu`), and
    /// with `gpu` only, the shading over vertex cuts under `--visibility approx` with maps at
    /// tree nodes and the direct light when every light has a shadow map (on lavapipe they
    /// are slower than their CPU twins so far; docs/gpu.md).
    pub device: Device,
}

/// Seconds per stage.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct SgTimes {
    pub tree: f64,
    /// Variance shadow maps (`--visibility vsm|approx`; 0 otherwise).
    pub shadow_maps: f64,
    /// The visibility maps between reflectors and receivers (`--visibility approx`): the maps
    /// at tree nodes, or the VPLs, their imperfect shadow maps and every node's 3 nearest.
    pub vpls: f64,
    pub lighting: f64,
    pub primary: f64,
    pub vertex_cuts: f64,
    /// Tile cuts (`CutMode::Tile`): selecting every group's cut and evaluating it with
    /// visibility for the group's samples; the shading pass then adds the direct light.
    pub tile_cuts: f64,
    /// The indirect light on the GPU (`render::gpu::sg_shade`, with `shading_on` "gpu …"):
    /// gathering and uploading the cuts, the shading itself, the read-back; 0 otherwise.
    pub gpu_shading: f64,
    /// The direct light on the GPU (`render::gpu::direct`, with `direct_on` "gpu …"); 0
    /// otherwise.
    pub gpu_direct: f64,
    pub shading: f64,
}

/// Statistics of an SG render.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SgStats {
    /// Where the shadow maps were made ("cpu", "gpu (adapter)", or why the GPU was not used);
    /// empty without shadow maps.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub shadow_maps_on: String,
    /// Where the indirect light was shaded, when the GPU was asked to shade it (`--device gpu`
    /// with `--cut vertex` and `--visibility approx` with maps at tree nodes): "gpu (adapter)",
    /// or "cpu (why the GPU failed)"; empty otherwise.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub shading_on: String,
    /// Where the direct light was computed: "cpu", "gpu (adapter)" (`--device gpu` with a
    /// shadow map for every light), or "cpu (why the GPU failed)"; empty without direct light.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub direct_on: String,
    /// Where the VPLs' sampling weights were computed (`--visibility approx` with the VPLs'
    /// imperfect shadow maps, `node_maps = 0`):
    /// "cpu", "gpu (adapter)" (`--device gpu` with shadow maps), or "cpu (why the GPU
    /// failed)"; empty without VPLs.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub vpls_on: String,
    /// Where the VPLs' imperfect shadow maps were splatted (`node_maps = 0`): "cpu", "gpu
    /// (adapter)" (`--device gpu`), or "cpu (why the GPU failed)"; empty without VPLs.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub ism_on: String,
    /// Per light, what the GPU shading uploaded (empty on the CPU).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub gpu_uploads: Vec<crate::render::gpu::sg_shade::ShadeUpload>,
    pub reflector_triangles: usize,
    /// Reflector triangles after splitting to `max_edge` (what the tree is built over).
    pub reflector_pieces: usize,
    pub tree_nodes: usize,
    /// Receiver points shaded (pixel samples hitting a receiver, per light).
    pub shading_points: u64,
    /// Cuts selected (per pixel sample or per vertex, per light).
    pub cuts: u64,
    pub cut_size_mean: f64,
    pub cut_size_max: u64,
    /// Cuts by size: entry i counts the cuts of 2^i to 2^(i+1) − 1 nodes (entry 0 also the
    /// empty ones), up to the largest entry used.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub cut_size_histogram: Vec<u64>,
    /// Cuts that ended at the `max_cut` cap rather than at the error threshold.
    pub cuts_at_cap: u64,
    /// Nodes whose bound and approximation were evaluated, per pixel (all samples and lights,
    /// including vertex cuts shared out over the pixels; for tile cuts, one per node and sample
    /// the kernel evaluated it at, during selection at the representatives and in shading).
    pub nodes_evaluated_per_pixel: f64,
    /// Of those, exact triangle integrations (leaves, or every triangle for `sg-brute`).
    pub leaves_evaluated_per_pixel: f64,
    /// Shadow rays between receivers and reflectors.
    pub visibility_rays: u64,
    /// Visibility maps at tree nodes (`--visibility approx`), summed over the lights.
    pub node_maps: usize,
    pub nonfinite_samples: u64,
    pub seconds: SgTimes,
    /// Whether the light stage was the previous frame's ([`render_sg_prepared`]); not in the
    /// JSON log.
    #[serde(skip)]
    pub light_stage_kept: bool,
    /// Mean cut size of each pixel's samples (row-major), for the viewer's heatmap; zeros with
    /// vertex cuts, which are selected before the pixels are shaded. Not in the JSON log.
    #[serde(skip)]
    pub pixel_cut_sizes: Vec<f32>,
}

/// Entries of `SgStats::cut_size_histogram` at most (the last holds every larger cut).
const CUT_SIZE_BUCKETS: usize = 24;

#[derive(Default)]
pub(super) struct Tally {
    pub(super) shading_points: AtomicU64,
    cuts: AtomicU64,
    cut_size_sum: AtomicU64,
    cut_size_max: AtomicU64,
    cut_size_histogram: [AtomicU64; CUT_SIZE_BUCKETS],
    cuts_at_cap: AtomicU64,
    /// The cut's size cap (`CutOptions::max_cut`; 0: none), for `cuts_at_cap`.
    pub(super) cap: u64,
    evaluated: AtomicU64,
    leaves: AtomicU64,
    pub(super) rays: AtomicU64,
    bad: AtomicU64,
}

thread_local! {
    /// Cut nodes selected on this thread so far: the pixel loop reads it before and after a
    /// pixel for the per-pixel cut sizes (`SgStats::pixel_cut_sizes`).
    static THREAD_CUT_NODES: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

impl Tally {
    pub(super) fn add_cut(&self, size: usize, c: &CutCounters) {
        THREAD_CUT_NODES.with(|n| n.set(n.get() + size as u64));
        self.cuts.fetch_add(1, Ordering::Relaxed);
        self.cut_size_sum.fetch_add(size as u64, Ordering::Relaxed);
        self.cut_size_max.fetch_max(size as u64, Ordering::Relaxed);
        let bucket = size.max(1).ilog2() as usize;
        self.cut_size_histogram[bucket.min(CUT_SIZE_BUCKETS - 1)].fetch_add(1, Ordering::Relaxed);
        if self.cap > 0 && size as u64 >= self.cap {
            self.cuts_at_cap.fetch_add(1, Ordering::Relaxed);
        }
        self.add_counters(c);
    }
    /// The histogram of cut sizes, trimmed after its last non-empty entry.
    fn cut_size_histogram(&self) -> Vec<u64> {
        let mut h: Vec<u64> = self
            .cut_size_histogram
            .iter()
            .map(|c| c.load(Ordering::Relaxed))
            .collect();
        while h.last() == Some(&0) {
            h.pop();
        }
        h
    }
    pub(super) fn add_counters(&self, c: &CutCounters) {
        self.evaluated.fetch_add(c.evaluated, Ordering::Relaxed);
        self.leaves.fetch_add(c.leaves, Ordering::Relaxed);
    }
}

/// The primary hit of sample `s` of `spp` in pixel `pixel` (row-major, `camera.width` wide).
pub(crate) fn primary_hit(
    accel: &Accel,
    camera: &crate::scene::Camera,
    spp: u32,
    seed: u64,
    pixel: usize,
    s: u32,
) -> Option<Hit> {
    let w = camera.width as usize;
    let o = sample_offset(spp, s, seed, pixel as u64);
    let dir = camera.ray_dir((pixel % w) as f32 + o.x, (pixel / w) as f32 + o.y);
    accel.intersect(camera.position, dir, 0.0, f32::INFINITY)
}

/// Every sample's primary hit, pixel after pixel (`spp` per pixel).
pub(crate) fn primary_hits(
    accel: &Accel,
    camera: &crate::scene::Camera,
    spp: u32,
    seed: u64,
) -> Vec<Option<Hit>> {
    let spp = spp.max(1);
    let n = camera.width as usize * camera.height as usize * spp as usize;
    (0..n)
        .into_par_iter()
        .map(|i| {
            primary_hit(
                accel,
                camera,
                spp,
                seed,
                i / spp as usize,
                (i % spp as usize) as u32,
            )
        })
        .collect()
}

/// Sub-pixel position of sample `s` of `spp` in pixel `pixel`.
pub(crate) fn sample_offset(spp: u32, s: u32, seed: u64, pixel: u64) -> Vec2 {
    if spp == 1 {
        return Vec2::splat(0.5);
    }
    let k = (spp as f32).sqrt().round() as u32;
    let mut rng = crate::math::Rng::keyed(seed, pixel, s as u64);
    let j = rng.vec2();
    if k * k == spp {
        Vec2::new(
            ((s % k) as f32 + j.x) / k as f32,
            ((s / k) as f32 + j.y) / k as f32,
        )
    } else {
        j
    }
}

/// Work units of [`render_sg`] for a progress bar: one per image row and pass (vertex and tile
/// cuts take a pass before the pixels').
pub fn sg_work_units(opts: &SgOptions) -> u64 {
    opts.height as u64 * if opts.mode == CutMode::Pixel { 1 } else { 2 }
}

/// Renders `scene` with the SG method. `None` when cancelled.
pub fn render_sg(
    scene: &Scene,
    accel: &Accel,
    opts: &SgOptions,
    progress: &Progress,
) -> Option<(Image, SgStats)> {
    let mut prepared = SgPrepared::build(scene, opts);
    if progress.cancel.load(Ordering::Relaxed) {
        return None;
    }
    render_sg_prepared(scene, accel, opts, &mut prepared, progress)
}

/// What `sg` computes before it sees the camera, kept between frames
/// ([`render_sg_prepared`]):
/// - the reflector pieces and their tree, which depend on the geometry, the materials'
///   albedos and `max_edge`, not on the lights or the camera;
/// - the last frame's light stage (shadow maps, the lit tree, the visibility maps), which
///   depends on the lights and the visibility settings, not on the camera: a frame from a new
///   viewpoint under the same light reuses it.
pub struct SgPrepared {
    pieces: Vec<ReflectorPiece>,
    tree: ReflectorTree,
    max_edge: f32,
    indirect: bool,
    /// Time the pieces and the tree took.
    pub seconds: f64,
    light_stage: Option<LightStage>,
}

/// The light stage of a frame, owned (a [`LitScene`] borrows the tree it lights).
struct LightStage {
    /// What it was computed for: the lights and every setting it depends on.
    key: String,
    maps: Vec<Option<VarianceShadowMap>>,
    shadow_maps_on: String,
    lit: Vec<(
        Vec<LitTriangle>,
        Vec<crate::sg::LitNode>,
        Vec3,
        ReceiverOptions,
    )>,
    vpl_vis: Vec<Option<ApproxVisibility>>,
}

impl SgPrepared {
    pub fn build(scene: &Scene, opts: &SgOptions) -> SgPrepared {
        let t = Instant::now();
        let pieces = if opts.indirect {
            reflector_pieces(scene, opts.max_edge)
        } else {
            Vec::new()
        };
        let tree = build_tree(scene, &pieces);
        SgPrepared {
            pieces,
            tree,
            max_edge: opts.max_edge,
            indirect: opts.indirect,
            seconds: t.elapsed().as_secs_f64(),
            light_stage: None,
        }
    }

    /// Whether it was built for these options (the same `max_edge`, and pieces when the
    /// indirect light is wanted).
    pub fn fits(&self, opts: &SgOptions) -> bool {
        self.max_edge.to_bits() == opts.max_edge.to_bits() && (self.indirect || !opts.indirect)
    }

    /// Number of nodes of the tree.
    pub fn tree_nodes(&self) -> usize {
        self.tree.nodes.len()
    }

    /// The bounding boxes (min, max) of the tree's nodes `depth` levels below the root (and of
    /// the leaves above that depth), for drawing the tree over the image.
    pub fn node_boxes(&self, depth: u32) -> Vec<(Vec3, Vec3)> {
        let mut out = Vec::new();
        if self.tree.is_empty() {
            return out;
        }
        let mut stack = vec![(0u32, 0u32)];
        while let Some((n, d)) = stack.pop() {
            let node = &self.tree.nodes[n as usize];
            match node.children {
                Some([l, r]) if d < depth => {
                    stack.push((l, d + 1));
                    stack.push((r, d + 1));
                }
                _ => {
                    let (mut lo, mut hi) =
                        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                    let range = node.first as usize..(node.first + node.count) as usize;
                    for &t in &self.tree.tri_order[range] {
                        for v in self.pieces[t as usize].vertices {
                            lo = lo.min(v);
                            hi = hi.max(v);
                        }
                    }
                    out.push((lo, hi));
                }
            }
        }
        out
    }
}

/// [`render_sg`] from pieces and a tree built before (`prepared`, which must fit `opts`;
/// otherwise they are built afresh), reusing its light stage when the lights and settings are
/// those of its last frame (`stats.light_stage_kept`; the stage's times are then 0);
/// `seconds.tree` is the time the pieces and tree took when they were built. The image is
/// the same as [`render_sg`]'s, bit for bit.
pub fn render_sg_prepared(
    scene: &Scene,
    accel: &Accel,
    opts: &SgOptions,
    prepared: &mut SgPrepared,
    progress: &Progress,
) -> Option<(Image, SgStats)> {
    if !prepared.fits(opts) {
        return render_sg(scene, accel, opts, progress);
    }
    let mut stats = SgStats::default();
    let eps = ray_epsilon(scene);
    let key = format!(
        "{:?}",
        (
            &scene.lights,
            opts.visibility,
            opts.device,
            opts.seed,
            opts.indirect,
            &scene.settings.vsm,
            &scene.settings.ism,
            scene.settings.vpl_count,
        )
    );
    let kept = prepared.light_stage.take().filter(|s| s.key == key);
    let (pieces, tree) = (&prepared.pieces, &prepared.tree);
    stats.seconds.tree = prepared.seconds;
    stats.reflector_triangles = scene
        .objects
        .iter()
        .filter(|o| o.reflector)
        .map(|o| o.tri_count as usize)
        .sum();
    stats.reflector_pieces = pieces.len();
    stats.tree_nodes = tree.nodes.len();
    let brute = opts.brute || !tree::needs_tree(tree.tri_order.len());

    let (maps, lits, vpl_vis) = if let Some(k) = kept {
        stats.light_stage_kept = true;
        stats.shadow_maps_on = k.shadow_maps_on;
        let lits: Vec<LitScene> = k
            .lit
            .into_iter()
            .map(|(tris, nodes, light_pos, receiver)| LitScene {
                tree,
                tris,
                nodes,
                light_pos,
                receiver,
            })
            .collect();
        (k.maps, lits, k.vpl_vis)
    } else {
        // Shadow maps (`--visibility vsm`), one per light.
        let t = Instant::now();
        let (maps, place) = shadow_maps(scene, accel, opts.visibility, opts.device);
        stats.shadow_maps_on = place;
        stats.seconds.shadow_maps = t.elapsed().as_secs_f64();

        // Light every reflector piece, per light (shadow rays or the shadow map at four points).
        let t = Instant::now();
        let rx_opts = ReceiverOptions::default();
        let lits: Vec<LitScene> = if opts.indirect && !tree.is_empty() {
            scene
                .lights
                .iter()
                .zip(&maps)
                .map(|(light, map)| {
                    light_scene(
                        scene,
                        accel,
                        pieces,
                        tree,
                        light,
                        map.as_ref(),
                        eps,
                        rx_opts,
                    )
                })
                .collect()
        } else {
            Vec::new()
        };
        stats.seconds.lighting = t.elapsed().as_secs_f64();
        if progress.cancel.load(Ordering::Relaxed) {
            return None;
        }

        // The visibility maps between reflectors and receivers (`--visibility approx`), per light:
        // at the tree's nodes, or (`node_maps = 0`) the VPLs' imperfect shadow maps.
        let t = Instant::now();
        let ism = &scene.settings.ism;
        let vpl_vis: Vec<Option<ApproxVisibility>> =
            if opts.visibility != Visibility::Approx || lits.is_empty() {
                Vec::new()
            } else if ism.node_maps > 0 {
                let far = 2.0 * scene.mesh.diagonal().max(1e-3);
                lits.iter()
                    .map(|lit| {
                        Some(ApproxVisibility::Nodes(NodeMaps::build(
                            accel,
                            lit,
                            ism.node_maps as usize,
                            ism.resolution,
                            ism.bias,
                            eps,
                            far,
                        )))
                    })
                    .collect()
            } else {
                let (vpls, place) = scene_vpls(
                    scene,
                    accel,
                    &maps,
                    scene.settings.vpl_count as usize,
                    opts.seed,
                    eps,
                    opts.device,
                );
                stats.vpls_on = place;
                let mut ism_on = String::new();
                let vis = vpls
                    .iter()
                    .enumerate()
                    .map(|(k, vpls)| {
                        let (ism, place) =
                            imperfect_shadow_maps(scene, vpls, opts.seed ^ k as u64, opts.device);
                        merge_place(&mut ism_on, place);
                        Some(ApproxVisibility::nearest_vpls(
                            scene, tree, pieces, vpls, ism,
                        ))
                    })
                    .collect();
                stats.ism_on = ism_on;
                vis
            };
        stats.seconds.vpls = t.elapsed().as_secs_f64();
        (maps, lits, vpl_vis)
    };
    stats.node_maps = vpl_vis
        .iter()
        .flatten()
        .map(ApproxVisibility::node_maps)
        .sum();
    let shadow_maps_on = stats.shadow_maps_on.clone();
    let result = shade_frame(
        scene, accel, opts, eps, tree, brute, &lits, &maps, &vpl_vis, stats, progress,
    );
    // The light stage is kept even when the frame was cancelled: the next frame (often the
    // one that cancelled it, from another viewpoint) can use it.
    prepared.light_stage = Some(LightStage {
        key,
        maps,
        shadow_maps_on,
        lit: lits
            .into_iter()
            .map(|l| (l.tris, l.nodes, l.light_pos, l.receiver))
            .collect(),
        vpl_vis,
    });
    result
}

/// The camera's part of an sg frame: primary hits, cuts and shading, from a light stage.
#[allow(clippy::too_many_arguments)]
fn shade_frame(
    scene: &Scene,
    accel: &Accel,
    opts: &SgOptions,
    eps: f32,
    tree: &ReflectorTree,
    brute: bool,
    lits: &[LitScene],
    maps: &[Option<VarianceShadowMap>],
    vpl_vis: &[Option<ApproxVisibility>],
    mut stats: SgStats,
    progress: &Progress,
) -> Option<(Image, SgStats)> {
    let camera = scene.camera.with_resolution(opts.width, opts.height);
    let w = opts.width as usize;
    let n_px = w * opts.height as usize;
    let spp = opts.spp as usize;
    // Primary hits of every sample.
    let t = Instant::now();
    let hits = primary_hits(accel, &camera, opts.spp, opts.seed);
    stats.seconds.primary = t.elapsed().as_secs_f64();
    if progress.cancel.load(Ordering::Relaxed) {
        return None;
    }

    let tally = Tally {
        cap: u64::from(opts.cut.max_cut),
        ..Tally::default()
    };
    let ctx = Ctx {
        scene,
        accel,
        eps,
        lits,
        maps,
        vpl_vis,
        leaf_of: if brute && !vpl_vis.is_empty() {
            let mut leaf_of = vec![0u32; tree.tri_order.len()];
            for (i, n) in tree.nodes.iter().enumerate() {
                if n.is_leaf() {
                    leaf_of[n.first as usize] = i as u32;
                }
            }
            leaf_of
        } else {
            Vec::new()
        },
        opts,
        brute,
        camera_pos: camera.position,
    };

    // Vertex cuts: one per light and receiver vertex seen by some sample.
    let t = Instant::now();
    let vertex_cuts = if opts.mode == CutMode::Vertex && !brute && !lits.is_empty() {
        let cuts = ctx.vertex_cuts(&hits, &tally, progress)?;
        Some(cuts)
    } else {
        None
    };
    stats.seconds.vertex_cuts = t.elapsed().as_secs_f64();

    // The indirect light over the vertex cuts on the GPU, where it can run there (asked for
    // with `--device gpu`: on lavapipe it is not yet faster than the CPU, docs/gpu.md).
    let t = Instant::now();
    let gpu_ready = opts.device == Device::Gpu
        && !vpl_vis.is_empty()
        && vpl_vis
            .iter()
            .all(|v| matches!(v, Some(ApproxVisibility::Nodes(_))));
    let gpu_indirect = match vertex_cuts.as_ref() {
        Some(vc) if gpu_ready => match ctx.gpu_indirect(&hits, vc, &tally, progress.cancel) {
            Ok(Some((shaded, adapter))) => {
                stats.shading_on = format!("gpu ({adapter})");
                stats.gpu_uploads = shaded.uploads;
                Some(shaded.radiance)
            }
            Ok(None) => return None,
            Err(e) => {
                stats.shading_on = format!("cpu (the GPU failed: {e})");
                None
            }
        },
        _ => None,
    };
    stats.seconds.gpu_shading = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let (on, gpu_direct) = direct_on_gpu(
        scene,
        opts.device,
        opts.direct,
        maps,
        &hits,
        eps,
        progress.cancel,
    )?;
    stats.direct_on = on;
    stats.seconds.gpu_direct = t.elapsed().as_secs_f64();

    // Tile cuts: the indirect light of every sample, a tile's samples of one material at once.
    let t = Instant::now();
    let tiled = opts.mode == CutMode::Tile
        && !brute
        && opts.indirect
        && !lits.is_empty()
        && gpu_indirect.is_none()
        && lits
            .iter()
            .all(|l| l.receiver == ReceiverOptions::default());
    let tile_indirect = if tiled {
        Some(match super::sg_sparse::sparse_agree() {
            Some(agree) => ctx.sparse_tile_indirect(&hits, &tally, progress, agree)?,
            None => ctx.tile_indirect(
                &hits,
                super::sg_tiles::tile_side(opts.spp),
                &ctx.tile_summaries(),
                &tally,
                progress,
            )?,
        })
    } else {
        // The pass sg_work_units counts for tile cuts, done at once.
        if opts.mode == CutMode::Tile {
            (progress.done)(opts.height as u64);
        }
        None
    };
    stats.seconds.tile_cuts = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let mut img = Image::new(opts.width, opts.height);
    let mut cut_sizes = vec![0f32; n_px];
    img.data
        .par_chunks_mut(w)
        .zip(cut_sizes.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, (row, sizes))| {
            if progress.cancel.load(Ordering::Relaxed) {
                return;
            }
            let mut scratch = Vec::new();
            for (x, (out, size)) in row.iter_mut().zip(sizes.iter_mut()).enumerate() {
                let nodes_before = THREAD_CUT_NODES.with(|n| n.get());
                // Per pixel as well as per row: a row at a high spp can take many seconds.
                if progress.cancel.load(Ordering::Relaxed) {
                    return;
                }
                let p = y * w + x;
                let mut sum = DVec3::ZERO;
                for s in 0..spp {
                    let v = ctx.shade(
                        hits[p * spp + s].as_ref(),
                        vertex_cuts.as_ref(),
                        gpu_direct.as_ref().map(|g| g[p * spp + s]),
                        gpu_indirect
                            .as_ref()
                            .or(tile_indirect.as_ref().map(|t| &t.0))
                            .map(|g| g[p * spp + s]),
                        &mut scratch,
                        &tally,
                    );
                    if v.is_finite() {
                        sum += v.as_dvec3();
                    } else {
                        tally.bad.fetch_add(1, Ordering::Relaxed);
                    }
                }
                *out = (sum / spp as f64).as_vec3();
                *size = match &tile_indirect {
                    Some((_, sizes)) => sizes[p * spp..(p + 1) * spp].iter().sum::<f32>(),
                    None => (THREAD_CUT_NODES.with(|n| n.get()) - nodes_before) as f32,
                } / spp as f32;
            }
            (progress.done)(1);
        });
    stats.seconds.shading = t.elapsed().as_secs_f64();
    stats.pixel_cut_sizes = cut_sizes;
    if progress.cancel.load(Ordering::Relaxed) {
        return None;
    }
    stats.cut_size_histogram = tally.cut_size_histogram();
    let cuts = tally.cuts.into_inner();
    stats.shading_points = tally.shading_points.into_inner();
    stats.cuts = cuts;
    stats.cut_size_mean = tally.cut_size_sum.into_inner() as f64 / cuts.max(1) as f64;
    stats.cut_size_max = tally.cut_size_max.into_inner();
    stats.cuts_at_cap = tally.cuts_at_cap.into_inner();
    stats.nodes_evaluated_per_pixel = tally.evaluated.into_inner() as f64 / n_px as f64;
    stats.leaves_evaluated_per_pixel = tally.leaves.into_inner() as f64 / n_px as f64;
    stats.visibility_rays = tally.rays.into_inner();
    stats.nonfinite_samples = tally.bad.into_inner();
    Some((img, stats))
}

/// The light's visibility at surface point `p` in [0, 1]: a shadow ray (offset `eps` towards
/// the light), or the lit fraction of the light's variance shadow map at the same offset point.
/// One variance shadow map per light, or none for each with `Visibility::Exact`.
///
/// With `device` other than [`Device::Cpu`], the maps are rasterised on the GPU
/// (`render::gpu::vsm`: a point light's cube, a spot's face, a directional light's orthographic
/// face); the returned string says where the maps were made ("cpu", "gpu (adapter
/// name)", or "cpu (the GPU failed: …)" when `Device::Auto` fell back).
pub(super) fn shadow_maps(
    scene: &Scene,
    accel: &Accel,
    visibility: Visibility,
    device: Device,
) -> (Vec<Option<VarianceShadowMap>>, String) {
    if visibility == Visibility::Exact {
        return (scene.lights.iter().map(|_| None).collect(), String::new());
    }
    let mut place = "cpu".to_string();
    let gpu = if device == Device::Cpu || scene.lights.is_empty() {
        None
    } else {
        match crate::render::gpu::Gpu::shared() {
            Ok(g) => Some(g),
            Err(e) => {
                place = format!("cpu (no GPU: {e})");
                None
            }
        }
    };
    let mapper = gpu.as_ref().and_then(|g| {
        match crate::render::gpu::vsm::ShadowMapper::new(
            g,
            &scene.mesh.positions,
            &scene.mesh.indices,
        ) {
            Ok(m) => Some(m),
            Err(e) => {
                place = format!("cpu (the GPU failed: {e})");
                None
            }
        }
    });
    let failure = std::cell::Cell::new(None::<String>);
    let raster = |setup: &crate::visibility::vsm::MapSetup, blur: u32| {
        let moments = mapper.as_ref()?.map_moments(setup, blur);
        moments.map_err(|e| failure.set(Some(e.to_string()))).ok()
    };
    let maps = scene
        .lights
        .iter()
        .map(|light| {
            Some(VarianceShadowMap::build_with(
                accel,
                scene.mesh.bounds(),
                light,
                &scene.settings.vsm,
                mapper
                    .is_some()
                    .then_some(&raster as &crate::visibility::vsm::MapRaster<'_>),
            ))
        })
        .collect();
    if let (Some(g), true) = (gpu.as_ref(), mapper.is_some()) {
        place = match failure.into_inner() {
            Some(e) => format!("cpu (the GPU failed: {e})"),
            None => format!("gpu ({})", g.adapter),
        };
    }
    (maps, place)
}

/// Direct light of every light reflected at `sp` towards `wo`, the light's visibility by a
/// shadow ray or by its shadow map (`maps[k]`, when there is one).
pub(super) fn direct_light(
    scene: &Scene,
    accel: &Accel,
    maps: &[Option<VarianceShadowMap>],
    brdf: &crate::brdf::Brdf,
    sp: &SurfacePoint,
    wo: Vec3,
    eps: f32,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    for (k, light) in scene.lights.iter().enumerate() {
        l += match maps.get(k).and_then(Option::as_ref) {
            None => reflected_light(accel, brdf, sp, wo, light, eps),
            Some(m) => reflected_light_with(brdf, sp, wo, light, |inc| {
                m.lit(sp.offset(eps) + inc.wi * eps)
            }),
        };
    }
    l
}

/// The direct light of every sample (`hits`) on the GPU (`render::gpu::direct`), with
/// `--device gpu` when every light has a shadow map: where it ran ("cpu", "gpu (adapter)",
/// "cpu (the GPU failed: …)"; empty without direct light) and the values, `None` when the CPU
/// is to compute them. `None` when cancelled.
pub(super) fn direct_on_gpu(
    scene: &Scene,
    device: Device,
    direct: bool,
    maps: &[Option<VarianceShadowMap>],
    hits: &[Option<Hit>],
    eps: f32,
    cancel: &std::sync::atomic::AtomicBool,
) -> Option<(String, Option<Vec<Vec3>>)> {
    if !direct {
        return Some((String::new(), None));
    }
    let all_mapped = !scene.lights.is_empty()
        && maps.len() == scene.lights.len()
        && maps.iter().all(Option::is_some);
    if device != Device::Gpu || !all_mapped {
        return Some(("cpu".into(), None));
    }
    let run = || -> Result<Option<(Vec<Vec3>, String)>, crate::render::gpu::GpuError> {
        let gpu = crate::render::gpu::Gpu::shared()?;
        // Points seen from the front reflect direct light; the others get none.
        let (index, points) = gpu_points(scene, hits, scene.camera.position, |_, sp, wo, wo_l| {
            sp.ng.dot(wo) > 0.0 && wo_l.z > 0.0
        });
        let materials: Vec<crate::brdf::Brdf> = scene.materials.iter().map(|m| m.brdf).collect();
        let Some(values) = crate::render::gpu::direct::direct(
            &gpu,
            &scene.lights,
            maps,
            &materials,
            &points,
            eps,
            cancel,
        )?
        else {
            return Ok(None);
        };
        Ok(Some((scatter(&index, &values), gpu.adapter.clone())))
    };
    match run() {
        Ok(Some((v, adapter))) => Some((format!("gpu ({adapter})"), Some(v))),
        Ok(None) => None,
        Err(e) => Some((format!("cpu (the GPU failed: {e})"), None)),
    }
}

/// The VPLs of every light (`vpl::generate`, `count` each, seeds `seed ^ k`), their visibility
/// from the light's shadow map or shadow rays. With `--device gpu` and a shadow map, the
/// sources' weights are computed on the GPU (`render::gpu::vpl_gen`) and the VPLs drawn from
/// them on the CPU. Also says where the weights were computed ("cpu", "gpu (adapter)", or
/// "cpu (the GPU failed: …)").
#[allow(clippy::too_many_arguments)]
pub(super) fn scene_vpls(
    scene: &Scene,
    accel: &Accel,
    maps: &[Option<VarianceShadowMap>],
    count: usize,
    seed: u64,
    eps: f32,
    device: Device,
) -> (Vec<Vec<Vpl>>, String) {
    let sources = vpl::sources(scene);
    let mut place = "cpu".to_string();
    let vpls = scene
        .lights
        .iter()
        .zip(maps)
        .enumerate()
        .map(|(k, (light, map))| {
            let visible = |p: Vec3| light_fraction(accel, light, map.as_ref(), p, eps);
            let seed = seed ^ k as u64;
            let gpu_weights = match (device, map) {
                (Device::Gpu, Some(m)) => {
                    let run = || -> Result<(Vec<f32>, String), crate::render::gpu::GpuError> {
                        let gpu = crate::render::gpu::Gpu::shared()?;
                        let w = crate::render::gpu::vpl_gen::source_weights(
                            &gpu,
                            &sources,
                            light,
                            Some(m),
                            eps,
                        )?;
                        Ok((w, gpu.adapter.clone()))
                    };
                    match run() {
                        Ok((w, adapter)) => {
                            merge_place(&mut place, format!("gpu ({adapter})"));
                            Some(w)
                        }
                        Err(e) => {
                            place = format!("cpu (the GPU failed: {e})");
                            None
                        }
                    }
                }
                _ => None,
            };
            match gpu_weights {
                Some(w) => vpl::generate_weighted(&sources, &w, light, count, seed, &visible),
                None => vpl::generate(&sources, light, count, seed, &visible),
            }
        })
        .collect();
    (vpls, place)
}

/// The imperfect shadow maps of `vpls` (the scene's `[visibility]` settings): splatted on the
/// GPU with `--device gpu` (`render::gpu::ism`), otherwise — and when the GPU fails — on the
/// CPU. Returns them and where they were made: "cpu", "gpu (adapter)" or "cpu (the GPU
/// failed: why)".
pub(super) fn imperfect_shadow_maps(
    scene: &Scene,
    vpls: &[Vpl],
    seed: u64,
    device: Device,
) -> (ImperfectShadowMaps, String) {
    let (positions, indices) = (&scene.mesh.positions, &scene.mesh.indices);
    let opts = &scene.settings.ism;
    let mut place = "cpu".to_string();
    if device == Device::Gpu {
        let run = || -> Result<(ImperfectShadowMaps, String), crate::render::gpu::GpuError> {
            let gpu = crate::render::gpu::Gpu::shared()?;
            let maps = crate::render::gpu::ism::build(&gpu, positions, indices, vpls, opts, seed)?;
            Ok((maps, gpu.adapter.clone()))
        };
        match run() {
            Ok((maps, adapter)) => return (maps, format!("gpu ({adapter})")),
            Err(e) => place = format!("cpu (the GPU failed: {e})"),
        }
    }
    let maps = ImperfectShadowMaps::build(positions, indices, vpls, opts, seed);
    (maps, place)
}

/// Folds one light's stage place into `all`: the first failure ("cpu (why)") sticks, otherwise
/// the last place.
pub(super) fn merge_place(all: &mut String, place: String) {
    if !all.starts_with("cpu (") {
        *all = place;
    }
}

/// The light's visibility at surface point `p`: a shadow ray (0 or 1), or the shadow map.
pub fn light_fraction(
    accel: &Accel,
    light: &Light,
    map: Option<&VarianceShadowMap>,
    p: Vec3,
    eps: f32,
) -> f32 {
    match map {
        None => {
            if light_visible(accel, light, p, eps) {
                1.0
            } else {
                0.0
            }
        }
        Some(m) => light.incident(p).map_or(0.0, |inc| m.lit(p + inc.wi * eps)),
    }
}

/// The reflector pieces lit by `light` (shadow rays, or its shadow map `map`) and summed up
/// `tree`.
#[allow(clippy::too_many_arguments)]
fn light_scene<'t>(
    scene: &Scene,
    accel: &Accel,
    pieces: &[ReflectorPiece],
    tree: &'t ReflectorTree,
    light: &Light,
    map: Option<&VarianceShadowMap>,
    eps: f32,
    rx_opts: ReceiverOptions,
) -> LitScene<'t> {
    let visible = |c: Vec3, _t: u32| -> f32 { light_fraction(accel, light, map, c, eps) };
    let tris = light_triangles(scene, pieces, &tree.tri_order, light, &visible);
    LitScene::new(tree, tris, light_anchor(scene, light), rx_opts)
}

/// Convenience: [`render_sg`] with no progress reporting or cancellation.
pub fn render_sg_quiet(scene: &Scene, accel: &Accel, opts: &SgOptions) -> (Image, SgStats) {
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let p = Progress {
        done: &super::reference::no_progress,
        cancel: &cancel,
    };
    render_sg(scene, accel, opts, &p).expect("not cancelled")
}

/// The visibility between reflectors and receivers for one light under `--visibility
/// approx`: ray-cast maps at tree nodes (`[visibility] node_maps` > 0, the default), or the
/// paper's proxy (`node_maps = 0`).
pub(super) enum ApproxVisibility {
    Nodes(NodeMaps),
    NearestVpls(NearestVpls),
}

/// The paper's proxy: the VPLs' imperfect shadow maps and, per tree node, the interpolation
/// weights of its 3 nearest VPLs (from the node's area-weighted centroid).
pub(super) struct NearestVpls {
    ism: ImperfectShadowMaps,
    weights: Vec<[(u32, f32); 3]>,
}

impl ApproxVisibility {
    fn nearest_vpls(
        scene: &Scene,
        tree: &ReflectorTree,
        pieces: &[ReflectorPiece],
        vpls: &[Vpl],
        ism: ImperfectShadowMaps,
    ) -> ApproxVisibility {
        let object_of = |t: u32| scene.mesh.tri_object[t as usize];
        let vpl_objects: Vec<u32> = vpls.iter().map(|v| object_of(v.tri)).collect();
        let weights = tree
            .nodes
            .par_iter()
            .map(|n| {
                // VPLs on the node's own object (that of its first piece), facing within 60° of
                // the node's normal when its normals are coherent.
                let object = object_of(pieces[tree.tri_order[n.first as usize] as usize].tri);
                let normal = (n.mean_normal.length() >= 0.5).then(|| n.mean_normal.normalize());
                let accept = |i: usize, v: &Vpl| {
                    vpl_objects[i] == object && normal.is_none_or(|m| v.normal.dot(m) >= 0.5)
                };
                nearest_vpl_weights_among(n.centroid, &accept, vpls)
            })
            .collect();
        ApproxVisibility::NearestVpls(NearestVpls { ism, weights })
    }

    /// How many maps sit at tree nodes (0 for the paper's proxy).
    fn node_maps(&self) -> usize {
        match self {
            ApproxVisibility::Nodes(m) => m.len(),
            ApproxVisibility::NearestVpls(_) => 0,
        }
    }

    /// Visibility of tree node `node` from receiver point `x`.
    pub(super) fn node(&self, node: u32, x: Vec3) -> f32 {
        self.node_view(node).at(x)
    }

    /// Tree node `node`'s visibility data resolved once, for many receiver points
    /// ([`NodeView::at`] gives what [`Self::node`] gives).
    pub(super) fn node_view(&self, node: u32) -> NodeView<'_> {
        match self {
            ApproxVisibility::Nodes(m) => NodeView::Map(m.map(node)),
            ApproxVisibility::NearestVpls(v) => NodeView::Vpls(&v.ism, &v.weights[node as usize]),
        }
    }
}

/// One tree node's approximate visibility ([`ApproxVisibility::node_view`]).
pub(super) enum NodeView<'a> {
    /// Its ray-cast map, or none (visible from everywhere).
    Map(Option<MapView<'a>>),
    /// Its nearest VPLs' imperfect shadow maps and their interpolation weights.
    Vpls(&'a ImperfectShadowMaps, &'a [(u32, f32); 3]),
}

impl NodeView<'_> {
    /// The node's visibility in [0, 1] from receiver point `x`.
    #[inline]
    pub(super) fn at(&self, x: Vec3) -> f32 {
        match self {
            NodeView::Map(m) => node_map_visibility(m.as_ref(), x),
            NodeView::Vpls(ism, weights) => ism.interpolated(weights, x),
        }
    }
}

/// How many levels below a cut node its visibility is sampled: 2^depth rays per non-leaf node.
/// Measured on the dragon at 32×24 against sg-brute (`results/sg-cpu.md`): depth 0 (one ray,
/// to the node's brightest triangle) 6.3 %, 1: 5.3 %, 2: 5.1 %, 3: 5.1 %, with shading taking
/// 0.77, 0.97, 1.25 and 1.71 s.
pub const NODE_VISIBILITY_DEPTH: u32 = 1;

/// Results of the rays to a cut node's receiver-independent targets ([`Ctx::node_targets`])
/// that a group of receivers shares: bit k of `known` says target k's result is known, bit k
/// of `visible` what it is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct SharedRays {
    pub(super) known: u8,
    pub(super) visible: u8,
}

impl SharedRays {
    /// Targets per node at most: 2^[`NODE_VISIBILITY_DEPTH`] descendants, or a leaf's four
    /// visibility points.
    pub(super) const MAX: usize = 4;
    /// Nothing shared: every ray is traced.
    pub(super) const NONE: SharedRays = SharedRays {
        known: 0,
        visible: 0,
    };

    const _FITS: () = assert!(1 << NODE_VISIBILITY_DEPTH <= SharedRays::MAX);

    /// Target k's shared result, if known.
    fn get(self, k: usize) -> Option<bool> {
        (self.known & (1 << k) != 0).then_some(self.visible & (1 << k) != 0)
    }
}

/// Cuts per light and vertex: `cuts[light][vertex]` (empty for vertices no sample needs).
type VertexCuts = Vec<Vec<Vec<u32>>>;

pub(super) struct Ctx<'a> {
    pub(super) scene: &'a Scene,
    pub(super) accel: &'a Accel,
    pub(super) eps: f32,
    pub(super) lits: &'a [LitScene<'a>],
    /// Per light: its variance shadow map (`--visibility vsm`), or none (shadow rays).
    pub(super) maps: &'a [Option<VarianceShadowMap>],
    /// Per light: the visibility maps of `--visibility approx` (empty otherwise).
    pub(super) vpl_vis: &'a [Option<ApproxVisibility>],
    /// Tree node of each leaf position (`tri_order` index), for `sg-brute` with those maps.
    pub(super) leaf_of: Vec<u32>,
    pub(super) opts: &'a SgOptions,
    pub(super) brute: bool,
    pub(super) camera_pos: Vec3,
}

impl Ctx<'_> {
    /// Light `k`'s variance shadow map, if its visibility comes from one.
    fn map(&self, k: usize) -> Option<&VarianceShadowMap> {
        self.maps.get(k).and_then(Option::as_ref)
    }

    /// Light `k`'s visibility maps between reflectors and receivers, under `--visibility
    /// approx`.
    pub(super) fn vpl_vis(&self, k: usize) -> Option<&ApproxVisibility> {
        self.vpl_vis.get(k).and_then(Option::as_ref)
    }

    /// Is the segment from the receiver (offset point `xo`) to `target` on a reflector free?
    fn visible(&self, xo: Vec3, target: Vec3) -> bool {
        let d = target - xo;
        let len = d.length();
        if !(len > 0.0) {
            return false;
        }
        self.accel
            .unoccluded(xo, d / len, 0.0, len * (1.0 - 1e-4) - self.eps)
    }

    fn rep_point(&self, lit: &LitScene, node: u32) -> Vec3 {
        let pos = lit.nodes[node as usize].rep;
        let v = lit.tris[pos as usize].vertices;
        (v[0] + v[1] + v[2]) / 3.0
    }

    /// Visibility of a non-leaf cut node from the receiver (offset point `xo`): one ray to the
    /// representative (brightest triangle) of each of the node's descendants
    /// [`NODE_VISIBILITY_DEPTH`] levels down, weighted by its subtree's light weight. Returns
    /// (fraction, rays).
    pub(super) fn node_visibility(&self, xo: Vec3, lit: &LitScene, node: u32) -> (f32, u64) {
        self.node_visibility_shared(xo, lit, node, SharedRays::NONE)
    }

    /// [`Ctx::node_visibility`] with the results of the rays to the node's targets
    /// ([`Ctx::node_targets`]) that `shared` knows taken from it instead of traced.
    pub(super) fn node_visibility_shared(
        &self,
        xo: Vec3,
        lit: &LitScene,
        node: u32,
        shared: SharedRays,
    ) -> (f32, u64) {
        let (mut num, mut den, mut rays) = (0.0f32, 0.0f32, 0u64);
        let mut k = 0;
        self.for_node_targets(lit, node, |n, w| {
            den += w;
            let seen = match shared.get(k) {
                Some(v) => v,
                None => {
                    rays += 1;
                    self.visible(xo, self.rep_point(lit, n))
                }
            };
            if seen {
                num += w;
            }
            k += 1;
        });
        (if den > 0.0 { num / den } else { 0.0 }, rays)
    }

    /// Calls `f(descendant, weight)` for the descendants of `node` whose representatives
    /// [`Ctx::node_visibility`] traces rays to, in its order.
    fn for_node_targets(&self, lit: &LitScene, node: u32, mut f: impl FnMut(u32, f32)) {
        let depth = NODE_VISIBILITY_DEPTH;
        let mut stack = [(node, 0u32); 2 << NODE_VISIBILITY_DEPTH];
        let mut len = 1;
        while len > 0 {
            len -= 1;
            let (n, d) = stack[len];
            match lit.tree.nodes[n as usize].children {
                Some([a, b]) if d < depth => {
                    stack[len] = (a, d + 1);
                    stack[len + 1] = (b, d + 1);
                    len += 2;
                }
                _ => {
                    let w = lit.nodes[n as usize].weight;
                    if w > 0.0 {
                        f(n, w);
                    }
                }
            }
        }
    }

    /// The points a cut node's visibility traces rays to whatever the receiver (at most
    /// [`SharedRays::MAX`], in the order [`Ctx::node_visibility_shared`] and
    /// [`Ctx::triangle_visibility_shared`] number them; `None` for a point they skip): the
    /// representatives of an inner node's descendants, a leaf's lit visibility points. A
    /// leaf's point along the receiver's lobe depends on the receiver and is not among them.
    pub(super) fn node_targets(
        &self,
        lit: &LitScene,
        node: u32,
    ) -> [Option<Vec3>; SharedRays::MAX] {
        let mut out = [None; SharedRays::MAX];
        let tn = &lit.tree.nodes[node as usize];
        if tn.is_leaf() {
            let t = &lit.tris[tn.first as usize];
            for (k, p) in t.visibility_points().into_iter().enumerate() {
                if t.light_mask & (1 << k) != 0 {
                    out[k] = Some(p);
                }
            }
        } else {
            let mut k = 0;
            self.for_node_targets(lit, node, |n, _| {
                out[k] = Some(self.rep_point(lit, n));
                k += 1;
            });
        }
        out
    }

    /// Is the segment from the receiver (offset point `xo`) to `target` on a reflector free?
    /// (For callers that share rays between receivers.)
    pub(super) fn ray_visible(&self, xo: Vec3, target: Vec3) -> bool {
        self.visible(xo, target)
    }

    /// Visibility factor of a reflector triangle seen from the receiver (offset point `xo`),
    /// correlated with the light's visibility on the triangle, whose mean V̄ the triangle's lobes
    /// already carry. Points p_k: the four the light's visibility was sampled at, plus the point
    /// the receiver's main lobe looks at (its axis through the triangle's plane, clamped into the
    /// triangle). With weights w_k = the receiver's BRDF towards p_k (luminance; diffuse part plus
    /// lobes), the factor is Σ w_k V_x(p_k) V_l(p_k) / (V̄ Σ w_k): a wide receiver lobe averages
    /// the points (≤ 1), a sharp one follows its own point — the specular point of a
    /// half-shadowed floor triangle is either fully lit or dark, not half lit. Returns
    /// (factor, rays).
    pub(super) fn triangle_visibility(
        &self,
        xo: Vec3,
        t: &LitTriangle,
        k_light: usize,
        rx: &ReceiverLobes,
    ) -> (f32, u64) {
        self.triangle_visibility_shared(xo, t, k_light, rx, SharedRays::NONE)
    }

    /// [`Ctx::triangle_visibility`] with the results of the rays to the triangle's lit
    /// visibility points that `shared` knows taken from it instead of traced (the point along
    /// the receiver's lobe is always traced).
    pub(super) fn triangle_visibility_shared(
        &self,
        xo: Vec3,
        t: &LitTriangle,
        k_light: usize,
        rx: &ReceiverLobes,
        shared: SharedRays,
    ) -> (f32, u64) {
        let light = &self.scene.lights[k_light];
        let map = self.map(k_light);
        let [a, b, c] = t.vertices;
        let mut rays = 0;
        let weight = |p: Vec3| -> f32 {
            let d = (p - xo).normalize_or_zero();
            let f = rx.lobes().iter().fold(rx.diffuse, |acc, h| acc + h.eval(d));
            crate::math::luminance(f).max(0.0)
        };
        let (mut num, mut den) = (0.0f32, 0.0f32);
        for (k, &p) in t.visibility_points().iter().enumerate() {
            let w = weight(p);
            den += w;
            if w > 0.0 && t.light_mask & (1 << k) != 0 {
                let seen = match shared.get(k) {
                    Some(v) => v,
                    None => {
                        rays += 1;
                        self.visible(xo, p)
                    }
                };
                if seen {
                    num += w;
                }
            }
        }
        if let Some(h) = rx.lobes().first() {
            let n = (b - a).cross(c - a);
            let denom = n.dot(h.axis);
            let s = if denom.abs() > 1e-20 {
                n.dot(a - xo) / denom
            } else {
                -1.0
            };
            let p = if s > 0.0 {
                closest_point_on_triangle(xo + h.axis * s, a, b, c)
            } else {
                closest_point_on_triangle(xo, a, b, c)
            };
            let w = weight(p);
            den += w;
            if w > 0.0 {
                rays += 1;
                let lit = if t.light_visibility >= 1.0 {
                    1.0
                } else {
                    rays += u64::from(map.is_none());
                    light_fraction(self.accel, light, map, p, self.eps)
                };
                if lit > 0.0 && self.visible(xo, p) {
                    num += w * lit;
                }
            }
        }
        if !(den > 0.0) || !(t.light_visibility > 0.0) {
            return (0.0, rays);
        }
        (num / (den * t.light_visibility), rays)
    }

    /// Radiance of one pixel sample; `direct` and `indirect` are its direct and indirect light
    /// when the GPU computed them.
    fn shade(
        &self,
        hit: Option<&Hit>,
        vertex_cuts: Option<&VertexCuts>,
        direct: Option<Vec3>,
        indirect: Option<Vec3>,
        scratch: &mut Vec<CutEntry>,
        tally: &Tally,
    ) -> Vec3 {
        let Some(hit) = hit else {
            return Vec3::ZERO;
        };
        let wo = (self.camera_pos - self.scene.mesh.point(hit.tri, hit.u, hit.v)).normalize();
        let Some(sp) = SurfacePoint::from_hit(self.scene, hit, wo) else {
            return Vec3::ZERO;
        };
        let brdf = self.scene.tri_material(hit.tri);
        let mut l = Vec3::ZERO;
        if self.opts.direct {
            l += match direct {
                Some(d) => d,
                None => direct_light(self.scene, self.accel, self.maps, brdf, &sp, wo, self.eps),
            };
        }
        if let Some(v) = indirect {
            return l + v;
        }
        if !self.opts.indirect || !self.scene.tri_object(hit.tri).receiver {
            return l;
        }
        let rx = ReceiverLobes::new(brdf, sp.frame.n, wo);
        if rx.is_black() {
            return l;
        }
        let xo = sp.offset(self.eps);
        let mut rays = 0u64;
        for (k, lit) in self.lits.iter().enumerate() {
            tally.shading_points.fetch_add(1, Ordering::Relaxed);
            if self.brute {
                let mut c = CutCounters::default();
                for (pos, t) in lit.tris.iter().enumerate() {
                    if t.sg.is_none() {
                        continue;
                    }
                    c.evaluated += 1;
                    c.leaves += 1;
                    let v = t.shade(sp.p, &rx, &lit.receiver);
                    if v != Vec3::ZERO {
                        let f = match self.vpl_vis(k) {
                            Some(vv) => vv.node(self.leaf_of[pos], xo),
                            None => {
                                let (f, r) = self.triangle_visibility(xo, t, k, &rx);
                                rays += r;
                                f
                            }
                        };
                        l += v * f;
                    }
                }
                tally.add_counters(&c);
                continue;
            }
            let mut c = CutCounters::default();
            match vertex_cuts {
                Some(vc) => {
                    let vid = nearest_vertex(self.scene, hit);
                    let nodes = &vc[k][vid as usize];
                    lit.evaluate(nodes.iter().copied(), sp.p, &rx, scratch, &mut c);
                    tally.add_counters(&c);
                }
                None => {
                    lit.select(sp.p, &rx, &self.opts.cut, scratch, &mut c);
                    tally.add_cut(scratch.len(), &c);
                }
            }
            for e in scratch.iter() {
                if e.value == Vec3::ZERO {
                    continue;
                }
                if let Some(vv) = self.vpl_vis(k) {
                    l += e.value * vv.node(e.node, xo);
                    continue;
                }
                let n = &lit.tree.nodes[e.node as usize];
                if n.is_leaf() {
                    let t = &lit.tris[n.first as usize];
                    let (f, r) = self.triangle_visibility(xo, t, k, &rx);
                    rays += r;
                    l += e.value * f;
                } else {
                    let (f, r) = self.node_visibility(xo, lit, e.node);
                    rays += r;
                    l += e.value * f;
                }
            }
        }
        tally.rays.fetch_add(rays, Ordering::Relaxed);
        l
    }

    /// The indirect light of every pixel sample over the vertex cuts `cuts`, shaded on the GPU
    /// (`render::gpu::sg_shade`) with the maps at tree nodes (`radiance` per sample), with the
    /// adapter's name. `Ok(None)` when cancelled.
    fn gpu_indirect(
        &self,
        hits: &[Option<Hit>],
        cuts: &VertexCuts,
        tally: &Tally,
        cancel: &std::sync::atomic::AtomicBool,
    ) -> Result<Option<(crate::render::gpu::sg_shade::Shaded, String)>, crate::render::gpu::GpuError>
    {
        use crate::render::gpu::sg_shade::{self, LightCuts, ShadePoint};
        let gpu = crate::render::gpu::Gpu::shared()?;
        let (index, points) = sample_points(self.scene, hits, self.camera_pos, |hit, sp, wo, _| {
            if !self.scene.tri_object(hit.tri).receiver {
                return None;
            }
            let rx = ReceiverLobes::new(self.scene.tri_material(hit.tri), sp.frame.n, wo);
            (!rx.is_black()).then(|| ShadePoint {
                x: sp.p,
                xo: sp.offset(self.eps),
                vertex: nearest_vertex(self.scene, hit),
                rx,
            })
        });
        let lights: Vec<LightCuts> = self
            .lits
            .iter()
            .zip(cuts)
            .zip(self.vpl_vis)
            .filter_map(|((lit, cuts), vis)| match vis {
                Some(ApproxVisibility::Nodes(maps)) => Some(LightCuts { lit, maps, cuts }),
                _ => None,
            })
            .collect();
        let Some(sg_shade::Shaded {
            radiance: values,
            uploads,
        }) = sg_shade::shade(&gpu, &lights, &points, cancel)?
        else {
            return Ok(None);
        };
        // The same counts the CPU's evaluation of the cuts makes.
        for (lit, cuts) in self.lits.iter().zip(cuts) {
            let (evaluated, leaves) = points
                .par_iter()
                .map(|p| {
                    let cut = &cuts[p.vertex as usize];
                    let leaves = cut
                        .iter()
                        .filter(|&&n| lit.tree.nodes[n as usize].is_leaf())
                        .count();
                    (cut.len() as u64, leaves as u64)
                })
                .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
            tally
                .shading_points
                .fetch_add(points.len() as u64, Ordering::Relaxed);
            tally.add_counters(&CutCounters { evaluated, leaves });
        }
        let radiance = scatter(&index, &values);
        Ok(Some((
            sg_shade::Shaded { radiance, uploads },
            gpu.adapter.clone(),
        )))
    }

    /// Selects a cut at every receiver vertex that some sample's nearest vertex is.
    fn vertex_cuts(
        &self,
        hits: &[Option<Hit>],
        tally: &Tally,
        progress: &Progress,
    ) -> Option<VertexCuts> {
        let mesh = &self.scene.mesh;
        // The triangle each needed vertex is shaded with (its material and orientation).
        let mut owner: Vec<u32> = vec![u32::MAX; mesh.positions.len()];
        for h in hits.iter().flatten() {
            if self.scene.tri_object(h.tri).receiver {
                owner[nearest_vertex(self.scene, h) as usize] = h.tri;
            }
        }
        let needed: Vec<u32> = (0..owner.len() as u32)
            .filter(|&v| owner[v as usize] != u32::MAX)
            .collect();
        let mut out = Vec::new();
        let rows = self.opts.height as u64;
        let per_row = needed.len().div_ceil(rows.max(1) as usize).max(1);
        for lit in self.lits {
            let mut cuts: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
            let chunks: Vec<Vec<(u32, Vec<u32>)>> = needed
                .par_chunks(per_row)
                .map(|chunk| {
                    let mut scratch = Vec::new();
                    let mut res = Vec::with_capacity(chunk.len());
                    if progress.cancel.load(Ordering::Relaxed) {
                        return res;
                    }
                    for &v in chunk {
                        let tri = owner[v as usize];
                        let p = mesh.positions[v as usize];
                        let wo = (self.camera_pos - p).normalize_or_zero();
                        let mut ng = mesh.tri_cross(tri).normalize_or_zero();
                        let mut n = mesh.normals[v as usize];
                        if ng.dot(wo) < 0.0 {
                            ng = -ng;
                            n = -n;
                        }
                        if !(n.dot(ng) > 0.0) {
                            n = ng;
                        }
                        let rx = ReceiverLobes::new(self.scene.tri_material(tri), n, wo);
                        let mut c = CutCounters::default();
                        lit.select(p, &rx, &self.opts.cut, &mut scratch, &mut c);
                        tally.add_cut(scratch.len(), &c);
                        let mut nodes: Vec<u32> = scratch.iter().map(|e| e.node).collect();
                        if nodes.is_empty() {
                            // A black receiver at the vertex: shade pixels with the root.
                            nodes.push(0);
                        }
                        res.push((v, nodes));
                    }
                    if self.lits.len() == 1 {
                        (progress.done)(1);
                    }
                    res
                })
                .collect();
            for (v, nodes) in chunks.into_iter().flatten() {
                cuts[v as usize] = nodes;
            }
            out.push(cuts);
        }
        if progress.cancel.load(Ordering::Relaxed) {
            return None;
        }
        Some(out)
    }
}

/// The vertex of the hit triangle with the largest barycentric weight.
fn nearest_vertex(scene: &Scene, h: &Hit) -> u32 {
    let idx = scene.mesh.indices[h.tri as usize];
    let w = [1.0 - h.u - h.v, h.u, h.v];
    let k = if w[0] >= w[1] && w[0] >= w[2] {
        0
    } else if w[1] >= w[2] {
        1
    } else {
        2
    };
    idx[k]
}

/// The point of triangle (a, b, c) closest to p (Ericson, Real-Time Collision Detection, 5.1.5).
fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
#[path = "sg_probes.rs"]
mod probes;
