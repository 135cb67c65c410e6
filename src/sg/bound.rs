//! The error bound of a tree node at a receiver point (`docs/sg-renderer.md`, "The error
//! bound"): an upper bound of every leaf's contribution summed, so that both the leaves' sum and
//! the node's clamped approximation lie in [0, bound].

use super::lighting::{LitNode, LitScene, SHARPNESS_BINS};
use super::transport::receiver::ReceiverLobes;
use super::tree::{Node, NormalCone};
use crate::math::luminance;
use glam::Vec3;

impl LitScene<'_> {
    /// Upper bound (per channel) of the summed SG contribution of the triangles under `node` at
    /// receiver `x`, without visibility (visibility only lowers it). Zero for a leaf, whose
    /// value is exact; infinite when x lies inside the node's bounding box.
    pub fn bound(&self, node: u32, x: Vec3, rx: &ReceiverLobes) -> Vec3 {
        let n = &self.tree.nodes[node as usize];
        let lit = &self.nodes[node as usize];
        if n.is_leaf() || !(lit.weight > 0.0) {
            return Vec3::ZERO;
        }
        node_bound(n, lit, x, rx)
    }

    /// The factors of [`Self::bound`] (see `node_bound_parts`), for diagnostics.
    #[cfg(test)]
    pub(crate) fn bound_parts(&self, node: u32, x: Vec3, rx: &ReceiverLobes) -> [f32; 6] {
        let mut parts = [0.0; 6];
        let n = &self.tree.nodes[node as usize];
        node_bound_parts(n, &self.nodes[node as usize], x, rx, Some(&mut parts));
        parts
    }
}

/// Upper bound of Σ_i ∫_{Ω_i} L_i f_x cos dω over the triangles i under `n`: each triangle's
/// solid angle is at most A_i / d_min², the cosine at most 1, the receiver lobes at most their
/// maximum over the cone of directions to the node's bounding sphere, and the reflected
/// radiance at most its diffuse part plus each lobe's peak times its falloff: a triangle's lobes,
/// re-aimed at x, peak towards x → its light image and have at least their own sharpness (the
/// re-aiming only sharpens), so over the node they are at most exp(λ_min (cos γ − 1)) with γ the
/// smallest angle at x between the node's bounding sphere and the images' bounding sphere.
pub fn node_bound(n: &Node, lit: &LitNode, x: Vec3, rx: &ReceiverLobes) -> Vec3 {
    node_bound_parts(n, lit, x, rx, None)
}

/// [`node_bound`], with its factors written to `parts` when given (diagnostics): [luminance of
/// the radiance bound, of hmax, cos_max / d², gap (radians, −1 when none), image radius angle,
/// node half-angle].
fn node_bound_parts(
    n: &Node,
    lit: &LitNode,
    x: Vec3,
    rx: &ReceiverLobes,
    mut parts: Option<&mut [f32; 6]>,
) -> Vec3 {
    let (lo, hi) = (n.bbox_min, n.bbox_max);
    // Entirely below the receiver's horizon: nothing arrives (the transport clips to it).
    let nx = rx.normal;
    let mut above = false;
    for i in 0..8 {
        let corner = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        if nx.dot(corner - x) > 0.0 {
            above = true;
            break;
        }
    }
    if !above {
        return Vec3::ZERO;
    }
    let d2 = (x.clamp(lo, hi) - x).length_squared();
    if !(d2 > 0.0) {
        return Vec3::splat(f32::INFINITY);
    }
    let centre = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let to_c = centre - x;
    let dist = to_c.length();
    let mut hmax = rx.diffuse;
    let cone = (dist > radius).then(|| (to_c / dist, (radius / dist).asin()));
    match cone {
        Some((dir, half)) => {
            // An anisotropic receiver lobe is wider by its stretch in one direction.
            let widest = 1.0 / rx.stretch();
            for h in rx.lobes() {
                let gap = (angle(h.axis, dir) - half).max(0.0);
                hmax += h.amplitude * (h.sharpness * widest * cos_minus_one(gap)).min(0.0).exp();
            }
        }
        None => {
            for h in rx.lobes() {
                hmax += h.amplitude;
            }
        }
    }
    let gap = match cone {
        Some((dir, half)) if lit.image_min.x <= lit.image_max.x => {
            let ic = 0.5 * (lit.image_min + lit.image_max);
            let ir = 0.5 * (lit.image_max - lit.image_min).length();
            let to_i = ic - x;
            let di = to_i.length();
            if let Some(p) = parts.as_deref_mut() {
                p[4] = (ir / di).min(1.0).asin();
                p[5] = half;
            }
            (di > ir).then(|| (angle(dir, to_i / di) - half - (ir / di).asin()).max(0.0))
        }
        _ => None,
    };
    let radiance = radiance_bound(lit, gap);
    let cos_max = cos_max_bound(n.cone, cone);
    if let Some(p) = parts {
        p[..4].copy_from_slice(&[
            luminance(radiance),
            luminance(hmax),
            cos_max / d2,
            gap.unwrap_or(-1.0),
        ]);
    }
    // 1e-3: headroom for the rounding of the f32 sums and of the quadrature (≤ 5e-7 relative).
    radiance * hmax * (1.001 * cos_max / d2)
}

/// The reflected radiance of the node's triangles towards directions at least `gap` (radians;
/// `None`: no gap known) from their lobes' peaks: the diffuse part plus each sharpness bin's
/// peak falling off with the bin's lower edge.
pub(crate) fn radiance_bound(lit: &LitNode, gap: Option<f32>) -> Vec3 {
    let mut radiance = lit.diffuse;
    for (edge, peak) in SHARPNESS_BINS.iter().zip(&lit.peak_by_sharpness) {
        let f = match gap {
            Some(g) => (edge * cos_minus_one(g)).min(0.0).exp(),
            None => 1.0,
        };
        radiance += *peak * f;
    }
    radiance
}

/// Each triangle's solid angle is ∫ cos θ_y / r² dA ≤ A cos_max / d²: the largest |cos| between
/// a normal of the node's cone `normals` (either orientation) and a direction of the cone
/// `towards` (axis, half-angle) from the receiver to the node; 1 when either is unknown.
pub(crate) fn cos_max_bound(normals: Option<NormalCone>, towards: Option<(Vec3, f32)>) -> f32 {
    match (towards, normals) {
        (Some((dir, half)), Some(c)) => {
            let g = angle(c.axis, dir);
            let g = g.min(std::f32::consts::PI - g);
            (g - c.half_angle - half).max(0.0).cos()
        }
        _ => 1.0,
    }
}

/// cos γ − 1 as −2 sin²(γ/2): exact to rounding for small γ, where cos γ − 1 would cancel (and
/// an exponent λ (cos γ − 1) of a sharp lobe magnify the cancellation).
#[inline]
pub fn cos_minus_one(g: f32) -> f32 {
    let s = (0.5 * g).sin();
    -2.0 * s * s
}

/// The angle between two unit vectors, accurate near 0 and π.
#[inline]
pub(crate) fn angle(a: Vec3, b: Vec3) -> f32 {
    a.cross(b).length().atan2(a.dot(b))
}
