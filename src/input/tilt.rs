//! The tilt input path: a board-frame reading ([`AccelMg`]) → the apparent
//! gravity the physics consumes ([`GravityMg`], handed on by
//! `Game::set_gravity_mg` to [`crate::physics::world::World::set_gravity_mg`]).
//!
//! ```text
//! reading ─▶ [plausibility, on entry] ─▶ stuck check ─▶ low-pass ─▶ − calibration ─▶ [dead zone (x, z), off by default] ─▶ negate
//! ```
//!
//! A reading is judged plausible once on its way: a sensor's sample by its
//! supervision ([`TiltPipeline`](crate::input::sensor::TiltPipeline)), which
//! must count a refused one as a fault; every other reading (keys, the
//! autopilot, a trace, a ghost) here, on entry. [`TiltConfig::plausibility`] says
//! which: [`TiltConfig::SENSOR`] takes the sensor's samples as judged.
//!
//! Nothing is clamped here: a believed reading keeps to ±[`MAX_READING_MG`]
//! per axis (`super::plausible`), so its gravity is within the physics'
//! largest pull as it is, and the world holds it to its level's own bound.
//!
//! # What reaches the physics
//!
//! Once the low-pass has settled, the gravity handed on is exactly the negated,
//! calibrated, filtered reading (rounded to the nearest mg): a board held still at
//! 10° (reading `(−174, 985, 0)`) rolls the marble at 5/7 · 174 mg = 1 219 mm/s²,
//! as a real one does (`tests/tilt_path.rs` measures this through the whole
//! session for 1° to 60°). Nothing is taken off small tilts.
//!
//! # Why no dead zone, and what holds a resting marble
//!
//! A near-level board must hold a resting marble still. That is the job of the
//! physics, not of the input: with the `friction` effect, rolling resistance has a
//! static threshold ([`crate::physics::dynamics::effects::Drag`]): a resting marble
//! stays put while the in-plane pull is at most `c_rr` times the normal one, i.e.
//! for tilts with `tan θ ≤ c_rr` — 10 mg (0.57°) at the default `c_rr` = 0.01, 15 mg
//! at grand-tour's 0.015. The low-pass (τ ≈ 7.5 samples by default) divides white
//! sensor noise's standard deviation by √(2^(k+1) − 1) ≈ 3.9, so the few-mg noise of
//! a MEMS accelerometer at rest stays under that threshold and the marble does not
//! creep (`tests/tilt_path.rs` feeds ±5 mg of noise). Without `friction` a marble on
//! a board 5 mg off level does roll, slowly — that is the physics of a frictionless
//! marble, and what calibration is for.
//!
//! A dead zone would have to be sized from the accelerometer's measured noise:
//! the LSM303AGR's noise density, or the micro:bit v2's reading noise at rest.
//! We have no sourced figure for either — we could not find an accelerometer
//! noise figure to cite for the LSM303AGR (ST datasheet DocID027765), and the
//! board's noise has not been measured (no micro:bit has run this firmware yet,
//! see docs/boards.md) — so the default width is 0: no dead zone, and no number made
//! up. The knob ([`TiltConfig::dead_zone_mg`]) stays for a board that proves
//! noisier once measured; it is a ramped zone that gives the input back
//! unchanged beyond twice its width (see there), never a bias on every reading.
//!
//! # Frames and signs
//!
//! Readings are in the **board frame** of [`crate::input::sensor`] (after its
//! [`AxisMap`](crate::input::sensor::AxisMap)): `x` right (grid columns), `y` up out of
//! the board, `z` towards the player (grid rows downwards). An accelerometer
//! reads the reaction to gravity, so a flat board reads `(0, +1000, 0)` and the
//! gravity handed to the physics is its negation, `(0, −1000, 0)` (down = −y).
//! A reading with `x < 0` gives gravity `x > 0`: the marble rolls towards `+x`;
//! likewise `z < 0` rolls it towards `+z` (the player). A board tilted by `θ`
//! towards `+x` reads `(−1000 sin θ, 1000 cos θ, 0)`.
//!
//! # Fit with [`crate::input::sensor`]
//!
//! The plausibility bounds are a [`Plausibility`], judged by the one rule
//! (`Plausibility::judge`) the sensor's
//! [`TiltPipeline`](crate::input::sensor::TiltPipeline) applies: a filter fed
//! the pipeline's samples ([`TiltConfig::SENSOR`]) judges them no more, one fed
//! anything else judges on entry, by the same rule; the "level" offset is a
//! [`Calibration`], applied here and nowhere else (a board's buttons and the keys send `Command::Calibrate` to the game). A
//! [`TiltError`] converts into a [`Fault`](crate::input::event::Fault) (`Stuck`
//! → `Fault::NoData`, the rest → `Fault::Implausible`), so a [`SensorSupervisor`](crate::input::sensor::SensorSupervisor)
//! over gravity can run the re-init / fault-display policy:
//! `supervisor.feed(filter.push(raw).map_err(Fault::from))`. Feed it raw
//! (uncalibrated) board-frame samples: the filter does its own calibration.
//!
//! # Cost
//!
//! Per sample: three comparisons per axis, three 32-bit multiplications (the
//! magnitude), shifts and adds. No division, no 64-bit arithmetic, no floats:
//! cheap on a Cortex-M0. Every operation is saturating or provably in range,
//! so no `i32` input can overflow or panic.

use super::axes::{AccelMg, Calibration};
pub use super::plausible::{Plausibility, TiltError, MAX_READING_MG};

/// The apparent gravity the tilt path hands the physics
/// (`Game::set_gravity_mg`), in milli-g, board frame: **not** a reading but
/// its negation, after the low-pass, the calibration and the dead zone. A
/// sensor reads the reaction to gravity ([`AccelMg`]: a level board reads
/// `(0, +1000, 0)`); the pull on the marble points the other way, down = −y,
/// so a level board gives [`GravityMg::LEVEL`], `(0, −1000, 0)`. Each axis
/// is within ±8 000 mg (a believed reading's ±[`MAX_READING_MG`] plus the
/// largest calibration offset): the physics' largest pull, taken without a
/// clamp. Only [`TiltFilter`] makes one from readings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GravityMg {
    /// X component (right), milli-g.
    pub x: i32,
    /// Y component (up out of the board), milli-g: about −1000 near level.
    pub y: i32,
    /// Z component (towards the player), milli-g.
    pub z: i32,
}

impl GravityMg {
    /// The pull on a level board: 1 g straight down.
    pub const LEVEL: Self = Self::new(0, -1000, 0);

    /// A pull from its three components (tools and tests that set the
    /// physics' gravity directly).
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self { x, y, z }
    }

    /// Its `[x, y, z]` components: the vector the physics' world takes.
    pub const fn to_array(self) -> [i32; 3] {
        [self.x, self.y, self.z]
    }
}

/// Fractional bits of the low-pass state (the state is mg · 2^12).
///
/// With the readings limited to ±[`MAX_READING_MG`], the state and any
/// difference of two states stay below 2^26, far from `i32` overflow.
const FRAC_BITS: u32 = 12;

/// The largest low-pass shift accepted ([`TiltConfig::filter_shift`] is
/// clamped to it): a time constant of about 32 767 samples.
pub(crate) const MAX_FILTER_SHIFT: u8 = 15;

/// Tuning of a [`TiltFilter`]. Every field is public; out-of-range values are
/// clamped (documented per field), never rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltConfig {
    /// Which readings are believed, judged on entry: `Some(bounds)` for
    /// readings nothing judged before (keys, the autopilot, traces, ghosts);
    /// `None` for a sensor's samples, which its supervision
    /// ([`TiltPipeline`](crate::input::sensor::TiltPipeline)) judged already
    /// with the same rule ([`TiltConfig::SENSOR`]): each reading is judged
    /// once. With `None` the readings must be believed ones, within
    /// ±[`MAX_READING_MG`] per axis (a pipeline's are). Default
    /// `Some(`[`Plausibility::DEFAULT`]`)`: per axis ±4000 mg (twice the
    /// firmware's ±2 g range, whose saturated readings, ±2048 at most, are
    /// therefore always accepted per axis), total 300..=3000 mg (a held toy
    /// feels about 1 g; beyond 3 g is a knock, not a tilt). `max_axis_mg` is
    /// capped at [`MAX_READING_MG`].
    pub plausibility: Option<Plausibility>,
    /// Low-pass shift `k`: each sample moves the state by 2^−k of the way to
    /// it. Time constant τ ≈ 2^k − ½ samples (exactly −1 / ln(1 − 2^−k));
    /// see [`TiltConfig::time_constant_us`]. Default 3: τ ≈ 7.5 samples =
    /// 75 ms at the firmware's 100 Hz, which smooths the sensor noise (a few
    /// mg) while the marble still answers a tilt within a tenth of a second.
    /// 0 disables the filter; clamped to `MAX_FILTER_SHIFT`.
    pub filter_shift: u8,
    /// Width `w` of an optional dead zone on the in-plane components (`x`,
    /// `z`) after filtering and calibration, mg. Per component `v`:
    ///
    /// ```text
    /// |v| ≤ w        out = 0
    /// w < |v| < 2w   out = sign(v) · 2(|v| − w)   (ramps back to the identity)
    /// |v| ≥ 2w       out = v                       (untouched)
    /// ```
    ///
    /// Continuous, odd, and off by at most `w` (at `|v| = w`); beyond `2w` the
    /// tilt reaches the physics unchanged. **Default 0: no dead zone** — a
    /// resting marble is held by rolling resistance's static threshold, and no
    /// sourced noise figure of the accelerometer justifies a width (see the
    /// module documentation). Capped at [`MAX_READING_MG`].
    pub dead_zone_mg: u32,
    /// Identical consecutive raw samples after which [`TiltError::Stuck`] is
    /// reported (that sample and the following identical ones are rejected).
    /// Default 50 (0.5 s at 100 Hz). Below 2 disables the check.
    pub stuck_samples: u16,
    /// The calibration in force at start (e.g. one restored from storage).
    /// Default [`Calibration::NONE`]. Offsets are clamped to
    /// ±[`Calibration::MAX_OFFSET_MG`].
    pub calibration: Calibration,
}

impl TiltConfig {
    /// The defaults (see each field).
    pub const DEFAULT: Self = Self {
        plausibility: Some(Plausibility::DEFAULT),
        filter_shift: 3,
        dead_zone_mg: 0,
        stuck_samples: 50,
        calibration: Calibration::NONE,
    };

    /// For a sensor's samples
    /// ([`TiltPipeline::tilt`](crate::input::sensor::TiltPipeline::tilt)):
    /// [`TiltConfig::DEFAULT`] but not judged again, since the pipeline's
    /// supervision judged them by the same rule and bounds
    /// ([`Plausibility::DEFAULT`]) and kept only believed ones.
    pub const SENSOR: Self = Self {
        plausibility: None,
        ..Self::DEFAULT
    };

    /// The low-pass time constant in µs for samples `sample_period_us`
    /// apart: (2^k − ½) · period, saturating. This is where the step
    /// response reaches 63 % (within one sample).
    pub const fn time_constant_us(&self, sample_period_us: u32) -> u32 {
        let k = clamp_shift(self.filter_shift);
        // (2^(k+1) − 1) · period / 2, without a division.
        let twice = (2u32 << k) - 1;
        twice.saturating_mul(sample_period_us) >> 1
    }
}

impl Default for TiltConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The tilt filter: plausibility and stuck-sensor rejection, a first-order
/// low-pass, "level" calibration and an optional dead zone.
///
/// Until its first accepted sample its gravity is level, `(0, −1000, 0)`; the
/// first accepted sample initialises the low-pass (no start-up transient).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltFilter {
    config: TiltConfig,
    calibration: Calibration,
    /// Low-pass state: filtered raw board-frame reading, mg · 2^FRAC_BITS.
    state: [i32; 3],
    primed: bool,
    last_raw: AccelMg,
    /// How many times `last_raw` came in a row (0: no sample yet).
    repeats: u16,
}

impl TiltFilter {
    /// A filter with `config`, level until its first good sample.
    pub const fn new(config: TiltConfig) -> Self {
        Self {
            config,
            calibration: clamp_calibration(config.calibration),
            state: [0, 1000 << FRAC_BITS, 0],
            primed: false,
            last_raw: AccelMg::new(0, 0, 0),
            repeats: 0,
        }
    }

    /// The configuration given to [`TiltFilter::new`].
    pub const fn config(&self) -> &TiltConfig {
        &self.config
    }

    /// Feeds one raw board-frame reading and returns the new gravity
    /// ([`GravityMg`]: down = −y, each axis within ±8 000 mg, the physics'
    /// `MAX_MG`).
    ///
    /// A rejected reading returns why and leaves the filter — and so
    /// [`TiltFilter::gravity_mg`], the last good gravity — unchanged (only the
    /// stuck detector notes it). Checks, first failure wins (the first three
    /// only when [`TiltConfig::plausibility`] judges on entry):
    /// [`TiltError::AllZero`], [`TiltError::OutOfRange`],
    /// [`TiltError::Magnitude`], [`TiltError::Stuck`].
    pub fn push(&mut self, reading: AccelMg) -> Result<GravityMg, TiltError> {
        let stuck = self.note_repeat(reading);
        if let Some(bounds) = self.config.plausibility {
            bounds.judge(reading)?;
        }
        let reading_mg = reading.to_array();
        if stuck {
            return Err(TiltError::Stuck);
        }
        if self.primed {
            let k = clamp_shift(self.config.filter_shift);
            for (s, &r) in self.state.iter_mut().zip(reading_mg.iter()) {
                *s = lowpass(*s, r << FRAC_BITS, k);
            }
        } else {
            // |r| ≤ MAX_READING_MG < 2^13 once judged (here or by the
            // sensor's supervision): the shift fits.
            self.state = reading_mg.map(|r| r << FRAC_BITS);
            self.primed = true;
        }
        Ok(self.gravity_mg())
    }

    /// The gravity to hand to `Game::set_gravity_mg` (board frame,
    /// down = −y): the negated filtered reading minus the calibration, with
    /// the dead zone (if any) on `x` and `z`; each axis within ±8 000 (a
    /// believed reading's ±[`MAX_READING_MG`] plus the largest calibration
    /// offset). Level, `(0, −1000, 0)`, until the first good sample.
    pub fn gravity_mg(&self) -> GravityMg {
        if !self.primed {
            return GravityMg::LEVEL;
        }
        let dz = (min_u32(self.config.dead_zone_mg, MAX_READING_MG) as i32) << FRAC_BITS;
        let c = self.calibration;
        // |state| < 2^26, |offset| ≤ 500 · 2^12: no overflow below.
        let x = dead_zone(self.state[0] - (c.offset_x << FRAC_BITS), dz);
        let z = dead_zone(self.state[2] - (c.offset_z << FRAC_BITS), dz);
        let [x, y, z] = [x, self.state[1], z].map(|v| -round_fx(v));
        GravityMg::new(x, y, z)
    }

    /// The low-pass output before calibration, dead zone and negation: the
    /// filtered raw board-frame reading, rounded to mg (`(0, 1000, 0)` before
    /// the first good sample). `f.calibrate(f.filtered_reading_mg())` levels
    /// the current, noise-free orientation.
    pub fn filtered_reading_mg(&self) -> AccelMg {
        AccelMg::from_array(self.state.map(round_fx))
    }

    /// Whether the last reading was (part of) a stuck run, i.e. whether the
    /// next identical reading will be rejected with [`TiltError::Stuck`].
    pub fn is_stuck(&self) -> bool {
        let n = self.config.stuck_samples;
        n >= 2 && self.repeats >= n
    }

    /// Makes the orientation that reads `current_reading` (raw board frame)
    /// "level": its in-plane components (`x`, `z`), each clamped to
    /// ±[`Calibration::MAX_OFFSET_MG`] (about 30°), become the offset
    /// subtracted from later filtered readings — exactly
    /// [`Calibration::from_reference`]. Afterwards that reading gives gravity
    /// `(0, −y, 0)`: the in-plane part is zero, `y` is kept (small-angle model;
    /// `|y|` is `cos(tilt)` · 1 g, e.g. 966 mg at 15°). A tilt beyond the clamp
    /// is only partly levelled. Replaces (does not stack on) the previous
    /// calibration and takes effect at once; the low-pass state and the stuck
    /// detector are untouched.
    ///
    /// An implausible reading is refused (the calibration unchanged), by the
    /// bounds of [`TiltConfig::plausibility`], or the sensor's
    /// ([`Plausibility::DEFAULT`]) when the readings come judged. Stuck runs
    /// are not checked here: pass a reading the filter accepted, or
    /// [`TiltFilter::filtered_reading_mg`].
    pub fn calibrate(&mut self, current_reading: AccelMg) -> Result<Calibration, TiltError> {
        let bounds = self.config.plausibility.unwrap_or(Plausibility::DEFAULT);
        bounds.judge(current_reading)?;
        self.calibration = Calibration::from_reference(current_reading);
        Ok(self.calibration)
    }

    /// The calibration in force (e.g. to store it).
    pub const fn calibration(&self) -> Calibration {
        self.calibration
    }

    /// Replaces the calibration (offsets clamped to
    /// ±[`Calibration::MAX_OFFSET_MG`]).
    pub fn set_calibration(&mut self, calibration: Calibration) {
        self.calibration = clamp_calibration(calibration);
    }

    /// Forgets the filtered state and the stuck detector (e.g. after a sensor
    /// re-init); keeps the calibration. Level until the next good sample.
    pub fn reset(&mut self) {
        *self = Self {
            calibration: self.calibration,
            ..Self::new(self.config)
        };
    }

    /// Counts `raw` in the run of identical readings; `true` if the run is
    /// now long enough to call the sensor stuck.
    fn note_repeat(&mut self, raw: AccelMg) -> bool {
        if self.repeats > 0 && raw == self.last_raw {
            self.repeats = self.repeats.saturating_add(1);
        } else {
            self.last_raw = raw;
            self.repeats = 1;
        }
        self.is_stuck()
    }
}

impl Default for TiltFilter {
    fn default() -> Self {
        Self::new(TiltConfig::DEFAULT)
    }
}

/// One step of the first-order IIR `s += (target − s) · 2^−k`, rounding the
/// step away from zero so that any nonzero difference moves the state: it
/// reaches `target` exactly (no dead band, no bias), from either side.
/// Operands are below 2^27 in magnitude, so nothing overflows.
fn lowpass(s: i32, target: i32, k: u32) -> i32 {
    let d = target - s;
    let mut step = d >> k; // floor: towards −∞
    if step == 0 && d > 0 {
        step = 1;
    }
    // For d < 0 the floor already gives at least −1.
    s + step
}

/// The ramped dead zone of [`TiltConfig::dead_zone_mg`] (fixed point, `dz ≥ 0`):
/// 0 for `|v| ≤ dz`, `sign(v) · 2(|v| − dz)` up to `2·dz`, `v` beyond. With
/// `|v| < 2^27` and `dz ≤ 16 000 · 2^12 < 2^26`, nothing overflows.
fn dead_zone(v: i32, dz: i32) -> i32 {
    let a = v.abs();
    if a >= 2 * dz {
        v
    } else if a <= dz {
        0
    } else {
        let out = 2 * (a - dz);
        if v < 0 {
            -out
        } else {
            out
        }
    }
}

/// Fixed point → mg, rounding half away from zero (symmetric in sign).
fn round_fx(v: i32) -> i32 {
    let half = 1u32 << (FRAC_BITS - 1);
    let m = ((v.unsigned_abs() + half) >> FRAC_BITS) as i32;
    if v < 0 {
        -m
    } else {
        m
    }
}

const fn clamp_shift(k: u8) -> u32 {
    if k > MAX_FILTER_SHIFT {
        MAX_FILTER_SHIFT as u32
    } else {
        k as u32
    }
}

const fn min_u32(a: u32, b: u32) -> u32 {
    if a < b {
        a
    } else {
        b
    }
}

const fn clamp_calibration(c: Calibration) -> Calibration {
    Calibration::from_reference(AccelMg::new(c.offset_x, 0, c.offset_z))
}
