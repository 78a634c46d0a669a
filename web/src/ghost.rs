//! The ghost: every attempt written as one while it plays (`Recorder`), the
//! best run of the level replayed beside the next attempt (`GhostRun`),
//! racing from the player's first tilt (`ghost::race_frame`).

use core::cell::UnsafeCell;

use marble_rolling::game::ghost::{race_frame, replay, Ghost, GhostWriter, Readings};
use marble_rolling::game::rules::{Game, Phase};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::physics::Fx;

use crate::game_loop::{phase_code, with_app};
use crate::page_state::{is_out, marble_coord, storey_of};
use crate::storage::answer;
use crate::Single;

/// Bytes of a ghost (its format: `marble_rolling::game::ghost`). The
/// autopilot's runs take 188 to 279 B per second, a run with a sensor's noise
/// 489 (docs/ghost.md): 64 KiB keep about four minutes, or two of the noisy
/// run, longer than any built-in level's limit; a longer run leaves no ghost.
pub(crate) const GHOST_CAPACITY: usize = 64 * 1024;

/// Where the page writes a stored ghost for [`load_ghost`].
pub(crate) static GHOST_IN: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));

/// The ghost on show, copied from [`GHOST_IN`]: its replay reads it frame by
/// frame (see [`GhostRun`]).
pub(crate) static GHOST: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));

/// The attempt in play, written as a ghost while it is played (see [`Recorder`]).
pub(crate) static RECORD: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));

/// The attempt in play, written as a ghost frame by frame into [`RECORD`]: a
/// win is then a ghost already, without a copy of its readings.
pub(crate) struct Recorder {
    pub(crate) writer: Option<GhostWriter<'static>>,
    /// Frames of the attempt seen so far.
    pub(crate) frames: u32,
    /// The writer has every reading of the attempt from its first frame.
    pub(crate) whole: bool,
}

impl Recorder {
    pub(crate) fn new() -> Self {
        Recorder {
            writer: None,
            frames: 0,
            whole: false,
        }
    }

    /// Starts over, for an attempt at its first frame.
    pub(crate) fn start(&mut self) {
        // The old writer goes first: it holds the only reference into RECORD.
        self.writer = None;
        // SAFETY: single thread (see `Single`). The writer just dropped was
        // the only reference into RECORD (a finished ghost is handed out as a
        // length, its slice dropped at once), so this one is alone.
        let buf: &'static mut [u8; GHOST_CAPACITY] = unsafe { &mut *RECORD.0.get() };
        self.writer = GhostWriter::new(buf).ok();
        self.frames = 0;
        self.whole = self.writer.is_some();
    }

    /// After a frame, a restart or a new level: keeps the frame's reading.
    pub(crate) fn observe(&mut self, session: &Session<'static, Fx>) {
        let frames = session.game().frames();
        if frames == 0 {
            if self.frames != 0 || self.writer.is_none() {
                self.start();
            }
            return;
        }
        if frames == self.frames {
            // A finished attempt on show: no frame played.
            return;
        }
        let pushed = frames == self.frames + 1
            && self
                .writer
                .as_mut()
                .is_some_and(|w| w.push(session.reading()).is_ok());
        // A frame missed, or no room left: this attempt leaves no ghost.
        self.whole &= pushed;
        self.frames = frames;
    }

    /// The ghost of the attempt that just ended (a win) in [`RECORD`]: its
    /// length, or 0 if the attempt was not kept whole.
    pub(crate) fn finish(&mut self, session: &Session<'static, Fx>) -> u32 {
        let Some(writer) = self.writer.take() else {
            return 0;
        };
        if !self.whole || writer.frames() != session.game().frames() {
            return 0;
        }
        writer
            .finish(session.state_hash(), session.tilt().calibration())
            .map_or(0, |bytes| bytes.len() as u32)
    }
}

/// A stored ghost played beside the live game, one frame per live frame.
pub(crate) struct GhostRun {
    pub(crate) session: Session<'static, Fx>,
    pub(crate) ghost: Ghost<'static>,
    pub(crate) readings: Readings<'static>,
    /// Its time on the level clock, frames (measured by the replay that
    /// checked it).
    pub(crate) clock: u32,
    /// Its frames before its clock started: it plays them at once and waits
    /// there for the player's first tilt ([`race_frame`]).
    pub(crate) idle: u32,
}

impl GhostRun {
    /// Plays the ghost as far as it goes beside the live attempt `live`
    /// ([`race_frame`]: from the player's first tilt), from its start again if
    /// the live game started over, or to its end.
    pub(crate) fn follow(&mut self, live: &Game<'static, Fx>) {
        let frames = race_frame(self.idle, live);
        if frames < self.session.game().frames() {
            // A restart keeps the calibration, the ghost's.
            self.session.restart();
            self.readings = self.ghost.readings();
        }
        while self.session.game().frames() < frames && self.session.game().phase() == Phase::Playing
        {
            match self.readings.next() {
                Some(Ok(reading)) => {
                    self.session.frame(reading);
                }
                // Checked when loaded: the readings neither end early nor break.
                _ => break,
            }
        }
    }
}

/// Where the last win's ghost is
/// ([`finished_ghost_len`](crate::game_loop::finished_ghost_len) bytes).
#[no_mangle]
pub extern "C" fn record_ptr() -> *const u8 {
    RECORD.0.get().cast()
}

/// Where the page writes a stored ghost for [`load_ghost`].
#[no_mangle]
pub extern "C" fn ghost_in_ptr() -> *mut u8 {
    GHOST_IN.0.get().cast()
}

/// Bytes a ghost can have.
#[no_mangle]
pub extern "C" fn ghost_capacity() -> u32 {
    GHOST_CAPACITY as u32
}

/// Takes the `len` bytes at [`ghost_in_ptr`] as the ghost of the level in
/// play, if its replay (with the stepper in play) wins the level and ends on
/// the ghost's state hash; it then plays beside the attempt, from the
/// attempt's frame. 0, or the length of why not in the answer buffer (a
/// ghost of another build, level or stepper; the page then forgets it).
#[no_mangle]
pub extern "C" fn load_ghost(len: u32) -> u32 {
    with_app(0, |app| {
        // Nothing borrows GHOST from here on.
        app.ghost = None;
        // SAFETY: single thread; the page writes GHOST_IN only between calls.
        let input: &[u8; GHOST_CAPACITY] = unsafe { &*GHOST_IN.0.get() };
        let Some(bytes) = input.get(..len as usize) else {
            return answer(format_args!("a ghost is at most {GHOST_CAPACITY} bytes"));
        };
        // SAFETY: the ghost just dropped was the only reference into GHOST;
        // from here on the new one borrows it until the next load or clear.
        let stored: &'static mut [u8; GHOST_CAPACITY] = unsafe { &mut *GHOST.0.get() };
        stored[..bytes.len()].copy_from_slice(bytes);
        let stored: &'static [u8] = &stored[..bytes.len()];
        let ghost = match Ghost::parse(stored) {
            Ok(ghost) => ghost,
            Err(e) => return answer(format_args!("{e}")),
        };
        let level = *app.level();
        let config = app.player.game().config();
        let (Ok(mut check), Ok(mut session)) = (
            Session::<Fx>::new(level, config, SYNTHETIC_TILT),
            Session::<Fx>::new(level, config, SYNTHETIC_TILT),
        ) else {
            return answer(format_args!("the level cannot be set up for the ghost"));
        };
        match replay(&mut check, &ghost) {
            Ok((Phase::Won, true)) => {}
            Ok((phase, same)) => {
                return answer(format_args!(
                    "the ghost's replay ends {} after {} frames{}: not a run of this level",
                    match phase {
                        Phase::Won => "won",
                        Phase::Playing => "unfinished",
                        Phase::Fell => "fallen",
                        Phase::TimeUp => "timed out",
                    },
                    check.game().frames(),
                    if same { "" } else { " on another state hash" }
                ))
            }
            Err(e) => return answer(format_args!("{e}")),
        }
        session.tilt_mut().set_calibration(ghost.calibration);
        let mut run = GhostRun {
            session,
            ghost,
            readings: ghost.readings(),
            clock: check.game().clock_frames(),
            idle: check.game().frames() - check.game().clock_frames(),
        };
        run.follow(app.player.game());
        app.ghost = Some(run);
        0
    })
}

/// Drops the ghost on show.
#[no_mangle]
pub extern "C" fn clear_ghost() {
    with_app((), |app| app.ghost = None)
}

/// 1 while a ghost plays beside the attempt.
#[no_mangle]
pub extern "C" fn ghost_active() -> u32 {
    with_app(0, |app| app.ghost.is_some() as u32)
}

/// The ghost's recorded run: `what` 0 its frames, 1 its time on the level
/// clock (frames), 2 its frames before its clock started; 0 without a ghost.
#[no_mangle]
pub extern "C" fn ghost_record(what: u32) -> u32 {
    with_app(0, |app| {
        app.ghost.as_ref().map_or(0, |g| match what {
            0 => g.ghost.frames,
            1 => g.clock,
            _ => g.idle,
        })
    })
}

/// Frames on the ghost's level clock so far in this attempt (the player's,
/// once the ghost races: both start at a first tilt).
#[no_mangle]
pub extern "C" fn ghost_clock_frames() -> u32 {
    with_app(0, |app| {
        app.ghost
            .as_ref()
            .map_or(0, |g| g.session.game().clock_frames())
    })
}

/// The state hash the ghost's run ended on (its header's).
#[no_mangle]
pub extern "C" fn ghost_record_hash() -> u64 {
    with_app(0, |app| {
        app.ghost.as_ref().map_or(0, |g| g.ghost.state_hash)
    })
}

/// Frames the ghost has played so far in this attempt.
#[no_mangle]
pub extern "C" fn ghost_frames() -> u32 {
    with_app(0, |app| {
        app.ghost.as_ref().map_or(0, |g| g.session.game().frames())
    })
}

/// Where the ghost's replay stands (as [`phase`](crate::game_loop::phase)).
#[no_mangle]
pub extern "C" fn ghost_phase() -> u32 {
    with_app(0, |app| {
        app.ghost
            .as_ref()
            .map_or(0, |g| phase_code(g.session.game().phase()))
    })
}

/// The ghost's replay's state hash now: the record's once it has ended.
#[no_mangle]
pub extern "C" fn ghost_state_hash() -> u64 {
    with_app(0, |app| {
        app.ghost.as_ref().map_or(0, |g| g.session.state_hash())
    })
}

/// Marbles of the ghost (0 without one).
#[no_mangle]
pub extern "C" fn ghost_marble_count() -> u32 {
    with_app(0, |app| {
        app.ghost
            .as_ref()
            .map_or(0, |g| g.session.game().world().marbles().len() as u32)
    })
}

/// As [`marble_mm`](crate::page_state::marble_mm), for the ghost's marble `index`.
#[no_mangle]
pub extern "C" fn ghost_marble_mm(index: u32, axis: u32) -> f64 {
    with_app(0.0, |app| {
        app.ghost
            .as_ref()
            .map_or(0.0, |g| marble_coord(g.session.game().world(), index, axis))
    })
}

/// As [`marble_out`](crate::page_state::marble_out), for the ghost's marble `index`.
#[no_mangle]
pub extern "C" fn ghost_marble_out(index: u32) -> u32 {
    with_app(1, |app| {
        app.ghost
            .as_ref()
            .is_none_or(|g| is_out(g.session.game().world(), index)) as u32
    })
}

/// As [`marble_storey`](crate::page_state::marble_storey), for the ghost's marble `index`.
#[no_mangle]
pub extern "C" fn ghost_marble_storey(index: u32) -> u32 {
    with_app(0, |app| {
        let storeys = app.level().info.storeys;
        app.ghost
            .as_ref()
            .map_or(0, |g| storey_of(g.session.game().world(), index, storeys))
    })
}
