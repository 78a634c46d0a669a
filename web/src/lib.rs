//! Marble Rolling in a browser: the library's game — its fixed-point physics,
//! levels, level parser, tilt path, autopilot and renderer — compiled to
//! `wasm32-unknown-unknown`, driven by `web/www/app.js`.
//!
//! This crate is only the glue. Each frame is one [`Player::tick`], the very
//! step the firmware's game task, `cargo play` and the host tests call, fed a
//! reading made by the library's
//! [`AccelMg::from_xz`](marble_rolling::input::axes::AccelMg::from_xz) from the
//! page's tilt (keys, mouse joystick or the phone's orientation) through
//! [`SYNTHETIC_TILT`], the tilt path `cargo play` and `cargo sim` use. So a run
//! here plays the same game as on the host and the boards, and the autopilot
//! ends each built-in level with `cargo sim -- --autopilot`'s `state_hash`
//! (the browser test checks that).
//!
//! # Both steppers
//!
//! The page plays with event stepping, as every board and `cargo sim` do by
//! default (the accuracy study's recommendation), and can switch to fixed
//! steps, the study's baseline: [`set_stepping`](game_loop::set_stepping).
//! The stepper is a constant of the [`Player`] type (a board links one), so
//! the page holds either player (`AnyPlayer`); both cost the module their
//! code, which a browser can spare.
//!
//! # Generated mazes and the ghost
//!
//! [`play_generated`](maze::play_generated) plays the maze of a seed from the
//! core's generator (`game::generate`, with `cargo sim -- --generate`'s
//! defaults), parsed from its text as the editor's level is, alone in its
//! list: a win plays it again.
//! Every attempt is written as a ghost while it plays (`Recorder`, the
//! core's `game::ghost` format); a win's ghost is handed to the page
//! ([`finished_ghost_len`](game_loop::finished_ghost_len),
//! [`record_ptr`](ghost::record_ptr)), which keeps the best per level in
//! `localStorage` and hands it back at the next attempt
//! ([`load_ghost`](ghost::load_ghost)): it is taken only if its replay wins
//! the level on its recorded state hash, and then a second session fed its
//! readings plays beside the attempt, from the player's first tilt one frame
//! per frame on the player's clock.
//!
//! # Why no wasm-bindgen
//!
//! The interface is numbers and a few byte buffers, so it is plain
//! `extern "C"` functions over linear memory and a hand-written loader.
//! wasm-bindgen would need its CLI at exactly the crate's version (a
//! multi-minute `cargo install` on every fresh CI machine) and a generated JS
//! glue file, for no gain here. Strings cross as UTF-8 bytes: the page writes
//! a level's text into [`text_ptr`](storage::text_ptr)'s buffer; answers
//! (names, error messages) come back in [`out_ptr`](storage::out_ptr)'s
//! buffer, their length the function's result.
//!
//! # State without an allocator
//!
//! Everything lives in statics: the game (about what the firmware keeps in
//! RAM), the one level typed into the editor (or generated), parsed in place,
//! and three ghost buffers (the attempt's, the page's, the one on show). A
//! `wasm32-unknown-unknown` module without the atomics feature runs on one
//! thread, the page's, and every export runs to its end before the next one
//! starts; `Single` states that. The other `unsafe` code reads the text
//! buffer the page writes, keeps the editor's level (see `Custom`) and lends
//! the ghost buffers to the ghost's writer and reader (see `Recorder`,
//! `load_ghost`). A wrong input — a malformed level, an out-of-range index, a
//! broken ghost — is an answer (an error message, a zero), never a trap.
//!
//! # Modules
//!
//! [`game_loop`]: the game in play, its frame and its level lists;
//! [`page_state`]: what the page draws (LEDs, tiles, marbles); [`storage`]:
//! the buffers shared with the page and the editor's level kept in them;
//! [`maze`]: generated mazes; [`ghost`]: the ghost's recording and replay;
//! [`download`]: the editor's level written into the micro:bit's universal
//! hex ([`universal_hex`]), the file the page offers as "Download for
//! micro:bit"; [`race`]: a race against another page through `cargo web`'s
//! relay.
#![cfg_attr(target_arch = "wasm32", no_std)]

pub mod download;
pub mod game_loop;
pub mod ghost;
pub mod ghost_run;
pub mod maze;
pub mod page_state;
pub mod race;
pub mod storage;
pub mod universal_hex;

use marble_rolling::board::microbit::{HEIGHT, WIDTH};
use marble_rolling::game::level::LevelView;
use marble_rolling::game::rules::Game;
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::input::axes::AccelMg;
use marble_rolling::physics::Fx;
use marble_rolling::player::{Player, Tick};

/// The micro:bit's player (its 5×5 matrix) with the autopilot (the page has
/// a button for it, as the QEMU board has a key), stepped by events (`EVENTS`)
/// or fixed steps: `cargo sim -- --stepping events|fixed` replays either.
type WebPlayer<const EVENTS: bool> = Player<'static, WIDTH, HEIGHT, true, EVENTS>;

/// The player on the stepper the page chose (see the module doc).
pub(crate) enum AnyPlayer {
    Events(WebPlayer<true>),
    Fixed(WebPlayer<false>),
}

/// `$body` with `$p` bound to the player, whichever stepper it has.
macro_rules! each {
    ($player:expr, $p:ident => $body:expr) => {
        match $player {
            AnyPlayer::Events($p) => $body,
            AnyPlayer::Fixed($p) => $body,
        }
    };
}

impl AnyPlayer {
    pub(crate) fn new(
        levels: &'static [LevelView<'static>],
        index: usize,
        events: bool,
        autopilot: bool,
    ) -> Option<AnyPlayer> {
        Some(if events {
            AnyPlayer::Events(WebPlayer::new(levels, index, SYNTHETIC_TILT, autopilot).ok()?)
        } else {
            AnyPlayer::Fixed(WebPlayer::new(levels, index, SYNTHETIC_TILT, autopilot).ok()?)
        })
    }
    pub(crate) fn events(&self) -> bool {
        matches!(self, AnyPlayer::Events(_))
    }
    pub(crate) fn tick(&mut self, reading: AccelMg) -> Tick<WIDTH, HEIGHT> {
        each!(self, p => p.tick(reading, true))
    }
    pub(crate) fn game(&self) -> &Game<'static, Fx> {
        each!(self, p => p.game())
    }
    pub(crate) fn level_index(&self) -> usize {
        each!(self, p => p.level_index())
    }
    pub(crate) fn session(&self) -> &Session<'static, Fx> {
        each!(self, p => p.session())
    }
    pub(crate) fn state_hash(&self) -> u64 {
        self.session().state_hash()
    }
    pub(crate) fn reading(&self) -> AccelMg {
        each!(self, p => p.session().reading())
    }
    pub(crate) fn autopilot(&self) -> bool {
        each!(self, p => p.autopilot())
    }
    pub(crate) fn set_autopilot(&mut self, on: bool) {
        each!(self, p => p.set_autopilot(on))
    }
    pub(crate) fn restart(&mut self) {
        each!(self, p => p.restart())
    }
    pub(crate) fn next_level(&mut self) {
        each!(self, p => p.next_level())
    }
}

/// A value of this module's single thread (see the module doc).
pub(crate) struct Single<T>(pub(crate) T);

// SAFETY: wasm32-unknown-unknown without the `atomics` target feature has no
// threads: the page calls one export at a time, each runs to its end. On the
// host (where this crate only builds, for `cargo check` and clippy) nothing
// calls these functions.
unsafe impl<T> Sync for Single<T> {}

#[cfg(target_arch = "wasm32")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // No panic is expected (inputs are checked, the library reports errors as
    // values); should one happen, the module traps and the page says so.
    core::arch::wasm32::unreachable()
}

/// The editor's messages, on the host (`cargo test -p marble-web`): what the
/// page shows for a level is `cargo sim -- --check`'s after the file name.
#[cfg(test)]
mod tests;
