//! The PRT image pass: every pixel sample interpolates the relit radiance of its triangle's
//! vertices (barycentric, as a rasteriser would). The transfer and the relighting are in
//! [`crate::precompute::prt`] and `render::gpu::prt`.

use super::Progress;
use super::sg::sample_offset;
use crate::accel::Accel;
use crate::image::Image;
use crate::scene::Scene;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::Ordering;

/// What the image pass draws.
#[derive(Clone, Copy, Debug)]
pub struct PrtImageOptions {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel (1: the centre; a square number: a jittered grid).
    pub spp: u32,
    pub seed: u64,
}

/// Renders the image from per-vertex radiance (`vertex_radiance[v]`, already relit); `None` when
/// cancelled. Camera rays that miss stay black, as in every method.
pub fn render_prt_image(
    scene: &Scene,
    accel: &Accel,
    vertex_radiance: &[Vec3],
    opts: &PrtImageOptions,
    progress: &Progress,
) -> Option<Image> {
    let camera = scene.camera.with_resolution(opts.width, opts.height);
    let mut img = Image::new(opts.width, opts.height);
    let w = opts.width as usize;
    img.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        if progress.cancel.load(Ordering::Relaxed) {
            return;
        }
        for (x, out) in row.iter_mut().enumerate() {
            // Per pixel as well as per row: a row at a high spp can take many seconds.
            if progress.cancel.load(Ordering::Relaxed) {
                return;
            }
            let pixel = (y * w + x) as u64;
            let mut sum = DVec3::ZERO;
            for s in 0..opts.spp {
                let o = sample_offset(opts.spp, s, opts.seed, pixel);
                let dir = camera.ray_dir(x as f32 + o.x, y as f32 + o.y);
                let Some(hit) = accel.intersect(camera.position, dir, 0.0, f32::INFINITY) else {
                    continue;
                };
                let [a, b, c] = scene.mesh.indices[hit.tri as usize];
                let l = vertex_radiance[a as usize] * (1.0 - hit.u - hit.v)
                    + vertex_radiance[b as usize] * hit.u
                    + vertex_radiance[c as usize] * hit.v;
                sum += l.max(Vec3::ZERO).as_dvec3();
            }
            *out = (sum / opts.spp as f64).as_vec3();
        }
        (progress.done)(1);
    });
    (!progress.cancel.load(Ordering::Relaxed)).then_some(img)
}
