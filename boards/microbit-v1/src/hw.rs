//! The nRF51822's register-level half: emulation detection, the clock and
//! embassy time driver on TIMER0, the CPU meter, stack painting, the WFI
//! executor (these two and the NOP loop are `marble_board_runtime`'s, on this
//! board's clock and RAM), semihosting (QEMU only), and the fault and panic
//! handlers.
//!
//! # Time: TIMER0 on hardware too (one code path)
//!
//! embassy-nrf's time driver counts RTC1 ticks. QEMU's `microbit` machine
//! (7.2) has no RTC (its registers read 0), so under emulation that clock
//! never advances; its TIMERs are emulated (16 MHz, prescaler, compare
//! interrupts, capture). This driver uses TIMER0 at 1 MHz (prescaler 4,
//! 32 bits, extended to 64 bits in software) everywhere — in QEMU and on the
//! board. The alternative, RTC on hardware and TIMER in QEMU, would let the
//! board sleep with only the 32 kHz clock running; the TIMER keeps the
//! 16 MHz clock (HFCLK) requested while the CPU sleeps, a fraction of a
//! milliampere by the nRF51822 product specification's current tables (not
//! measured here). We pay it, because:
//!
//! * the LED matrix never sleeps: it is scanned with BCM at 4.5 kHz
//!   (TIMER1, `display.rs`), so HFCLK runs most of the time anyway, and the
//!   LEDs themselves draw milliamperes;
//! * the 32 768 Hz RTC cannot place BCM slices of 222 µs exactly (6.8 RTC
//!   ticks), the 1 MHz TIMER can;
//! * one code path: the time driver that QEMU verifies in CI (the demo's
//!   frame pacing, the GPIO check of the display timing) is the one the board
//!   runs. A second, RTC-based driver would only ever be tested on a board.
//!
//! # QEMU or a board?
//!
//! The same ELF runs in both. At boot [`detect_emulation`] starts the
//! low-frequency clock and RTC0 and waits 2 ms on TIMER0: a real RTC has
//! counted ~65 ticks, QEMU's reads 0. Under emulation the firmware uses
//! semihosting (command line, defmt log, exit status); on a board it never
//! executes a semihosting call (a `BKPT` without a debugger would fault) and
//! logs over RTT (`log.rs`).
//!
//! # Why no embassy-nrf
//!
//! Its nRF51 support has no UART or TWI driver and its time driver is the
//! RTC's; the GPIO and TIMER writes this board needs are a few registers,
//! written through `nrf-pac` (the PAC embassy-nrf itself uses).

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::Waker;

use cortex_m::peripheral::NVIC;
use cortex_m_rt::{exception, ExceptionFrame};
use critical_section::Mutex;
use embassy_time_queue_utils::Queue;
use marble_rolling::board::microbit_v1::Options;
use nrf_pac as pac;
use pac::Interrupt;

/// Whether we run in QEMU (set once by [`detect_emulation`]).
static EMULATED: AtomicBool = AtomicBool::new(false);

/// Whether the firmware runs in QEMU (see the module doc).
pub fn emulated() -> bool {
    EMULATED.load(Ordering::Relaxed)
}

/// NVIC priorities (the M0 has four levels, in the top two bits): the
/// display's TIMER1 above everything else, so that no other interrupt
/// stretches a BCM slice.
const PRIORITY_DISPLAY: u8 = 0x40;
/// TIMER0 (time driver) and the rest.
const PRIORITY_TIMER: u8 = 0x80;

/// Sets `irq`'s priority and unmasks it.
pub fn enable_irq(irq: Interrupt, display: bool) {
    // SAFETY: priorities and masks are set once at boot, before the
    // executor runs; the handlers are defined in this crate.
    unsafe {
        let mut nvic = cortex_m::Peripherals::steal().NVIC;
        nvic.set_priority(
            irq,
            if display {
                PRIORITY_DISPLAY
            } else {
                PRIORITY_TIMER
            },
        );
        NVIC::unpend(irq);
        NVIC::unmask(irq);
    }
}

/// Finds out whether the RTC runs (a board) or not (QEMU), see the module
/// doc. Call after [`clock::start`], before anything logs.
pub fn detect_emulation() -> bool {
    let clock = pac::CLOCK;
    // The low-frequency clock from its RC oscillator (the v1 has no 32 kHz
    // crystal).
    clock.lfclksrc().write_value(pac::clock::regs::Lfclksrc(0));
    clock.events_lfclkstarted().write_value(0);
    clock.tasks_lfclkstart().write_value(1);
    let start = clock::now();
    while clock.events_lfclkstarted().read() == 0 && clock::now() - start < 5_000 {}
    let rtc = pac::RTC0;
    rtc.prescaler().write_value(pac::rtc::regs::Prescaler(0));
    rtc.tasks_clear().write_value(1);
    rtc.tasks_start().write_value(1);
    let start = clock::now();
    while clock::now() - start < 2_000 {}
    let counted = rtc.counter().read().0 & 0x00ff_ffff;
    rtc.tasks_stop().write_value(1);
    rtc.tasks_clear().write_value(1);
    clock.tasks_lfclkstop().write_value(1);
    let emulated = counted == 0;
    EMULATED.store(emulated, Ordering::Relaxed);
    emulated
}

/// Ends the run: under QEMU, exits with `code` (semihosting
/// SYS_EXIT_EXTENDED); on a board, stops here (a debugger sees the core
/// spin in WFI).
pub fn exit(code: i32) -> ! {
    cortex_m::interrupt::disable();
    if emulated() {
        semihosting::process::exit(code)
    }
    loop {
        cortex_m::asm::wfi();
    }
}

/// Logs `what` and ends the run with a failure status.
pub fn fatal(what: &str) -> ! {
    defmt::error!("fatal: {=str}", what);
    exit(1)
}

/// The firmware's options: the semihosting command line under QEMU,
/// defaults (play) on a board.
pub fn options() -> Options {
    if !emulated() {
        return Options::default();
    }
    match semihosting::experimental::env::args::<256>() {
        Ok(args) => Options::parse((&args).filter_map(Result::ok)),
        Err(_) => Options::default(),
    }
}

/// Logs the panic's location once and ends the run (status 101 under QEMU). On a board
/// with probe-rs attached the log shows over RTT; without one the core
/// stops in [`exit`].
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    static PANICKED: AtomicBool = AtomicBool::new(false);
    cortex_m::interrupt::disable();
    // Load and store, not swap: the M0 has no atomic read-modify-write
    // (interrupts are off, so nothing can run in between).
    if !PANICKED.load(Ordering::Relaxed) {
        PANICKED.store(true, Ordering::Relaxed);
        // Where, not why: the message would need `core::fmt` (about 3 KB of
        // flash this board does not have); the location finds the `panic!`.
        match info.location() {
            Some(at) => defmt::error!("panic at {=str}:{=u32}", at.file(), at.line()),
            None => defmt::error!("panic"),
        }
    }
    exit(101)
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    defmt::error!(
        "HardFault: pc {=u32:#010x} lr {=u32:#010x}",
        frame.pc(),
        frame.lr()
    );
    exit(1)
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    defmt::error!("unexpected interrupt or exception {}", irqn);
    exit(1)
}

// ---------------------------------------------------------------------------
// Clock: TIMER0, 1 MHz, 32 bits, extended to 64
// ---------------------------------------------------------------------------

/// TIMER0 as the board's free-running 1 MHz clock.
///
/// CC\[0\] is the time driver's alarm, CC\[1\] and CC\[2\] compare at 0 and
/// at 2³¹ so that the clock is read (and extended) at least twice per
/// 32-bit wrap (71.6 minutes) whatever else runs, CC\[3\] takes the
/// captures that read the counter. Every capture is also a line of QEMU's
/// `nrf51_timer_set_count` trace: the xtask's clock for the GPIO trace.
pub mod clock {
    use core::cell::Cell;

    use critical_section::Mutex;
    use marble_rolling::board::microbit_v1::TIMER_PRESCALER;
    use nrf_pac as pac;

    /// The capture register.
    const CAPTURE: usize = 3;

    /// Counter value at the last read, and the wraps counted up to it.
    static STATE: Mutex<Cell<(u32, u32)>> = Mutex::new(Cell::new((0, 0)));

    /// Starts TIMER0 from 0, 1 MHz, 32 bits, no interrupt yet.
    pub fn start() {
        let timer = pac::TIMER0;
        timer.tasks_stop().write_value(1);
        timer.mode().write_value(pac::timer::regs::Mode(0));
        timer.bitmode().write_value(pac::timer::regs::Bitmode(3));
        timer
            .prescaler()
            .write_value(pac::timer::regs::Prescaler(u32::from(TIMER_PRESCALER)));
        timer.cc(1).write_value(0);
        timer.cc(2).write_value(1 << 31);
        timer.tasks_clear().write_value(1);
        timer.tasks_start().write_value(1);
    }

    /// The raw 32-bit counter (a capture).
    #[inline(always)]
    fn raw() -> u32 {
        let timer = pac::TIMER0;
        timer.tasks_capture(CAPTURE).write_value(1);
        timer.cc(CAPTURE).read()
    }

    /// µs since [`start`].
    pub fn now() -> u64 {
        critical_section::with(|cs| {
            let state = STATE.borrow(cs);
            let (last, wraps) = state.get();
            let raw = raw();
            let wraps = if raw < last {
                wraps.wrapping_add(1)
            } else {
                wraps
            };
            state.set((raw, wraps));
            (u64::from(wraps) << 32) | u64::from(raw)
        })
    }
}

/// The embassy time driver: [`clock`] for `now()`, TIMER0's compare 0 for
/// wake-ups, the timer queue from `embassy-time-queue-utils`.
struct Driver {
    /// Timer queue and its earliest deadline (µs).
    queue: Mutex<RefCell<(Queue, u64)>>,
}

impl embassy_time_driver::Driver for Driver {
    fn now(&self) -> u64 {
        clock::now()
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        critical_section::with(|cs| {
            let mut state = self.queue.borrow(cs).borrow_mut();
            let (queue, next) = &mut *state;
            if queue.schedule_wake(at, waker) && at < *next {
                *next = at;
                arm(at);
            }
        });
    }
}

embassy_time_driver::time_driver_impl!(static DRIVER: Driver = Driver {
    queue: Mutex::new(RefCell::new((Queue::new(), u64::MAX))),
});

/// Sets the alarm (CC\[0\]) for `at`, or fires it at once when `at` has
/// passed; an alarm more than 2³¹ µs away is left to the half-wrap
/// interrupts, which re-arm it in time. Called with interrupts disabled.
fn arm(at: u64) {
    let timer = pac::TIMER0;
    if at == u64::MAX {
        timer.intenclr().write_value(pac::timer::regs::Int(1 << 16));
        return;
    }
    let now = clock::now();
    if at <= now {
        NVIC::pend(Interrupt::TIMER0);
        return;
    }
    if at - now >= 1 << 31 {
        timer.intenclr().write_value(pac::timer::regs::Int(1 << 16));
        return;
    }
    timer.events_compare(0).write_value(0);
    timer.cc(0).write_value(at as u32);
    timer.intenset().write_value(pac::timer::regs::Int(1 << 16));
    // A compare only fires when the counter *becomes* CC: if it got there
    // while we wrote it, fire now.
    if clock::now() >= at {
        NVIC::pend(Interrupt::TIMER0);
    }
}

/// Starts the clock and its interrupt (compare 0: alarm, 1 and 2: the
/// half-wrap reads).
pub fn start_time() {
    clock::start();
    pac::TIMER0
        .intenset()
        .write_value(pac::timer::regs::Int((1 << 17) | (1 << 18)));
    enable_irq(Interrupt::TIMER0, false);
}

#[unsafe(no_mangle)]
extern "C" fn TIMER0() {
    let timer = pac::TIMER0;
    for n in 0..3 {
        if timer.events_compare(n).read() != 0 {
            timer.events_compare(n).write_value(0);
        }
    }
    critical_section::with(|cs| {
        let now = clock::now();
        let mut state = DRIVER.queue.borrow(cs).borrow_mut();
        let (queue, next) = &mut *state;
        if now >= *next {
            *next = queue.next_expiration(now);
        }
        arm(*next);
    });
}

// ---------------------------------------------------------------------------
// CPU meter
// ---------------------------------------------------------------------------

/// Busy time, i.e. executed instructions under `-icount`, from the 1 MHz
/// [`clock`] and the WFI sleeps the [`executor`] reports (see
/// `marble_rolling::board::microbit_v1::LoadReport`).
pub mod cpu_meter {
    use core::cell::Cell;

    use critical_section::Mutex;
    use marble_board_runtime::nop::{self, Stopwatch};
    use marble_rolling::board::microbit_v1::{Calibration, Sample};

    use super::clock;

    /// µs spent in WFI since the clock started.
    static IDLE: Mutex<Cell<u64>> = Mutex::new(Cell::new(0));
    static CALIBRATION: Mutex<Cell<Calibration>> = Mutex::new(Cell::new(Calibration::NOMINAL));

    /// Records a WFI sleep from `before` to `after` (µs).
    pub fn record_sleep(before: u64, after: u64) {
        critical_section::with(|cs| {
            let idle = IDLE.borrow(cs);
            idle.set(idle.get() + after.saturating_sub(before));
        });
    }

    /// Total and idle µs so far.
    pub fn sample() -> Sample {
        critical_section::with(|cs| Sample {
            total_us: clock::now(),
            idle_us: IDLE.borrow(cs).get(),
        })
    }

    /// The clock as the runtime's stopwatch: µs, interrupts off.
    struct Micros;

    impl Stopwatch for Micros {
        fn time(&self, f: impl FnOnce()) -> u32 {
            critical_section::with(|_| {
                let before = clock::now();
                f();
                (clock::now() - before) as u32
            })
        }
    }

    /// Measures µs per instruction with the runtime's two NOP loops
    /// (`marble_board_runtime::nop`: their difference, 80 000 instructions,
    /// cancels the call and clock-read overhead), as `study/bench-m0` does.
    /// Stores and returns it.
    pub fn calibrate() -> Calibration {
        let timing = nop::time_nop_loops(&Micros);
        let calibration = Calibration {
            instructions: timing.instructions,
            us: timing.ticks,
            overhead_us: timing.overhead_ticks,
        };
        critical_section::with(|cs| CALIBRATION.borrow(cs).set(calibration));
        calibration
    }

    /// `f`'s result and the instructions it took (interrupts off; the
    /// timing's own overhead removed; resolution one µs, 7.8 instructions
    /// under `-icount shift=7`). The profile build's only.
    #[cfg(feature = "profile")]
    pub fn count_instructions<R>(f: impl FnOnce() -> R) -> (R, u64) {
        let calibration = calibration();
        let (out, us) = critical_section::with(|_| {
            let before = clock::now();
            let out = f();
            (out, (clock::now() - before) as u32)
        });
        let busy = us.saturating_sub(calibration.overhead_us);
        (out, calibration.instructions(u64::from(busy)))
    }

    /// [`count_instructions`] as the app's `Meter` (the demo's profile).
    #[cfg(feature = "profile")]
    pub fn meter(f: &mut dyn FnMut()) -> u64 {
        count_instructions(f).1
    }

    /// The last [`calibrate`] result.
    pub fn calibration() -> Calibration {
        critical_section::with(|cs| CALIBRATION.borrow(cs).get())
    }
}

// ---------------------------------------------------------------------------
// Stack high-water mark
// ---------------------------------------------------------------------------

/// Stack painting (`marble_board_runtime::stack`) on this board's RAM. The
/// firmware links through flip-link (`.cargo/config.toml`): the statics sit
/// at the top of RAM and the stack below them, growing down towards the
/// start of RAM, so an overflow faults (no RAM below) instead of overwriting
/// them. [`paint`](stack::paint) fills the free stack at boot,
/// [`high_water`](stack::high_water) finds the deepest word overwritten since.
pub mod stack {
    use marble_rolling::board::microbit_v1::{RAM_BASE, RAM_BYTES, STACK_PAINT};

    /// Paints the free stack. Call first thing in `main`.
    #[inline(always)]
    pub fn paint() {
        marble_board_runtime::stack::paint(RAM_BASE, STACK_PAINT);
    }

    /// Stack use so far.
    #[derive(Clone, Copy, defmt::Format)]
    pub struct StackUse {
        /// Deepest use, bytes.
        pub used: usize,
        /// Room the stack has (below the statics), bytes.
        pub size: usize,
        /// The statics (data + bss + uninit, flip-link's alignment), bytes.
        pub statics: usize,
    }

    /// The high-water mark since [`paint`].
    pub fn high_water() -> StackUse {
        let stack = marble_board_runtime::stack::high_water(RAM_BASE, STACK_PAINT);
        StackUse {
            used: stack.used,
            size: stack.size,
            statics: (RAM_BASE + RAM_BYTES as usize)
                .saturating_sub(marble_board_runtime::stack::top()),
        }
    }
}

// ---------------------------------------------------------------------------
// Executor
// ---------------------------------------------------------------------------

/// The runtime's embassy executor that sleeps with WFI
/// (`marble_board_runtime::executor`, as the QEMU board's, and for the same
/// reason: QEMU treats WFE as a no-op, so the stock thread executor would
/// spin through every idle period), its sleeps timed on the [`clock`] for
/// the [`cpu_meter`].
pub mod executor {
    use embassy_executor::Spawner;
    use marble_board_runtime::executor::{self, Pended};

    use super::{clock, cpu_meter};

    /// The executor's wake-up flag (in this crate's statics: see [`Pended`]).
    static PENDED: Pended = Pended::new();

    /// Runs the executor forever; `init` spawns the first tasks. Call once.
    /// `init` a plain function, so that nothing of the spawning stays on the
    /// stack below the tasks for good.
    #[inline(always)]
    pub fn run(init: fn(Spawner)) -> ! {
        // SAFETY: `run` is called once, from `main`, which never returns (no
        // guard: it would cost RAM this board does not have).
        unsafe { executor::run(&PENDED, init, clock::now, cpu_meter::record_sleep) }
    }
}

// ---------------------------------------------------------------------------
// Watchdog
// ---------------------------------------------------------------------------

/// The nRF51's WDT: a 2 s period on its 32 768 Hz clock
/// (`board::microbit_v1::WATCHDOG_TIMEOUT_TICKS` says why) (the WDT starts the
/// RC oscillator itself), paused while a debugger halts the core, running
/// while it sleeps; one reload register. Petted by the watchdog task only
/// when every task's heartbeat moved (`board::watchdog::WatchdogGate`, the
/// rule the v2 runs too, and its host tests). QEMU's `microbit` machine has no WDT (its
/// registers are unimplemented: writes ignored): there it never resets.
pub mod watchdog {
    use marble_rolling::board::microbit_v1::WATCHDOG_TIMEOUT_TICKS;
    use nrf_pac as pac;

    /// The value a reload register takes to pet (nRF51 reference manual).
    const RELOAD: u32 = 0x6E52_4635;

    /// Starts the watchdog (once started it runs until a reset).
    pub fn start() {
        let wdt = pac::WDT;
        if wdt.runstatus().read().0 & 1 != 0 {
            // Already running since before a soft reset: its configuration
            // cannot change; keep petting it.
            return;
        }
        wdt.crv().write_value(WATCHDOG_TIMEOUT_TICKS);
        // SLEEP = run while asleep, HALT = pause under the debugger.
        wdt.config().write_value(pac::wdt::regs::Config(1));
        wdt.rren().write_value(pac::wdt::regs::Rren(1));
        wdt.tasks_start().write_value(1);
    }

    /// Reloads the counter.
    pub fn pet() {
        pac::WDT.rr(0).write_value(pac::wdt::regs::Rr(RELOAD));
    }
}

// ---------------------------------------------------------------------------
// The levels region
// ---------------------------------------------------------------------------

/// The levels region's bytes in flash
/// ([`marble_rolling::board::levels_region::V1`]), as the .hex put them
/// there: the caller reads them with `levels_region::at_boot`.
pub fn levels_region() -> &'static [u8] {
    use marble_rolling::board::levels_region::{SIZE, V1};
    // SAFETY: the region is SIZE bytes of on-chip flash, memory-mapped at
    // V1.start, always readable, aligned for bytes; memory.x keeps the
    // linker out of it and this firmware never erases or writes it,
    // so the bytes do not change while the slice lives.
    unsafe { core::slice::from_raw_parts(V1.start as usize as *const u8, SIZE) }
}
