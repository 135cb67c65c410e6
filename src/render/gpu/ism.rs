//! Imperfect shadow maps on the GPU (`shaders/ism.wgsl`): every VPL's sparse point set splatted
//! into its paraboloid map, each texel's nearest layer of points kept, the holes filled by
//! pull-push and the moments blurred. Rust twin: [`ImperfectShadowMaps::build`]. The points are
//! sampled on the CPU by the same [`IsmSampler`] (a random stream per VPL, drawn in order), so
//! both sides splat the same points; the pass does the rest (projection, the per-texel layers,
//! pull-push, blur) for all maps at once, one dispatch per phase and pyramid level.
//!
//! Per-texel sums are added with integer atomics as 64-bit fixed point, so the result does not
//! depend on the order the lanes run in; the CPU adds in f32 in point order, which is why the
//! two differ by rounding (`tests/gpu_ism.rs`).

use super::layout::{GpuIsmParams, GpuMapOrigin};
use super::{Gpu, GpuError, describe, f32s};
use crate::precompute::vpl::Vpl;
use crate::visibility::ism::{FRONT_LAYER, ImperfectShadowMaps, IsmOptions, IsmSampler};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use wgpu::util::DeviceExt;

fn failed(reason: impl Into<String>) -> GpuError {
    GpuError::Failed {
        what: "imperfect shadow maps".into(),
        reason: reason.into(),
    }
}

/// Invocations per workgroup, as in the shader.
const GROUP: u32 = 64;
/// u32 words per texel of the splat buffer, as in the shader.
const TEXEL_WORDS: usize = 6;

/// The pass's entry points, in the order they run (`shaders/ism.wgsl`).
const ENTRIES: [&str; 6] = [
    "ism",
    "ism_layer",
    "ism_finest",
    "ism_pull",
    "ism_push",
    "ism_blur",
];
const NEAREST: usize = 0;
const LAYER: usize = 1;
const FINEST: usize = 2;
const PULL: usize = 3;
const PUSH: usize = 4;
const BLUR: usize = 5;

/// The pass's pipelines, [`ENTRIES`] in order, sharing one explicit layout (the uniform, the
/// points and origins read-only, the splats, pyramid and atlas read-write), since some entry
/// points use only some of the bindings.
fn pipelines(gpu: &Gpu) -> Vec<wgpu::ComputePipeline> {
    use wgpu::BufferBindingType::{Storage, Uniform};
    let read = Storage { read_only: true };
    let write = Storage { read_only: false };
    let layout = gpu.buffer_layout("ism", &[Uniform, read, read, write, write, write]);
    ENTRIES
        .iter()
        .map(|e| gpu.compute_entry("ism", e, Some(&layout)))
        .collect()
}

/// The pull-push pyramid's levels: (texels per side, first entry), finest first.
fn levels(res: usize) -> Vec<(usize, usize)> {
    let mut out = vec![(res, 0)];
    while let Some(&(n, at)) = out.last().filter(|l| l.0 > 1) {
        out.push((n.div_ceil(2), at + n * n));
    }
    out
}

/// Maps of `opts`' size the pass can splat per dispatch, or why it cannot splat them at all
/// (more points per map than one dispatch row, or one map's buffers over the binding limit):
/// checked before any point is drawn, and by `render --device gpu` before rendering.
pub fn maps_per_dispatch(gpu: &Gpu, opts: &IsmOptions) -> Result<usize, GpuError> {
    let res = opts.resolution.max(2) as usize;
    let per = opts.points_per_map as usize;
    let texels = res * res;
    if per.div_ceil(GROUP as usize) > 65_535 {
        return Err(failed(format!(
            "{per} points per map exceed one dispatch row ({} at most); lower [visibility] ism_points, or render with --device cpu",
            65_535 * GROUP
        )));
    }
    let pyramid_len: usize = levels(res).iter().map(|(n, _)| n * n).sum();
    // Within the binding limit for every buffer, and the dispatch limit.
    let per_map_bytes = [
        per * 16,
        texels * TEXEL_WORDS * 4 + 4,
        pyramid_len * 16,
        texels * 8,
    ];
    let largest = per_map_bytes.iter().copied().max().unwrap_or(1).max(1) as u64;
    let chunk = ((gpu.max_binding / largest) as usize).min(65_535);
    if chunk == 0 {
        return Err(failed(format!(
            "one map's buffers ({largest} bytes) exceed the largest binding ({} bytes); lower [visibility] ism_points or ism_resolution, or render with --device cpu",
            gpu.max_binding
        )));
    }
    Ok(chunk)
}

/// The imperfect shadow maps of `vpls`, splatted on the GPU: the same maps as
/// [`ImperfectShadowMaps::build`] with the same arguments, to rounding.
pub fn build(
    gpu: &Gpu,
    positions: &[Vec3],
    indices: &[[u32; 3]],
    vpls: &[Vpl],
    opts: &IsmOptions,
    seed: u64,
) -> Result<ImperfectShadowMaps, GpuError> {
    let sampler = IsmSampler::new(positions, indices, vpls, opts, seed);
    let (res, per) = (sampler.res, sampler.points_per_map);
    let texels = res * res;
    let levels = levels(res);
    let pyramid_len: usize = levels.iter().map(|(n, _)| n * n).sum();
    let chunk = maps_per_dispatch(gpu, opts)?;
    let device = &gpu.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let pipelines = pipelines(gpu);
    let layout = pipelines[0].get_bind_group_layout(0);
    let mut atlas: Vec<Vec2> = Vec::with_capacity(sampler.origins.len() * texels);
    let mut far: Vec<f32> = Vec::with_capacity(sampler.origins.len());
    let maps: Vec<usize> = (0..sampler.origins.len()).collect();
    for group in maps.chunks(chunk) {
        let first = group[0];
        let count = group.len();
        // The points, map after map (w = 0: no point).
        let mut pts = vec![[0.0f32; 4]; count * per];
        pts.par_chunks_mut(per.max(1))
            .zip(group.par_iter())
            .for_each_init(
                || vec![None; per],
                |scratch, (out, &i)| {
                    sampler.map_points(i, scratch);
                    for (o, p) in out.iter_mut().zip(scratch.iter()) {
                        if let Some(p) = p {
                            *o = [p.x, p.y, p.z, 1.0];
                        }
                    }
                },
            );
        let origins: Vec<GpuMapOrigin> = sampler.origins[first..first + count]
            .iter()
            .map(|(y, frame)| GpuMapOrigin {
                position: y.to_array(),
                t: frame.t.to_array(),
                b: frame.b.to_array(),
                n: frame.n.to_array(),
                ..GpuMapOrigin::default()
            })
            .collect();
        let storage = |label: &str, bytes: &[u8]| {
            gpu.storage_buffer(
                "imperfect shadow maps",
                label,
                bytes,
                "lower [visibility] ism_points or ism_resolution, or render with --device cpu",
            )
        };
        let points_buf = storage("points", bytemuck::cast_slice(&pts))?;
        let origins_buf = storage("map origins", bytemuck::cast_slice(&origins))?;
        let scratch = |label: &str, bytes: usize, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(4) as u64,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        let splat_words = count * texels * TEXEL_WORDS;
        let splats = scratch(
            "ism splats",
            (splat_words + count) * 4,
            wgpu::BufferUsages::COPY_SRC,
        );
        let pyramid = scratch(
            "ism pyramid",
            count * pyramid_len * 16,
            wgpu::BufferUsages::empty(),
        );
        let atlas_bytes = (count * texels * 8) as u64;
        let atlas_buf = scratch(
            "ism atlas",
            atlas_bytes as usize,
            wgpu::BufferUsages::COPY_SRC,
        );
        let base = GpuIsmParams {
            res: res as u32,
            points_per_map: per as u32,
            maps: count as u32,
            pyramid_len: pyramid_len as u32,
            blur: u32::from(opts.blur),
            front_layer: FRONT_LAYER,
            ..GpuIsmParams::default()
        };
        // The phases in order: the entry point, its uniform, the items (per map) it covers.
        let mut phases: Vec<(usize, GpuIsmParams, usize)> = vec![
            (NEAREST, base, per),
            (LAYER, base, per),
            (FINEST, base, texels),
        ];
        for pair in levels.windows(2) {
            let [(fine_n, fine_at), (n, at)] = [pair[0], pair[1]];
            let params = GpuIsmParams {
                level_n: n as u32,
                level_offset: at as u32,
                other_n: fine_n as u32,
                other_offset: fine_at as u32,
                ..base
            };
            phases.push((PULL, params, n * n));
        }
        for (l, &(n, at)) in levels.iter().enumerate().rev() {
            let coarser = levels.get(l + 1).copied();
            let params = GpuIsmParams {
                level_n: n as u32,
                level_offset: at as u32,
                other_n: coarser.map_or(0, |c| c.0 as u32),
                other_offset: coarser.map_or(0, |c| c.1 as u32),
                has_other: u32::from(coarser.is_some()),
                ..base
            };
            phases.push((PUSH, params, n * n));
        }
        phases.push((BLUR, base, texels));
        let mut enc =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        for (entry, params, items) in phases {
            let params_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("ism params"),
                contents: bytemuck::bytes_of(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind = gpu.bind_buffers(
                &layout,
                &[
                    &params_buf,
                    &points_buf,
                    &origins_buf,
                    &splats,
                    &pyramid,
                    &atlas_buf,
                ],
            );
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(ENTRIES[entry]),
                timestamp_writes: None,
            });
            pass.set_pipeline(&pipelines[entry]);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups((items as u32).div_ceil(GROUP), count as u32, 1);
        }
        gpu.queue.submit([enc.finish()]);
        let data = gpu.read_back(&atlas_buf, atlas_bytes, "imperfect shadow maps")?;
        atlas.extend(f32s(&data).chunks_exact(2).map(|v| Vec2::new(v[0], v[1])));
        let data = gpu.read_back_range(
            &splats,
            (splat_words * 4) as u64,
            (count * 4) as u64,
            "imperfect shadow maps",
        )?;
        far.extend(
            data.chunks_exact(4)
                .map(|b| f32::from_bits(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))),
        );
    }
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(failed(describe(&e)));
    }
    gpu.check("imperfect shadow maps")?;
    Ok(ImperfectShadowMaps::from_splats(
        sampler, atlas, &far, opts.bias,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pyramid_levels_halve_rounding_up() {
        assert_eq!(
            levels(32),
            vec![
                (32, 0),
                (16, 1024),
                (8, 1280),
                (4, 1344),
                (2, 1360),
                (1, 1364)
            ]
        );
        assert_eq!(levels(5), vec![(5, 0), (3, 25), (2, 34), (1, 38)]);
        assert_eq!(levels(2), vec![(2, 0), (1, 4)]);
    }
}
