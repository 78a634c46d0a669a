//! Board-agnostic accelerometer plumbing: axis remapping, plausibility checks,
//! "level" calibration and the fault-supervision policy.
//!
//! Everything here is pure (no I/O, no time source, no allocation, no panics):
//! a board reads its sensor, maps the axes with its [`AxisMap`], and feeds the
//! result to a [`SensorSupervisor`], which says what to do next
//! ([`Action`]). The host tests drive the same code the firmware runs.
//!
//! # Board frame
//!
//! Samples handed to the game are in milli-g in the **board frame**: `x` to
//! the right, `y` up out of the display, `z` towards the player. The sensor
//! reports the reaction to gravity, so a board lying flat reads
//! `(0, +1000, 0)`, and tilting the right edge down (the marble rolls towards
//! `+x`) makes `x` negative.

/// One accelerometer sample in milli-g (1000 = 1 g).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AccelMg {
    /// X component, milli-g.
    pub x: i32,
    /// Y component, milli-g.
    pub y: i32,
    /// Z component, milli-g.
    pub z: i32,
}

impl AccelMg {
    /// A sample from its three components.
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self { x, y, z }
    }

    /// What a board lying flat and still reads in the board frame.
    pub const LEVEL: Self = Self::new(0, 1000, 0);

    /// Squared magnitude in mg², saturating (never overflows).
    pub const fn magnitude_sq(&self) -> u64 {
        let x = self.x.unsigned_abs() as u64;
        let y = self.y.unsigned_abs() as u64;
        let z = self.z.unsigned_abs() as u64;
        // Each term is at most 2^62, so the sum of three cannot overflow.
        x * x + y * y + z * z
    }
}

/// One of the sensor's three axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// Sensor X.
    X,
    /// Sensor Y.
    Y,
    /// Sensor Z.
    Z,
}

/// Where one board axis comes from: a sensor axis, possibly negated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisSource {
    /// The sensor axis read.
    pub axis: Axis,
    /// Whether its value is negated.
    pub negate: bool,
}

impl AxisSource {
    /// `+axis`.
    pub const fn pos(axis: Axis) -> Self {
        Self {
            axis,
            negate: false,
        }
    }

    /// `-axis`.
    pub const fn neg(axis: Axis) -> Self {
        Self { axis, negate: true }
    }

    const fn pick(&self, raw: AccelMg) -> i32 {
        let v = match self.axis {
            Axis::X => raw.x,
            Axis::Y => raw.y,
            Axis::Z => raw.z,
        };
        if self.negate {
            v.saturating_neg()
        } else {
            v
        }
    }
}

/// How a sensor is mounted: for each board axis (x, y, z), which sensor axis
/// and sign feed it. One table per board, easy to correct on the bench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisMap {
    /// Source of board `x` (right).
    pub x: AxisSource,
    /// Source of board `y` (up, out of the display).
    pub y: AxisSource,
    /// Source of board `z` (towards the player).
    pub z: AxisSource,
}

impl AxisMap {
    /// The sensor frame already is the board frame.
    pub const IDENTITY: Self = Self {
        x: AxisSource::pos(Axis::X),
        y: AxisSource::pos(Axis::Y),
        z: AxisSource::pos(Axis::Z),
    };

    /// A sensor sample expressed in the board frame.
    pub const fn apply(&self, raw: AccelMg) -> AccelMg {
        AccelMg {
            x: self.x.pick(raw),
            y: self.y.pick(raw),
            z: self.z.pick(raw),
        }
    }

    /// Whether every sensor axis is used exactly once (a permutation with
    /// signs). A table failing this is a typo.
    pub const fn is_permutation(&self) -> bool {
        let a = self.x.axis as u8;
        let b = self.y.axis as u8;
        let c = self.z.axis as u8;
        a != b && b != c && a != c
    }
}

/// Bounds a sample must lie within to be believed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Plausibility {
    /// Largest believable magnitude of any single axis, mg.
    pub max_axis_mg: u32,
    /// Smallest believable total magnitude, mg. A still or hand-held board
    /// always feels about 1 g; an all-zero reading is a sensor that lost its
    /// configuration (or free fall, when tilt means nothing anyway).
    pub min_total_mg: u32,
    /// Largest believable total magnitude, mg (beyond it: a knock or garbage).
    pub max_total_mg: u32,
}

impl Plausibility {
    /// Defaults for a hand-held toy on a ±2 g (or wider) range.
    pub const DEFAULT: Self = Self {
        max_axis_mg: 4_000,
        min_total_mg: 300,
        max_total_mg: 3_000,
    };

    /// Whether `s` is believable.
    pub const fn check(&self, s: AccelMg) -> bool {
        let max_axis = self.max_axis_mg;
        if s.x.unsigned_abs() > max_axis
            || s.y.unsigned_abs() > max_axis
            || s.z.unsigned_abs() > max_axis
        {
            return false;
        }
        let m = s.magnitude_sq();
        let lo = self.min_total_mg as u64;
        let hi = self.max_total_mg as u64;
        m >= lo * lo && m <= hi * hi
    }
}

impl Default for Plausibility {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// "This orientation is level": the offset subtracted from later samples.
///
/// Small-angle model: the horizontal components (`x`, `z`) of the reference
/// sample are subtracted, `y` is kept. Exact for the tilt directions and
/// accurate to a few percent for reference tilts up to ~15°, which is what a
/// player calibrating "roughly flat" produces. The offset is clamped to
/// ±[`Calibration::MAX_OFFSET_MG`] so that calibrating while holding the board
/// on its side cannot make the game unplayable.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration {
    /// Offset subtracted from `x`, mg.
    pub offset_x: i32,
    /// Offset subtracted from `z`, mg.
    pub offset_z: i32,
}

impl Calibration {
    /// Largest offset accepted (about 30° of tilt).
    pub const MAX_OFFSET_MG: i32 = 500;

    /// No correction.
    pub const NONE: Self = Self {
        offset_x: 0,
        offset_z: 0,
    };

    /// The calibration that makes `reference` (a board-frame sample) level.
    pub const fn from_reference(reference: AccelMg) -> Self {
        Self {
            offset_x: clamp_i32(reference.x, Self::MAX_OFFSET_MG),
            offset_z: clamp_i32(reference.z, Self::MAX_OFFSET_MG),
        }
    }

    /// `s` corrected (saturating).
    pub const fn apply(&self, s: AccelMg) -> AccelMg {
        AccelMg {
            x: s.x.saturating_sub(self.offset_x),
            y: s.y,
            z: s.z.saturating_sub(self.offset_z),
        }
    }
}

const fn clamp_i32(v: i32, limit: i32) -> i32 {
    if v > limit {
        limit
    } else if v < -limit {
        -limit
    } else {
        v
    }
}

/// Why a read produced no usable sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fault {
    /// The bus transfer failed (NACK, arbitration loss, timeout, …).
    Bus,
    /// The sensor answered but had no new data for longer than expected.
    NoData,
    /// The sample failed the [`Plausibility`] check.
    Implausible,
}

/// What the caller should do after feeding the supervisor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Action<S> {
    /// A good sample: use it.
    Use(S),
    /// Transient failure: keep using the last good sample (given here).
    KeepLast(S),
    /// Too many failures in a row: re-initialise the sensor, then report the
    /// outcome with [`SensorSupervisor::reinit_done`]. Keep the last good
    /// sample meanwhile.
    Reinit,
    /// The sensor stays down: show the fault pattern (keep the last good
    /// sample). The supervisor keeps asking for a [`Action::Reinit`] now and
    /// then and leaves this state on the first good sample.
    ShowFault,
}

/// Tuning of a [`SensorSupervisor`], in calls to [`SensorSupervisor::feed`]
/// (one per sampling period).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SupervisorConfig {
    /// Consecutive failed reads tolerated before asking for a re-init (≥ 1).
    pub failures_before_reinit: u16,
    /// Re-inits tried without a good sample in between before declaring the
    /// sensor down (≥ 0).
    pub reinits_before_fault: u8,
    /// While down, ask for a re-init every this many failed reads (≥ 1).
    pub retry_period_when_down: u16,
}

impl SupervisorConfig {
    /// Defaults for a ~100 Hz sampling loop: re-init after 50 ms of failures,
    /// fault shown after 3 failed re-inits (~0.2 s), retry twice a second.
    pub const DEFAULT: Self = Self {
        failures_before_reinit: 5,
        reinits_before_fault: 3,
        retry_period_when_down: 50,
    };
}

impl Default for SupervisorConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The sensor-fault policy: keep the last good sample through transient
/// errors, re-initialise after repeated ones, declare a fault if that does not
/// help, and recover by itself on the next good sample.
///
/// Feed it once per sampling period with the read's outcome; it never panics
/// and its counters saturate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorSupervisor<S> {
    config: SupervisorConfig,
    plausibility: Plausibility,
    last_good: S,
    consecutive_failures: u16,
    reinits: u8,
    down: bool,
    since_retry: u16,
    total_faults: u32,
}

impl<S: Copy> SensorSupervisor<S> {
    /// A supervisor whose "last good" sample starts as `initial` (e.g. level).
    pub const fn new(initial: S, config: SupervisorConfig) -> Self {
        Self {
            config,
            plausibility: Plausibility::DEFAULT,
            last_good: initial,
            consecutive_failures: 0,
            reinits: 0,
            down: false,
            since_retry: 0,
            total_faults: 0,
        }
    }

    /// The last good sample (or the initial one).
    pub const fn last_good(&self) -> S {
        self.last_good
    }

    /// Whether the sensor is considered down (fault pattern showing).
    pub const fn is_down(&self) -> bool {
        self.down
    }

    /// Failed reads so far (saturating), for diagnostics.
    pub const fn total_faults(&self) -> u32 {
        self.total_faults
    }

    /// Feeds the outcome of one read.
    pub fn feed(&mut self, read: Result<S, Fault>) -> Action<S> {
        match read {
            Ok(sample) => {
                self.last_good = sample;
                self.consecutive_failures = 0;
                self.reinits = 0;
                self.down = false;
                self.since_retry = 0;
                Action::Use(sample)
            }
            Err(_) => self.failure(),
        }
    }

    fn failure(&mut self) -> Action<S> {
        self.total_faults = self.total_faults.saturating_add(1);
        if self.down {
            self.since_retry = self.since_retry.saturating_add(1);
            if self.since_retry >= self.config.retry_period_when_down.max(1) {
                self.since_retry = 0;
                return Action::Reinit;
            }
            return Action::ShowFault;
        }
        self.consecutive_failures = self.consecutive_failures.saturating_add(1);
        if self.consecutive_failures < self.config.failures_before_reinit.max(1) {
            return Action::KeepLast(self.last_good);
        }
        self.consecutive_failures = 0;
        if self.reinits >= self.config.reinits_before_fault {
            self.down = true;
            self.since_retry = 0;
            return Action::ShowFault;
        }
        self.reinits = self.reinits.saturating_add(1);
        Action::Reinit
    }

    /// Reports the outcome of a re-init asked for by [`Action::Reinit`].
    /// A failed re-init counts as a full window of failures, so the next
    /// failed read escalates at once.
    pub fn reinit_done(&mut self, outcome: Result<(), Fault>) {
        match outcome {
            Ok(()) => self.consecutive_failures = 0,
            Err(_) => {
                self.total_faults = self.total_faults.saturating_add(1);
                if !self.down {
                    self.consecutive_failures =
                        self.config.failures_before_reinit.max(1).saturating_sub(1);
                }
            }
        }
    }
}

impl<S: Copy> SensorSupervisor<S> {
    /// Replaces the plausibility bounds used by [`SensorSupervisor::check`].
    pub const fn with_plausibility(mut self, plausibility: Plausibility) -> Self {
        self.plausibility = plausibility;
        self
    }
}

impl SensorSupervisor<AccelMg> {
    /// Feeds a raw read after the plausibility check (an implausible sample
    /// becomes [`Fault::Implausible`]).
    pub fn check(&mut self, read: Result<AccelMg, Fault>) -> Action<AccelMg> {
        let checked = match read {
            Ok(s) if self.plausibility.check(s) => Ok(s),
            Ok(_) => Err(Fault::Implausible),
            Err(e) => Err(e),
        };
        self.feed(checked)
    }
}

/// The whole tilt path of a board with an accelerometer, minus the I/O:
/// sensor-frame read → [`AxisMap`] → plausibility → [`SensorSupervisor`] →
/// [`Calibration`].
///
/// The supervisor keeps *uncalibrated* board-frame samples, so calibrating
/// again replaces the offset rather than stacking it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltPipeline {
    map: AxisMap,
    calibration: Calibration,
    supervisor: SensorSupervisor<AccelMg>,
    seen_good: bool,
}

impl TiltPipeline {
    /// Starts level, uncalibrated, with no good sample seen yet.
    pub const fn new(map: AxisMap, config: SupervisorConfig) -> Self {
        Self {
            map,
            calibration: Calibration::NONE,
            supervisor: SensorSupervisor::new(AccelMg::LEVEL, config),
            seen_good: false,
        }
    }

    /// Feeds one read in the **sensor** frame. `Use` and `KeepLast` carry the
    /// calibrated board-frame tilt to use; for `Reinit` and `ShowFault` keep
    /// using [`TiltPipeline::tilt`].
    pub fn feed(&mut self, read: Result<AccelMg, Fault>) -> Action<AccelMg> {
        let action = self.supervisor.check(read.map(|raw| self.map.apply(raw)));
        match action {
            Action::Use(s) => {
                self.seen_good = true;
                Action::Use(self.calibration.apply(s))
            }
            Action::KeepLast(s) => Action::KeepLast(self.calibration.apply(s)),
            other => other,
        }
    }

    /// Reports the outcome of a re-init asked for by [`Action::Reinit`].
    pub fn reinit_done(&mut self, outcome: Result<(), Fault>) {
        self.supervisor.reinit_done(outcome);
    }

    /// The calibrated board-frame tilt to use now (level until the first
    /// good sample).
    pub fn tilt(&self) -> AccelMg {
        self.calibration.apply(self.supervisor.last_good())
    }

    /// Makes the current orientation "level". Refused (returns `false`, the
    /// calibration unchanged) while no good sample has been seen or the sensor
    /// is down.
    pub fn calibrate(&mut self) -> bool {
        if !self.seen_good || self.supervisor.is_down() {
            return false;
        }
        self.calibration = Calibration::from_reference(self.supervisor.last_good());
        true
    }

    /// The calibration in force.
    pub const fn calibration(&self) -> Calibration {
        self.calibration
    }

    /// Whether the sensor is considered down.
    pub const fn is_down(&self) -> bool {
        self.supervisor.is_down()
    }

    /// The supervisor, for diagnostics.
    pub const fn supervisor(&self) -> &SensorSupervisor<AccelMg> {
        &self.supervisor
    }
}
