//! The WGSL math functions (`shaders/shared/math.wgsl`) next to their Rust twins: [`run`]
//! evaluates one of them on the GPU over a table of inputs (`shaders/math_twins.wgsl`), [`cpu`]
//! evaluates the Rust twin of the same name over the same table, and the GPU tests compare them.
//! The cut's bound, whose inputs are a tree node and a receiver, has its own pair:
//! [`run_node_bound`] against `cut::node_bound`.

use super::layout::{GpuLeaf, GpuLitNode, GpuNodeBound, GpuReceiver, TwinParams, TwinQuery};
use super::{Gpu, GpuError, describe, f32s};
use crate::math::sg::{Sg, lobe_integral};
use glam::{Vec2, Vec3};
use wgpu::util::DeviceExt;

/// A function with a WGSL twin; its index is the shader's `params.function`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Twin {
    /// `math::sg::lobe_integral(a.x)`.
    LobeIntegral = 0,
    /// `Sg::inner_product`: lobe (a.xyz axis, a.w λ, b.xyz amplitude) with (c, d) likewise.
    SgInnerProduct = 1,
    /// `visibility::vsm::chebyshev_upper_bound((a.x, a.y), a.z, a.w)`.
    ChebyshevUpperBound = 2,
    /// `visibility::vsm::reduce_bleeding(a.x, a.y)`.
    ReduceBleeding = 3,
    /// `cut::clamped_cosine_mean(a.x, a.y)`.
    ClampedCosineMean = 4,
    /// `math::spherical_triangle::integrate_sg(a.xyz axis, a.w λ, b.xyz, c.xyz, d.xyz)`.
    IntegrateSg = 5,
    /// `transport::receiver::cosine_weighted`: the unit-amplitude lobe (a.xyz axis, a.w λ) times
    /// n·ω over the triangle (b.xyz, c.xyz, d.xyz), n = (b.w, c.w, d.w).
    CosineWeighted = 9,
    /// `Brdf::eval(wo = a.xyz, wi = b.xyz)` of the material in [`brdf_row`]'s encoding: model
    /// a.w, parameter b.w, diffuse c.xyz, distribution c.w, specular d.xyz.
    BrdfEval = 10,
}

impl Twin {
    pub const ALL: [Twin; 8] = [
        Twin::LobeIntegral,
        Twin::SgInnerProduct,
        Twin::ChebyshevUpperBound,
        Twin::ReduceBleeding,
        Twin::ClampedCosineMean,
        Twin::IntegrateSg,
        Twin::CosineWeighted,
        Twin::BrdfEval,
    ];

    /// The WGSL function's name (the Rust twin's, a method `T::f` as `t_f`).
    pub fn wgsl_name(self) -> &'static str {
        match self {
            Twin::LobeIntegral => "lobe_integral",
            Twin::SgInnerProduct => "sg_inner_product",
            Twin::ChebyshevUpperBound => "chebyshev_upper_bound",
            Twin::ReduceBleeding => "reduce_bleeding",
            Twin::ClampedCosineMean => "clamped_cosine_mean",
            Twin::IntegrateSg => "integrate_sg",
            Twin::CosineWeighted => "cosine_weighted",
            Twin::BrdfEval => "brdf_eval",
        }
    }
}

/// A [`Twin::BrdfEval`] row: `brdf` evaluated at (wo, wi).
pub fn brdf_row(brdf: &crate::brdf::Brdf, wo: Vec3, wi: Vec3) -> TwinQuery {
    let g = super::layout::GpuBrdf::from(brdf);
    TwinQuery {
        a: [wo.x, wo.y, wo.z, g.model as f32],
        b: [wi.x, wi.y, wi.z, g.param],
        c: [
            g.diffuse[0],
            g.diffuse[1],
            g.diffuse[2],
            g.distribution as f32,
        ],
        d: [g.specular[0], g.specular[1], g.specular[2], 0.0],
    }
}

/// The material of a [`brdf_row`].
fn row_brdf(q: &TwinQuery) -> crate::brdf::Brdf {
    use crate::brdf::{Brdf, Distribution};
    let (diffuse, specular, p) = (v3(q.c), v3(q.d), q.b[3]);
    match q.a[3] as u32 {
        0 => Brdf::Lambert { diffuse },
        1 => Brdf::Phong {
            diffuse,
            specular,
            exponent: p,
        },
        2 => Brdf::BlinnPhong {
            diffuse,
            specular,
            exponent: p,
        },
        3 => Brdf::Ward {
            diffuse,
            specular,
            roughness: p,
        },
        _ => Brdf::CookTorrance {
            diffuse,
            specular,
            roughness: p,
            distribution: if q.c[3] == 1.0 {
                Distribution::Ggx
            } else {
                Distribution::Beckmann
            },
        },
    }
}

fn v3(a: [f32; 4]) -> Vec3 {
    Vec3::new(a[0], a[1], a[2])
}

/// The Rust twin of `twin` on one row (unused result lanes are 0).
pub fn cpu(twin: Twin, q: &TwinQuery) -> [f32; 4] {
    let one = |x: f32| [x, 0.0, 0.0, 0.0];
    match twin {
        Twin::LobeIntegral => one(lobe_integral(q.a[0])),
        Twin::SgInnerProduct => {
            let a = Sg::new(v3(q.a), q.a[3], v3(q.b));
            let b = Sg::new(v3(q.c), q.c[3], v3(q.d));
            let r = a.inner_product(&b);
            [r.x, r.y, r.z, 0.0]
        }
        Twin::ChebyshevUpperBound => one(crate::visibility::vsm::chebyshev_upper_bound(
            Vec2::new(q.a[0], q.a[1]),
            q.a[2],
            q.a[3],
        )),
        Twin::ReduceBleeding => one(crate::visibility::vsm::reduce_bleeding(q.a[0], q.a[1])),
        Twin::ClampedCosineMean => one(crate::sg::clamped_cosine_mean(q.a[0], q.a[1])),
        Twin::IntegrateSg => one(crate::math::spherical_triangle::integrate_sg(
            v3(q.a),
            q.a[3],
            v3(q.b),
            v3(q.c),
            v3(q.d),
        )),
        Twin::CosineWeighted => one(crate::sg::transport::receiver::cosine_weighted(
            &Sg::new(v3(q.a), q.a[3], Vec3::ONE),
            Vec3::new(q.b[3], q.c[3], q.d[3]),
            v3(q.b),
            v3(q.c),
            v3(q.d),
        )),
        Twin::BrdfEval => {
            let f = row_brdf(q).eval(v3(q.a), v3(q.b));
            [f.x, f.y, f.z, 0.0]
        }
    }
}

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "math twins".into(),
        reason: reason.into(),
    }
}

/// The WGSL twin of `twin` over `queries`, on the GPU.
pub fn run(gpu: &Gpu, twin: Twin, queries: &[TwinQuery]) -> Result<Vec<[f32; 4]>, GpuError> {
    let node = [GpuNodeBound::default()];
    let receiver = [GpuReceiver::default()];
    dispatch(
        gpu,
        twin as u32,
        queries,
        &node,
        &receiver,
        &Transport::default(),
    )
}

/// The rows of the transport twins beyond the receivers.
#[derive(Default)]
struct Transport<'a> {
    leaves: &'a [GpuLeaf],
    nodes: &'a [GpuLitNode],
}

/// Indices of `lit_triangle_shade` and `lit_scene_cluster` in `shaders/math_twins.wgsl`.
const LEAF_SHADE: u32 = 7;
const CLUSTER: u32 = 8;

/// One receiver row of the transport twins: the point, the receiver's lobes and its direction
/// across the plane of incidence (`ReceiverLobes::across`).
#[derive(Clone, Copy, Debug)]
pub struct ReceiverRow {
    pub x: Vec3,
    pub receiver: GpuReceiver,
    pub across: Vec3,
}

fn transport_queries(rows: &[ReceiverRow], light: Vec3) -> Vec<TwinQuery> {
    rows.iter()
        .map(|r| TwinQuery {
            a: [r.x.x, r.x.y, r.x.z, 0.0],
            b: [r.across.x, r.across.y, r.across.z, 0.0],
            c: [light.x, light.y, light.z, 0.0],
            ..TwinQuery::default()
        })
        .collect()
}

/// The WGSL `lit_triangle_shade` (twin of `cut::LitTriangle::shade` with the default receiver
/// options) of `leaves[i]` at `rows[i]`, on the GPU; RGB in the first three lanes.
pub fn run_leaf_shade(
    gpu: &Gpu,
    leaves: &[GpuLeaf],
    rows: &[ReceiverRow],
) -> Result<Vec<[f32; 4]>, GpuError> {
    let t = Transport {
        leaves,
        ..Transport::default()
    };
    run_transport(
        gpu,
        LEAF_SHADE,
        ("leaves", leaves.len()),
        rows,
        Vec3::ZERO,
        &t,
    )
}

/// The WGSL `lit_scene_cluster` (twin of `cut::LitScene::cluster`, lobes aimed from `light`)
/// of `nodes[i]` at `rows[i]`, on the GPU; RGB in the first three lanes.
pub fn run_cluster(
    gpu: &Gpu,
    nodes: &[GpuLitNode],
    light: Vec3,
    rows: &[ReceiverRow],
) -> Result<Vec<[f32; 4]>, GpuError> {
    let t = Transport {
        nodes,
        ..Transport::default()
    };
    run_transport(gpu, CLUSTER, ("nodes", nodes.len()), rows, light, &t)
}

/// A transport twin (`function`) over `rows`, one of `items` (name, count) per row.
fn run_transport(
    gpu: &Gpu,
    function: u32,
    (what, items): (&str, usize),
    rows: &[ReceiverRow],
    light: Vec3,
    t: &Transport,
) -> Result<Vec<[f32; 4]>, GpuError> {
    if items != rows.len() {
        return Err(failed(format!(
            "inconsistent sizes: {items} {what}, {} rows",
            rows.len()
        )));
    }
    let receivers: Vec<GpuReceiver> = rows.iter().map(|r| r.receiver).collect();
    let queries = transport_queries(rows, light);
    dispatch(
        gpu,
        function,
        &queries,
        &[GpuNodeBound::default()],
        &receivers,
        t,
    )
}

/// Index of `node_bound` in `shaders/math_twins.wgsl` (it takes a node and a receiver per row,
/// beyond a [`TwinQuery`]).
const NODE_BOUND: u32 = 6;

/// The WGSL `node_bound` (twin of `cut::node_bound`) at `points[i]` for `nodes[i]` and
/// `receivers[i]`, on the GPU; RGB in the first three lanes.
pub fn run_node_bound(
    gpu: &Gpu,
    nodes: &[GpuNodeBound],
    receivers: &[GpuReceiver],
    points: &[Vec3],
) -> Result<Vec<[f32; 4]>, GpuError> {
    if nodes.len() != points.len() || receivers.len() != points.len() {
        return Err(failed(format!(
            "inconsistent sizes: {} nodes, {} receivers, {} points",
            nodes.len(),
            receivers.len(),
            points.len()
        )));
    }
    let queries: Vec<TwinQuery> = points
        .iter()
        .map(|p| TwinQuery {
            a: [p.x, p.y, p.z, 0.0],
            ..TwinQuery::default()
        })
        .collect();
    dispatch(
        gpu,
        NODE_BOUND,
        &queries,
        nodes,
        receivers,
        &Transport::default(),
    )
}

fn dispatch(
    gpu: &Gpu,
    function: u32,
    queries: &[TwinQuery],
    nodes: &[GpuNodeBound],
    receivers: &[GpuReceiver],
    transport: &Transport,
) -> Result<Vec<[f32; 4]>, GpuError> {
    if queries.is_empty() {
        return Ok(Vec::new());
    }
    let bytes = std::mem::size_of_val(queries) as u64;
    if bytes > gpu.max_binding {
        return Err(failed(format!(
            "{} rows ({bytes} bytes) exceed the largest binding ({} bytes)",
            queries.len(),
            gpu.max_binding
        )));
    }
    if queries.len() > 65_535 * 64 {
        return Err(failed(format!(
            "{} rows: at most {} per dispatch",
            queries.len(),
            65_535 * 64
        )));
    }
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let pipeline = gpu.compute_pipeline("math_twins");
    let params = TwinParams {
        function,
        count: queries.len() as u32,
        _pad0: 0,
        _pad1: 0,
    };
    let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("twin params"),
        contents: bytemuck::bytes_of(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let query_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("twin queries"),
        contents: bytemuck::cast_slice(queries),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let node_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("twin nodes"),
        contents: bytemuck::cast_slice(nodes),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let receiver_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("twin receivers"),
        contents: bytemuck::cast_slice(receivers),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let out_bytes = (queries.len() * 16) as u64;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("twin results"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let one_leaf = [GpuLeaf::default()];
    let one_node = [GpuLitNode::default()];
    let leaves = if transport.leaves.is_empty() {
        &one_leaf[..]
    } else {
        transport.leaves
    };
    let lit_nodes = if transport.nodes.is_empty() {
        &one_node[..]
    } else {
        transport.nodes
    };
    let leaf_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("twin leaves"),
        contents: bytemuck::cast_slice(leaves),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let lit_node_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("twin lit nodes"),
        contents: bytemuck::cast_slice(lit_nodes),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let bind = gpu.bind_buffers(
        &pipeline.get_bind_group_layout(0),
        &[
            &params_buf,
            &query_buf,
            &out,
            &node_buf,
            &receiver_buf,
            &leaf_buf,
            &lit_node_buf,
        ],
    );
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("math_twins"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((queries.len() as u32).div_ceil(64), 1, 1);
    }
    gpu.queue.submit([enc.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(failed(describe(&e)));
    }
    let data = gpu.read_back(&out, out_bytes, "math twins")?;
    gpu.check("math twins")?;
    Ok(f32s(&data)
        .chunks_exact(4)
        .map(|v| [v[0], v[1], v[2], v[3]])
        .collect())
}
