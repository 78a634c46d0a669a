//! The page's calls on the ghost ([`crate::ghost_run`]): where the last
//! win's ghost is, loading a stored one (taken only if its replay wins), and
//! where the replay beside the attempt stands.

use marble_rolling::game::ghost::{replay, Ghost};
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::physics::Fx;

use crate::game_loop::{phase_code, with_app};
use crate::ghost_run::{GhostRun, GHOST, GHOST_CAPACITY, GHOST_IN, RECORD};
use crate::page_state::{is_out, marble_coord, storey_of};
use crate::storage::answer;

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
