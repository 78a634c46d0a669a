//! The race task: racing a friend's board over a radio ([`crate::race`]), in
//! place of the game task. The board's radio task moves the packets
//! ([`Air`]); this task chooses the channel and group with the buttons
//! ([`RaceSetup`]), finds an opponent, plays the race on the tilt at the
//! game's frame rate and draws it ([`crate::render::race`]).
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
use crate::game::endless::{MazeArgs, MazeSlot};
use crate::game::rules::Phase;
use crate::input::event::{Command, InputEvent};
use crate::input::race_setup::{RaceSetup, Tuning};
use crate::input::sensor::Calibration;
use crate::physics::Fx;
use crate::race::{offer, race_id, MazeSpec, Race, RaceLink, Status, MAX_PACKET};
use crate::render::race::{race_frame, searching_frame, setup_frame};
use crate::render::Renderer;

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

/// What ended a race on the board.
enum Next {
    /// Race again on the same channel and group.
    Again,
    /// Back to the chooser.
    Choose,
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
/// link sizes `O`, `I`, `E` ([`RaceLink`]); each race's maze is made in
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
            let next =
                race_once::<W, H, O, I, E, WORDS, TEXT>(links, air, &mut ticker, mazes, id).await;
            if let Next::Choose = next {
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

/// Looks for an opponent as board `id`: the link once paired, with the
/// agreed maze; `None` if B asked for the chooser.
async fn search<const W: usize, const H: usize, const O: usize, const I: usize, const E: usize>(
    links: &Links<W, H>,
    air: &Air,
    ticker: &mut Ticker,
    id: NonZeroU32,
) -> Option<(RaceLink<O, I, E>, MazeSpec)> {
    let mut link = RaceLink::<O, I, E>::sized(id, offer(id), Calibration::NONE);
    let mut packet = [0u8; MAX_PACKET];
    #[cfg(feature = "defmt")]
    defmt::info!("race: board {=u32} looking for an opponent", id.get());
    loop {
        ticker.next().await;
        if command(links) == Some(Command::NextLevel) {
            return None;
        }
        while let Ok(p) = air.incoming.try_receive() {
            let _ = link.receive(&p);
        }
        link.tick();
        if let Some(p) = link.transmit(&mut packet) {
            send(air, p);
        }
        if let Some((_peer, spec)) = link.paired() {
            #[cfg(feature = "defmt")]
            defmt::info!(
                "race: paired with board {=u32}, maze {=u32} size {=u8} storeys {=u8} difficulty {=u8}",
                _peer,
                spec.seed,
                spec.size,
                spec.storeys,
                spec.difficulty
            );
            return Some((link, spec));
        }
        if !links.frames.signaled() {
            links.frames.signal(searching_frame(link.now()));
        }
    }
}

/// One race as board `id`: the search, the race, the verdict on show until
/// a button says what next.
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
) -> Next {
    // The search is a future of its own: its link, borrowed across its
    // awaits, is kept in this future only until the race takes it, not
    // beside the race (the race alone is 5.6 KB on the micro:bit v2).
    let Some((link, spec)) = search::<W, H, O, I, E>(links, air, ticker, id).await else {
        return Next::Choose;
    };
    let args = MazeArgs {
        seed: spec.seed,
        size: spec.size,
        storeys: spec.storeys,
        difficulty: spec.difficulty,
    };
    let level = match mazes.make(args) {
        Ok(level) => level,
        Err(_e) => {
            // The opponent offered a maze this board cannot hold: look for
            // another race (the opponent hears this board fall silent).
            #[cfg(feature = "defmt")]
            defmt::warn!("race: the agreed maze cannot be played here: {}", _e);
            return Next::Again;
        }
    };
    // The call's result is the local the future keeps, borrowed from here
    // on (matched into a local of its own, the race would be kept twice).
    let mut made = Race::<Fx, O, I, E>::new(link, level);
    let race = match &mut made {
        Ok(race) => race,
        Err(_e) => {
            #[cfg(feature = "defmt")]
            defmt::warn!("race: {}", _e);
            return Next::Again;
        }
    };
    let mut packet = [0u8; MAX_PACKET];
    let mut renderer = Renderer::<W, H>::new();
    let mut shown = race.status();
    let mut silent = false;
    loop {
        ticker.next().await;
        let command = command(links);
        if race.own().game().phase() != Phase::Playing {
            match command {
                Some(Command::Restart) => return Next::Again,
                Some(Command::NextLevel) => return Next::Choose,
                _ => {}
            }
        }
        while let Ok(p) = air.incoming.try_receive() {
            let _ = race.receive(&p);
        }
        let reading = links.tilt.get().reading_mg();
        race.frame(|_| reading);
        if let Some(p) = race.transmit(&mut packet) {
            send(air, p);
        }
        let status = race.status();
        if status != shown {
            report(race, shown, status, links);
            shown = status;
        }
        if race.link().silent() != silent {
            silent = !silent;
            #[cfg(feature = "defmt")]
            if silent {
                defmt::warn!("race: opponent silent: racing alone");
            } else {
                defmt::info!("race: the opponent is back");
            }
        }
        if !links.frames.signaled() {
            links.frames.signal(race_frame(&mut renderer, race));
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

/// Logs the race's new `status` after `before` (and sounds its start and
/// verdict).
fn report<const W: usize, const H: usize, const O: usize, const I: usize, const E: usize>(
    race: &Race<'_, Fx, O, I, E>,
    before: Status,
    status: Status,
    links: &Links<W, H>,
) {
    let _ = links;
    match (before, status) {
        (Status::Countdown(_), Status::Racing) => {
            #[cfg(feature = "defmt")]
            defmt::info!("race: go");
            #[cfg(feature = "sound")]
            let _ = links
                .sounds
                .try_send(crate::sound::Sound::Click { loudness: 255 });
        }
        (_, Status::Decided(_verdict)) => {
            let (own, opp) = (race.own_run(), race.opponent().run());
            #[cfg(feature = "defmt")]
            defmt::info!(
                "race: verdict {}; own {=str} in {=u32} frames; opponent {=str} in {=u32} frames, verified {}",
                _verdict,
                own.phase.as_str(),
                own.frames,
                opp.phase.as_str(),
                opp.frames,
                race.opponent().verified()
            );
            #[cfg(feature = "sound")]
            let _ = links.sounds.try_send(match _verdict {
                crate::race::Verdict::Won => crate::sound::Sound::Win,
                _ => crate::sound::Sound::Loss,
            });
            let _ = (own, opp);
        }
        _ => {}
    }
}
