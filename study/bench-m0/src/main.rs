//! Physics cost on a Cortex-M0: QEMU's `microbit` machine (nRF51822, ARMv6-M, no
//! FPU, no hardware divide), counted under `-icount shift=7,align=off,sleep=off`.
//!
//! The same measurements as the Cortex-M4F benchmark (`src/bin/bench.rs`): the
//! study's scenes ([`marble_rolling::study`]), one plain-text line per run on the
//! semihosting console:
//!
//! ```text
//! BENCH <scene> <backend> <variant> <step_log2> <steps> <instructions> <hash> <contacts> <collisions>
//! ```
//!
//! (`<step_log2>` 0 is event stepping, `study::EVENTS_LOG2`: a step per frame.)
//!
//! No embassy, no defmt: cortex-m-rt's startup with this crate's own memory
//! map (`memory.x`: the nRF51822's 256 KiB flash and 16 KiB RAM), and the
//! `semihosting` crate for the console, the command line and the exit status.
//! Run by `cargo accuracy`; by hand: `cargo xtask bench-m0 [--backends=MASK]
//! [--rates=MASK]` (options as for `bench`).
//!
//! **The counter.** The nRF51 has no SysTick; its TIMER0 (0x4000_8000) runs at
//! 16 MHz / 2^PRESCALER. Under `-icount shift=7` each instruction advances
//! virtual time by 128 ns, so at prescaler 0 the timer gains 2.048 ticks per
//! instruction; the exact ratio is calibrated against two NOP loops of known
//! length (their difference cancels the call and read overhead), as on the M4.
#![no_std]
#![no_main]

use cortex_m_rt::{entry, exception, ExceptionFrame};
use marble_board_runtime::args::number_option as mask_option;
use marble_board_runtime::nop::{time_nop_loops, Stopwatch};
use marble_rolling::study::{bench_one_in, bench_plan, Scene, BACKENDS};

/// The backends this benchmark is built with (bit `n` for `BACKENDS[n]`): with
/// event stepping the code of all six does not fit the nRF51's 256 KiB of flash
/// (170 KB over), so the M0 measures i8f24 (the firmware's), i16f16 and f32.
const M0_BACKENDS: u32 = 0b00_1011;
use semihosting::println;

#[exception]
unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
    println!("FAULT: HardFault");
    semihosting::process::exit(1)
}

#[exception]
unsafe fn DefaultHandler(irq: i16) {
    println!("FAULT: unexpected exception {}", irq);
    semihosting::process::exit(1)
}

// ---------------------------------------------------------------------------
// nRF51 TIMER0 as the instruction counter
// ---------------------------------------------------------------------------

mod timer {
    const BASE: usize = 0x4000_8000;
    const TASKS_START: usize = BASE;
    const TASKS_STOP: usize = BASE + 0x004;
    const TASKS_CLEAR: usize = BASE + 0x00C;
    const TASKS_CAPTURE0: usize = BASE + 0x040;
    const MODE: usize = BASE + 0x504;
    const BITMODE: usize = BASE + 0x508;
    const PRESCALER: usize = BASE + 0x510;
    const CC0: usize = BASE + 0x540;

    #[inline(always)]
    fn write(addr: usize, v: u32) {
        // SAFETY: TIMER0 registers of the nRF51.
        unsafe { core::ptr::write_volatile(addr as *mut u32, v) }
    }

    /// Free-running 32-bit timer at 16 MHz.
    pub fn start() {
        write(TASKS_STOP, 1);
        write(MODE, 0);
        write(BITMODE, 3);
        write(PRESCALER, 0);
        write(TASKS_CLEAR, 1);
        write(TASKS_START, 1);
    }

    /// The counter (captured into CC[0]).
    #[inline(always)]
    pub fn now() -> u32 {
        write(TASKS_CAPTURE0, 1);
        // SAFETY: as above.
        unsafe { core::ptr::read_volatile(CC0 as *const u32) }
    }
}

fn time<R>(f: impl FnOnce() -> R) -> (R, u32) {
    let before = timer::now();
    let r = f();
    (r, timer::now().wrapping_sub(before))
}

/// TIMER0 as the runtime's stopwatch, for the NOP loops' calibration.
struct Timer0;

impl Stopwatch for Timer0 {
    fn time(&self, f: impl FnOnce()) -> u32 {
        time(f).1
    }
}

/// Calibration: `(instructions, ticks, overhead ticks)`, from the NOP loops
/// the boards' CPU meters use (`marble_board_runtime::nop`).
fn calibrate() -> (u32, u32, u32) {
    let t = time_nop_loops(&Timer0);
    (t.instructions, t.ticks, t.overhead_ticks)
}

#[entry]
fn main() -> ! {
    timer::start();
    let (cal_instr, cal_ticks, overhead) = calibrate();
    println!(
        "CALIBRATION {} {} {} {}",
        cal_instr,
        cal_ticks,
        cal_ticks as u64 * 1000 / cal_instr as u64,
        overhead
    );
    let to_instructions = |ticks: u32| -> u64 {
        let net = ticks.saturating_sub(overhead) as u64;
        (net * cal_instr as u64 + cal_ticks as u64 / 2) / (cal_ticks as u64).max(1)
    };
    let (_, empty) = time(|| core::hint::black_box(0u32));
    println!("EMPTY {}", to_instructions(empty));

    let backends = mask_option("--backends", M0_BACKENDS) & M0_BACKENDS;
    let rates = mask_option("--rates", u32::MAX);

    bench_plan(backends, rates, |item| {
        let result = bench_one_in::<M0_BACKENDS>(&item, &mut |f| to_instructions(time(f).1));
        match result {
            Some(r) => println!(
                "BENCH {} {} {} {} {} {} {} {} {}",
                Scene::get(item.scene).name,
                BACKENDS[item.backend],
                item.variant_name(),
                item.step_log2,
                r.steps,
                r.instructions,
                r.hash,
                r.contacts,
                r.collisions
            ),
            None => println!(
                "ERROR setup failed: {} {}",
                Scene::get(item.scene).name,
                BACKENDS[item.backend]
            ),
        }
    });
    println!("DONE");
    semihosting::process::exit(0)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    println!("panic: {}", info);
    semihosting::process::exit(1)
}
