//! BBC micro:bit v2: the hardware half (embassy-nrf wiring only).
//!
//! The `marble-microbit` firmware crate's board module (target
//! thumbv7em-none-eabihf). Every decision — sensor fault policy, axis table,
//! calibration, button combinations, scan timing, what the game does — is in
//! host-tested library code ([`marble_rolling::sensor`],
//! [`marble_rolling::buttons`], [`marble_rolling::board::microbit`],
//! [`marble_rolling::app`]); this file only moves bits between those and the
//! pins, and nothing here panics on a sensor or bus error.

use embassy_nrf::gpio::{Input, Level, Output, OutputDrive, Pull};
use embassy_nrf::twim::{self, Twim};
use embassy_nrf::wdt::WatchdogHandle;
use embassy_time::{Duration, Instant, Ticker, Timer};
use heapless::Deque;
use lsm303agr::interface::I2cInterface;
use lsm303agr::mode::MagOneShot;
use lsm303agr::{AccelMode, AccelOutputDataRate, Lsm303agr};

use marble_rolling::app::{MatrixOutput, TiltInput, REFRESH_HZ};
use marble_rolling::board::microbit as board;
use marble_rolling::input::buttons::{ButtonEvent, Buttons};
use marble_rolling::input::event::{Command, InputEvent, Tilt};
use marble_rolling::input::sensor::{AccelMg, Action, Fault, TiltPipeline};
use marble_rolling::matrix::ScanStep;

/// RTC ticks per BCM base tick (4 → 109 Hz refresh; see the board module).
const RTC_TICKS_PER_BASE_TICK: u64 = board::rtc_ticks_per_base_tick(REFRESH_HZ) as u64;

/// One full refresh, in RTC ticks.
const REFRESH_TICKS: u64 = RTC_TICKS_PER_BASE_TICK
    * marble_rolling::matrix::Scanner::<{ board::WIDTH }, { board::HEIGHT }>::TICKS_PER_REFRESH
        as u64;

// ---------------------------------------------------------------------------
// LED matrix
// ---------------------------------------------------------------------------

/// The 5×5 LED matrix: rows driven high, columns pulled low to light.
pub struct Matrix {
    rows: [Output<'static>; board::HEIGHT],
    cols: [Output<'static>; board::WIDTH],
    lit_row: Option<usize>,
    deadline: Instant,
}

impl Matrix {
    /// Takes the row pins (top to bottom) and column pins (left to right).
    pub fn new(
        rows: [Output<'static>; board::HEIGHT],
        cols: [Output<'static>; board::WIDTH],
    ) -> Self {
        Self {
            rows,
            cols,
            lit_row: None,
            deadline: Instant::now(),
        }
    }

    /// An output pin for a row (idle low = off).
    pub fn row_pin(
        pin: embassy_nrf::Peri<'static, impl embassy_nrf::gpio::Pin>,
    ) -> Output<'static> {
        Output::new(pin, Level::Low, OutputDrive::HighDrive)
    }

    /// An output pin for a column (idle high = off).
    pub fn col_pin(
        pin: embassy_nrf::Peri<'static, impl embassy_nrf::gpio::Pin>,
    ) -> Output<'static> {
        Output::new(pin, Level::High, OutputDrive::HighDrive)
    }
}

impl MatrixOutput<{ board::WIDTH }, { board::HEIGHT }> for Matrix {
    async fn show(&mut self, step: ScanStep) {
        let columns = step.columns;
        if self.lit_row != Some(step.row) {
            // Columns off before switching rows: no ghosting of the old row.
            for col in &mut self.cols {
                col.set_high();
            }
            for (y, row) in self.rows.iter_mut().enumerate() {
                row.set_level(if y == step.row {
                    Level::High
                } else {
                    Level::Low
                });
            }
            self.lit_row = Some(step.row);
        }
        for (x, col) in self.cols.iter_mut().enumerate() {
            col.set_level(if (columns >> x) & 1 != 0 {
                Level::Low
            } else {
                Level::High
            });
        }
        // Absolute deadlines: slice lengths do not accumulate wake-up latency.
        // After a long stall (debugger, flash), restart the schedule from now
        // instead of racing through the missed slices.
        let now = Instant::now();
        if now > self.deadline + Duration::from_ticks(REFRESH_TICKS) {
            self.deadline = now;
        }
        self.deadline += Duration::from_ticks(u64::from(step.ticks) * RTC_TICKS_PER_BASE_TICK);
        Timer::at(self.deadline).await;
    }
}

// ---------------------------------------------------------------------------
// Accelerometer
// ---------------------------------------------------------------------------

/// The LSM303AGR on TWIM0 (address 0x19 for the accelerometer).
pub type Sensor = Lsm303agr<I2cInterface<Twim<'static>>, MagOneShot>;

/// The driver's mode changes take a blocking delay; we wait asynchronously
/// afterwards instead ([`board::ACCEL_SETTLE_MS`]).
struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

/// I²C configuration of the internal bus.
pub fn twim_config() -> twim::Config {
    let mut config = twim::Config::default();
    config.frequency = twim::Frequency::K400;
    config
}

/// (Re)configures the accelerometer: identity check, block data update,
/// high-resolution mode at [`board::ACCEL_ODR_HZ`], then waits until the
/// output is valid.
async fn configure(sensor: &mut Sensor) -> Result<(), Fault> {
    let id = sensor.accelerometer_id().await.map_err(|_| Fault::Bus)?;
    if !id.is_correct() {
        return Err(Fault::Implausible);
    }
    sensor.init().await.map_err(|_| Fault::Bus)?;
    sensor
        .set_accel_mode_and_odr(
            &mut NoDelay,
            AccelMode::HighResolution,
            AccelOutputDataRate::Hz200,
        )
        .await
        .map_err(|_| Fault::Bus)?;
    Timer::after_millis(board::ACCEL_SETTLE_MS).await;
    Ok(())
}

/// One sample in the sensor frame, milli-g.
async fn read(sensor: &mut Sensor) -> Result<AccelMg, Fault> {
    let status = sensor.accel_status().await.map_err(|_| Fault::Bus)?;
    if !status.xyz_new_data() {
        return Err(Fault::NoData);
    }
    let (x, y, z) = sensor
        .acceleration()
        .await
        .map_err(|_| Fault::Bus)?
        .xyz_mg();
    Ok(AccelMg::new(x, y, z))
}

fn saturate(v: i32) -> i16 {
    v.clamp(i32::from(i16::MIN), i32::from(i16::MAX)) as i16
}

fn to_tilt(s: AccelMg) -> Tilt {
    Tilt {
        x: saturate(s.x),
        y: saturate(s.y),
        z: saturate(s.z),
    }
}

// ---------------------------------------------------------------------------
// Input: accelerometer + buttons → app::TiltInput
// ---------------------------------------------------------------------------

/// Polls the accelerometer and buttons every [`board::INPUT_PERIOD_MS`] and
/// produces the app's tilt and command events.
pub struct MicrobitInput {
    sensor: Sensor,
    button_a: Input<'static>,
    button_b: Input<'static>,
    buttons: Buttons,
    pipeline: TiltPipeline,
    ticker: Option<Ticker>,
    /// Events of this poll still to hand out, in order.
    pending: Deque<InputEvent, 4>,
    /// Whether the game has been told the sensor is down.
    down: bool,
    last_fault: Fault,
    watchdog: Option<WatchdogHandle>,
}

impl MicrobitInput {
    /// `watchdog` is this loop's watchdog channel (petted every period).
    pub fn new(
        sensor: Sensor,
        button_a: Input<'static>,
        button_b: Input<'static>,
        watchdog: Option<WatchdogHandle>,
    ) -> Self {
        Self {
            sensor,
            button_a,
            button_b,
            buttons: Buttons::new(board::BUTTONS),
            pipeline: TiltPipeline::new(board::AXIS_MAP, board::SUPERVISOR),
            ticker: None,
            pending: Deque::new(),
            down: false,
            last_fault: Fault::Bus,
            watchdog,
        }
    }

    /// A button input (active low; the board has pull-ups, the internal one
    /// is added for safety).
    pub fn button_pin(
        pin: embassy_nrf::Peri<'static, impl embassy_nrf::gpio::Pin>,
    ) -> Input<'static> {
        Input::new(pin, Pull::Up)
    }

    /// One polling period: buttons, then the sensor through the pipeline.
    async fn poll(&mut self) -> (Option<Command>, Tilt) {
        let command = match self
            .buttons
            .update(self.button_a.is_low(), self.button_b.is_low())
        {
            Some(ButtonEvent::NextLevel) => Some(Command::NextLevel),
            Some(ButtonEvent::Restart) => Some(Command::Restart),
            Some(ButtonEvent::Calibrate) => Some(Command::Calibrate),
            None => None,
        };
        let sample = read(&mut self.sensor).await;
        match self.pipeline.feed(sample) {
            Action::Use(_) => {}
            Action::KeepLast(_) => {
                if let Err(fault) = sample {
                    defmt::debug!("accelerometer: {}", fault);
                }
            }
            Action::Reinit => {
                defmt::warn!("accelerometer: re-initialising");
                let outcome = configure(&mut self.sensor).await;
                if let Err(fault) = outcome {
                    defmt::warn!("accelerometer: re-init failed: {}", fault);
                }
                self.pipeline.reinit_done(outcome);
            }
            Action::ShowFault => {}
        }
        if let Err(fault) = sample {
            self.last_fault = fault;
        }
        let down = self.pipeline.is_down();
        if self.down != down {
            self.down = down;
            defmt::warn!("accelerometer down: {}", down);
            let event = if down {
                InputEvent::SensorDown(self.last_fault)
            } else {
                InputEvent::SensorUp
            };
            let _ = self.pending.push_back(event);
        }
        (command, to_tilt(self.pipeline.tilt()))
    }
}

impl TiltInput for MicrobitInput {
    async fn next_event(&mut self) -> InputEvent {
        if let Some(event) = self.pending.pop_front() {
            return event;
        }
        match &mut self.ticker {
            Some(ticker) => ticker.next().await,
            None => {
                // First call: bring the sensor up (a failure is handled by the
                // supervisor like any other).
                let outcome = configure(&mut self.sensor).await;
                if let Err(fault) = outcome {
                    defmt::warn!("accelerometer: init failed: {}", fault);
                }
                self.pipeline.reinit_done(outcome);
                self.ticker = Some(Ticker::every(Duration::from_millis(board::INPUT_PERIOD_MS)));
            }
        }
        if let Some(watchdog) = &mut self.watchdog {
            watchdog.pet();
        }
        let (command, tilt) = self.poll().await;
        if let Some(command) = command {
            let _ = self.pending.push_back(InputEvent::Command(command));
        }
        let _ = self.pending.push_back(InputEvent::Tilt(tilt));
        self.pending.pop_front().unwrap_or(InputEvent::Tilt(tilt))
    }
}
