//! The headless demo ([`GameMode::Demo`](super::GameMode::Demo)): the
//! autopilot plays the levels of the board's levels region as `cargo sim --
//! --level FILE --autopilot` plays their files, then every built-in level
//! once, exactly as `cargo sim -- --level <name> --autopilot` does, then the
//! first [`DEMO_MAZES`] generated mazes of the endless run as `cargo sim --
//! --generate …  --autopilot` does, and each level's outcome, physics steps
//! and `state_hash` are logged, with an instruction profile when the board has
//! a [`Meter`].

use embassy_time::Ticker;

#[cfg(feature = "ghosts")]
use super::ghosts::GhostStore;
#[cfg(feature = "records")]
use super::links::Win;
use super::links::{Links, Meter};
use super::mode::{DemoSummary, GameExit};
use crate::game::endless::{Endless, MazeArgs, MazeSlot, Seeds, StageError, DEMO_MAZES};
use crate::game::levels::LEVELS;
use crate::game::rules::Phase;
use crate::game::session::{Session, SYNTHETIC_TILT};
use crate::game::stress::{HARD_MAZES, STRESS};
use crate::input::axes::AccelMg;
use crate::input::event::{Command, InputEvent};
use crate::matrix::Frame;
use crate::physics::world::SetupError;
use crate::physics::Fx;
use crate::player::{Player, Status, WIN_PAUSE_FRAMES};
use crate::render::screens::{win_flash, win_frame};

/// [`Player::frame`]'s two calls, each counted (out of line: the demo's
/// own path keeps its stack).
#[inline(never)]
fn profiled_frame<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    player: &mut Player<'_, W, H, PILOT, EVENTS>,
    meter: Meter,
    profile: &mut Profile,
) -> Phase {
    let mut reading = AccelMg::default();
    let pilot = meter(&mut || reading = player.reading(AccelMg::LEVEL));
    let mut phase = Phase::Playing;
    let physics = meter(&mut || phase = player.session_mut().frame_in::<EVENTS>(reading));
    profile.frame(pilot, physics);
    phase
}

/// [`Player::render`], counted.
#[inline(never)]
fn profiled_render<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    player: &mut Player<'_, W, H, PILOT, EVENTS>,
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

/// Frames a profile replays of each level, generated maze or stress scene
/// at most (a scene plays its own count).
pub const PROFILE_FRAMES: u32 = 1024;

/// Profiles what the built-in levels do not reach, on every board alike:
/// each of [`HARD_MAZES`] (made in `mazes`), the autopilot playing up to
/// [`PROFILE_FRAMES`] of its frames, then every stress scene
/// ([`STRESS`]) with its scripted tilt. Logs for each the `profile NAME: …`
/// line of a level (the physics only: autopilot and render 0) and how often
/// the flight budget cut a marble's step (`budget NAME: N marble-steps cut`),
/// which `cargo xtask check-demo` and `check-microbit-v1` read.
///
/// `count` plays one frame of the session on the reading and returns its
/// phase and the instructions it took: the board's CPU meter around
/// `Session::frame_in` (called once here, so that it is inlined once). A
/// stress scene is played through a player without the autopilot: its
/// session is the one `Session::new` makes with the player's configuration,
/// and one loop for both kinds is less flash on the micro:bit v1 than two.
/// A scene that cannot be set up logs nothing: the checks want every line.
/// Out of line: the players live in its frame, not in the caller's future.
#[inline(never)]
pub fn profile_scenes<
    const W: usize,
    const H: usize,
    const PILOT: bool,
    const EVENTS: bool,
    const WORDS: usize,
    const TEXT: usize,
>(
    mazes: &mut MazeSlot<WORDS, TEXT>,
    mut count: impl FnMut(&mut Session<'_, Fx>, AccelMg) -> (Phase, u64),
) {
    for number in 0..HARD_MAZES.len() + STRESS.len() {
        // A maze is played by the autopilot up to PROFILE_FRAMES, a stress
        // scene by its script for all its frames, the phase aside.
        let (level, frames, script) = match number.checked_sub(HARD_MAZES.len()) {
            None => match HARD_MAZES.get(number).map(|&args| mazes.make(args)) {
                Some(Ok(level)) => (level, PROFILE_FRAMES, None),
                _ => continue,
            },
            Some(k) => match STRESS.get(k) {
                Some(scene) => (scene.level, scene.frames, Some(scene.tilt)),
                None => continue,
            },
        };
        // Matched by reference: moving the player out of the result would
        // copy it through a temporary on the stack (see `demo`).
        let mut made =
            Player::<W, H, PILOT, EVENTS>::single(level, SYNTHETIC_TILT, script.is_none());
        let Ok(player) = &mut made else {
            continue;
        };
        let mut profile = Profile::default();
        while profile.frames < frames {
            let reading = match script {
                Some(tilt) => tilt(profile.frames),
                None => player.reading(AccelMg::LEVEL),
            };
            let (phase, physics) = count(player.session_mut(), reading);
            profile.frame(0, physics);
            if script.is_none() && phase != Phase::Playing {
                break;
            }
        }
        log_scene(player.level_name(), &profile, player.session());
    }
}

/// A scene's profile line and its flight budget's cuts
/// (`physics::world::FLIGHT_BUDGET`).
fn log_scene(name: &str, profile: &Profile, session: &Session<'_, Fx>) {
    profile.log(name);
    #[cfg(feature = "defmt")]
    defmt::info!(
        "budget {=str}: {=u32} marble-steps cut",
        name,
        session.game().world().stats.budget_cuts
    );
    let _ = session;
}

/// Waits for the next frame tick, taking the input events meanwhile: in the
/// demo only the sensor's (a downed sensor pauses it like a game) and Quit.
/// Returns `false` on Quit.
async fn demo_tick<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    player: &mut Player<'_, W, H, PILOT, EVENTS>,
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

/// [`GameMode::Demo`](super::GameMode::Demo): each level exactly as the host simulator plays it
/// with `--autopilot` (a fresh session with the player's configuration and
/// [`SYNTHETIC_TILT`], the autopilot's reading taken from the game before
/// each frame, stopping at the first phase that is not
/// [`Phase::Playing`]), one frame per tick, paused while the sensor is down;
/// then the outcome is shown for [`WIN_PAUSE_FRAMES`]. First the levels of
/// the region `mazes` carries, each parsed into `mazes` (one that cannot be
/// played is skipped, with a log line, and is not one of the demo's levels).
/// After the built-in
/// levels, the endless run's first [`DEMO_MAZES`] generated mazes
/// ([`Seeds::Count`]), each made in `mazes` and played the same way, as
/// `cargo sim -- --generate SEED --size N --storeys S --difficulty D
/// --autopilot` plays it.
pub(super) async fn demo<
    const W: usize,
    const H: usize,
    const PILOT: bool,
    const EVENTS: bool,
    const WORDS: usize,
    const TEXT: usize,
>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    records: bool,
    mazes: &mut MazeSlot<WORDS, TEXT>,
    #[cfg(feature = "ghosts")] mut ghosts: Option<&mut impl GhostStore>,
) -> GameExit {
    let meter = links.meter.get();
    let mut summary = DemoSummary::default();
    let mut sensor = None;
    let endless = Endless::new(mazes.region(), mazes.reach(), Seeds::Count);
    let run = endless.from_region + LEVELS.len() + DEMO_MAZES;
    // The demo's levels are those it can play: the region's that do not
    // parse or fit are left out of its count (each is logged when its turn
    // comes), so that the demo's verdict is the played levels'.
    let skipped = unplayable(&endless, mazes);
    let total = run - skipped;
    let mut shown = 0;
    // The checkers replay the demo with `cargo sim -- --stepping <this>`.
    #[cfg(feature = "defmt")]
    defmt::info!(
        "demo stepping={=str}",
        if EVENTS { "events" } else { "fixed" }
    );
    for number in 0..run {
        let level = match endless.level(number, mazes) {
            Ok(level) => level,
            Err(e) => {
                // A level of the region that is skipped is not one of the
                // demo's; anything else is a level that failed.
                if !not_played(e, shown + 1, total) {
                    summary.levels = summary.levels.saturating_add(1);
                    shown += 1;
                }
                continue;
            }
        };
        summary.levels = summary.levels.saturating_add(1);
        shown += 1;
        // The call writes the player straight into `made`, a local the
        // demo's future keeps across its awaits; everything after borrows it.
        // Matching it into a local of its own would move it through a 2 KB
        // temporary on the stack, under the game's deepest call (the making
        // of the player itself): more than the micro:bit v1 has.
        let mut made = Player::<W, H, PILOT, EVENTS>::single(level, SYNTHETIC_TILT, true);
        let player = match &mut made {
            Ok(player) => player,
            Err(e) => {
                setup_failed(shown, total, DemoSetup::Level(*e));
                continue;
            }
        };
        player.endless_at(number);
        let maze = endless.maze(number);
        // The level's stored best run raced beside the autopilot, and its
        // win kept when it is faster (the ghosts check: the first demo
        // writes them, the next races them to their hashes).
        #[cfg(feature = "ghosts")]
        let mut ghost = match ghosts.as_deref_mut() {
            Some(kit) => Some(kit.begin::<EVENTS>(player.session()).await),
            None => None,
        };
        #[cfg(feature = "ghosts")]
        if let Some(ghost) = &mut ghost {
            ghost.check(player.session()).await;
        }
        if let Some(fault) = sensor {
            player.handle(InputEvent::SensorDown(fault));
        }
        let mut profile = Profile::default();
        let phase = loop {
            if !demo_tick(links, ticker, player).await {
                return GameExit::Quit;
            }
            if player.sensor_down().is_some() {
                // Paused: the same picture as the game's (Player::tick).
                if let Some(frame) = player.tick(AccelMg::LEVEL, true).frame {
                    links.frames.signal(frame);
                }
                links.status.set(status_of(player, maze));
                continue;
            }
            let phase = match meter {
                None => player.frame(AccelMg::LEVEL),
                Some(meter) => profiled_frame(player, meter, &mut profile),
            };
            #[cfg(feature = "ghosts")]
            if let Some(ghost) = &mut ghost {
                ghost.frame(player.session());
            }
            links.status.set(status_of(player, maze));
            if !links.frames.signaled() || phase != Phase::Playing {
                #[allow(unused_mut)]
                let mut picture = match meter {
                    None => player.render(),
                    Some(meter) => profiled_render(player, meter, &mut profile),
                };
                #[cfg(feature = "ghosts")]
                if let Some(ghost) = &ghost {
                    ghost.draw(&mut picture, player.session(), player.viewport());
                }
                links.frames.signal(picture);
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
            // Records are the built-in levels' only (see game_task).
            #[cfg(feature = "records")]
            if let (true, Some(level)) = (records, endless.builtin(number)) {
                links
                    .wins
                    .send(Win {
                        level: level.min(usize::from(u8::MAX)) as u8,
                        frames: game.clock_frames(),
                    })
                    .await;
            }
        }
        let _ = records;
        #[cfg(feature = "defmt")]
        defmt::info!(
            "demo {=usize}/{=usize} level={=str} outcome={=str} steps={=u64} state_hash={=u64:016x}",
            shown,
            total,
            player.level_name(),
            phase.as_str(),
            game.steps(),
            player.session().state_hash()
        );
        if meter.is_some() {
            profile.log(player.level_name());
        }
        #[cfg(feature = "ghosts")]
        if let Some(ghost) = ghost {
            log_raced(player.level_name(), &ghost);
            let recorded = ghost.leave(player.session());
            let len = match recorded {
                Some(bytes) => super::ghosts::replays::<EVENTS>(bytes, player.session()).await,
                None => None,
            };
            if let Some(len) = len {
                if let Some(kit) = ghosts.as_deref_mut() {
                    let _ = kit.keep_recorded(player.level_name(), len).await;
                }
            }
        }
        let last = player.render();
        // The pause's picture changes only when the flash does: each one is
        // sent once (the display keeps showing it), not once a refresh.
        let mut sent = None;
        for left in (1..=WIN_PAUSE_FRAMES).rev() {
            if !demo_tick(links, ticker, player).await {
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

/// Whether the raced ghost reached the end of its run on its own state hash
/// (the board replayed it bit-exactly), for the ghosts check.
#[cfg(feature = "ghosts")]
#[inline(never)]
fn log_raced<const EVENTS: bool>(name: &str, ghost: &super::ghosts::LevelGhost<'_, '_, EVENTS>) {
    match ghost.raced_to_its_end() {
        #[cfg(feature = "defmt")]
        Some((frames, hash)) => defmt::info!(
            "ghost {=str} raced to its end: {=u32} frames, state_hash={=u64:016x} (its own)",
            name,
            frames,
            hash
        ),
        #[cfg(not(feature = "defmt"))]
        Some(_) => {}
        None => {}
    }
    let _ = name;
}

/// `player`'s status, with the generated maze on show (`maze`, feature
/// `storey-maps`).
fn status_of<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    player: &Player<'_, W, H, PILOT, EVENTS>,
    maze: Option<MazeArgs>,
) -> Status {
    #[cfg(feature = "storey-maps")]
    return Status {
        maze,
        ..player.status()
    };
    #[cfg(not(feature = "storey-maps"))]
    {
        let _ = maze;
        player.status()
    }
}

/// The levels of the slot's region that the demo skips
/// ([`StageError::Skipped`]), each parsed into `mazes` once to know. Out of line, like everything the
/// region adds to the demo: in the demo's own body it would grow the task's
/// stack frame by kilobytes on the micro:bit v1.
#[inline(never)]
fn unplayable<const WORDS: usize, const TEXT: usize>(
    endless: &Endless,
    mazes: &mut MazeSlot<WORDS, TEXT>,
) -> usize {
    (0..endless.from_region)
        .filter(|&number| {
            matches!(
                endless.level(number, mazes),
                Err(StageError::Skipped { .. })
            )
        })
        .count()
}

/// Logs why a level of the demo's run is not played: `true` for a level of
/// the region that is skipped, `false` for the demo's level `shown` (from 1)
/// of `total` that failed.
#[inline(never)]
fn not_played(e: StageError<'_>, shown: usize, total: usize) -> bool {
    if let StageError::Skipped { .. } = e {
        #[cfg(feature = "defmt")]
        defmt::warn!("demo: {}", e);
        true
    } else {
        setup_failed(shown, total, DemoSetup::Stage(e));
        false
    }
}

/// Logs that level `shown` (from 1) of the demo's `total` could not be set
/// up, and why.
fn setup_failed(shown: usize, total: usize, why: DemoSetup) {
    #[cfg(feature = "defmt")]
    defmt::error!(
        "demo {=usize}/{=usize} level={=usize} outcome=setup-error ({})",
        shown,
        total,
        shown,
        why
    );
    let _ = (shown, total, why);
}

/// Why a demo level could not be set up (for the log).
#[cfg_attr(not(feature = "defmt"), allow(dead_code))]
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
enum DemoSetup<'t> {
    Level(SetupError),
    /// A level that is not there, or a maze that could not be made (a bug).
    Stage(StageError<'t>),
}
