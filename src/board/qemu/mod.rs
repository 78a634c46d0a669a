//! QEMU `mps2-an386` board (Cortex-M4F, 25 MHz): the safe half.
//!
//! This part is plain, host-testable code: memory map constants, the
//! firmware's command-line options, the CPU-load arithmetic
//! ([`cpu_meter`]) and the virtual LED matrix that shows the scanned frames on
//! an ANSI terminal (`virtual_matrix`, with feature `app` only: it needs
//! embassy). The register-level half (UART and TIMER0 drivers, the WFI
//! executor, interrupt handlers, the time driver, semihosting exit) is the
//! firmware crate `boards/qemu`; it needs `unsafe`, which this library
//! forbids. `cargo qemu` (xtask) builds it and runs it in qemu-system-arm.

pub mod cpu_meter;
#[cfg(feature = "app")]
pub mod virtual_matrix;

/// Virtual matrix width in pixels: as wide as the widest built-in maze
/// (`grand-tour`, 19 tiles), so no built-in level scrolls.
pub const WIDTH: usize = 19;
/// Virtual matrix height in pixels (the tallest built-in maze has 9 rows).
pub const HEIGHT: usize = 9;

/// Core (and APB peripheral) clock of QEMU's mps2-an386, Hz.
pub const SYSCLK_HZ: u32 = 25_000_000;
/// CMSDK APB UART0 base address.
pub const UART0_BASE: usize = 0x4000_4000;
/// UART0 receive interrupt number.
pub const UART0_RX_IRQ: u16 = 0;
/// UART0 transmit interrupt number.
pub const UART0_TX_IRQ: u16 = 1;
/// CMSDK APB TIMER0 base address.
pub const TIMER0_BASE: usize = 0x4000_0000;
/// TIMER0 interrupt number.
pub const TIMER0_IRQ: u16 = 8;
/// The `-icount shift=N` the runner uses for headless runs: every
/// instruction advances virtual time by `2^N` ns.
pub const ICOUNT_SHIFT: u32 = 7;

/// Start of RAM (memory.x): with flip-link the stack grows down towards it.
pub const RAM_BASE: usize = 0x2000_0000;
/// The word the firmware paints its free stack with at boot, to measure the
/// stack's high-water mark at the end of the demo.
pub const STACK_PAINT: u32 = 0x5ac4_5ac4;

/// How the firmware was started, from its semihosting command line.
///
/// The runner (`cargo qemu`, xtask) always passes exactly one of
/// `--interactive` (UART on the user's terminal, real-time clock) or
/// `--headless` (UART discarded, `-icount shift=7,align=off,sleep=off`,
/// deterministic), followed by the user's own arguments. When neither is
/// present (e.g. QEMU started by hand without `-semihosting-config arg=...`)
/// the firmware assumes headless: the demo needs no input and always ends,
/// whereas an interactive game with nobody at the UART would never quit.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Options {
    /// Play on the UART terminal (else run the headless demo).
    pub interactive: bool,
}

impl Options {
    /// Parses the command-line words (the first, the program name, included
    /// or not: unknown words are ignored). `--demo` forces headless.
    pub fn parse<'a>(args: impl IntoIterator<Item = &'a str>) -> Options {
        let mut options = Options::default();
        let mut demo = false;
        for arg in args {
            match arg {
                "--interactive" => options.interactive = true,
                "--headless" => options.interactive = false,
                "--demo" => demo = true,
                _ => {}
            }
        }
        if demo {
            options.interactive = false;
        }
        options
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options() {
        assert!(!Options::parse([]).interactive);
        assert!(Options::parse(["qemu", "--interactive"]).interactive);
        assert!(!Options::parse(["qemu", "--interactive", "--demo"]).interactive);
        assert!(!Options::parse(["--headless", "--whatever"]).interactive);
    }
}
