//! The runtime the firmware crates share: what QEMU's mps2-an386 board
//! (`marble-qemu`), the micro:bit v1 (`marble-microbit-v1`) and the micro:bit
//! v2 (`marble-microbit`) would otherwise each copy, and what the two
//! benchmarks (`marble-qemu`'s `bench`, the Cortex-M0's `marble-bench-m0`)
//! share with them: the NOP loop's calibration and the command line's
//! options. Board-agnostic Cortex-M code only: the registers, pins, clocks, time drivers and memory maps stay
//! in each board's crate, which hands this one its clock where one is needed.
//!
//! * `executor` (feature `wfi-executor`): the embassy raw executor that
//!   sleeps with WFI, and its pender (QEMU and the v1; the v2 runs embassy's
//!   stock executors, which bring their own pender);
//! * [`nop`]: the NOP loop of known length and its timing, the CPU meters'
//!   calibration (QEMU and the v1);
//! * [`stack`]: stack painting and the high-water mark (QEMU and the v1);
//! * [`heartbeat`]: a future that beats each time it is polled (the two
//!   micro:bits' watchdog rule for the game task);
//! * `args` (feature `args`): the benchmarks' numeric options on the
//!   semihosting command line (QEMU's Cortex-M4F and Cortex-M0 benchmarks);
//! * `build.rs`: the three firmware crates' build script.
//!
//! A crate of its own, not a module of the core: it needs `unsafe` (inline
//! assembly, exported symbols, raw stack reads), which the core forbids.
#![no_std]
#![cfg(target_os = "none")]

#[cfg(feature = "args")]
pub mod args;
#[cfg(feature = "wfi-executor")]
pub mod executor;
pub mod heartbeat;
pub mod nop;
pub mod stack;
