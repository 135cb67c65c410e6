use super::*;
use crate::sg::tests::{grid, lit_config};
use crate::sg::transport::receiver::ReceiverOptions;
use crate::sg::{LitScene, LitTriangle};

fn lit(cfg: &crate::sg::tests::Config) -> LitScene<'_> {
    LitScene::new(
        &cfg.tree,
        cfg.tris.clone(),
        cfg.light,
        ReceiverOptions::default(),
    )
}

/// Every lit node uses a map, its own or its nearest mapped ancestor's; no more maps than the
/// budget; with a budget of every node, every lit node has its own.
#[test]
fn layout_keeps_the_budget_and_maps_every_lit_node() {
    let cfg = grid(16); // 512 triangles, 1023 nodes
    let lit = lit(&cfg);
    let nodes = &cfg.tree.nodes;
    let mut parent = vec![u32::MAX; nodes.len()];
    for (i, n) in nodes.iter().enumerate() {
        for c in n.children.into_iter().flatten() {
            parent[c as usize] = i as u32;
        }
    }
    for count in [1usize, 2, 7, 100, 1000, 5000] {
        let l = layout(&lit, count, 1e-4);
        assert!(
            l.origins.len() <= count,
            "{count}: {} maps",
            l.origins.len()
        );
        assert!(!l.origins.is_empty());
        assert_eq!(l.map_of[0], 0, "the root has the first map");
        let mut own = vec![false; l.origins.len()];
        for (i, (&m, &p)) in l.map_of.iter().zip(&parent).enumerate() {
            assert_ne!(m, u32::MAX, "{count}: node {i} is lit and has no map");
            if p != u32::MAX && l.map_of[p as usize] != m {
                // A map of its own: first use in pre-order.
                assert!(!own[m as usize], "{count}: map {m} used by two subtrees");
                own[m as usize] = true;
            }
        }
        if count >= nodes.len() {
            assert_eq!(l.origins.len(), nodes.len(), "every node its own map");
        }
        // Each origin sits just above a lit triangle of the grid (y = 0), facing the light.
        for o in &l.origins {
            assert!((o.position.y - 1e-4).abs() < 1e-6, "{o:?}");
            assert!((o.normal - Vec3::Y).length() < 1e-5, "{o:?}");
        }
    }
    let l = layout(&lit, 0, 1e-4);
    assert!(l.origins.is_empty() && l.map_of.iter().all(|&m| m == u32::MAX));
}

/// Nothing lit: no maps, and every node's visibility is 1 (nothing to say).
#[test]
fn unlit_tree_has_no_maps() {
    let mut cfg = grid(4);
    for t in &mut cfg.tris {
        *t = LitTriangle { sg: None, ..*t };
    }
    let lit = lit(&cfg);
    let l = layout(&lit, 100, 1e-4);
    assert!(l.origins.is_empty() && l.map_of.iter().all(|&m| m == u32::MAX));
}

/// The budget goes to the bright, large nodes first: two patches, one lit 100× brighter than
/// the other (nearer the light); with a small budget the bright patch gets most maps.
#[test]
fn layout_refines_where_the_light_is() {
    let quad = |x0: f32, k: usize| {
        let mut t = Vec::new();
        for i in 0..k {
            for j in 0..k {
                let p = |a: usize, b: usize| {
                    Vec3::new(x0 + a as f32 / k as f32, 0.0, b as f32 / k as f32)
                };
                t.push(([p(i, j), p(i, j + 1), p(i + 1, j)], 0));
                t.push(([p(i + 1, j), p(i, j + 1), p(i + 1, j + 1)], 0));
            }
        }
        t
    };
    let mut tris = quad(0.0, 8);
    tris.extend(quad(20.0, 8));
    // Light 0.5 above the first patch: the second is 40× as far, 1/1600 the irradiance.
    let cfg = lit_config(&tris, Vec3::new(0.5, 0.5, 0.5));
    let lit = lit(&cfg);
    let l = layout(&lit, 64, 1e-4);
    let near = l.origins.iter().filter(|o| o.position.x < 10.0).count();
    assert!(
        near > 3 * (l.origins.len() - near),
        "{near} of {}",
        l.origins.len()
    );
}
