//! The terminal in raw mode for the interactive game, and put back afterwards
//! (also on early returns: the guard restores it when dropped). QEMU's serial
//! backend reprograms the line itself, so the saved settings cannot always be
//! restored on a pseudo-terminal; `stty sane` is the fallback then.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::process::{Command, Stdio};

use crate::error::Failure;

const TTY: &str = "/dev/tty";

/// The controlling terminal, raw, until dropped.
pub struct RawTerminal {
    saved: String,
}

impl RawTerminal {
    /// Saves the terminal's settings and makes it raw, without echo.
    pub fn enter() -> Result<Self, Failure> {
        let saved = stty(&["-g"])?.trim().to_string();
        stty(&["raw", "-echo"])?;
        Ok(RawTerminal { saved })
    }
}

impl Drop for RawTerminal {
    fn drop(&mut self) {
        if stty(&[&self.saved]).is_err() {
            let _ = stty(&["sane"]);
        }
        // Colours off and the cursor back on, whatever the game left behind.
        if let Ok(mut tty) = OpenOptions::new().write(true).open(TTY) {
            let _ = tty.write_all(b"\x1b[0m\x1b[?25h");
        }
    }
}

/// Whether there is a controlling terminal to play on.
pub fn available() -> bool {
    OpenOptions::new().read(true).write(true).open(TTY).is_ok()
}

/// `stty ARGS </dev/tty`, its stdout.
fn stty(args: &[&str]) -> Result<String, Failure> {
    let tty = File::open(TTY).map_err(|e| Failure::new(format!("cannot open {TTY}: {e}")))?;
    let out = Command::new("stty")
        .args(args)
        .stdin(tty)
        .stderr(Stdio::null())
        .output()
        .map_err(|e| Failure::new(format!("cannot run stty: {e}")))?;
    if !out.status.success() {
        return Err(Failure::new(format!("`stty {}` failed", args.join(" "))));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}
