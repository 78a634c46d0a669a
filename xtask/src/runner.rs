//! Runs firmware ELFs on any board of [`crate::boards`]: in its QEMU machine,
//! the log decoded by defmt-print (a defmt log) or passed on (a console), or
//! on the board itself with probe-rs. The firmware learns how it was started
//! from its semihosting command line: program name, then (a machine whose
//! firmware reads it, mps2-an386) `--headless`, `--interactive` or `--race`,
//! then the user's arguments.
//!
//! Headless runs use `-icount shift=7,align=off,sleep=off`: each instruction is
//! 2^7 ns of virtual time and idle time is skipped, so the output is the same on
//! every machine and every run, and instruction counts are exact. They are
//! killed after QEMU_TIMEOUT seconds, should the firmware hang (a CPU lockup
//! never exits).

use std::fs::File;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use crate::boards::{Firmware, Log, Machine};
use crate::error::{Failure, Outcome};
use crate::process;
use crate::setup::Qemu;
use crate::tty::{self, RawTerminal};

/// Virtual time from the instruction count (see the module doc).
pub const ICOUNT: [&str; 2] = ["-icount", "shift=7,align=off,sleep=off"];

/// Where a headless run's output goes.
pub enum Output<'a> {
    /// Our stdout and stderr.
    Terminal,
    /// One file for everything (check-demo's log).
    File(&'a File),
}

impl Output<'_> {
    /// A handle for one of a child's output streams.
    fn stdio(&self) -> Result<Stdio, Failure> {
        match self {
            Output::Terminal => Ok(Stdio::inherit()),
            Output::File(file) => clone(file),
        }
    }
}

fn clone(file: &File) -> Result<Stdio, Failure> {
    Ok(file
        .try_clone()
        .map_err(|e| Failure::new(format!("cannot share the log file: {e}")))?
        .into())
}

/// The arguments without `--` separators: `cargo qemu -- --demo` (through the
/// alias) and `cargo qemu --demo` mean the same.
pub fn drop_separators(args: &[String]) -> Vec<String> {
    args.iter().filter(|arg| *arg != "--").cloned().collect()
}

/// `-semihosting-config` for `program` with `args`; QEMU's option syntax needs
/// a comma inside a value doubled.
pub fn semihosting_config(program: &str, args: &[String]) -> String {
    let mut config = format!("enable=on,target=native,arg={}", program.replace(',', ",,"));
    for arg in args {
        config.push_str(",arg=");
        config.push_str(&arg.replace(',', ",,"));
    }
    config
}

/// The ELF's file name, which the firmware sees as its program name.
fn program(elf: &Path) -> String {
    elf.file_name()
        .map(|name| name.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// What QEMU loads.
pub enum Load<'a> {
    /// An ELF, as the kernel; its file name is the firmware's program name.
    Elf(&'a Path),
    /// A flash image (a `.hex`, as a person drags onto a board, or an ELF)
    /// put in place by QEMU's generic loader: the core then boots from the
    /// vector table it wrote, as a chip does from flash. The firmware sees
    /// `program` as its program name.
    Image { image: &'a Path, program: &'a str },
}

/// QEMU's `machine`, no display, no monitor, no default devices, with
/// `load`, its semihosting command line the program name, then `mode` (if
/// the machine's firmware reads one: [`Machine::modes`]), then `args`;
/// started in the workspace root (the mps2 firmware keeps its records' flash
/// image in `target/qemu-records.bin`, a path relative to there).
pub fn qemu(machine: &Machine, qemu: &Path, load: &Load, mode: &str, args: &[String]) -> Command {
    let mut line = Vec::with_capacity(args.len() + 1);
    if machine.modes {
        line.push(mode.to_string());
    }
    line.extend_from_slice(args);
    let program = match load {
        Load::Elf(elf) => program(elf),
        Load::Image { program, .. } => program.to_string(),
    };
    let mut cmd = Command::new(qemu);
    cmd.current_dir(crate::workspace::root());
    cmd.args(["-machine", machine.name]);
    if let Some(cpu) = machine.cpu {
        cmd.args(["-cpu", cpu]);
    }
    cmd.args(["-display", "none", "-monitor", "none", "-nodefaults"])
        .arg("-semihosting-config")
        .arg(semihosting_config(&program, &line));
    match load {
        Load::Elf(elf) => {
            cmd.arg("-kernel").arg(elf);
        }
        Load::Image { image, .. } => {
            let mut loader = std::ffi::OsString::from("loader,file=");
            loader.push(image.to_string_lossy().replace(',', ",,"));
            cmd.arg("-device").arg(loader);
        }
    }
    cmd
}

/// [`qemu`] headless: `--headless`, virtual time from the instruction count
/// ([`ICOUNT`]) and what the machine discards ([`Machine::headless`]).
pub fn headless_command(
    machine: &Machine,
    qemu_path: &Path,
    load: &Load,
    args: &[String],
) -> Command {
    let mut cmd = qemu(machine, qemu_path, load, "--headless", args);
    cmd.args(ICOUNT).args(machine.headless);
    cmd
}

/// The headless run of `elf` (`firmware`, built) on `machine`, killed after
/// `limit`, its log to `output`: a defmt log (semihosting, which QEMU writes
/// to its stdout) through defmt-print, a console (semihosting SYS_WRITE0,
/// which QEMU writes to its stderr) as it is, in one stream with the rest.
/// The status is QEMU's (the firmware sets it), else defmt-print's.
pub fn headless(
    machine: &Machine,
    firmware: &Firmware,
    tools: &Qemu,
    elf: &Path,
    args: &[String],
    output: Output,
    limit: Duration,
) -> Outcome {
    let mut cmd = headless_command(machine, &tools.qemu, &Load::Elf(elf), args);
    match firmware.log {
        Log::Defmt => decoded(cmd, tools, elf, output, limit).map(|(status, _)| status),
        Log::Console => {
            let stdout = match &output {
                Output::Terminal => stdout_copy(),
                Output::File(file) => clone(file)?,
            };
            cmd.stdin(Stdio::null())
                .stdout(output.stdio()?)
                .stderr(stdout);
            let mut child = process::spawn(&mut cmd)?;
            Ok(process::code(wait_at_most(&mut child, limit)?))
        }
    }
}

/// Runs `qemu`, a headless QEMU command line of any machine, killed after
/// `limit`, its defmt log (semihosting, on QEMU's stdout) through defmt-print
/// to `output`: the status (QEMU's when it failed, else defmt-print's) and the
/// host time QEMU ran.
pub fn decoded(
    mut qemu: Command,
    tools: &Qemu,
    elf: &Path,
    output: Output,
    limit: Duration,
) -> Result<(u8, Duration), Failure> {
    qemu.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(output.stdio()?);
    let started = Instant::now();
    let mut qemu_child = process::spawn(&mut qemu)?;
    let mut decoder = decoder(
        tools,
        elf,
        &mut qemu_child,
        output.stdio()?,
        output.stdio()?,
    )?;
    let qemu_status = wait_at_most(&mut qemu_child, limit);
    let decoder_status = decoder.wait();
    let qemu_status = qemu_status?;
    let decoder_status =
        decoder_status.map_err(|e| Failure::new(format!("waiting for defmt-print: {e}")))?;
    Ok((
        pipeline_status(qemu_status, decoder_status),
        started.elapsed(),
    ))
}

/// The interactive run (a machine that has it, [`Machine::interactive`]):
/// UART0 on the terminal (raw mode), real time (no -icount), the defmt log
/// into `log`, whose tail is printed at the end.
pub fn interactive(
    machine: &Machine,
    tools: &Qemu,
    elf: &Path,
    args: &[String],
    log: &Path,
) -> Outcome {
    if !tty::available() {
        return Err(
            Failure::new("interactive mode needs a terminal (/dev/tty); use --demo").status(2),
        );
    }
    if let Some(dir) = log.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::new(format!("cannot create {}: {e}", dir.display())))?;
    }
    let log_file = File::create(log)
        .map_err(|e| Failure::new(format!("cannot write {}: {e}", log.display())))?;
    let mut qemu = qemu(machine, &tools.qemu, &Load::Elf(elf), "--interactive", args);
    qemu.args([
        "-chardev",
        "serial,id=term,path=/dev/tty",
        "-serial",
        "chardev:term",
    ]);
    qemu.stdout(Stdio::piped());
    let raw = RawTerminal::enter()?;
    let mut qemu_child = process::spawn(&mut qemu)?;
    let mut decoder = decoder(
        tools,
        elf,
        &mut qemu_child,
        clone(&log_file)?,
        clone(&log_file)?,
    )?;
    let qemu_status = qemu_child.wait();
    let decoder_status = decoder.wait();
    drop(raw);
    let (Ok(qemu_status), Ok(decoder_status)) = (qemu_status, decoder_status) else {
        return Err(Failure::new("lost track of QEMU or defmt-print"));
    };
    println!();
    println!("xtask qemu: defmt log in {}; last lines:", log.display());
    let text = std::fs::read(log).unwrap_or_default();
    let text = String::from_utf8_lossy(&text);
    let lines: Vec<&str> = text.lines().collect();
    for line in &lines[lines.len().saturating_sub(8)..] {
        println!("{line}");
    }
    Ok(pipeline_status(qemu_status, decoder_status))
}

/// `defmt-print -e ELF` reading QEMU's stdout.
fn decoder(
    tools: &Qemu,
    elf: &Path,
    qemu: &mut Child,
    stdout: Stdio,
    stderr: Stdio,
) -> Result<Child, Failure> {
    let Some(pipe) = qemu.stdout.take() else {
        return Err(Failure::new("QEMU's stdout was not piped"));
    };
    let Some(defmt_print) = &tools.defmt_print else {
        let _ = qemu.kill();
        return Err(Failure::new("defmt-print was not set up for this run"));
    };
    let mut cmd = Command::new(defmt_print);
    cmd.arg("-e")
        .arg(elf)
        .stdin(pipe)
        .stdout(stdout)
        .stderr(stderr);
    process::spawn(&mut cmd).inspect_err(|_| {
        let _ = qemu.kill();
    })
}

/// Our stdout, for a child's stderr.
fn stdout_copy() -> Stdio {
    #[cfg(unix)]
    {
        use std::os::fd::AsFd;
        if let Ok(fd) = std::io::stdout().as_fd().try_clone_to_owned() {
            return fd.into();
        }
    }
    Stdio::inherit()
}

/// `probe-rs run --chip CHIP` on a board; probe-rs replaces us (its Ctrl-C
/// handling stops the core cleanly, and its status is the run's).
pub fn probe_rs(chip: &str, probe: &Path, elf: &Path, args: &[String]) -> Outcome {
    let mut cmd = Command::new(probe);
    cmd.args(["run", "--chip", chip]).arg(elf).args(args);
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        let error = cmd.exec();
        Err(Failure::new(format!("cannot run `{}`: {error}", process::shown(&cmd))).status(127))
    }
    #[cfg(not(unix))]
    Ok(process::code(process::status(&mut cmd)?))
}

/// The headless runs' time limit: QEMU_TIMEOUT seconds, else `default`.
/// Read before building, so that a typo fails at once.
pub fn timeout(default: u64) -> Result<Duration, Failure> {
    Ok(Duration::from_secs(crate::workspace::env_number(
        "QEMU_TIMEOUT",
        default,
    )?))
}

/// Waits for `child`, killing it after `limit` (status 124, as timeout(1) has).
pub fn wait_at_most(child: &mut Child, limit: Duration) -> Result<ExitStatus, Failure> {
    let start = Instant::now();
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return Ok(status),
            Ok(None) if start.elapsed() < limit => thread::sleep(Duration::from_millis(20)),
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(Failure::new(format!(
                    "QEMU timed out after {} s (a hung firmware? raise QEMU_TIMEOUT if not)",
                    limit.as_secs()
                ))
                .status(124));
            }
            Err(e) => return Err(Failure::new(format!("waiting for QEMU: {e}"))),
        }
    }
}

/// The run's status: QEMU's when it failed (the firmware's verdict), else the
/// decoder's, so that a decoding failure does not pass silently.
fn pipeline_status(qemu: ExitStatus, decoder: ExitStatus) -> u8 {
    match process::code(qemu) {
        0 => process::code(decoder),
        code => code,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boards;

    fn strings(args: &[&str]) -> Vec<String> {
        args.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn separators_are_dropped() {
        assert_eq!(
            drop_separators(&strings(&["--", "--demo", "--", "x"])),
            ["--demo", "x"]
        );
    }

    #[test]
    fn semihosting_commas_are_doubled() {
        assert_eq!(
            semihosting_config("qemu", &strings(&["--headless", "--level=a,b", ""])),
            "enable=on,target=native,arg=qemu,arg=--headless,arg=--level=a,,b,arg="
        );
        assert_eq!(
            semihosting_config("bench_m0", &[]),
            "enable=on,target=native,arg=bench_m0"
        );
    }

    #[cfg(unix)]
    #[test]
    fn hung_children_are_killed() {
        let Ok(mut child) = Command::new("sleep").arg("30").spawn() else {
            return;
        };
        let start = Instant::now();
        let failure = wait_at_most(&mut child, Duration::from_millis(200)).unwrap_err();
        assert_eq!(failure.status, 124);
        assert!(start.elapsed() < Duration::from_secs(5));
        let mut quick = Command::new("true");
        let status = wait_at_most(&mut quick.spawn().unwrap(), Duration::from_secs(30));
        assert!(status.unwrap().success());
    }

    #[cfg(unix)]
    #[test]
    fn pipeline_status_prefers_qemu() {
        use std::os::unix::process::ExitStatusExt;
        let exit = |code: i32| ExitStatus::from_raw(code << 8);
        assert_eq!(pipeline_status(exit(0), exit(0)), 0);
        assert_eq!(pipeline_status(exit(1), exit(0)), 1);
        assert_eq!(pipeline_status(exit(0), exit(3)), 3);
        assert_eq!(pipeline_status(exit(2), exit(3)), 2);
        assert_eq!(pipeline_status(ExitStatus::from_raw(9), exit(0)), 137);
    }

    #[test]
    fn mps2_command_line() {
        let machine = boards::QEMU.machine().expect("a machine");
        let load = Load::Elf(Path::new("/t/qemu"));
        let cmd = qemu(
            machine,
            Path::new("qemu-system-arm"),
            &load,
            "--headless",
            &["--demo".into()],
        );
        assert_eq!(
            process::shown(&cmd),
            "qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -display none -monitor none \
             -nodefaults -semihosting-config \
             enable=on,target=native,arg=qemu,arg=--headless,arg=--demo -kernel /t/qemu"
        );
        let cmd = headless_command(machine, Path::new("qemu-system-arm"), &load, &[]);
        assert!(process::shown(&cmd).ends_with(
            "arg=qemu,arg=--headless -kernel /t/qemu -icount shift=7,align=off,sleep=off -serial null"
        ));
    }

    #[test]
    fn microbit_command_line_has_no_mode() {
        let machine = boards::MICROBIT_V1.machine().expect("a machine");
        let cmd = headless_command(
            machine,
            Path::new("qemu-system-arm"),
            &Load::Elf(Path::new("/t/microbit-v1")),
            &["--demo".into()],
        );
        assert_eq!(
            process::shown(&cmd),
            "qemu-system-arm -machine microbit -display none -monitor none -nodefaults \
             -semihosting-config enable=on,target=native,arg=microbit-v1,arg=--demo \
             -kernel /t/microbit-v1 -icount shift=7,align=off,sleep=off"
        );
    }

    #[test]
    fn an_image_is_loaded_by_the_generic_loader_not_as_the_kernel() {
        let image = Load::Image {
            image: Path::new("/t/a,b/v1.hex"),
            program: "microbit-v1",
        };
        let machine = boards::MICROBIT_V1.machine().expect("a machine");
        let cmd = qemu(
            machine,
            Path::new("qemu-system-arm"),
            &image,
            "--headless",
            &["--demo".into()],
        );
        let shown = process::shown(&cmd);
        assert!(
            shown.ends_with("arg=microbit-v1,arg=--demo -device loader,file=/t/a,,b/v1.hex"),
            "{shown}"
        );
        assert!(!shown.contains("-kernel"), "{shown}");
    }
}
