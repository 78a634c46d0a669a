//! Board-agnostic accelerometer plumbing: axis remapping, plausibility checks,
//! the "level" offset arithmetic and the fault-supervision policy.
//!
//! Everything here is pure (no I/O, no time source, no allocation, no panics)
//! so that the policy a real board depends on is the code the host tests run:
//! a board polls its sensor once a period and hands the outcome ([`Read`]: a
//! sample, "no new sample yet", or a fault) to a [`TiltPipeline`], which maps
//! the axes, checks plausibility, supervises, and says what to do next
//! ([`Action`]) and whether the sensor just went down or came back
//! ([`Transition`]). The board forwards; it keeps no state of its own about
//! the sensor's health, so the game and the tests see one story.
//!
//! # "Not ready yet" is not a fault
//!
//! A poll may find no new sample for harmless reasons: the poll came a little
//! early, or the sensor was just re-initialised. Counting that as a failure
//! would turn poll-timing jitter into spurious re-inits and fault pictures, so the
//! supervisor tolerates [`SupervisorConfig::not_ready_before_fault`] − 1
//! not-ready polls in a row uncounted; only data missing for longer is
//! [`Fault::NoData`].
//!
//! # One calibration
//!
//! The pipeline does not calibrate: the game's tilt filter
//! ([`crate::input::tilt::TiltFilter`]) does, on [`Command::Calibrate`]
//! (e.g. the micro:bit's A+B hold). Two calibrations in series would stack their
//! offsets, and only the filter knows the filtered reading the player sees as
//! "level". [`Calibration`] is the offset arithmetic on board-frame samples
//! ([`super::axes`]), which the filter applies.
//!
//! [`Command::Calibrate`]: crate::input::event::Command::Calibrate

pub use super::axes::{AccelMg, Axis, AxisMap, AxisSource, Calibration};
pub use super::event::Fault;
use super::event::InputEvent;
pub use super::plausible::Plausibility;

/// The outcome of one poll of the sensor, in the sensor's frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Read<S> {
    /// A new sample.
    Sample(S),
    /// The sensor answered, but has no new sample since the last one: not a
    /// fault by itself (see the module doc).
    NotReady,
    /// The poll failed.
    Failed(Fault),
}

impl<S> From<Result<S, Fault>> for Read<S> {
    fn from(read: Result<S, Fault>) -> Self {
        match read {
            Ok(sample) => Read::Sample(sample),
            Err(fault) => Read::Failed(fault),
        }
    }
}

/// What the caller should do after feeding the supervisor.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Action<S> {
    /// A good sample: use it.
    Use(S),
    /// Transient failure, or no new sample yet: keep using the last good
    /// sample (given here).
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

/// Tuning of a [`SensorSupervisor`], in polls (one per sampling period).
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
    /// The n-th not-ready poll in a row is the first to count as a
    /// [`Fault::NoData`] failure (≥ 1; every later one in the streak counts
    /// too). Choose it so that n polls span several of the sensor's sample
    /// periods: fewer not-ready polls are taken as "not yet", uncounted.
    pub not_ready_before_fault: u16,
}

impl SupervisorConfig {
    /// Defaults for a ~100 Hz poll of a sensor sampling at least as fast:
    /// re-init after 50 ms of failures, fault shown after 3 failed re-inits
    /// (~0.2 s), retry twice a second; no new sample for 3 polls in a row
    /// (~30 ms) is a fault.
    pub const DEFAULT: Self = Self {
        failures_before_reinit: 5,
        reinits_before_fault: 3,
        retry_period_when_down: 50,
        not_ready_before_fault: 3,
    };
}

impl Default for SupervisorConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The sensor-fault policy: keep the last good sample through transient
/// errors and not-ready polls, re-initialise after repeated failures, declare
/// the sensor down if that does not help, and recover by itself on the next
/// good sample.
///
/// Feed it once per sampling period with the poll's outcome; it never panics
/// and its counters saturate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorSupervisor<S> {
    config: SupervisorConfig,
    plausibility: Plausibility,
    last_good: S,
    consecutive_failures: u16,
    not_ready_streak: u16,
    reinits: u8,
    /// `Some(fault that brought it down)` while down.
    down: Option<Fault>,
    last_fault: Option<Fault>,
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
            not_ready_streak: 0,
            reinits: 0,
            down: None,
            last_fault: None,
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
        self.down.is_some()
    }

    /// While down, the fault of the failure that brought the sensor down.
    pub const fn down_fault(&self) -> Option<Fault> {
        self.down
    }

    /// The most recent failure (of a read or a re-init), for diagnostics.
    pub const fn last_fault(&self) -> Option<Fault> {
        self.last_fault
    }

    /// Failures so far (saturating), for diagnostics. Not-ready polls count
    /// only once they are [`Fault::NoData`].
    pub const fn total_faults(&self) -> u32 {
        self.total_faults
    }

    /// Feeds the outcome of one completed read.
    pub(crate) fn feed(&mut self, read: Result<S, Fault>) -> Action<S> {
        self.not_ready_streak = 0;
        match read {
            Ok(sample) => {
                self.last_good = sample;
                self.consecutive_failures = 0;
                self.reinits = 0;
                self.down = None;
                self.since_retry = 0;
                Action::Use(sample)
            }
            Err(fault) => self.failure(fault),
        }
    }

    /// Feeds a poll that found no new sample. Uncounted ([`Action::KeepLast`],
    /// or [`Action::ShowFault`] while down) until
    /// [`SupervisorConfig::not_ready_before_fault`] such polls in a row; from
    /// then on each is a [`Fault::NoData`] failure.
    pub fn not_ready(&mut self) -> Action<S> {
        self.not_ready_streak = self.not_ready_streak.saturating_add(1);
        if self.not_ready_streak >= self.config.not_ready_before_fault.max(1) {
            return self.failure(Fault::NoData);
        }
        if self.down.is_some() {
            Action::ShowFault
        } else {
            Action::KeepLast(self.last_good)
        }
    }

    /// Feeds one poll's outcome (no plausibility check: see
    /// [`SensorSupervisor::check`] for samples that need one).
    pub fn poll(&mut self, read: Read<S>) -> Action<S> {
        match read {
            Read::Sample(sample) => self.feed(Ok(sample)),
            Read::NotReady => self.not_ready(),
            Read::Failed(fault) => self.feed(Err(fault)),
        }
    }

    fn failure(&mut self, fault: Fault) -> Action<S> {
        self.total_faults = self.total_faults.saturating_add(1);
        self.last_fault = Some(fault);
        if self.down.is_some() {
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
            self.down = Some(fault);
            self.since_retry = 0;
            return Action::ShowFault;
        }
        self.reinits = self.reinits.saturating_add(1);
        Action::Reinit
    }

    /// Reports the outcome of a re-init asked for by [`Action::Reinit`].
    /// A failed re-init counts as a full window of failures, so the next
    /// failed read escalates at once. Either way the not-ready streak starts
    /// over: a freshly configured sensor needs a moment for its first sample.
    pub fn reinit_done(&mut self, outcome: Result<(), Fault>) {
        self.not_ready_streak = 0;
        match outcome {
            Ok(()) => self.consecutive_failures = 0,
            Err(fault) => {
                self.total_faults = self.total_faults.saturating_add(1);
                self.last_fault = Some(fault);
                if self.down.is_none() {
                    self.consecutive_failures =
                        self.config.failures_before_reinit.max(1).saturating_sub(1);
                }
            }
        }
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

/// The sensor went down or came back: what the game must hear about once.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Transition {
    /// The supervisor gave up on the sensor, because of this fault.
    Down(Fault),
    /// A good sample after being down.
    Up,
}

impl Transition {
    /// The input event that tells the game.
    pub const fn event(self) -> InputEvent {
        match self {
            Transition::Down(fault) => InputEvent::SensorDown(fault),
            Transition::Up => InputEvent::SensorUp,
        }
    }
}

/// What one [`TiltPipeline::feed`] says.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Step {
    /// What to do now. `Use` and `KeepLast` carry the board-frame tilt.
    pub action: Action<AccelMg>,
    /// The sensor went down or came back with this poll.
    pub transition: Option<Transition>,
}

/// The whole tilt path of a board with an accelerometer, minus the I/O:
/// sensor-frame poll → [`AxisMap`] → plausibility → [`SensorSupervisor`] →
/// board-frame tilt and down/up [`Transition`]s.
///
/// Samples come out uncalibrated: the game's tilt filter calibrates (see the
/// module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TiltPipeline {
    map: AxisMap,
    supervisor: SensorSupervisor<AccelMg>,
    /// Whether the last transition reported was `Down`.
    reported_down: bool,
}

impl TiltPipeline {
    /// Starts level and up, with no sample seen yet.
    pub const fn new(map: AxisMap, config: SupervisorConfig) -> Self {
        Self {
            map,
            supervisor: SensorSupervisor::new(AccelMg::LEVEL, config),
            reported_down: false,
        }
    }

    /// Feeds one poll in the **sensor** frame. Each down and up of the
    /// sensor comes out exactly once, as [`Step::transition`]; for `Reinit`
    /// and `ShowFault` keep using [`TiltPipeline::tilt`].
    pub fn feed(&mut self, read: Read<AccelMg>) -> Step {
        let action = match read {
            Read::Sample(raw) => self.supervisor.check(Ok(self.map.apply(raw))),
            Read::NotReady => self.supervisor.not_ready(),
            Read::Failed(fault) => self.supervisor.check(Err(fault)),
        };
        let transition = match (self.reported_down, self.supervisor.down_fault()) {
            (false, Some(fault)) => Some(Transition::Down(fault)),
            (true, None) => Some(Transition::Up),
            _ => None,
        };
        if transition.is_some() {
            self.reported_down = !self.reported_down;
        }
        Step { action, transition }
    }

    /// Reports the outcome of a re-init asked for by [`Action::Reinit`].
    pub fn reinit_done(&mut self, outcome: Result<(), Fault>) {
        self.supervisor.reinit_done(outcome);
    }

    /// The board-frame tilt to use now: the last good sample (level until
    /// the first one).
    pub const fn tilt(&self) -> AccelMg {
        self.supervisor.last_good()
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
