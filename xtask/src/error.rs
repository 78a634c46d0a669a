//! Errors are values. Every task returns an [`Outcome`]; `main` prints a failure
//! once, as `xtask <task>: <message>`, and exits with its status, so no task
//! prints-and-exits on its own and nothing panics on bad input.

use std::fmt::Display;
use std::sync::OnceLock;

static TASK: OnceLock<&'static str> = OnceLock::new();

/// Names the running task for [`say!`] lines and the final error line.
pub fn set_task(name: &'static str) {
    let _ = TASK.set(name);
}

/// The running task's name (`qemu`, `check-demo`, ...).
pub fn task() -> &'static str {
    TASK.get().copied().unwrap_or("xtask")
}

/// One status line on stderr, `xtask <task>: <message>`: stdout is left to what
/// the task reports (firmware logs, tables), which other tools parse.
macro_rules! say {
    ($($arg:tt)*) => {
        eprintln!("xtask {}: {}", $crate::error::task(), format_args!($($arg)*))
    };
}
pub(crate) use say;

/// Why a task stopped, and the exit status that says so.
#[derive(Debug, PartialEq, Eq)]
pub struct Failure {
    pub message: String,
    pub status: u8,
}

impl Failure {
    /// A failure with exit status 1.
    pub fn new(message: impl Display) -> Self {
        Failure {
            message: message.to_string(),
            status: 1,
        }
    }

    /// The same failure with another exit status (e.g. 2 for usage, 127 for a
    /// missing tool, a child's own status).
    pub fn status(mut self, status: u8) -> Self {
        self.status = status;
        self
    }
}

/// A task's result: the exit status to end with, or why it failed.
pub type Outcome = Result<u8, Failure>;
