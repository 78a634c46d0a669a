//! CPU load in QEMU, in instructions: the arithmetic half.
//!
//! Under `-icount shift=N` QEMU advances virtual time by exactly `2^N` ns per
//! executed instruction and jumps over idle time (`sleep=off`). A hardware
//! timer clocked at [`SYSCLK_HZ`](super::SYSCLK_HZ) therefore advances by
//! `25 MHz × 2^N ns` ticks per instruction: 3.2 at `shift=7`. So timer ticks
//! spent outside the executor's WFI sleep measure executed instructions.
//!
//! The hardware half (TIMER0 as a free-running counter, the idle accounting
//! in the WFI executor loop, the NOP-loop calibration, counting the
//! instructions of a closure) is `hw::cpu_meter` in `hw.rs`. This module turns
//! its raw tick counts into numbers: [`Calibration`] (ticks per instruction,
//! measured with a block of known instruction count) and [`LoadReport`].
//!
//! The figures are *instructions*, not Cortex-M4 cycles: the percentage of a
//! 64 MHz M4 assumes one instruction per cycle, which real code does not quite
//! reach (loads, taken branches and divisions take more), so read it as a
//! lower bound. Without `-icount` (interactive runs) the timer follows host
//! time and the figures mean nothing.

/// Ticks per instruction × 1000 that `-icount shift=`[`ICOUNT_SHIFT`](super::ICOUNT_SHIFT)
/// should give: `SYSCLK_HZ × 2^shift / 10^6` (3200).
pub(crate) const EXPECTED_MILLITICKS_PER_INSTRUCTION: u64 =
    super::SYSCLK_HZ as u64 * (1 << super::ICOUNT_SHIFT) / 1_000_000;

/// Reference core clock for the load percentage: the nRF52833's 64 MHz M4F.
pub(crate) const REFERENCE_HZ: u64 = 64_000_000;

/// Timer ticks per instruction, measured by timing a block of known
/// instruction count (the fixed cost of reading the timer subtracted).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration {
    /// Instructions in the measured block.
    pub instructions: u32,
    /// Timer ticks the block took, measurement overhead removed.
    pub ticks: u32,
    /// Timer ticks of the measurement itself (timing an empty block).
    pub overhead_ticks: u32,
}

impl Calibration {
    /// The theoretical calibration for `-icount shift=7`, for when no
    /// measurement is available.
    pub const NOMINAL: Calibration = Calibration {
        instructions: 1000,
        ticks: EXPECTED_MILLITICKS_PER_INSTRUCTION as u32,
        overhead_ticks: 0,
    };

    /// Ticks per instruction × 1000 (3200 expected at `shift=7`).
    pub fn milliticks_per_instruction(&self) -> u64 {
        if self.instructions == 0 {
            return 0;
        }
        u64::from(self.ticks) * 1000 / u64::from(self.instructions)
    }

    /// Whether the measurement matches `-icount shift=7` within 1 %.
    pub fn matches_icount(&self) -> bool {
        let measured = self.milliticks_per_instruction();
        measured.abs_diff(EXPECTED_MILLITICKS_PER_INSTRUCTION)
            <= EXPECTED_MILLITICKS_PER_INSTRUCTION / 100
    }

    /// Instructions executed in `ticks` timer ticks (rounded to nearest).
    pub fn instructions(&self, ticks: u64) -> u64 {
        if self.ticks == 0 {
            return 0;
        }
        let ticks_cal = u128::from(self.ticks);
        let scaled = u128::from(ticks) * u128::from(self.instructions);
        ((scaled + ticks_cal / 2) / ticks_cal).min(u128::from(u64::MAX)) as u64
    }
}

/// A reading of the meter: timer ticks since it started, and how many of
/// them the core spent asleep in the executor's WFI.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample {
    /// All ticks since the meter started.
    pub total_ticks: u64,
    /// Ticks spent in WFI.
    pub idle_ticks: u64,
}

/// CPU load between two [`Sample`]s.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LoadReport {
    /// Firmware (virtual) time covered, µs.
    pub firmware_us: u64,
    /// Timer ticks spent outside WFI.
    pub(crate) busy_ticks: u64,
    /// Instructions executed outside WFI.
    pub busy_instructions: u64,
    /// Busy instructions per second of firmware time.
    pub instructions_per_second: u64,
    /// `instructions_per_second` as a share of `REFERENCE_HZ`, in
    /// hundredths of a percent (1234 = 12.34 %).
    pub centipercent_of_64mhz: u64,
}

impl LoadReport {
    /// The load between `start` and `end`; `None` if no time passed or the
    /// samples are out of order.
    pub fn between(calibration: &Calibration, start: Sample, end: Sample) -> Option<LoadReport> {
        let total = end.total_ticks.checked_sub(start.total_ticks)?;
        let idle = end.idle_ticks.checked_sub(start.idle_ticks)?;
        if total == 0 {
            return None;
        }
        let busy_ticks = total.saturating_sub(idle);
        let busy_instructions = calibration.instructions(busy_ticks);
        let hz = u128::from(super::SYSCLK_HZ);
        let firmware_us = (u128::from(total) * 1_000_000 / hz) as u64;
        let instructions_per_second =
            (u128::from(busy_instructions) * hz / u128::from(total)) as u64;
        let centipercent_of_64mhz =
            (u128::from(instructions_per_second) * 10_000 / u128::from(REFERENCE_HZ)) as u64;
        Some(LoadReport {
            firmware_us,
            busy_ticks,
            busy_instructions,
            instructions_per_second,
            centipercent_of_64mhz,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nominal_is_3_2_ticks_per_instruction() {
        assert_eq!(EXPECTED_MILLITICKS_PER_INSTRUCTION, 3200);
        assert!(Calibration::NOMINAL.matches_icount());
        assert_eq!(Calibration::NOMINAL.instructions(32_000), 10_000);
    }

    #[test]
    fn report() {
        let cal = Calibration::NOMINAL;
        // One second, a quarter of it busy.
        let start = Sample::default();
        let end = Sample {
            total_ticks: 25_000_000,
            idle_ticks: 18_750_000,
        };
        let r = LoadReport::between(&cal, start, end).unwrap();
        assert_eq!(r.firmware_us, 1_000_000);
        assert_eq!(r.busy_instructions, 6_250_000 * 10 / 32);
        assert_eq!(r.instructions_per_second, 1_953_125);
        assert_eq!(r.centipercent_of_64mhz, 305);
        assert!(LoadReport::between(&cal, end, start).is_none());
    }
}
