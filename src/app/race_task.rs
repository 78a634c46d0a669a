//! The race task: racing a friend's board over a radio ([`crate::race`]), in
//! place of the game task. The board's radio task moves the packets
//! ([`Air`]); this task chooses the channel and group with the buttons
//! ([`RaceSetup`]), then plays rounds ([`RaceRound`]: the search, the race on
//! the tilt, its picture) at the game's frame rate.
//!
//! Its buttons: while choosing, **A** counts up and **B** chooses (the
//! channel, then the group); while looking for an opponent, **B** goes back
//! to the chooser; once this board's run is over, **A** races again (a new
//! board id, a new maze) and **B** goes back to the chooser. During the
//! countdown and the run they do nothing: a board that left would leave its
//! opponent racing alone.

use core::num::NonZeroU32;

use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;
use embassy_time::{Duration, Ticker};
use heapless::Vec;

use super::links::Links;
use super::FRAME_HZ;
use crate::game::endless::MazeSlot;
use crate::input::event::{Command, InputEvent};
use crate::input::race_setup::{RaceSetup, Tuning};
use crate::physics::Fx;
use crate::player::race::{RaceRound, RoundEvent, RoundExit};
use crate::race::{race_id, MAX_PACKET};
use crate::render::race::setup_frame;

/// A race packet on its way to or from the radio.
pub type AirPacket = Vec<u8, MAX_PACKET>;

/// The links between the race task and the board's radio task.
pub struct Air {
    /// The channel and group the radio listens and sends on, set by the race
    /// task each time they are chosen; the radio sends and hears nothing
    /// before the first.
    pub tuning: Signal<CriticalSectionRawMutex, Tuning>,
    /// Packets to send (the race task never waits: what does not fit is
    /// dropped, and the protocol repeats it).
    pub outgoing: Channel<CriticalSectionRawMutex, AirPacket, 2>,
    /// Packets received on the tuning's channel and group, for the race.
    pub incoming: Channel<CriticalSectionRawMutex, AirPacket, 4>,
}

impl Air {
    /// Nothing tuned, nothing queued.
    pub const fn new() -> Self {
        Air {
            tuning: Signal::new(),
            outgoing: Channel::new(),
            incoming: Channel::new(),
        }
    }
}

impl Default for Air {
    fn default() -> Self {
        Self::new()
    }
}

/// The buttons' command since the last frame, if any (the last one wins).
fn command<const W: usize, const H: usize>(links: &Links<W, H>) -> Option<Command> {
    let mut last = None;
    while let Ok(event) = links.events.try_receive() {
        if let InputEvent::Command(c) = event {
            last = Some(c);
        }
    }
    last
}

/// Races for ever: the chooser, then races on its channel and group, with the
/// link sizes `O`, `I`, `E` ([`crate::race::RaceLink`]); each race's maze is made in
/// `mazes` (a maze beyond its reach is refused, and the board looks for
/// another opponent). Board ids come from `seed` ([`race_id`]).
pub async fn race_task<
    const W: usize,
    const H: usize,
    const O: usize,
    const I: usize,
    const E: usize,
    const WORDS: usize,
    const TEXT: usize,
>(
    links: &Links<W, H>,
    air: &Air,
    mazes: &mut MazeSlot<WORDS, TEXT>,
    seed: u32,
) -> ! {
    let mut ticker = Ticker::every(Duration::from_hz(u64::from(FRAME_HZ)));
    let mut tuning = Tuning::DEFAULT;
    let mut n = 0u32;
    loop {
        tuning = choose(links, &mut ticker, tuning).await;
        #[cfg(feature = "defmt")]
        defmt::info!(
            "race: channel {=u8}, group {=u8}",
            tuning.channel,
            tuning.group
        );
        air.tuning.signal(tuning);
        loop {
            let id = race_id(seed, n);
            n = n.wrapping_add(1);
            let exit =
                race_once::<W, H, O, I, E, WORDS, TEXT>(links, air, &mut ticker, mazes, id).await;
            if exit == RoundExit::Choose {
                break;
            }
        }
    }
}

/// The chooser, from `start`, until the group is chosen.
async fn choose<const W: usize, const H: usize>(
    links: &Links<W, H>,
    ticker: &mut Ticker,
    start: Tuning,
) -> Tuning {
    let mut setup = RaceSetup::new(start);
    loop {
        ticker.next().await;
        if let Some(tuning) = command(links).and_then(|c| setup.command(c)) {
            return tuning;
        }
        if !links.frames.signaled() {
            links.frames.signal(setup_frame(&setup));
        }
    }
}

/// One race as board `id` ([`RaceRound`]): until a button (or a maze that
/// cannot be played here) ends it.
async fn race_once<
    const W: usize,
    const H: usize,
    const O: usize,
    const I: usize,
    const E: usize,
    const WORDS: usize,
    const TEXT: usize,
>(
    links: &Links<W, H>,
    air: &Air,
    ticker: &mut Ticker,
    mazes: &mut MazeSlot<WORDS, TEXT>,
    id: NonZeroU32,
) -> RoundExit {
    let mut round = RaceRound::<Fx, O, I, E, WORDS, TEXT, W, H>::new(id, mazes);
    let mut packet = [0u8; MAX_PACKET];
    #[cfg(feature = "defmt")]
    defmt::info!("race: board {=u32} looking for an opponent", id.get());
    loop {
        ticker.next().await;
        while let Ok(p) = air.incoming.try_receive() {
            let _ = round.receive(&p);
        }
        let reading = links.tilt.get();
        match round.frame(command(links), |_| reading) {
            Ok(Some(event)) => report(event, links),
            Ok(None) => {}
            Err(exit) => return exit,
        }
        if let Some(p) = round.transmit(&mut packet) {
            send(air, p);
        }
        if !links.frames.signaled() {
            links.frames.signal(round.picture());
        }
    }
}

/// Queues `packet` for the radio; a full queue drops it (the protocol repeats
/// what it carried).
fn send(air: &Air, packet: &[u8]) {
    if let Ok(p) = Vec::from_slice(packet) {
        let _ = air.outgoing.try_send(p);
    }
}

/// Logs what happened (and sounds the start and the verdict).
fn report<const W: usize, const H: usize>(event: RoundEvent, links: &Links<W, H>) {
    #[cfg(feature = "defmt")]
    match event {
        RoundEvent::Paired { peer, maze } => defmt::info!(
            "race: paired with board {=u32}, maze {=u32} size {=u8} storeys {=u8} difficulty {=u8}",
            peer,
            maze.seed,
            maze.size,
            maze.storeys,
            maze.difficulty
        ),
        RoundEvent::Refused(e) => defmt::warn!("race: the agreed maze cannot be played here: {}", e),
        RoundEvent::Unplayable(e) => defmt::error!("race: {}", e),
        RoundEvent::Go => defmt::info!("race: go"),
        RoundEvent::Silent => defmt::warn!("race: opponent silent: racing alone"),
        RoundEvent::Back => defmt::info!("race: the opponent is back"),
        RoundEvent::Verdict {
            verdict,
            own,
            opponent,
            verified,
        } => defmt::info!(
            "race: verdict {}; own {=str} in {=u32} frames; opponent {=str} in {=u32} frames, verified {}",
            verdict,
            own.1.as_str(),
            own.0,
            opponent.1.as_str(),
            opponent.0,
            verified
        ),
    }
    #[cfg(feature = "sound")]
    match event {
        RoundEvent::Go => {
            let _ = links
                .sounds
                .try_send(crate::sound::Sound::Click { loudness: 255 });
        }
        RoundEvent::Verdict { verdict, .. } => {
            let _ = links.sounds.try_send(match verdict {
                crate::race::Verdict::Won => crate::sound::Sound::Win,
                _ => crate::sound::Sound::Loss,
            });
        }
        _ => {}
    }
    let _ = (event, links);
}
