//! The GPU path (wgpu; on machines without a GPU, Mesa's lavapipe). This is the only module
//! that imports wgpu. Each pass has one WGSL file under `shaders/` named after it and a Rust twin
//! of the same name on the CPU, which the GPU tests compare it with.
//!
//! Every pass's source is `shaders/shared/*.wgsl` (the layouts of [`layout`], mirrored, and the
//! WGSL math twins) followed by its own file ([`shaders::source`]).
//!
//! Passes so far: [`prt::relight`] (`shaders/prt_relight.wgsl`) and [`twins::run`]
//! (`shaders/math_twins.wgsl`, which runs the WGSL math functions over a table for the tests).

pub mod direct;
pub mod gbuffer;
pub mod ism;
pub mod layout;
pub mod prt;
pub mod sg_shade;
pub mod shaders;
pub mod tonemap;
pub mod twins;
pub mod vpl;
pub mod vpl_gen;
pub mod vsm;
pub mod window;

use std::sync::{Arc, Mutex};

/// Why the GPU path could not run.
#[derive(thiserror::Error, Debug)]
pub enum GpuError {
    #[error(
        "no GPU adapter found ({0}); on a machine without a GPU install the software Vulkan driver (scripts/install-deps.sh installs mesa-vulkan-drivers), or render with --device cpu"
    )]
    NoAdapter(String),
    #[error("cannot open the GPU device of adapter \"{adapter}\": {reason}")]
    Device { adapter: String, reason: String },
    #[error("GPU {what}: {reason}")]
    Failed { what: String, reason: String },
}

/// Longest wait for the GPU to finish submitted work before giving up with an error.
pub const WAIT_LIMIT: std::time::Duration = std::time::Duration::from_secs(120);

/// An open device and its queue.
pub struct Gpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    /// Adapter name and backend, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)".
    pub adapter: String,
    /// Largest storage-buffer binding, in bytes (128 MiB on lavapipe).
    pub max_binding: u64,
    /// Errors the device reported outside an error scope (validation, out of memory).
    uncaptured: Arc<Mutex<Vec<String>>>,
    /// Nanoseconds per timestamp tick, when the device has timestamp queries.
    timestamp_period: Option<f32>,
    /// The compute pipelines built so far, by pass: lavapipe compiles a pipeline when it is
    /// created (from Mesa's disk cache after the first time, still tens of milliseconds).
    pipelines: Mutex<std::collections::HashMap<String, wgpu::ComputePipeline>>,
}

/// Opens a device on `adapter` (named `name` in errors) with all its limits and `features`.
pub(crate) fn open_device(
    adapter: &wgpu::Adapter,
    name: &str,
    label: &str,
    features: wgpu::Features,
) -> Result<(wgpu::Device, wgpu::Queue), GpuError> {
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some(label),
        required_features: features,
        required_limits: adapter.limits(),
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    }))
    .map_err(|e| GpuError::Device {
        adapter: name.to_string(),
        reason: e.to_string(),
    })
}

/// The process's shared device ([`Gpu::shared`]).
static SHARED: Mutex<Option<Arc<Gpu>>> = Mutex::new(None);

/// Timestamp queries around passes: pass `k` writes its start to query 2k and its end to
/// 2k + 1; [`Timer::resolve`] appends the copy, [`Timer::read`] returns each pass's duration.
pub(crate) struct Timer {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readable: wgpu::Buffer,
    passes: u32,
    period: f32,
}

impl Timer {
    /// A timer for `passes` passes, or `None` when the device has no timestamps.
    pub(crate) fn new(gpu: &Gpu, passes: u32) -> Option<Timer> {
        let period = gpu.timestamp_period?;
        let count = 2 * passes.max(1);
        let bytes = count as u64 * 8;
        Some(Timer {
            set: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readable: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps read"),
                size: bytes,
                usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            passes: passes.max(1),
            period,
        })
    }

    pub(crate) fn render_writes(&self, k: u32) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        }
    }

    pub(crate) fn compute_writes(&self, k: u32) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        }
    }

    pub(crate) fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        let n = 2 * self.passes;
        enc.resolve_query_set(&self.set, 0..n, &self.resolve, 0);
        enc.copy_buffer_to_buffer(&self.resolve, 0, &self.readable, 0, n as u64 * 8);
    }

    /// The summed duration of the passes in seconds (see [`Self::read`]).
    pub(crate) fn read_total(&self, gpu: &Gpu) -> Result<f64, GpuError> {
        Ok(self.read(gpu)?.iter().sum())
    }

    /// Each pass's duration in seconds (after the work was submitted with [`Self::resolve`]).
    pub(crate) fn read(&self, gpu: &Gpu) -> Result<Vec<f64>, GpuError> {
        let bytes = gpu.read_back(&self.readable, 2 * self.passes as u64 * 8, "timestamps")?;
        let ticks: Vec<u64> = bytes
            .chunks_exact(8)
            .map(|b| u64::from_ne_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
            .collect();
        Ok(ticks
            .chunks_exact(2)
            .map(|t| t[1].saturating_sub(t[0]) as f64 * self.period as f64 * 1e-9)
            .collect())
    }
}

impl Gpu {
    /// Opens the first adapter wgpu finds (high-performance preference), with that adapter's
    /// own limits. A missing adapter is an error, never a panic.
    pub fn new() -> Result<Gpu, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let name = format!("{} ({:?})", info.name, info.backend);
        let limits = adapter.limits();
        // Timestamps, for per-pass GPU times, where the adapter has them.
        let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let (device, queue) = open_device(&adapter, &name, "interreflect", features)?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let lost = uncaptured.clone();
        device.set_device_lost_callback(move |reason, message| {
            if let Ok(mut v) = lost.lock() {
                v.push(format!("device lost ({reason:?}): {message}"));
            }
        });
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(describe(&e));
            }
        }));
        let timestamp_period = features
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| queue.get_timestamp_period());
        Ok(Gpu {
            device,
            queue,
            timestamp_period,
            adapter: name,
            max_binding: limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size),
            uncaptured,
            pipelines: Mutex::new(std::collections::HashMap::new()),
        })
    }

    /// One device for the whole process, opened on first use: the renderer's passes share it
    /// (and its compiled pipelines) rather than each opening its own. A failure to open is
    /// returned, and the next call tries again.
    pub fn shared() -> Result<Arc<Gpu>, GpuError> {
        let mut cell = SHARED.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(g) = cell.as_ref() {
            return Ok(g.clone());
        }
        let g = Arc::new(Gpu::new()?);
        *cell = Some(g.clone());
        Ok(g)
    }

    /// The assembled shader of `pass` (`shaders::source`), compiled.
    fn shader(&self, pass: &str) -> wgpu::ShaderModule {
        self.device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(pass),
                source: wgpu::ShaderSource::Wgsl(
                    shaders::source(pass).expect("a known pass").into(),
                ),
            })
    }

    /// The compute pipeline of `pass`, whose entry point has the pass's name.
    fn compute_pipeline(&self, pass: &str) -> wgpu::ComputePipeline {
        self.compute_entry(pass, pass, None)
    }

    /// The compute pipeline of `pass` for the scene's `materials`: the shared BRDF code compiled
    /// with only the models they use (the `BRDF_MODELS` override, [`layout::brdf_models`]).
    fn compute_pipeline_for(
        &self,
        pass: &str,
        materials: &[layout::GpuBrdf],
    ) -> wgpu::ComputePipeline {
        let models = layout::brdf_models(materials);
        self.compute_with(pass, pass, None, &[("BRDF_MODELS", f64::from(models))])
    }

    /// A pipeline layout of one bind group whose binding i is a buffer of kind `bindings[i]`
    /// (compute stage): for a pass whose entry points share bind groups but not all bindings.
    fn buffer_layout(
        &self,
        label: &str,
        bindings: &[wgpu::BufferBindingType],
    ) -> wgpu::PipelineLayout {
        let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
            .iter()
            .enumerate()
            .map(|(i, &ty)| wgpu::BindGroupLayoutEntry {
                binding: i as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            })
            .collect();
        let group = self
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &entries,
            });
        self.device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(&group)],
                immediate_size: 0,
            })
    }

    /// The compute pipeline of entry point `entry` of `pass`, with `layout` (or the layout
    /// derived from what the entry point uses). Built once per device and (pass, entry).
    fn compute_entry(
        &self,
        pass: &str,
        entry: &str,
        layout: Option<&wgpu::PipelineLayout>,
    ) -> wgpu::ComputePipeline {
        self.compute_with(pass, entry, layout, &[])
    }

    /// [`Self::compute_entry`] with values for the shader's override constants.
    fn compute_with(
        &self,
        pass: &str,
        entry: &str,
        layout: Option<&wgpu::PipelineLayout>,
        constants: &[(&str, f64)],
    ) -> wgpu::ComputePipeline {
        let mut key = if entry == pass {
            pass.to_string()
        } else {
            format!("{pass}:{entry}")
        };
        for (name, value) in constants {
            key.push_str(&format!(" {name}={value}"));
        }
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = cache.get(&key) {
            return p.clone();
        }
        let module = self.shader(pass);
        let p = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&key),
                layout,
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                cache: None,
            });
        cache.insert(key, p.clone());
        p
    }

    /// The render pipeline of `pass` that rasterises triangle lists of `vec3<f32>` positions
    /// (both faces), keeps the nearest fragment (32-bit depth, less) and writes one `format`
    /// target: the vertex entry is `<pass>_vertex`, the fragment entry `<pass>`.
    fn raster_pipeline(&self, pass: &str, format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
        let module = self.shader(pass);
        let vertex_entry = format!("{pass}_vertex");
        self.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(pass),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(&vertex_entry),
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
                    entry_point: Some(pass),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
    }

    /// A 2-D texture of `width` × `height` texels, one mip level, one sample.
    fn texture_2d(
        &self,
        label: &str,
        (width, height): (u32, u32),
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    }

    /// A bind group of `layout` with `buffers[i]` at binding i.
    /// A read-only storage buffer holding `bytes`, or an error naming `what`'s `label` and
    /// `hint` (what the user can change) when it exceeds the binding limit.
    fn storage_buffer(
        &self,
        what: &str,
        label: &str,
        bytes: &[u8],
        hint: &str,
    ) -> Result<wgpu::Buffer, GpuError> {
        use wgpu::util::DeviceExt;
        if bytes.len() as u64 > self.max_binding {
            return Err(GpuError::Failed {
                what: what.into(),
                reason: format!(
                    "the {label} ({} bytes) exceed the largest binding ({} bytes); {hint}",
                    bytes.len(),
                    self.max_binding
                ),
            });
        }
        Ok(self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            }))
    }

    fn bind_buffers(
        &self,
        layout: &wgpu::BindGroupLayout,
        buffers: &[&wgpu::Buffer],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout,
            entries: &entries,
        })
    }

    /// Fails with the first error the device reported outside an error scope, if any.
    fn check(&self, what: &str) -> Result<(), GpuError> {
        let first = self
            .uncaptured
            .lock()
            .ok()
            .and_then(|mut v| (!v.is_empty()).then(|| v.remove(0)));
        match first {
            Some(reason) => Err(GpuError::Failed {
                what: what.into(),
                reason,
            }),
            None => Ok(()),
        }
    }

    /// Waits for all submitted work, at most [`WAIT_LIMIT`]: a lost or hung device is an error,
    /// never a hang.
    fn wait(&self, what: &str) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: Some(WAIT_LIMIT),
            })
            .map_err(|e| GpuError::Failed {
                what: what.into(),
                reason: e.to_string(),
            })?;
        Ok(())
    }

    /// Copies `bytes` bytes of a GPU buffer back to the CPU.
    fn read_back(&self, src: &wgpu::Buffer, bytes: u64, what: &str) -> Result<Vec<u8>, GpuError> {
        self.read_back_range(src, 0, bytes, what)
    }

    /// Copies `bytes` bytes of a GPU buffer, from byte `offset` on, back to the CPU.
    fn read_back_range(
        &self,
        src: &wgpu::Buffer,
        offset: u64,
        bytes: u64,
        what: &str,
    ) -> Result<Vec<u8>, GpuError> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read back"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        enc.copy_buffer_to_buffer(src, offset, &staging, 0, bytes);
        self.queue.submit([enc.finish()]);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait(what)?;
        let failed = |reason: String| GpuError::Failed {
            what: what.into(),
            reason,
        };
        rx.recv()
            .map_err(|e| failed(e.to_string()))?
            .map_err(|e| failed(e.to_string()))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| failed(e.to_string()))?
            .to_vec();
        staging.unmap();
        Ok(data)
    }
}

/// Workgroups of 64 in x per dispatch row; more items go to further rows in y.
const ROW_WORKGROUPS: u32 = 1024;

/// The dispatch grid (x, y) of workgroups of 64 for `count` items, at most [`ROW_WORKGROUPS`]
/// per row: item i is at `gid.y * x * 64 + gid.x`.
fn dispatch_grid(count: u32) -> (u32, u32) {
    let groups = count.div_ceil(64);
    if groups <= ROW_WORKGROUPS {
        (groups, 1)
    } else {
        (ROW_WORKGROUPS, groups.div_ceil(ROW_WORKGROUPS))
    }
}

/// Native-endian f32s of read-back bytes (the bytes need not be aligned for f32).
fn f32s(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// The useful part of a wgpu error: its description (its `Display` says only "Validation
/// Error"), on one line.
pub(crate) fn describe(e: &wgpu::Error) -> String {
    match e {
        wgpu::Error::Validation { description, .. } | wgpu::Error::Internal { description, .. } => {
            description.split_whitespace().collect::<Vec<_>>().join(" ")
        }
        wgpu::Error::OutOfMemory { .. } => "out of GPU memory".into(),
    }
}

/// Whether the environment asks GPU tests to fail rather than skip when no adapter exists
/// (`CI=true`).
pub fn adapter_required() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true" || v == "1")
}
