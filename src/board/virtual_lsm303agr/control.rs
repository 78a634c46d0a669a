//! What a virtual chip is given from outside (the tilt, injected faults,
//! reset requests) and what its bus counts, shared between whoever injects
//! (terminal keys, the fault script, a test) and the virtual bus that
//! applies them: the QEMU board's [`VirtualTwim`] and the v1's virtual TWI
//! (`board::microbit_v1::virtual_twi`) alike.
//!
//! [`VirtualTwim`]: crate::board::qemu::virtual_i2c::VirtualTwim

use core::sync::atomic::{AtomicI32, AtomicU32, AtomicU8, Ordering};

use crate::input::axes::AccelMg;

/// A fault injected into the virtual chip or its bus.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum InjectedFault {
    /// Everything works.
    Healthy = 0,
    /// Nothing acknowledges its address: every transfer fails at once.
    Nak = 1,
    /// A transfer starts and never completes (a slave holding SDA low): the
    /// transfer's future stays pending; only the caller's timeout ends it.
    /// The bus stays stuck after the fault is lifted, until the firmware
    /// clears it (nine clocks and a STOP) or the chip is reset; a bus clear
    /// while the fault is in force does not free it.
    StuckBus = 2,
    /// Conversions stall: the output registers keep their last values and no
    /// new data is flagged; writes are accepted, a re-init does not help.
    FrozenData = 3,
    /// Every new sample is random, in the top tenth of the full scale on
    /// every axis: implausible.
    Garbage = 4,
    /// The chip resets once (a brown-out): its registers go back to their
    /// power-on values (powered down, no data) and the fault is over; the
    /// driver has to initialise it again.
    ChipReset = 5,
}

impl InjectedFault {
    /// Every fault, in key order (`0` to `5`).
    pub const ALL: [InjectedFault; 6] = [
        InjectedFault::Healthy,
        InjectedFault::Nak,
        InjectedFault::StuckBus,
        InjectedFault::FrozenData,
        InjectedFault::Garbage,
        InjectedFault::ChipReset,
    ];

    /// The fault with this number (its key), if any.
    pub(crate) const fn from_u8(value: u8) -> Option<InjectedFault> {
        if (value as usize) < Self::ALL.len() {
            Some(Self::ALL[value as usize])
        } else {
            None
        }
    }

    /// A short name for logs and the status line.
    pub const fn name(self) -> &'static str {
        match self {
            InjectedFault::Healthy => "healthy",
            InjectedFault::Nak => "NAK",
            InjectedFault::StuckBus => "stuck bus",
            InjectedFault::FrozenData => "frozen data",
            InjectedFault::Garbage => "garbage",
            InjectedFault::ChipReset => "chip reset",
        }
    }
}

/// What the virtual chip is given from outside, and what its bus counts:
/// shared (`&`) between whoever sets the tilt and injects faults (terminal
/// keys, a script, a test) and the [`VirtualTwim`](crate::board::qemu::virtual_i2c::VirtualTwim)
/// that applies them to the chip at each transfer.
///
/// Atomics with plain loads and stores (no read-modify-write, so it builds
/// for the Cortex-M0 too): the firmware runs its tasks on one core without
/// preemption between them, so the three components of a tilt are never
/// seen half written.
#[derive(Debug)]
pub struct ChipControl {
    tilt: [AtomicI32; 3],
    fault: AtomicU8,
    reset_requests: AtomicU32,
    transfers: AtomicU32,
    refused: AtomicU32,
    resets_applied: AtomicU32,
}

impl ChipControl {
    /// A flat board, healthy, nothing counted.
    pub const fn new() -> Self {
        Self {
            tilt: [
                AtomicI32::new(AccelMg::LEVEL.x),
                AtomicI32::new(AccelMg::LEVEL.y),
                AtomicI32::new(AccelMg::LEVEL.z),
            ],
            fault: AtomicU8::new(InjectedFault::Healthy as u8),
            reset_requests: AtomicU32::new(0),
            transfers: AtomicU32::new(0),
            refused: AtomicU32::new(0),
            resets_applied: AtomicU32::new(0),
        }
    }

    /// Sets the tilt (board frame, milli-g) the chip samples from now on.
    pub fn set_tilt(&self, tilt: AccelMg) {
        self.tilt[0].store(tilt.x, Ordering::Relaxed);
        self.tilt[1].store(tilt.y, Ordering::Relaxed);
        self.tilt[2].store(tilt.z, Ordering::Relaxed);
    }

    /// The tilt the chip samples.
    pub fn tilt(&self) -> AccelMg {
        AccelMg::new(
            self.tilt[0].load(Ordering::Relaxed),
            self.tilt[1].load(Ordering::Relaxed),
            self.tilt[2].load(Ordering::Relaxed),
        )
    }

    /// Injects `fault` (replacing the one in force). [`InjectedFault::ChipReset`]
    /// is an event: it ends the fault in force and resets the chip once, at
    /// its next transfer.
    pub fn inject(&self, fault: InjectedFault) {
        if fault == InjectedFault::ChipReset {
            let requests = self.reset_requests.load(Ordering::Relaxed);
            self.reset_requests
                .store(requests.wrapping_add(1), Ordering::Relaxed);
            self.fault
                .store(InjectedFault::Healthy as u8, Ordering::Relaxed);
        } else {
            self.fault.store(fault as u8, Ordering::Relaxed);
        }
    }

    /// The fault in force ([`InjectedFault::Healthy`] after a chip reset).
    pub fn fault(&self) -> InjectedFault {
        InjectedFault::from_u8(self.fault.load(Ordering::Relaxed)).unwrap_or(InjectedFault::Healthy)
    }

    /// Chip resets asked for so far.
    pub(crate) fn reset_requests(&self) -> u32 {
        self.reset_requests.load(Ordering::Relaxed)
    }

    /// Chip resets the chip went through so far.
    pub fn resets_applied(&self) -> u32 {
        self.resets_applied.load(Ordering::Relaxed)
    }

    /// Transfers that reached the bus (acknowledged or not; a stuck one
    /// counts when it starts).
    pub fn transfers(&self) -> u32 {
        self.transfers.load(Ordering::Relaxed)
    }

    /// Transfers refused before reaching the bus (the DMA rule, lengths).
    pub fn refused(&self) -> u32 {
        self.refused.load(Ordering::Relaxed)
    }

    fn bump(counter: &AtomicU32) {
        counter.store(
            counter.load(Ordering::Relaxed).wrapping_add(1),
            Ordering::Relaxed,
        );
    }

    pub(crate) fn count_transfer(&self) {
        Self::bump(&self.transfers);
    }

    pub(crate) fn count_refused(&self) {
        Self::bump(&self.refused);
    }

    pub(crate) fn count_reset(&self) {
        Self::bump(&self.resets_applied);
    }
}

impl Default for ChipControl {
    fn default() -> Self {
        Self::new()
    }
}
