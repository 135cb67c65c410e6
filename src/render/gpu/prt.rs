//! PRT relighting on the GPU (`shaders/prt_relight.wgsl`): one dot product per vertex and
//! colour channel. Rust twin: [`crate::precompute::prt::relight_cpu`].

use super::{Gpu, GpuError};
use glam::Vec3;
use wgpu::util::DeviceExt;

/// Vertices per dispatch row (workgroups of 64 in x; the rest in y).
const ROW_WORKGROUPS: u32 = 1024;

/// Radiance of every vertex: Σ_i transfer[v][i] ⊙ lighting[i]. `transfer` holds
/// `coefficients` RGB entries per vertex. Vertices are processed in chunks whose transfer
/// buffer stays within the device's binding limit (so the 871k-triangle dragon at order 8 fits
/// lavapipe's 128 MiB).
pub fn relight(
    gpu: &Gpu,
    transfer: &[Vec3],
    coefficients: usize,
    lighting: &[Vec3],
) -> Result<Vec<Vec3>, GpuError> {
    let fail = |reason: String| GpuError::Failed {
        what: "PRT relighting".into(),
        reason,
    };
    if coefficients == 0
        || lighting.len() != coefficients
        || !transfer.len().is_multiple_of(coefficients)
    {
        return Err(fail(format!(
            "inconsistent sizes: {} transfer entries, {} coefficients, {} lighting entries",
            transfer.len(),
            coefficients,
            lighting.len()
        )));
    }
    let vertices = transfer.len() / coefficients;
    let bytes_per_vertex = (coefficients * 12) as u64;
    let per_chunk = (gpu.max_binding / bytes_per_vertex).clamp(1, 1 << 22) as usize;
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("prt_relight.wgsl"),
        source: wgpu::ShaderSource::Wgsl(include_str!("../../../shaders/prt_relight.wgsl").into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("prt_relight"),
        layout: None,
        module: &module,
        entry_point: Some("prt_relight"),
        compilation_options: Default::default(),
        cache: None,
    });
    let light_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("SH lighting"),
        contents: bytemuck::cast_slice(&flatten(lighting)),
        usage: wgpu::BufferUsages::STORAGE,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(fail(e.to_string()));
    }
    let mut out = Vec::with_capacity(vertices);
    for first in (0..vertices).step_by(per_chunk) {
        let count = per_chunk.min(vertices - first);
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let chunk = &transfer[first * coefficients..(first + count) * coefficients];
        let transfer_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("PRT transfer"),
            contents: bytemuck::cast_slice(&flatten(chunk)),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let out_bytes = (count * 12) as u64;
        let out_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vertex radiance"),
            size: out_bytes,
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
            layout: &pipeline.get_bind_group_layout(0),
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
                    resource: light_buf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: out_buf.as_entire_binding(),
                },
            ],
        });
        let mut enc =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("prt_relight"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        gpu.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(fail(e.to_string()));
        }
        let bytes = gpu.read_back(&out_buf, out_bytes, "PRT relighting")?;
        let floats: &[f32] = bytemuck::cast_slice(&bytes);
        out.extend(floats.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
    }
    gpu.check("PRT relighting")?;
    Ok(out)
}

fn flatten(v: &[Vec3]) -> Vec<f32> {
    v.iter().flat_map(|x| x.to_array()).collect()
}
