//! The VPL baseline's one-bounce light on the GPU (`shaders/vpl.wgsl`): for every pixel sample
//! on a receiver, the sum over the VPLs of the light each re-emits through its material's BRDF,
//! reflected by the receiver's BRDF, with the clamped geometry term and the VPL's imperfect
//! shadow map. Rust twin: the indirect part of `render::cpu::vpl` with `--visibility approx`
//! (which hands its points, VPLs and maps over).
//!
//! One invocation per point loops over a chunk of at most [`VPL_CHUNK`] VPLs and adds to the
//! point's sums, so that no invocation comes near lavapipe's loop budget (65,535 iterations over
//! all of an invocation's loops; docs/gpu.md). The points go up [`POINT_CHUNK`] at a time,
//! each chunk summed over all VPLs and read back before the next, so that no binding grows
//! with the image and a cancelled render stops between chunks.

use super::layout::{GpuBrdf, GpuMapOrigin, GpuSurfacePoint, GpuVpl, GpuVplParams, GpuVplSum};
use super::{Gpu, GpuError, describe};
use crate::brdf::Brdf;
use crate::visibility::ism::ImperfectShadowMaps;
use glam::Vec3;
use std::sync::atomic::{AtomicBool, Ordering};
use wgpu::util::DeviceExt;

/// VPLs one invocation sums per dispatch (one loop iteration each), and the size of the
/// uniform buffer that holds them (256 × 176 bytes, under the 64 KiB uniform binding; the
/// shader's `array<GpuVpl, 256>` has the same length).
pub const VPL_CHUNK: usize = 256;

/// Points per dispatch, at most.
pub const POINT_CHUNK: usize = 1 << 16;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "VPL shading".into(),
        reason: reason.into(),
    }
}

/// The imperfect shadow maps of every light, one atlas (all maps have the scene's resolution).
#[derive(Default)]
pub struct MapAtlas {
    res: u32,
    bias: f32,
    origins: Vec<GpuMapOrigin>,
    atlas: Vec<[f32; 2]>,
}

impl MapAtlas {
    /// Appends `ism`'s maps; returns the index of its first map. Every set must share one
    /// resolution and bias (one scene's `[visibility.ism]`).
    pub fn push(&mut self, ism: &ImperfectShadowMaps) -> Result<u32, GpuError> {
        let p = ism.parts();
        if self.origins.is_empty() {
            self.res = p.res as u32;
            self.bias = p.bias;
        } else if self.res != p.res as u32 || self.bias != p.bias {
            return Err(failed(
                "imperfect shadow maps of different resolutions or biases in one atlas",
            ));
        }
        let first = self.origins.len() as u32;
        for ((pos, frame), &mv) in p.origins.iter().zip(p.min_variance) {
            self.origins.push(GpuMapOrigin {
                position: pos.to_array(),
                min_variance: mv,
                t: frame.t.to_array(),
                b: frame.b.to_array(),
                n: frame.n.to_array(),
                ..GpuMapOrigin::default()
            });
        }
        self.atlas.extend(p.atlas.iter().map(|t| t.to_array()));
        Ok(first)
    }
}

/// What [`shade`] returns for every point: its indirect radiance and pair counts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VplShaded {
    pub radiance: Vec3,
    /// VPL–point pairs evaluated (facing each other, both BRDFs nonzero).
    pub pairs: u32,
    /// Of those, the pairs whose geometry term the clamp reduced.
    pub clamped: u32,
}

/// The VPLs' one-bounce light at every point on the GPU; `materials` are the scene's BRDFs
/// (indexed by the points' and VPLs' `material`), `clamp_distance` is d_c. `None` when
/// `cancel` was set (checked between dispatches).
pub fn shade(
    gpu: &Gpu,
    materials: &[Brdf],
    points: &[GpuSurfacePoint],
    vpls: &[GpuVpl],
    maps: &MapAtlas,
    clamp_distance: f32,
    cancel: &AtomicBool,
) -> Result<Option<Vec<VplShaded>>, GpuError> {
    if points.is_empty() || vpls.is_empty() {
        return Ok(Some(vec![VplShaded::default(); points.len()]));
    }
    let n_mat = materials.len() as u32;
    let n_maps = maps.origins.len() as u32;
    if let Some(i) = points.iter().position(|p| p.material >= n_mat) {
        return Err(failed(format!("point {i} has no material")));
    }
    if let Some(i) = vpls
        .iter()
        .position(|v| v.material >= n_mat || (v.map != u32::MAX && v.map >= n_maps))
    {
        return Err(failed(format!("VPL {i} has no material or map")));
    }
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let gpu_materials: Vec<GpuBrdf> = materials.iter().map(GpuBrdf::from).collect();
    let pipeline = gpu.compute_pipeline_for("vpl", &gpu_materials);
    let storage = |label: &str, bytes: &[u8]| {
        gpu.storage_buffer(
            "VPL shading",
            label,
            bytes,
            "render with --device cpu or a lower resolution",
        )
    };
    // Empty buffers cannot be bound: one unused texel without maps.
    let no_maps = [[0.0f32; 2]];
    let atlas: &[[f32; 2]] = if maps.atlas.is_empty() {
        &no_maps
    } else {
        &maps.atlas
    };
    let bufs = [
        storage("materials", bytemuck::cast_slice(&gpu_materials))?,
        storage("imperfect shadow maps", bytemuck::cast_slice(atlas))?,
    ];
    let layout = pipeline.get_bind_group_layout(0);
    // Each chunk of VPLs a uniform buffer of exactly VPL_CHUNK (the last one padded).
    let chunk_bufs: Vec<wgpu::Buffer> = vpls
        .chunks(VPL_CHUNK)
        .map(|c| {
            let mut padded = c.to_vec();
            for v in &mut padded {
                if v.map != u32::MAX {
                    v.origin = maps.origins[v.map as usize];
                }
            }
            padded.resize(VPL_CHUNK, GpuVpl::default());
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("VPLs"),
                contents: bytemuck::cast_slice(&padded),
                usage: wgpu::BufferUsages::UNIFORM,
            })
        })
        .collect();
    // The points a chunk at a time: uploaded, summed over every chunk of VPLs in one
    // submission (each dispatch adds to the sums the one before wrote; wgpu orders the
    // passes), read back.
    let mut sums: Vec<GpuVplSum> = Vec::with_capacity(points.len());
    for chunk in points.chunks(POINT_CHUNK) {
        let count = chunk.len();
        let points_buf = storage("points", bytemuck::cast_slice(chunk))?;
        let out_bytes = (count * std::mem::size_of::<GpuVplSum>()) as u64;
        let sums_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("VPL sums"),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let mut enc =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        let mut binds = Vec::new();
        for (k, vpl_buf) in chunk_bufs.iter().enumerate() {
            let params = GpuVplParams {
                count: count as u32,
                vpl_count: VPL_CHUNK.min(vpls.len() - k * VPL_CHUNK) as u32,
                accumulate: u32::from(k > 0),
                clamp2: clamp_distance * clamp_distance,
                map_res: maps.res,
                map_bias: maps.bias,
                ..GpuVplParams::default()
            };
            let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("VPL params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            binds.push(gpu.bind_buffers(
                &layout,
                &[
                    &params_buf,
                    &points_buf,
                    vpl_buf,
                    &bufs[0],
                    &bufs[1],
                    &sums_buf,
                ],
            ));
        }
        for bind in &binds {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("vpl"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups((count as u32).div_ceil(64), 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        let data = gpu.read_back(&sums_buf, out_bytes, "VPL shading")?;
        sums.extend(bytemuck::pod_collect_to_vec::<u8, GpuVplSum>(&data));
        if cancel.load(Ordering::Relaxed) {
            return Ok(None);
        }
    }
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(failed(describe(&e)));
    }
    gpu.check("VPL shading")?;
    Ok(Some(
        sums.iter()
            .map(|s| VplShaded {
                radiance: Vec3::from_array(s.radiance),
                pairs: s.pairs,
                clamped: s.clamped,
            })
            .collect(),
    ))
}
