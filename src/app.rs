//! Board-agnostic firmware logic, shared by every board binary.
//!
//! embassy tasks cannot be generic, so the shape is: this module has plain
//! `async fn`s parameterised by small traits, and each board binary wraps them
//! in thin `#[embassy_executor::task]` functions that pass its own hardware:
//!
//! ```text
//!  input_task(TiltInput) ──tilt (latest)──┐
//!                       └─commands (queue)┴─> game_task ──frames (latest)──> display_task(MatrixOutput)
//!                                              │ Ticker at FRAME_HZ (128 Hz), each tick:
//!                                              └ Player::frame(reading) → Session::frame → render
//! ```
//!
//! * [`TiltInput`]: where tilt and commands come from (accelerometer and
//!   buttons, or a terminal via [`TerminalInput`]).
//! * [`game_task`] runs the game ([`Player`]: a [`Session`] on a built-in
//!   level, a [`Renderer`] and optionally the [`Autopilot`]) at the game's
//!   frame rate [`FRAME_HZ`] on an embassy `Ticker` (not `Timer::after`,
//!   which rounds up to the time driver's tick and drifts). In
//!   [`GameMode::Demo`] the autopilot plays every built-in level once, exactly
//!   as `cargo sim -- --level <name> --autopilot` does, and each level's
//!   outcome, physics steps and `state_hash` are logged.
//! * [`MatrixOutput`]: how one BCM scan step of [`crate::matrix::Scanner`]
//!   reaches LEDs (real pins, or QEMU's virtual matrix).
//! * [`Console`]: a blocking byte sink for an interactive terminal.
//!
//! The display size `W`×`H` and whether the autopilot is linked (`PILOT`) are
//! the board binary's choice, passed as const generics: the micro:bit's 5×5
//! matrix, whose view scrolls with the marble, without the autopilot; or for
//! QEMU a 19×9 virtual matrix that shows every built-in maze whole. The board
//! binary owns the [`Links`] between its tasks in a `static`.

use core::cell::Cell;
use core::future::Future;
use core::sync::atomic::{AtomicBool, Ordering};

use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::{Duration, Ticker};

use crate::game::autopilot::Autopilot;
use crate::game::levels::LEVELS;
use crate::game::rules::{Game, GameConfig, Phase};
use crate::game::session::{Session, SYNTHETIC_TILT};
use crate::matrix::{Frame, ScanStep, Scanner, MAX_BRIGHTNESS};
use crate::physics::world::SetupError;
use crate::physics::Fx;
use crate::render::Renderer;
use crate::tilt::TiltConfig;

/// The game's configuration: 128 frames/s × 8 physics steps (the same as the
/// host tools, so that `state_hash`es agree).
pub const GAME_CONFIG: GameConfig = GameConfig::DEFAULT;
/// Game frames per second (each one is `2^substeps_log2` physics steps).
pub const FRAME_HZ: u32 = GAME_CONFIG.frame_hz();
/// Full LED-matrix refreshes per second.
pub const REFRESH_HZ: u32 = 100;
/// How long a won level is shown (flashing) before the next one, in frames.
pub const WIN_PAUSE_FRAMES: u32 = FRAME_HZ;
/// How long a lost attempt (fell, time up) is shown before the restart.
pub const LOSS_PAUSE_FRAMES: u32 = FRAME_HZ / 2;
/// Flash period of the win display, frames (on and off for this long each).
const WIN_FLASH_FRAMES: u32 = FRAME_HZ / 8;

/// One g in milli-g.
pub const ONE_G_MG: i32 = 1000;

// ---------------------------------------------------------------------------
// Tilt and commands
// ---------------------------------------------------------------------------

/// An accelerometer reading in milli-g, in the board frame: `x` to the right,
/// `y` up (out of the LEDs), `z` towards the player.
///
/// It is the reaction to gravity, so a flat board reads [`Tilt::FLAT`]
/// (`y = +1000`), and lowering the right edge gives `x < 0`, which makes the
/// marble roll towards `+x`. Likewise `z < 0` rolls it towards the player
/// (down the screen).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tilt {
    /// Right, milli-g.
    pub x: i16,
    /// Up, milli-g.
    pub y: i16,
    /// Towards the player, milli-g.
    pub z: i16,
}

impl Tilt {
    /// The board lying flat.
    pub const FLAT: Tilt = Tilt {
        x: 0,
        y: 1000,
        z: 0,
    };

    /// A 1 g reading with the given `x` and `z` components (clamped to
    /// ±1000 mg together) and `y = +sqrt(1000² - x² - z²)`.
    pub fn from_xz(x: i32, z: i32) -> Tilt {
        let x = x.clamp(-ONE_G_MG, ONE_G_MG);
        let z = z.clamp(-ONE_G_MG, ONE_G_MG);
        let horizontal = x * x + z * z;
        let y = ((ONE_G_MG * ONE_G_MG - horizontal).max(0) as u32).isqrt();
        Tilt {
            x: x as i16,
            y: y as i16,
            z: z as i16,
        }
    }

    /// As the `[x, y, z]` reading the game's tilt path takes.
    pub const fn reading_mg(self) -> [i32; 3] {
        [self.x as i32, self.y as i32, self.z as i32]
    }
}

/// A discrete user command.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Restart the current level.
    Restart,
    /// Skip to the next level.
    NextLevel,
    /// Take the current (filtered) tilt as level.
    Calibrate,
    /// Hand the board to the autopilot, or take it back.
    ToggleAutopilot,
    /// Leave the game (QEMU exits with status 0).
    Quit,
}

/// What a [`TiltInput`] produces.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InputEvent {
    /// A new tilt reading (replaces the previous one).
    Tilt(Tilt),
    /// A command for the game.
    Command(Command),
}

/// A source of tilt readings and commands (accelerometer, keyboard, script).
pub trait TiltInput {
    /// Waits for the next event.
    fn next_event(&mut self) -> impl Future<Output = InputEvent>;
}

/// Bytes from an interactive terminal (e.g. a UART's receive queue).
pub trait ByteSource {
    /// Waits for the next received byte.
    fn read_byte(&mut self) -> impl Future<Output = u8>;
}

/// A blocking byte sink for an interactive terminal.
pub trait Console {
    /// Writes all of `bytes`.
    fn write(&mut self, bytes: &[u8]);
}

// ---------------------------------------------------------------------------
// Links between the tasks
// ---------------------------------------------------------------------------

/// The latest value of something, readable at any time (e.g. the tilt).
pub struct Latest<T: Copy> {
    value: Mutex<CriticalSectionRawMutex, Cell<T>>,
}

impl<T: Copy> Latest<T> {
    /// Holds `value` until the first [`Latest::set`].
    pub const fn new(value: T) -> Self {
        Self {
            value: Mutex::new(Cell::new(value)),
        }
    }

    /// The latest value.
    pub fn get(&self) -> T {
        self.value.lock(Cell::get)
    }

    /// Replaces the value.
    pub fn set(&self, value: T) {
        self.value.lock(|cell| cell.set(value));
    }
}

/// What the game is doing, for status displays (QEMU's terminal).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Index of the level in [`LEVELS`].
    pub level: u8,
    /// Where the attempt stands.
    pub phase: Phase,
    /// Frames played in this attempt.
    pub frames: u32,
    /// The reading fed to the game last (milli-g, board frame).
    pub reading: [i32; 3],
    /// Whether the autopilot is playing.
    pub autopilot: bool,
}

impl Status {
    /// Before the first frame.
    pub const START: Status = Status {
        level: 0,
        phase: Phase::Playing,
        frames: 0,
        reading: [0, ONE_G_MG, 0],
        autopilot: false,
    };
}

/// The links between the tasks of a board with a `W`×`H` display. Each board
/// binary owns one in a `static` (the size is the board's, so it cannot be a
/// static of this module) and hands it to the tasks.
pub struct Links<const W: usize, const H: usize> {
    /// Latest tilt, written by [`input_task`], read by [`game_task`] each frame.
    pub tilt: Latest<Tilt>,
    /// Commands from [`input_task`] to [`game_task`].
    pub commands: Channel<CriticalSectionRawMutex, Command, 8>,
    /// Latest frame from [`game_task`] to [`display_task`] (older ones are
    /// dropped).
    pub frames: Signal<CriticalSectionRawMutex, Frame<W, H>>,
    /// The game's status after its latest frame.
    pub status: Latest<Status>,
    /// Set by the board while its accelerometer is down: the game pauses and
    /// shows [`fault_frame`] until it is cleared.
    pub sensor_fault: AtomicBool,
}

impl<const W: usize, const H: usize> Links<W, H> {
    /// Nothing sent yet: a flat board, no command, no frame.
    pub const fn new() -> Self {
        Self {
            tilt: Latest::new(Tilt::FLAT),
            commands: Channel::new(),
            frames: Signal::new(),
            status: Latest::new(Status::START),
            sensor_fault: AtomicBool::new(false),
        }
    }
}

impl<const W: usize, const H: usize> Default for Links<W, H> {
    fn default() -> Self {
        Self::new()
    }
}

// ---------------------------------------------------------------------------
// Tasks
// ---------------------------------------------------------------------------

/// Forwards events from `input` to [`Links::tilt`] and [`Links::commands`],
/// forever.
pub async fn input_task<I: TiltInput, const W: usize, const H: usize>(
    links: &Links<W, H>,
    input: &mut I,
) -> ! {
    loop {
        match input.next_event().await {
            InputEvent::Tilt(tilt) => links.tilt.set(tilt),
            InputEvent::Command(command) => links.commands.send(command).await,
        }
    }
}

/// How [`game_task`] plays.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GameMode {
    /// A player with a tilt input: endless, levels in order, [`Links::commands`]
    /// obeyed. `tilt` configures the game's tilt path:
    /// [`TiltConfig::DEFAULT`] for a real accelerometer, [`SYNTHETIC_TILT`]
    /// for keys.
    Play {
        /// The tilt path's configuration.
        tilt: TiltConfig,
    },
    /// The headless demo: the autopilot plays each built-in level once, in
    /// order, then [`game_task`] returns.
    Demo,
}

/// Why [`game_task`] returned.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GameExit {
    /// The player quit.
    Quit,
    /// The demo played every level.
    DemoDone(DemoSummary),
    /// No level could be set up (a bug in the built-in levels).
    SetupFailed(SetupError),
}

/// The demo's totals.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DemoSummary {
    /// Levels played.
    pub levels: u8,
    /// Levels won.
    pub won: u8,
    /// Physics steps over all levels.
    pub steps: u64,
    /// Game frames over all levels.
    pub frames: u64,
}

impl DemoSummary {
    /// Every level played was won (and there was at least one).
    pub const fn all_won(&self) -> bool {
        self.levels > 0 && self.won == self.levels
    }
}

/// Runs the game at [`FRAME_HZ`] in `mode` (see [`GameMode`]), publishing a
/// frame on [`Links::frames`] and the [`Links::status`] every tick. Returns
/// on [`Command::Quit`] or at the end of the demo. `PILOT` says whether the
/// board has the autopilot (see [`Player`]).
pub async fn game_task<const W: usize, const H: usize, const PILOT: bool>(
    links: &Links<W, H>,
    mode: GameMode,
) -> GameExit {
    let mut ticker = Ticker::every(Duration::from_hz(u64::from(FRAME_HZ)));
    match mode {
        GameMode::Play { tilt } => play::<W, H, PILOT>(links, &mut ticker, tilt).await,
        GameMode::Demo => demo::<W, H, PILOT>(links, &mut ticker).await,
    }
}

/// One tick of the frame loop.
async fn tick(ticker: &mut Ticker) {
    ticker.next().await;
}

/// [`GameMode::Play`].
async fn play<const W: usize, const H: usize, const PILOT: bool>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    tilt: TiltConfig,
) -> GameExit {
    let mut player = match Player::<W, H, PILOT>::new(0, tilt, false) {
        Ok(player) => player,
        Err(e) => return GameExit::SetupFailed(e),
    };
    #[cfg(feature = "defmt")]
    defmt::info!("level 1: {=str}", player.level_name());
    // The finished attempt on show, and frames left to show it.
    let mut pause: Option<(Phase, u32)> = None;
    loop {
        tick(ticker).await;
        while let Ok(command) = links.commands.try_receive() {
            #[cfg(feature = "defmt")]
            defmt::info!("command {}", command);
            match command {
                Command::Restart => player.restart(),
                Command::NextLevel => player.next_level(),
                Command::Calibrate => player.calibrate(),
                Command::ToggleAutopilot => player.set_autopilot(!player.autopilot()),
                Command::Quit => return GameExit::Quit,
            }
            if matches!(command, Command::Restart | Command::NextLevel) {
                pause = None;
            }
        }
        if links.sensor_fault.load(Ordering::Relaxed) {
            if !links.frames.signaled() {
                links.frames.signal(fault_frame());
            }
            continue;
        }
        // Draw only once the display has taken the previous frame (it
        // refreshes at REFRESH_HZ < FRAME_HZ): rendering is not free.
        let draw = !links.frames.signaled();
        let frame = match pause {
            None => {
                let phase = player.frame(links.tilt.get().reading_mg());
                if phase != Phase::Playing {
                    #[cfg(feature = "defmt")]
                    defmt::info!(
                        "level {=usize} {=str}: {=str} after {=u64} steps",
                        player.level_index() + 1,
                        player.level_name(),
                        phase.as_str(),
                        player.game().steps()
                    );
                    let frames = if phase == Phase::Won {
                        WIN_PAUSE_FRAMES
                    } else {
                        LOSS_PAUSE_FRAMES
                    };
                    pause = Some((phase, frames));
                }
                draw.then(|| player.render())
            }
            Some((phase, 0)) => {
                pause = None;
                if phase == Phase::Won {
                    player.next_level();
                } else {
                    player.restart();
                }
                draw.then(|| player.render())
            }
            Some((phase, left)) => {
                pause = Some((phase, left - 1));
                draw.then(|| {
                    let frame = player.render();
                    if phase == Phase::Won {
                        win_frame(&frame, left)
                    } else {
                        frame
                    }
                })
            }
        };
        links.status.set(player.status());
        if let Some(frame) = frame {
            links.frames.signal(frame);
        }
    }
}

/// [`GameMode::Demo`]: each level exactly as the host simulator plays it
/// with `--autopilot` (a fresh [`Session`] with [`GAME_CONFIG`] and
/// [`SYNTHETIC_TILT`], the autopilot's reading taken from the game before
/// each frame, stopping at the first phase that is not
/// [`Phase::Playing`]), one frame per tick; then the outcome is shown for
/// [`WIN_PAUSE_FRAMES`].
async fn demo<const W: usize, const H: usize, const PILOT: bool>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
) -> GameExit {
    let mut summary = DemoSummary::default();
    for index in 0..LEVELS.len() {
        summary.levels = summary.levels.saturating_add(1);
        let mut player = match Player::<W, H, PILOT>::new(index, SYNTHETIC_TILT, true) {
            Ok(player) => player,
            Err(e) => {
                #[cfg(feature = "defmt")]
                defmt::error!(
                    "demo {=usize}/{=usize} level={=str} outcome=setup-error ({})",
                    index + 1,
                    LEVELS.len(),
                    level_name(index),
                    e
                );
                let _ = e;
                continue;
            }
        };
        let phase = loop {
            tick(ticker).await;
            let phase = player.frame(Tilt::FLAT.reading_mg());
            links.status.set(player.status());
            if !links.frames.signaled() || phase != Phase::Playing {
                links.frames.signal(player.render());
            }
            if phase != Phase::Playing {
                break phase;
            }
        };
        let game = player.game();
        summary.steps = summary.steps.saturating_add(game.steps());
        summary.frames = summary.frames.saturating_add(u64::from(game.frames()));
        if phase == Phase::Won {
            summary.won = summary.won.saturating_add(1);
        }
        #[cfg(feature = "defmt")]
        defmt::info!(
            "demo {=usize}/{=usize} level={=str} outcome={=str} steps={=u64} state_hash={=u64:016x}",
            index + 1,
            LEVELS.len(),
            player.level_name(),
            phase.as_str(),
            game.steps(),
            player.session().state_hash()
        );
        let last = player.render();
        // The pause's picture changes only when the flash does: each one is
        // sent once (the display keeps showing it), not once a refresh.
        let mut sent = None;
        for left in (1..=WIN_PAUSE_FRAMES).rev() {
            tick(ticker).await;
            let flash = phase == Phase::Won && win_flash(left);
            if sent != Some(flash) {
                sent = Some(flash);
                links.frames.signal(if phase == Phase::Won {
                    win_frame(&last, left)
                } else {
                    last
                });
            }
        }
    }
    GameExit::DemoDone(summary)
}

/// Something that can show BCM scan steps on a `W`×`H` LED matrix.
pub trait MatrixOutput<const W: usize, const H: usize> {
    /// Lights row `step.row` with the columns set in `step.columns`, holds it
    /// for `step.ticks` base ticks of the board's scan clock, then returns
    /// (the caller immediately shows the next step).
    fn show(&mut self, step: ScanStep) -> impl Future<Output = ()>;

    /// Shows one full refresh: the next [`Scanner::STEPS_PER_REFRESH`] steps
    /// of `scanner` (which is at the start of a refresh), in order, and
    /// returns when the refresh is over. By default, step by step with
    /// [`show`](Self::show); an output with nothing to wait for between steps
    /// (the virtual matrix) takes the whole refresh at once and saves an
    /// await per step.
    fn show_refresh(&mut self, scanner: &mut Scanner<W, H>) -> impl Future<Output = ()> {
        async move {
            for _ in 0..Scanner::<W, H>::STEPS_PER_REFRESH {
                self.show(scanner.next_step()).await;
            }
        }
    }
}

/// Scans the latest frame from [`Links::frames`] onto `output`, forever. A
/// new frame is taken only at the start of a refresh, so a refresh never
/// mixes frames (the scanner skips a frame equal to the one on show).
pub async fn display_task<O: MatrixOutput<W, H>, const W: usize, const H: usize>(
    links: &Links<W, H>,
    output: &mut O,
) -> ! {
    let mut scanner = Scanner::<W, H>::new();
    loop {
        if let Some(frame) = links.frames.try_take() {
            scanner.load(&frame);
        }
        output.show_refresh(&mut scanner).await;
    }
}

// ---------------------------------------------------------------------------
// The game
// ---------------------------------------------------------------------------

/// The name of built-in level `index` (`"?"` past the end).
pub fn level_name(index: usize) -> &'static str {
    LEVELS.get(index).map_or("?", |level| level.info.name)
}

/// One player's game on a `W`×`H` display: a [`Session`] on a built-in level
/// (fixed-point [`Fx`] physics), the [`Renderer`] that follows the marble,
/// and, when it plays, the [`Autopilot`]. Synchronous and board-agnostic:
/// [`game_task`] drives it from its ticker.
///
/// `PILOT` says whether the board has the autopilot at all
/// ([`Command::ToggleAutopilot`], [`GameMode::Demo`]). It is a constant, not
/// a flag, so that a board without it (the micro:bit: no button combination
/// is left for it) does not link the controller: about 6 KiB of flash.
#[derive(Clone, Debug)]
pub struct Player<const W: usize, const H: usize, const PILOT: bool> {
    level: usize,
    session: Session<'static, Fx>,
    renderer: Renderer<W, H>,
    tilt: TiltConfig,
    autopilot: Option<Autopilot>,
}

impl<const W: usize, const H: usize, const PILOT: bool> Player<W, H, PILOT> {
    /// Built-in level `level` (wrapped into range) with the tilt path `tilt`;
    /// the autopilot plays if `autopilot` (and the board has it, `PILOT`).
    pub fn new(level: usize, tilt: TiltConfig, autopilot: bool) -> Result<Self, SetupError> {
        let level = level % LEVELS.len();
        let view = LEVELS[level];
        Ok(Player {
            level,
            session: Session::new(view, GAME_CONFIG, tilt)?,
            renderer: Renderer::new(),
            tilt,
            autopilot: (PILOT && autopilot).then(|| Autopilot::new(&view)),
        })
    }

    /// Index of the level in [`LEVELS`].
    pub fn level_index(&self) -> usize {
        self.level
    }
    /// The level's name.
    pub fn level_name(&self) -> &'static str {
        level_name(self.level)
    }
    /// The session.
    pub fn session(&self) -> &Session<'static, Fx> {
        &self.session
    }
    /// The session, mutably (profiling, tools).
    pub fn session_mut(&mut self) -> &mut Session<'static, Fx> {
        &mut self.session
    }
    /// The game.
    pub fn game(&self) -> &Game<'static, Fx> {
        self.session.game()
    }
    /// Whether the autopilot plays.
    pub fn autopilot(&self) -> bool {
        self.autopilot.is_some()
    }

    /// Hands the board to the autopilot (planned afresh for the level), or
    /// takes it back. Without `PILOT` it stays off.
    pub fn set_autopilot(&mut self, on: bool) {
        self.autopilot = (PILOT && on).then(|| Autopilot::new(&LEVELS[self.level]));
    }

    /// The reading for the next frame: the autopilot's when it plays, else
    /// `tilt_mg` (the accelerometer's or the keys').
    pub fn reading(&mut self, tilt_mg: [i32; 3]) -> [i32; 3] {
        match &mut self.autopilot {
            // `PILOT` again, though the pilot is never set without it: the
            // compiler cannot see that, and the constant drops the controller
            // (~2 KB) from a board without it.
            Some(pilot) if PILOT => pilot.reading_mg(self.session.game()),
            _ => tilt_mg,
        }
    }

    /// Plays one frame (`2^substeps_log2` physics steps) with
    /// [`Player::reading`]`(tilt_mg)` and returns where the attempt stands. A
    /// finished attempt stays finished (the game does not step any more).
    pub fn frame(&mut self, tilt_mg: [i32; 3]) -> Phase {
        let reading = self.reading(tilt_mg);
        self.session.frame(reading)
    }

    /// The current picture.
    pub fn render(&mut self) -> Frame<W, H> {
        self.renderer.render(self.session.game())
    }

    /// For status displays.
    pub fn status(&self) -> Status {
        let game = self.session.game();
        Status {
            level: self.level.min(usize::from(u8::MAX)) as u8,
            phase: game.phase(),
            frames: game.frames(),
            reading: self.session.reading(),
            autopilot: self.autopilot(),
        }
    }

    /// Starts the level over (the tilt calibration is kept).
    pub fn restart(&mut self) {
        self.session.restart();
        self.renderer.reset();
        if self.autopilot.is_some() {
            self.set_autopilot(true);
        }
    }

    /// Moves on to the next built-in level (after the last: the first),
    /// keeping the tilt calibration and the autopilot setting. A level that
    /// cannot be set up (never for the tested built-in ones) is skipped.
    pub fn next_level(&mut self) {
        let calibration = self.session.tilt().calibration();
        for offset in 1..=LEVELS.len() {
            if let Ok(mut next) = Self::new(self.level + offset, self.tilt, self.autopilot()) {
                next.session.tilt_mut().set_calibration(calibration);
                *self = next;
                #[cfg(feature = "defmt")]
                defmt::info!("level {=usize}: {=str}", self.level + 1, self.level_name());
                return;
            }
        }
    }

    /// Takes the current filtered tilt as level (an implausible one is
    /// refused).
    pub fn calibrate(&mut self) {
        let reading = self.session.tilt().filtered_reading_mg();
        let result = self.session.tilt_mut().calibrate(reading);
        #[cfg(feature = "defmt")]
        defmt::info!("calibrate: {}", result);
        let _ = result;
    }
}

/// The won level's display: the final picture flashing with a full-on
/// screen, [`WIN_FLASH_FRAMES`] each; `left` counts the frames down.
pub fn win_frame<const W: usize, const H: usize>(last: &Frame<W, H>, left: u32) -> Frame<W, H> {
    if win_flash(left) {
        Frame::filled(MAX_BRIGHTNESS)
    } else {
        *last
    }
}

/// Whether [`win_frame`] shows the full-on screen with `left` frames to go.
fn win_flash(left: u32) -> bool {
    (left / WIN_FLASH_FRAMES.max(1)).is_multiple_of(2)
}

/// Shown while the accelerometer is down: a cross from corner to corner.
pub fn fault_frame<const W: usize, const H: usize>() -> Frame<W, H> {
    let mut frame = Frame::new();
    for y in 0..H {
        let x = if H > 1 { y * (W - 1) / (H - 1) } else { 0 };
        frame.set(x, y, MAX_BRIGHTNESS);
        frame.set(W - 1 - x, y, MAX_BRIGHTNESS);
    }
    frame
}

// ---------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------

/// Tilt added per key press, milli-g.
pub const KEY_TILT_STEP_MG: i32 = 100;
/// Largest tilt reachable with keys, milli-g per axis.
pub const KEY_TILT_MAX_MG: i32 = 500;

/// A key recognised by [`KeyDecoder`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Key {
    /// Arrow up or `w`: roll the marble up the screen (away from the player).
    Up,
    /// Arrow down or `s`.
    Down,
    /// Arrow left or `a`.
    Left,
    /// Arrow right or `d`.
    Right,
    /// Space: level the board.
    Level,
    /// `r`.
    Restart,
    /// `n`.
    Next,
    /// `c`: take the current tilt as level.
    Calibrate,
    /// `p`: autopilot on / off.
    Autopilot,
    /// `q` or Ctrl-C.
    Quit,
}

/// Escape-sequence state of [`KeyDecoder`].
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
enum Escape {
    #[default]
    None,
    /// After ESC.
    Esc,
    /// After `ESC [` or `ESC O`, inside a control sequence.
    Sequence,
}

/// Decodes terminal bytes (raw mode) into [`Key`]s: arrow keys (`ESC [ A`,
/// `ESC O A`, with or without modifiers like `ESC [ 1 ; 5 A`), WASD, space,
/// `r`, `n`, `c`, `p`, `q`, Ctrl-C. Other bytes are ignored.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeyDecoder {
    state: Escape,
}

impl KeyDecoder {
    /// A decoder outside any escape sequence.
    pub const fn new() -> Self {
        Self {
            state: Escape::None,
        }
    }

    /// Feeds one byte; returns a key when one is complete.
    pub fn feed(&mut self, byte: u8) -> Option<Key> {
        match self.state {
            Escape::None => Self::plain(byte, &mut self.state),
            Escape::Esc => {
                if byte == b'[' || byte == b'O' {
                    self.state = Escape::Sequence;
                    None
                } else {
                    self.state = Escape::None;
                    Self::plain(byte, &mut self.state)
                }
            }
            Escape::Sequence => match byte {
                // Parameters and intermediates: stay in the sequence.
                0x20..=0x3f => None,
                final_byte => {
                    self.state = Escape::None;
                    match final_byte {
                        b'A' => Some(Key::Up),
                        b'B' => Some(Key::Down),
                        b'C' => Some(Key::Right),
                        b'D' => Some(Key::Left),
                        _ => None,
                    }
                }
            },
        }
    }

    fn plain(byte: u8, state: &mut Escape) -> Option<Key> {
        match byte {
            0x1b => {
                *state = Escape::Esc;
                None
            }
            b'w' | b'W' => Some(Key::Up),
            b's' | b'S' => Some(Key::Down),
            b'a' | b'A' => Some(Key::Left),
            b'd' | b'D' => Some(Key::Right),
            b' ' => Some(Key::Level),
            b'r' | b'R' => Some(Key::Restart),
            b'n' | b'N' => Some(Key::Next),
            b'c' | b'C' => Some(Key::Calibrate),
            b'p' | b'P' => Some(Key::Autopilot),
            b'q' | b'Q' | 0x03 => Some(Key::Quit),
            _ => None,
        }
    }
}

/// A virtual accelerometer driven by keys: each arrow/WASD press tilts the
/// board one [`KEY_TILT_STEP_MG`] step further that way (up to
/// [`KEY_TILT_MAX_MG`]); space levels it. A terminal sends no key releases,
/// so the tilt stays until changed, like a board held tilted.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeyTilt {
    decoder: KeyDecoder,
    x: i32,
    z: i32,
}

impl KeyTilt {
    /// Flat, outside any escape sequence.
    pub const fn new() -> Self {
        Self {
            decoder: KeyDecoder::new(),
            x: 0,
            z: 0,
        }
    }

    /// Feeds one terminal byte; returns the event it completes, if any.
    pub fn feed(&mut self, byte: u8) -> Option<InputEvent> {
        let step = KEY_TILT_STEP_MG;
        let (dx, dz) = match self.decoder.feed(byte)? {
            // Marble up the screen = towards -z: raise the near edge, z > 0.
            Key::Up => (0, step),
            Key::Down => (0, -step),
            // Marble right = towards +x: lower the right edge, x < 0.
            Key::Right => (-step, 0),
            Key::Left => (step, 0),
            Key::Level => (-self.x, -self.z),
            Key::Restart => return Some(InputEvent::Command(Command::Restart)),
            Key::Next => return Some(InputEvent::Command(Command::NextLevel)),
            Key::Calibrate => return Some(InputEvent::Command(Command::Calibrate)),
            Key::Autopilot => return Some(InputEvent::Command(Command::ToggleAutopilot)),
            Key::Quit => return Some(InputEvent::Command(Command::Quit)),
        };
        let max = KEY_TILT_MAX_MG;
        self.x = (self.x + dx).clamp(-max, max);
        self.z = (self.z + dz).clamp(-max, max);
        Some(InputEvent::Tilt(Tilt::from_xz(self.x, self.z)))
    }
}

/// [`TiltInput`] from an interactive terminal's bytes, via [`KeyTilt`].
pub struct TerminalInput<S: ByteSource> {
    source: S,
    keys: KeyTilt,
}

impl<S: ByteSource> TerminalInput<S> {
    /// Reads keys from `source`.
    pub const fn new(source: S) -> Self {
        Self {
            source,
            keys: KeyTilt::new(),
        }
    }
}

impl<S: ByteSource> TiltInput for TerminalInput<S> {
    async fn next_event(&mut self) -> InputEvent {
        loop {
            let byte = self.source.read_byte().await;
            if let Some(event) = self.keys.feed(byte) {
                return event;
            }
        }
    }
}
