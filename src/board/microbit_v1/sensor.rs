//! The v1's accelerometer poll loop as a plain state machine over any bus
//! with the v1 TWI's errors and a bus clear ([`Bus`]): the firmware
//! (`boards/microbit-v1/src/sensor.rs`) runs it on the nRF51's TWI, the host
//! tests on the virtual chips (`super::virtual_nxp`), so what the tests prove
//! is the code the board runs. The board keeps only the wiring: the TWI
//! driver, the poll period, the logs and the hand-over to the app.
//!
//! What it does:
//!
//! * bring-up: while no chip is known, probes every accelerometer a v1 may
//!   carry by identity ([`nxp_driver::probe`]), then configures the chip it
//!   found; its samples are turned into the board frame by that chip's axis
//!   map (`Accelerometer::axis_map`) before the supervision sees them, so
//!   one supervision runs from boot on: a sensor the game was told is down
//!   (no chip answered) comes back up through it once a chip is found;
//! * one poll: a read (the NXP burst, or the `lsm303agr` driver's), fed to
//!   the shared supervision ([`TiltPipeline`]), and a re-initialisation
//!   (probe first if nothing was found yet) when the supervisor asks for it;
//! * the bus clear (nine clocks and a STOP) before the first transfer and
//!   after every failed one, by wrapping the bus in [`Recovering`].
//!
//! The LSM303AGR of the v1.5 boards is driven through the `lsm303agr` crate
//! (feature `lsm303agr`, which the firmware enables). Without the feature
//! the library has no driver for it: a probe that finds one reports it, and
//! configuring it fails as [`Fault::Implausible`], so the supervisor keeps
//! the sensor down rather than play on a chip nothing reads.

use embedded_hal_async::i2c::I2c;

use super::accel::{Accelerometer, NxpChip};
use super::nxp_driver;
use super::twi::{Pause, TwiError};
use crate::board::accel_link::SUPERVISOR;
use crate::board::i2c::{ClearBus, Recovering};
use crate::input::sensor::{AccelMg, Action, AxisMap, Fault, Read, TiltPipeline, Transition};

/// The bus the poll loop needs: async I²C with the v1 TWI's errors, a bus
/// clear, and a pause (the wait after an NXP chip's soft reset).
pub trait Bus: I2c<Error = TwiError> + ClearBus + Pause {}

impl<T: I2c<Error = TwiError> + ClearBus + Pause> Bus for T {}

/// The LSM303AGR driver on the recovering bus.
#[cfg(feature = "lsm303agr")]
type Lsm<B> = crate::input::lsm303::Sensor<Recovering<B>>;

/// What is on the bus.
enum Chip<B: Bus> {
    /// Nothing probed yet, or no probe answered: the bare bus.
    Unknown(Recovering<B>),
    /// The MMA8653FC or the FXOS8700CQ.
    Nxp(Recovering<B>, &'static NxpChip),
    /// The LSM303AGR, its driver owning the bus.
    #[cfg(feature = "lsm303agr")]
    Lsm303agr(Lsm<B>),
    /// The LSM303AGR without its driver (feature `lsm303agr` off).
    #[cfg(not(feature = "lsm303agr"))]
    Lsm303agr(Recovering<B>),
}

/// What a bring-up's probe found, for the board's log.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Probed {
    /// This chip answered with its identity (the first probe that did).
    Found(Accelerometer),
    /// None of the three answered.
    NoneAnswered,
}

/// What one poll did.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Polled {
    /// The sensor went down or came back on this poll.
    pub transition: Option<Transition>,
    /// A re-initialisation on this poll probed the bus (nothing had been
    /// found before).
    pub probed: Option<Probed>,
}

/// The poll loop (see the module doc).
pub struct PollLoop<B: Bus> {
    /// `None` only while a bring-up moves the bus from one variant to
    /// another.
    chip: Option<Chip<B>>,
    pipeline: TiltPipeline,
    reinits: u32,
}

impl<B: Bus> PollLoop<B> {
    /// The bus, nothing probed yet. The pipeline is fed board-frame samples
    /// (the chip's map applied here), hence its identity map.
    pub fn new(bus: B) -> Self {
        Self {
            chip: Some(Chip::Unknown(Recovering::new(bus))),
            pipeline: TiltPipeline::new(AxisMap::IDENTITY, SUPERVISOR),
            reinits: 0,
        }
    }

    /// The first bring-up: probe, configure. Not counted in
    /// [`PollLoop::reinits`]; a failure is the supervisor's to handle, as a
    /// failed re-initialisation is.
    pub async fn bring_up(&mut self) -> Option<Probed> {
        self.configure().await
    }

    /// One poll (see the module doc).
    pub async fn poll(&mut self) -> Polled {
        let reading = match &mut self.chip {
            Some(chip) => read(chip).await,
            None => Read::Failed(Fault::Bus),
        };
        let reading = match (reading, self.found()) {
            (Read::Sample(raw), Some(chip)) => Read::Sample(chip.axis_map().apply(raw)),
            (Read::Sample(_), None) => Read::Failed(Fault::Implausible),
            (other, _) => other,
        };
        let step = self.pipeline.feed(reading);
        let mut probed = None;
        if let Action::Reinit = step.action {
            self.reinits = self.reinits.wrapping_add(1);
            probed = self.configure().await;
        }
        Polled {
            transition: step.transition,
            probed,
        }
    }

    /// The tilt the game gets: the last good sample in the board frame,
    /// milli-g.
    pub const fn tilt(&self) -> AccelMg {
        self.pipeline.tilt()
    }

    /// The supervision.
    pub const fn pipeline(&self) -> &TiltPipeline {
        &self.pipeline
    }

    /// Re-initialisations the supervisor asked for (the bring-up not
    /// counted).
    pub const fn reinits(&self) -> u32 {
        self.reinits
    }

    /// Faults the supervisor counted.
    pub const fn faults(&self) -> u32 {
        self.pipeline.supervisor().total_faults()
    }

    /// The chip found, if any.
    pub fn found(&self) -> Option<Accelerometer> {
        match self.chip.as_ref()? {
            Chip::Unknown(_) => None,
            Chip::Nxp(_, nxp) => Some(nxp.chip),
            Chip::Lsm303agr(_) => Some(Accelerometer::Lsm303agr),
        }
    }

    /// The recovering bus, while no driver owns it (nothing found, an NXP
    /// chip, or the LSM303AGR without its driver): for inspection by tests.
    pub fn bus(&mut self) -> Option<&mut Recovering<B>> {
        match self.chip.as_mut()? {
            Chip::Unknown(bus) | Chip::Nxp(bus, _) => Some(bus),
            #[cfg(not(feature = "lsm303agr"))]
            Chip::Lsm303agr(bus) => Some(bus),
            #[cfg(feature = "lsm303agr")]
            Chip::Lsm303agr(_) => None,
        }
    }

    /// Brings up the chip: probes while none is known, then configures it;
    /// tells the supervisor how it went.
    async fn configure(&mut self) -> Option<Probed> {
        let mut probed = None;
        if let Some(Chip::Unknown(_)) = self.chip {
            let Some(Chip::Unknown(mut bus)) = self.chip.take() else {
                return None;
            };
            match nxp_driver::probe(&mut bus).await {
                Some(found) => {
                    self.chip = Some(match found.nxp() {
                        Some(nxp) => Chip::Nxp(bus, nxp),
                        #[cfg(feature = "lsm303agr")]
                        None => Chip::Lsm303agr(lsm303agr::Lsm303agr::new_with_i2c(bus)),
                        #[cfg(not(feature = "lsm303agr"))]
                        None => Chip::Lsm303agr(bus),
                    });
                    probed = Some(Probed::Found(found));
                }
                None => {
                    self.chip = Some(Chip::Unknown(bus));
                    self.pipeline.reinit_done(Err(Fault::Implausible));
                    return Some(Probed::NoneAnswered);
                }
            }
        }
        let outcome = match &mut self.chip {
            Some(Chip::Nxp(bus, nxp)) => nxp_driver::configure(bus, nxp).await,
            // Probing has just read WHO_AM_I (or did at the first bring-up).
            #[cfg(feature = "lsm303agr")]
            Some(Chip::Lsm303agr(sensor)) => crate::input::lsm303::configure(sensor).await,
            _ => Err(Fault::Implausible),
        };
        self.pipeline.reinit_done(outcome);
        probed
    }
}

/// One read, in the chip's frame, milli-g.
async fn read<B: Bus>(chip: &mut Chip<B>) -> Read<AccelMg> {
    match chip {
        Chip::Nxp(bus, nxp) => nxp_driver::read(bus, nxp).await,
        #[cfg(feature = "lsm303agr")]
        Chip::Lsm303agr(sensor) => crate::input::lsm303::read(sensor).await,
        _ => Read::Failed(Fault::Implausible),
    }
}
