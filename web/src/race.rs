//! The page's race against another board (`marble_rolling::race`): one round
//! at a time ([`RaceRound`], the round the micro:bit v2 plays), its packets
//! carried by the page through `cargo web`'s relay (`GET /race`, see
//! `web/www/js/race.js`), its picture an 11 × 11 matrix that holds the whole
//! 5-cell maze, the opponent's marble dimmer.
//!
//! The page writes a received packet at [`race_in_ptr`] and calls
//! [`race_receive`]; after each [`race_tick`] it takes the packet to send,
//! if any, from [`race_out_ptr`] ([`race_transmit`] says its length).

use core::cell::{RefCell, UnsafeCell};
use core::num::NonZeroU32;

use marble_rolling::board::microbit::MAZE_REACH;
use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::endless::MazeSlot;
use marble_rolling::game::rules::Phase;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::event::Command;
use marble_rolling::physics::Fx;
use marble_rolling::player::race::{RaceRound, RoundExit};
use marble_rolling::race::stream::{EARLY_BLOCKS, INBOX_READINGS, OUT_BLOCKS};
use marble_rolling::race::{Status, Verdict, MAX_PACKET};

use crate::Single;

/// The race's picture: 11 × 11, a 5-cell maze whole.
pub const PICTURE: usize = 11;
const WORDS: usize = MAZE_REACH.words();
const TEXT: usize = MAZE_REACH.text_bytes();

type Round =
    RaceRound<'static, Fx, OUT_BLOCKS, INBOX_READINGS, EARLY_BLOCKS, WORDS, TEXT, PICTURE, PICTURE>;

struct WebRace {
    round: Round,
    /// The autopilot plays this board's run (the browser test), after this
    /// many frames of a flat board.
    autopilot: Option<u32>,
    pilot: Option<Autopilot>,
    exit: Option<RoundExit>,
}

/// The slot the round's maze is made in: lent to the round in [`RACE`] for
/// as long as it lives (see [`race_start`]).
static SLOT: Single<UnsafeCell<MazeSlot<WORDS, TEXT>>> =
    Single(UnsafeCell::new(MazeSlot::new(MAZE_REACH)));
static RACE: Single<RefCell<Option<WebRace>>> = Single(RefCell::new(None));
static IN: Single<UnsafeCell<[u8; MAX_PACKET]>> = Single(UnsafeCell::new([0; MAX_PACKET]));
static OUT: Single<RefCell<[u8; MAX_PACKET]>> = Single(RefCell::new([0; MAX_PACKET]));
static PIXELS: Single<RefCell<[u8; PICTURE * PICTURE]>> =
    Single(RefCell::new([0; PICTURE * PICTURE]));

fn with_race<R>(default: R, f: impl FnOnce(&mut WebRace) -> R) -> R {
    match RACE.0.borrow_mut().as_mut() {
        Some(race) => f(race),
        None => default,
    }
}

/// Starts a round as board `id` (0 is taken as 1), the autopilot playing
/// if `autopilot` ≠ 0, after `looks` frames of a flat board; a round under
/// way is dropped.
#[no_mangle]
pub extern "C" fn race_start(id: u32, autopilot: u32, looks: u32) {
    let mut race = RACE.0.borrow_mut();
    // The round that borrowed the slot goes first.
    *race = None;
    // SAFETY: the slot's one borrow is the round's in RACE, dropped just
    // above; the page's calls run one at a time (see `Single`).
    let slot = unsafe { &mut *SLOT.0.get() };
    *race = Some(WebRace {
        round: RaceRound::new(NonZeroU32::new(id).unwrap_or(NonZeroU32::MIN), slot),
        autopilot: (autopilot != 0).then_some(looks),
        pilot: None,
        exit: None,
    });
}

/// Ends the race (back to the game).
#[no_mangle]
pub extern "C" fn race_stop() {
    *RACE.0.borrow_mut() = None;
}

/// Where the page writes a received packet for [`race_receive`].
#[no_mangle]
pub extern "C" fn race_in_ptr() -> *mut u8 {
    IN.0.get().cast()
}

/// Takes the packet of `len` bytes at [`race_in_ptr`]; 1 if the race took
/// it, 0 if dropped (garbled, foreign, not this race's: counted).
#[no_mangle]
pub extern "C" fn race_receive(len: u32) -> u32 {
    // SAFETY: the page wrote the buffer before this call and does not touch
    // it during it.
    let buf = unsafe { &*IN.0.get() };
    let Some(bytes) = buf.get(..len as usize) else {
        return 0;
    };
    with_race(0, |race| u32::from(race.round.receive(bytes).is_ok()))
}

/// Where [`race_transmit`] writes the packet to send.
#[no_mangle]
pub extern "C" fn race_out_ptr() -> *const u8 {
    OUT.0.as_ptr().cast()
}

/// The packet to send now, at [`race_out_ptr`]: its length, 0 if none.
#[no_mangle]
pub extern "C" fn race_transmit() -> u32 {
    let mut out = OUT.0.borrow_mut();
    with_race(0, |race| {
        race.round.transmit(&mut out).map_or(0, |p| p.len() as u32)
    })
}

/// One frame with the page's tilt (`right_mg`, `up_mg`, as [`set_tilt`]
/// takes it) and a button: `command` 1 is A (race again, once this board's
/// run is over), 2 is B (back to the chooser: here, the end of the race),
/// 0 none. Returns the race's state: 0 no race, 1 looking for an opponent,
/// 2 counting down, 3 racing, 4 this board's run over and the verdict not
/// known, 5 won, 6 lost, 7 a draw, 8 over: race again, 9 over: stop.
///
/// [`set_tilt`]: crate::game_loop::set_tilt
#[no_mangle]
pub extern "C" fn race_tick(right_mg: i32, up_mg: i32, command: u32) -> u32 {
    let command = match command {
        1 => Some(Command::Restart),
        2 => Some(Command::NextLevel),
        _ => None,
    };
    with_race(0, |race| {
        if race.exit.is_none() {
            let tilt = AccelMg::from_xz(right_mg.saturating_neg(), up_mg);
            let (autopilot, pilot) = (race.autopilot, &mut race.pilot);
            let frame = race.round.frame(command, |s| match autopilot {
                Some(looks) if s.game().frames() < looks => AccelMg::LEVEL,
                Some(_) => pilot
                    .get_or_insert_with(|| Autopilot::new(s.game().level()))
                    .reading_mg(s.game()),
                None => tilt,
            });
            if let Err(exit) = frame {
                race.exit = Some(exit);
            }
        }
        state(race)
    })
}

fn state(race: &WebRace) -> u32 {
    match race.exit {
        Some(RoundExit::Again) => return 8,
        Some(RoundExit::Choose) => return 9,
        None => {}
    }
    let Some(r) = race.round.race() else {
        return 1;
    };
    match r.status() {
        Status::Countdown(_) => 2,
        Status::Decided(v) if r.own().game().phase() != Phase::Playing => match v {
            Verdict::Won => 5,
            Verdict::Lost => 6,
            Verdict::Draw => 7,
        },
        _ if r.own().game().phase() != Phase::Playing => 4,
        _ => 3,
    }
}

/// The race's picture ([`PICTURE`] × [`PICTURE`] brightness levels, 0 to 15,
/// row by row), drawn now; its address.
#[no_mangle]
pub extern "C" fn race_picture() -> *const u8 {
    let mut pixels = PIXELS.0.borrow_mut();
    with_race((), |race| {
        let frame = race.round.picture();
        for (x, y, b) in frame.iter() {
            pixels[y * PICTURE + x] = b;
        }
    });
    pixels.as_ptr()
}

/// The picture's side, pixels.
#[no_mangle]
pub extern "C" fn race_picture_side() -> u32 {
    PICTURE as u32
}

/// The opponent's board id, once paired (0 before).
#[no_mangle]
pub extern "C" fn race_opponent() -> u32 {
    with_race(0, |race| {
        race.round
            .race()
            .and_then(|r| r.link().paired())
            .map_or(0, |(peer, _)| peer)
    })
}

/// Frames of the race this board: `which` 0 its own run, 1 its replay of the
/// opponent's (behind by the link's latency).
#[no_mangle]
pub extern "C" fn race_frames(which: u32) -> u32 {
    with_race(0, |race| {
        race.round.race().map_or(0, |r| {
            if which == 0 {
                r.own_run().frames
            } else {
                r.opponent().run().frames
            }
        })
    })
}

/// `Session::state_hash` of this board's run (`which` 0) or of its replay
/// of the opponent's (1); 0 before the race.
#[no_mangle]
pub extern "C" fn race_hash(which: u32) -> u64 {
    with_race(0, |race| {
        race.round.race().map_or(0, |r| {
            if which == 0 {
                r.own().state_hash()
            } else {
                r.opponent().session().state_hash()
            }
        })
    })
}

/// 1 once the replay of the opponent reached its end on the opponent's own
/// state hash, 2 if it did not, 0 not yet.
#[no_mangle]
pub extern "C" fn race_verified() -> u32 {
    with_race(0, |race| {
        match race.round.race().and_then(|r| r.opponent().verified()) {
            Some(true) => 1,
            Some(false) => 2,
            None => 0,
        }
    })
}

/// 1 while the opponent has been silent for 3 s (this board races alone).
#[no_mangle]
pub extern "C" fn race_silent() -> u32 {
    with_race(0, |race| {
        u32::from(race.round.link().is_some_and(|l| l.silent()))
    })
}
