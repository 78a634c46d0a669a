//! `cargo xtask hex --check`: the proof that the files `cargo xtask hex`
//! writes ([`crate::hex_files`], whose doc says what is proven) are right, by
//! tools other than ours: the micro:bit Foundation's library splits the
//! universal hex, llvm-objcopy flattens every file and ELF, and the V1 image
//! from the universal hex plays the demo in QEMU's `microbit` machine.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::boards::MICROBIT_V1;
use crate::demo;
use crate::error::{say, Failure};
use crate::hex::{self, Image};
use crate::hex_files::{
    region_holds, write, Written, BOARDS, FORMAT_WORDS, LIBRARY, LIBRARY_VERSION,
};
use crate::microbit_v1;
use crate::process;
use crate::runner;
use crate::setup;
use crate::workspace;

use marble_rolling::board::levels_region;

/// The proof (see the module doc).
pub(crate) fn check(written: &Written) -> Result<(), Failure> {
    let Written {
        target,
        built,
        universal,
        levels,
    } = written;
    let levels = levels.as_deref();
    let dir = target.join("hex-check");
    std::fs::create_dir_all(&dir)
        .map_err(|e| Failure::new(format!("cannot create {}: {e}", dir.display())))?;
    let separated = separate(&dir, universal)?;
    let objcopy = llvm_objcopy()?;
    let mut problems = Vec::new();
    for (board, built) in BOARDS.iter().zip(built) {
        let Some(from_universal) = separated.get(&board.block) else {
            problems.push(format!(
                "{}: the library found no block of type {:#06x} in {}",
                board.name,
                board.block,
                universal.display()
            ));
            continue;
        };
        let mut reference = flat_binary(&objcopy, &built.elf, None, &dir, board.name, "elf")?;
        if let Some(files) = levels {
            // llvm-objcopy's image of the ELF, and after it the region (read
            // back below with the firmware's reader, not compared to ours).
            let (base, _) = built.elf_image.flat();
            let (_, with_region) = built.image.flat();
            let at = (board.region - base) as usize;
            reference.resize(at, 0);
            reference.extend_from_slice(&with_region[at..]);
            let split = std::fs::read_to_string(from_universal)
                .map_err(|e| e.to_string())
                .and_then(|text| hex::image_of_intel_hex(&text))
                .and_then(|image| region_holds(&image, board.region, files));
            match split {
                Ok(()) => say!(
                    "{}: the region in the library's split holds the {} level(s), as the firmware reads it",
                    board.name,
                    files.len()
                ),
                Err(e) => problems.push(format!("{}: {e}", board.name)),
            }
        }
        let tried = [
            (
                "the library's split of the universal hex",
                from_universal,
                "universal",
            ),
            ("the plain file", &built.plain, "plain"),
        ];
        for (what, file, tag) in tried {
            // llvm-objcopy's flat binary starts wherever the file does: the
            // start address is compared apart.
            let start = |image: &Image| image.runs().first().map(|run| run.0);
            let read = std::fs::read_to_string(file)
                .map_err(|e| format!("cannot read it: {e}"))
                .and_then(|text| hex::image_of_intel_hex(&text));
            match read.map(|image| start(&image)) {
                Ok(at) if at == start(&built.image) => {}
                Ok(at) => problems.push(format!(
                    "{}: {what} ({}) starts at {at:x?}, the ELF's image at {:x?}",
                    board.name,
                    file.display(),
                    start(&built.image)
                )),
                Err(e) => {
                    problems.push(format!("{}: {what} ({}): {e}", board.name, file.display()))
                }
            }
            let binary = flat_binary(&objcopy, file, Some("ihex"), &dir, board.name, tag)?;
            match first_difference(&reference, &binary) {
                None => say!(
                    "{}: {what} ({}) is the ELF's image{} byte for byte ({} B, llvm-objcopy -O binary)",
                    board.name,
                    file.display(),
                    if levels.is_some() { " and the levels region" } else { "" },
                    reference.len()
                ),
                Some(at) => problems.push(format!(
                    "{}: {what} ({}) differs from llvm-objcopy's image of {} at byte {at:#x} \
                     (lengths {} and {})",
                    board.name,
                    file.display(),
                    built.elf.display(),
                    binary.len(),
                    reference.len()
                )),
            }
        }
    }
    if let (Some(v1_hex), Some(v1)) = (separated.get(&hex::BOARD_V1), built.first()) {
        if let Err(problem) = demo_from_image(target, &v1.elf, v1_hex, levels) {
            problems.push(problem);
        }
    }
    if problems.is_empty() {
        say!("OK: the Foundation's library splits the universal hex into our images; the V1's wins the QEMU demo");
        Ok(())
    } else {
        for problem in &problems {
            say!("{problem}");
        }
        Err(Failure::new(format!(
            "FAILED: {} problem(s) with the files in {}",
            problems.len(),
            universal.parent().unwrap_or(target).display()
        )))
    }
}

/// Splits `universal` with the Foundation's library (installed in `dir`
/// when missing): block type → the Intel HEX file it wrote.
fn separate(dir: &Path, universal: &Path) -> Result<BTreeMap<u16, PathBuf>, Failure> {
    let node = setup::apt_tool("node", "nodejs")?;
    if installed_version(dir).as_deref() != Some(LIBRARY_VERSION) {
        let npm = setup::apt_tool("npm", "npm")?;
        let mut install = Command::new(npm);
        install.current_dir(dir).args([
            "install",
            "--prefix",
            ".",
            "--no-save",
            "--no-package-lock",
            "--no-audit",
            "--no-fund",
            &format!("{LIBRARY}@{LIBRARY_VERSION}"),
        ]);
        process::quietly(
            &format!("installing {LIBRARY}@{LIBRARY_VERSION} with npm (once)…"),
            &mut [install],
        )?;
        if installed_version(dir).as_deref() != Some(LIBRARY_VERSION) {
            return Err(Failure::new(format!(
                "npm installed {LIBRARY}@{LIBRARY_VERSION} but {} has version {:?}",
                dir.display(),
                installed_version(dir)
            )));
        }
    }
    let script = dir.join("separate-universal-hex.cjs");
    write(&script, include_str!("../js/separate-universal-hex.cjs"))?;
    let out = dir.join("separated");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out)
        .map_err(|e| Failure::new(format!("cannot create {}: {e}", out.display())))?;
    let mut cmd = Command::new(node);
    cmd.current_dir(dir).arg(&script).arg(universal).arg(&out);
    let listing = process::read(&mut cmd)?;
    let separated = parse_separated(&listing)
        .map_err(|e| Failure::new(format!("`{}`: {e}", process::shown(&cmd))))?;
    say!(
        "{LIBRARY}@{LIBRARY_VERSION} split {} into block types {}",
        universal.display(),
        separated
            .keys()
            .map(|id| format!("{id:#06x}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(separated)
}

/// The version of the library installed in `dir`, if any.
fn installed_version(dir: &Path) -> Option<String> {
    let manifest = dir.join("node_modules").join(LIBRARY).join("package.json");
    let text = std::fs::read_to_string(manifest).ok()?;
    let json: serde_json::Value = serde_json::from_str(&text).ok()?;
    json["version"].as_str().map(str::to_string)
}

/// The script's `<block type in hex> <file>` lines.
fn parse_separated(listing: &str) -> Result<BTreeMap<u16, PathBuf>, String> {
    let mut files = BTreeMap::new();
    for line in listing.lines().filter(|line| !line.trim().is_empty()) {
        let (id, file) = line
            .split_once(' ')
            .ok_or_else(|| format!("unexpected line {line:?}"))?;
        let id = u16::from_str_radix(id, 16)
            .map_err(|_| format!("block type {id:?} is not a 16-bit hex number"))?;
        if files.insert(id, PathBuf::from(file)).is_some() {
            return Err(format!("block type {id:#06x} twice"));
        }
    }
    Ok(files)
}

/// llvm-objcopy from rustup's llvm-tools (added when missing: it belongs to
/// the pinned toolchain, rust-toolchain.toml lists it).
fn llvm_objcopy() -> Result<PathBuf, Failure> {
    let mut rustc = Command::new("rustc");
    rustc.current_dir(workspace::root()).arg("-vV");
    let version = process::read(&mut rustc)?;
    let host = version
        .lines()
        .find_map(|line| line.strip_prefix("host: "))
        .ok_or_else(|| Failure::new("`rustc -vV` names no host"))?
        .trim()
        .to_string();
    let mut sysroot = Command::new("rustc");
    sysroot
        .current_dir(workspace::root())
        .args(["--print", "sysroot"]);
    let sysroot = PathBuf::from(process::read(&mut sysroot)?.trim());
    let path = sysroot
        .join("lib/rustlib")
        .join(&host)
        .join("bin")
        .join(format!("llvm-objcopy{}", std::env::consts::EXE_SUFFIX));
    if path.is_file() {
        return Ok(path);
    }
    let mut add = Command::new("rustup");
    add.current_dir(workspace::root())
        .args(["component", "add", "llvm-tools"]);
    process::quietly("installing rustup's llvm-tools (once)…", &mut [add])?;
    if path.is_file() {
        Ok(path)
    } else {
        Err(Failure::new(format!(
            "`rustup component add llvm-tools` ran but {} is missing",
            path.display()
        ))
        .status(127))
    }
}

/// `llvm-objcopy [-I FORMAT] -O binary FILE` into `dir`, read back.
fn flat_binary(
    objcopy: &Path,
    file: &Path,
    input: Option<&str>,
    dir: &Path,
    board: &str,
    tag: &str,
) -> Result<Vec<u8>, Failure> {
    let out = dir.join(format!("{board}-{tag}.bin"));
    let mut cmd = Command::new(objcopy);
    if let Some(format) = input {
        cmd.args(["-I", format]);
    }
    cmd.args(["-O", "binary"]).arg(file).arg(&out);
    process::read(&mut cmd)?;
    std::fs::read(&out).map_err(|e| Failure::new(format!("cannot read {}: {e}", out.display())))
}

/// Where two byte strings first differ (the shorter one's end if one is a
/// prefix of the other), `None` when equal.
pub fn first_difference(a: &[u8], b: &[u8]) -> Option<usize> {
    match a.iter().zip(b).position(|(x, y)| x != y) {
        Some(at) => Some(at),
        None if a.len() == b.len() => None,
        None => Some(a.len().min(b.len())),
    }
}

/// Runs the V1 demo in QEMU from `image` (the .hex the library split off),
/// decoding the log with `elf`; it must win every level, and with `levels`
/// in its region play them first, as the simulator plays their files.
fn demo_from_image(
    target: &Path,
    elf: &Path,
    image: &Path,
    levels: Option<&[(String, Vec<u8>)]>,
) -> Result<(), String> {
    let fail = |e: Failure| e.message;
    let limit = runner::timeout(MICROBIT_V1.game.timeout).map_err(fail)?;
    let tools = MICROBIT_V1.game.qemu_tools().map_err(fail)?;
    let log_path = target.join("hex-check/v1-demo.log");
    let file = demo::create_log(&log_path).map_err(fail)?;
    say!(
        "running the V1 demo in QEMU microbit from {} (QEMU's loader; log {})…",
        image.display(),
        log_path.display()
    );
    let args = ["--demo".to_string(), "--no-frame-log".to_string()];
    let status = microbit_v1::run_image(&tools, elf, image, &args, &file, limit).map_err(fail)?;
    let text = demo::read_log(&log_path).map_err(fail)?;
    let won = demo_verdict(status, &text).map_err(|why| {
        format!(
            "V1 from the universal hex in QEMU: {why} (log {})",
            log_path.display()
        )
    })?;
    say!("V1 from the universal hex: {won}/{won} levels won in QEMU microbit");
    let Some(files) = levels else {
        return Ok(());
    };
    let played = region_first(&text, files).map_err(|why| {
        format!(
            "V1 from the universal hex in QEMU: {why} (log {})",
            log_path.display()
        )
    })?;
    let stepping = demo::parse_stepping(&text).ok_or_else(|| {
        format!(
            "V1 from the universal hex: no `demo stepping=` line in {}",
            log_path.display()
        )
    })?;
    let sim = demo::build_sim().map_err(|e| e.message)?;
    let mut mismatches = Vec::new();
    for ((file, _), level) in files.iter().zip(&played) {
        // The simulator runs in the workspace's root: the file by its full path.
        let path = std::fs::canonicalize(file).unwrap_or_else(|_| PathBuf::from(file));
        let host = demo::simulate(&sim, &path.to_string_lossy(), stepping);
        match demo::verdict(level, host.as_ref()) {
            demo::Verdict::Ok => say!(
                "V1 from the universal hex plays the region's {} ({file}) before the built-in levels: \
                 {} in {} steps, state_hash={} as cargo sim -- --level {file} --autopilot --stepping {stepping}",
                level.name,
                level.outcome,
                level.steps,
                level.hash
            ),
            verdict => mismatches.push(format!(
                "{} ({file}): QEMU {} in {} steps, state_hash={}; cargo sim {:?}: {verdict:?}",
                level.name, level.outcome, level.steps, level.hash, host
            )),
        }
    }
    if mismatches.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "V1 from the universal hex: the region's levels do not play as in cargo sim: {} (log {})",
            mismatches.join("; "),
            log_path.display()
        ))
    }
}

/// The demo's first levels in `log`, which must be those of `files` (name,
/// contents: the levels region's), in order, named as their headers name
/// them: the firmware plays its region before the built-in levels.
pub fn region_first(log: &str, files: &[(String, Vec<u8>)]) -> Result<Vec<demo::Level>, String> {
    let (played, _) = demo::parse_levels(log);
    let mut first = Vec::new();
    for (index, (file, bytes)) in files.iter().enumerate() {
        // Boxed: the largest level's grid is 16 KiB.
        let parsed = Box::new(levels_region::level::<FORMAT_WORDS>(bytes));
        let name = match &*parsed {
            Ok(level) => level.info.name,
            Err(e) => return Err(format!("{file}: not a level the region can hold: {e:?}")),
        };
        match played.get(index) {
            Some(level) if level.name == name => first.push(level.clone()),
            Some(level) => {
                return Err(format!(
                    "demo level {} is {}, not the region's {name} ({file})",
                    index + 1,
                    level.name
                ))
            }
            None => {
                return Err(format!(
                    "the demo played {} levels, not the region's {name} ({file})",
                    played.len()
                ))
            }
        }
    }
    Ok(first)
}

/// The demo's verdict from its exit status and log: the number of levels,
/// when every one was won and the firmware's summary says PASS.
pub fn demo_verdict(status: u8, log: &str) -> Result<usize, String> {
    if status != 0 {
        return Err(format!("the firmware exited with status {status}"));
    }
    let (levels, total) = demo::parse_levels(log);
    if levels.is_empty() {
        return Err("no level was played".into());
    }
    if total != Some(levels.len()) {
        return Err(format!(
            "{} levels played of {}",
            levels.len(),
            total.map_or("an unknown number".into(), |n| n.to_string())
        ));
    }
    if let Some(lost) = levels.iter().find(|level| level.outcome != "won") {
        return Err(format!("level {} ended {}", lost.name, lost.outcome));
    }
    let summary = format!("demo summary: {n}/{n} levels won", n = levels.len());
    match log.lines().find(|line| line.contains("demo summary: ")) {
        Some(line) if line.contains(&summary) && line.trim_end().ends_with("PASS") => {
            Ok(levels.len())
        }
        Some(line) => Err(format!("the summary says {:?}", line.trim())),
        None => Err("no `demo summary:` line".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences() {
        assert_eq!(first_difference(b"abc", b"abc"), None);
        assert_eq!(first_difference(b"abc", b"abd"), Some(2));
        assert_eq!(first_difference(b"abc", b"ab"), Some(2));
        assert_eq!(first_difference(b"", b"a"), Some(0));
        assert_eq!(first_difference(b"", b""), None);
    }

    #[test]
    fn the_scripts_listing() {
        let files = parse_separated("9900 /t/board-9900.hex\n9903 /t/board-9903.hex\n").unwrap();
        assert_eq!(files[&0x9900], PathBuf::from("/t/board-9900.hex"));
        assert_eq!(files[&0x9903], PathBuf::from("/t/board-9903.hex"));
        assert!(parse_separated("9900 a\n9900 b\n").is_err());
        assert!(parse_separated("zz a\n").is_err());
        assert!(parse_separated("9900\n").is_err());
    }

    const CORNER: &str =
        "name: my-corner\n---\n#########\n#S......#\n#######.#\n#G......#\n#########\n";

    fn files(levels: &[(&str, &str)]) -> Vec<(String, Vec<u8>)> {
        levels
            .iter()
            .map(|(name, text)| (name.to_string(), text.as_bytes().to_vec()))
            .collect()
    }

    const WON: &str = "1.0 INFO  demo stepping=events\n\
        1.5 INFO  demo 1/2 level=first-roll outcome=won steps=73 state_hash=09e3a713b6b01b0e\n\
        4.4 INFO  demo 2/2 level=corner outcome=won steps=241 state_hash=88cb3b0d88d46483\n\
        4.5 INFO  demo summary: 2/2 levels won, 314 physics steps in 314 frames: PASS\n";

    #[test]
    fn the_regions_levels_come_first_in_the_demo() {
        let region = files(&[("tests/levels/my-corner.level", CORNER)]);
        let first = WON.replace("level=first-roll", "level=my-corner");
        let played = region_first(&first, &region).unwrap();
        assert_eq!(played.len(), 1);
        assert_eq!(played[0].name, "my-corner");
        assert_eq!(played[0].hash, "09e3a713b6b01b0e");
        // The built-in levels first: the firmware did not play its region.
        assert_eq!(
            region_first(WON, &region).unwrap_err(),
            "demo level 1 is first-roll, not the region's my-corner (tests/levels/my-corner.level)"
        );
        assert!(region_first("", &region)
            .unwrap_err()
            .starts_with("the demo played 0 levels"));
    }

    #[test]
    fn the_demos_verdict() {
        assert_eq!(demo_verdict(0, WON), Ok(2));
        assert!(demo_verdict(1, WON).unwrap_err().contains("status 1"));
        let lost = WON.replace("corner outcome=won", "corner outcome=lost");
        assert!(demo_verdict(0, &lost).unwrap_err().contains("corner"));
        let short: String = WON.lines().take(2).map(|l| format!("{l}\n")).collect();
        assert!(demo_verdict(0, &short)
            .unwrap_err()
            .contains("1 levels played of 2"));
        let failed = WON.replace(": PASS", ": FAIL");
        assert!(demo_verdict(0, &failed).is_err());
        assert!(demo_verdict(0, "").is_err());
    }
}
