//! PRT relighting on the GPU (`shaders/prt_relight.wgsl`): one dot product per vertex and
//! colour channel. Rust twin: [`crate::precompute::prt::relight_cpu`].
//!
//! A [`Relighter`] uploads the transfer once (in chunks that each fit the device's
//! storage-binding limit) and then relights for any lighting by uploading only the order² SH
//! coefficients — what an interactive viewer does every frame.

use super::{Gpu, GpuError, describe};
use glam::Vec3;
use wgpu::util::DeviceExt;

/// Vertices per dispatch row (workgroups of 64 in x; the rest in y).
const ROW_WORKGROUPS: u32 = 1024;

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
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("prt_relight.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                super::shaders::source("prt_relight")
                    .expect("a known pass")
                    .into(),
            ),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("prt_relight"),
            layout: None,
            module: &module,
            entry_point: Some("prt_relight"),
            compilation_options: Default::default(),
            cache: None,
        });
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
            let groups = (count as u32).div_ceil(64);
            let (gx, gy) = if groups <= ROW_WORKGROUPS {
                (groups, 1)
            } else {
                (ROW_WORKGROUPS, groups.div_ceil(ROW_WORKGROUPS))
            };
            let params: [u32; 4] = [count as u32, coefficients as u32, gx * 64, 0];
            let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("params"),
                contents: bytemuck::cast_slice(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: transfer_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: lighting.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: out.as_entire_binding(),
                    },
                ],
            });
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
            let floats: &[f32] = bytemuck::cast_slice(&bytes);
            out.extend(floats.chunks_exact(3).map(|v| Vec3::new(v[0], v[1], v[2])));
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
