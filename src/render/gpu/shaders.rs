//! The WGSL sources, assembled: every pass is `shaders/shared/*.wgsl` (the layouts mirrored from
//! [`super::layout`] and the math twins), then the parts it uses (`shaders/parts/*.wgsl`: code
//! that reads bindings the pass declares), then the pass's own file, `shaders/<pass>.wgsl`.
//! WGSL has no includes; this concatenation is the only way a pass gets the shared code.

/// The shared files, in the order they are prepended.
pub const SHARED: [(&str, &str); 5] = [
    (
        "shared/layout.wgsl",
        include_str!("../../../shaders/shared/layout.wgsl"),
    ),
    (
        "shared/math.wgsl",
        include_str!("../../../shaders/shared/math.wgsl"),
    ),
    (
        "shared/transport.wgsl",
        include_str!("../../../shaders/shared/transport.wgsl"),
    ),
    (
        "shared/brdf.wgsl",
        include_str!("../../../shaders/shared/brdf.wgsl"),
    ),
    (
        "shared/light.wgsl",
        include_str!("../../../shaders/shared/light.wgsl"),
    ),
];

/// The parts: code shared by some passes that reads module-scope bindings those passes
/// declare (`shadow_map`: the maps' texels as `moments`).
pub const PARTS: [(&str, &str); 1] = [(
    "parts/shadow_map.wgsl",
    include_str!("../../../shaders/parts/shadow_map.wgsl"),
)];

/// The parts each pass is assembled with (the others use none).
pub fn parts(pass: &str) -> &'static [&'static str] {
    match pass {
        "direct" | "vpl_gen" => &["parts/shadow_map.wgsl"],
        _ => &[],
    }
}

/// Every pass: (name = file stem = entry point, its own source).
pub const PASSES: [(&str, &str); 12] = [
    (
        "prt_relight",
        include_str!("../../../shaders/prt_relight.wgsl"),
    ),
    (
        "math_twins",
        include_str!("../../../shaders/math_twins.wgsl"),
    ),
    ("vsm", include_str!("../../../shaders/vsm.wgsl")),
    ("vsm_blur", include_str!("../../../shaders/vsm_blur.wgsl")),
    ("tonemap", include_str!("../../../shaders/tonemap.wgsl")),
    ("gbuffer", include_str!("../../../shaders/gbuffer.wgsl")),
    ("sg_shade", include_str!("../../../shaders/sg_shade.wgsl")),
    (
        "sg_shade_sum",
        include_str!("../../../shaders/sg_shade_sum.wgsl"),
    ),
    ("vpl", include_str!("../../../shaders/vpl.wgsl")),
    ("direct", include_str!("../../../shaders/direct.wgsl")),
    ("vpl_gen", include_str!("../../../shaders/vpl_gen.wgsl")),
    ("ism", include_str!("../../../shaders/ism.wgsl")),
];

/// The assembled source of `pass` (shared files, then the pass), or `None` for an unknown pass.
pub fn source(pass: &str) -> Option<String> {
    let (_, own) = PASSES.iter().find(|(n, _)| *n == pass)?;
    let mut s = String::new();
    for (name, text) in SHARED {
        s.push_str(&format!("// ---- shaders/{name}\n"));
        s.push_str(text);
        s.push('\n');
    }
    for part in parts(pass) {
        let (_, text) = PARTS.iter().find(|(n, _)| n == part)?;
        s.push_str(&format!("// ---- shaders/{part}\n"));
        s.push_str(text);
        s.push('\n');
    }
    s.push_str(&format!("// ---- shaders/{pass}.wgsl\n"));
    s.push_str(own);
    Some(s)
}
