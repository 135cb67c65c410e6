//! The node approximation on SIMD lanes: one tree node shaded as one reflector at many
//! receiver points at once, lanes = receivers (the twin of `LitScene::cluster`, which stays the
//! oracle; `docs/sg-renderer.md`, "Shading a node as one reflector").
//!
//! Everything that depends on the node alone (its centroid, mean normal, merged lobes, the
//! light's mirror image in its plane) is computed once per node ([`NodeSummary`]); everything
//! that depends on the receiver (the cap of the node's solid angle, the re-aimed lobes, the
//! products with the receiver's lobes) per lane.

use super::lobes::{AnisoV, SgV, clamped_cosine_mean, tangent_of};
use super::receivers::ReceiversV;
use super::simd::Vf;
use super::v3::V3;
use crate::brdf::sg_fit::MAX_LOBES;
use crate::math::luminance;
use crate::sg::lighting::LitNode;
use crate::sg::transport::receiver::MAX_STRETCH;
use glam::Vec3;

/// One merged lobe slot of a node: its unaimed axis, 1/variance and peak (energy / variance /
/// area, RGB).
#[derive(Clone, Copy, Debug, Default)]
pub struct MergedLobe {
    pub axis: Vec3,
    pub inv_var: f32,
    pub amp: Vec3,
}

/// What the node approximation needs of a node, computed once per node and frame.
#[derive(Clone, Copy, Debug)]
pub struct NodeSummary {
    /// Something under the node is lit (weight and area > 0).
    pub valid: bool,
    pub centroid: Vec3,
    pub normal_sum: Vec3,
    pub area: f32,
    /// Unit mean normal (zero when the normals cancel).
    pub nbar: Vec3,
    /// Σ A d / A, the mean diffuse radiance; zero when the node has none.
    pub diffuse: Vec3,
    /// The light's height above the mean plane, its mirror image, cos θ at the centroid.
    pub h_l: f32,
    pub image: Vec3,
    pub cos_c: f32,
    /// Half-vector lobes with the anisotropic transport (the specular point's incidence).
    pub half_vector: bool,
    pub lobes: [MergedLobe; MAX_LOBES],
    pub n_lobes: usize,
}

impl NodeSummary {
    /// The summary of `lit` lit from `light_pos`; `anisotropic` as `ReceiverOptions`.
    pub fn new(lit: &LitNode, light_pos: Vec3, anisotropic: bool) -> NodeSummary {
        let valid = lit.weight > 0.0 && lit.area > 0.0;
        let centroid = if valid {
            lit.centroid_sum / lit.weight
        } else {
            Vec3::ZERO
        };
        let inv_area = if valid { 1.0 / lit.area } else { 0.0 };
        let nbar = lit.normal_sum.normalize_or_zero();
        let h_l = (light_pos - centroid).dot(nbar);
        let mut lobes = [MergedLobe::default(); MAX_LOBES];
        let mut n_lobes = 0;
        for l in &lit.lobes {
            let weight = luminance(l.energy);
            if !(weight > 0.0) {
                continue;
            }
            let mean_axis = l.axis_sum / weight;
            let rlen = mean_axis.length().min(1.0);
            let own = l.inv_sharpness_sum / weight;
            let var = (own + (1.0 - rlen)).max(1e-12);
            lobes[n_lobes] = MergedLobe {
                axis: mean_axis.normalize_or_zero(),
                inv_var: 1.0 / var,
                amp: l.energy * (inv_area / var),
            };
            n_lobes += 1;
        }
        NodeSummary {
            valid,
            centroid,
            normal_sum: lit.normal_sum,
            area: lit.area,
            nbar,
            diffuse: lit.diffuse * inv_area,
            h_l,
            image: light_pos - 2.0 * h_l * nbar,
            cos_c: h_l / (light_pos - centroid).length(),
            half_vector: lit.half_vector && anisotropic,
            lobes,
            n_lobes,
        }
    }
}

/// The node's approximate contribution (RGB, no visibility, not clamped) at every lane's
/// receiver, as `LitScene::cluster`.
#[inline(always)]
pub fn evaluate<V: Vf>(node: &NodeSummary, rx: &ReceiversV<V>) -> V3<V> {
    let zero = V::splat(0.0);
    let one = V::splat(1.0);
    let mut sum = V3::new(zero, zero, zero);
    if !node.valid {
        return sum;
    }
    let v = rx.x - V3::splat(node.centroid);
    let d2 = v.length_squared();
    let inv_d = d2.max(V::splat(1e-30)).rsqrt();
    let r = v.scale(inv_d);
    let proj = V3::splat(node.normal_sum).dot(r) * V::splat(1.0 / node.area);
    let live = d2.gt(zero) & proj.gt(zero);
    if !V::any(live) {
        return sum;
    }
    // The node's solid angle as a unit-height SG cap around −r with the same integral.
    let tau = V::splat(2.0 * std::f32::consts::PI);
    let omega = (V::splat(node.area) * proj * inv_d * inv_d)
        .max(V::splat(1e-12))
        .min(tau);
    let cap_sharp = tau * omega.recip();
    let cap_amp = omega * super::lobes::lobe_integral(cap_sharp).recip();
    let cap = SgV {
        axis: -r,
        sharp: cap_sharp,
        amp: V3::new(cap_amp, cap_amp, cap_amp),
    };
    let cap_a = AnisoV::isotropic(cap);
    let mut incoming: [Option<AnisoV<V>>; MAX_LOBES + 1] = [None; MAX_LOBES + 1];
    if node.diffuse != Vec3::ZERO {
        incoming[0] = Some(AnisoV::isotropic(SgV {
            amp: V3::new(
                cap_amp * V::splat(node.diffuse.x),
                cap_amp * V::splat(node.diffuse.y),
                cap_amp * V::splat(node.diffuse.z),
            ),
            ..cap
        }));
    }
    if node.n_lobes > 0 {
        // Mirror-image aiming about the mean plane (`LitScene::cluster`).
        let nbar = V3::splat(node.nbar);
        let h_l = V::splat(node.h_l);
        let h_x = v.dot(nbar);
        let to_x = rx.x - V3::splat(node.image);
        let dl2 = to_x.length_squared();
        let aim = h_x.gt(zero) & dl2.gt(zero) & V::splat(node.h_l).gt(zero);
        let axis_a = to_x.scale(dl2.max(V::splat(1e-30)).rsqrt());
        // (1 + d_x/d_l)² with d_l = d h_l / (h_l + h_x): ((h_l + h_x) / h_l)².
        let ratio = (h_l + h_x) * h_l.max(V::splat(1e-30)).recip();
        let mut scale = ratio * ratio;
        let mut stretch = one;
        if node.half_vector {
            let cos_s = axis_a.dot(nbar).max(V::splat(1.0 / MAX_STRETCH));
            let inv_s = cos_s.recip();
            scale = scale * V::splat(node.cos_c) * inv_s;
            stretch = inv_s;
        }
        let scale = V::select(aim, scale, one);
        let stretch = V::select(aim, stretch, one);
        for (k, l) in node.lobes[..node.n_lobes].iter().enumerate() {
            let axis = V3::select(aim, axis_a, V3::splat(l.axis));
            let neg = -axis;
            let lobe = SgV {
                axis: neg,
                sharp: scale * V::splat(l.inv_var),
                amp: V3::splat(l.amp),
            };
            let t = neg.cross(nbar);
            let tl = t.length_squared();
            let t = V3::select(
                tl.gt(V::splat(1e-24)),
                t.scale(tl.max(V::splat(1e-30)).rsqrt()),
                tangent_of(neg),
            );
            // An unaimed lobe whose merged axis is zero is skipped (`LitScene::cluster`).
            let keep = aim | V::splat(l.axis.length_squared()).gt(zero);
            let prod = AnisoV::new(lobe, t, stretch).product(&cap_a);
            incoming[1 + k] = Some(AnisoV {
                sg: SgV {
                    amp: V3::select(keep, prod.sg.amp, V3::new(zero, zero, zero)),
                    ..prod.sg
                },
                ..prod
            });
        }
    }
    let n_x = rx.n;
    for s in incoming.iter().flatten() {
        let s0 = &s.sg;
        let f = clamped_cosine_mean(n_x.dot(s0.axis), s0.sharp);
        let int = s0.integral();
        sum = sum
            + V3::new(
                rx.diffuse.x * int.x,
                rx.diffuse.y * int.y,
                rx.diffuse.z * int.z,
            )
            .scale(f);
        for h in &rx.lobes[..rx.n_lobes] {
            let p = s.product(h).sg;
            sum = sum
                + p.integral()
                    .scale(clamped_cosine_mean(n_x.dot(p.axis), p.sharp));
        }
    }
    V3::select(live, sum, V3::new(zero, zero, zero))
}
