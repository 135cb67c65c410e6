//! Without a GPU: every pass assembles (shared files + its own), parses and validates with naga,
//! has its entry point, and every shared struct has exactly the Rust layout of
//! `render::gpu::layout` (member names, offsets, size); every math twin exists in WGSL.

use interreflect::render::gpu::layout::layouts;
use interreflect::render::gpu::shaders::{PASSES, SHARED, source};
use interreflect::render::gpu::twins::Twin;
use naga::valid::{Capabilities, ValidationFlags, Validator};

fn module(pass: &str) -> naga::Module {
    let src = source(pass).expect("a known pass");
    let module = naga::front::wgsl::parse_str(&src)
        .unwrap_or_else(|e| panic!("{pass}: {}", e.emit_to_string(&src)));
    Validator::new(ValidationFlags::all(), Capabilities::all())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{pass}: {}", e.emit_to_string(&src)));
    module
}

#[test]
fn shaders_validate_and_layouts_match() {
    assert!(source("no_such_pass").is_none());
    for (pass, _) in PASSES {
        let m = module(pass);
        assert!(
            m.entry_points.iter().any(|e| e.name == pass),
            "{pass}: no entry point named after the pass"
        );
        for l in layouts() {
            let (_, ty) = m
                .types
                .iter()
                .find(|(_, t)| t.name.as_deref() == Some(l.name))
                .unwrap_or_else(|| panic!("{pass}: struct {} missing", l.name));
            let naga::TypeInner::Struct { members, span } = &ty.inner else {
                panic!("{pass}: {} is not a struct", l.name);
            };
            assert_eq!(*span as usize, l.size, "{pass}: size of {}", l.name);
            let wgsl: Vec<(Option<&str>, usize)> = members
                .iter()
                .map(|m| (m.name.as_deref(), m.offset as usize))
                .collect();
            let rust: Vec<(Option<&str>, usize)> =
                l.members.iter().map(|(n, o)| (Some(*n), *o)).collect();
            assert_eq!(wgsl, rust, "{pass}: members of {}", l.name);
        }
    }
    let twins = module("math_twins");
    for t in Twin::ALL {
        assert!(
            twins
                .functions
                .iter()
                .any(|(_, f)| f.name.as_deref() == Some(t.wgsl_name())),
            "no WGSL function {}",
            t.wgsl_name()
        );
    }
}

/// A layout that differs from the shader's is caught: the comparison is not vacuous.
#[test]
fn a_mismatched_layout_is_detected() {
    let (_, layout_wgsl) = SHARED[0];
    let swapped = layout_wgsl.replace(
        "    sharpness: f32,\n    amplitude: vec3<f32>,",
        "    amplitude: vec3<f32>,\n    sharpness: f32,",
    );
    assert_ne!(swapped, layout_wgsl, "the members to swap were not found");
    let m = naga::front::wgsl::parse_str(&swapped).expect("still valid WGSL");
    let gpu_sg = layouts().into_iter().find(|l| l.name == "GpuSg").unwrap();
    let (_, ty) = m
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("GpuSg"))
        .unwrap();
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        panic!()
    };
    let offsets: Vec<usize> = members.iter().map(|m| m.offset as usize).collect();
    let rust: Vec<usize> = gpu_sg.members.iter().map(|(_, o)| *o).collect();
    assert_ne!(offsets, rust);
}

/// Every pass has its page in `docs/passes/` (what it computes, its inputs and outputs, its
/// twin and its cost), listed in that folder's README.
#[test]
fn every_pass_has_a_page() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/passes");
    let index = std::fs::read_to_string(dir.join("README.md")).unwrap();
    for (pass, _) in PASSES {
        let page = dir.join(format!("{pass}.md"));
        let text =
            std::fs::read_to_string(&page).unwrap_or_else(|e| panic!("{}: {e}", page.display()));
        assert!(
            text.starts_with(&format!("# `{pass}`")),
            "{pass}.md's title"
        );
        for part in ["**Computes.**", "**Inputs.**", "**Cost.**"] {
            assert!(text.contains(part), "{pass}.md has no {part}");
        }
        assert!(
            index.contains(&format!("({pass}.md)")),
            "README.md does not list {pass}.md"
        );
    }
}
