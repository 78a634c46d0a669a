//! Where the matrix's pictures go: a board's LED rows, one BCM scan step at a
//! time ([`MatrixOutput`]), at [`REFRESH_HZ`]; or an interactive terminal's
//! bytes ([`Console`]), where the QEMU board draws its virtual matrix.
//!
//! The traits sit with the display, below the boards that implement them and
//! the firmware tasks that drive them, so that a board's display needs nothing
//! from the tasks.

use core::future::Future;

use super::{ScanStep, Scanner};

/// Full LED-matrix refreshes per second.
pub const REFRESH_HZ: u32 = 100;

/// A blocking byte sink for an interactive terminal.
pub trait Console {
    /// Writes all of `bytes`.
    fn write(&mut self, bytes: &[u8]);
}

/// Something that can show BCM scan steps on a `W`×`H` LED matrix.
pub trait MatrixOutput<const W: usize, const H: usize> {
    /// Lights row `step.row` with the columns set in `step.columns`, holds it
    /// for `step.ticks` base ticks of the board's scan clock, then returns
    /// (the caller immediately shows the next step).
    fn show(&mut self, step: ScanStep) -> impl Future<Output = ()>;

    /// Shows one full refresh: the next [`Scanner::STEPS_PER_REFRESH`] steps
    /// of `scanner` (which is at the start of a refresh), in order, and
    /// returns when the refresh is over. By default, step by step with
    /// [`show`](Self::show); an output with nothing to wait for between steps
    /// (the virtual matrix) takes the whole refresh at once and saves an
    /// await per step.
    fn show_refresh(&mut self, scanner: &mut Scanner<W, H>) -> impl Future<Output = ()> {
        async move {
            for _ in 0..Scanner::<W, H>::STEPS_PER_REFRESH {
                self.show(scanner.next_step()).await;
            }
        }
    }
}
