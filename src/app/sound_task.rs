//! The sound task: the game's [`Sound`]s played in order on a board's
//! [`SoundOutput`], away from the game's frame clock.

use core::future::Future;

use super::links::Links;
use crate::matrix::output::Console;
use crate::sound::Sound;

/// Where a board plays a [`Sound`] (feature `sound`).
pub trait SoundOutput {
    /// Plays `sound`; returns when the next one may start (a speaker's
    /// sequence may still be sounding: it must not block the game).
    fn play(&mut self, sound: Sound) -> impl Future<Output = ()>;
}

/// Plays the sounds from `Links::sounds` on `output`, in order, forever.
pub async fn sound_task<O: SoundOutput, const W: usize, const H: usize>(
    links: &Links<W, H>,
    output: &mut O,
) -> ! {
    loop {
        let sound = links.sounds.receive().await;
        output.play(sound).await;
    }
}

/// [`SoundOutput`] for a terminal: each sound in the log, and the terminal's
/// bell on a win (the one sound a terminal has).
pub struct TerminalSound<C: Console> {
    console: C,
}

impl<C: Console> TerminalSound<C> {
    /// Rings `console`'s bell.
    pub const fn new(console: C) -> Self {
        Self { console }
    }
}

impl<C: Console> SoundOutput for TerminalSound<C> {
    async fn play(&mut self, sound: Sound) {
        #[cfg(feature = "defmt")]
        defmt::info!("sound {}", sound);
        if sound == Sound::Win {
            self.console.write(b"\x07");
        }
    }
}
