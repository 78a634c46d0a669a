//! One player's game as the firmware and the terminal player run it: a
//! [`Session`] on a level, the [`Renderer`] that follows the marble, the
//! autopilot when it plays, and the game loop's own state — the pause that
//! shows a finished attempt, and the pause while the sensor is down.
//!
//! [`Player::tick`] is one frame of that loop, synchronous and free of
//! time: the firmware's game task calls it from its ticker, host tests call
//! it frame by frame, and `cargo play` calls it from its terminal loop, so
//! all three play the same game for the same inputs.
//!
//! # A downed sensor pauses the game
//!
//! While the accelerometer is down ([`InputEvent::SensorDown`]) nothing
//! moves: no physics step, no frame on the level clock, no countdown of a
//! win or loss display, and the display shows [`fault_frame`]. The tilt the
//! game last had is not trusted any more, and letting the marble roll on it
//! behind the fault picture would let it win or fall unseen. When the sensor
//! is back ([`InputEvent::SensorUp`]) the game goes on from the very state it
//! paused in: pausing changes no bit of the session.
//!
//! The player is a floor of its own, above the game, the picture
//! ([`crate::render`]) and the sounds ([`crate::sound`]) it drives: those
//! read the game's levels and rules, and only the player takes all three
//! (docs/architecture.md, tests/layers.rs).

pub mod power_on;
pub mod race;
mod status;

#[cfg(feature = "storey-maps")]
pub use status::MarbleSpot;
pub use status::Status;

use crate::game::autopilot::Autopilot;
use crate::game::level::LevelView;
use crate::game::rules::{Game, GameConfig, Phase};
use crate::game::session::Session;
use crate::input::axes::AccelMg;
use crate::input::event::{Command, Fault, InputEvent};
use crate::input::sensor::Calibration;
use crate::input::tilt::TiltConfig;
use crate::matrix::Frame;
use crate::physics::world::SetupError;
use crate::physics::Fx;
use crate::render::screens::{fault_frame, record_frame, win_frame};
use crate::render::Renderer;
use crate::sound::{self, Sounds};

/// Game frames per second, whatever the stepper ([`Player::CONFIG`]: both
/// configurations run at the same frame rate).
pub const FRAME_HZ: u32 = GameConfig::DEFAULT.frame_hz();
const _: () = assert!(GameConfig::EVENTS.frame_hz() == FRAME_HZ);
/// How long a won level is shown (flashing) before the next one, in frames.
pub const WIN_PAUSE_FRAMES: u32 = FRAME_HZ;
/// How long a lost attempt (fell, time up) is shown before the restart.
pub const LOSS_PAUSE_FRAMES: u32 = FRAME_HZ / 2;

/// What one [`Player::tick`] did.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Tick<const W: usize, const H: usize> {
    /// The picture to show, when the caller asked for one (and something is
    /// to be shown: the fault picture is drawn once per outage).
    pub frame: Option<Frame<W, H>>,
    /// The attempt finished in this frame, with this outcome.
    pub finished: Option<Phase>,
    /// What to play for this frame: its bounces' clicks and the outcome
    /// (none while muted, and none at all without the `sound` feature).
    pub sounds: Sounds,
}

/// A player's place in the endless run ([`Player::endless_at`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Endless {
    /// The level's number in the run, counted from 0.
    number: usize,
    /// Done with it: won, or skipped.
    done: bool,
}

/// What a player keeps from one level to the next ([`Player::carried`],
/// [`Player::carry`]): within its list the player keeps it itself; in the
/// endless run, where each level gets a player of its own, the game task
/// carries it into the next one.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Carried {
    calibration: Calibration,
    autopilot: bool,
    sensor_down: Option<Fault>,
    fault_shown: bool,
    muted: bool,
}

impl Carried {
    /// Whether the autopilot played: the next level's [`Player::new`] takes it.
    pub const fn autopilot(&self) -> bool {
        self.autopilot
    }
}

/// One player's game on a `W`×`H` display (see the module doc).
///
/// `PILOT` says whether the board has the autopilot at all
/// ([`Command::ToggleAutopilot`], the demo). It is a constant, not a flag, so
/// that a board without it (the micro:bit: no button combination is left for
/// it) does not link the controller: about 6 KiB of flash.
///
/// `EVENTS` picks the physics stepper ([`GameConfig::stepped_by`]), a constant for
/// the same reason: the event stepper costs 18 to 24 KiB of flash, which a board
/// with a 64 KiB budget does not have, and the fixed step is then all it links.
#[derive(Clone, Debug)]
pub struct Player<'a, const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool> {
    levels: &'a [LevelView<'a>],
    level: usize,
    /// In the endless run, the level's number in it (counted from 0), and
    /// whether the player is done with it ([`Player::endless_at`]).
    endless: Option<Endless>,
    session: Session<'a, Fx>,
    renderer: Renderer<W, H>,
    autopilot: Option<Autopilot>,
    /// The finished attempt on show, and frames left to show it.
    pause: Option<(Phase, u32)>,
    /// Why the sensor is down, while it is.
    sensor_down: Option<Fault>,
    /// The fault picture has been handed out for this outage.
    fault_shown: bool,
    /// Sound off ([`Command::ToggleMute`]).
    muted: bool,
    /// The win on show is a new record: [`record_frame`] instead of the flash.
    new_record: bool,
}

impl<'a, const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>
    Player<'a, W, H, PILOT, EVENTS>
{
    /// The game's configuration on this player: [`GameConfig::stepped_by`]`(EVENTS)`.
    pub const CONFIG: GameConfig = GameConfig::stepped_by(EVENTS);

    /// Level `level` of `levels` (wrapped into range; `levels` must not be
    /// empty) with the tilt path `tilt`; the autopilot plays if `autopilot`
    /// (and the board has it, `PILOT`).
    pub fn new(
        levels: &'a [LevelView<'a>],
        level: usize,
        tilt: TiltConfig,
        autopilot: bool,
    ) -> Result<Self, SetupError> {
        let level = level % levels.len().max(1);
        let Some(view) = levels.get(level) else {
            return Err(SetupError::MarbleCount);
        };
        Self::on(levels, level, *view, tilt, autopilot)
    }

    /// Level `view`, number `level` of `levels` (or alone, with no list).
    fn on(
        levels: &'a [LevelView<'a>],
        level: usize,
        view: LevelView<'a>,
        tilt: TiltConfig,
        autopilot: bool,
    ) -> Result<Self, SetupError> {
        Ok(Player {
            levels,
            level,
            endless: None,
            session: Session::new(view, Self::CONFIG, tilt)?,
            renderer: Renderer::new(),
            autopilot: (PILOT && autopilot).then(|| Autopilot::new(&view)),
            pause: None,
            sensor_down: None,
            fault_shown: false,
            muted: false,
            new_record: false,
        })
    }

    /// A player on `level`, which no list holds (a level of the endless run:
    /// [`Player::endless_at`]; a level alone, which starts again when won).
    pub fn single(
        level: LevelView<'a>,
        tilt: TiltConfig,
        autopilot: bool,
    ) -> Result<Self, SetupError> {
        Self::on(&[], 0, level, tilt, autopilot)
    }

    /// The level's number: in the endless run its number in the run (counted
    /// from 0), otherwise its index in the player's list.
    pub fn level_index(&self) -> usize {
        self.endless.map_or(self.level, |endless| endless.number)
    }
    /// The level's name.
    pub fn level_name(&self) -> &'a str {
        self.session.game().level().info.name
    }
    /// Makes this player's level number `number` of the endless run
    /// ([`crate::game::endless`]): what [`Player::level_index`] and the status
    /// say; and moving on from it (a win, [`Command::NextLevel`]) is not the
    /// player's: it only says it is done ([`Player::wants_next`]), and its
    /// caller brings the next level, which no list holds.
    pub fn endless_at(&mut self, number: usize) {
        self.endless = Some(Endless {
            number,
            done: false,
        });
    }
    /// In the endless run, the player is done with its level (won, or
    /// skipped): its caller brings the next one ([`Player::carried`] says what
    /// to keep).
    pub fn wants_next(&self) -> bool {
        self.endless.is_some_and(|endless| endless.done)
    }
    /// The session.
    pub fn session(&self) -> &Session<'a, Fx> {
        &self.session
    }
    /// The session, mutably (profiling, tools).
    pub fn session_mut(&mut self) -> &mut Session<'a, Fx> {
        &mut self.session
    }
    /// The game.
    pub fn game(&self) -> &Game<'a, Fx> {
        self.session.game()
    }
    /// Whether the sound is off ([`Command::ToggleMute`]).
    pub fn muted(&self) -> bool {
        self.muted
    }
    /// Whether the autopilot plays.
    pub fn autopilot(&self) -> bool {
        self.autopilot.is_some()
    }
    /// Why the sensor is down, while the game is paused for it.
    pub fn sensor_down(&self) -> Option<Fault> {
        self.sensor_down
    }

    /// Hands the board to the autopilot (planned afresh for the level), or
    /// takes it back. Without `PILOT` it stays off.
    pub fn set_autopilot(&mut self, on: bool) {
        self.autopilot = (PILOT && on).then(|| Autopilot::new(self.session.game().level()));
    }

    /// The reading for the next frame: the autopilot's when it plays, else
    /// `tilt` (the accelerometer's or the keys').
    pub fn reading(&mut self, tilt: AccelMg) -> AccelMg {
        match &mut self.autopilot {
            // `PILOT` again, though the pilot is never set without it: the
            // compiler cannot see that, and the constant drops the controller
            // (~2 KB) from a board without it.
            Some(pilot) if PILOT => pilot.reading_mg(self.session.game()),
            _ => tilt,
        }
    }

    /// Plays one frame (`2^substeps_log2` physics steps) with
    /// [`Player::reading`]`(tilt)` and returns where the attempt stands. A
    /// finished attempt stays finished (the game does not step any more).
    /// This is the bare step, without the loop's pauses: [`Player::tick`] is
    /// the game loop.
    pub(crate) fn frame(&mut self, tilt: AccelMg) -> Phase {
        let reading = self.reading(tilt);
        self.session.frame_in::<EVENTS>(reading)
    }

    /// The viewport of the last picture (a ghost is drawn through it).
    pub fn viewport(&self) -> crate::render::Viewport {
        self.renderer.viewport()
    }

    /// The current picture.
    pub fn render(&mut self) -> Frame<W, H> {
        self.renderer.render(self.session.game())
    }

    /// For status displays.
    pub fn status(&self) -> Status {
        let game = self.session.game();
        Status {
            level: self.level_index().min(usize::from(u8::MAX)) as u8,
            phase: game.phase(),
            frames: game.clock_frames(),
            reading: self.session.reading(),
            autopilot: self.autopilot(),
            sensor_down: self.sensor_down.is_some(),
            muted: self.muted,
            new_record: self.new_record,
            #[cfg(feature = "records")]
            best: None,
            #[cfg(feature = "storey-maps")]
            marbles: status::marble_spots(game),
            #[cfg(feature = "storey-maps")]
            maze: None,
        }
    }

    /// Takes an input event other than a tilt reading (tilt readings are
    /// passed to [`Player::tick`]). Returns `false` for [`Command::Quit`].
    pub fn handle(&mut self, event: InputEvent) -> bool {
        match event {
            InputEvent::Tilt(_) => {}
            InputEvent::Command(command) => match command {
                Command::Restart => self.restart(),
                Command::NextLevel => self.next_level(),
                Command::Calibrate => self.calibrate(),
                Command::ToggleAutopilot => self.set_autopilot(!self.autopilot()),
                Command::ToggleMute => self.muted = !self.muted,
                Command::Quit => return false,
            },
            InputEvent::SensorDown(fault) => {
                if self.sensor_down.is_none() {
                    self.fault_shown = false;
                }
                self.sensor_down = Some(fault);
            }
            InputEvent::SensorUp => self.sensor_down = None,
        }
        true
    }

    /// One frame of the game loop with the latest tilt reading `tilt`:
    /// paused while the sensor is down; else a physics frame, or one frame of
    /// a finished attempt's display, after which a won level moves on to the
    /// next and a lost one restarts. `draw` asks for the picture (the
    /// firmware asks only once the display has taken the previous one:
    /// rendering is not free).
    pub fn tick(&mut self, tilt: AccelMg, draw: bool) -> Tick<W, H> {
        if self.sensor_down.is_some() {
            let frame = (draw && !self.fault_shown).then(fault_frame);
            self.fault_shown |= frame.is_some();
            return Tick {
                frame,
                finished: None,
                sounds: Sounds::NONE,
            };
        }
        if self.fault_shown {
            // Back from an outage: the game's picture replaces the fault's.
            self.fault_shown = false;
        }
        let mut finished = None;
        let mut sounds = Sounds::NONE;
        let frame = match self.pause {
            None => {
                let phase = self.frame(tilt);
                if cfg!(feature = "sound") {
                    let world = self.session.game_mut().world_mut();
                    let impacts = world.take_impacts();
                    let pitch_um = world.params().layout.pitch_um;
                    let ended = (phase != Phase::Playing).then_some(phase);
                    sounds = sound::frame_sounds(&impacts, pitch_um, ended, self.muted);
                }
                if phase != Phase::Playing {
                    finished = Some(phase);
                    let frames = if phase == Phase::Won {
                        WIN_PAUSE_FRAMES
                    } else {
                        LOSS_PAUSE_FRAMES
                    };
                    self.pause = Some((phase, frames));
                }
                draw.then(|| self.render())
            }
            Some((phase, 0)) => {
                if phase == Phase::Won {
                    self.next_level();
                } else {
                    self.restart();
                }
                draw.then(|| self.render())
            }
            Some((phase, left)) => {
                self.pause = Some((phase, left - 1));
                let record = self.new_record;
                draw.then(|| {
                    let frame = self.render();
                    match (phase, record) {
                        (Phase::Won, true) => record_frame(WIN_PAUSE_FRAMES.saturating_sub(left)),
                        (Phase::Won, false) => win_frame(&frame, left),
                        _ => frame,
                    }
                })
            }
        };
        Tick {
            frame,
            finished,
            sounds,
        }
    }

    /// The win on show set a new record (the records task found it, while the
    /// win is shown): the rest of the pause shows [`record_frame`]. Ignored
    /// unless a won level is on show.
    pub fn announce_record(&mut self) {
        if let Some((Phase::Won, _)) = self.pause {
            self.new_record = true;
        }
    }

    /// Starts the level over (the tilt calibration is kept).
    pub fn restart(&mut self) {
        self.session.restart();
        self.renderer.reset();
        self.pause = None;
        self.new_record = false;
        if self.autopilot.is_some() {
            self.set_autopilot(true);
        }
    }

    /// Moves on to the next level of the list (after the last: the first),
    /// keeping what [`Player::carried`] says; a level that cannot be set up is
    /// skipped, and a level without a list starts again. In the endless run
    /// the player only says it is done ([`Player::wants_next`]).
    pub fn next_level(&mut self) {
        if let Some(endless) = &mut self.endless {
            endless.done = true;
            return;
        }
        if self.levels.is_empty() {
            self.restart();
            return;
        }
        let carried = self.carried();
        for offset in 1..=self.levels.len() {
            let index = self.level + offset;
            if let Ok(next) = Self::new(
                self.levels,
                index,
                self.session.tilt_config(),
                carried.autopilot,
            ) {
                *self = next;
                self.carry(carried);
                #[cfg(feature = "defmt")]
                defmt::info!(
                    "level {=usize}: {=str}",
                    self.level_index() + 1,
                    self.level_name()
                );
                return;
            }
        }
    }

    /// What moves on with the player to the next level.
    pub fn carried(&self) -> Carried {
        Carried {
            calibration: self.session.tilt().calibration(),
            autopilot: self.autopilot(),
            sensor_down: self.sensor_down,
            fault_shown: self.fault_shown,
            muted: self.muted,
        }
    }

    /// Takes on what the player had on the level before ([`Player::carried`]):
    /// the tilt calibration, a sensor outage and the sound setting. Not the
    /// autopilot: that is [`Player::new`]'s argument
    /// ([`Carried::autopilot`]), so that it is planned once.
    pub fn carry(&mut self, carried: Carried) {
        self.session.tilt_mut().set_calibration(carried.calibration);
        self.sensor_down = carried.sensor_down;
        self.fault_shown = carried.fault_shown;
        self.muted = carried.muted;
    }

    /// Takes the current filtered tilt as level (an implausible one is
    /// refused). This is the one place the game calibrates: a board's
    /// buttons and a terminal's key both send [`Command::Calibrate`].
    pub(crate) fn calibrate(&mut self) {
        let reading = self.session.tilt().filtered_reading_mg();
        let result = self.session.tilt_mut().calibrate(reading);
        #[cfg(feature = "defmt")]
        defmt::info!("calibrate: {}", result);
        let _ = result;
    }
}
