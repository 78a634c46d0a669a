//! The input task: whatever a board reads (accelerometer and buttons, a
//! terminal's keys, a script) comes in as [`InputEvent`]s and goes on to the
//! game task, the tilt as the latest value, the rest in order.

use core::future::Future;

use super::links::Links;
use crate::input::event::InputEvent;

/// A source of tilt readings and commands (accelerometer, keyboard, script).
pub trait TiltInput {
    /// Waits for the next event.
    fn next_event(&mut self) -> impl Future<Output = InputEvent>;
}

/// Forwards events from `input`: tilts to [`Links::tilt`], the rest to
/// [`Links::events`], forever.
pub async fn input_task<I: TiltInput, const W: usize, const H: usize>(
    links: &Links<W, H>,
    input: &mut I,
) -> ! {
    loop {
        match input.next_event().await {
            InputEvent::Tilt(tilt) => links.tilt.set(tilt),
            event => links.events.send(event).await,
        }
    }
}
