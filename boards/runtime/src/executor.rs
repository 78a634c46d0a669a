//! An embassy executor that sleeps with WFI.
//!
//! embassy's stock Cortex-M thread executor sleeps with WFE, which QEMU
//! treats as a no-op: the core spins, which under `-icount ...,sleep=off`
//! burns host time instead of jumping over idle time (one firmware second
//! took 28 s). This one polls the raw executor and, when no task was woken
//! meanwhile, executes WFI with interrupts masked (PRIMASK): a pending
//! interrupt still ends WFI, and its handler runs when interrupts are
//! unmasked again, so no wake-up can be lost between the check and the
//! sleep. Each sleep is timed on the board's clock, for its CPU meter.
//!
//! The flags are plain loads and stores (the M0 has no compare-and-swap),
//! with interrupts masked where it matters.

use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicBool, Ordering};

use embassy_executor::{raw, Spawner};

/// Set by the pender when a task is woken; cleared before each poll.
///
/// The board places it in a static of its own (`static PENDED: Pended =
/// Pended::new();`) and hands it to [`run`]: there its byte packs with the
/// board's other one-byte flags. A static of this crate's own, alone at the
/// end of the v1's `.bss`, measured 8 B more of the v1's tight RAM (statics
/// 4 192 B instead of 4 184, `cargo xtask check-microbit-v1`).
pub struct Pended(AtomicBool);

impl Pended {
    /// Not pended.
    pub const fn new() -> Self {
        Self(AtomicBool::new(false))
    }
}

impl Default for Pended {
    fn default() -> Self {
        Self::new()
    }
}

/// The pender embassy's raw executor calls (from any context) when a task
/// becomes ready, with the executor's context: [`run`]'s [`Pended`].
/// embassy-executor 0.10 links it by this symbol name (`platform-cortex-m`
/// defines its own only with `executor-thread` / `executor-interrupt`, which
/// the boards that link this do not enable).
#[unsafe(export_name = "__pender")]
fn pender(context: *mut ()) {
    // SAFETY: the only executor is `run`'s, whose context is a
    // `&'static Pended`.
    let pended = unsafe { &*(context as *const Pended) };
    pended.0.store(true, Ordering::SeqCst);
}

/// Runs the executor forever, `pended` its wake-up flag; `init` spawns the
/// first tasks.
///
/// Each sleep is timed: `now` is read just before and just after the WFI,
/// interrupts masked, and `slept(before, after)` is told. Not inlined, so
/// that nothing of the spawning stays on the stack below the tasks for good
/// (pass `init` as a plain function where the stack is tight).
///
/// # Safety
///
/// Call at most once (from `main`, which never returns): the executor lives
/// in a static that this call hands out as the only reference to it. The
/// check is the board's (a guard costs RAM the micro:bit v1 does not have).
#[inline(never)]
pub unsafe fn run<T>(
    pended: &'static Pended,
    init: impl FnOnce(Spawner),
    now: impl Fn() -> T,
    slept: impl Fn(T, T),
) -> ! {
    static mut EXECUTOR: MaybeUninit<raw::Executor> = MaybeUninit::uninit();
    // SAFETY: the caller calls this once: this is the only reference to
    // EXECUTOR ever made.
    let executor: &'static raw::Executor = unsafe {
        let slot = &mut *core::ptr::addr_of_mut!(EXECUTOR);
        slot.write(raw::Executor::new(pended as *const Pended as *mut ()))
    };
    init(executor.spawner());
    loop {
        pended.0.store(false, Ordering::SeqCst);
        // SAFETY: never re-entered: the pender only sets a flag.
        unsafe { executor.poll() };
        cortex_m::interrupt::disable();
        if !pended.0.load(Ordering::SeqCst) {
            let before = now();
            cortex_m::asm::wfi();
            let after = now();
            slept(before, after);
        }
        // SAFETY: re-enables the interrupts disabled just above.
        unsafe { cortex_m::interrupt::enable() };
    }
}
