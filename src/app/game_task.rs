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
use crate::game::levels::LEVELS;
use crate::game::player::Player;
#[cfg(feature = "records")]
use crate::game::rules::Phase;
use crate::input::tilt::TiltConfig;

/// Runs the game at [`FRAME_HZ`] in `mode` (see [`GameMode`]), publishing a
/// frame on [`Links::frames`] and the [`Links::status`] every tick. Returns
/// on [`Command::Quit`](crate::input::event::Command::Quit) or at the end of the demo. `PILOT` says whether the
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
    // Without `sleep` the start is the literal 0: on the micro:bit v1 even a
    // start level passed in as a constant measured 2 KB more stack (`cargo
    // xtask check-microbit-v1`), over its RAM budget.
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
            if let crate::input::event::InputEvent::Command(_) = event {
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
        let status = crate::game::player::Status {
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
