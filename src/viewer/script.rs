//! Viewer scripts (`interreflect view SCENE --script FILE`): one command per line, run in
//! order, for tests and for producing figures. `#` starts a comment.
//!
//! ```text
//! method sg                      # sg | vpl | direct | prt | reference
//! size 96 72                     # full-quality image size (height 0: the camera's aspect)
//! spp 4                          # samples per pixel of a full-quality frame
//! light 0 position 1 2.5 0.5     # light index, then position | direction | intensity | colour
//! light 0 intensity 40           # one number: scales to that luminous strength, keeps colour
//! material gold roughness 0.2    # roughness | exponent | diffuse r g b | specular r g b
//! orbit 30 -10                   # degrees of yaw and pitch about the target
//! pan 0.1 0                      # right and up, in units of the distance to the target
//! dolly 0.5                      # log-distance steps towards the target (negative: away)
//! reset                          # the scene file's camera
//! indirect on                    # on: indirect light only; off: everything
//! overlay vpls on                # vpls | boxes | heatmap
//! split direct                   # compare with a second method side by side; `split off`
//! wait                           # until the full-quality frame of the current state is shown
//! frames 10                      # let 10 window frames pass
//! screenshot out/ring-a.png      # waits, then writes out/ring-a.png and out/ring-a.exr
//! ```

use std::fmt;
use std::path::{Path, PathBuf};

/// What a light command sets.
#[derive(Clone, Debug, PartialEq)]
pub enum LightField {
    Position([f32; 3]),
    Direction([f32; 3]),
    /// RGB intensity (point, spot) or irradiance (directional).
    Intensity([f32; 3]),
    /// Keeps the colour, sets the largest channel.
    Strength(f32),
}

/// What a material command sets.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialField {
    Roughness(f32),
    Exponent(f32),
    Diffuse([f32; 3]),
    Specular([f32; 3]),
}

#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    Method(String),
    Size(u32, u32),
    Spp(u32),
    Light(usize, LightField),
    Material(String, MaterialField),
    Orbit(f32, f32),
    Pan(f32, f32),
    Dolly(f32),
    Reset,
    IndirectOnly(bool),
    Overlay(String, bool),
    Split(Option<String>),
    Wait,
    Frames(u32),
    Screenshot(PathBuf),
}

/// A parse error naming the file and line.
#[derive(Debug, Clone, PartialEq)]
pub struct ScriptError {
    pub file: PathBuf,
    pub line: usize,
    pub message: String,
}

impl fmt::Display for ScriptError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.file.display(), self.line, self.message)
    }
}

impl std::error::Error for ScriptError {}

/// Largest image side a script may ask for (the renderer's own limit is larger; a viewer
/// frame this big would take minutes on a CPU).
pub const MAX_SIDE: u32 = 4096;
/// Most samples per pixel a script may ask for.
pub const MAX_SPP: u32 = 4096;
/// Most frames one `frames` command may wait.
pub const MAX_FRAMES: u32 = 100_000;

/// The methods `method` and `split` accept: [`crate::viewer::ViewMethod::ALL`]'s names.
pub const METHODS: [&str; 5] = ["sg", "vpl", "direct", "prt", "reference"];
pub const OVERLAYS: [&str; 3] = ["vpls", "boxes", "heatmap"];

/// Parses a script; relative screenshot paths are kept as written (relative to the working
/// directory, like every other path on the command line).
pub fn parse(file: &Path, text: &str) -> Result<Vec<Command>, ScriptError> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let err = |message: String| ScriptError {
            file: file.to_path_buf(),
            line: i + 1,
            message,
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        out.push(command(&words).map_err(err)?);
    }
    Ok(out)
}

fn number(w: &str, what: &str) -> Result<f32, String> {
    let v: f32 = w
        .parse()
        .map_err(|_| format!("{what}: {w:?} is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{what}: {w} is not finite"));
    }
    Ok(v)
}

fn count(w: &str, what: &str, max: u32) -> Result<u32, String> {
    let v: u32 = w
        .parse()
        .map_err(|_| format!("{what}: {w:?} is not a whole number"))?;
    if v > max {
        return Err(format!("{what}: {v} is more than {max}"));
    }
    Ok(v)
}

fn rgb(words: &[&str], what: &str) -> Result<[f32; 3], String> {
    match words {
        [r, g, b] => Ok([number(r, what)?, number(g, what)?, number(b, what)?]),
        _ => Err(format!("{what}: expected three numbers")),
    }
}

fn on_off(w: Option<&&str>, what: &str) -> Result<bool, String> {
    match w.copied() {
        Some("on") => Ok(true),
        Some("off") => Ok(false),
        _ => Err(format!("{what}: expected on or off")),
    }
}

fn args(words: &[&str], n: usize, usage: &str) -> Result<(), String> {
    if words.len() != n + 1 {
        return Err(format!("expected `{usage}`"));
    }
    Ok(())
}

fn command(words: &[&str]) -> Result<Command, String> {
    let name = words[0];
    Ok(match name {
        "method" => {
            args(words, 1, "method sg|vpl|direct|reference")?;
            let m = words[1];
            if !METHODS.contains(&m) {
                return Err(format!(
                    "method: unknown method {m:?} (known: {})",
                    METHODS.join(", ")
                ));
            }
            Command::Method(m.to_string())
        }
        "size" => {
            args(words, 2, "size WIDTH HEIGHT")?;
            let w = count(words[1], "size", MAX_SIDE)?;
            let h = count(words[2], "size", MAX_SIDE)?;
            if w == 0 {
                return Err("size: the width must be at least 1".into());
            }
            Command::Size(w, h)
        }
        "spp" => {
            args(words, 1, "spp N")?;
            let n = count(words[1], "spp", MAX_SPP)?;
            if n == 0 {
                return Err("spp: must be at least 1".into());
            }
            Command::Spp(n)
        }
        "light" => {
            if words.len() < 4 {
                return Err(
                    "expected `light INDEX position|direction|intensity|colour ...`".into(),
                );
            }
            let k = count(words[1], "light index", 1 << 20)? as usize;
            let rest = &words[3..];
            let field = match words[2] {
                "position" => LightField::Position(rgb(rest, "light position")?),
                "direction" => {
                    let d = rgb(rest, "light direction")?;
                    if d.iter().all(|&x| x == 0.0) {
                        return Err("light direction: must not be zero".into());
                    }
                    LightField::Direction(d)
                }
                "intensity" | "colour" | "color" if rest.len() == 1 => {
                    let v = number(rest[0], "light intensity")?;
                    if v < 0.0 {
                        return Err("light intensity: must be ≥ 0".into());
                    }
                    LightField::Strength(v)
                }
                "intensity" | "colour" | "color" => {
                    let c = rgb(rest, "light intensity")?;
                    if c.iter().any(|&x| x < 0.0) {
                        return Err("light intensity: must be ≥ 0".into());
                    }
                    LightField::Intensity(c)
                }
                f => {
                    return Err(format!(
                        "light: unknown field {f:?} (known: position, direction, intensity, colour)"
                    ));
                }
            };
            Command::Light(k, field)
        }
        "material" => {
            if words.len() < 4 {
                return Err(
                    "expected `material NAME roughness|exponent|diffuse|specular ...`".into(),
                );
            }
            let rest = &words[3..];
            let one = |what: &str| -> Result<f32, String> {
                match rest {
                    [v] => number(v, what),
                    _ => Err(format!("{what}: expected one number")),
                }
            };
            let field = match words[2] {
                "roughness" => MaterialField::Roughness(one("material roughness")?),
                "exponent" => MaterialField::Exponent(one("material exponent")?),
                "diffuse" => MaterialField::Diffuse(rgb(rest, "material diffuse")?),
                "specular" => MaterialField::Specular(rgb(rest, "material specular")?),
                f => {
                    return Err(format!(
                        "material: unknown field {f:?} (known: roughness, exponent, diffuse, specular)"
                    ));
                }
            };
            Command::Material(words[1].to_string(), field)
        }
        "orbit" => {
            args(words, 2, "orbit YAW_DEGREES PITCH_DEGREES")?;
            Command::Orbit(number(words[1], "orbit")?, number(words[2], "orbit")?)
        }
        "pan" => {
            args(words, 2, "pan RIGHT UP")?;
            Command::Pan(number(words[1], "pan")?, number(words[2], "pan")?)
        }
        "dolly" => {
            args(words, 1, "dolly STEPS")?;
            Command::Dolly(number(words[1], "dolly")?)
        }
        "reset" => {
            args(words, 0, "reset")?;
            Command::Reset
        }
        "indirect" => {
            args(words, 1, "indirect on|off")?;
            Command::IndirectOnly(on_off(words.get(1), "indirect")?)
        }
        "overlay" => {
            args(words, 2, "overlay vpls|boxes|heatmap on|off")?;
            if !OVERLAYS.contains(&words[1]) {
                return Err(format!(
                    "overlay: unknown overlay {:?} (known: {})",
                    words[1],
                    OVERLAYS.join(", ")
                ));
            }
            Command::Overlay(words[1].to_string(), on_off(words.get(2), "overlay")?)
        }
        "split" => {
            args(words, 1, "split METHOD|off")?;
            match words[1] {
                "off" => Command::Split(None),
                m if METHODS.contains(&m) => Command::Split(Some(m.to_string())),
                m => {
                    return Err(format!(
                        "split: unknown method {m:?} (known: {}, off)",
                        METHODS.join(", ")
                    ));
                }
            }
        }
        "wait" => {
            args(words, 0, "wait")?;
            Command::Wait
        }
        "frames" => {
            args(words, 1, "frames N")?;
            Command::Frames(count(words[1], "frames", MAX_FRAMES)?)
        }
        "screenshot" => {
            args(words, 1, "screenshot OUT.png")?;
            let p = PathBuf::from(words[1]);
            if p.extension().and_then(|e| e.to_str()) != Some("png") {
                return Err(format!(
                    "screenshot: {} must end in .png (the EXR is written beside it)",
                    words[1]
                ));
            }
            Command::Screenshot(p)
        }
        c => {
            return Err(format!(
                "unknown command {c:?} (known: method, size, spp, light, material, orbit, pan, dolly, reset, indirect, overlay, split, wait, frames, screenshot)"
            ));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The script accepts exactly the viewer's methods.
    #[test]
    fn script_methods_are_the_viewers() {
        let names: Vec<&str> = crate::viewer::ViewMethod::ALL
            .iter()
            .map(|m| m.name())
            .collect();
        assert_eq!(names, METHODS);
    }

    #[test]
    fn every_command_parses() {
        let text = "# a session\nmethod vpl\nsize 96 0\nspp 4\nlight 0 position 1 2.5 -0.5\n\
                    light 1 intensity 40\nlight 0 colour 1 0.5 0.25 # warm\n\
                    material gold roughness 0.2\nmaterial wall diffuse 0.5 0.5 0.5\n\
                    orbit 30 -10\npan 0.1 0\ndolly -0.5\nreset\nindirect on\n\
                    overlay vpls on\nsplit direct\nsplit off\nwait\nframes 3\n\
                    screenshot out/a.png\n";
        let c = parse(Path::new("s.txt"), text).unwrap();
        assert_eq!(c.len(), 19);
        assert_eq!(c[0], Command::Method("vpl".into()));
        assert_eq!(c[1], Command::Size(96, 0));
        assert_eq!(
            c[3],
            Command::Light(0, LightField::Position([1.0, 2.5, -0.5]))
        );
        assert_eq!(c[4], Command::Light(1, LightField::Strength(40.0)));
        assert_eq!(
            c[5],
            Command::Light(0, LightField::Intensity([1.0, 0.5, 0.25]))
        );
        assert_eq!(
            c[6],
            Command::Material("gold".into(), MaterialField::Roughness(0.2))
        );
        assert_eq!(c[15], Command::Split(None));
        assert_eq!(c[18], Command::Screenshot("out/a.png".into()));
    }

    #[test]
    fn errors_name_the_file_and_line() {
        for (text, line, needle) in [
            ("method sg\nmethod magic\n", 2, "unknown method"),
            ("size 10\n", 1, "size WIDTH HEIGHT"),
            ("spp 0\n", 1, "at least 1"),
            ("light 0 position 1 2\n", 1, "three numbers"),
            ("light 0 position 1 nan 2\n", 1, "not finite"),
            ("light 0 direction 0 0 0\n", 1, "not be zero"),
            ("light 0 intensity -1\n", 1, "≥ 0"),
            ("\n\norbit 1 x\n", 3, "not a number"),
            ("screenshot a.jpg\n", 1, ".png"),
            ("frames 1000000\n", 1, "more than"),
            ("jump\n", 1, "unknown command"),
            ("overlay boxes maybe\n", 1, "on or off"),
        ] {
            let e = parse(Path::new("dir/s.txt"), text).unwrap_err();
            assert_eq!(e.line, line, "{text:?}: {e}");
            let shown = e.to_string();
            assert!(shown.starts_with(&format!("dir/s.txt:{line}: ")), "{shown}");
            assert!(shown.contains(needle), "{text:?}: {shown}");
        }
    }
}
