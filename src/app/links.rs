//! The links between the tasks: the latest tilt, status and frame, and the
//! queues of events, sounds and wins, all in one [`Links`] a board binary
//! keeps in a `static`.

use core::cell::Cell;

use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::blocking_mutex::Mutex;
use embassy_sync::channel::Channel;
use embassy_sync::signal::Signal;

#[cfg(feature = "records")]
use crate::game::levels::LEVELS;
use crate::input::axes::AccelMg;
use crate::input::event::InputEvent;
use crate::matrix::Frame;
use crate::player::Status;
#[cfg(feature = "sound")]
use crate::sound::Sound;

/// The latest value of something, readable at any time (e.g. the tilt).
pub struct Latest<T: Copy> {
    value: Mutex<CriticalSectionRawMutex, Cell<T>>,
}

impl<T: Copy> Latest<T> {
    /// Holds `value` until the first [`Latest::set`].
    pub(crate) const fn new(value: T) -> Self {
        Self {
            value: Mutex::new(Cell::new(value)),
        }
    }

    /// The latest value.
    pub fn get(&self) -> T {
        self.value.lock(Cell::get)
    }

    /// Replaces the value.
    pub fn set(&self, value: T) {
        self.value.lock(|cell| cell.set(value));
    }
}

/// The links between the tasks of a board with a `W`×`H` display. Each board
/// binary owns one in a `static` (the size is the board's, so it cannot be a
/// static of this module) and hands it to the tasks.
pub struct Links<const W: usize, const H: usize> {
    /// Latest tilt, written by [`input_task`](super::input_task), read by [`game_task`](super::game_task) each frame.
    pub tilt: Latest<AccelMg>,
    /// Commands and the sensor's ups and downs, from [`input_task`](super::input_task) to
    /// [`game_task`](super::game_task), in order.
    pub events: Channel<CriticalSectionRawMutex, InputEvent, 8>,
    /// Latest frame from [`game_task`](super::game_task) to [`display_task`](super::display_task) (older ones are
    /// dropped).
    pub frames: Signal<CriticalSectionRawMutex, Frame<W, H>>,
    /// The game's status after its latest frame.
    pub status: Latest<Status>,
    /// Set by a board before the demo starts: the demo counts each frame's
    /// instructions with it and logs a profile per level (see [`Meter`]).
    pub meter: Latest<Option<Meter>>,
    /// Sounds from [`game_task`](super::game_task) to [`sound_task`](super::sound_task), in order (the game never
    /// waits: what does not fit is dropped). Feature `sound` only.
    #[cfg(feature = "sound")]
    pub(crate) sounds: Channel<CriticalSectionRawMutex, Sound, 8>,
    /// Levels won by the player (not the autopilot), from [`game_task`](super::game_task) to
    /// `records_task`. Feature `records` only.
    #[cfg(feature = "records")]
    pub(crate) wins: Channel<CriticalSectionRawMutex, Win, 2>,
    /// Every level's record as `records_task` last read or wrote it.
    #[cfg(feature = "records")]
    pub(crate) bests: Latest<Bests>,
    /// The level whose win `records_task` has just stored as a new record.
    #[cfg(feature = "records")]
    pub(crate) new_record: Signal<CriticalSectionRawMutex, u8>,
}

impl<const W: usize, const H: usize> Links<W, H> {
    /// Nothing sent yet: a flat board, no command, no frame.
    pub const fn new() -> Self {
        Self {
            tilt: Latest::new(AccelMg::LEVEL),
            events: Channel::new(),
            frames: Signal::new(),
            status: Latest::new(Status::START),
            meter: Latest::new(None),
            #[cfg(feature = "sound")]
            sounds: Channel::new(),
            #[cfg(feature = "records")]
            wins: Channel::new(),
            #[cfg(feature = "records")]
            bests: Latest::new([None; LEVELS.len()]),
            #[cfg(feature = "records")]
            new_record: Signal::new(),
        }
    }
}

impl<const W: usize, const H: usize> Default for Links<W, H> {
    fn default() -> Self {
        Self::new()
    }
}

/// Runs `f` and returns the instructions it took: a board's CPU meter. Set
/// in [`Links::meter`] before a demo, it makes the demo log per level
/// `profile LEVEL: N frames, instructions per frame: physics AVG (max MAX),
/// autopilot AVG, render AVG` (render per frame drawn). The game is the
/// demo's, call for call (the same hashes).
pub type Meter = fn(&mut dyn FnMut()) -> u64;

/// A level won by the player, in game frames ([`FRAME_HZ`](super::FRAME_HZ) per second).
#[cfg(feature = "records")]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct Win {
    /// Index of the level in [`LEVELS`](crate::game::levels::LEVELS).
    pub(crate) level: u8,
    /// The time it took.
    pub(crate) frames: u32,
}

/// Each built-in level's record in frames, if it has one.
#[cfg(feature = "records")]
pub(crate) type Bests = [Option<u32>; LEVELS.len()];
