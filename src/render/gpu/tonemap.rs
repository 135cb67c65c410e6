//! Tonemapping on the GPU (`shaders/tonemap.wgsl`): linear RGB to 8-bit sRGB with the exposure
//! and tone operator of a [`Tonemap`]. Rust twin: [`crate::image::to_srgb8`].

use super::layout::GpuTonemapParams;
use super::{Gpu, GpuError, describe};
use crate::image::{Image, ToneOperator, Tonemap};
use wgpu::util::DeviceExt;

/// Pixels per dispatch row (workgroups of 64 in x; the rest in y).
const ROW_WORKGROUPS: u32 = 1024;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "tonemapping".into(),
        reason: reason.into(),
    }
}

/// `img` tonemapped to 8-bit sRGB on the GPU, row-major from the top-left.
pub fn to_srgb8(gpu: &Gpu, img: &Image, tm: &Tonemap) -> Result<Vec<[u8; 3]>, GpuError> {
    let count = img.data.len();
    if count == 0 {
        return Ok(Vec::new());
    }
    if (count * 12) as u64 > gpu.max_binding {
        return Err(failed(format!(
            "{count} pixels exceed the largest binding ({} bytes)",
            gpu.max_binding
        )));
    }
    let groups = (count as u32).div_ceil(64);
    let (gx, gy) = if groups <= ROW_WORKGROUPS {
        (groups, 1)
    } else {
        (ROW_WORKGROUPS, groups.div_ceil(ROW_WORKGROUPS))
    };
    let params = GpuTonemapParams {
        scale: tm.exposure.exp2(),
        tone_operator: match tm.operator {
            ToneOperator::Clamp => 0,
            ToneOperator::Reinhard => 1,
            ToneOperator::Aces => 2,
        },
        count: count as u32,
        row_stride: gx * 64,
    };
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("tonemap.wgsl"),
        source: wgpu::ShaderSource::Wgsl(
            super::shaders::source("tonemap")
                .expect("a known pass")
                .into(),
        ),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("tonemap"),
        layout: None,
        module: &module,
        entry_point: Some("tonemap"),
        compilation_options: Default::default(),
        cache: None,
    });
    let linear: Vec<f32> = img.data.iter().flat_map(|v| v.to_array()).collect();
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("tonemap params"),
        contents: bytemuck::bytes_of(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("linear image"),
        contents: bytemuck::cast_slice(&linear),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let out_bytes = (count * 4) as u64;
    let out = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("display image"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: input.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: out.as_entire_binding(),
            },
        ],
    });
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tonemap"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    gpu.queue.submit([enc.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(failed(describe(&e)));
    }
    let bytes = gpu.read_back(&out, out_bytes, "tonemapping")?;
    gpu.check("tonemapping")?;
    Ok(bytes.chunks_exact(4).map(|p| [p[0], p[1], p[2]]).collect())
}
