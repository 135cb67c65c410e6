//! Direct light on the GPU (`shaders/direct.wgsl`): for every pixel sample, the light each
//! light reflects towards the eye through the sample's BRDF, its visibility from the light's
//! variance shadow map. Rust twin: `render::cpu::sg::direct_light` with a map per light (which
//! `sg` and `vpl` use with `--visibility vsm` or `approx`); the renderer hands its samples and
//! maps over with `--device gpu`.

use super::layout::{GpuBrdf, GpuDirectParams, GpuLight, GpuShadowMap, GpuSurfacePoint};
use super::{Gpu, GpuError, describe, f32s};
use crate::brdf::Brdf;
use crate::scene::Light;
use crate::visibility::vsm::{ShadowMapParts, VarianceShadowMap};
use glam::Vec3;
use std::sync::atomic::{AtomicBool, Ordering};
use wgpu::util::DeviceExt;

/// Points per dispatch, at most.
pub const POINT_CHUNK: usize = 1 << 18;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "direct light".into(),
        reason: reason.into(),
    }
}

impl GpuShadowMap {
    /// A map (`VarianceShadowMap::parts`), its moments starting at texel `first_texel` of the
    /// shared moments buffer.
    pub(crate) fn new(p: &ShadowMapParts, first_texel: u32) -> GpuShadowMap {
        let mut g = GpuShadowMap {
            origin: p.origin.to_array(),
            projection: p.projection,
            res: p.res,
            first_texel,
            margin: p.margin,
            min_variance: p.min_variance,
            bleeding: p.bleeding,
            scale: p.scale,
            ..GpuShadowMap::default()
        };
        for (k, [f, r, u]) in p.faces.iter().take(6).enumerate() {
            g.forward[k] = f.extend(0.0).to_array();
            g.right[k] = r.extend(0.0).to_array();
            g.up[k] = u.extend(0.0).to_array();
        }
        g
    }
}

/// The lights, their maps and the maps' texels as the passes that read shadow maps bind them
/// (`shaders/parts/shadow_map.wgsl`): light k's `map` indexes `maps[k]`'s entry, or is `NONE`.
/// Never empty (an unused map and texel stand in), since empty buffers cannot be bound.
#[allow(clippy::type_complexity)]
pub(crate) fn light_buffers(
    lights: &[Light],
    maps: &[Option<&VarianceShadowMap>],
) -> Result<(Vec<GpuLight>, Vec<GpuShadowMap>, Vec<[f32; 2]>), String> {
    let mut gpu_lights: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
    let mut gpu_maps = Vec::new();
    let mut moments: Vec<[f32; 2]> = Vec::new();
    for (k, m) in maps.iter().enumerate().take(lights.len()) {
        if let Some(m) = m {
            if moments.len() > u32::MAX as usize {
                return Err("the shadow maps hold more than 2^32 texels".into());
            }
            let parts = m.parts();
            gpu_lights[k].map = gpu_maps.len() as u32;
            gpu_maps.push(GpuShadowMap::new(&parts, moments.len() as u32));
            moments.extend(parts.moments.iter().map(|t| t.to_array()));
        }
    }
    if gpu_maps.is_empty() {
        gpu_maps.push(GpuShadowMap::default());
        moments.push([0.0; 2]);
    }
    Ok((gpu_lights, gpu_maps, moments))
}

/// The direct light at every point, summed over `lights` (`maps[k]` the shadow map of light
/// k; a light without one counts as unshadowed, so callers pass a map for every light);
/// `materials` are the scene's BRDFs, `eps` its ray epsilon. Points whose eye direction is
/// below their surface must be left out by the caller (they reflect nothing). `None` when
/// `cancel` was set (checked between dispatches).
pub fn direct(
    gpu: &Gpu,
    lights: &[Light],
    maps: &[Option<VarianceShadowMap>],
    materials: &[Brdf],
    points: &[GpuSurfacePoint],
    eps: f32,
    cancel: &AtomicBool,
) -> Result<Option<Vec<Vec3>>, GpuError> {
    if points.is_empty() || lights.is_empty() {
        return Ok(Some(vec![Vec3::ZERO; points.len()]));
    }
    if let Some(i) = points
        .iter()
        .position(|p| p.material as usize >= materials.len())
    {
        return Err(failed(format!("point {i} has no material")));
    }
    let maps: Vec<Option<&VarianceShadowMap>> = maps.iter().map(Option::as_ref).collect();
    let (gpu_lights, gpu_maps, moments) = light_buffers(lights, &maps).map_err(failed)?;
    let gpu_materials: Vec<GpuBrdf> = materials.iter().map(GpuBrdf::from).collect();
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let pipeline = gpu.compute_pipeline_for("direct", &gpu_materials);
    let storage = |label: &str, bytes: &[u8]| {
        gpu.storage_buffer(
            "direct light",
            label,
            bytes,
            "render with --device cpu or a lower shadow-map resolution",
        )
    };
    let bufs = [
        storage("lights", bytemuck::cast_slice(&gpu_lights))?,
        storage("shadow maps", bytemuck::cast_slice(&gpu_maps))?,
        storage("shadow-map moments", bytemuck::cast_slice(&moments))?,
        storage("materials", bytemuck::cast_slice(&gpu_materials))?,
    ];
    let layout = pipeline.get_bind_group_layout(0);
    let mut out = Vec::with_capacity(points.len());
    for chunk in points.chunks(POINT_CHUNK) {
        let count = chunk.len();
        let points_buf = storage("points", bytemuck::cast_slice(chunk))?;
        let out_bytes = (count * 16) as u64;
        let radiance = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("direct radiance"),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let params = GpuDirectParams {
            count: count as u32,
            light_count: gpu_lights.len() as u32,
            eps,
            ..GpuDirectParams::default()
        };
        let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("direct params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind = gpu.bind_buffers(
            &layout,
            &[
                &params_buf,
                &points_buf,
                &bufs[0],
                &bufs[1],
                &bufs[2],
                &bufs[3],
                &radiance,
            ],
        );
        let mut enc =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("direct"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups((count as u32).div_ceil(64), 1, 1);
        }
        gpu.queue.submit([enc.finish()]);
        let data = gpu.read_back(&radiance, out_bytes, "direct light")?;
        out.extend(
            f32s(&data)
                .chunks_exact(4)
                .map(|v| Vec3::new(v[0], v[1], v[2])),
        );
        if cancel.load(Ordering::Relaxed) {
            return Ok(None);
        }
    }
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(failed(describe(&e)));
    }
    gpu.check("direct light")?;
    Ok(Some(out))
}
