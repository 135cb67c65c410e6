//! A light's variance shadow map on the GPU: each face — the six of a point light's cube, a
//! spot's one perspective face, a directional light's one orthographic face — is rasterised
//! (`shaders/vsm.wgsl`: moments (z, z²) of the depth, the distance to the light or along its
//! direction, nearest surface kept by the depth test) and the faces are blurred
//! (`shaders/vsm_blur.wgsl`, separable Gaussian). Rust twin:
//! [`crate::visibility::vsm::VarianceShadowMap::build`], which casts a ray per texel centre;
//! [`map_moments`] returns the same texel layout, so the two compare texel by texel.

use super::layout::{GpuBlurParams, GpuVsmFace};
use super::{Gpu, GpuError, describe, f32s};
use crate::visibility::vsm::MapSetup;
use glam::{Vec2, Vec3};
use wgpu::util::DeviceExt;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "shadow map".into(),
        reason: reason.into(),
    }
}

/// The moments of `setup`'s faces over the triangles (`positions`, `indices`), blurred with
/// `blur` texels of radius (0: none): face after face, rows from v = −1 up, as
/// [`crate::visibility::vsm::VarianceShadowMap::moments`].
pub fn map_moments(
    gpu: &Gpu,
    positions: &[Vec3],
    indices: &[[u32; 3]],
    setup: &MapSetup,
    blur: u32,
) -> Result<Vec<Vec2>, GpuError> {
    ShadowMapper::new(gpu, positions, indices)?.map_moments(setup, blur)
}

/// The shadow-map passes compiled and the scene's triangles uploaded, once; then
/// [`ShadowMapper::map_moments`] per frame (per light).
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
        let pipeline = gpu.raster_pipeline("vsm", wgpu::TextureFormat::Rg32Float);
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
        let blur_pipeline = gpu.compute_pipeline("vsm_blur");
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

    /// The moments of `setup`'s faces, blurred with `blur` texels of radius (0: none): face
    /// after face, rows from v = −1 up, as
    /// [`crate::visibility::vsm::VarianceShadowMap::moments`].
    pub fn map_moments(&self, setup: &MapSetup, blur: u32) -> Result<Vec<Vec2>, GpuError> {
        Ok(self.map_moments_timed(setup, blur)?.0)
    }

    /// [`Self::map_moments`] and, when the device has timestamp queries, the GPU time of the
    /// rasterisation (a pass per face) and of the blur (two passes), in seconds.
    pub fn map_moments_timed(
        &self,
        setup: &MapSetup,
        blur: u32,
    ) -> Result<(Vec<Vec2>, Option<PassTimes>), GpuError> {
        let gpu = self.gpu;
        let n = setup.resolution;
        if n == 0 || n > 8192 {
            return Err(failed(format!("resolution {n}: must be 1 to 8192")));
        }
        let faces = setup.faces.len();
        if !(1..=6).contains(&faces) {
            return Err(failed(format!("{faces} faces: must be 1 to 6")));
        }
        let row_bytes = n as u64 * 8;
        // copy_texture_to_buffer needs rows aligned to 256 bytes.
        let padded_row = row_bytes.div_ceil(256) * 256;
        if faces as u64 * row_bytes * n as u64 > gpu.max_binding {
            return Err(failed(format!(
                "{n}² texels per face exceed the largest binding ({} bytes)",
                gpu.max_binding
            )));
        }
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let (pipeline, vertices, index_buf) = (&self.pipeline, &self.vertices, &self.index_buf);
        let timer = super::Timer::new(gpu, faces as u32);
        let extent = wgpu::Extent3d {
            width: n,
            height: n,
            depth_or_array_layers: 1,
        };
        let target = gpu.texture_2d(
            "vsm moments",
            (n, n),
            wgpu::TextureFormat::Rg32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let depth = gpu.texture_2d(
            "vsm depth",
            (n, n),
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let target_view = target.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        // The faces' moments, padded rows, one face after another.
        // Dense rows (n a multiple of 32) let the blur run on the copied faces directly, with
        // one read-back; otherwise the rows are unpadded on the CPU first.
        let dense = padded_row == row_bytes;
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vsm faces"),
            size: faces as u64 * padded_row * n as u64,
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
                scale: setup.scale,
                light: setup.position.to_array(),
                orthographic: setup.orthographic as u32,
            };
            let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("vsm face"),
                contents: bytemuck::bytes_of(&face),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind = gpu.bind_buffers(&pipeline.get_bind_group_layout(0), &[&uniform]);
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
        let raster_time = |gpu: &Gpu| timer.as_ref().map(|t| t.read_total(gpu)).transpose();
        let (raster, (moments, blur_time)) = if dense && blur > 0 {
            gpu.wait("shadow map")?;
            gpu.check("shadow map")?;
            (
                raster_time(gpu)?,
                self.blur_buffer(&staging, n, faces, blur)?,
            )
        } else {
            let bytes =
                gpu.read_back(&staging, faces as u64 * padded_row * n as u64, "shadow map")?;
            gpu.check("shadow map")?;
            // Unpad the rows. The vertex shader maps v to NDC y = −v / margin, so the
            // framebuffer's row 0 (NDC y = +1) is v = −margin, the CPU's row 0: no flip.
            let floats = f32s(&bytes);
            let row_floats = (padded_row / 4) as usize;
            let n = n as usize;
            let mut moments = vec![Vec2::ZERO; faces * n * n];
            for face in 0..faces {
                for row in 0..n {
                    let src = (face * n + row) * row_floats;
                    let dst = (face * n + row) * n;
                    for i in 0..n {
                        moments[dst + i] = Vec2::new(floats[src + 2 * i], floats[src + 2 * i + 1]);
                    }
                }
            }
            let blurred = if blur == 0 {
                (moments, Some(0.0))
            } else {
                self.blur_faces(&moments, n as u32, faces, blur)?
            };
            (raster_time(gpu)?, blurred)
        };
        let times = raster
            .zip(blur_time)
            .map(|(raster, blur)| PassTimes { raster, blur });
        Ok((moments, times))
    }

    /// The separable blur of `faces` n × n faces on the GPU (two dispatches).
    fn blur_faces(
        &self,
        moments: &[Vec2],
        n: u32,
        faces: usize,
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
        self.blur_buffer(&a, n, faces, radius)
    }

    /// The blur of `faces` dense n × n faces held in `a` (a storage buffer), in place, read
    /// back.
    fn blur_buffer(
        &self,
        a: &wgpu::Buffer,
        n: u32,
        faces: usize,
        radius: u32,
    ) -> Result<(Vec<Vec2>, Option<f64>), GpuError> {
        let gpu = self.gpu;
        let device = &gpu.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = &self.blur_pipeline;
        let timer = super::Timer::new(gpu, 2);
        let bytes = faces as u64 * (n as u64) * (n as u64) * 8;
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
            let bind = gpu.bind_buffers(&pipeline.get_bind_group_layout(0), &[&uniform, src, dst]);
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("vsm_blur"),
                timestamp_writes: timer.as_ref().map(|t| t.compute_writes(vertical)),
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(n.div_ceil(8), n.div_ceil(8), faces as u32);
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
        let blur_time = timer.as_ref().map(|t| t.read_total(gpu)).transpose()?;
        let moments = f32s(&out).chunks_exact(2).map(Vec2::from_slice).collect();
        Ok((moments, blur_time))
    }
}

/// GPU time of the shadow-map passes from timestamp queries, in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassTimes {
    /// The faces' rasterisation.
    pub raster: f64,
    /// The two blur dispatches (0 without a blur).
    pub blur: f64,
}
