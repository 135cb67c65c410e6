//! The viewer's window: a wgpu surface on a winit window that presents what egui paints (the
//! panel, and the rendered image as an egui texture). Its device is the window's own; the
//! renderer's passes keep using [`super::Gpu::shared`].

use super::GpuError;
use std::sync::Arc;

/// What egui painted this frame, in the window's physical pixels.
pub struct Painted<'a> {
    pub primitives: &'a [egui::ClippedPrimitive],
    pub textures: &'a egui::TexturesDelta,
    pub size: [u32; 2],
    pub pixels_per_point: f32,
}

/// The window's surface, device and egui renderer.
pub struct WindowGpu {
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    renderer: egui_wgpu::Renderer,
    /// Adapter name and backend.
    pub adapter: String,
    /// Largest texture side the device takes (egui needs it).
    pub max_texture_side: usize,
}

impl WindowGpu {
    /// Opens a surface on `window` and a device that can present to it.
    pub fn new(window: Arc<winit::window::Window>) -> Result<WindowGpu, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let size = window.inner_size();
        let surface = instance
            .create_surface(window)
            .map_err(|e| GpuError::Failed {
                what: "window surface".into(),
                reason: e.to_string(),
            })?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(&surface),
            apply_limit_buckets: false,
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let name = format!("{} ({:?})", info.name, info.backend);
        let (device, queue) = super::open_device(
            &adapter,
            &name,
            "interreflect viewer",
            wgpu::Features::empty(),
        )?;
        let caps = surface.get_capabilities(&adapter);
        // egui paints in gamma space: a non-sRGB format shows its colours as meant.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| GpuError::Failed {
                what: "window surface".into(),
                reason: format!("adapter {name} cannot present to this window"),
            })?;
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&device, &config);
        let renderer = egui_wgpu::Renderer::new(
            &device,
            format,
            egui_wgpu::RendererOptions {
                // Dithering costs a software GPU time on every pixel; the panel does not need it.
                dithering: false,
                ..egui_wgpu::RendererOptions::default()
            },
        );
        let max_texture_side = device.limits().max_texture_dimension_2d as usize;
        Ok(WindowGpu {
            surface,
            device,
            queue,
            config,
            renderer,
            adapter: name,
            max_texture_side,
        })
    }

    /// Follows the window's new size.
    pub fn resize(&mut self, width: u32, height: u32) {
        if width > 0 && height > 0 {
            self.config.width = width;
            self.config.height = height;
            self.surface.configure(&self.device, &self.config);
        }
    }

    /// Uploads egui's textures and draws its primitives to the window.
    pub fn paint(&mut self, p: &Painted<'_>) -> Result<(), GpuError> {
        for (id, deltas) in &p.textures.set {
            for delta in deltas {
                self.renderer
                    .update_texture(&self.device, &self.queue, *id, delta);
            }
        }
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.device, &self.config);
                return Ok(());
            }
            // Try again next frame.
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(());
            }
            other => {
                return Err(GpuError::Failed {
                    what: "window frame".into(),
                    reason: format!("{other:?}"),
                });
            }
        };
        let view = frame
            .texture
            .create_view(&wgpu::TextureViewDescriptor::default());
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: p.size,
            pixels_per_point: p.pixels_per_point,
        };
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("viewer"),
            });
        let extra = self.renderer.update_buffers(
            &self.device,
            &self.queue,
            &mut encoder,
            p.primitives,
            &screen,
        );
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    resolve_target: None,
                    depth_slice: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: 0.08,
                            g: 0.08,
                            b: 0.09,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let mut pass = pass.forget_lifetime();
            self.renderer.render(&mut pass, p.primitives, &screen);
        }
        self.queue
            .submit(extra.into_iter().chain(std::iter::once(encoder.finish())));
        self.queue.present(frame);
        for id in &p.textures.free {
            self.renderer.free_texture(id);
        }
        Ok(())
    }
}
