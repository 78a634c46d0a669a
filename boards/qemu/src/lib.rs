//! QEMU `mps2-an386` board: the register-level half, shared by the game
//! (`src/main.rs`) and the study's benchmark (`src/bin/bench.rs`).
//!
//! A crate of its own because it needs `unsafe` (MMIO, interrupt handlers,
//! exported symbols), which the core library forbids. The safe half
//! (memory map, options, CPU-load arithmetic, the virtual matrix) is
//! `marble_rolling::board::qemu`, tested on the host.
//!
//! Contents: [`clock`] (TIMER0 as a free-running 64-bit clock), the embassy
//! time driver (that clock + SysTick wake-ups), [`uart`] (CMSDK APB UART0
//! driver), [`cpu_meter`] (idle accounting, calibration, instruction
//! counting), [`stack`] (painting, high-water mark), [`executor`] (an embassy
//! raw executor that sleeps with WFI; these two and the NOP loop are
//! `marble_board_runtime`'s, on this board's clock and RAM),
//! interrupt/fault handlers, and semihosting [`options`] / [`exit`].
#![no_std]

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, Ordering};
use core::task::Waker;

use cortex_m::interrupt::{InterruptNumber, Mutex};
use cortex_m_rt::{exception, ExceptionFrame};
use embassy_time_queue_utils::Queue;
use marble_rolling::board::qemu::{Options, SYSCLK_HZ};

// ---------------------------------------------------------------------------
// MMIO, interrupts, exit
// ---------------------------------------------------------------------------

#[inline(always)]
fn read(addr: usize) -> u32 {
    // SAFETY: only called with register addresses of this board's devices.
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

#[inline(always)]
fn write(addr: usize, value: u32) {
    // SAFETY: only called with register addresses of this board's devices.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

/// An external interrupt number for the NVIC.
#[derive(Clone, Copy)]
struct Irq(u16);

// SAFETY: numbers come from the board's constants, all valid on mps2-an386.
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// Logs the panic once (a panic inside the logger, or a second one, must not
/// recurse) and exits QEMU with status 101. Shared by every binary built on this
/// board module.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    static PANICKED: AtomicBool = AtomicBool::new(false);
    cortex_m::interrupt::disable();
    if !PANICKED.swap(true, Ordering::SeqCst) {
        defmt::error!("panic: {}", defmt::Display2Format(info));
    }
    exit(101)
}

/// Ends the QEMU process with `code` as its exit status (semihosting
/// SYS_EXIT_EXTENDED): 0 = success.
pub fn exit(code: i32) -> ! {
    cortex_m::interrupt::disable();
    semihosting::process::exit(code)
}

/// Logs `what` and exits with a failure status.
pub fn fatal(what: &str) -> ! {
    defmt::error!("fatal: {=str}", what);
    exit(1)
}

/// The firmware's options, from the semihosting command line the runner
/// passes (see [`Options`]); defaults (headless demo) when there is none.
pub fn options() -> Options {
    match semihosting::experimental::env::args::<256>() {
        Ok(args) => Options::parse((&args).filter_map(Result::ok)),
        Err(_) => {
            defmt::warn!("no semihosting command line; running headless");
            Options::default()
        }
    }
}

/// The records' flash image in a host file (semihosting), so that best times
/// survive from one run to the next. QEMU's working directory is the
/// workspace root (`cargo qemu` starts it there).
pub mod records_file {
    use core::ffi::CStr;

    /// The image's file.
    pub const PATH: &CStr = c"target/qemu-records.bin";

    /// Fills `image` from the file; a missing file (the first run) or one of
    /// another size leaves `image` as it is (erased), with a log line.
    pub fn load(image: &mut [u8]) {
        super::flash_file::load(PATH, "records", image)
    }

    /// Writes `image` to the file (a failure is logged: the records still
    /// hold for this run).
    pub fn save(image: &[u8]) {
        super::flash_file::save(PATH, "records", image)
    }
}

/// The ghosts' flash image in a host file, as the records' is.
pub mod ghosts_file {
    use core::ffi::CStr;

    /// The image's file.
    pub const PATH: &CStr = c"target/qemu-ghosts.bin";

    /// Fills `image` from the file (see [`super::records_file::load`]).
    pub fn load(image: &mut [u8]) {
        super::flash_file::load(PATH, "ghosts", image)
    }

    /// Writes `image` to the file (a failure is logged).
    pub fn save(image: &[u8]) {
        super::flash_file::save(PATH, "ghosts", image)
    }
}

/// A flash image in a host file (semihosting).
mod flash_file {
    use core::ffi::CStr;
    use semihosting::fs;
    use semihosting::io::Read;

    /// Fills `image` from `path`; a missing file (the first run) or one of
    /// another size leaves `image` as it is (erased), with a log line naming
    /// `what`.
    pub fn load(path: &CStr, what: &str, image: &mut [u8]) {
        let read = fs::File::open(path).and_then(|mut file| {
            let len = file.metadata()?.len();
            if len != image.len() as u64 {
                return Ok(false);
            }
            file.read_exact(image).map(|()| true)
        });
        let name = path.to_str().unwrap_or("?");
        match read {
            Ok(true) => defmt::info!("{=str}: loaded from {=str}", what, name),
            Ok(false) => defmt::warn!("{=str}: {=str} has another size, not loaded", what, name),
            Err(_) => defmt::info!("{=str}: no {=str} yet: starting empty", what, name),
        }
    }

    /// Writes `image` to `path` (a failure is logged: what is in RAM still
    /// holds for this run).
    pub fn save(path: &CStr, what: &str, image: &[u8]) {
        if fs::write(path, image).is_err() {
            defmt::warn!(
                "{=str}: cannot write {=str}",
                what,
                path.to_str().unwrap_or("?")
            );
        }
    }
}

/// Every interrupt without a handler of its own lands here (cortex-m-rt's
/// default vector table); the board's few interrupts are dispatched by number,
/// which needs neither a PAC nor a `device.x`.
#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == marble_rolling::board::qemu::UART0_RX_IRQ as i16 {
        uart::on_rx_interrupt();
    } else {
        defmt::error!("unexpected interrupt or exception {}", irqn);
        exit(1);
    }
}

/// A fault: log and exit with a failure status. (A stack overflow never gets
/// here: with flip-link the stack runs off the bottom of RAM, the exception
/// entry cannot push its frame, the core locks up, and QEMU 7.2 aborts with
/// "Lockup: can't escalate 3 to HardFault" and exit status 134.)
#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    defmt::error!(
        "HardFault: pc {=u32:#010x} lr {=u32:#010x}",
        frame.pc(),
        frame.lr()
    );
    exit(1)
}

// ---------------------------------------------------------------------------
// Clock and time driver
// ---------------------------------------------------------------------------

/// TIMER0 (CMSDK APB timer, 25 MHz) as the board's free-running clock,
/// extended to 64 bits. It counts down from `u32::MAX` and wraps every
/// 171.8 s; every read extends it, and the 1 kHz SysTick wake-ups guarantee a
/// read well within each wrap.
pub mod clock {
    use core::cell::Cell;

    use marble_rolling::board::qemu::{SYSCLK_HZ, TIMER0_BASE};

    use super::{read, write, Mutex};

    const CTRL: usize = TIMER0_BASE;
    const VALUE: usize = TIMER0_BASE + 0x04;
    const RELOAD: usize = TIMER0_BASE + 0x08;
    const CTRL_ENABLE: u32 = 1 << 0;

    /// Clock ticks per embassy tick (`TICK_HZ`, 1 MHz by default).
    const PER_EMBASSY_TICK: u32 = {
        let per = SYSCLK_HZ as u64 / embassy_time_driver::TICK_HZ;
        assert!(
            per * embassy_time_driver::TICK_HZ == SYSCLK_HZ as u64 && per <= u32::MAX as u64,
            "embassy's TICK_HZ must divide the 25 MHz clock"
        );
        per as u32
    };

    /// What has been counted up to the last raw value read.
    #[derive(Clone, Copy)]
    struct Count {
        /// The last raw value.
        raw: u32,
        /// Clock ticks up to it.
        ticks: u64,
        /// Embassy ticks up to it, and the clock ticks left over (`< PER_EMBASSY_TICK`).
        embassy: u64,
        rest: u32,
    }

    static STATE: Mutex<Cell<Count>> = Mutex::new(Cell::new(Count {
        raw: u32::MAX,
        ticks: 0,
        embassy: 0,
        rest: 0,
    }));

    /// Starts TIMER0 counting down from `u32::MAX`, no interrupt. Call once,
    /// before anything reads the time.
    pub fn start() {
        write(CTRL, 0);
        write(RELOAD, u32::MAX);
        write(VALUE, u32::MAX);
        write(CTRL, CTRL_ENABLE);
    }

    /// The raw counter (counts *down* at 25 MHz).
    #[inline(always)]
    pub fn raw() -> u32 {
        read(VALUE)
    }

    /// Counts up to `raw`, a value read just before with interrupts disabled
    /// (so that no newer value was seen meanwhile).
    fn count_to(raw: u32) -> Count {
        cortex_m::interrupt::free(|cs| {
            let cell = STATE.borrow(cs);
            let mut count = cell.get();
            let delta = count.raw.wrapping_sub(raw);
            count.raw = raw;
            count.ticks += u64::from(delta);
            // Embassy time advances by whole ticks of the delta: a 32-bit divide
            // by a constant (a multiply), not `ticks / 25` on the 64-bit total,
            // which would be a library division on every `now()` — 1 000
            // SysTicks a second plus every Ticker. The SysTick reads the clock each millisecond,
            // so `delta + rest` cannot overflow (it would take 171 s).
            let pending = delta.saturating_add(count.rest);
            count.embassy += u64::from(pending / PER_EMBASSY_TICK);
            count.rest = pending % PER_EMBASSY_TICK;
            cell.set(count);
            count
        })
    }

    /// 25 MHz ticks since [`start`], up to `raw`, a value read just before
    /// with interrupts disabled (so that no newer value was seen meanwhile).
    pub fn ticks_at(raw: u32) -> u64 {
        count_to(raw).ticks
    }

    /// Embassy ticks (`TICK_HZ`) since [`start`].
    pub fn embassy_ticks() -> u64 {
        cortex_m::interrupt::free(|_| count_to(raw()).embassy)
    }

    /// 25 MHz ticks since [`start`].
    pub fn ticks() -> u64 {
        cortex_m::interrupt::free(|_| ticks_at(raw()))
    }
}

/// The embassy time driver: [`clock`] for `now()` (1 MHz embassy ticks), a
/// periodic 1 kHz SysTick interrupt to wake expired timers.
///
/// Why not the `systick-timer` crate, which keeps time by counting SysTick
/// interrupts: QEMU 7.2 with `-icount ...,sleep=off` does not end a WFI at the
/// first timer deadline but one timer period later (measured with a 10 ms
/// SysTick: a WFI 1 ms before the wrap returned after 11 ms; with a periodic
/// timer of N ticks as the only source, after 2N). So every idle period
/// spans two SysTick wraps and only one interrupt is taken: a SysTick-counting
/// clock runs at about half speed of virtual time (measured: 100 ms of
/// embassy time took 201 ms of TIMER0 time). Reading a free-running counter
/// cannot lose time; wake-ups are then at most 2 ms late under `sleep=off`
/// (1 ms otherwise), and `Ticker`s keep their average rate.
struct Driver {
    /// Timer queue and its earliest deadline (embassy ticks).
    queue: Mutex<RefCell<(Queue, u64)>>,
}

impl embassy_time_driver::Driver for Driver {
    fn now(&self) -> u64 {
        clock::embassy_ticks()
    }

    fn schedule_wake(&self, at: u64, waker: &Waker) {
        cortex_m::interrupt::free(|cs| {
            let mut state = self.queue.borrow(cs).borrow_mut();
            let (queue, next) = &mut *state;
            if queue.schedule_wake(at, waker) {
                *next = (*next).min(at);
            }
        });
    }
}

embassy_time_driver::time_driver_impl!(static DRIVER: Driver = Driver {
    queue: Mutex::new(RefCell::new((Queue::new(), u64::MAX))),
});

/// Starts the clock and the 1 kHz SysTick wake-ups.
pub fn start_time(syst: &mut cortex_m::peripheral::SYST) {
    use cortex_m::peripheral::syst::SystClkSource;
    clock::start();
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYSCLK_HZ / 1000 - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

#[exception]
fn SysTick() {
    use embassy_time_driver::Driver as _;
    let now = DRIVER.now();
    cortex_m::interrupt::free(|cs| {
        let mut state = DRIVER.queue.borrow(cs).borrow_mut();
        let (queue, next) = &mut *state;
        if now >= *next {
            *next = queue.next_expiration(now);
        }
    });
}

// ---------------------------------------------------------------------------
// UART
// ---------------------------------------------------------------------------

/// CMSDK APB UART0: interrupt-driven receive into a queue, blocking transmit.
///
/// Hand-written: no crates.io crate drives the CMSDK APB UART (the Rust
/// drivers that exist live inside example/training repositories and are
/// transmit-only), and the device is five registers.
pub mod uart {
    use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
    use embassy_sync::channel::Channel;
    use marble_rolling::app::{ByteSource, Console};
    use marble_rolling::board::qemu::{SYSCLK_HZ, UART0_BASE, UART0_RX_IRQ};

    use super::{read, write, Irq};

    const DATA: usize = UART0_BASE;
    const STATE: usize = UART0_BASE + 0x04;
    const CTRL: usize = UART0_BASE + 0x08;
    /// Read: interrupt status; write 1s: clear.
    const INT: usize = UART0_BASE + 0x0c;
    const BAUDDIV: usize = UART0_BASE + 0x10;

    const STATE_TX_FULL: u32 = 1 << 0;
    const STATE_RX_FULL: u32 = 1 << 1;
    const STATE_RX_OVERRUN: u32 = 1 << 3;
    const CTRL_TX_EN: u32 = 1 << 0;
    const CTRL_RX_EN: u32 = 1 << 1;
    const CTRL_RX_INT_EN: u32 = 1 << 3;
    const INT_RX: u32 = 1 << 1;
    const INT_RX_OVERRUN: u32 = 1 << 3;

    /// Received bytes; dropped when full (a human cannot type 64 keys ahead).
    static RX: Channel<CriticalSectionRawMutex, u8, 64> = Channel::new();

    /// Enables TX and interrupt-driven RX at 115200 baud (QEMU ignores the
    /// rate but wants a divider ≥ 16).
    pub fn init() {
        write(CTRL, 0);
        write(BAUDDIV, SYSCLK_HZ / 115_200);
        write(INT, INT_RX | INT_RX_OVERRUN);
        write(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT_EN);
        // SAFETY: the handler (DefaultHandler → on_rx_interrupt) is ready.
        unsafe { cortex_m::peripheral::NVIC::unmask(Irq(UART0_RX_IRQ)) };
    }

    /// RX interrupt: acknowledge, then drain the (one-byte) receive buffer.
    pub(super) fn on_rx_interrupt() {
        write(INT, INT_RX | INT_RX_OVERRUN);
        write(STATE, STATE_RX_OVERRUN);
        while read(STATE) & STATE_RX_FULL != 0 {
            let byte = read(DATA) as u8;
            let _ = RX.try_send(byte);
        }
    }

    /// Blocking transmit of `bytes`.
    pub fn write_bytes(bytes: &[u8]) {
        for &byte in bytes {
            while read(STATE) & STATE_TX_FULL != 0 {}
            write(DATA, u32::from(byte));
        }
    }

    /// The UART as the game's terminal output.
    pub struct UartConsole;

    impl Console for UartConsole {
        fn write(&mut self, bytes: &[u8]) {
            write_bytes(bytes);
        }
    }

    /// The UART's received bytes.
    pub struct UartRx;

    impl ByteSource for UartRx {
        async fn read_byte(&mut self) -> u8 {
            RX.receive().await
        }
    }
}

// ---------------------------------------------------------------------------
// CPU meter
// ---------------------------------------------------------------------------

/// Busy time, i.e. executed instructions under `-icount`, measured with the
/// 25 MHz [`clock`] (see `marble_rolling::board::qemu::cpu_meter` for the
/// arithmetic and caveats).
///
/// The executor loop reports its WFI sleeps to
/// [`record_sleep`](cpu_meter::record_sleep); [`sample`](cpu_meter::sample)
/// gives total and idle ticks; [`calibrate`](cpu_meter::calibrate) times a NOP
/// loop of known length; [`count_instructions`](cpu_meter::count_instructions)
/// counts the instructions of a closure (e.g. one physics step) with
/// interrupts off.
pub mod cpu_meter {
    use core::cell::Cell;

    use marble_board_runtime::nop::{self, Stopwatch};
    use marble_rolling::board::qemu::cpu_meter::{Calibration, Sample};

    use super::{clock, Mutex};

    /// Clock ticks spent in WFI since [`clock::start`].
    static IDLE: Mutex<Cell<u64>> = Mutex::new(Cell::new(0));
    static CALIBRATION: Mutex<Cell<Calibration>> = Mutex::new(Cell::new(Calibration::NOMINAL));

    /// Records a WFI sleep from raw clock value `before` to `after` (called
    /// by the executor loop, interrupts disabled).
    pub fn record_sleep(before: u32, after: u32) {
        cortex_m::interrupt::free(|cs| {
            let idle = IDLE.borrow(cs);
            idle.set(idle.get() + u64::from(before.wrapping_sub(after)));
        });
    }

    /// Total and idle clock ticks since the clock started.
    pub fn sample() -> Sample {
        cortex_m::interrupt::free(|cs| Sample {
            total_ticks: clock::ticks(),
            idle_ticks: IDLE.borrow(cs).get(),
        })
    }

    /// The clock as the runtime's stopwatch: ticks (it counts down),
    /// interrupts off.
    struct Ticks;

    impl Stopwatch for Ticks {
        fn time(&self, f: impl FnOnce()) -> u32 {
            cortex_m::interrupt::free(|_| {
                let before = clock::raw();
                f();
                before.wrapping_sub(clock::raw())
            })
        }
    }

    /// Measures ticks per instruction with the runtime's two NOP loops
    /// (`marble_board_runtime::nop`: their difference, 80 000 instructions,
    /// cancels the call and timer-read overhead). Stores the result for
    /// [`count_instructions`], and returns it.
    pub fn calibrate() -> Calibration {
        let timing = nop::time_nop_loops(&Ticks);
        let calibration = Calibration {
            instructions: timing.instructions,
            ticks: timing.ticks,
            overhead_ticks: timing.overhead_ticks,
        };
        cortex_m::interrupt::free(|cs| CALIBRATION.borrow(cs).set(calibration));
        calibration
    }

    /// The last [`calibrate`] result ([`Calibration::NOMINAL`] before).
    pub fn calibration() -> Calibration {
        cortex_m::interrupt::free(|cs| CALIBRATION.borrow(cs).get())
    }

    /// Runs `f` with interrupts disabled and returns its result and the
    /// number of instructions it executed (meaningful under `-icount` only;
    /// exact to about ±1 instruction after [`calibrate`]).
    pub fn count_instructions<R>(f: impl FnOnce() -> R) -> (R, u64) {
        cortex_m::interrupt::free(|cs| {
            let calibration = CALIBRATION.borrow(cs).get();
            let before = clock::raw();
            let result = f();
            let ticks = before.wrapping_sub(clock::raw());
            let net = ticks.saturating_sub(calibration.overhead_ticks);
            (result, calibration.instructions(u64::from(net)))
        })
    }
}

// ---------------------------------------------------------------------------
// Stack high-water mark
// ---------------------------------------------------------------------------

/// Stack painting (`marble_board_runtime::stack`) on this board's RAM:
/// [`paint`](stack::paint) fills the free stack with
/// [`STACK_PAINT`](marble_rolling::board::qemu::STACK_PAINT) at boot;
/// [`high_water`](stack::high_water) later finds the lowest word that was
/// overwritten. With flip-link the stack starts just below `.data`/`.bss`
/// (`_stack_start`, the initial SP) and grows down towards
/// [`RAM_BASE`](marble_rolling::board::qemu::RAM_BASE).
pub mod stack {
    pub use marble_board_runtime::stack::StackUse;
    use marble_rolling::board::qemu::{RAM_BASE, STACK_PAINT};

    /// Paints the stack from [`RAM_BASE`] up to a little below the current
    /// SP. Call first thing in `main`.
    #[inline(always)]
    pub fn paint() {
        marble_board_runtime::stack::paint(RAM_BASE, STACK_PAINT);
    }

    /// The high-water mark since [`paint`].
    pub fn high_water() -> StackUse {
        marble_board_runtime::stack::high_water(RAM_BASE, STACK_PAINT)
    }
}

// ---------------------------------------------------------------------------
// Executor
// ---------------------------------------------------------------------------

/// The runtime's embassy executor that sleeps with WFI
/// (`marble_board_runtime::executor`: QEMU does not sleep on the stock
/// executor's WFE), its sleeps timed on the [`clock`] for the [`cpu_meter`].
pub mod executor {
    use core::sync::atomic::{AtomicBool, Ordering};

    use embassy_executor::Spawner;
    use marble_board_runtime::executor::{self, Pended};

    use super::{clock, cpu_meter};

    /// The executor's wake-up flag (in this crate's statics: see [`Pended`]).
    static PENDED: Pended = Pended::new();

    /// Runs the executor forever; `init` spawns the first tasks. Call once.
    pub fn run(init: impl FnOnce(Spawner)) -> ! {
        static STARTED: AtomicBool = AtomicBool::new(false);
        if STARTED.swap(true, Ordering::SeqCst) {
            super::fatal("executor::run called twice");
        }
        // SAFETY: guarded above: the only call.
        unsafe { executor::run(&PENDED, init, clock::raw, cpu_meter::record_sleep) }
    }
}
