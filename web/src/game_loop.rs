//! The game loop: the page's game (`App`, in `APP`) plays one
//! [`Player::tick`](marble_rolling::player::Player::tick) a frame at the
//! page's tilt, keeps the LEDs and the last finished attempt, and moves
//! between the level lists (built-ins, the editor's level, a generated maze);
//! its exports are the frame, the tilt, the level choice and the attempt's
//! numbers.

use core::cell::RefCell;

use marble_rolling::board::microbit::{HEIGHT, WIDTH};
use marble_rolling::game::level::LevelView;
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::Phase;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::player::FRAME_HZ;

use crate::ghost_run::{GhostRun, Recorder};
use crate::{AnyPlayer, Single};

/// The game, set up by [`init`].
pub(crate) static APP: Single<RefCell<Option<App>>> = Single(RefCell::new(None));

/// The last attempt that finished (won, fell, timed out), for the page's best
/// times and the browser test's hashes.
#[derive(Clone, Copy)]
pub(crate) struct Finished {
    /// Attempts finished since [`init`]: the page notices a new one by it.
    pub(crate) count: u32,
    pub(crate) level: u32,
    pub(crate) source: Source,
    pub(crate) phase: Phase,
    pub(crate) frames: u32,
    /// Frames on the level clock (the time a player is shown and a record keeps).
    pub(crate) clock: u32,
    pub(crate) hash: u64,
    /// Bytes of the attempt's ghost in [`RECORD`](crate::ghost_run::RECORD) (a
    /// win played whole from its first frame, that fitted); 0 for none.
    pub(crate) ghost_len: u32,
}

/// The arguments of
/// [`generate`](marble_rolling::game::generate::generate) a generated maze
/// came from ([`crate::maze`] makes it).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) struct MazeArgs {
    pub(crate) seed: u32,
    pub(crate) size: u8,
    pub(crate) storeys: u8,
    pub(crate) difficulty: u8,
}

/// Where the level list in play comes from.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Source {
    /// The built-in levels.
    Builtin,
    /// The editor's level, then the built-in ones.
    Editor,
    /// A generated maze alone: a win plays it again, against the ghost of
    /// that win if it is the best.
    Generated(MazeArgs),
}

pub(crate) struct App {
    pub(crate) player: AnyPlayer,
    /// The level list in play (the built-ins, or the editor's level and them).
    pub(crate) levels: &'static [LevelView<'static>],
    /// Where that list comes from.
    pub(crate) source: Source,
    /// The page's tilt, as the accelerometer reading the player is fed.
    pub(crate) reading: AccelMg,
    /// The matrix as the last frame drew it, row by row (brightness 0..=15).
    pub(crate) led: [u8; WIDTH * HEIGHT],
    pub(crate) finished: Finished,
    pub(crate) recorder: Recorder,
    /// The stored best run of the level in play, replayed beside it.
    pub(crate) ghost: Option<GhostRun>,
}

impl App {
    pub(crate) fn new() -> Option<App> {
        let player = AnyPlayer::new(
            &LEVELS,
            0,
            marble_rolling::game::rules::DEFAULT_EVENTS,
            false,
        )?;
        Some(App {
            player,
            levels: &LEVELS,
            source: Source::Builtin,
            reading: AccelMg::LEVEL,
            led: [0; WIDTH * HEIGHT],
            finished: Finished {
                count: 0,
                level: 0,
                source: Source::Builtin,
                phase: Phase::Playing,
                frames: 0,
                clock: 0,
                hash: 0,
                ghost_len: 0,
            },
            recorder: Recorder::new(),
            ghost: None,
        })
        .map(|mut app| {
            app.recorder.start();
            app
        })
    }

    /// Plays level `index` of `levels` from its start with the stepper in
    /// use; the autopilot setting carries over. False (and the game
    /// unchanged) if it cannot be set up.
    pub(crate) fn start(&mut self, levels: &'static [LevelView<'static>], index: usize) -> bool {
        self.start_stepped(levels, index, self.player.events())
    }

    /// [`App::start`] with the stepper `events` picks.
    pub(crate) fn start_stepped(
        &mut self,
        levels: &'static [LevelView<'static>],
        index: usize,
        events: bool,
    ) -> bool {
        match AnyPlayer::new(levels, index, events, self.player.autopilot()) {
            Some(player) => {
                self.player = player;
                self.levels = levels;
                // Another level (or stepper): the ghost on show was not for it.
                self.ghost = None;
                self.recorder.start();
                true
            }
            None => false,
        }
    }

    pub(crate) fn tick(&mut self) -> u32 {
        let level = self.player.level_index();
        let tick = self.player.tick(self.reading);
        if let Some(frame) = tick.frame {
            for (y, row) in frame.rows().iter().enumerate() {
                self.led[y * WIDTH..(y + 1) * WIDTH].copy_from_slice(row);
            }
        }
        let moved_on = self.player.level_index() != level;
        if moved_on {
            self.ghost = None;
        }
        self.follow_attempt();
        let mut flags = 0;
        if let Some(phase) = tick.finished {
            let ghost_len = match phase {
                Phase::Won => self.recorder.finish(self.player.session()),
                _ => 0,
            };
            let game = self.player.game();
            self.finished = Finished {
                count: self.finished.count.wrapping_add(1),
                level: self.level_number(),
                source: self.level_source(),
                phase,
                frames: game.frames(),
                clock: game.clock_frames(),
                hash: self.player.state_hash(),
                ghost_len,
            };
            flags |= TICK_FINISHED;
        }
        if moved_on || self.player.game().frames() == 0 {
            flags |= TICK_NEW_ATTEMPT;
        }
        flags
    }

    /// After a frame (or a restart, a new level): the attempt's reading goes
    /// into its ghost, and the ghost on show plays as far as the attempt.
    pub(crate) fn follow_attempt(&mut self) {
        let session = self.player.session();
        self.recorder.observe(session);
        if let Some(ghost) = &mut self.ghost {
            ghost.follow(session.game());
        }
    }

    /// Where the level in play comes from (the built-ins after the editor's
    /// level are built-in).
    pub(crate) fn level_source(&self) -> Source {
        match self.source {
            Source::Editor if self.player.level_index() > 0 => Source::Builtin,
            source => source,
        }
    }

    /// Whether the level in play is the editor's.
    pub(crate) fn is_custom_level(&self) -> bool {
        self.level_source() == Source::Editor
    }

    /// The level in play as a built-in index (the editor's or a generated
    /// maze: the built-ins' count).
    pub(crate) fn level_number(&self) -> u32 {
        let index = self.player.level_index();
        let builtin = match self.source {
            Source::Builtin => Some(index),
            Source::Editor => index.checked_sub(1),
            Source::Generated(_) => None,
        };
        builtin.unwrap_or(LEVELS.len()) as u32
    }

    pub(crate) fn level(&self) -> &LevelView<'static> {
        self.player.game().level()
    }
}

/// [`tick`]'s result bit: an attempt finished in this frame.
pub(crate) const TICK_FINISHED: u32 = 1;

/// [`tick`]'s result bit: a new attempt started (another level, or a restart).
pub(crate) const TICK_NEW_ATTEMPT: u32 = 2;

/// Runs `f` on the game; `default` before [`init`] (or if it failed).
pub(crate) fn with_app<R>(default: R, f: impl FnOnce(&mut App) -> R) -> R {
    match APP.0.borrow_mut().as_mut() {
        Some(app) => f(app),
        None => default,
    }
}

/// Sets the game up on the first built-in level; 1 on success.
#[no_mangle]
pub extern "C" fn init() -> u32 {
    let mut app = APP.0.borrow_mut();
    if app.is_none() {
        *app = App::new();
    }
    app.is_some() as u32
}

/// Game frames per second (the firmware's: 128).
#[no_mangle]
pub extern "C" fn frame_hz() -> u32 {
    FRAME_HZ
}

/// One game frame at the current tilt: the loop's step
/// ([`Player::tick`](marble_rolling::player::Player::tick)). Bit 0: an
/// attempt finished; bit 1: a new attempt started.
#[no_mangle]
pub extern "C" fn tick() -> u32 {
    with_app(0, App::tick)
}

/// `n` frames (the browser test's fast-forward: the same step as [`tick`]);
/// stops early after a frame that finished an attempt if `stop_on_finish`.
/// Returns the frames played.
#[no_mangle]
pub extern "C" fn ticks(n: u32, stop_on_finish: u32) -> u32 {
    with_app(0, |app| {
        for done in 1..=n {
            if app.tick() & TICK_FINISHED != 0 && stop_on_finish != 0 {
                return done;
            }
        }
        n
    })
}

/// The page's tilt in milli-g: `right_mg` lowers the right edge (the marble
/// rolls right), `up_mg` lowers the far edge (it rolls up the screen). Made a
/// 1 g reading in the board frame by the library ([`AccelMg::from_xz`]: x right,
/// z towards the player, so both signs flip as the keys' do in
/// `input::keys::KeyTilt`).
#[no_mangle]
pub extern "C" fn set_tilt(right_mg: i32, up_mg: i32) {
    with_app((), |app| {
        app.reading = AccelMg::from_xz(right_mg.saturating_neg(), up_mg);
    })
}

/// The reading fed to the game last, x (mg, board frame).
#[no_mangle]
pub extern "C" fn reading_x() -> i32 {
    with_app(0, |app| app.player.reading().x)
}

/// The reading fed to the game last, z (mg, board frame).
#[no_mangle]
pub extern "C" fn reading_z() -> i32 {
    with_app(0, |app| app.player.reading().z)
}

/// Plays built-in level `index` from its start; 1 on success.
#[no_mangle]
pub extern "C" fn select_level(index: u32) -> u32 {
    with_app(0, |app| {
        if index as usize >= LEVELS.len() {
            return 0;
        }
        let ok = app.start(&LEVELS, index as usize);
        if ok {
            app.source = Source::Builtin;
        }
        ok as u32
    })
}

/// Starts the level over.
#[no_mangle]
pub extern "C" fn restart() {
    with_app((), |app| {
        app.player.restart();
        app.follow_attempt();
    })
}

/// Moves on to the next level (after the last built-in: the first).
#[no_mangle]
pub extern "C" fn next_level() {
    with_app((), |app| {
        let level = app.player.level_index();
        app.player.next_level();
        if app.player.level_index() != level {
            app.ghost = None;
        }
        app.follow_attempt();
    })
}

/// Hands the board to the autopilot (`on` ≠ 0) or takes it back.
#[no_mangle]
pub extern "C" fn set_autopilot(on: u32) {
    with_app((), |app| app.player.set_autopilot(on != 0))
}

/// 1 while the autopilot plays.
#[no_mangle]
pub extern "C" fn autopilot() -> u32 {
    with_app(0, |app| app.player.autopilot() as u32)
}

/// Where the attempt stands: 0 playing, 1 won, 2 fell, 3 time up.
#[no_mangle]
pub extern "C" fn phase() -> u32 {
    with_app(0, |app| phase_code(app.player.game().phase()))
}

pub(crate) fn phase_code(phase: Phase) -> u32 {
    match phase {
        Phase::Playing => 0,
        Phase::Won => 1,
        Phase::Fell => 2,
        Phase::TimeUp => 3,
    }
}

/// Frames played in this attempt (the clock's idle ones included: the
/// simulated time `cargo sim` reports).
#[no_mangle]
pub extern "C" fn frames() -> u32 {
    with_app(0, |app| app.player.game().frames())
}

/// Frames on the level clock in this attempt (`Game::clock_frames`: it starts
/// at the first tilt that rolls a marble, on every board).
#[no_mangle]
pub extern "C" fn clock_frames() -> u32 {
    with_app(0, |app| app.player.game().clock_frames())
}

/// 1 while the page plays with event stepping, 0 with fixed steps.
#[no_mangle]
pub extern "C" fn stepping_events() -> u32 {
    with_app(0, |app| app.player.events() as u32)
}

/// Switches the stepper (`events` ≠ 0: event stepping, else fixed steps) and
/// starts the level in play over with it; 1 on success.
#[no_mangle]
pub extern "C" fn set_stepping(events: u32) -> u32 {
    with_app(0, |app| {
        let index = app.player.level_index();
        app.start_stepped(app.levels, index, events != 0) as u32
    })
}

/// The exact state's digest (`Session::state_hash`, as `cargo sim` prints it).
#[no_mangle]
pub extern "C" fn state_hash() -> u64 {
    with_app(0, |app| app.player.state_hash())
}

/// Attempts finished so far (see the `finished_*` functions for the last one).
#[no_mangle]
pub extern "C" fn finished_count() -> u32 {
    with_app(0, |app| app.finished.count)
}

/// The last finished attempt's level (as [`level_index`](crate::page_state::level_index)).
#[no_mangle]
pub extern "C" fn finished_level() -> u32 {
    with_app(0, |app| app.finished.level)
}

/// 1 if the last finished attempt was on the editor's level.
#[no_mangle]
pub extern "C" fn finished_custom() -> u32 {
    with_app(0, |app| (app.finished.source == Source::Editor) as u32)
}

/// 1 if the last finished attempt was on a generated maze.
#[no_mangle]
pub extern "C" fn finished_generated() -> u32 {
    with_app(0, |app| {
        matches!(app.finished.source, Source::Generated(_)) as u32
    })
}

/// Bytes of the last finished attempt's ghost at
/// [`record_ptr`](crate::ghost::record_ptr): a win played whole from its
/// first frame (0 for a loss, or a run longer than the buffer holds). They
/// stay there until the next attempt starts.
#[no_mangle]
pub extern "C" fn finished_ghost_len() -> u32 {
    with_app(0, |app| app.finished.ghost_len)
}

/// How the last finished attempt ended (as [`phase`]).
#[no_mangle]
pub extern "C" fn finished_phase() -> u32 {
    with_app(0, |app| phase_code(app.finished.phase))
}

/// Frames the last finished attempt took.
#[no_mangle]
pub extern "C" fn finished_frames() -> u32 {
    with_app(0, |app| app.finished.frames)
}

/// The last finished attempt's time on the level clock, frames.
#[no_mangle]
pub extern "C" fn finished_clock() -> u32 {
    with_app(0, |app| app.finished.clock)
}

/// `state_hash` at the end of the last finished attempt.
#[no_mangle]
pub extern "C" fn finished_hash() -> u64 {
    with_app(0, |app| app.finished.hash)
}
