//! VPL generation's per-triangle weights on the GPU (`shaders/vpl_gen.wgsl`): for every
//! reflector triangle, the weight VPLs are sampled by — area × albedo luminance × the light's
//! irradiance at the centroid × (0.1 + 0.9 × its visibility from the light's variance shadow
//! map). Rust twin: [`crate::precompute::vpl::source_weights`] with the map's visibility. The
//! pass is the part of VPL generation whose work grows with the scene (one weight per
//! triangle); drawing the VPLs from the weights (200 samples of a distribution) stays on the
//! CPU, [`crate::precompute::vpl::generate_weighted`].

use super::layout::{GpuVplGenParams, GpuVplSource};
use super::{Gpu, GpuError, describe, f32s};
use crate::precompute::vpl::VplSource;
use crate::scene::Light;
use crate::visibility::vsm::VarianceShadowMap;
use wgpu::util::DeviceExt;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "VPL generation".into(),
        reason: reason.into(),
    }
}

impl From<&VplSource> for GpuVplSource {
    fn from(s: &VplSource) -> Self {
        GpuVplSource {
            v0: s.vertices[0].to_array(),
            v1: s.vertices[1].to_array(),
            v2: s.vertices[2].to_array(),
            albedo: s.albedo.to_array(),
            ..GpuVplSource::default()
        }
    }
}

/// Sources per dispatch: 65,535 workgroups of 64 invocations, the dispatch limit.
const CHUNK: usize = 65_535 * 64;

/// The weight of every source under `light`, its visibility from `map` (the light's variance
/// shadow map, looked up at the centroid offset by `eps` towards the light). Without a map the
/// light counts as unshadowed: callers with shadow rays use the CPU twin.
pub fn source_weights(
    gpu: &Gpu,
    sources: &[VplSource],
    light: &Light,
    map: Option<&VarianceShadowMap>,
    eps: f32,
) -> Result<Vec<f32>, GpuError> {
    if sources.is_empty() {
        return Ok(Vec::new());
    }
    let (lights, gpu_maps, moments) =
        super::direct::light_buffers(std::slice::from_ref(light), &[map]).map_err(failed)?;
    let gpu_sources: Vec<GpuVplSource> = sources.iter().map(GpuVplSource::from).collect();
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let pipeline = gpu.compute_pipeline("vpl_gen");
    let storage = |label: &str, bytes: &[u8]| {
        gpu.storage_buffer(
            "VPL generation",
            label,
            bytes,
            "render with --device cpu or a lower shadow-map resolution",
        )
    };
    let fixed = [
        storage("light", bytemuck::cast_slice(&lights))?,
        storage("shadow map", bytemuck::cast_slice(&gpu_maps))?,
        storage("shadow-map moments", bytemuck::cast_slice(&moments))?,
    ];
    let layout = pipeline.get_bind_group_layout(0);
    let mut out = Vec::with_capacity(sources.len());
    for chunk in gpu_sources.chunks(CHUNK) {
        let count = chunk.len();
        let sources_buf = storage("reflector triangles", bytemuck::cast_slice(chunk))?;
        let out_bytes = (count * 4) as u64;
        let weights = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl_gen weights"),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let params = GpuVplGenParams {
            count: count as u32,
            eps,
            ..GpuVplGenParams::default()
        };
        let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vpl_gen params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind = gpu.bind_buffers(
            &layout,
            &[
                &params_buf,
                &sources_buf,
                &fixed[0],
                &fixed[1],
                &fixed[2],
                &weights,
            ],
        );
        let mut enc =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("vpl_gen"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups((count as u32).div_ceil(64), 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        let data = gpu.read_back(&weights, out_bytes, "VPL generation")?;
        out.extend(f32s(&data));
    }
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(failed(describe(&e)));
    }
    gpu.check("VPL generation")?;
    Ok(out)
}
