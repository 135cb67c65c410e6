use super::*;
use crate::math::Rng;
use crate::render::cpu::surface::light_visible;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Cantelli's inequality as the map evaluates it: for random depth distributions under a
    /// random filter footprint (non-negative weights, summed in f32 like the blur), the bound is
    /// never below the weighted fraction of depths ≥ t. Tolerance 1e-5 for the f32 sums; the
    /// σ² floor (`min_variance`) is what keeps the rounding of E[z²] − μ² from breaking it.
    #[test]
    fn chebyshev_bound_is_never_below_the_lit_fraction(
        seed in 0u64..1_000_000,
        n in 1usize..64,
        clusters in 1usize..4,
        t in 0.5f32..12.0,
    ) {
        let mut rng = Rng::keyed(seed, 3, 4);
        let centres: Vec<f32> = (0..clusters).map(|_| 1.0 + 9.0 * rng.f32()).collect();
        let spread = 10f32.powf(-4.0 * rng.f32());
        let depths: Vec<f32> = (0..n)
            .map(|_| (centres[rng.next_u32() as usize % clusters] + spread * (rng.f32() - 0.5)).max(0.0))
            .collect();
        let weights: Vec<f32> = (0..n).map(|_| rng.f32() + 1e-3).collect();
        let total: f32 = weights.iter().sum();
        let m = depths.iter().zip(&weights).fold(Vec2::ZERO, |a, (&z, &w)| {
            a + Vec2::new(z, z * z) * (w / total)
        });
        let lit: f32 = depths
            .iter()
            .zip(&weights)
            .filter(|(z, _)| **z >= t)
            .map(|(_, w)| w / total)
            .sum();
        let bound = chebyshev_upper_bound(m, t, min_variance(12.0));
        prop_assert!(bound >= lit - 1e-5, "bound {bound} < lit {lit} (moments {m:?}, t {t})");
    }
}

#[test]
fn light_bleeding_reduction_maps_b_to_zero_and_keeps_one() {
    assert_eq!(reduce_bleeding(1.0, 0.3), 1.0);
    assert_eq!(reduce_bleeding(0.3, 0.3), 0.0);
    assert_eq!(reduce_bleeding(0.1, 0.3), 0.0);
    assert!((reduce_bleeding(0.65, 0.3) - 0.5).abs() < 1e-6);
    assert_eq!(reduce_bleeding(0.42, 0.0), 0.42);
}

/// A 10 × 10 floor at y = 0 (two triangles) and, optionally, a 1 × 1 occluder at y = 1.
fn floor_scene(occluder: bool) -> (Accel, (Vec3, Vec3)) {
    let mut positions = vec![
        Vec3::new(-5.0, 0.0, -5.0),
        Vec3::new(5.0, 0.0, -5.0),
        Vec3::new(5.0, 0.0, 5.0),
        Vec3::new(-5.0, 0.0, 5.0),
    ];
    let mut indices = vec![[0, 2, 1], [0, 3, 2]];
    if occluder {
        positions.extend([
            Vec3::new(-0.5, 1.0, -0.5),
            Vec3::new(0.5, 1.0, -0.5),
            Vec3::new(0.5, 1.0, 0.5),
            Vec3::new(-0.5, 1.0, 0.5),
        ]);
        indices.extend([[4, 6, 5], [4, 7, 6]]);
    }
    let accel = Accel::build(&positions, &indices);
    let lo = positions.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
    let hi = positions.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
    (accel, (lo, hi))
}

fn lights() -> [Light; 4] {
    [
        Light::Point {
            position: Vec3::new(0.3, 4.0, 0.2),
            intensity: Vec3::ONE,
        },
        Light::Spot {
            position: Vec3::new(0.3, 4.0, 0.2),
            direction: Vec3::NEG_Y,
            intensity: Vec3::ONE,
            cos_cone: 45f32.to_radians().cos(),
            cos_falloff: 40f32.to_radians().cos(),
        },
        Light::Spot {
            position: Vec3::new(0.3, 4.0, 0.2),
            direction: Vec3::new(0.1, -1.0, 0.0),
            intensity: Vec3::ONE,
            cos_cone: 80f32.to_radians().cos(),
            cos_falloff: 75f32.to_radians().cos(),
        },
        Light::Directional {
            direction: Vec3::new(-0.2, -1.0, -0.1).normalize(),
            irradiance: Vec3::ONE,
        },
    ]
}

/// Random floor points within `r` of the origin, offset 1e-3 towards the light (as the renderer
/// offsets its shading points).
fn floor_points(light: &Light, r: f32, count: usize) -> Vec<Vec3> {
    let mut rng = Rng::keyed(7, 8, 9);
    (0..count)
        .filter_map(|_| {
            let p = Vec3::new(rng.f32() * 2.0 - 1.0, 0.0, rng.f32() * 2.0 - 1.0) * r;
            light.incident(p).map(|inc| p + inc.wi * 1e-3)
        })
        .collect()
}

/// With no occluder every point of the floor is lit exactly (1, not nearly 1), for every
/// projection (cube, perspective, a spot wide enough for a cube, orthographic), blurred or not.
#[test]
fn unoccluded_floor_is_fully_lit() {
    let (accel, bounds) = floor_scene(false);
    for light in lights() {
        for blur in [0, 2] {
            let opts = VsmOptions {
                resolution: 128,
                blur,
                light_bleeding: 0.2,
            };
            let map = VarianceShadowMap::build(&accel, bounds, &light, &opts);
            let r = if matches!(light, Light::Spot { cos_cone, .. } if cos_cone > 0.5) {
                3.0
            } else {
                4.5
            };
            for p in floor_points(&light, r, 2000) {
                assert_eq!(map.lit(p), 1.0, "{light:?}, blur {blur}: {p}");
            }
        }
    }
}

/// Under a square occluder the map agrees with shadow rays at ≥ 99 % of random floor points
/// (lit when the map says > 0.5; measured 99.5–99.9 %); the rest lie in the blurred band along
/// the shadow's edge (2 texels of blur at 256 texels: a few cm of the 10 m floor). Points deep in the umbra
/// are dark (< 0.05) and points far outside it are lit exactly.
#[test]
fn occluded_floor_matches_shadow_rays() {
    let (accel, bounds) = floor_scene(true);
    for light in lights() {
        let opts = VsmOptions {
            resolution: 256,
            ..VsmOptions::default()
        };
        let map = VarianceShadowMap::build(&accel, bounds, &light, &opts);
        let points = floor_points(&light, 2.5, 4000);
        let agree = points
            .iter()
            .filter(|&&p| (map.lit(p) > 0.5) == light_visible(&accel, &light, p, 1e-4))
            .count();
        let rate = agree as f64 / points.len() as f64;
        println!("{light:?}: agreement {rate:.4}");
        assert!(rate >= 0.99, "{light:?}: agreement {rate}");
        // The umbra's centre: straight below the occluder as seen from the light.
        let pos = light.position();
        let centre = match pos {
            Some(l) => l + (Vec3::new(0.0, 1.0, 0.0) - l) * (l.y / (l.y - 1.0)),
            None => {
                let Light::Directional { direction, .. } = light else {
                    unreachable!()
                };
                Vec3::new(0.0, 1.0, 0.0) + direction * (1.0 / -direction.y)
            }
        };
        assert!(
            map.lit(centre + Vec3::Y * 1e-3) < 0.05,
            "{light:?}: umbra {}",
            map.lit(centre)
        );
        assert_eq!(map.lit(Vec3::new(2.4, 1e-3, -2.3)), 1.0, "{light:?}");
    }
}
