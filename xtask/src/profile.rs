//! `cargo xtask qemu-profile [TOP] [--v1]`: where the QEMU firmware's
//! instructions go, by function (the mps2-an386 board's, or with `--v1` the
//! micro:bit v1's in QEMU microbit). Runs the headless demo with QEMU's translation-block trace on
//! (`-d in_asm,exec,nochain`: every executed block is logged, chaining off so
//! none is skipped) and attributes every executed instruction to the function
//! holding it (see trace.rs). The trace is large (about 2 GB for the whole
//! demo, in PROFILE_DIR, default `<target>/qemu-profile`; deleted afterwards
//! unless KEEP_TRACE=1), so it is streamed, never loaded whole.

use std::fs::File;
use std::io::{BufRead, BufReader};
use std::process::Stdio;

use crate::error::{say, Failure, Outcome};
use crate::firmware::{self, Artifact};
use crate::microbit_v1;
use crate::process;
use crate::runner;
use crate::setup::{self, M0, M4};
use crate::symbols::{self, Symbols};
use crate::trace::Profile;
use crate::workspace;

/// Runs, attributes, prints the tables on stdout.
pub fn run(top: usize, v1: bool) -> Outcome {
    let qemu = setup::qemu()?;
    let elf = if v1 {
        setup::target(M0)?;
        firmware::build(&Artifact::firmware(
            microbit_v1::PACKAGE,
            microbit_v1::BIN,
            M0,
        ))?
    } else {
        setup::target(M4)?;
        setup::flip_link()?;
        firmware::build(&Artifact::firmware("marble-qemu", "qemu", M4))?
    };
    let dir = workspace::env_path("PROFILE_DIR", workspace::target_dir()?.join("qemu-profile"));
    std::fs::create_dir_all(&dir)
        .map_err(|e| Failure::new(format!("cannot create {}: {e}", dir.display())))?;
    let trace = dir.join("trace.log");
    let defmt = File::create(dir.join("defmt.bin"))
        .map_err(|e| Failure::new(format!("cannot write in {}: {e}", dir.display())))?;

    let demo = ["--demo".to_string()];
    let mut cmd = if v1 {
        // Its command line already counts instructions (`-icount`).
        microbit_v1::qemu_command(&qemu, &elf, &demo)
    } else {
        let mut cmd = runner::mps2(&qemu, &elf, "--headless", &demo);
        cmd.args(runner::ICOUNT).args(["-serial", "null"]);
        cmd
    };
    cmd.args(["-d", "in_asm,exec,nochain", "-D"])
        .arg(&trace)
        .stdin(Stdio::null())
        .stdout(defmt);
    say!(
        "tracing the headless demo in QEMU (about 2 GB in {})…",
        trace.display()
    );
    let status = process::status(&mut cmd)?;
    if !status.success() {
        return Err(Failure::new(format!(
            "QEMU exited with status {} (`{}`)",
            process::code(status),
            process::shown(&cmd)
        )));
    }

    let data = std::fs::read(&elf)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", elf.display())))?;
    let symbols = symbols::code_symbols(&data)
        .map_err(|e| Failure::new(format!("cannot read the symbols of {}: {e}", elf.display())))?;
    let mut profile = Profile::new(Symbols::new(&symbols));
    say!("attributing the trace to functions…");
    let file = File::open(&trace)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", trace.display())))?;
    let mut reader = BufReader::with_capacity(1 << 20, file);
    let mut line = Vec::with_capacity(256);
    loop {
        line.clear();
        match reader.read_until(b'\n', &mut line) {
            Ok(0) => break,
            Ok(_) => profile.line(&line),
            Err(e) => return Err(Failure::new(format!("reading {}: {e}", trace.display()))),
        }
    }
    print!("{}", profile.report(top));
    if std::env::var("KEEP_TRACE").as_deref() != Ok("1") {
        let _ = std::fs::remove_file(&trace);
    }
    Ok(0)
}
