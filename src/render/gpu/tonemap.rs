//! Tonemapping on the GPU (`shaders/tonemap.wgsl`): linear RGB to 8-bit sRGB with the exposure
//! and tone operator of a [`Tonemap`]. Rust twin: [`crate::image::to_srgb8`].

use super::layout::GpuTonemapParams;
use super::{Gpu, GpuError, describe, dispatch_grid};
use crate::image::{Image, ToneOperator, Tonemap};
use wgpu::util::DeviceExt;

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
    let (gx, gy) = dispatch_grid(count as u32);
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
    let pipeline = gpu.compute_pipeline("tonemap");
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
    let bind = gpu.bind_buffers(
        &pipeline.get_bind_group_layout(0),
        &[&uniform, &input, &out],
    );
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
