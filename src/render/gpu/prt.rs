//! PRT relighting on the GPU (`shaders/prt_relight.wgsl`): one dot product per vertex and
//! colour channel. Rust twin: [`crate::precompute::prt::relight_cpu`].
//!
//! A [`Relighter`] uploads the transfer once (in chunks that each fit the device's
//! storage-binding limit) and then relights for any lighting by uploading only the order² SH
//! coefficients — what an interactive viewer does every frame.

use super::{Gpu, GpuError, describe, dispatch_grid, f32s};
use glam::Vec3;
use wgpu::util::DeviceExt;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "PRT relighting".into(),
        reason: reason.into(),
    }
}

struct Chunk {
    vertices: u32,
    groups: (u32, u32),
    out: wgpu::Buffer,
    bind: wgpu::BindGroup,
}

/// Transfer vectors resident on the GPU, ready to be relit.
pub struct Relighter<'g> {
    gpu: &'g Gpu,
    coefficients: usize,
    pipeline: wgpu::ComputePipeline,
    lighting: wgpu::Buffer,
    chunks: Vec<Chunk>,
}

impl<'g> Relighter<'g> {
    /// Uploads `transfer` (`coefficients` RGB entries per vertex).
    pub fn new(
        gpu: &'g Gpu,
        transfer: &[Vec3],
        coefficients: usize,
    ) -> Result<Relighter<'g>, GpuError> {
        if coefficients == 0 || !transfer.len().is_multiple_of(coefficients) {
            return Err(failed(format!(
                "inconsistent sizes: {} transfer entries, {coefficients} coefficients",
                transfer.len()
            )));
        }
        let vertices = transfer.len() / coefficients;
        let bytes_per_vertex = (coefficients * 12) as u64;
        let per_chunk = (gpu.max_binding / bytes_per_vertex).clamp(1, 1 << 22) as usize;
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = gpu.compute_pipeline("prt_relight");
        let lighting = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("SH lighting"),
            size: (coefficients * 12) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = pipeline.get_bind_group_layout(0);
        let mut chunks = Vec::new();
        for first in (0..vertices).step_by(per_chunk) {
            let count = per_chunk.min(vertices - first);
            let part = &transfer[first * coefficients..(first + count) * coefficients];
            let transfer_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("PRT transfer"),
                contents: bytemuck::cast_slice(&structure_of_arrays(part, coefficients)),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let out = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("vertex radiance"),
                size: (count * 12) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let (gx, gy) = dispatch_grid(count as u32);
            let params: [u32; 4] = [count as u32, coefficients as u32, gx * 64, 0];
            let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("params"),
                contents: bytemuck::cast_slice(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind = gpu.bind_buffers(&layout, &[&params_buf, &transfer_buf, &lighting, &out]);
            chunks.push(Chunk {
                vertices: count as u32,
                groups: (gx, gy),
                out,
                bind,
            });
        }
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(failed(describe(&e)));
        }
        gpu.wait("PRT upload")?;
        gpu.check("PRT upload")?;
        Ok(Relighter {
            gpu,
            coefficients,
            pipeline,
            lighting,
            chunks,
        })
    }

    /// Radiance of every vertex under `lighting` (order² RGB SH coefficients).
    pub fn relight(&self, lighting: &[Vec3]) -> Result<Vec<Vec3>, GpuError> {
        if lighting.len() != self.coefficients {
            return Err(failed(format!(
                "inconsistent sizes: {} lighting entries for {} coefficients",
                lighting.len(),
                self.coefficients
            )));
        }
        let gpu = self.gpu;
        let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        gpu.queue
            .write_buffer(&self.lighting, 0, bytemuck::cast_slice(&flatten(lighting)));
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("prt_relight"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            for c in &self.chunks {
                pass.set_bind_group(0, &c.bind, &[]);
                pass.dispatch_workgroups(c.groups.0, c.groups.1, 1);
            }
        }
        gpu.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(failed(describe(&e)));
        }
        let mut out = Vec::new();
        for c in &self.chunks {
            let bytes = gpu.read_back(&c.out, c.vertices as u64 * 12, "PRT relighting")?;
            out.extend(f32s(&bytes).chunks_exact(3).map(Vec3::from_slice));
        }
        gpu.check("PRT relighting")?;
        Ok(out)
    }
}

/// One-shot relighting: uploads `transfer` and relights it once (see [`Relighter`]).
pub fn relight(
    gpu: &Gpu,
    transfer: &[Vec3],
    coefficients: usize,
    lighting: &[Vec3],
) -> Result<Vec<Vec3>, GpuError> {
    if lighting.len() != coefficients {
        return Err(failed(format!(
            "inconsistent sizes: {} lighting entries for {coefficients} coefficients",
            lighting.len()
        )));
    }
    Relighter::new(gpu, transfer, coefficients)?.relight(lighting)
}

/// `[vertex][coefficient]` RGB → `[coefficient][channel][vertex]` floats (the shader's layout).
fn structure_of_arrays(part: &[Vec3], coefficients: usize) -> Vec<f32> {
    let vertices = part.len() / coefficients;
    let mut out = vec![0.0f32; part.len() * 3];
    for (v, t) in part.chunks_exact(coefficients).enumerate() {
        for (i, c) in t.iter().enumerate() {
            for k in 0..3 {
                out[(3 * i + k) * vertices + v] = c[k];
            }
        }
    }
    out
}

fn flatten(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|x| x.to_array()).collect()
}
