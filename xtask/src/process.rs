//! Child processes: exit statuses as a shell reports them (so a wrapped tool's
//! status passes through unchanged), commands shown the way a user would type
//! them, and quiet runs for installs, whose output only matters when they fail.

use std::io::{IsTerminal, Read, Write};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::thread;
use std::time::{Duration, Instant};

use crate::error::{say, task, Failure};

/// The status a shell would report: the exit code, or 128 + the signal.
pub fn code(status: ExitStatus) -> u8 {
    if let Some(code) = status.code() {
        return (code & 0xff) as u8;
    }
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            return (128 + signal).clamp(0, 255) as u8;
        }
    }
    1
}

/// `cmd` as one would type it: environment assignments, program, arguments
/// (quoted when the shell would need it).
pub fn shown(cmd: &Command) -> String {
    let mut words = Vec::new();
    for (key, value) in cmd.get_envs() {
        // PATH is only ever widened by us (the cargo bin directory): not worth showing.
        if let (Some(value), false) = (value, key == "PATH") {
            words.push(format!(
                "{}={}",
                key.to_string_lossy(),
                quote(&value.to_string_lossy())
            ));
        }
    }
    words.push(quote(&cmd.get_program().to_string_lossy()));
    words.extend(cmd.get_args().map(|arg| quote(&arg.to_string_lossy())));
    words.join(" ")
}

/// Single quotes around a word the shell would split or expand.
fn quote(word: &str) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c);
    if !word.is_empty() && word.chars().all(plain) {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

/// Starts `cmd`, naming it in the error when it cannot start (not installed...).
pub fn spawn(cmd: &mut Command) -> Result<Child, Failure> {
    cmd.spawn()
        .map_err(|e| Failure::new(format!("cannot run `{}`: {e}", shown(cmd))).status(127))
}

/// Runs `cmd` to the end with inherited stdio.
pub fn status(cmd: &mut Command) -> Result<ExitStatus, Failure> {
    let mut child = spawn(cmd)?;
    child
        .wait()
        .map_err(|e| Failure::new(format!("waiting for `{}`: {e}", shown(cmd))))
}

/// Runs `cmd` and returns its stdout; a failure quotes its stderr.
pub fn read(cmd: &mut Command) -> Result<String, Failure> {
    cmd.stdin(Stdio::null());
    let out = cmd
        .output()
        .map_err(|e| Failure::new(format!("cannot run `{}`: {e}", shown(cmd))).status(127))?;
    if !out.status.success() {
        return Err(Failure::new(format!(
            "`{}` failed ({}): {}",
            shown(cmd),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim_end()
        )));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Runs `cmds` one after the other with their output captured, under one status
/// line (`line`, with a spinner while it works when stderr is a terminal). On
/// success that line is all the user sees; on failure the error holds the
/// failing command's output and the command to run by hand.
pub fn quietly(line: &str, cmds: &mut [Command]) -> Result<(), Failure> {
    let spinner = std::io::stderr().is_terminal();
    if !spinner {
        say!("{line}");
    }
    let start = Instant::now();
    let mut result = Ok(());
    for cmd in cmds.iter_mut() {
        result = run_captured(cmd, |tick| {
            if spinner {
                let frame = ['|', '/', '-', '\\'][tick % 4];
                let seconds = start.elapsed().as_secs();
                eprint!("\r\x1b[Kxtask {}: {line} {frame} {seconds} s", task());
                let _ = std::io::stderr().flush();
            }
        });
        if result.is_err() {
            break;
        }
    }
    if spinner {
        eprintln!("\r\x1b[Kxtask {}: {line}", task());
    }
    result
}

/// One captured run; `tick` is called about ten times a second while it runs.
fn run_captured(cmd: &mut Command, mut tick: impl FnMut(usize)) -> Result<(), Failure> {
    let shown = shown(cmd);
    cmd.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = spawn(cmd)?;
    // Both pipes drained concurrently: a tool blocked on a full stderr pipe
    // while we wait for it would never end.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        thread::spawn(move || {
            let mut text = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut text);
            }
            text
        })
    };
    let out = drain(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = drain(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let mut ticks = 0;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) => {}
            Err(e) => return Err(Failure::new(format!("waiting for `{shown}`: {e}"))),
        }
        tick(ticks);
        ticks += 1;
        thread::sleep(Duration::from_millis(100));
    };
    let mut output = out.join().unwrap_or_default();
    output.extend(err.join().unwrap_or_default());
    if status.success() {
        return Ok(());
    }
    let output = String::from_utf8_lossy(&output);
    Err(Failure::new(format!(
        "`{shown}` failed ({status}); its output:\n{}\nrun it yourself: {shown}",
        output.trim_end()
    ))
    .status(code(status).max(1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_are_shown_as_typed() {
        let mut cmd = Command::new("apt-get");
        cmd.env("DEBIAN_FRONTEND", "noninteractive")
            .args(["install", "-y", "a b", "it's"]);
        assert_eq!(
            shown(&cmd),
            r"DEBIAN_FRONTEND=noninteractive apt-get install -y 'a b' 'it'\''s'"
        );
    }

    #[test]
    fn quiet_failure_keeps_output_and_command() {
        let mut cmds = [Command::new("sh")];
        cmds[0].args(["-c", "echo out; echo err >&2; exit 3"]);
        let failure = quietly("testing", &mut cmds).unwrap_err();
        assert_eq!(failure.status, 3);
        assert!(failure.message.contains("out\nerr"), "{}", failure.message);
        assert!(
            failure.message.contains("run it yourself: sh -c"),
            "{}",
            failure.message
        );
    }
}
