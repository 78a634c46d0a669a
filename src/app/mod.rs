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
//! * [`game_task`] runs the game ([`Player`](crate::player::Player), the synchronous game
//!   loop step) at the game's frame rate [`FRAME_HZ`] on an embassy `Ticker`
//!   (not `Timer::after`, which rounds up to the time driver's tick and
//!   drifts). After the built-in levels it plays the endless run of generated
//!   mazes ([`crate::game::endless`]), each made in the board's maze slot. In
//!   [`GameMode::Demo`] the autopilot plays every built-in level once, exactly
//!   as `cargo sim -- --level <name> --autopilot` does, then three generated
//!   mazes as `cargo sim -- --generate … --autopilot` does, and each level's
//!   outcome, physics steps and `state_hash` are logged.
//! * [`MatrixOutput`]: how one BCM scan step of [`crate::matrix::Scanner`]
//!   reaches LEDs (real pins, or QEMU's virtual matrix).
//! * `SoundOutput` (feature `sound`): how a [`crate::sound::Sound`] is played (QEMU: a log line, the
//!   terminal's bell on a win), from the game's queue by `sound_task`.
//! * [`Console`]: a blocking byte sink for an interactive terminal.
//! * [`race_task`] races a friend's board in place of the game task, its
//!   packets carried by the board's radio task through an [`Air`].
//! * [`power_on`]: the flows a 5 × 5 board may run before the game (the
//!   self-test, the question before the best times are cleared).
//!
//! The display size `W`×`H` and whether the autopilot is linked (`PILOT`) are
//! the board binary's choice, passed as const generics: the micro:bit's 5×5
//! matrix, whose view scrolls with the marble, without the autopilot; or for
//! QEMU a 19×9 virtual matrix that shows every built-in maze whole. The board
//! binary owns the [`Links`] between its tasks in a `static`.

mod demo;
mod display_task;
mod game_task;
#[cfg(feature = "ghosts")]
mod ghosts;
mod input_task;
mod links;
mod mode;
pub mod power_on;
mod race_task;
#[cfg(feature = "records")]
mod records_task;
#[cfg(feature = "sound")]
mod sound_task;
mod summary;
mod terminal_input;

pub use crate::matrix::output::{Console, MatrixOutput, REFRESH_HZ};
pub use crate::player::FRAME_HZ;
pub use demo::{profile_scenes, PROFILE_FRAMES};
pub use display_task::display_task;
pub use game_task::{game_task, play_task};
#[cfg(feature = "ghosts")]
pub use ghosts::{replays, GhostKit, GhostStore, LevelGhost};
pub use input_task::{input_task, TiltInput};
pub use links::{Latest, Links, Meter};
pub use mode::{DemoSummary, GameExit, GameMode};
pub use race_task::{race_task, Air, AirPacket};
#[cfg(feature = "records")]
pub use records_task::records_task;
#[cfg(feature = "sound")]
pub use sound_task::{sound_task, SoundOutput, TerminalSound};
pub use summary::{SensorTotals, Verdict};
pub use terminal_input::{ByteSource, TerminalInput};
