//! Per-pixel SG shading over the cut on the GPU (`shaders/sg_shade.wgsl`): for every pixel
//! sample on a receiver, the sum over its cut's nodes of the node's SG contribution (a leaf's
//! exact transport over the triangle's solid angle, an inner node's clustered approximation
//! clamped to its bound) times the node's visibility from the maps at tree nodes. Its Rust
//! twin is the shading stage of `render::cpu::sg` with `--visibility approx` and `--cut
//! vertex`; cuts are selected per receiver vertex on the CPU and handed over.
//!
//! Two passes: `sg_shade` evaluates one (point, cut node) pair per invocation and
//! `sg_shade_sum` adds up each point's pairs. Not one invocation per point, because lavapipe ends
//! every loop of an invocation once its loops together have run 65,535 iterations (llvmpipe's
//! `LP_MAX_TGSI_LOOP_ITERATIONS`, shared by every loop of a shader), and one leaf's transport
//! takes about a thousand: a per-point loop over a 141-leaf cut silently stopped after ~60.
//! `sg_shade` has two entry points, one for the (point, leaf) pairs and one (`sg_shade_clusters`)
//! for the (point, inner node) pairs, each cut listing its leaves first: lavapipe runs all the
//! code an entry point can reach, so inner nodes evaluated beside the leaf transport paid for it
//! (the stage took 25–30 % longer).
//!
//! Only what the cuts use is uploaded: the nodes that appear in some needed vertex's cut, the
//! leaves among them and the maps they read, renumbered, so that the buffers stay far below
//! the binding limit (128 MiB on lavapipe) whatever the tree's size. Pairs are dispatched in
//! chunks of at most [`PAIR_CHUNK`] (whole points each), with a wait after each, so that no
//! single submission runs long and a cancelled render stops between chunks.

use super::layout::{
    GpuLeaf, GpuLitNode, GpuMapOrigin, GpuNodeBound, GpuNodeLobe, GpuReceiver, GpuSg,
    GpuShadeParams, GpuShadePoint,
};
use super::{Gpu, GpuError, describe, f32s};
use crate::sg::node_maps::NodeMaps;
use crate::sg::transport::receiver::ReceiverLobes;
use crate::sg::{LitScene, LitTriangle};
use glam::Vec3;
use std::sync::atomic::{AtomicBool, Ordering};
use wgpu::util::DeviceExt;

/// (Point, cut node) pairs per dispatch, at most.
pub const PAIR_CHUNK: usize = 1 << 18;

/// The largest cut the GPU sums (the summing loop must stay well inside lavapipe's 65,535
/// iterations per invocation).
pub const MAX_GPU_CUT: usize = 60_000;

/// One pixel sample to shade: its point, the offset point visibility is looked up from, the
/// receiver vertex whose cut it evaluates, and its BRDF lobes.
#[derive(Clone, Copy, Debug)]
pub struct ShadePoint {
    pub x: Vec3,
    pub xo: Vec3,
    pub vertex: u32,
    pub rx: ReceiverLobes,
}

/// One light's lit tree, its maps at tree nodes and its cut per receiver vertex
/// (`cuts[vertex]`, tree node indices; empty for vertices no point needs).
pub struct LightCuts<'a> {
    pub lit: &'a LitScene<'a>,
    pub maps: &'a NodeMaps,
    pub cuts: &'a [Vec<u32>],
}

/// What one light's shading uploaded (for the log).
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct ShadeUpload {
    /// Distinct tree nodes in the cuts, of which leaves, and maps they read.
    pub nodes: usize,
    pub leaves: usize,
    pub maps: usize,
    /// Bytes uploaded for the light.
    pub bytes: u64,
}

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "sg shading".into(),
        reason: reason.into(),
    }
}

impl GpuLeaf {
    /// A lit triangle and its reflected lobes (zero, `has_sg` 0, when unlit).
    pub fn new(t: &LitTriangle) -> GpuLeaf {
        let [v0, v1, v2] = t.vertices.map(|v| v.to_array());
        let mut g = GpuLeaf {
            v0,
            v1,
            v2,
            ..GpuLeaf::default()
        };
        if let Some(s) = &t.sg {
            g.has_sg = 1;
            g.lobe_count = s.len.min(4) as u32;
            g.half_vector = u32::from(s.half_vector);
            g.diffuse = s.diffuse.to_array();
            g.stretch = s.stretch;
            g.normal = s.normal.to_array();
            g.geometric_normal = s.geometric_normal.to_array();
            g.origin = s.origin.to_array();
            g.light = s.light.to_array();
            for (slot, l) in g.lobes.iter_mut().zip(s.lobes()) {
                *slot = GpuSg::from(*l);
            }
        }
        g
    }
}

impl GpuLitNode {
    /// Node `i` of a lit scene; `leaf` and `map` index the uploaded leaves and maps.
    pub fn new(lit: &LitScene, i: u32, leaf: u32, map: u32) -> GpuLitNode {
        let l = &lit.nodes[i as usize];
        let centroid = if l.weight > 0.0 {
            l.centroid_sum / l.weight
        } else {
            Vec3::ZERO
        };
        let mut lobes = [GpuNodeLobe::default(); 4];
        for (slot, nl) in lobes.iter_mut().zip(&l.lobes) {
            *slot = GpuNodeLobe {
                energy: nl.energy.to_array(),
                inv_sharpness_sum: nl.inv_sharpness_sum,
                axis_sum: nl.axis_sum.to_array(),
                _pad: 0.0,
            };
        }
        GpuLitNode {
            bound: GpuNodeBound::new(lit, i),
            centroid: centroid.to_array(),
            weight: l.weight,
            normal_sum: l.normal_sum.to_array(),
            area: l.area,
            diffuse: l.diffuse.to_array(),
            leaf,
            lobes,
            half_vector: u32::from(l.half_vector),
            map,
            _pad0: 0,
            _pad1: 0,
        }
    }
}

/// One light's buffers' contents.
struct LightData {
    params: GpuShadeParams,
    points: Vec<GpuShadePoint>,
    cut_nodes: Vec<u32>,
    nodes: Vec<GpuLitNode>,
    leaves: Vec<GpuLeaf>,
    origins: Vec<GpuMapOrigin>,
    atlas: Vec<[f32; 2]>,
}

/// Gathers what `light` needs for `points`: the needed vertices' cuts, renumbered.
fn gather(light: &LightCuts, points: &[ShadePoint]) -> Result<LightData, GpuError> {
    let lit = light.lit;
    let tree = lit.tree;
    let (ism, map_of) = light.maps.parts();
    let crate::visibility::ism::MapParts {
        res,
        origins: map_origins,
        atlas,
        min_variance,
        bias,
    } = ism.parts();
    let mut node_id = vec![u32::MAX; tree.nodes.len()];
    let mut map_id = vec![u32::MAX; map_origins.len()];
    let mut range: Vec<(u32, u32)> = vec![(u32::MAX, 0); light.cuts.len()];
    let mut leaves_in: Vec<u32> = vec![0; light.cuts.len()];
    let mut leaf_pairs = 0u64;
    let mut d = LightData {
        params: GpuShadeParams {
            light_pos: lit.light_pos.to_array(),
            map_res: res as u32,
            map_bias: bias,
            ..GpuShadeParams::default()
        },
        points: Vec::with_capacity(points.len()),
        cut_nodes: Vec::new(),
        nodes: Vec::new(),
        leaves: Vec::new(),
        origins: Vec::new(),
        atlas: Vec::new(),
    };
    let mut pairs = 0u64;
    for p in points {
        let v = p.vertex as usize;
        let Some(cut) = light.cuts.get(v) else {
            return Err(failed(format!("vertex {v} has no cut")));
        };
        if cut.len() > MAX_GPU_CUT {
            return Err(failed(format!(
                "a cut of {} nodes: the GPU sums at most {MAX_GPU_CUT}; set [sg] max_cut lower or render with --device cpu",
                cut.len()
            )));
        }
        if range[v].0 == u32::MAX {
            // Leaves first (the `sg_shade` entry point), then inner nodes
            // (`sg_shade_clusters`), each in cut order.
            let (leaf_nodes, inner_nodes): (Vec<u32>, Vec<u32>) =
                cut.iter().partition(|&&n| tree.nodes[n as usize].is_leaf());
            range[v] = (d.cut_nodes.len() as u32, cut.len() as u32);
            leaves_in[v] = leaf_nodes.len() as u32;
            for &n in leaf_nodes.iter().chain(&inner_nodes) {
                let slot = &mut node_id[n as usize];
                if *slot == u32::MAX {
                    *slot = d.nodes.len() as u32;
                    let tn = &tree.nodes[n as usize];
                    let leaf = if tn.is_leaf() {
                        d.leaves.push(GpuLeaf::new(&lit.tris[tn.first as usize]));
                        (d.leaves.len() - 1) as u32
                    } else {
                        u32::MAX
                    };
                    let map = match map_of.get(n as usize) {
                        Some(&m) if m != u32::MAX => {
                            let id = &mut map_id[m as usize];
                            if *id == u32::MAX {
                                *id = d.origins.len() as u32;
                                let (pos, frame) = map_origins[m as usize];
                                d.origins.push(GpuMapOrigin {
                                    position: pos.to_array(),
                                    min_variance: min_variance[m as usize],
                                    t: frame.t.to_array(),
                                    b: frame.b.to_array(),
                                    n: frame.n.to_array(),
                                    ..GpuMapOrigin::default()
                                });
                                let texels = res * res;
                                d.atlas.extend(
                                    atlas[m as usize * texels..(m as usize + 1) * texels]
                                        .iter()
                                        .map(|t| t.to_array()),
                                );
                            }
                            *id
                        }
                        _ => u32::MAX,
                    };
                    d.nodes.push(GpuLitNode::new(lit, n, leaf, map));
                }
                d.cut_nodes.push(*slot);
            }
        }
        let (start, count) = range[v];
        let leaf_count = leaves_in[v];
        if pairs + u64::from(count) > u64::from(u32::MAX) {
            return Err(failed(format!(
                "more than {} (point, cut node) pairs",
                u32::MAX
            )));
        }
        d.points.push(GpuShadePoint {
            x: p.x.to_array(),
            cut_start: start,
            xo: p.xo.to_array(),
            cut_count: count,
            across: p.rx.across().to_array(),
            pair_start: pairs as u32,
            receiver: GpuReceiver::new(&p.rx),
            leaf_count,
            leaf_pair_start: leaf_pairs as u32,
            _pad0: 0,
            _pad1: 0,
        });
        pairs += u64::from(count);
        leaf_pairs += u64::from(leaf_count);
    }
    // Empty buffers cannot be bound: one unused element each.
    if d.cut_nodes.is_empty() {
        d.cut_nodes.push(0);
    }
    if d.nodes.is_empty() {
        d.nodes.push(GpuLitNode::default());
    }
    if d.leaves.is_empty() {
        d.leaves.push(GpuLeaf::default());
    }
    if d.origins.is_empty() {
        d.origins.push(GpuMapOrigin::default());
        d.atlas.push([0.0; 2]);
    }
    Ok(d)
}

/// What [`shade`] returns.
pub struct Shaded {
    /// The indirect radiance of every point, summed over the lights.
    pub radiance: Vec<Vec3>,
    /// Per light, what was uploaded.
    pub uploads: Vec<ShadeUpload>,
}

/// The indirect radiance of every point, summed over `lights`, on the GPU. `None` when
/// `cancel` was set (checked between chunks).
pub fn shade(
    gpu: &Gpu,
    lights: &[LightCuts],
    points: &[ShadePoint],
    cancel: &AtomicBool,
) -> Result<Option<Shaded>, GpuError> {
    if points.is_empty() || lights.is_empty() {
        return Ok(Some(Shaded {
            radiance: vec![Vec3::ZERO; points.len()],
            uploads: Vec::new(),
        }));
    }
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let layout = {
        use wgpu::BufferBindingType::{Storage, Uniform};
        let read = Storage { read_only: true };
        gpu.buffer_layout(
            "sg_shade",
            &[
                Uniform,
                read,
                read,
                read,
                read,
                read,
                read,
                Storage { read_only: false },
            ],
        )
    };
    let leaf_pipeline = gpu.compute_entry("sg_shade", "sg_shade", Some(&layout));
    let cluster_pipeline = gpu.compute_entry("sg_shade", "sg_shade_clusters", Some(&layout));
    let sum_pipeline = gpu.compute_pipeline("sg_shade_sum");
    let out_bytes = (points.len() * 16) as u64;
    if out_bytes > gpu.max_binding {
        return Err(failed(format!(
            "{} points exceed the largest binding ({} bytes)",
            points.len(),
            gpu.max_binding
        )));
    }
    let radiance = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sg radiance"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let pair_values = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("sg pair values"),
        size: (PAIR_CHUNK * 16) as u64,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let mut uploads = Vec::new();
    for light in lights {
        let d = gather(light, points)?;
        let storage = |label: &str, bytes: &[u8]| {
            gpu.storage_buffer(
                "sg shading",
                label,
                bytes,
                "render with --device cpu or fewer node maps",
            )
        };
        let bufs = [
            storage("points", bytemuck::cast_slice(&d.points))?,
            storage("cut nodes", bytemuck::cast_slice(&d.cut_nodes))?,
            storage("nodes", bytemuck::cast_slice(&d.nodes))?,
            storage("leaves", bytemuck::cast_slice(&d.leaves))?,
            storage("map origins", bytemuck::cast_slice(&d.origins))?,
            storage("node maps", bytemuck::cast_slice(&d.atlas))?,
        ];
        uploads.push(ShadeUpload {
            nodes: d.nodes.len(),
            leaves: d.leaves.len(),
            maps: d.origins.len(),
            bytes: bufs.iter().map(|b| b.size()).sum(),
        });
        // Whole points per dispatch, at most PAIR_CHUNK pairs.
        let mut point_first = 0usize;
        while point_first < d.points.len() {
            if cancel.load(Ordering::Relaxed) {
                return Ok(None);
            }
            let first = d.points[point_first].pair_start as usize;
            let mut point_end = point_first;
            while point_end < d.points.len() {
                let p = &d.points[point_end];
                if p.pair_start as usize + p.cut_count as usize - first > PAIR_CHUNK {
                    break;
                }
                point_end += 1;
            }
            let (head, last) = (&d.points[point_first], &d.points[point_end - 1]);
            let count = last.pair_start as usize + last.cut_count as usize - first;
            let leaf_first = head.leaf_pair_start as usize;
            let leaves = last.leaf_pair_start as usize + last.leaf_count as usize - leaf_first;
            let params = GpuShadeParams {
                count: leaves as u32,
                first: first as u32,
                point_first: point_first as u32,
                point_end: point_end as u32,
                leaf_first: leaf_first as u32,
                cluster_count: (count - leaves) as u32,
                cluster_first: (first - leaf_first) as u32,
                ..d.params
            };
            let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sg shade params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind = gpu.bind_buffers(
                &leaf_pipeline.get_bind_group_layout(0),
                &[
                    &params_buf,
                    &bufs[0],
                    &bufs[1],
                    &bufs[2],
                    &bufs[3],
                    &bufs[4],
                    &bufs[5],
                    &pair_values,
                ],
            );
            let sum_bind = gpu.bind_buffers(
                &sum_pipeline.get_bind_group_layout(0),
                &[&params_buf, &bufs[0], &pair_values, &radiance],
            );
            let mut enc =
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
            for (p, b, n) in [
                (&leaf_pipeline, &bind, leaves),
                (&cluster_pipeline, &bind, count - leaves),
                (&sum_pipeline, &sum_bind, point_end - point_first),
            ] {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("sg_shade"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(p);
                pass.set_bind_group(0, b, &[]);
                pass.dispatch_workgroups((n as u32).div_ceil(64).max(1), 1, 1);
            }
            gpu.queue.submit([enc.finish()]);
            gpu.wait("sg shading")?;
            point_first = point_end;
        }
    }
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(failed(describe(&e)));
    }
    let data = gpu.read_back(&radiance, out_bytes, "sg shading")?;
    gpu.check("sg shading")?;
    let radiance = f32s(&data)
        .chunks_exact(4)
        .map(|v| Vec3::new(v[0], v[1], v[2]))
        .collect();
    Ok(Some(Shaded { radiance, uploads }))
}
