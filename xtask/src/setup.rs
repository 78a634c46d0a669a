//! Prerequisites, installed on first use so that a fresh machine needs nothing
//! but rustup: the firmware targets' standard libraries, qemu-system-arm (with
//! apt-get when we are root), and flip-link and defmt-print (`cargo install`).
//! Each install is one status line; the tool's own output shows only when it
//! fails, with the command to run by hand. probe-rs is never installed: it is
//! large, and only the micro:bit needs it.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::{say, Failure, Outcome};
use crate::process;
use crate::workspace::{self, find_tool, on_path};

/// The tools a QEMU run needs, where they were found.
pub struct Qemu {
    pub qemu: PathBuf,
    /// For a defmt log.
    pub defmt_print: Option<PathBuf>,
}

/// `cargo xtask setup [--all]`: everything the boards' firmware and the
/// study's target benchmarks need (`targets`: each board's, from
/// `boards::ALL`, which the boards' descriptions hold; this module is what
/// they call on, so it takes them as they come); `--all` also reports on
/// probe-rs (micro:bit).
pub fn run<'a>(all: bool, targets: impl IntoIterator<Item = &'a str>) -> Outcome {
    let mut targets: Vec<&str> = targets.into_iter().collect();
    targets.dedup();
    for triple in targets {
        target(triple)?;
    }
    qemu()?;
    flip_link()?;
    defmt_print()?;
    if all {
        match probe_rs() {
            Ok(path) => say!("probe-rs: {}", path.display()),
            // Informational only: the QEMU tasks work without it.
            Err(missing) => say!("{}", missing.message),
        }
    }
    say!("all set");
    Ok(0)
}

/// What a headless QEMU run needs (the firmware's own needs are
/// `boards::Firmware::build`'s): qemu-system-arm, and defmt-print
/// for a `defmt` log.
pub fn qemu_tools(defmt: bool) -> Result<Qemu, Failure> {
    let qemu = qemu()?;
    let defmt_print = if defmt { Some(defmt_print()?) } else { None };
    Ok(Qemu { qemu, defmt_print })
}

/// flip-link, the firmware's linker (set in .cargo/config.toml).
pub fn flip_link() -> Result<PathBuf, Failure> {
    cargo_tool("flip-link", "flip-link", "about a minute")
}

/// defmt-print, which decodes the firmware's defmt log (semihosting, in QEMU).
fn defmt_print() -> Result<PathBuf, Failure> {
    cargo_tool("defmt-print", "defmt-print", "a few minutes")
}

/// The standard library of `triple`, added with rustup when missing.
pub fn target(triple: &str) -> Result<(), Failure> {
    let mut rustc = Command::new("rustc");
    rustc
        .current_dir(workspace::root())
        .args(["--print", "sysroot"]);
    let sysroot = PathBuf::from(process::read(&mut rustc)?.trim());
    let lib = sysroot.join("lib/rustlib").join(triple).join("lib");
    if has_libcore(&lib) {
        return Ok(());
    }
    if on_path("rustup").is_none() {
        return Err(Failure::new(format!(
            "the {triple} standard library is missing (no libcore in {}) and rustup is not \
             installed: install rustup (https://rustup.rs), then run `rustup target add {triple}` \
             in {}",
            lib.display(),
            workspace::root().display()
        ))
        .status(127));
    }
    // `target add` installs even where RUSTUP_AUTO_INSTALL=0 stops rustup from
    // installing toolchains on its own; run in the root, it picks the pinned one.
    let mut add = Command::new("rustup");
    add.current_dir(workspace::root())
        .args(["target", "add", triple]);
    process::quietly(
        &format!("installing the {triple} target (once)…"),
        &mut [add],
    )?;
    if has_libcore(&lib) {
        Ok(())
    } else {
        Err(Failure::new(format!(
            "`rustup target add {triple}` ran but {} still has no libcore",
            lib.display()
        )))
    }
}

fn has_libcore(lib: &Path) -> bool {
    std::fs::read_dir(lib).is_ok_and(|entries| {
        entries.flatten().any(|entry| {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            name.starts_with("libcore-") && name.ends_with(".rlib")
        })
    })
}

/// qemu-system-arm, installed with apt-get when we can (root, Debian-like).
pub fn qemu() -> Result<PathBuf, Failure> {
    if let Some(path) = on_path("qemu-system-arm") {
        return Ok(path);
    }
    if let Some(installed) = apt_install("qemu-system-arm", "qemu-system-arm") {
        return installed;
    }
    Err(Failure::new(
        "qemu-system-arm not found. Install it, e.g.:\n\
         \x20   sudo apt-get install qemu-system-arm     (Debian/Ubuntu)\n\
         \x20   sudo dnf install qemu-system-arm         (Fedora)\n\
         \x20   brew install qemu                        (macOS)",
    )
    .status(127))
}

/// `binary` (chromium, node, npm for the browser test), installed from
/// Debian's `package` with apt-get when missing and we can (root, Debian-like).
pub fn apt_tool(binary: &str, package: &str) -> Result<PathBuf, Failure> {
    if let Some(path) = on_path(binary) {
        return Ok(path);
    }
    if let Some(installed) = apt_install(binary, package) {
        return installed;
    }
    Err(Failure::new(format!(
        "{binary} not found. Install it, e.g. `sudo apt-get install {package}` (Debian/Ubuntu)"
    ))
    .status(127))
}

/// `apt-get install package` for `binary`, where we are root on a system with
/// apt-get (none elsewhere: the caller says what to install by hand).
fn apt_install(binary: &str, package: &str) -> Option<Result<PathBuf, Failure>> {
    if !is_root() || on_path("apt-get").is_none() {
        return None;
    }
    let mut update = Command::new("apt-get");
    update.args(["update", "-qq"]);
    let mut install = Command::new("apt-get");
    install
        .env("DEBIAN_FRONTEND", "noninteractive")
        .args(["install", "-y", "-qq", package]);
    let installed = process::quietly(
        &format!("installing {package} with apt-get (once)…"),
        &mut [update, install],
    )
    .and_then(|()| {
        on_path(binary).ok_or_else(|| {
            Failure::new(format!(
                "apt-get installed {package} but {binary} is not on PATH"
            ))
            .status(127)
        })
    });
    Some(installed)
}

fn is_root() -> bool {
    let mut id = Command::new("id");
    id.arg("-u");
    process::read(&mut id).is_ok_and(|uid| uid.trim() == "0")
}

/// A tool installed with `cargo install <krate> --locked` when missing
/// (`duration`: how long that takes, for the status line).
fn cargo_tool(binary: &str, krate: &str, duration: &str) -> Result<PathBuf, Failure> {
    if let Some(path) = find_tool(binary) {
        return Ok(path);
    }
    let mut install = workspace::cargo();
    install.args(["install", krate, "--locked", "--quiet"]);
    process::quietly(
        &format!("installing {binary} (once, {duration})…"),
        &mut [install],
    )?;
    find_tool(binary).ok_or_else(|| {
        Failure::new(format!(
            "`cargo install {krate} --locked` ran but {binary} is neither on PATH nor in {}",
            workspace::cargo_bin().unwrap_or_default().display()
        ))
        .status(127)
    })
}

/// probe-rs, for the micro:bit; never installed for the user.
pub fn probe_rs() -> Result<PathBuf, Failure> {
    find_tool("probe-rs").ok_or_else(|| {
        Failure::new(
            "probe-rs is needed to run the micro:bit firmware; install it with: \
             cargo install probe-rs-tools --locked (on Linux also install its udev rules: \
             https://probe.rs/docs/getting-started/probe-setup/)",
        )
        .status(127)
    })
}
