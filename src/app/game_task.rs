//! The game task: the [`Player`] stepped at the game's frame rate on an
//! embassy `Ticker` (not `Timer::after`, which rounds up to the time driver's
//! tick and drifts), its frame and status published every tick, its sounds
//! and wins queued for their tasks; or the demo ([`GameMode::Demo`]).

use embassy_time::{Duration, Ticker};

use super::demo::demo;
use super::links::Links;
#[cfg(feature = "records")]
use super::links::Win;
use super::mode::{GameExit, GameMode};
use super::FRAME_HZ;
use crate::game::endless::{Endless, MazeSlot, Seeds, StageError};
#[cfg(feature = "records")]
use crate::game::rules::Phase;
use crate::input::tilt::TiltConfig;
use crate::player::{Carried, Player};

#[cfg(feature = "ghosts")]
use super::ghosts::{GhostStore, LevelGhost};

/// Runs the game at [`FRAME_HZ`] in `mode` (see [`GameMode`]), publishing a
/// frame on [`Links::frames`] and the [`Links::status`] every tick. Returns
/// on [`Command::Quit`](crate::input::event::Command::Quit) or at the end of the demo. `PILOT` says whether the
/// board has the autopilot, `EVENTS` which physics stepper it links (see
/// [`Player`]). The levels of the board's levels region, which `mazes`
/// carries ([`MazeSlot::with_region`]; none: the board has none, or it is
/// erased or refused), come first, each parsed into `mazes` when its turn
/// comes; the generated mazes after the built-in levels are made there too.
/// Its size is the board's choice ([`Reach`](crate::game::endless::Reach)).
pub async fn game_task<
    const W: usize,
    const H: usize,
    const PILOT: bool,
    const EVENTS: bool,
    const WORDS: usize,
    const TEXT: usize,
>(
    links: &Links<W, H>,
    mode: GameMode,
    mazes: &mut MazeSlot<WORDS, TEXT>,
    #[cfg(feature = "ghosts")] ghosts: Option<&mut impl GhostStore>,
) -> GameExit {
    let mut ticker = Ticker::every(Duration::from_hz(u64::from(FRAME_HZ)));
    match mode {
        #[cfg(all(not(feature = "sleep"), not(feature = "ghosts")))]
        GameMode::Play { tilt, seeds } => {
            play::<W, H, PILOT, EVENTS, WORDS, TEXT>(links, &mut ticker, tilt, seeds, mazes).await
        }
        #[cfg(all(not(feature = "sleep"), feature = "ghosts"))]
        GameMode::Play { tilt, seeds } => {
            play::<W, H, PILOT, EVENTS, WORDS, TEXT>(links, &mut ticker, tilt, seeds, mazes, ghosts)
                .await
        }
        #[cfg(all(feature = "sleep", not(feature = "ghosts")))]
        GameMode::Play { tilt, level, seeds } => {
            play::<W, H, PILOT, EVENTS, WORDS, TEXT>(links, &mut ticker, tilt, level, seeds, mazes)
                .await
        }
        #[cfg(all(feature = "sleep", feature = "ghosts"))]
        GameMode::Play { tilt, level, seeds } => {
            play::<W, H, PILOT, EVENTS, WORDS, TEXT>(
                links,
                &mut ticker,
                tilt,
                level,
                seeds,
                mazes,
                ghosts,
            )
            .await
        }
        #[cfg(not(feature = "ghosts"))]
        GameMode::Demo { records } => {
            demo::<W, H, PILOT, EVENTS, WORDS, TEXT>(links, &mut ticker, records, mazes).await
        }
        #[cfg(feature = "ghosts")]
        GameMode::Demo { records } => {
            demo::<W, H, PILOT, EVENTS, WORDS, TEXT>(links, &mut ticker, records, mazes, ghosts)
                .await
        }
    }
}

/// [`GameMode::Play`] alone, for a board that never runs the demo (the
/// micro:bit v2): [`game_task`]'s future holds the larger of the play's and
/// the demo's, and with the ghost the demo's is the larger (1 120 B more of
/// the v2's static RAM). The arguments are [`GameMode::Play`]'s (`level` with
/// feature `sleep`).
pub async fn play_task<
    const W: usize,
    const H: usize,
    const PILOT: bool,
    const EVENTS: bool,
    const WORDS: usize,
    const TEXT: usize,
>(
    links: &Links<W, H>,
    tilt: TiltConfig,
    #[cfg(feature = "sleep")] level: u8,
    seeds: Seeds,
    mazes: &mut MazeSlot<WORDS, TEXT>,
    #[cfg(feature = "ghosts")] ghosts: Option<&mut impl GhostStore>,
) -> GameExit {
    let mut ticker = Ticker::every(Duration::from_hz(u64::from(FRAME_HZ)));
    #[cfg(all(not(feature = "sleep"), not(feature = "ghosts")))]
    let game = play::<W, H, PILOT, EVENTS, WORDS, TEXT>(links, &mut ticker, tilt, seeds, mazes);
    #[cfg(all(not(feature = "sleep"), feature = "ghosts"))]
    let game =
        play::<W, H, PILOT, EVENTS, WORDS, TEXT>(links, &mut ticker, tilt, seeds, mazes, ghosts);
    #[cfg(all(feature = "sleep", not(feature = "ghosts")))]
    let game =
        play::<W, H, PILOT, EVENTS, WORDS, TEXT>(links, &mut ticker, tilt, level, seeds, mazes);
    #[cfg(all(feature = "sleep", feature = "ghosts"))]
    let game = play::<W, H, PILOT, EVENTS, WORDS, TEXT>(
        links,
        &mut ticker,
        tilt,
        level,
        seeds,
        mazes,
        ghosts,
    );
    game.await
}

/// [`GameMode::Play`]: [`Player::tick`] at every tick of the frame clock, the
/// levels of the region `mazes` carries, the built-in levels in order and
/// then the endless run of generated mazes ([`Endless`]), each made in `mazes` when the one before
/// is won or skipped. A level of the region that does not parse, does not fit
/// `mazes` or that the physics refuses is logged and skipped; a maze that
/// cannot be made (a bug) is logged and the run starts again at the first
/// level.
async fn play<
    const W: usize,
    const H: usize,
    const PILOT: bool,
    const EVENTS: bool,
    const WORDS: usize,
    const TEXT: usize,
>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    tilt: TiltConfig,
    #[cfg(feature = "sleep")] level: u8,
    seeds: Seeds,
    mazes: &mut MazeSlot<WORDS, TEXT>,
    #[cfg(feature = "ghosts")] mut ghosts: Option<&mut impl GhostStore>,
) -> GameExit {
    // Without `sleep` there is no level to resume: the run starts at the
    // first.
    #[cfg(feature = "sleep")]
    let mut number = usize::from(level);
    #[cfg(not(feature = "sleep"))]
    let mut number = 0;
    let endless = Endless::new(mazes.region(), mazes.reach(), seeds);
    let mut carried = None;
    // Two minutes without a command and with the tilt still (feature `sleep`).
    #[cfg(feature = "sleep")]
    let mut idle =
        crate::input::idle::Idle::new(crate::input::idle::IdleConfig::two_minutes(FRAME_HZ));
    loop {
        let level = match endless.level(number, mazes) {
            Ok(level) => level,
            Err(e @ StageError::Skipped { .. }) => {
                // The player's level that cannot be played: the next one.
                #[cfg(feature = "defmt")]
                defmt::warn!("level {=usize}: {}", number + 1, e);
                let _ = e;
                number += 1;
                continue;
            }
            Err(e) => {
                // A maze that cannot be made (a bug): the run starts again.
                #[cfg(feature = "defmt")]
                defmt::error!("level {=usize}: {}: back to level 1", number + 1, e);
                let _ = e;
                number = 0;
                continue;
            }
        };
        let autopilot = carried.is_some_and(|c: Carried| c.autopilot());
        // The call writes the player straight into `made`, a local the
        // game's future keeps across its awaits; everything after borrows it.
        // Matching it into a local of its own would move it through a 2 KB
        // temporary on the stack, under the game's deepest call (the making
        // of the player itself): more than the micro:bit v1 has.
        let mut made = Player::<W, H, PILOT, EVENTS>::single(level, tilt, autopilot);
        let player = match &mut made {
            Ok(player) => player,
            // A built-in level that cannot be set up is the firmware's bug.
            Err(e) if endless.builtin(number).is_some() => return GameExit::SetupFailed(*e),
            Err(e) => {
                // One of the region's that the physics refuses: the next
                // level; a maze the physics refuses (a bug too): the run
                // starts again.
                if number < endless.from_region {
                    #[cfg(feature = "defmt")]
                    defmt::warn!(
                        "level {=usize} of the levels region is skipped: {}",
                        number + 1,
                        e
                    );
                    number += 1;
                } else {
                    #[cfg(feature = "defmt")]
                    defmt::error!("level {=usize}: {}: back to level 1", number + 1, e);
                    number = 0;
                }
                let _ = e;
                continue;
            }
        };
        player.endless_at(number);
        // The best times are kept by built-in level, whatever comes before.
        #[cfg(feature = "records")]
        let builtin = endless.builtin(number);
        if let Some(carried) = carried {
            player.carry(carried);
        }
        #[cfg(feature = "defmt")]
        defmt::info!(
            "level {=usize}: {=str}",
            player.level_index() + 1,
            player.level_name()
        );
        // The level's best run, raced beside each attempt (read from flash
        // and replayed to its hash in place first), and the attempts
        // recorded. In a block of its own: the level's ghost (its session)
        // is gone before the recording's replay below, which has a session
        // of its own; and held at one await only (the attempts'), so that
        // it shares its room with the flash's futures (held at two, it
        // would be kept beside them: 1 KB more of the v2's static RAM).
        let recorded = {
            #[cfg(feature = "ghosts")]
            let mut ghost = match ghosts.as_deref_mut() {
                Some(kit) => Some(kit.begin::<EVENTS>(player.session()).await),
                None => None,
            };
            let played = attempts(
                links,
                ticker,
                player,
                #[cfg(feature = "sleep")]
                &mut idle,
                #[cfg(feature = "records")]
                builtin,
                #[cfg(feature = "storey-maps")]
                endless.maze(number),
                #[cfg(feature = "ghosts")]
                ghost.as_mut(),
            )
            .await;
            if let Err(exit) = played {
                return exit;
            }
            #[cfg(feature = "ghosts")]
            let recorded = ghost.and_then(|ghost| ghost.leave(player.session()));
            #[cfg(not(feature = "ghosts"))]
            let recorded: Option<&[u8]> = None;
            recorded
        };
        #[cfg(not(feature = "ghosts"))]
        let _ = recorded;
        // A win that beat the ghost, whose recording replays to its hash,
        // becomes the level's ghost, written between levels.
        #[cfg(feature = "ghosts")]
        if let Some(bytes) = recorded {
            if let Some(len) = super::ghosts::replays::<EVENTS>(bytes, player.session()).await {
                if let Some(kit) = ghosts.as_deref_mut() {
                    let _ = kit.keep_recorded(player.level_name(), len).await;
                }
            }
        }
        carried = Some(player.carried());
        number = player.level_index().saturating_add(1);
    }
}

/// One level's attempts at the frame clock's ticks, the level's ghost
/// checked first and raced beside them: `Ok` once the level is won or
/// skipped, `Err` with what [`play`] returns when the game ends.
#[allow(clippy::too_many_arguments)]
async fn attempts<const W: usize, const H: usize, const PILOT: bool, const EVENTS: bool>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    player: &mut Player<'_, W, H, PILOT, EVENTS>,
    #[cfg(feature = "sleep")] idle: &mut crate::input::idle::Idle,
    #[cfg(feature = "records")] builtin: Option<usize>,
    #[cfg(feature = "storey-maps")] maze: Option<crate::game::endless::MazeArgs>,
    #[cfg(feature = "ghosts")] mut ghost: Option<&mut LevelGhost<'_, '_, EVENTS>>,
) -> Result<(), GameExit> {
    #[cfg(feature = "ghosts")]
    if let Some(ghost) = ghost.as_deref_mut() {
        ghost.check(player.session()).await;
    }
    loop {
        ticker.next().await;
        while let Ok(event) = links.events.try_receive() {
            #[cfg(feature = "defmt")]
            defmt::info!("input {}", event);
            #[cfg(feature = "sleep")]
            if let crate::input::event::InputEvent::Command(_) = event {
                idle.activity();
            }
            if !player.handle(event) {
                return Err(GameExit::Quit);
            }
        }
        // Won or skipped (here or in the last tick): the next level.
        if player.wants_next() {
            return Ok(());
        }
        // The autopilot playing is the toy in use.
        #[cfg(feature = "sleep")]
        if idle.tick(links.tilt.get()) && !player.autopilot() {
            #[cfg(feature = "defmt")]
            defmt::info!(
                "idle for two minutes: asleep on level {=usize}",
                player.level_index() + 1
            );
            return Err(GameExit::Asleep {
                level: player.level_index().min(usize::from(u8::MAX)) as u8,
            });
        }
        // Draw only once the display has taken the previous frame (it
        // refreshes at REFRESH_HZ < FRAME_HZ): rendering is not free.
        let draw = !links.frames.signaled();
        let tick = player.tick(links.tilt.get(), draw);
        #[cfg(feature = "ghosts")]
        let tick = match ghost.as_deref_mut() {
            Some(ghost) => {
                ghost.frame(player.session());
                let mut tick = tick;
                if let Some(frame) = &mut tick.frame {
                    ghost.draw(frame, player.session(), player.viewport());
                }
                tick
            }
            None => tick,
        };
        if let Some(phase) = tick.finished {
            #[cfg(feature = "defmt")]
            defmt::info!(
                "level {=usize} {=str}: {=str} after {=u64} steps",
                player.level_index() + 1,
                player.level_name(),
                phase.as_str(),
                player.game().steps()
            );
            // Records are the built-in levels' only: a generated maze is
            // seldom played twice, and the region's levels change with
            // the .hex.
            #[cfg(feature = "records")]
            if let (Phase::Won, false, Some(Ok(level))) =
                (phase, player.autopilot(), builtin.map(u8::try_from))
            {
                // The records task writes the flash while the win is on
                // show, between levels; a full queue drops the win, never
                // the game.
                let _ = links.wins.try_send(Win {
                    level,
                    frames: player.game().clock_frames(),
                });
            }
            let _ = phase;
        }
        #[cfg(feature = "records")]
        if let (Some(record), Some(level)) = (links.new_record.try_take(), builtin) {
            if usize::from(record) == level {
                player.announce_record();
            }
        }
        #[cfg(feature = "records")]
        let status = crate::player::Status {
            best: builtin
                .and_then(|index| links.bests.get().get(index).copied())
                .flatten(),
            ..player.status()
        };
        #[cfg(not(feature = "records"))]
        let status = player.status();
        #[cfg(feature = "storey-maps")]
        let status = crate::player::Status { maze, ..status };
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
