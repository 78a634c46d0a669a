//! QEMU `mps2-an386` board (Cortex-M4F, 25 MHz): the safe half.
//!
//! This part is plain, host-testable code: memory map constants, the
//! firmware's command-line options, the CPU-load arithmetic
//! ([`cpu_meter`]), the virtual LED matrix that integrates the scanned frames
//! (`virtual_matrix`, with feature `app` only: it needs embassy) and the ANSI
//! terminal screen that shows them with the game's status (`terminal`), and
//! the virtual accelerometer the firmware reads its tilt from:
//! a [`virtual_lsm303agr`](crate::board::virtual_lsm303agr) (shared with the
//! v1's virtual bus) on a [`virtual_i2c`] bus that behaves like the
//! micro:bit's TWIM, driven by the terminal's keys ([`fault_keys`]) or the
//! fault script; and the records' flash, a RAM image with NOR rules
//! (`ram_flash`, feature `records`). The register-level half (UART and TIMER0 drivers, the WFI
//! executor, interrupt handlers, the time driver, semihosting exit) is the
//! firmware crate `boards/qemu`; it needs `unsafe`, which this library
//! forbids. `cargo qemu` (xtask) builds it and runs it in qemu-system-arm.

pub mod cpu_meter;
pub mod fault_keys;
#[cfg(feature = "records")]
pub mod ram_flash;
pub mod virtual_i2c;
#[cfg(feature = "app")]
pub mod terminal;
#[cfg(feature = "app")]
pub mod virtual_matrix;

use crate::board::{accel_link, game_sizes};
use crate::game::endless::Reach;
use crate::input::accel_timing;
use crate::input::sensor::{AxisMap, SupervisorConfig};
use crate::input::tilt::TiltConfig;
use virtual_i2c::RamRange;

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
pub(crate) const ICOUNT_SHIFT: u32 = 7;

/// Start of RAM (memory.x): with flip-link the stack grows down towards it.
pub const RAM_BASE: usize = 0x2000_0000;
/// One past the end of RAM (memory.x: 128 KiB).
pub(crate) const RAM_END: usize = 0x2002_0000;
/// RAM for the virtual TWIM's DMA rule: what its DMA could reach.
pub const QEMU_RAM: RamRange = RamRange {
    start: RAM_BASE,
    end: RAM_END,
};

// The virtual accelerometer is a micro:bit's: the same axis table, polling,
// rate and supervision, so the QEMU board runs the micro:bit's input stack.

/// The axis table the QEMU board's input reads through: the micro:bit's
/// [`AXIS_MAP`](crate::board::accel_link::AXIS_MAP). The virtual chip has its own
/// placement ([`MICROBIT_V2`](crate::board::virtual_lsm303agr::MICROBIT_V2)), so
/// a sign error here shows.
pub const SENSOR_AXIS_MAP: AxisMap = accel_link::AXIS_MAP;
/// Sensor polling period, ms (the micro:bit's).
pub const INPUT_PERIOD_MS: u64 = accel_link::INPUT_PERIOD_MS;
/// Accelerometer output data rate, Hz (the micro:bit's).
pub const ACCEL_ODR_HZ: u32 = accel_timing::ACCEL_ODR_HZ;
/// Wait after (re)configuring the accelerometer, ms (the micro:bit's).
pub const ACCEL_SETTLE_MS: u64 = accel_timing::ACCEL_SETTLE_MS;
/// Fault supervision (the micro:bit's).
pub const SUPERVISOR: SupervisorConfig = accel_link::SUPERVISOR;
/// The game's tilt path for what the virtual chip reads: its samples come
/// judged by the supervision ([`TiltConfig::SENSOR`]), and no stuck check, since
/// the keys tilt the chip and a held key repeats the same reading.
pub const PLAY_TILT: TiltConfig = TiltConfig {
    stuck_samples: 0,
    ..TiltConfig::SENSOR
};
/// The longest one I²C transfer may take before it counts as a hung bus,
/// ms (the micro:bit's [`I2C_TIMEOUT_MS`](accel_link::I2C_TIMEOUT_MS)).
pub const TRANSFER_TIMEOUT_MS: u64 = accel_link::I2C_TIMEOUT_MS;
/// The virtual TWIM's copy buffer for write buffers outside RAM, bytes (the
/// micro:bit's [`TWIM_COPY_BUFFER_BYTES`](accel_link::TWIM_COPY_BUFFER_BYTES)).
pub const DEFAULT_COPY_BUFFER: usize = accel_link::TWIM_COPY_BUFFER_BYTES;
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
///
/// `--fault-script` runs the headless fault script instead of the demo (the
/// virtual accelerometer's faults against the game's pause and resume);
/// `--no-copy-buffer` (or `--twim-copy-buffer=N`, bytes) sets the virtual
/// TWIM's copy buffer for write buffers outside RAM (default
/// [`DEFAULT_COPY_BUFFER`]; 0: none, so a write from flash is refused: the
/// TWIM's DMA cannot read flash).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Options {
    /// Play on the UART terminal (else run the headless demo or script).
    pub interactive: bool,
    /// Run the fault script (headless).
    pub fault_script: bool,
    /// The virtual TWIM's copy buffer, bytes.
    pub twim_copy_buffer: usize,
    /// Keep best times (`--records`): always when interactive; in the demo, the
    /// records check (the autopilot's wins offered as records, so that two
    /// runs show the records written, saved and read back).
    pub records: bool,
    /// Keep and race each level's best run (`--ghosts`): always when
    /// interactive; in the demo, the ghosts check (the autopilot's wins kept
    /// as ghosts, so that the next run races them to their hashes).
    pub ghosts: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            interactive: false,
            fault_script: false,
            twim_copy_buffer: DEFAULT_COPY_BUFFER,
            records: false,
            ghosts: false,
        }
    }
}

impl Options {
    /// Parses the command-line words (the first, the program name, included
    /// or not: unknown words, and a malformed copy buffer size, are ignored).
    /// `--demo` and `--fault-script` force headless.
    pub fn parse<'a>(args: impl IntoIterator<Item = &'a str>) -> Options {
        let mut options = Options::default();
        let mut headless = false;
        for arg in args {
            match arg {
                "--interactive" => options.interactive = true,
                "--headless" => options.interactive = false,
                "--demo" => headless = true,
                "--fault-script" => {
                    options.fault_script = true;
                    headless = true;
                }
                "--no-copy-buffer" => options.twim_copy_buffer = 0,
                "--records" => options.records = true,
                "--ghosts" => options.ghosts = true,
                _ => {
                    if let Some(Ok(bytes)) = arg
                        .strip_prefix("--twim-copy-buffer=")
                        .map(str::parse::<usize>)
                    {
                        options.twim_copy_buffer = bytes;
                    }
                }
            }
        }
        if headless {
            options.interactive = false;
        }
        options.records |= options.interactive && !options.fault_script;
        options.ghosts |= options.interactive && !options.fault_script;
        options
    }
}

/// The largest generated maze the endless run plays here: the micro:bit v2's
/// ([`game_sizes`]), so that the v2's maze code runs in QEMU, where its stack
/// is measured. The virtual matrix follows the marble and the storey maps show
/// a window of a maze too wide for the terminal.
pub const MAZE_REACH: Reach = game_sizes::MAZE_REACH;

/// The ghosts' region, bytes, in a RAM image of a flash: the micro:bit v2's
/// ([`game_sizes`]).
pub const GHOSTS_BYTES: usize = game_sizes::GHOSTS_BYTES;

/// The longest run kept as a ghost, bytes: the micro:bit v2's
/// ([`game_sizes`]), so that QEMU keeps and drops the runs the v2 does.
pub const GHOST_BYTES: usize = game_sizes::GHOST_BYTES;
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options() {
        assert!(!Options::parse([]).interactive);
        assert!(Options::parse(["qemu", "--interactive"]).interactive);
        assert!(!Options::parse(["qemu", "--interactive", "--demo"]).interactive);
        assert!(!Options::parse(["--headless", "--whatever"]).interactive);
        let script = Options::parse(["qemu", "--interactive", "--fault-script"]);
        assert!(script.fault_script && !script.interactive);
        assert_eq!(script.twim_copy_buffer, DEFAULT_COPY_BUFFER);
        assert_eq!(
            Options::parse(["--fault-script", "--no-copy-buffer"]).twim_copy_buffer,
            0
        );
        assert_eq!(Options::parse(["--twim-copy-buffer=0"]).twim_copy_buffer, 0);
        assert!(Options::parse(["--interactive"]).records);
        assert!(!Options::parse(["--demo"]).records);
        assert!(Options::parse(["--demo", "--records"]).records);
        assert!(Options::parse(["--interactive"]).ghosts);
        assert!(!Options::parse(["--demo", "--records"]).ghosts);
        assert!(Options::parse(["--demo", "--ghosts"]).ghosts);
        assert_eq!(Options::parse(["--twim-copy-buffer=3"]).twim_copy_buffer, 3);
        assert_eq!(
            Options::parse(["--twim-copy-buffer=x"]).twim_copy_buffer,
            DEFAULT_COPY_BUFFER
        );
        assert!(!Options::parse(["--demo"]).fault_script);
    }
}
