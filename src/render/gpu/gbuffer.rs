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
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("gbuffer.wgsl"),
        source: wgpu::ShaderSource::Wgsl(
            super::shaders::source("gbuffer")
                .expect("a known pass")
                .into(),
        ),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("gbuffer"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("gbuffer_vertex"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3],
            })],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("gbuffer"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: wgpu::TextureFormat::Rgba32Uint,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    });
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
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: uniform.as_entire_binding(),
        }],
    });
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
    let texture = |label, format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let target = texture(
        "gbuffer",
        wgpu::TextureFormat::Rgba32Uint,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = texture(
        "gbuffer depth",
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
