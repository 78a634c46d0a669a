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
//! Bare metal on purpose: no cortex-m-rt (its `link.x` would pick up the
//! repository's M4 `memory.x`, see `tools/m0/link.x`), no embassy, no defmt.
//! This file brings the vector table, the reset handler, semihosting output and
//! the instruction counter. Run by `cargo accuracy`; by hand:
//!
//! ```text
//! cargo run --release --target thumbv6m-none-eabi --features bench-m0 --bin bench_m0
//! ```
//!
//! (`.cargo/config.toml` gives the target its linker script and the runner
//! `tools/qemu-m0-run.sh`.) Options on the semihosting command line:
//! `--backends=MASK`, `--rates=MASK` as for `bench`.
//!
//! **The counter.** The nRF51 has no SysTick; its TIMER0 (0x4000_8000) runs at
//! 16 MHz / 2^PRESCALER. Under `-icount shift=7` each instruction advances
//! virtual time by 128 ns, so at prescaler 0 the timer gains 2.048 ticks per
//! instruction; the exact ratio is calibrated against two NOP loops of known
//! length (their difference cancels the call and read overhead), as on the M4.
#![no_std]
#![no_main]
#![allow(clippy::missing_safety_doc)]

use core::fmt::Write;

use marble_rolling::study::{bench_one, bench_plan, Scene, BACKENDS};

// ---------------------------------------------------------------------------
// Startup
// ---------------------------------------------------------------------------

unsafe extern "C" {
    static mut __m0_sdata: u32;
    static mut __m0_edata: u32;
    static __m0_sidata: u32;
    static mut __m0_sbss: u32;
    static mut __m0_ebss: u32;
}

/// Exceptions 1..=15 (the initial stack pointer, entry 0, is in the linker script).
#[unsafe(link_section = ".vector_table")]
#[unsafe(no_mangle)]
#[used]
pub static M0_VECTORS: [unsafe extern "C" fn() -> !; 15] = [
    m0_reset, fault, fault, fault, fault, fault, fault, fault, fault, fault, fault, fault, fault,
    fault, fault,
];

/// Reset: initialise `.data` and `.bss`, then run the benchmark.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn m0_reset() -> ! {
    // SAFETY: the linker script's symbols bound word-aligned regions of RAM and
    // flash; nothing has used RAM yet.
    unsafe {
        let mut src = core::ptr::addr_of!(__m0_sidata);
        let mut dst = core::ptr::addr_of_mut!(__m0_sdata);
        let end = core::ptr::addr_of_mut!(__m0_edata);
        while dst < end {
            dst.write_volatile(src.read_volatile());
            dst = dst.add(1);
            src = src.add(1);
        }
        let mut dst = core::ptr::addr_of_mut!(__m0_sbss);
        let end = core::ptr::addr_of_mut!(__m0_ebss);
        while dst < end {
            dst.write_volatile(0);
            dst = dst.add(1);
        }
    }
    core::sync::atomic::compiler_fence(core::sync::atomic::Ordering::SeqCst);
    main()
}

/// Any fault or unexpected exception: report and fail.
unsafe extern "C" fn fault() -> ! {
    semihosting::write0(b"FAULT: HardFault or unexpected exception\n\0");
    semihosting::exit(false)
}

// ---------------------------------------------------------------------------
// Semihosting (ARMv6-M: BKPT 0xAB)
// ---------------------------------------------------------------------------

mod semihosting {
    const SYS_WRITE0: u32 = 0x04;
    const SYS_GET_CMDLINE: u32 = 0x15;
    const SYS_EXIT: u32 = 0x18;
    const ADP_STOPPED_APPLICATION_EXIT: u32 = 0x20026;
    const ADP_STOPPED_RUN_TIME_ERROR: u32 = 0x20023;

    #[inline(always)]
    fn call(op: u32, arg: u32) -> u32 {
        let r: u32;
        // SAFETY: the semihosting trap; QEMU reads r0/r1 (and the memory r1
        // points to, which the callers keep alive) and writes r0.
        unsafe {
            core::arch::asm!("bkpt 0xab", inout("r0") op => r, in("r1") arg, options(nostack));
        }
        r
    }

    /// Writes a NUL-terminated byte string to the host's console.
    pub fn write0(s: &[u8]) {
        call(SYS_WRITE0, s.as_ptr() as u32);
    }

    /// Ends QEMU: exit status 0 for `ok`, 1 otherwise.
    pub fn exit(ok: bool) -> ! {
        let reason = if ok {
            ADP_STOPPED_APPLICATION_EXIT
        } else {
            ADP_STOPPED_RUN_TIME_ERROR
        };
        loop {
            call(SYS_EXIT, reason);
        }
    }

    /// The command line into `buf` (its length), or 0 if there is none.
    pub fn cmdline(buf: &mut [u8]) -> usize {
        let mut block = [buf.as_mut_ptr() as u32, buf.len() as u32];
        if call(SYS_GET_CMDLINE, block.as_mut_ptr() as u32) != 0 {
            return 0;
        }
        (block[1] as usize).min(buf.len())
    }
}

/// A line buffer printed with SYS_WRITE0.
struct Line {
    buf: [u8; 200],
    len: usize,
}

impl Line {
    fn new() -> Self {
        Line {
            buf: [0; 200],
            len: 0,
        }
    }
    fn flush(&mut self) {
        let n = self.len.min(self.buf.len() - 2);
        self.buf[n] = b'\n';
        self.buf[n + 1] = 0;
        semihosting::write0(&self.buf[..n + 2]);
        self.len = 0;
    }
}

impl Write for Line {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for &b in s.as_bytes() {
            if self.len + 2 < self.buf.len() {
                self.buf[self.len] = b;
                self.len += 1;
            }
        }
        Ok(())
    }
}

macro_rules! println {
    ($($arg:tt)*) => {{
        let mut line = Line::new();
        let _ = write!(line, $($arg)*);
        line.flush();
    }};
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

/// Runs `iterations` (≥ 1) of a loop of exactly 8 instructions.
#[inline(never)]
fn nop_loop(iterations: u32) {
    let iterations = iterations.max(1);
    // SAFETY: touches only the register it declares.
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

fn time<R>(f: impl FnOnce() -> R) -> (R, u32) {
    let before = timer::now();
    let r = f();
    (r, timer::now().wrapping_sub(before))
}

/// Calibration: `(instructions, ticks, overhead ticks)`.
fn calibrate() -> (u32, u32, u32) {
    const SHORT: u32 = 1_000;
    const LONG: u32 = 11_000;
    let (_, short) = time(|| nop_loop(SHORT));
    let (_, long) = time(|| nop_loop(LONG));
    let (_, overhead) = time(|| core::hint::black_box(()));
    (8 * (LONG - SHORT), long.wrapping_sub(short), overhead)
}

fn mask_option(cmdline: &str, name: &str, default: u32) -> u32 {
    for word in cmdline.split_ascii_whitespace() {
        if let Some(v) = word.strip_prefix(name).and_then(|v| v.strip_prefix('=')) {
            if let Ok(m) = v.parse::<u32>() {
                return m;
            }
        }
    }
    default
}

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

    let mut buf = [0u8; 128];
    let n = semihosting::cmdline(&mut buf);
    let cmdline = core::str::from_utf8(&buf[..n]).unwrap_or("");
    let backends = mask_option(cmdline, "--backends", (1 << BACKENDS.len()) - 1);
    let rates = mask_option(cmdline, "--rates", u32::MAX);

    bench_plan(backends, rates, |item| {
        let result = bench_one(&item, &mut |f| to_instructions(time(f).1));
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
    semihosting::exit(true)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    println!("panic: {}", info);
    semihosting::exit(false)
}
