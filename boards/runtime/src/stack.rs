//! Stack painting. The firmware links through flip-link
//! (`.cargo/config.toml`): the statics sit at the top of RAM and the stack
//! below them (`_stack_start`, the initial SP), growing down towards the
//! board's RAM base, so an overflow faults instead of overwriting them.
//! [`paint`] fills the free stack at boot, [`high_water`] finds the deepest
//! word overwritten since. The board names its RAM base and the pattern.

/// Bytes below the SP left unpainted: room for anything below the stack
/// pointer at the time (none is expected: interrupts are off and the loop
/// calls nothing).
const RED_ZONE: usize = 64;

extern "C" {
    /// The initial stack pointer (cortex-m-rt's `link.x`, set by flip-link).
    static _stack_start: u32;
}

/// The top of the stack (the initial SP, just below the statics).
pub fn top() -> usize {
    // Only the symbol's address is taken, never its value.
    core::ptr::addr_of!(_stack_start) as usize
}

/// Paints the stack with `pattern` from `bottom` (the start of RAM) up to a
/// little below the current SP. Call first thing in `main`.
#[inline(never)]
pub fn paint(bottom: usize, pattern: u32) {
    cortex_m::interrupt::free(|_| {
        let sp = cortex_m::register::msp::read() as usize;
        let end = sp.saturating_sub(RED_ZONE) & !3;
        let mut addr = bottom;
        while addr < end {
            // SAFETY: [bottom, SP - RED_ZONE) is free stack: RAM that nothing
            // uses yet (flip-link puts every static above it).
            unsafe { core::ptr::write_volatile(addr as *mut u32, pattern) };
            addr += 4;
        }
    });
}

/// Stack use so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StackUse {
    /// Deepest use, bytes (from the top down to the lowest overwritten word).
    pub used: usize,
    /// The whole stack region (below the statics), bytes.
    pub size: usize,
}

/// The high-water mark since [`paint`] with the same `bottom` and `pattern`.
pub fn high_water(bottom: usize, pattern: u32) -> StackUse {
    let top = top();
    let mut addr = bottom;
    // SAFETY: word reads of stack RAM from its start to the stack top (still
    // painted, or left by finished calls), word-aligned.
    while addr < top && unsafe { core::ptr::read_volatile(addr as *const u32) } == pattern {
        addr += 4;
    }
    StackUse {
        used: top.saturating_sub(addr),
        size: top.saturating_sub(bottom),
    }
}
