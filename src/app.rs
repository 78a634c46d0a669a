//! The firmware's tasks and the links between them, shared by every board.
//!
//! embassy tasks cannot be generic, so the shape is: this module has plain
//! `async fn`s parameterised by small traits, and each board binary wraps them
//! in thin `#[embassy_executor::task]` functions that pass its own hardware and
//! its [`Links`]:
//!
//! ```text
//!  input_task(TiltInput) ──tilt (latest)────────┐
//!                       └─events (queue: commands, sensor down/up)┴─> game_task ──frames (latest)──> display_task(MatrixOutput)
//!                                              │ Ticker at FRAME_HZ (128 Hz), each tick:
//!                                              │ Player::handle(events), Player::tick(tilt) → Session::frame → render
//!                                              └──sounds (queue, dropped when full)──> sound_task(SoundOutput)
//! ```
//!
//! * [`TiltInput`]: where tilt and commands come from (accelerometer and
//!   buttons, or a terminal via [`TerminalInput`]).
//! * [`game_task`] runs the game ([`Player`], the game layer's synchronous
//!   loop step) at the game's frame rate [`FRAME_HZ`] on an embassy `Ticker`
//!   (not `Timer::after`, which rounds up to the time driver's tick and
//!   drifts). In [`GameMode::Demo`] the autopilot plays every built-in level
//!   once, exactly as `cargo sim -- --level <name> --autopilot` does, and each
//!   level's outcome, physics steps and `state_hash` are logged.
//! * [`MatrixOutput`]: how one BCM scan step of [`crate::matrix::Scanner`]
//!   reaches LEDs (real pins, or QEMU's virtual matrix).
//! * `SoundOutput` (feature `sound`): how a [`crate::sound::Sound`] is played (QEMU: a log line, the
//!   terminal's bell on a win), from the game's queue by `sound_task`.
//! * [`Console`]: a blocking byte sink for an interactive terminal.
//!
//! The display size `W`×`H` and whether the autopilot is linked (`PILOT`) are
//! the board binary's choice, passed as const generics: the micro:bit's 5×5
//! matrix, whose view scrolls with the marble, without the autopilot; or for
//! QEMU a 19×9 virtual matrix that shows every built-in maze whole. The board
//! binary owns the [`Links`] between its tasks in a `static`.

use core::cell::Cell;
use core::future::Future;

use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::{Duration, Ticker};

use crate::game::levels::LEVELS;
use crate::game::player::{Player, Status, WIN_PAUSE_FRAMES};
use crate::game::rules::Phase;
use crate::game::session::SYNTHETIC_TILT;
use crate::input::event::{Command, InputEvent, Tilt};
use crate::input::keys::KeyTilt;
use crate::input::tilt::TiltConfig;
use crate::matrix::{Frame, Scanner};
use crate::physics::world::SetupError;
#[cfg(feature = "records")]
use crate::records::{Offer, Records};
use crate::render::screens::{win_flash, win_frame};
#[cfg(feature = "sound")]
use crate::sound::Sound;
#[cfg(feature = "records")]
use embedded_storage_async::nor_flash::NorFlash;

pub use crate::game::player::FRAME_HZ;
pub use crate::matrix::output::{Console, MatrixOutput, REFRESH_HZ};

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

/// The links between the tasks of a board with a `W`×`H` display. Each board
/// binary owns one in a `static` (the size is the board's, so it cannot be a
/// static of this module) and hands it to the tasks.
pub struct Links<const W: usize, const H: usize> {
    /// Latest tilt, written by [`input_task`], read by [`game_task`] each frame.
    pub tilt: Latest<Tilt>,
    /// Commands and the sensor's ups and downs, from [`input_task`] to
    /// [`game_task`], in order.
    pub events: Channel<CriticalSectionRawMutex, InputEvent, 8>,
    /// Latest frame from [`game_task`] to [`display_task`] (older ones are
    /// dropped).
    pub frames: Signal<CriticalSectionRawMutex, Frame<W, H>>,
    /// The game's status after its latest frame.
    pub status: Latest<Status>,
    /// Set by a board before the demo starts: the demo counts each frame's
    /// instructions with it and logs a profile per level (see [`Meter`]).
    pub meter: Latest<Option<Meter>>,
    /// Sounds from [`game_task`] to [`sound_task`], in order (the game never
    /// waits: what does not fit is dropped). Feature `sound` only.
    #[cfg(feature = "sound")]
    pub sounds: Channel<CriticalSectionRawMutex, Sound, 8>,
    /// Levels won by the player (not the autopilot), from [`game_task`] to
    /// `records_task`. Feature `records` only.
    #[cfg(feature = "records")]
    pub wins: Channel<CriticalSectionRawMutex, Win, 2>,
    /// Every level's record as `records_task` last read or wrote it.
    #[cfg(feature = "records")]
    pub bests: Latest<Bests>,
    /// The level whose win `records_task` has just stored as a new record.
    #[cfg(feature = "records")]
    pub new_record: Signal<CriticalSectionRawMutex, u8>,
}

/// A level won by the player, in game frames ([`FRAME_HZ`] per second).
#[cfg(feature = "records")]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Win {
    /// Index of the level in [`LEVELS`].
    pub level: u8,
    /// The time it took.
    pub frames: u32,
}

/// Each built-in level's record in frames, if it has one.
#[cfg(feature = "records")]
pub type Bests = [Option<u32>; LEVELS.len()];

impl<const W: usize, const H: usize> Links<W, H> {
    /// Nothing sent yet: a flat board, no command, no frame.
    pub const fn new() -> Self {
        Self {
            tilt: Latest::new(Tilt::FLAT),
            events: Channel::new(),
            frames: Signal::new(),
            status: Latest::new(Status::START),
            meter: Latest::new(None),
            #[cfg(feature = "sound")]
            sounds: Channel::new(),
            #[cfg(feature = "records")]
            wins: Channel::new(),
            #[cfg(feature = "records")]
            bests: Latest::new([None; LEVELS.len()]),
            #[cfg(feature = "records")]
            new_record: Signal::new(),
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

/// Forwards events from `input`: tilts to [`Links::tilt`], the rest to
/// [`Links::events`], forever.
pub async fn input_task<I: TiltInput, const W: usize, const H: usize>(
    links: &Links<W, H>,
    input: &mut I,
) -> ! {
    loop {
        match input.next_event().await {
            InputEvent::Tilt(tilt) => links.tilt.set(tilt),
            event => links.events.send(event).await,
        }
    }
}

/// How [`game_task`] plays.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GameMode {
    /// A player with a tilt input: endless, levels in order, commands ([`Links::events`])
    /// obeyed. `tilt` configures the game's tilt path:
    /// [`TiltConfig::DEFAULT`] for a real accelerometer, [`SYNTHETIC_TILT`]
    /// for keys.
    Play {
        /// The tilt path's configuration.
        tilt: TiltConfig,
        /// The level to start at (index in [`LEVELS`], wrapped): 0, or the
        /// one the toy fell asleep on. Feature `sleep` only (without it, 0).
        #[cfg(feature = "sleep")]
        level: u8,
    },
    /// The headless demo: the autopilot plays each built-in level once, in
    /// order, then [`game_task`] returns.
    Demo {
        /// Offer the autopilot's wins to the records task (feature
        /// `records`) as if they were a player's: the records check, which
        /// runs the demo twice and reads the first run's records back in the
        /// second. A player's game never records the autopilot's wins.
        records: bool,
    },
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
    /// Nobody touched the toy for two minutes ([`crate::input::idle`]):
    /// the board may sleep, and resume at the start of `level`. Feature
    /// `sleep` only.
    #[cfg(feature = "sleep")]
    Asleep {
        /// The level on show (index in [`LEVELS`]).
        level: u8,
    },
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
/// board has the autopilot, `EVENTS` which physics stepper it links (see
/// [`Player`]).
pub async fn game_task<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    links: &Links<W, H>,
    mode: GameMode,
) -> GameExit {
    let mut ticker = Ticker::every(Duration::from_hz(u64::from(FRAME_HZ)));
    match mode {
        #[cfg(not(feature = "sleep"))]
        GameMode::Play { tilt } => play::<W, H, PILOT, EVENTS>(links, &mut ticker, tilt).await,
        #[cfg(feature = "sleep")]
        GameMode::Play { tilt, level } => {
            play::<W, H, PILOT, EVENTS>(links, &mut ticker, tilt, level).await
        }
        GameMode::Demo { records } => {
            demo::<W, H, PILOT, EVENTS>(links, &mut ticker, records).await
        }
    }
}

/// [`GameMode::Play`]: [`Player::tick`] at every tick of the frame clock.
async fn play<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    tilt: TiltConfig,
    #[cfg(feature = "sleep")] level: u8,
) -> GameExit {
    // Without `sleep` the start is the literal 0, as it always was: on the
    // micro:bit v1 even a start level passed in as a constant measured 2 KB
    // more stack (`cargo xtask check-microbit-v1`), over its RAM budget.
    #[cfg(feature = "sleep")]
    let start = usize::from(level);
    #[cfg(not(feature = "sleep"))]
    let start = 0;
    let mut player = match Player::<W, H, PILOT, EVENTS>::new(&LEVELS, start, tilt, false) {
        Ok(player) => player,
        Err(e) => return GameExit::SetupFailed(e),
    };
    #[cfg(feature = "defmt")]
    defmt::info!("level {=usize}: {=str}", start + 1, player.level_name());
    // Two minutes without a command and with the tilt still (feature `sleep`).
    #[cfg(feature = "sleep")]
    let mut idle =
        crate::input::idle::Idle::new(crate::input::idle::IdleConfig::two_minutes(FRAME_HZ));
    loop {
        ticker.next().await;
        while let Ok(event) = links.events.try_receive() {
            #[cfg(feature = "defmt")]
            defmt::info!("input {}", event);
            #[cfg(feature = "sleep")]
            if let InputEvent::Command(_) = event {
                idle.activity();
            }
            if !player.handle(event) {
                return GameExit::Quit;
            }
        }
        // The autopilot playing is the toy in use.
        #[cfg(feature = "sleep")]
        if idle.tick(links.tilt.get().reading_mg()) && !player.autopilot() {
            #[cfg(feature = "defmt")]
            defmt::info!(
                "idle for two minutes: asleep on level {=usize}",
                player.level_index() + 1
            );
            return GameExit::Asleep {
                level: player.level_index().min(usize::from(u8::MAX)) as u8,
            };
        }
        // Draw only once the display has taken the previous frame (it
        // refreshes at REFRESH_HZ < FRAME_HZ): rendering is not free.
        let draw = !links.frames.signaled();
        let tick = player.tick(links.tilt.get().reading_mg(), draw);
        if let Some(phase) = tick.finished {
            #[cfg(feature = "defmt")]
            defmt::info!(
                "level {=usize} {=str}: {=str} after {=u64} steps",
                player.level_index() + 1,
                player.level_name(),
                phase.as_str(),
                player.game().steps()
            );
            #[cfg(feature = "records")]
            if phase == Phase::Won && !player.autopilot() {
                // The records task writes the flash while the win is on show,
                // between levels; a full queue drops the win, never the game.
                let _ = links.wins.try_send(Win {
                    level: player.level_index().min(usize::from(u8::MAX)) as u8,
                    frames: player.game().clock_frames(),
                });
            }
            let _ = phase;
        }
        #[cfg(feature = "records")]
        if links.new_record.try_take() == Some(player.level_index() as u8) {
            player.announce_record();
        }
        #[cfg(feature = "records")]
        let status = Status {
            best: links
                .bests
                .get()
                .get(player.level_index())
                .copied()
                .flatten(),
            ..player.status()
        };
        #[cfg(not(feature = "records"))]
        let status = player.status();
        links.status.set(status);
        if let Some(frame) = tick.frame {
            links.frames.signal(frame);
        }
        #[cfg(feature = "sound")]
        for sound in tick.sounds.iter() {
            let _ = links.sounds.try_send(sound);
        }
    }
}

/// Runs `f` and returns the instructions it took: a board's CPU meter. Set
/// in [`Links::meter`] before a demo, it makes the demo log per level
/// `profile LEVEL: N frames, instructions per frame: physics AVG (max MAX),
/// autopilot AVG, render AVG` (render per frame drawn). The game is the
/// demo's, call for call (the same hashes).
pub type Meter = fn(&mut dyn FnMut()) -> u64;

/// [`Player::frame`]'s two calls, each counted (out of line: the demo's
/// own path keeps its stack).
#[inline(never)]
fn profiled_frame<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    player: &mut Player<W, H, PILOT, EVENTS>,
    meter: Meter,
    profile: &mut Profile,
) -> Phase {
    let mut reading = [0; 3];
    let pilot = meter(&mut || reading = player.reading(Tilt::FLAT.reading_mg()));
    let mut phase = Phase::Playing;
    let physics = meter(&mut || phase = player.session_mut().frame_in::<EVENTS>(reading));
    profile.frame(pilot, physics);
    phase
}

/// [`Player::render`], counted.
#[inline(never)]
fn profiled_render<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    player: &mut Player<W, H, PILOT, EVENTS>,
    meter: Meter,
    profile: &mut Profile,
) -> Frame<W, H> {
    let mut picture = Frame::new();
    let render = meter(&mut || picture = player.render());
    profile.render(render);
    picture
}

/// One level's instruction counts (see [`Meter`]).
#[derive(Clone, Copy, Debug, Default)]
struct Profile {
    frames: u32,
    physics: u64,
    physics_max: u64,
    pilot: u64,
    renders: u32,
    render: u64,
}

impl Profile {
    fn frame(&mut self, pilot: u64, physics: u64) {
        self.frames = self.frames.saturating_add(1);
        self.pilot = self.pilot.saturating_add(pilot);
        self.physics = self.physics.saturating_add(physics);
        self.physics_max = self.physics_max.max(physics);
    }

    fn render(&mut self, render: u64) {
        self.renders = self.renders.saturating_add(1);
        self.render = self.render.saturating_add(render);
    }

    fn log(&self, level: &str) {
        let frames = u64::from(self.frames.max(1));
        #[cfg(feature = "defmt")]
        defmt::info!(
            "profile {=str}: {=u32} frames, instructions per frame: physics {=u64} (max {=u64}), autopilot {=u64}, render {=u64}",
            level,
            self.frames,
            self.physics / frames,
            self.physics_max,
            self.pilot / frames,
            self.render / u64::from(self.renders.max(1))
        );
        let _ = (level, frames);
    }
}

/// Waits for the next frame tick, taking the input events meanwhile: in the
/// demo only the sensor's (a downed sensor pauses it like a game) and Quit.
/// Returns `false` on Quit.
async fn demo_tick<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    player: &mut Player<W, H, PILOT, EVENTS>,
) -> bool {
    ticker.next().await;
    while let Ok(event) = links.events.try_receive() {
        match event {
            InputEvent::SensorDown(_) | InputEvent::SensorUp => {
                #[cfg(feature = "defmt")]
                defmt::info!("demo: {}", event);
                player.handle(event);
            }
            InputEvent::Command(Command::Quit) => return false,
            InputEvent::Command(_) | InputEvent::Tilt(_) => {}
        }
    }
    true
}

/// [`GameMode::Demo`]: each level exactly as the host simulator plays it
/// with `--autopilot` (a fresh session with the player's configuration and
/// [`SYNTHETIC_TILT`], the autopilot's reading taken from the game before
/// each frame, stopping at the first phase that is not
/// [`Phase::Playing`]), one frame per tick, paused while the sensor is down;
/// then the outcome is shown for [`WIN_PAUSE_FRAMES`].
async fn demo<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    records: bool,
) -> GameExit {
    let meter = links.meter.get();
    let mut summary = DemoSummary::default();
    let mut sensor = None;
    // The checkers replay the demo with `cargo sim -- --stepping <this>`.
    #[cfg(feature = "defmt")]
    defmt::info!(
        "demo stepping={=str}",
        if EVENTS { "events" } else { "fixed" }
    );
    for (index, level) in LEVELS.iter().enumerate() {
        // Named in the defmt log only.
        let _ = level;
        summary.levels = summary.levels.saturating_add(1);
        let mut player =
            match Player::<W, H, PILOT, EVENTS>::new(&LEVELS, index, SYNTHETIC_TILT, true) {
                Ok(player) => player,
                Err(e) => {
                    #[cfg(feature = "defmt")]
                    defmt::error!(
                        "demo {=usize}/{=usize} level={=str} outcome=setup-error ({})",
                        index + 1,
                        LEVELS.len(),
                        level.info.name,
                        e
                    );
                    let _ = e;
                    continue;
                }
            };
        if let Some(fault) = sensor {
            player.handle(InputEvent::SensorDown(fault));
        }
        let mut profile = Profile::default();
        let phase = loop {
            if !demo_tick(links, ticker, &mut player).await {
                return GameExit::Quit;
            }
            if player.sensor_down().is_some() {
                // Paused: the same picture as the game's (Player::tick).
                if let Some(frame) = player.tick(Tilt::FLAT.reading_mg(), true).frame {
                    links.frames.signal(frame);
                }
                links.status.set(player.status());
                continue;
            }
            let phase = match meter {
                None => player.frame(Tilt::FLAT.reading_mg()),
                Some(meter) => profiled_frame(&mut player, meter, &mut profile),
            };
            links.status.set(player.status());
            if !links.frames.signaled() || phase != Phase::Playing {
                links.frames.signal(match meter {
                    None => player.render(),
                    Some(meter) => profiled_render(&mut player, meter, &mut profile),
                });
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
            #[cfg(feature = "records")]
            if records {
                links
                    .wins
                    .send(Win {
                        level: index.min(usize::from(u8::MAX)) as u8,
                        frames: game.clock_frames(),
                    })
                    .await;
            }
        }
        let _ = records;
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
        if meter.is_some() {
            profile.log(player.level_name());
        }
        let last = player.render();
        // The pause's picture changes only when the flash does: each one is
        // sent once (the display keeps showing it), not once a refresh.
        let mut sent = None;
        for left in (1..=WIN_PAUSE_FRAMES).rev() {
            if !demo_tick(links, ticker, &mut player).await {
                return GameExit::Quit;
            }
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
        sensor = player.sensor_down();
    }
    GameExit::DemoDone(summary)
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

/// Keeps the best times (feature `records`): reads every level's record into
/// [`Links::bests`], then offers each [`Win`] from [`Links::wins`] to
/// `records` and, on a new record, tells the game ([`Links::new_record`]).
/// `written` runs after each update that wrote (QEMU saves its flash image to
/// a host file there). Flash errors are logged and the game goes on without
/// the record.
#[cfg(feature = "records")]
pub async fn records_task<F: NorFlash, const W: usize, const H: usize>(
    links: &Links<W, H>,
    records: &mut Records<F>,
    mut written: impl FnMut(&mut F),
) -> ! {
    let mut bests: Bests = [None; LEVELS.len()];
    read_bests(records, &mut bests).await;
    links.bests.set(bests);
    loop {
        let win = links.wins.receive().await;
        let offer = records.offer(win.level, win.frames).await;
        #[cfg(feature = "defmt")]
        log_offer(win, offer);
        if let Ok(Offer::Kept { .. }) = offer {
            continue;
        }
        // Something was written (a record, or an erase of a corrupted
        // region): every level's record again, as the flash now holds them.
        read_bests(records, &mut bests).await;
        links.bests.set(bests);
        if let Ok(Offer::New { .. }) = offer {
            links.new_record.signal(win.level);
        }
        written(records.flash());
    }
}

/// Every level's record into `bests` (one that cannot be read: none).
#[cfg(feature = "records")]
async fn read_bests<F: NorFlash>(records: &mut Records<F>, bests: &mut Bests) {
    for (level, best) in bests.iter_mut().enumerate() {
        *best = match records.best(level as u8).await {
            Ok(b) => b,
            Err(e) => {
                #[cfg(feature = "defmt")]
                defmt::warn!("records: level {=usize}: {=str}", level + 1, e.as_str());
                let _ = e;
                None
            }
        };
    }
}

/// The record news in the log: the time in seconds with hundredths.
#[cfg(all(feature = "records", feature = "defmt"))]
fn log_offer(win: Win, offer: Result<Offer, crate::records::RecordError>) {
    let name = LEVELS
        .get(usize::from(win.level))
        .map_or("?", |level| level.info.name);
    let cs = |frames: u32| frames.saturating_mul(100) / FRAME_HZ;
    match offer {
        Ok(Offer::New {
            previous: Some(previous),
        }) => defmt::info!(
            "new record: level {=u8} {=str} in {=u32}.{=u32:02} s (was {=u32}.{=u32:02} s)",
            win.level + 1,
            name,
            cs(win.frames) / 100,
            cs(win.frames) % 100,
            cs(previous) / 100,
            cs(previous) % 100
        ),
        Ok(Offer::New { previous: None }) => defmt::info!(
            "new record: level {=u8} {=str} in {=u32}.{=u32:02} s (the first)",
            win.level + 1,
            name,
            cs(win.frames) / 100,
            cs(win.frames) % 100
        ),
        Ok(Offer::Kept { best }) => defmt::info!(
            "level {=u8} {=str} in {=u32}.{=u32:02} s: the record stays {=u32}.{=u32:02} s",
            win.level + 1,
            name,
            cs(win.frames) / 100,
            cs(win.frames) % 100,
            cs(best) / 100,
            cs(best) % 100
        ),
        Err(e) => defmt::warn!("records: {=str}", e.as_str()),
    }
}

/// Where a board plays a [`Sound`] (feature `sound`).
#[cfg(feature = "sound")]
pub trait SoundOutput {
    /// Plays `sound`; returns when the next one may start (a speaker's
    /// sequence may still be sounding: it must not block the game).
    fn play(&mut self, sound: Sound) -> impl Future<Output = ()>;
}

/// Plays the sounds from [`Links::sounds`] on `output`, in order, forever.
#[cfg(feature = "sound")]
pub async fn sound_task<O: SoundOutput, const W: usize, const H: usize>(
    links: &Links<W, H>,
    output: &mut O,
) -> ! {
    loop {
        let sound = links.sounds.receive().await;
        output.play(sound).await;
    }
}

/// [`SoundOutput`] for a terminal: each sound in the log, and the terminal's
/// bell on a win (the one sound a terminal has).
#[cfg(feature = "sound")]
pub struct TerminalSound<C: Console> {
    console: C,
}

#[cfg(feature = "sound")]
impl<C: Console> TerminalSound<C> {
    /// Rings `console`'s bell.
    pub const fn new(console: C) -> Self {
        Self { console }
    }
}

#[cfg(feature = "sound")]
impl<C: Console> SoundOutput for TerminalSound<C> {
    async fn play(&mut self, sound: Sound) {
        #[cfg(feature = "defmt")]
        defmt::info!("sound {}", sound);
        if sound == Sound::Win {
            self.console.write(b"\x07");
        }
    }
}

// ---------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------

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
