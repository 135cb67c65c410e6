//! The WGSL sources, assembled: every pass is `shaders/shared/*.wgsl` (the layouts mirrored from
//! [`super::layout`] and the math twins) followed by the pass's own file, `shaders/<pass>.wgsl`.
//! WGSL has no includes; this concatenation is the only way a pass gets the shared code.

/// The shared files, in the order they are prepended.
pub const SHARED: [(&str, &str); 4] = [
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
];

/// Every pass: (name = file stem = entry point, its own source).
pub const PASSES: [(&str, &str); 10] = [
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
    s.push_str(&format!("// ---- shaders/{pass}.wgsl\n"));
    s.push_str(own);
    Some(s)
}
