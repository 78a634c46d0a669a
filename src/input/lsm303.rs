//! The LSM303AGR accelerometer as every board drives it, over whatever
//! asynchronous I²C bus the board has: the micro:bit v2's TWIM, the QEMU
//! board's virtual TWIM with its virtual chip, the micro:bit v1.5's TWI. One
//! copy, so that what the fault script proves against the virtual chip in QEMU
//! is the code the boards run.
//!
//! The boards keep the wiring (which bus, its error type, when to poll); the
//! supervision that decides what a failed read means is [`super::sensor`]'s.
//! Driver calls go through the `lsm303agr` crate; only the mode change's
//! blocking delay is replaced: the caller waits asynchronously instead.

use embassy_time::Timer;
use embedded_hal_async::i2c::I2c;
use lsm303agr::interface::I2cInterface;
use lsm303agr::mode::MagOneShot;
use lsm303agr::{AccelMode, AccelOutputDataRate, Error, Lsm303agr};

use super::event::Fault;
use super::sensor::{AccelMg, Action, Read, Step, TiltPipeline};

/// The driver on bus `I2C`.
pub type Sensor<I2C> = Lsm303agr<I2cInterface<I2C>, MagOneShot>;

/// How long the output takes to become valid after a mode change at 200 Hz
/// (the datasheet's 1/ODR plus margin).
pub(crate) const SETTLE_MS: u64 = super::accel_timing::ACCEL_SETTLE_MS;

// The driver is configured for the rate the input path names.
const _: () = assert!(
    super::accel_timing::ACCEL_ODR_HZ == 200,
    "configure() sets AccelOutputDataRate::Hz200"
);

/// What a board's bus error means to the supervisor: a timeout (a stuck bus,
/// worth a bus clear) or any other bus error.
pub trait BusFault {
    /// The supervisor's name for this error.
    fn fault(&self) -> Fault;
}

/// The supervisor's name for a driver error.
pub(crate) fn fault<E: BusFault>(e: Error<E>) -> Fault {
    match e {
        Error::Comm(e) => e.fault(),
        Error::InvalidInputData => Fault::Implausible,
    }
}

/// The driver's mode changes take a blocking delay; [`configure`] waits
/// asynchronously afterwards instead.
struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

/// Whether the chip on the bus says it is an LSM303AGR accelerometer.
pub(crate) async fn check_identity<I2C>(sensor: &mut Sensor<I2C>) -> Result<(), Fault>
where
    I2C: I2c,
    I2C::Error: BusFault,
{
    let id = sensor.accelerometer_id().await.map_err(fault)?;
    if id.is_correct() {
        Ok(())
    } else {
        Err(Fault::Implausible)
    }
}

/// (Re)configures the accelerometer: init (block data update), high
/// resolution at 200 Hz, then waits `SETTLE_MS` until the output is valid.
pub(crate) async fn configure<I2C>(sensor: &mut Sensor<I2C>) -> Result<(), Fault>
where
    I2C: I2c,
    I2C::Error: BusFault,
{
    sensor.init().await.map_err(fault)?;
    sensor
        .set_accel_mode_and_odr(
            &mut NoDelay,
            AccelMode::HighResolution,
            AccelOutputDataRate::Hz200,
        )
        .await
        .map_err(fault)?;
    Timer::after_millis(SETTLE_MS).await;
    Ok(())
}

/// The (re)init every LSM303AGR board runs: the identity check
/// (`check_identity`), then, if the chip is one, `configure`. The
/// outcome goes to `pipeline` ([`TiltPipeline::reinit_done`]) and back to
/// the board, which logs a failure.
pub async fn reinit<I2C>(sensor: &mut Sensor<I2C>, pipeline: &mut TiltPipeline) -> Result<(), Fault>
where
    I2C: I2c,
    I2C::Error: BusFault,
{
    let outcome = match check_identity(sensor).await {
        Ok(()) => configure(sensor).await,
        Err(fault) => Err(fault),
    };
    pipeline.reinit_done(outcome);
    outcome
}

/// What one [`poll`] did, for the board to log and count.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Polled {
    /// What the read returned.
    pub read: Read<AccelMg>,
    /// What the pipeline made of it.
    pub step: Step,
    /// The re-init's outcome, when the pipeline asked for one
    /// ([`Action::Reinit`]).
    pub reinit: Option<Result<(), Fault>>,
}

/// One polling period's sensor work, as every LSM303AGR board does it: a
/// `read` fed to `pipeline`, then `on_step` (the board's counts and log
/// lines, before any re-init as they always were), then a [`reinit`] when
/// the pipeline asks for one ([`Action::Reinit`]). The board keeps its own
/// rule for when to start its ticker over.
pub async fn poll<I2C>(
    sensor: &mut Sensor<I2C>,
    pipeline: &mut TiltPipeline,
    on_step: impl FnOnce(Read<AccelMg>, Step),
) -> Polled
where
    I2C: I2c,
    I2C::Error: BusFault,
{
    let read = read(sensor).await;
    let step = pipeline.feed(read);
    on_step(read, step);
    let reinit = if step.action == Action::Reinit {
        Some(reinit(sensor, pipeline).await)
    } else {
        None
    };
    Polled { read, step, reinit }
}

/// Powers the accelerometer down (`CTRL_REG1_A` ODR = 0: no conversions;
/// measuring at 200 Hz it would draw more than the whole nRF in System OFF),
/// before the board sleeps. `configure` brings it back; the magnetometer stays in the
/// idle mode it starts in (the driver never starts it).
pub async fn power_down<I2C>(sensor: &mut Sensor<I2C>) -> Result<(), Fault>
where
    I2C: I2c,
    I2C::Error: BusFault,
{
    sensor
        .set_accel_mode_and_odr(&mut NoDelay, AccelMode::PowerDown, None)
        .await
        .map_err(fault)
}

/// One poll in the sensor's frame, milli-g: a new sample, none yet (not a
/// fault), or the bus's fault.
pub(crate) async fn read<I2C>(sensor: &mut Sensor<I2C>) -> Read<AccelMg>
where
    I2C: I2c,
    I2C::Error: BusFault,
{
    match sensor.accel_status().await {
        Ok(status) if !status.xyz_new_data() => return Read::NotReady,
        Ok(_) => {}
        Err(e) => return Read::Failed(fault(e)),
    }
    match sensor.acceleration().await {
        Ok(a) => {
            let (x, y, z) = a.xyz_mg();
            Read::Sample(AccelMg::new(x, y, z))
        }
        Err(e) => Read::Failed(fault(e)),
    }
}
