//! The memory budget through the binary: where the budget comes from (flag, environment
//! variable, default), the check before loading and the check after loading, and the estimate in
//! the render's log. The messages of the flag's bad values are snapshots in `bad_input.rs`.

use interreflect::memory::{self, MIB, Workload};
use interreflect::render::{Method, Visibility};
use std::path::Path;
use std::process::{Command, Output};

const SCENE_HEAD: &str = r#"
[camera]
position = [0.0, 2.0, 4.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 40.0
width = 16
height = 12

[[lights]]
type = "point"
position = [0.0, 3.0, 0.0]
intensity = [5.0, 5.0, 5.0]

[materials.white]
model = "lambert"
diffuse = [0.5, 0.5, 0.5]

[[objects]]
material = "white"
shape = { type = "plane", size = [4.0, 4.0] }
"#;

fn render(dir: &Path, extra: &[&str], env: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_interreflect"));
    c.arg("render")
        .arg(dir.join("scene.toml"))
        .args(["--spp", "1", "--quiet", "--output"])
        .arg(dir.join("out.exr"))
        .args(extra)
        .env_remove(memory::BUDGET_ENV);
    if let Some(v) = env {
        c.env(memory::BUDGET_ENV, v);
    }
    c.output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn outputs(dir: &Path) -> usize {
    ["out.exr", "out.png", "out.json"]
        .iter()
        .filter(|f| dir.join(f).exists())
        .count()
}

#[test]
fn the_budget_comes_from_the_flag_else_the_environment_else_the_default() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("scene.toml"), SCENE_HEAD).unwrap();

    // The environment variable alone: too small, refused, named.
    let o = render(dir.path(), &[], Some("1MiB"));
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("memory budget of 1 MiB (INTERREFLECT_MEMORY_BUDGET)"),
        "{e}"
    );
    assert_eq!(outputs(dir.path()), 0);

    // A malformed variable is an error naming it.
    let o = render(dir.path(), &[], Some("plenty"));
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.starts_with("error: INTERREFLECT_MEMORY_BUDGET: 'plenty' is not a size"),
        "{e}"
    );

    // The flag wins over the variable.
    let o = render(dir.path(), &["--memory-budget", "off"], Some("1MiB"));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let log: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out.json")).unwrap()).unwrap();
    assert_eq!(log["memory"]["budget_bytes"], serde_json::Value::Null);
    let est = log["memory"]["estimate_bytes"].as_u64().unwrap();
    // A 2-triangle scene at 16x12: the runtime's 16 MiB and little else.
    assert!((16 * MIB..17 * MIB).contains(&est), "{est}");

    // Neither: the default, a fraction of the physical memory, is in the log.
    let o = render(dir.path(), &[], None);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let log: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out.json")).unwrap()).unwrap();
    assert_eq!(
        log["memory"]["budget_bytes"].as_u64(),
        Some(memory::default_budget())
    );
}

/// A PLY of quads: its header counts faces, which the check before loading takes for
/// triangles; loaded, each quad is two. A budget between the two estimates passes the first
/// check and is refused by the second, after loading and before the BVH, naming the scene.
#[test]
fn polygons_beyond_the_header_count_are_caught_after_loading() {
    let dir = tempfile::tempdir().unwrap();
    let n = 40usize; // n × n quads
    let mut ply = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        (n + 1) * (n + 1),
        n * n
    );
    for j in 0..=n {
        for i in 0..=n {
            ply += &format!("{} 0 {}\n", i as f32 / n as f32, j as f32 / n as f32);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            ply += &format!("4 {} {} {} {}\n", a, a + n + 1, a + n + 2, a + 1);
        }
    }
    std::fs::write(dir.path().join("quads.ply"), ply).unwrap();
    std::fs::write(
        dir.path().join("scene.toml"),
        format!(
            "{SCENE_HEAD}\n[[objects]]\nmaterial = \"white\"\nshape = {{ type = \"mesh\", file = \"quads.ply\" }}\n"
        ),
    )
    .unwrap();
    let (quads, verts) = ((n * n) as u64, ((n + 1) * (n + 1)) as u64);
    let workload = |triangles: u64, vertices: u64| Workload {
        method: Method::Reference,
        visibility: Visibility::Exact,
        triangles,
        vertices,
        pixels: 16 * 12,
        samples: 16 * 12,
        environment_texels: 0,
        vertex_cut_nodes: None,
        prt_order: 8,
        prt_gpu: true,
        lights: 1,
        node_map_bytes: 0,
    };
    // The plane adds 2 triangles and 4 vertices to both.
    let before = memory::estimate(&workload(quads + 2, verts + 4)).total();
    let after = memory::estimate(&workload(2 * quads + 2, verts + 4)).total();
    assert!(after > before + 100_000, "{before} {after}");
    let budget = format!("{}", (before + after) / 2);
    let o = render(dir.path(), &["--memory-budget", &budget], None);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    let scene = dir.path().join("scene.toml");
    assert!(
        e.starts_with(&format!(
            "error: {}: 3,202 triangles and 1,685 vertices rendered with --method reference",
            scene.display()
        )),
        "{e}"
    );
    assert_eq!(outputs(dir.path()), 0);
    // With the budget at the loaded estimate, it renders.
    let o = render(dir.path(), &["--memory-budget", &after.to_string()], None);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}
