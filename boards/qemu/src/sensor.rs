//! The QEMU board's accelerometer input: the micro:bit's input stack — the
//! `lsm303agr` 1.1 async driver, a per-transfer timeout, the
//! [`TiltPipeline`] supervision — running on a virtual LSM303AGR on a virtual
//! TWIM (`marble_rolling::board::virtual_lsm303agr`, shared with the v1's virtual
//! bus, and `marble_rolling::board::qemu::virtual_i2c`).
//!
//! The terminal's arrow keys do not hand the game a tilt: they set the
//! virtual chip's tilt, and the game gets what the driver reads back through
//! the pipeline, with the sensor's down/up transitions; the digit keys inject
//! faults (see `fault_keys`). Commands from keys pass straight to the game.
//! The headless runs (demo, fault script) have no keys; the fault script drives
//! the chip through the same [`ChipControl`].
//!
//! Like `boards/microbit/src/sensor.rs`'s `MicrobitInput`, which this follows
//! step for step (configure, read, poll, ticker reset after slow work), the
//! board only forwards: the pipeline decides.

use core::pin::pin;
use core::sync::atomic::{AtomicU32, Ordering};
use core::task::Poll;

use embassy_futures::poll_once;
use embassy_futures::select::{select, Either};
use embassy_time::{with_timeout, Duration, Instant, Ticker};
use embedded_hal_async::i2c::{ErrorKind, ErrorType, I2c, Operation};
use heapless::Deque;

use marble_rolling::app::{ByteSource, Console, TiltInput};
use marble_rolling::board::i2c::{ClearBus, Recovering};
use marble_rolling::board::qemu::fault_keys::{FaultKeys, QemuKey, FAULT_KEYS_HELP};
use marble_rolling::board::qemu::virtual_i2c::{RamRange, TwimError, VirtualTwim};
use marble_rolling::board::qemu::{
    HEIGHT, INPUT_PERIOD_MS, SENSOR_AXIS_MAP, SUPERVISOR, TRANSFER_TIMEOUT_MS,
};
use marble_rolling::board::virtual_lsm303agr::ChipControl;
use marble_rolling::input::event::InputEvent;
use marble_rolling::input::lsm303::{self, BusFault};
use marble_rolling::input::pacing;
use marble_rolling::input::sensor::{Action, Fault, Read, TiltPipeline};

/// The firmware's clock for the virtual chip, µs.
pub fn now_us() -> u64 {
    Instant::now().as_micros()
}

/// The virtual TWIM as the firmware builds it: embassy-time's clock, QEMU's
/// RAM for the DMA rule.
pub type QemuTwim<'a> = VirtualTwim<'a, fn() -> u64, RamRange>;

/// What the sensor input did, for the fault script and the logs.
pub struct SensorReport {
    samples: AtomicU32,
    reinits: AtomicU32,
    failed_reinits: AtomicU32,
    faults: AtomicU32,
}

impl SensorReport {
    /// Nothing yet.
    pub const fn new() -> Self {
        Self {
            samples: AtomicU32::new(0),
            reinits: AtomicU32::new(0),
            failed_reinits: AtomicU32::new(0),
            faults: AtomicU32::new(0),
        }
    }

    /// Good samples used so far.
    pub fn samples(&self) -> u32 {
        self.samples.load(Ordering::Relaxed)
    }

    /// (Re)configurations so far, the first included.
    pub fn reinits(&self) -> u32 {
        self.reinits.load(Ordering::Relaxed)
    }

    /// Of those, the failed ones.
    pub fn failed_reinits(&self) -> u32 {
        self.failed_reinits.load(Ordering::Relaxed)
    }

    /// Polls that failed, or whose sample the plausibility rules refused: 0 in a
    /// fault-free run (a frame that starves the input task shows here first).
    pub fn faults(&self) -> u32 {
        self.faults.load(Ordering::Relaxed)
    }

    fn bump(counter: &AtomicU32) {
        // One writer (the input task): a load and a store suffice.
        counter.store(
            counter.load(Ordering::Relaxed).wrapping_add(1),
            Ordering::Relaxed,
        );
    }
}

impl Default for SensorReport {
    fn default() -> Self {
        Self::new()
    }
}

// ---------------------------------------------------------------------------
// The bus: the virtual TWIM with a deadline per transfer
// ---------------------------------------------------------------------------

/// Why a transfer on [`Bus`] failed.
#[derive(Clone, Copy, PartialEq, Eq, Debug, defmt::Format)]
pub enum BusError {
    /// The TWIM refused or failed it.
    Twim(TwimError),
    /// It did not finish within [`TRANSFER_TIMEOUT_MS`] (a stuck bus).
    Timeout,
}

impl embedded_hal_async::i2c::Error for BusError {
    fn kind(&self) -> ErrorKind {
        match self {
            BusError::Twim(e) => embedded_hal_async::i2c::Error::kind(e),
            BusError::Timeout => ErrorKind::Other,
        }
    }
}

/// The virtual TWIM under the boards' bus-clear rule ([`Recovering`]): a
/// clear before the first transfer and after every transfer that failed on
/// the wire. The virtual bus stays stuck until cleared, as a real one does.
pub type Bus<'a> = Recovering<TimedTwim<'a>>;

/// The virtual TWIM with a deadline on every transfer: a stuck transfer is
/// dropped after [`TRANSFER_TIMEOUT_MS`]. Logs the first failure of each
/// kind in a row.
pub struct TimedTwim<'a> {
    twim: QemuTwim<'a>,
    last_logged: Option<BusError>,
}

impl<'a> TimedTwim<'a> {
    /// `twim` with deadlines.
    pub fn new(twim: QemuTwim<'a>) -> Self {
        Self {
            twim,
            last_logged: None,
        }
    }
}

impl ClearBus for TimedTwim<'_> {
    fn clear_bus(&mut self) {
        let outcome = self.twim.clear_bus();
        if !outcome.is_clear() {
            defmt::warn!("i2c: bus clear #{=u32}: {}", self.twim.clears(), outcome);
        }
    }

    /// Only failures on the wire: a refused buffer never reached the bus.
    fn on_the_wire(error: &BusError) -> bool {
        matches!(
            error,
            BusError::Timeout | BusError::Twim(TwimError::AddressNack)
        )
    }
}

impl ErrorType for TimedTwim<'_> {
    type Error = BusError;
}

impl I2c for TimedTwim<'_> {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [Operation<'_>],
    ) -> Result<(), BusError> {
        let copy_buffer = self.twim.copy_buffer_len();
        // A virtual transfer normally completes at its first poll: the
        // deadline (a clock read and a timer) is armed only for one that does
        // not, from that moment on — a stuck bus is caught just the same, and
        // the demo's CPU load does not pay for a timer per transfer. The
        // transfer is dropped at the end of the block, before a bus clear.
        let outcome = {
            let mut transfer = pin!(self.twim.transaction(address, operations));
            match poll_once(transfer.as_mut()) {
                Poll::Ready(outcome) => Ok(outcome),
                Poll::Pending => {
                    with_timeout(Duration::from_millis(TRANSFER_TIMEOUT_MS), transfer).await
                }
            }
        };
        let result = match outcome {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(BusError::Twim(e)),
            Err(_) => Err(BusError::Timeout),
        };
        match result {
            Ok(()) => self.last_logged = None,
            Err(e) if self.last_logged != Some(e) => {
                self.last_logged = Some(e);
                defmt::warn!(
                    "i2c: transfer to {=u8:#04x} failed: {} (copy buffer {=usize} bytes)",
                    address,
                    e,
                    copy_buffer
                );
            }
            Err(_) => {}
        }
        result
    }
}

// ---------------------------------------------------------------------------
// The driver
// ---------------------------------------------------------------------------

/// The LSM303AGR driver on the virtual bus.
pub type Sensor<'a> = lsm303::Sensor<Bus<'a>>;

impl BusFault for BusError {
    fn fault(&self) -> Fault {
        match self {
            BusError::Timeout => Fault::Timeout,
            BusError::Twim(_) => Fault::Bus,
        }
    }
}

// ---------------------------------------------------------------------------
// The input
// ---------------------------------------------------------------------------

/// Terminal row of the sensor's status line (the fault keys' help below it):
/// below the virtual matrix's title, blank line, matrix, blank line, level,
/// tilt and two key lines.
const STATUS_ROW: usize = HEIGHT + 8;

/// Redraw the status line at least this often, polls (a full redraw of the
/// matrix clears the screen once, at its first draw).
const STATUS_EVERY_POLLS: u32 = 100;

/// The terminal's keys: a byte source, its decoder, and the console for the
/// fault keys' status line.
pub struct Keys<S, C> {
    source: S,
    decoder: FaultKeys,
    console: C,
}

impl<S, C> Keys<S, C> {
    /// Keys from `source`, the status line on `console`.
    pub fn new(source: S, console: C) -> Self {
        Self {
            source,
            decoder: FaultKeys::new(),
            console,
        }
    }
}

/// Polls the virtual accelerometer every [`INPUT_PERIOD_MS`] through the
/// driver and the pipeline, and (interactive) takes the terminal's keys
/// meanwhile. See the module doc.
pub struct QemuInput<'a, S, C> {
    sensor: Sensor<'a>,
    keys: Option<Keys<S, C>>,
    chip: &'static ChipControl,
    report: &'static SensorReport,
    pipeline: TiltPipeline,
    ticker: Option<Ticker>,
    /// When the sensor was last polled (`input::pacing`).
    last_poll: Option<Instant>,
    /// Events of this poll still to hand out, in order.
    pending: Deque<InputEvent, 4>,
    polls: u32,
}

impl<'a, S: ByteSource, C: Console> QemuInput<'a, S, C> {
    /// Reads `sensor`; `keys` for an interactive terminal.
    pub fn new(
        sensor: Sensor<'a>,
        keys: Option<Keys<S, C>>,
        chip: &'static ChipControl,
        report: &'static SensorReport,
    ) -> Self {
        Self {
            sensor,
            keys,
            chip,
            report,
            pipeline: TiltPipeline::new(SENSOR_AXIS_MAP, SUPERVISOR),
            ticker: None,
            last_poll: None,
            pending: Deque::new(),
            polls: 0,
        }
    }

    /// (Re)configures the sensor and tells the pipeline how it went
    /// ([`lsm303::reinit`]).
    async fn reinit(&mut self) {
        SensorReport::bump(&self.report.reinits);
        let outcome = lsm303::reinit(&mut self.sensor, &mut self.pipeline).await;
        self.reinit_failed(outcome);
    }

    /// Counts and logs a failed (re)init.
    fn reinit_failed(&self, outcome: Result<(), Fault>) {
        if let Err(fault) = outcome {
            SensorReport::bump(&self.report.failed_reinits);
            defmt::warn!("accelerometer: (re)init failed: {}", fault);
        }
    }

    /// One polling period: the sensor through the pipeline ([`lsm303::poll`]).
    /// Returns whether it took long (a re-init with its settling time, a
    /// timed-out transfer): the only slow work here, as a virtual transfer
    /// takes no time.
    async fn poll(&mut self) -> bool {
        let report = self.report;
        let polled = lsm303::poll(&mut self.sensor, &mut self.pipeline, |read, step| {
            if matches!(
                (read, step.action),
                (Read::Failed(_), _) | (Read::Sample(_), Action::KeepLast(_))
            ) {
                SensorReport::bump(&report.faults);
            }
            match step.action {
                Action::Use(_) => SensorReport::bump(&report.samples),
                Action::KeepLast(_) | Action::ShowFault => {}
                Action::Reinit => {
                    defmt::warn!("accelerometer: re-initialising");
                    SensorReport::bump(&report.reinits);
                }
            }
        })
        .await;
        let step = polled.step;
        let mut slow = polled.read == Read::Failed(Fault::Timeout);
        if let Some(outcome) = polled.reinit {
            self.reinit_failed(outcome);
            slow = true;
        }
        if let Some(transition) = step.transition {
            defmt::warn!(
                "accelerometer: {} (injected: {=str})",
                transition,
                self.chip.fault().name()
            );
            let _ = self.pending.push_back(transition.event());
            self.draw_status();
        }
        slow
    }

    /// A key: a tilt goes to the chip, a digit injects a fault, a command
    /// goes to the game.
    fn key(&mut self, byte: u8) -> Option<InputEvent> {
        let key = self.keys.as_mut()?.decoder.feed(byte)?;
        match key {
            QemuKey::Input(InputEvent::Tilt(tilt)) => {
                self.chip.set_tilt(tilt);
                None
            }
            QemuKey::Input(event) => Some(event),
            QemuKey::Inject(fault) => {
                defmt::info!("keys: inject {=str}", fault.name());
                self.chip.inject(fault);
                self.draw_status();
                None
            }
        }
    }

    /// The sensor's status line and the fault keys' help (interactive only).
    fn draw_status(&mut self) {
        let down = self.pipeline.supervisor().down_fault();
        let fault = self.chip.fault();
        let Some(keys) = self.keys.as_mut() else {
            return;
        };
        let mut line = heapless::String::<192>::new();
        let _ = core::fmt::write(
            &mut line,
            format_args!(
                "\x1b7\x1b[{};1H  sensor {}, injected fault: {}\x1b[K\r\n  {}\x1b[K\x1b8",
                STATUS_ROW,
                match down {
                    None => "up",
                    Some(Fault::Bus) => "DOWN (bus)",
                    Some(Fault::Timeout) => "DOWN (timeout)",
                    Some(Fault::NoData) => "DOWN (no data)",
                    Some(Fault::Implausible) => "DOWN (implausible)",
                },
                fault.name(),
                FAULT_KEYS_HELP
            ),
        );
        keys.console.write(line.as_bytes());
    }
}

impl<S: ByteSource, C: Console> TiltInput for QemuInput<'_, S, C> {
    async fn next_event(&mut self) -> InputEvent {
        let period = Duration::from_millis(INPUT_PERIOD_MS);
        loop {
            if let Some(event) = self.pending.pop_front() {
                return event;
            }
            let Some(ticker) = self.ticker.as_mut() else {
                // First call: bring the sensor up (a failure is handled by
                // the supervisor like any other).
                self.reinit().await;
                self.ticker = Some(Ticker::every(period));
                continue;
            };
            if let Some(keys) = self.keys.as_mut() {
                let woke = select(ticker.next(), keys.source.read_byte()).await;
                if let Either::Second(byte) = woke {
                    if let Some(event) = self.key(byte) {
                        return event;
                    }
                    continue;
                }
            } else {
                ticker.next().await;
            }
            // A tick after a stall (another task held the CPU) polls once and
            // starts the period over, rather than catch up in a burst of polls
            // that find no new sample (`input::pacing`).
            let now = Instant::now();
            let late = self.last_poll.is_some_and(|last| {
                pacing::late(last.as_micros(), now.as_micros(), period.as_micros())
            });
            self.last_poll = Some(now);
            if self.poll().await || late {
                // Slow work: start the period over rather than poll back to
                // back (as the micro:bit does).
                if let Some(ticker) = &mut self.ticker {
                    ticker.reset();
                }
            }
            self.polls = self.polls.wrapping_add(1);
            if self.polls.is_multiple_of(STATUS_EVERY_POLLS) {
                self.draw_status();
            }
            // After this poll's transition, if any (as the micro:bit).
            let tilt = InputEvent::Tilt(self.pipeline.tilt());
            if self.pending.push_back(tilt).is_err() {
                return tilt;
            }
        }
    }
}
