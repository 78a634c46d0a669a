//! Board support: one submodule per firmware target, each behind its feature.
//!
//! The library is `#![forbid(unsafe_code)]`, so only the safe, host-testable
//! half of a board lives here (terminal rendering, arithmetic, argument
//! parsing). Register access, interrupt handlers and the executor loop live in
//! files that only the firmware binaries compile (for QEMU:
//! `src/board/qemu/hw.rs`, included by `src/bin/qemu.rs` with `#[path]`).

// The QEMU board's pure parts are compiled everywhere too (host tests); its
// virtual matrix needs the firmware dependencies (feature board-qemu).
pub mod qemu;
// The micro:bit v2 board module: pure (pin-free) code, compiled everywhere so
// that plain host `cargo test` covers it; its hardware half (hw.rs) is only
// compiled by `src/bin/microbit.rs` (feature board-microbit).
pub mod microbit;
