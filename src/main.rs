//! The `interreflect` command line: render, compare, info, convert-mesh.
#![forbid(unsafe_code)]

mod cli;

use clap::Parser;

fn main() {
    let args = cli::Cli::parse();
    let code = match cli::run(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", message(&e));
            2
        }
    };
    std::process::exit(code);
}

/// The error and its causes, `: `-separated, leaving out a cause whose text the message already
/// holds (the crate's error types print their source themselves: anyhow's `{:#}` would repeat it).
fn message(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::message;

    #[derive(Debug, thiserror::Error)]
    #[error("scene.toml: cannot read the scene file: {source}")]
    struct Quoting {
        source: std::io::Error,
    }

    #[test]
    fn causes_are_not_repeated() {
        let io = || std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let e = anyhow::Error::new(Quoting { source: io() });
        assert_eq!(
            message(&e),
            "scene.toml: cannot read the scene file: no such file"
        );
        // A context that does not quote its cause still shows it.
        let e = anyhow::Error::new(io()).context("cannot write out.json");
        assert_eq!(message(&e), "cannot write out.json: no such file");
    }
}
