//! The fault script (`--fault-script`, headless): one level played with a
//! scripted tilt through the virtual accelerometer — the driver, the
//! per-transfer timeout and the [`TiltPipeline`](marble_rolling::input::sensor::TiltPipeline)
//! of `sensor.rs` — while faults are injected at scripted times, checking
//! that each outage reaches the game as the player must see it:
//!
//! 1. the sensor delivers within 0.5 s of boot, and the game plays;
//! 2. for NAK (0.5 s), a stuck bus (0.5 s), frozen data (1 s), garbage
//!    (1 s): the sensor goes down for that reason (`Bus`, `Timeout`,
//!    `NoData`, `Implausible`) within 1 s → the game pauses (its frame count
//!    and state hash do not change while down) and the display gets the
//!    fault frame → the fault ends, the sensor comes back within 0.5 s → the
//!    game resumes where it paused;
//! 3. a chip reset (registers back to power-on): the supervisor re-initialises
//!    the chip within 1 s, without an outage, and samples flow again;
//! 4. throughout, every frame the game played equals, frame count and state
//!    hash, that of a reference [`Player`] run in the firmware itself with the
//!    same readings and no outage (pausing changes no bit of the game).
//!
//! Each expectation logs a line (`fault script: ok: …` / `FAILED: …`); the
//! run ends with one verdict line and the exit status: 0 only if every
//! expectation held. With `--no-copy-buffer` the virtual TWIM refuses the
//! driver's register reads (their `&[REG]` is in flash) and the sensor never
//! comes up: the script fails at its first expectation.
//!
//! The game loop here is `app::play`'s (events to [`Player::handle`], then
//! [`Player::tick`] with the latest tilt, the frame to the display), with the
//! checks between.

use embassy_time::{Duration, Ticker};

use marble_rolling::app::{Links, FRAME_HZ};
use marble_rolling::board::qemu::{HEIGHT, PLAY_TILT, WIDTH};
use marble_rolling::board::virtual_lsm303agr::{ChipControl, InjectedFault};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::event::InputEvent;
use marble_rolling::input::sensor::Fault;
use marble_rolling::matrix::Frame;
use marble_rolling::player::Player;
use marble_rolling::render::screens::fault_frame;

use crate::sensor::SensorReport;

/// The level played: "switchback" (no holes to fall in, 60 s).
const LEVEL: usize = 2;

/// Ticks (game frames) per second.
const T: u32 = FRAME_HZ;

/// The scripted tilt: this many ticks per step of [`TILTS`].
const TILT_STEP_TICKS: u32 = T / 2;

/// The scripted tilt's steps (x, z in milli-g), in a loop: the marble rolls
/// back and forth along the maze's first corridor.
const TILTS: [(i32, i32); 4] = [(-250, 0), (250, 60), (-250, -60), (250, 0)];

/// A game without the autopilot.
type ScriptPlayer = Player<'static, WIDTH, HEIGHT, false, { crate::EVENTS }>;

/// Firmware milliseconds of `ticks` game frames.
fn ms(ticks: u32) -> u32 {
    ticks.saturating_mul(1000) / T.max(1)
}

/// How the script ended.
#[derive(Clone, Copy, PartialEq, Eq, Debug, defmt::Format)]
pub struct Verdict {
    /// Expectations that held.
    pub held: u32,
    /// Expectations that failed.
    pub failed: u32,
}

impl Verdict {
    /// Every expectation held (and there was at least one).
    pub fn passed(&self) -> bool {
        self.failed == 0 && self.held > 0
    }
}

struct Script {
    links: &'static Links<WIDTH, HEIGHT>,
    chip: &'static ChipControl,
    report: &'static SensorReport,
    ticker: Ticker,
    player: ScriptPlayer,
    reference: ScriptPlayer,
    fault: Frame<WIDTH, HEIGHT>,
    tick: u32,
    /// The sensor is down (from the events the game got), and why.
    down: Option<Fault>,
    downs: u32,
    ups: u32,
    /// The game's frame count when it last heard `SensorUp`.
    up_at_frame: u32,
    /// Fault frames handed to the display since the last outage began.
    fault_frames: u32,
    paused_ticks: u32,
    /// Ticks where the game changed while the sensor was down.
    pause_violations: u32,
    /// Played ticks where the game differed from the reference run.
    mismatches: u32,
    held: u32,
    failed: u32,
    first_failure: Option<(&'static str, &'static str)>,
}

impl Script {
    fn frames(&self) -> u32 {
        self.player.game().frames()
    }

    fn hash(&self) -> u64 {
        self.player.session().state_hash()
    }

    fn matches_reference(&self) -> bool {
        self.reference.game().frames() == self.frames()
            && self.reference.session().state_hash() == self.hash()
    }

    /// Records one expectation.
    fn expect(&mut self, ok: bool, step: &'static str, what: &'static str) -> bool {
        if ok {
            self.held += 1;
            defmt::info!("fault script: ok: {=str}: {=str}", step, what);
        } else {
            self.failed += 1;
            self.first_failure.get_or_insert((step, what));
            defmt::error!("fault script: FAILED: {=str}: {=str}", step, what);
        }
        ok
    }

    /// One game frame: the scripted tilt, the events, the game's tick, and
    /// the checks of a paused or a played frame.
    async fn tick(&mut self) {
        self.ticker.next().await;
        if self.tick.is_multiple_of(TILT_STEP_TICKS) {
            let step = (self.tick / TILT_STEP_TICKS) as usize % TILTS.len();
            let (x, z) = TILTS[step];
            self.chip.set_tilt(AccelMg::from_xz(x, z));
        }
        self.tick = self.tick.wrapping_add(1);
        while let Ok(event) = self.links.events.try_receive() {
            match event {
                InputEvent::SensorDown(fault) => {
                    self.down = Some(fault);
                    self.downs += 1;
                    defmt::info!(
                        "fault script: t={=u32} ms: the game got SensorDown({}) at frame {=u32}",
                        ms(self.tick),
                        fault,
                        self.frames()
                    );
                }
                InputEvent::SensorUp => {
                    self.down = None;
                    self.ups += 1;
                    self.up_at_frame = self.frames();
                    defmt::info!(
                        "fault script: t={=u32} ms: the game got SensorUp at frame {=u32}",
                        ms(self.tick),
                        self.frames()
                    );
                }
                _ => {}
            }
            self.player.handle(event);
        }
        let reading = self.links.tilt.get();
        let before = (self.frames(), self.hash());
        let draw = !self.links.frames.signaled();
        let tick = self.player.tick(reading, draw);
        if let Some(frame) = tick.frame {
            if frame == self.fault {
                self.fault_frames += 1;
            }
            self.links.frames.signal(frame);
        }
        self.links.status.set(self.player.status());
        if self.down.is_some() {
            self.paused_ticks += 1;
            if (self.frames(), self.hash()) != before || self.player.sensor_down().is_none() {
                self.pause_violations += 1;
            }
        } else {
            // The reference plays exactly the frames the game played, with
            // the same readings, and never hears of the sensor.
            self.reference.tick(reading, false);
            if !self.matches_reference() {
                self.mismatches += 1;
            }
        }
    }

    async fn run_for(&mut self, ticks: u32) {
        for _ in 0..ticks {
            self.tick().await;
        }
    }

    /// Ticks until `done` holds (checked after each tick), at most `limit`;
    /// `None` if it never did.
    async fn wait_for(&mut self, limit: u32, done: impl Fn(&Script) -> bool) -> Option<u32> {
        for waited in 1..=limit {
            self.tick().await;
            if done(self) {
                return Some(waited);
            }
        }
        None
    }

    /// One outage: `fault` injected for `hold` ticks (at least), expected to
    /// bring the sensor down for `reason`.
    async fn outage(&mut self, fault: InjectedFault, reason: Fault, hold: u32) {
        let name = fault.name();
        let start = self.tick;
        let violations = self.pause_violations;
        self.fault_frames = 0;
        defmt::info!(
            "fault script: t={=u32} ms: inject {=str} for {=u32} ms (game at frame {=u32})",
            ms(self.tick),
            name,
            ms(hold),
            self.frames()
        );
        self.chip.inject(fault);
        let went_down = self.wait_for(T, |s| s.down.is_some()).await;
        if let Some(waited) = went_down {
            defmt::info!(
                "fault script: {=str}: down after {=u32} ms: {}",
                name,
                ms(waited),
                self.down
            );
        }
        self.expect(
            self.down == Some(reason),
            name,
            "the sensor goes down within 1 s, for the fault's reason",
        );
        let paused = (self.frames(), self.hash());
        while self.tick.wrapping_sub(start) < hold {
            self.tick().await;
        }
        defmt::info!(
            "fault script: {=str}: paused at frame {=u32}, state hash {=u64:016x}; after the hold: frame {=u32}, state hash {=u64:016x}",
            name,
            paused.0,
            paused.1,
            self.frames(),
            self.hash()
        );
        let still = self.down.is_some()
            && (self.frames(), self.hash()) == paused
            && self.pause_violations == violations;
        self.expect(
            still,
            name,
            "the game stays paused while the sensor is down (frame count and state hash unchanged)",
        );
        self.expect(
            self.fault_frames > 0,
            name,
            "the display gets the fault frame",
        );
        self.chip.inject(InjectedFault::Healthy);
        let came_up = self.wait_for(T / 2, |s| s.down.is_none()).await;
        if let Some(waited) = came_up {
            defmt::info!(
                "fault script: {=str}: up {=u32} ms after the fault ended",
                name,
                ms(waited)
            );
        }
        self.expect(
            came_up.is_some(),
            name,
            "the sensor comes back within 0.5 s of the fault's end",
        );
        let resumed_at = self.up_at_frame;
        let mismatches = self.mismatches;
        self.run_for(T / 4).await;
        defmt::info!(
            "fault script: {=str}: resumed from frame {=u32} to {=u32}, state hash {=u64:016x}, reference {=u64:016x}",
            name,
            resumed_at,
            self.frames(),
            self.hash(),
            self.reference.session().state_hash()
        );
        let resumed = came_up.is_some()
            && resumed_at == paused.0
            && self.frames() > resumed_at
            && self.mismatches == mismatches
            && self.matches_reference();
        self.expect(
            resumed,
            name,
            "the game resumes where it paused (state hash equal to the reference run's)",
        );
    }

    /// A chip reset: re-initialised by the supervisor, no outage.
    async fn chip_reset(&mut self) {
        let name = InjectedFault::ChipReset.name();
        let resets = self.chip.resets_applied();
        let reinits = self.report.reinits();
        let downs = self.downs;
        let frames = self.frames();
        defmt::info!(
            "fault script: t={=u32} ms: inject {=str} (game at frame {=u32})",
            ms(self.tick),
            name,
            frames
        );
        self.chip.inject(InjectedFault::ChipReset);
        let reinit = self
            .wait_for(T, |s| {
                s.chip.resets_applied() > resets && s.report.reinits() > reinits
            })
            .await;
        let samples = self.report.samples();
        let flowing = match reinit {
            Some(_) => self.wait_for(T / 2, |s| s.report.samples() > samples).await,
            None => None,
        };
        if let (Some(reinit), Some(flowing)) = (reinit, flowing) {
            defmt::info!(
                "fault script: {=str}: re-initialised {=u32} ms after the reset, samples again {=u32} ms later",
                name,
                ms(reinit),
                ms(flowing)
            );
        }
        self.expect(
            flowing.is_some(),
            name,
            "the chip lost its configuration, the supervisor re-initialised it within 1 s, samples flow again",
        );
        self.run_for(T / 4).await;
        self.expect(
            self.downs == downs && self.down.is_none() && self.frames() > frames,
            name,
            "no outage: the game kept playing",
        );
    }

    /// The run's end: totals, the verdict line.
    fn finish(&mut self) -> Verdict {
        defmt::info!(
            "fault script: {=u32} ticks: {=u32} frames played, {=u32} paused; {=u32} downs, {=u32} ups; {=u32} sensor (re)inits, {=u32} failed; state hash {=u64:016x}, reference {=u64:016x}; bus: {=u32} transfers, {=u32} refused by the DMA rule",
            self.tick,
            self.frames(),
            self.paused_ticks,
            self.downs,
            self.ups,
            self.report.reinits(),
            self.report.failed_reinits(),
            self.hash(),
            self.reference.session().state_hash(),
            self.chip.transfers(),
            self.chip.refused()
        );
        let verdict = Verdict {
            held: self.held,
            failed: self.failed,
        };
        match self.first_failure {
            None if verdict.passed() => defmt::info!(
                "fault script verdict: PASS ({=u32} of {=u32} expectations held)",
                verdict.held,
                verdict.held + verdict.failed
            ),
            None => defmt::error!("fault script verdict: FAIL (no expectation checked)"),
            Some((step, what)) => defmt::error!(
                "fault script verdict: FAIL ({=u32} of {=u32} expectations failed; first: {=str}: {=str})",
                verdict.failed,
                verdict.held + verdict.failed,
                step,
                what
            ),
        }
        verdict
    }
}

/// Runs the script (see the module doc); `copy_buffer` is the virtual
/// TWIM's, for the log.
pub async fn run(
    links: &'static Links<WIDTH, HEIGHT>,
    chip: &'static ChipControl,
    report: &'static SensorReport,
    copy_buffer: usize,
) -> Verdict {
    let new = || ScriptPlayer::new(&LEVELS, LEVEL, PLAY_TILT, false);
    let (player, reference) = match (new(), new()) {
        (Ok(player), Ok(reference)) => (player, reference),
        _ => {
            defmt::error!("fault script verdict: FAIL (cannot set up the level)");
            return Verdict { held: 0, failed: 1 };
        }
    };
    defmt::info!(
        "fault script: level {=str}, scripted tilt through the virtual LSM303AGR (TWIM copy buffer {=usize} bytes)",
        player.level_name(),
        copy_buffer
    );
    let mut script = Script {
        links,
        chip,
        report,
        ticker: Ticker::every(Duration::from_hz(u64::from(FRAME_HZ))),
        player,
        reference,
        fault: fault_frame(),
        tick: 0,
        down: None,
        downs: 0,
        ups: 0,
        up_at_frame: 0,
        fault_frames: 0,
        paused_ticks: 0,
        pause_violations: 0,
        mismatches: 0,
        held: 0,
        failed: 0,
        first_failure: None,
    };

    let start = "start";
    let up = script.wait_for(T / 2, |s| s.report.samples() > 0).await;
    if !script.expect(
        up.is_some() && script.down.is_none(),
        start,
        "the sensor delivers samples within 0.5 s of boot",
    ) {
        defmt::error!(
            "fault script: the sensor never came up ({=u32} transfers refused by the DMA rule, TWIM copy buffer {=usize} bytes): the rest is skipped",
            chip.refused(),
            copy_buffer
        );
        return script.finish();
    }
    let frames = script.frames();
    script.run_for(T).await;
    script.expect(
        script.frames() == frames + T && script.downs == 0 && script.matches_reference(),
        start,
        "healthy: the game plays every frame, as the reference run",
    );

    script.outage(InjectedFault::Nak, Fault::Bus, T / 2).await;
    script.run_for(T / 2).await;
    script
        .outage(InjectedFault::StuckBus, Fault::Timeout, T / 2)
        .await;
    script.run_for(T / 2).await;
    script.chip_reset().await;
    script.run_for(T / 2).await;
    script
        .outage(InjectedFault::FrozenData, Fault::NoData, T)
        .await;
    script.run_for(T / 2).await;
    script
        .outage(InjectedFault::Garbage, Fault::Implausible, T)
        .await;
    script.run_for(T / 2).await;

    let end = "end";
    script.expect(
        script.pause_violations == 0,
        end,
        "while the sensor was down the game never stepped",
    );
    script.expect(
        script.mismatches == 0 && script.matches_reference(),
        end,
        "every frame played equals the reference run's (frame count, state hash)",
    );
    script.expect(
        script.downs == 4 && script.ups == 4 && script.down.is_none(),
        end,
        "four outages, each reported down and up exactly once",
    );
    script.finish()
}
