//! A point light's variance shadow map on the GPU: each of the six cube faces is rasterised
//! (`shaders/vsm.wgsl`: moments (z, z²) of the distance to the light, nearest surface kept by
//! the depth test) and the faces are blurred (`shaders/vsm_blur.wgsl`, separable Gaussian).
//! Rust twin: [`crate::visibility::vsm::VarianceShadowMap::build`], which casts a ray per texel
//! centre; [`cube_moments`] returns the same texel layout, so the two compare texel by texel.

use super::layout::{GpuBlurParams, GpuVsmFace};
use super::{Gpu, GpuError, describe};
use crate::visibility::vsm::CubeSetup;
use glam::{Vec2, Vec3};
use wgpu::util::DeviceExt;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "shadow map".into(),
        reason: reason.into(),
    }
}

/// The moments of the six faces of `setup`'s cube over the triangles (`positions`, `indices`),
/// blurred with `blur` texels of radius (0: none): face after face, rows from v = −1 up, as
/// [`crate::visibility::vsm::VarianceShadowMap::moments`].
pub fn cube_moments(
    gpu: &Gpu,
    positions: &[Vec3],
    indices: &[[u32; 3]],
    setup: &CubeSetup,
    blur: u32,
) -> Result<Vec<Vec2>, GpuError> {
    ShadowMapper::new(gpu, positions, indices)?.cube_moments(setup, blur)
}

/// The shadow-map passes compiled and the scene's triangles uploaded, once; then
/// [`ShadowMapper::cube_moments`] per frame (per light position).
pub struct ShadowMapper<'g> {
    gpu: &'g Gpu,
    pipeline: wgpu::RenderPipeline,
    blur_pipeline: wgpu::ComputePipeline,
    vertices: wgpu::Buffer,
    index_buf: wgpu::Buffer,
    index_count: u32,
}

impl<'g> ShadowMapper<'g> {
    pub fn new(
        gpu: &'g Gpu,
        positions: &[Vec3],
        indices: &[[u32; 3]],
    ) -> Result<ShadowMapper<'g>, GpuError> {
        if (positions.len() * 12) as u64 > gpu.max_binding
            || (indices.len() * 12) as u64 > gpu.max_binding
        {
            return Err(failed(format!(
                "{} triangles exceed the largest buffer ({} bytes)",
                indices.len(),
                gpu.max_binding
            )));
        }
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let source = |pass: &str| {
            wgpu::ShaderSource::Wgsl(super::shaders::source(pass).expect("a known pass").into())
        };
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("vsm.wgsl"),
            source: source("vsm"),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("vsm"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vsm_vertex"),
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
                entry_point: Some("vsm"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: wgpu::TextureFormat::Rg32Float,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vsm positions"),
            contents: bytemuck::cast_slice(positions),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vsm indices"),
            contents: bytemuck::cast_slice(indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let blur_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("vsm_blur.wgsl"),
            source: source("vsm_blur"),
        });
        let blur_pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("vsm_blur"),
            layout: None,
            module: &blur_module,
            entry_point: Some("vsm_blur"),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(failed(describe(&e)));
        }
        gpu.wait("shadow-map setup")?;
        gpu.check("shadow-map setup")?;
        Ok(ShadowMapper {
            gpu,
            pipeline,
            blur_pipeline,
            vertices,
            index_buf,
            index_count: (indices.len() * 3) as u32,
        })
    }

    /// The moments of the six faces of `setup`'s cube, blurred with `blur` texels of radius
    /// (0: none): face after face, rows from v = −1 up, as
    /// [`crate::visibility::vsm::VarianceShadowMap::moments`].
    pub fn cube_moments(&self, setup: &CubeSetup, blur: u32) -> Result<Vec<Vec2>, GpuError> {
        Ok(self.cube_moments_timed(setup, blur)?.0)
    }

    /// [`Self::cube_moments`] and, when the device has timestamp queries, the GPU time of the
    /// rasterisation (six passes) and of the blur (two passes), in seconds.
    pub fn cube_moments_timed(
        &self,
        setup: &CubeSetup,
        blur: u32,
    ) -> Result<(Vec<Vec2>, Option<PassTimes>), GpuError> {
        let gpu = self.gpu;
        let n = setup.resolution;
        if n == 0 || n > 8192 {
            return Err(failed(format!("resolution {n}: must be 1 to 8192")));
        }
        let row_bytes = n as u64 * 8;
        // copy_texture_to_buffer needs rows aligned to 256 bytes.
        let padded_row = row_bytes.div_ceil(256) * 256;
        if 6 * row_bytes * n as u64 > gpu.max_binding {
            return Err(failed(format!(
                "{n}² texels per face exceed the largest binding ({} bytes)",
                gpu.max_binding
            )));
        }
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let (pipeline, vertices, index_buf) = (&self.pipeline, &self.vertices, &self.index_buf);
        let timer = super::Timer::new(gpu, 6);
        let extent = wgpu::Extent3d {
            width: n,
            height: n,
            depth_or_array_layers: 1,
        };
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("vsm moments"),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rg32Float,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("vsm depth"),
            size: extent,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Depth32Float,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let target_view = target.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        // The faces' moments, padded rows, one face after another.
        // Dense rows (n a multiple of 32) let the blur run on the copied faces directly, with
        // one read-back; otherwise the rows are unpadded on the CPU first.
        let dense = padded_row == row_bytes;
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vsm faces"),
            size: 6 * padded_row * n as u64,
            usage: wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let far = setup.far;
        let mut enc =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        for (k, &(forward, right, up)) in setup.faces.iter().enumerate() {
            let face = GpuVsmFace {
                forward: forward.to_array(),
                margin: setup.margin,
                right: right.to_array(),
                far,
                up: up.to_array(),
                light: setup.position.to_array(),
                ..GpuVsmFace::default()
            };
            let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("vsm face"),
                contents: bytemuck::bytes_of(&face),
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
            {
                let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("vsm face"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &target_view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color {
                                r: far as f64,
                                g: (far * far) as f64,
                                b: 0.0,
                                a: 0.0,
                            }),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &depth_view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: timer.as_ref().map(|t| t.render_writes(k as u32)),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.set_index_buffer(index_buf.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..self.index_count, 0, 0..1);
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
                        offset: k as u64 * padded_row * n as u64,
                        bytes_per_row: Some(padded_row as u32),
                        rows_per_image: Some(n),
                    },
                },
                extent,
            );
        }
        if let Some(t) = &timer {
            t.resolve(&mut enc);
        }
        gpu.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(failed(describe(&e)));
        }
        if dense && blur > 0 {
            gpu.wait("shadow map")?;
            gpu.check("shadow map")?;
            let raster = match &timer {
                Some(t) => Some(t.read(gpu)?.iter().sum::<f64>()),
                None => None,
            };
            let (moments, blur_time) = self.blur_buffer(&staging, n, blur)?;
            let times = match (raster, blur_time) {
                (Some(r), Some(b)) => Some(PassTimes { raster: r, blur: b }),
                _ => None,
            };
            return Ok((moments, times));
        }
        let bytes = gpu.read_back(&staging, 6 * padded_row * n as u64, "shadow map")?;
        gpu.check("shadow map")?;
        let raster = match &timer {
            Some(t) => Some(t.read(gpu)?.iter().sum::<f64>()),
            None => None,
        };
        // Unpad the rows. The vertex shader maps v to NDC y = −v / margin, so the framebuffer's
        // row 0 (NDC y = +1) is v = −margin, the CPU's row 0: no flip.
        let mut moments = vec![Vec2::ZERO; 6 * (n * n) as usize];
        for face in 0..6usize {
            for row in 0..n as usize {
                let src = (face as u64 * padded_row * n as u64 + row as u64 * padded_row) as usize;
                let dst = face * (n * n) as usize + row * n as usize;
                for i in 0..n as usize {
                    let o = src + i * 8;
                    let z =
                        f32::from_ne_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
                    let z2 = f32::from_ne_bytes([
                        bytes[o + 4],
                        bytes[o + 5],
                        bytes[o + 6],
                        bytes[o + 7],
                    ]);
                    moments[dst + i] = Vec2::new(z, z2);
                }
            }
        }
        if blur == 0 {
            return Ok((
                moments,
                raster.map(|r| PassTimes {
                    raster: r,
                    blur: 0.0,
                }),
            ));
        }
        let (moments, blur_time) = self.blur_faces(&moments, n, blur)?;
        let times = match (raster, blur_time) {
            (Some(r), Some(b)) => Some(PassTimes { raster: r, blur: b }),
            _ => None,
        };
        Ok((moments, times))
    }

    /// The separable blur of six n × n faces on the GPU (two dispatches).
    fn blur_faces(
        &self,
        moments: &[Vec2],
        n: u32,
        radius: u32,
    ) -> Result<(Vec<Vec2>, Option<f64>), GpuError> {
        let a = self
            .gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("blur a"),
                contents: bytemuck::cast_slice(moments),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            });
        self.blur_buffer(&a, n, radius)
    }

    /// The blur of six dense n × n faces held in `a` (a storage buffer), in place, read back.
    fn blur_buffer(
        &self,
        a: &wgpu::Buffer,
        n: u32,
        radius: u32,
    ) -> Result<(Vec<Vec2>, Option<f64>), GpuError> {
        let gpu = self.gpu;
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = &self.blur_pipeline;
        let timer = super::Timer::new(gpu, 2);
        let bytes = 6 * (n as u64) * (n as u64) * 8;
        let b = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("blur b"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let mut enc =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        for (vertical, src, dst) in [(0u32, a, &b), (1u32, &b, a)] {
            let params = GpuBlurParams {
                resolution: n,
                radius,
                vertical,
                _pad: 0,
            };
            let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("blur params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
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
                        resource: src.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: dst.as_entire_binding(),
                    },
                ],
            });
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("vsm_blur"),
                timestamp_writes: timer.as_ref().map(|t| t.compute_writes(vertical)),
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(n.div_ceil(8), n.div_ceil(8), 6);
        }
        if let Some(t) = &timer {
            t.resolve(&mut enc);
        }
        gpu.queue.submit([enc.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(failed(describe(&e)));
        }
        let out = gpu.read_back(a, bytes, "shadow-map blur")?;
        gpu.check("shadow-map blur")?;
        let blur_time = match &timer {
            Some(t) => Some(t.read(gpu)?.iter().sum::<f64>()),
            None => None,
        };
        let moments = out
            .chunks_exact(8)
            .map(|c| {
                Vec2::new(
                    f32::from_ne_bytes([c[0], c[1], c[2], c[3]]),
                    f32::from_ne_bytes([c[4], c[5], c[6], c[7]]),
                )
            })
            .collect();
        Ok((moments, blur_time))
    }
}

/// GPU time of the shadow-map passes from timestamp queries, in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassTimes {
    /// The six faces' rasterisation.
    pub raster: f64,
    /// The two blur dispatches (0 without a blur).
    pub blur: f64,
}
