//! A loop of a known number of instructions, and the two timings of it that
//! calibrate a CPU meter: the difference between a loop of 1 000 and one of
//! 11 000 iterations (80 000 instructions) cancels the call and clock-read
//! overhead. Under QEMU's `-icount` the ratio of clock ticks to instructions
//! is fixed; the boards turn [`NopTiming`] into their own calibration.

/// Instructions per iteration of [`nop_loop`] (6 NOPs, SUBS, BNE).
pub const INSTRUCTIONS_PER_ITERATION: u32 = 8;

/// Iterations of the short timed loop.
const SHORT: u32 = 1_000;
/// Iterations of the long timed loop.
const LONG: u32 = 11_000;

/// Runs `iterations` (≥ 1) of a loop of exactly
/// [`INSTRUCTIONS_PER_ITERATION`] instructions (6 NOPs, SUBS, BNE).
#[inline(never)]
pub fn nop_loop(iterations: u32) {
    let iterations = iterations.max(1);
    // SAFETY: touches only the one register it declares.
    unsafe {
        core::arch::asm!(
            "2:",
            "nop", "nop", "nop", "nop", "nop", "nop",
            "subs {n}, {n}, #1",
            "bne 2b",
            n = inout(reg) iterations => _,
            options(nomem, nostack),
        );
    }
}

/// A board's clock, timing a closure.
pub trait Stopwatch {
    /// Clock ticks `f` took, interrupts off.
    fn time(&self, f: impl FnOnce()) -> u32;
}

/// The calibration's measurements, in the board's clock ticks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NopTiming {
    /// Instructions the long loop ran beyond the short one.
    pub instructions: u32,
    /// Ticks the long loop took beyond the short one.
    pub ticks: u32,
    /// Ticks of timing nothing: the clock reads' own cost.
    pub overhead_ticks: u32,
}

/// Times the short and the long loop, and an empty closure, on `stopwatch`.
pub fn time_nop_loops(stopwatch: &impl Stopwatch) -> NopTiming {
    let short = stopwatch.time(|| nop_loop(SHORT));
    let long = stopwatch.time(|| nop_loop(LONG));
    let overhead = stopwatch.time(|| core::hint::black_box(()));
    NopTiming {
        instructions: INSTRUCTIONS_PER_ITERATION * (LONG - SHORT),
        ticks: long.saturating_sub(short),
        overhead_ticks: overhead,
    }
}
