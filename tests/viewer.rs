//! `interreflect view` as a user drives it, under a virtual X display (`xvfb-run`, installed
//! by `scripts/install-deps.sh`): a scripted session on the ring moves the light, switches the
//! method and saves screenshots, which must equal `render`'s images for the same settings.
//! Without `xvfb-run` the session tests skip, unless `CI=true` requires them.

mod common;

use interreflect::compare::metrics;
use interreflect::image::{Image, read_exr};
use std::path::Path;
use std::process::Command;

fn exe() -> &'static str {
    env!("CARGO_BIN_EXE_interreflect")
}

fn ring() -> String {
    concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/ring.toml").to_string()
}

/// Whether `xvfb-run` is here; panics when CI=true and it is not.
fn have_xvfb() -> bool {
    let ok = Command::new("sh")
        .args(["-c", "command -v xvfb-run"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        assert!(
            !interreflect::render::gpu::adapter_required(),
            "CI=true requires xvfb-run for the viewer tests (scripts/install-deps.sh installs it)"
        );
        eprintln!("skipped: xvfb-run is not installed");
    }
    ok
}

/// `interreflect view` under a virtual display, with a private `XDG_RUNTIME_DIR` in `dir`; the
/// caller adds the arguments after `view`.
fn view(dir: &Path) -> Command {
    let mut c = Command::new("xvfb-run");
    c.args(["-a", "-s", "-screen 0 1280x800x24"])
        .arg(exe())
        .arg("view")
        .env("XDG_RUNTIME_DIR", dir);
    c
}

fn render(dir: &Path, scene: &str, name: &str, args: &[&str]) -> Image {
    common::render_cli(dir, scene, name, args);
    read_exr(&dir.join(format!("{name}.exr"))).unwrap()
}

fn mean(img: &Image) -> f64 {
    img.data
        .iter()
        .map(|p| (p.x + p.y + p.z) as f64)
        .sum::<f64>()
        / img.data.len() as f64
}

/// The scripted session: each screenshot is the full-quality frame of the state it was taken
/// in, rendered by the same renderers with the same options as `render`, so the images must
/// be identical (tolerance 0: both paths are deterministic for any thread count, and the view
/// is the scene file's own camera, not the orbit's reconstruction of it).
#[test]
fn a_scripted_session_matches_render_and_follows_the_light() {
    if !have_xvfb() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let shot = |n: &str| d.join(format!("{n}.png")).display().to_string();
    let script = format!(
        "# the ring at 32 px: sg, the light moved, then direct light only\n\
         size 32 0\n\
         screenshot {}\n\
         light 0 position -3 2.5 0.5\n\
         screenshot {}\n\
         method direct\n\
         frames 3\n\
         screenshot {}\n",
        shot("sg"),
        shot("sg-moved"),
        shot("direct-moved"),
    );
    std::fs::write(d.join("session.txt"), script).unwrap();
    let o = view(d)
        .args([ring().as_str(), "--window", "800x500", "--script"])
        .arg(d.join("session.txt"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    for n in ["sg", "sg-moved", "direct-moved"] {
        assert!(d.join(format!("{n}.png")).is_file(), "{n}.png: {stderr}");
    }
    let sg = read_exr(&d.join("sg.exr")).unwrap();
    let moved = read_exr(&d.join("sg-moved.exr")).unwrap();
    let direct = read_exr(&d.join("direct-moved.exr")).unwrap();
    assert_eq!((sg.width, sg.height), (32, 32));

    // The same pictures from `render`: the ring as it is, and with the light where the script
    // put it.
    let small = ["--width", "32", "--spp", "1"];
    let text = std::fs::read_to_string(ring()).unwrap();
    assert!(
        text.contains("position = [-4.5, 2.1, 0.0]"),
        "the ring's light moved"
    );
    let moved_scene = d.join("ring-moved.toml");
    std::fs::write(
        &moved_scene,
        text.replace("position = [-4.5, 2.1, 0.0]", "position = [-3.0, 2.5, 0.5]"),
    )
    .unwrap();
    let moved_scene = moved_scene.display().to_string();
    let r_sg = render(
        d,
        &ring(),
        "r-sg",
        &[&["--method", "sg"][..], &small].concat(),
    );
    let r_moved = render(
        d,
        &moved_scene,
        "r-moved",
        &[&["--method", "sg"][..], &small].concat(),
    );
    let r_direct = render(
        d,
        &moved_scene,
        "r-direct",
        &[&["--method", "direct"][..], &small].concat(),
    );
    for (name, a, b) in [
        ("sg", &sg, &r_sg),
        ("sg, light moved", &moved, &r_moved),
        ("direct, light moved", &direct, &r_direct),
    ] {
        let m = metrics(a, b).unwrap();
        assert_eq!(
            m.rel_rmse, 0.0,
            "{name}: the viewer's frame differs from render's"
        );
    }
    // The screenshots differ as they should: moving the light changes the image a lot, and
    // the direct light alone is darker than sg's direct plus one bounce.
    let m = metrics(&moved, &sg).unwrap();
    assert!(
        m.rel_rmse > 0.1,
        "moving the light changed little: {}",
        m.rel_rmse
    );
    assert!(
        mean(&direct) < 0.99 * mean(&moved),
        "direct {} against sg {}",
        mean(&direct),
        mean(&moved)
    );
    // The log reports the frames and the saved files.
    assert!(stderr.contains("saved"), "{stderr}");
    assert!(stderr.contains("view: sg 32×32"), "{stderr}");
}

/// A small PRT scene: the ring, coarsely tessellated, under a directional light, with a
/// transfer cheap enough for a test (order 3, 64 rays per vertex, about 4k vertices).
const PRT_RING: &str = r#"
name = "ring-prt-test"
[camera]
position = [0.0, 3.6, 2.3]
look_at = [0.0, 0.0, 0.15]
up = [0.0, 1.0, 0.0]
fov_y = 38.0
width = 32
height = 32
[[lights]]
type = "directional"
direction = [4.5, -2.1, 0.0]
irradiance = [2.4, 2.4, 2.4]
[materials.gold]
model = "lambert"
diffuse = [1.0, 0.71, 0.29]
[materials.floor]
model = "lambert"
diffuse = [0.75, 0.75, 0.75]
[[objects]]
name = "ring"
material = "gold"
shape = { type = "ring", radius = 1.0, height = 0.3, thickness = 0.05, segments = 48 }
[[objects]]
name = "floor"
material = "floor"
shape = { type = "plane", size = [8.0, 8.0], subdivisions = 48 }
[methods.prt]
order = 3
transfer = "interreflected"
bounces = 1
samples = 64
"#;

/// prt in the viewer: its frames are `render --method prt`'s images for the same settings,
/// bit for bit (both relight with the CPU twin here and read one transfer), the transfer the
/// viewer computed is the one `render` then reads from the cache, a turned directional light
/// changes the image without a new transfer, and indirect-only shows the bounce alone.
#[test]
fn prt_in_the_viewer_matches_render_and_relights_without_a_new_transfer() {
    if !have_xvfb() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = d.join("ring-prt.toml");
    std::fs::write(&scene, PRT_RING).unwrap();
    let cache = d.join("cache");
    let shot = |n: &str| d.join(format!("{n}.png")).display().to_string();
    let script = format!(
        "method prt\n\
         screenshot {}\n\
         light 0 direction 2 -4 1.5\n\
         screenshot {}\n\
         indirect on\n\
         screenshot {}\n",
        shot("prt"),
        shot("prt-moved"),
        shot("prt-indirect"),
    );
    std::fs::write(d.join("session.txt"), script).unwrap();
    let o = view(d)
        .arg(&scene)
        .args(["--window", "800x500", "--prt-cache"])
        .arg(&cache)
        .arg("--script")
        .arg(d.join("session.txt"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    // One transfer for the whole session: computed once, then relit.
    assert_eq!(
        stderr.matches("prt: transfer computed").count(),
        1,
        "{stderr}"
    );
    let shots: Vec<Image> = ["prt", "prt-moved", "prt-indirect"]
        .iter()
        .map(|n| read_exr(&d.join(format!("{n}.exr"))).unwrap())
        .collect();

    let moved_scene = d.join("ring-prt-moved.toml");
    assert!(PRT_RING.contains("direction = [4.5, -2.1, 0.0]"));
    std::fs::write(
        &moved_scene,
        PRT_RING.replace(
            "direction = [4.5, -2.1, 0.0]",
            "direction = [2.0, -4.0, 1.5]",
        ),
    )
    .unwrap();
    let cache_arg = cache.display().to_string();
    let args = [
        "--method",
        "prt",
        "--width",
        "32",
        "--spp",
        "1",
        "--device",
        "cpu",
        "--prt-cache",
        &cache_arg,
    ];
    let scene_arg = scene.display().to_string();
    let moved_arg = moved_scene.display().to_string();
    let expected = [
        render(d, &scene_arg, "r-prt", &args),
        render(d, &moved_arg, "r-prt-moved", &args),
        render(
            d,
            &moved_arg,
            "r-prt-indirect",
            &[&args[..], &["--indirect-only"]].concat(),
        ),
    ];
    let log = std::fs::read_to_string(d.join("r-prt.json")).unwrap();
    let log =
        serde_json::to_string(&serde_json::from_str::<serde_json::Value>(&log).unwrap()).unwrap();
    assert!(
        log.contains(r#""cache":"hit""#),
        "render read the viewer's transfer: {log}"
    );
    for (name, a, b) in [
        ("prt", &shots[0], &expected[0]),
        ("prt, light turned", &shots[1], &expected[1]),
        ("prt, indirect only", &shots[2], &expected[2]),
    ] {
        let m = metrics(a, b).unwrap();
        assert_eq!(
            m.rel_rmse, 0.0,
            "{name}: the viewer's frame differs from render's"
        );
    }
    // Turning the light changes the image a lot; the bounce alone is a small part of it.
    let m = metrics(&shots[1], &shots[0]).unwrap();
    assert!(
        m.rel_rmse > 0.1,
        "turning the light changed little: {}",
        m.rel_rmse
    );
    let (all, bounce) = (mean(&shots[1]), mean(&shots[2]));
    assert!(
        bounce > 0.0 && bounce < 0.5 * all,
        "bounce {bounce} of {all}"
    );
}

/// prt on a scene with only point lights: a black frame and a notice that names a scene PRT
/// can relight, without computing a transfer for nothing.
#[test]
fn prt_without_distant_lighting_says_so() {
    if !have_xvfb() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("prt.png");
    let o = view(d)
        .args([ring().as_str(), "--method", "prt", "--width", "16"])
        .args(["--frames", "1", "--window", "640x400", "--prt-cache"])
        .arg(d.join("cache"))
        .arg("--screenshot")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("no distant lighting"), "{stderr}");
    assert!(stderr.contains("scenes/prt/"), "{stderr}");
    assert!(!stderr.contains("transfer computed"), "{stderr}");
    assert!(!d.join("cache").exists(), "no transfer was cached");
    let img = read_exr(&out.with_extension("exr")).unwrap();
    assert_eq!(mean(&img), 0.0);
}

/// `--frames N --screenshot OUT` renders, saves the last frame and exits.
#[test]
fn frames_and_screenshot_save_the_frame_and_exit() {
    if !have_xvfb() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("shots/direct.png");
    let o = view(d)
        .args([
            ring().as_str(),
            "--method",
            "direct",
            "--width",
            "24",
            "--frames",
            "2",
            "--window",
            "640x400",
            "--screenshot",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = read_exr(&out.with_extension("exr")).unwrap();
    let r = render(
        d,
        &ring(),
        "r",
        &["--method", "direct", "--width", "24", "--spp", "1"],
    );
    assert_eq!(metrics(&img, &r).unwrap().rel_rmse, 0.0);
}

/// Without a display the viewer says so and suggests `render`, and writes nothing; a bad
/// script is reported with its file and line before any window opens.
#[test]
fn no_display_and_bad_scripts_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = Command::new(exe())
        .args(["view", &ring(), "--frames", "1", "--screenshot"])
        .arg(d.join("x.png"))
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("needs a display"), "{stderr}");
    assert!(stderr.contains("interreflect render"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!d.join("x.png").exists() && !d.join("x.exr").exists());

    std::fs::write(d.join("bad.txt"), "size 32 0\nlight 0 position 1 2\n").unwrap();
    let o = Command::new(exe())
        .args(["view", &ring(), "--script"])
        .arg(d.join("bad.txt"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("bad.txt:2: light position"), "{stderr}");

    for (args, needle) in [
        (&["--method", "bogus"][..], "--method bogus"),
        (&["--window", "10x10"][..], "--window"),
        (&["--frames", "1", "--screenshot", "a.jpg"][..], ".png"),
        (&["--screenshot", "a.png"][..], "--frames"),
        (&["--spp", "0"][..], "--spp"),
    ] {
        let o = Command::new(exe())
            .args(["view", &ring()])
            .args(args)
            .current_dir(d)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
}

/// What the viewer keeps between frames changes nothing: sg rendered from kept pieces, tree and
/// light stage — after a frame from another viewpoint, under the same light — is bit-identical
/// to a fresh render; and a moved light is noticed (the light stage is rebuilt, and the image
/// equals a fresh render under that light).
#[test]
fn kept_tree_and_light_stage_give_the_fresh_image() {
    use interreflect::render::cpu::reference::{Progress, no_progress};
    use interreflect::render::cpu::sg::{
        SgOptions, SgPrepared, render_sg_prepared, render_sg_quiet,
    };
    use interreflect::render::{Device, Visibility};
    let (mut scene, accel) = common::scene_and_accel("ring");
    let opts = SgOptions {
        width: 20,
        height: 20,
        spp: 1,
        seed: 3,
        direct: true,
        indirect: true,
        brute: false,
        cut: interreflect::sg::CutOptions::default(),
        mode: scene.settings.sg.cut,
        max_edge: scene.mesh.diagonal() / 128.0,
        visibility: Visibility::Approx,
        device: Device::Cpu,
    };
    let cancel = std::sync::atomic::AtomicBool::new(false);
    let p = Progress {
        done: &no_progress,
        cancel: &cancel,
    };
    let mut prepared = SgPrepared::build(&scene, &opts);
    let home = scene.camera;
    // A frame from elsewhere first, so that the kept stage is used for the home view.
    scene.camera = interreflect::scene::Camera::look_at(
        glam::Vec3::new(2.0, 3.0, 2.0),
        glam::Vec3::ZERO,
        glam::Vec3::Y,
        40.0,
        20,
        20,
    )
    .unwrap();
    let (_, first) = render_sg_prepared(&scene, &accel, &opts, &mut prepared, &p).unwrap();
    assert!(!first.light_stage_kept);
    scene.camera = home;
    let (kept, s) = render_sg_prepared(&scene, &accel, &opts, &mut prepared, &p).unwrap();
    assert!(s.light_stage_kept, "the same light: the stage is kept");
    let (fresh, _) = render_sg_quiet(&scene, &accel, &opts);
    assert_eq!(kept, fresh, "kept light stage");
    // Move the light: rebuilt, and again the fresh image.
    if let interreflect::scene::Light::Point { position, .. } = &mut scene.lights[0] {
        *position += glam::Vec3::new(0.5, 0.3, 0.2);
    } else {
        panic!("the ring's light is a point light");
    }
    let (moved, s) = render_sg_prepared(&scene, &accel, &opts, &mut prepared, &p).unwrap();
    assert!(!s.light_stage_kept, "a moved light rebuilds the stage");
    let (fresh_moved, _) = render_sg_quiet(&scene, &accel, &opts);
    assert_eq!(moved, fresh_moved, "after the light moved");
    assert_ne!(moved, kept);
}

/// The heatmap's per-pixel cut sizes add up to the cut statistics of the frame: with pixel
/// cuts, Σ over pixels of (mean cut size of the pixel's samples) × spp = Σ of every cut's size.
#[test]
fn per_pixel_cut_sizes_add_up_to_the_cut_statistics() {
    use interreflect::render::cpu::sg::{CutMode, SgOptions, render_sg_quiet};
    use interreflect::render::{Device, Visibility};
    let (scene, accel) = common::scene_and_accel("ring");
    let mut opts = SgOptions {
        width: 16,
        height: 16,
        spp: 2,
        seed: 3,
        direct: false,
        indirect: true,
        brute: false,
        cut: interreflect::sg::CutOptions::default(),
        mode: CutMode::Pixel,
        max_edge: scene.mesh.diagonal() / 128.0,
        visibility: Visibility::Exact,
        device: Device::Cpu,
    };
    let (_, s) = render_sg_quiet(&scene, &accel, &opts);
    assert_eq!(s.pixel_cut_sizes.len(), 256);
    let per_pixel: f64 = s.pixel_cut_sizes.iter().map(|&c| c as f64).sum::<f64>() * 2.0;
    let total = s.cut_size_mean * s.cuts as f64;
    assert!(total > 1000.0, "cuts were selected: {total}");
    // Float sums of a few thousand integers stored as f32 halves: 1e-5 relative is ample.
    assert!(
        (per_pixel - total).abs() <= 1e-5 * total,
        "{per_pixel} against {total}"
    );
    // Vertex cuts are chosen before the pixels: no per-pixel sizes.
    opts.mode = CutMode::Vertex;
    let (_, s) = render_sg_quiet(&scene, &accel, &opts);
    assert!(s.pixel_cut_sizes.iter().all(|&c| c == 0.0));
}
