//! The G-buffer on the GPU (`shaders/gbuffer.wgsl`): every pixel's nearest triangle,
//! barycentrics and distance, by rasterising the scene from the camera. Rust twin: the primary
//! hit of the ray through the pixel centre (`Camera::ray_dir`, `Accel::intersect`).

use super::layout::GpuCamera;
use super::{Gpu, GpuError, describe};
use crate::accel::Hit;
use crate::scene::Camera;
use glam::Vec3;
use wgpu::util::DeviceExt;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "G-buffer".into(),
        reason: reason.into(),
    }
}

/// The hit at every pixel centre of `camera` (its own width and height), row-major from the
/// top-left; `None` where no triangle is seen. `far` bounds the depth range (the scene's
/// extent as seen from the camera).
pub fn gbuffer(
    gpu: &Gpu,
    positions: &[Vec3],
    indices: &[[u32; 3]],
    camera: &Camera,
    far: f32,
) -> Result<Vec<Option<Hit>>, GpuError> {
    let (w, h) = (camera.width, camera.height);
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        return Err(failed(format!(
            "image size {w}x{h}: must be 1 to 8192 a side"
        )));
    }
    let corners: Vec<Vec3> = indices
        .iter()
        .flat_map(|t| t.map(|i| positions[i as usize]))
        .collect();
    if (corners.len() * 12) as u64 > gpu.max_binding {
        return Err(failed(format!(
            "{} triangles exceed the largest buffer ({} bytes)",
            indices.len(),
            gpu.max_binding
        )));
    }
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let pipeline = gpu.raster_pipeline("gbuffer", wgpu::TextureFormat::Rgba32Uint);
    let cam = GpuCamera {
        position: camera.position.to_array(),
        tan_half: (0.5 * camera.fov_y).tan(),
        forward: camera.forward.to_array(),
        aspect: w as f32 / h as f32,
        right: camera.right.to_array(),
        far: far.max(1e-6),
        up: camera.up.to_array(),
        _pad: 0.0,
    };
    let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("camera"),
        contents: bytemuck::bytes_of(&cam),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let bind = gpu.bind_buffers(&pipeline.get_bind_group_layout(0), &[&uniform]);
    let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("triangle corners"),
        contents: bytemuck::cast_slice(&corners),
        usage: wgpu::BufferUsages::VERTEX,
    });
    let extent = wgpu::Extent3d {
        width: w,
        height: h,
        depth_or_array_layers: 1,
    };
    let target = gpu.texture_2d(
        "gbuffer",
        (w, h),
        wgpu::TextureFormat::Rgba32Uint,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = gpu.texture_2d(
        "gbuffer depth",
        (w, h),
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let padded_row = (w as u64 * 16).div_ceil(256) * 256;
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("gbuffer copy"),
        size: padded_row * h as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target.create_view(&Default::default()),
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: u32::MAX as f64,
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth.create_view(&Default::default()),
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..));
        pass.draw(0..corners.len() as u32, 0..1);
    }
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: &target,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row as u32),
                rows_per_image: Some(h),
            },
        },
        extent,
    );
    gpu.queue.submit([enc.finish()]);
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(failed(describe(&e)));
    }
    let bytes = gpu.read_back(&staging, padded_row * h as u64, "G-buffer")?;
    gpu.check("G-buffer")?;
    let word = |o: usize| u32::from_ne_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h as usize {
        for x in 0..w as usize {
            let o = y * padded_row as usize + x * 16;
            let tri = word(o);
            out.push((tri != u32::MAX).then(|| Hit {
                tri,
                u: f32::from_bits(word(o + 4)),
                v: f32::from_bits(word(o + 8)),
                t: f32::from_bits(word(o + 12)),
            }));
        }
    }
    Ok(out)
}
