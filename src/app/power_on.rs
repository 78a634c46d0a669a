//! The power-on flows of a 5 × 5 board (the micro:bit v2) as tasks run them:
//! the self-test and the "clear the best times?" question, over the states of
//! [`crate::player::power_on`], which the host tests run. The board chooses
//! the flow from the buttons held ([`power_on`](crate::player::power_on::power_on)),
//! hands in what only it has (its pins, its watchdog, its flash) and does what
//! the answer asks.

use embassy_time::{Duration, Ticker};

use super::Links;
use crate::input::buttons::ButtonConfig;
use crate::player::power_on::{confirm_frame, Confirm, SelfTest, CONFIRM_SAMPLE_MS};
use crate::player::FRAME_HZ;

/// The self-test's frames at the game's frame rate, the dot from the live
/// tilt (none while the sensor is down); returns on **A**. The input task
/// must run: the events and the tilt come through `links`.
pub async fn self_test(links: &Links<5, 5>) {
    let mut ticker = Ticker::every(Duration::from_hz(u64::from(FRAME_HZ)));
    let mut test = SelfTest::new();
    loop {
        ticker.next().await;
        while let Ok(event) = links.events.try_receive() {
            if test.event(event) {
                return;
            }
        }
        links.frames.signal(test.next_frame(links.tilt.get()));
    }
}

/// Shows the question mark until one button answers, sampling the buttons
/// every [`CONFIRM_SAMPLE_MS`] with their default timing: `true` (**A**)
/// clears the best times, `false` (**B**, or nothing for
/// [`CONFIRM_TIMEOUT_SAMPLES`](crate::player::power_on::CONFIRM_TIMEOUT_SAMPLES)
/// samples, 10 s) keeps them. `pressed` reads the two buttons (`true`:
/// pressed); `each_sample` runs before every sample (the board pets its
/// watchdog there, its task not running yet). The question stays on the
/// matrix: the board clears it once it has done what the answer asks.
pub async fn ask_clear(
    links: &Links<5, 5>,
    mut pressed: impl FnMut() -> (bool, bool),
    mut each_sample: impl FnMut(),
) -> bool {
    links.frames.signal(confirm_frame());
    let mut question = Confirm::new(ButtonConfig::default());
    let mut ticker = Ticker::every(Duration::from_millis(CONFIRM_SAMPLE_MS));
    loop {
        ticker.next().await;
        each_sample();
        let (a, b) = pressed();
        if let Some(answer) = question.sample(a, b) {
            return answer;
        }
    }
}
