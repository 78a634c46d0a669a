//! Which readings are believed: the one plausibility rule of the tilt path.
//!
//! A board-frame reading (mg) is believed when no axis exceeds the sensor's
//! full scale and its total magnitude is that of a hand-held toy. The sensor's
//! supervision ([`super::sensor::TiltPipeline`]) asks it of every sample, to
//! count an implausible one as a fault; the tilt filter
//! ([`super::tilt::TiltFilter`]) asks it of every reading that comes from
//! anything else (keys, the autopilot, a trace, a ghost), on entry. Each
//! reading is judged once, by [`Plausibility::judge`]: a filter fed a
//! pipeline's samples ([`TiltConfig::SENSOR`](super::tilt::TiltConfig::SENSOR))
//! does not judge them again.
//!
//! # The range a believed reading keeps to
//!
//! No axis of a believed reading exceeds [`MAX_READING_MG`], whatever the
//! bounds configured: the physics' largest pull ([`MAX_MG`]) less the largest
//! calibration offset. So the gravity a believed reading becomes (negated,
//! offset, filtered: never larger) is within what the physics takes without a
//! clamp.

use super::axes::{AccelMg, Axis, Calibration};
use super::event::Fault;
use crate::physics::range::MAX_MG;

/// The largest axis of a believed reading, mg, whatever
/// [`Plausibility::max_axis_mg`] says: 7 500, the physics' [`MAX_MG`] less
/// [`Calibration::MAX_OFFSET_MG`] (a reading beyond 7.5 g on one axis is a
/// knock, not a tilt).
pub const MAX_READING_MG: u32 = (MAX_MG - Calibration::MAX_OFFSET_MG) as u32;

// A believed axis fits the app's 16-bit tilt.
const _: () = assert!(MAX_READING_MG <= i16::MAX as u32);

/// Why a reading was not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TiltError {
    /// All three components are exactly zero: a sensor that lost its
    /// configuration, or a dead bus reading zeros.
    AllZero,
    /// One component exceeds the sensor's full scale
    /// ([`Plausibility::max_axis_mg`], at most [`MAX_READING_MG`]); the first
    /// offending axis (x, y, z order) and its raw value.
    OutOfRange {
        /// The offending axis.
        axis: Axis,
        /// Its raw value, mg.
        value: i32,
    },
    /// The total magnitude is outside
    /// [`Plausibility::min_total_mg`]..=[`Plausibility::max_total_mg`]
    /// (free fall, a knock, or garbage).
    Magnitude {
        /// The squared magnitude of the sample, mg².
        squared_mg2: u32,
    },
    /// [`TiltConfig::stuck_samples`](super::tilt::TiltConfig::stuck_samples)
    /// identical raw samples in a row: a frozen sensor (real MEMS noise makes
    /// such repeats implausible). Reported for every further identical
    /// sample; the next different one is used again.
    Stuck,
}

impl From<TiltError> for Fault {
    /// `Stuck` is a sensor that stopped producing new data; the rest are
    /// implausible samples.
    fn from(e: TiltError) -> Self {
        match e {
            TiltError::Stuck => Fault::NoData,
            _ => Fault::Implausible,
        }
    }
}

/// Bounds a sample must lie within to be believed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Plausibility {
    /// Largest believable magnitude of any single axis, mg (at most
    /// [`MAX_READING_MG`] is believed, whatever this says).
    pub max_axis_mg: u32,
    /// Smallest believable total magnitude, mg. A still or hand-held board
    /// always feels about 1 g; an all-zero reading is a sensor that lost its
    /// configuration (or free fall, when tilt means nothing anyway).
    pub min_total_mg: u32,
    /// Largest believable total magnitude, mg (beyond it: a knock or garbage).
    pub max_total_mg: u32,
}

impl Plausibility {
    /// Defaults for a hand-held toy on a ±2 g (or wider) range: per axis
    /// ±4000 mg (twice the firmware's ±2 g range, whose saturated readings,
    /// ±2048 at most, are therefore always accepted per axis), total
    /// 300..=3000 mg (a held toy feels about 1 g; beyond 3 g is a knock, not a
    /// tilt).
    pub const DEFAULT: Self = Self {
        max_axis_mg: 4_000,
        min_total_mg: 300,
        max_total_mg: 3_000,
    };

    /// Whether `reading` (board frame, mg) is believed, and if not why; the
    /// first failure wins: [`TiltError::AllZero`], [`TiltError::OutOfRange`],
    /// [`TiltError::Magnitude`].
    ///
    /// Three comparisons per axis and three 32-bit multiplications: no
    /// division, no 64-bit arithmetic, no overflow for any `i32` input.
    pub(crate) const fn judge(&self, reading: AccelMg) -> Result<(), TiltError> {
        let AccelMg { x, y, z } = reading;
        if x == 0 && y == 0 && z == 0 {
            return Err(TiltError::AllZero);
        }
        let max_axis = min_u32(self.max_axis_mg, MAX_READING_MG);
        let axes = [(Axis::X, x), (Axis::Y, y), (Axis::Z, z)];
        let mut i = 0;
        while i < axes.len() {
            let (axis, value) = axes[i];
            if value.unsigned_abs() > max_axis {
                return Err(TiltError::OutOfRange { axis, value });
            }
            i += 1;
        }
        // Each |component| ≤ 7 500 now, so the sum of squares is < 1.7·10^8,
        // and bounds capped at 65 535 (> any such magnitude) square below 2^32.
        let (x, y, z) = (x.unsigned_abs(), y.unsigned_abs(), z.unsigned_abs());
        let sq = x * x + y * y + z * z;
        let lo = min_u32(self.min_total_mg, 65_535);
        let hi = min_u32(self.max_total_mg, 65_535);
        if sq < lo * lo || sq > hi * hi {
            return Err(TiltError::Magnitude { squared_mg2: sq });
        }
        Ok(())
    }

    /// Whether the sample `s` is believed (`Plausibility::judge`).
    pub const fn check(&self, s: AccelMg) -> bool {
        self.judge(s).is_ok()
    }
}

impl Default for Plausibility {
    fn default() -> Self {
        Self::DEFAULT
    }
}

const fn min_u32(a: u32, b: u32) -> u32 {
    if a < b {
        a
    } else {
        b
    }
}
