//! Where things are: the repository root, the target directory, tools on PATH
//! or in cargo's bin directory, and the cargo to run. Every task runs cargo from
//! the root, so the root `.cargo/config.toml` (linker, flags, `[env]`) applies
//! whatever directory the user typed `cargo xtask` in.

use std::env;
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::Failure;
use crate::process;

/// The repository root: xtask's parent directory, fixed at compile time (a
/// checkout moved after building is rebuilt by the next `cargo xtask` anyway).
pub fn root() -> &'static Path {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(manifest)
}

/// `cargo`, the one running us when there is one (its toolchain, not PATH's),
/// started in the root, with cargo's bin directory on PATH: flip-link, the
/// firmware's linker, may be installed there and not be on PATH yet.
pub fn cargo() -> Command {
    let mut cmd = Command::new(env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    cmd.current_dir(root());
    if let Some(path) = path_with_cargo_bin() {
        cmd.env("PATH", path);
    }
    cmd
}

/// The target directory (honours CARGO_TARGET_DIR and `build.target-dir`).
pub fn target_dir() -> Result<PathBuf, Failure> {
    let mut cmd = cargo();
    cmd.args(["metadata", "--format-version", "1", "--no-deps"]);
    let text = process::read(&mut cmd)?;
    let json: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Failure::new(format!("cannot parse `cargo metadata` output: {e}")))?;
    json["target_directory"]
        .as_str()
        .map(PathBuf::from)
        .ok_or_else(|| Failure::new("`cargo metadata` gave no target_directory"))
}

/// A path from the environment (`var`), relative to the root, or `default`.
pub fn env_path(var: &str, default: PathBuf) -> PathBuf {
    match env::var_os(var) {
        Some(value) if !value.is_empty() => root().join(value),
        _ => default,
    }
}

/// A whole number from the environment (`var`), or `default`.
pub fn env_number(var: &str, default: u64) -> Result<u64, Failure> {
    match env::var(var) {
        Ok(value) if !value.trim().is_empty() => value
            .trim()
            .parse()
            .map_err(|_| Failure::new(format!("{var}={value} is not a whole number")).status(2)),
        _ => Ok(default),
    }
}

/// cargo's bin directory (`cargo install` puts tools there).
pub fn cargo_bin() -> Option<PathBuf> {
    let home = match env::var_os("CARGO_HOME") {
        Some(home) if !home.is_empty() => PathBuf::from(home),
        _ => PathBuf::from(env::var_os("HOME")?).join(".cargo"),
    };
    Some(home.join("bin"))
}

/// An executable called `name` on PATH.
pub fn on_path(name: &str) -> Option<PathBuf> {
    env::split_paths(&env::var_os("PATH")?)
        .map(|dir| dir.join(name))
        .find(|path| is_executable(path))
}

/// An executable called `name` on PATH, or else in cargo's bin directory.
pub fn find_tool(name: &str) -> Option<PathBuf> {
    on_path(name).or_else(|| Some(cargo_bin()?.join(name)).filter(|path| is_executable(path)))
}

fn is_executable(path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        path.metadata()
            .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
    }
    #[cfg(not(unix))]
    {
        path.is_file()
    }
}

/// PATH with cargo's bin directory appended, when it is not on PATH already.
fn path_with_cargo_bin() -> Option<OsString> {
    let bin = cargo_bin()?;
    let path = env::var_os("PATH").unwrap_or_default();
    let mut dirs: Vec<PathBuf> = env::split_paths(&path).collect();
    if dirs.contains(&bin) {
        return None;
    }
    dirs.push(bin);
    env::join_paths(dirs).ok()
}
