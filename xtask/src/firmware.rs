//! Builds with cargo and learns the artifact's path from cargo itself
//! (`--message-format=json-render-diagnostics`), so the target directory, the
//! profile's directory name and the binary's name never have to be guessed.
//! Cargo's usual progress and diagnostics still go to stderr.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::Stdio;

use crate::error::{say, Failure};
use crate::process;
use crate::workspace;

/// A binary to build in the release profile.
pub struct Artifact<'a> {
    pub package: &'a str,
    pub bin: &'a str,
    /// Cross target; the host when `None`.
    pub target: Option<&'a str>,
    pub features: Option<&'a str>,
    /// `--quiet`: no progress lines (for the host simulator, built in passing).
    pub quiet: bool,
}

impl Artifact<'_> {
    /// `bin` of `package` for `target`, release profile.
    pub fn firmware<'a>(package: &'a str, bin: &'a str, target: &'a str) -> Artifact<'a> {
        Artifact {
            package,
            bin,
            target: Some(target),
            features: None,
            quiet: false,
        }
    }
}

/// Builds `what` and returns its executable.
pub fn build(what: &Artifact) -> Result<PathBuf, Failure> {
    let mut cmd = workspace::cargo();
    cmd.args(["build", "--release", "-p", what.package, "--bin", what.bin]);
    if let Some(target) = what.target {
        cmd.args(["--target", target]);
    }
    if let Some(features) = what.features {
        cmd.args(["--features", features]);
    }
    if what.quiet {
        cmd.arg("--quiet");
    }
    cmd.arg("--message-format=json-render-diagnostics");
    let shown = process::shown(&cmd);
    let target = what.target.unwrap_or("the host");
    if !what.quiet {
        match what.features {
            Some(features) => say!(
                "building {} ({}, features {features}) for {target}",
                what.bin,
                what.package
            ),
            None => say!("building {} ({}) for {target}", what.bin, what.package),
        }
    }
    cmd.stdin(Stdio::null()).stdout(Stdio::piped());
    let mut child = process::spawn(&mut cmd)?;
    let mut executable = None;
    if let Some(stdout) = child.stdout.take() {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if let Some(path) = executable_of(&line, what.bin) {
                executable = Some(path);
            }
        }
    }
    let status = child
        .wait()
        .map_err(|e| Failure::new(format!("waiting for `{shown}`: {e}")))?;
    if !status.success() {
        return Err(Failure::new(format!(
            "building {} ({}) for {target} failed: `{shown}` exited with {}",
            what.bin,
            what.package,
            process::code(status)
        ))
        .status(process::code(status).max(1)));
    }
    executable.ok_or_else(|| {
        Failure::new(format!(
            "`{shown}` succeeded but reported no executable named {}",
            what.bin
        ))
    })
}

/// The executable named in one of cargo's JSON messages, if it is `bin`'s.
fn executable_of(line: &str, bin: &str) -> Option<PathBuf> {
    let message: serde_json::Value = serde_json::from_str(line).ok()?;
    if message["reason"] != "compiler-artifact" || message["target"]["name"] != bin {
        return None;
    }
    message["executable"].as_str().map(PathBuf::from)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_executable_of_the_right_binary() {
        let line = r#"{"reason":"compiler-artifact","target":{"name":"qemu","kind":["bin"]},"executable":"/r/target/thumbv7em-none-eabihf/release/qemu","fresh":true}"#;
        assert_eq!(
            executable_of(line, "qemu"),
            Some(PathBuf::from(
                "/r/target/thumbv7em-none-eabihf/release/qemu"
            ))
        );
        assert_eq!(executable_of(line, "bench"), None);
        let lib = r#"{"reason":"compiler-artifact","target":{"name":"qemu"},"executable":null}"#;
        assert_eq!(executable_of(lib, "qemu"), None);
        assert_eq!(
            executable_of(r#"{"reason":"build-finished","success":true}"#, "qemu"),
            None
        );
        assert_eq!(executable_of("not json", "qemu"), None);
    }
}
