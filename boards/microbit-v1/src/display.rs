//! The LED matrix: the app's display task scans the game's 5×5 frame with
//! the shared `Scanner`; [`Matrix`] takes each refresh of those steps back
//! to the frame, rewires it onto the 3 × 9 lines and schedules it
//! (`marble_rolling::board::microbit_v1::schedule`), and TIMER1's interrupt
//! plays the schedule: 12 slices a refresh, each one GPIO `OUT` write and a
//! compare.
//!
//! TIMER1 runs at 1 MHz with the COMPARE0 → CLEAR short, so a slice lasts
//! exactly its CC\[0\] µs from the compare that started it, whatever the
//! interrupt's latency (which only delays the pin change by as much). The
//! interrupt has the highest priority, and the task hands it a whole
//! refresh at once, so the game's work never stretches a slice. A schedule
//! handed in is taken at the next refresh boundary (never mid-refresh);
//! until then, or if the task is late, the current one repeats.
//!
//! Before each `OUT` write the interrupt reads the clock (a TIMER0 capture):
//! in QEMU's trace that capture is the time stamp of the pin changes that
//! follow, which the xtask integrates (`xtask/src/microbit_v1.rs`).

use core::cell::RefCell;

use critical_section::Mutex;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use marble_rolling::app::{Latest, MatrixOutput};
use marble_rolling::board::microbit_v1::leds::{COL_PINS, MATRIX_PINS, ROW_PINS};
use marble_rolling::board::microbit_v1::{
    frame_from_refresh, rows_hex, schedule, Picture, Schedule, DARK_SCHEDULE,
    FRAME_LOG_MIN_REFRESHES, HEIGHT, REFRESH_US, SLICES, TIMER_PRESCALER, WIDTH,
};
use marble_rolling::board::watchdog::Task;
use marble_rolling::matrix::{ScanStep, Scanner};
use marble_rolling::player::Status;
use nrf_pac as pac;

use crate::hw;

/// What the interrupt plays, shared with the task.
struct Shared {
    current: Schedule,
    next: Option<Schedule>,
    /// The slice on show.
    index: usize,
    /// Schedules taken from `next` so far.
    swaps: u32,
    /// Clock (µs) at the last swap: the start of that schedule's first
    /// refresh.
    swapped_at: u64,
}

static SHARED: Mutex<RefCell<Shared>> = Mutex::new(RefCell::new(Shared {
    current: DARK_SCHEDULE,
    next: None,
    index: 0,
    swaps: 0,
    swapped_at: 0,
}));

/// Signalled at every refresh boundary.
static REFRESH: Signal<CriticalSectionRawMutex, ()> = Signal::new();

/// Writes the matrix bits of GPIO `OUT`, leaving the others as they are.
#[inline(always)]
fn drive(out: u32) {
    let gpio = pac::GPIO;
    let others = gpio.out().read().0 & !MATRIX_PINS;
    gpio.out().write_value(pac::gpio::regs::Out(others | out));
}

/// Configures the matrix pins as outputs (all dark) and starts TIMER1.
pub fn start() {
    let first = DARK_SCHEDULE[0];
    drive(first.out);
    for &pin in ROW_PINS.iter().chain(COL_PINS.iter()) {
        // DIR output, input buffer disconnected, standard drive.
        pac::GPIO
            .pin_cnf(usize::from(pin))
            .write_value(pac::gpio::regs::PinCnf(0b11));
    }
    let timer = pac::TIMER1;
    timer.tasks_stop().write_value(1);
    timer.mode().write_value(pac::timer::regs::Mode(0));
    // 16 bits: the nRF51's TIMER1 has no more (only TIMER0 counts 32 bits;
    // QEMU emulates 32 everywhere, so 32 here never showed). A slice is at
    // most 8 × 222 µs, far below 65 535.
    timer.bitmode().write_value(pac::timer::regs::Bitmode(0));
    timer
        .prescaler()
        .write_value(pac::timer::regs::Prescaler(u32::from(TIMER_PRESCALER)));
    // COMPARE0 → CLEAR.
    timer.shorts().write_value(pac::timer::regs::Shorts(1));
    timer.cc(0).write_value(first.us);
    timer.events_compare(0).write_value(0);
    timer.intenset().write_value(pac::timer::regs::Int(1 << 16));
    hw::enable_irq(pac::Interrupt::TIMER1, true);
    timer.tasks_clear().write_value(1);
    timer.tasks_start().write_value(1);
}

#[unsafe(no_mangle)]
extern "C" fn TIMER1() {
    pac::TIMER1.events_compare(0).write_value(0);
    let boundary = critical_section::with(|cs| {
        let mut shared = SHARED.borrow_ref_mut(cs);
        let mut boundary = false;
        let mut swapped = false;
        shared.index += 1;
        if shared.index >= SLICES {
            shared.index = 0;
            boundary = true;
            if let Some(next) = shared.next.take() {
                shared.current = next;
                shared.swaps = shared.swaps.wrapping_add(1);
                swapped = true;
            }
        }
        let slice = shared.current[shared.index];
        let timer = pac::TIMER1;
        timer.cc(0).write_value(slice.us);
        // The counter runs on from the compare that cleared it: if this
        // interrupt came later than the new slice is long (a long critical
        // section elsewhere), the compare has passed and would next match
        // only after the 16-bit counter wraps, 65.5 ms on at 1 MHz: six
        // refreshes with one row lit. Start the slice from now.
        timer.tasks_capture(1).write_value(1);
        if timer.cc(1).read() >= slice.us {
            timer.tasks_clear().write_value(1);
        }
        // The time stamp of this pin change (a TIMER0 capture).
        let now = hw::clock::now();
        if swapped {
            shared.swapped_at = now;
        }
        drive(slice.out);
        boundary
    });
    if boundary {
        REFRESH.signal(());
    }
}

/// A picture on the LEDs since `since` (µs), during level `level`.
#[derive(Clone, Copy)]
struct OnShow {
    picture: Picture,
    since: u64,
    level: u8,
}

/// The app's `MatrixOutput` for the v1's matrix (see the module doc).
pub struct Matrix {
    status: &'static Latest<Status>,
    /// Log the pictures that stay up for [`FRAME_LOG_MIN_REFRESHES`].
    log_frames: bool,
    /// The picture handed to the interrupt last.
    handed: Option<Picture>,
    /// The interrupt's swap count when we last looked.
    swaps: u32,
    /// The picture on the LEDs.
    on_show: Option<OnShow>,
    /// What [`MatrixOutput::show`] has gathered of a refresh, step by step
    /// (`display_task` calls `show_refresh`, which does not need it).
    gathered: Picture,
    /// Steps gathered.
    steps: usize,
}

impl Matrix {
    /// A matrix that reads the level from `status` for its frame log.
    pub fn new(status: &'static Latest<Status>, log_frames: bool) -> Self {
        Self {
            status,
            log_frames,
            handed: None,
            swaps: 0,
            on_show: None,
            gathered: Picture::new(),
            steps: 0,
        }
    }

    /// Shows `picture` from the next refresh boundary on, waits for the
    /// boundary, and logs the picture that the boundary replaced.
    async fn refresh(&mut self, picture: Picture) {
        if self.handed != Some(picture) {
            let next = schedule(&picture);
            critical_section::with(|cs| SHARED.borrow_ref_mut(cs).next = Some(next));
            self.handed = Some(picture);
        }
        REFRESH.wait().await;
        let (swaps, at) = critical_section::with(|cs| {
            let shared = SHARED.borrow_ref(cs);
            (shared.swaps, shared.swapped_at)
        });
        if swaps == self.swaps {
            return;
        }
        self.swaps = swaps;
        if let (Some(old), true) = (self.on_show, self.log_frames) {
            let refreshes =
                (at.saturating_sub(old.since) + u64::from(REFRESH_US / 2)) / u64::from(REFRESH_US);
            if refreshes >= u64::from(FRAME_LOG_MIN_REFRESHES) {
                let [r0, r1, r2, r3, r4] = rows_hex(&old.picture);
                defmt::info!(
                    "display frame level={=u8} t0={=u64} t1={=u64} rows={=u32:05x} {=u32:05x} {=u32:05x} {=u32:05x} {=u32:05x}",
                    old.level,
                    old.since,
                    at,
                    r0,
                    r1,
                    r2,
                    r3,
                    r4
                );
            }
        }
        if let Some(picture) = self.handed {
            self.on_show = Some(OnShow {
                picture,
                since: at,
                level: self.status.get().level,
            });
        }
    }
}

impl MatrixOutput<WIDTH, HEIGHT> for Matrix {
    async fn show(&mut self, step: ScanStep) {
        crate::HEARTBEATS.beat(Task::Display);
        // A refresh's steps add up to the picture (see `frame_from_refresh`).
        let mut lit = step.columns;
        while lit != 0 {
            let x = lit.trailing_zeros() as usize;
            lit &= lit - 1;
            let level = self.gathered.get(x, step.row);
            let ticks = u8::try_from(step.ticks).unwrap_or(u8::MAX);
            self.gathered.set(x, step.row, level.saturating_add(ticks));
        }
        self.steps += 1;
        if self.steps >= Scanner::<WIDTH, HEIGHT>::STEPS_PER_REFRESH {
            let picture = core::mem::take(&mut self.gathered);
            self.steps = 0;
            self.refresh(picture).await;
        }
    }

    async fn show_refresh(&mut self, scanner: &mut Scanner<WIDTH, HEIGHT>) {
        crate::HEARTBEATS.beat(Task::Display);
        let picture = frame_from_refresh(
            (0..Scanner::<WIDTH, HEIGHT>::STEPS_PER_REFRESH).map(|_| scanner.next_step()),
        );
        self.refresh(picture).await;
    }
}
