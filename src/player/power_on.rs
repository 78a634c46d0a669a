//! What the owner asks for at power-on, by the buttons held while a 5 × 5
//! board starts (the micro:bit v2): nothing (the game), **B** (the self-test),
//! **A+B** (clear the best times, after a confirmation); **A** alone races a
//! friend's board ([`crate::input::race_setup::race_at_power_on`]). Pure: the
//! board samples the pins and feeds [`power_on`]; the two flows, [`SelfTest`]
//! and [`Confirm`], are states here that the app's power-on flows
//! (`app::power_on`, firmware) tick, so that what they do is what the host
//! tests run.
//!
//! # The self-test
//!
//! How an owner checks the LEDs and the accelerometer's axes on a real board
//! (the v2's [`AXIS_MAP`](crate::board::accel_link::AXIS_MAP) is taken from the
//! micro:bit runtime, never checked on hardware here):
//! 1. every LED alone, at full brightness, left to right and top to bottom
//!    ([`SWEEP_FRAMES`] each): a dark step is a dead LED;
//! 2. the whole matrix at each brightness level, dimmest first
//!    ([`LEVEL_FRAMES`] each): the steps must look even;
//! 3. the live tilt as a dot where the marble would roll (the game's gravity:
//!    the reading negated): tilt the right edge down and the dot goes right,
//!    tilt the edge connector (the edge nearest you) down and it goes to the
//!    bottom row. If it goes the other way, flip that axis's sign in
//!    `AXIS_MAP` (x for left/right, z for up/down).
//!
//! **A** leaves the self-test for the game.
//!
//! # Clearing the records
//!
//! A+B at power-on shows [`confirm_frame`] (a question mark) until both are
//! released and one is pressed: **A** clears every best time, **B** keeps them,
//! and so does doing nothing for [`CONFIRM_TIMEOUT_SAMPLES`] (a board that
//! starts with both buttons stuck down never loses its records).

use crate::input::axes::AccelMg;
use crate::input::buttons::{ButtonConfig, ButtonEvent, Buttons};
use crate::input::event::{Command, InputEvent};
use crate::matrix::{Brightness, Frame, MAX_BRIGHTNESS};

/// What the buttons held at power-on ask for.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PowerOn {
    /// Nothing held: the game.
    Play,
    /// B held: the self-test.
    SelfTest,
    /// A+B held: clear the records, once confirmed.
    ClearRecords,
}

/// The choice for buttons A and B held (`true`) at power-on. A alone is the
/// game here: a race, unless the board is waking from its sleep, is
/// [`race_at_power_on`](crate::input::race_setup::race_at_power_on)'s to say.
pub const fn power_on(a_held: bool, b_held: bool) -> PowerOn {
    match (a_held, b_held) {
        (true, true) => PowerOn::ClearRecords,
        (false, true) => PowerOn::SelfTest,
        _ => PowerOn::Play,
    }
}

/// The period the confirmation samples the buttons at, ms: what
/// [`CONFIRM_TIMEOUT_SAMPLES`] and the buttons' default timing
/// ([`ButtonConfig::default`]: 30 ms debounce) count in.
pub const CONFIRM_SAMPLE_MS: u64 = 10;

/// Button samples ([`CONFIRM_SAMPLE_MS`] each) without an answer after which
/// the confirmation keeps the records: 10 s.
pub const CONFIRM_TIMEOUT_SAMPLES: u32 = 1000;

/// The answer to "clear the records?" after `samples` button samples, of
/// which the latest gave `event` (from [`crate::input::buttons::Buttons`],
/// which reports A or B only for a press of one button alone, so the A+B
/// still held from power-on answers nothing): `Some(true)` clear, `Some(false)`
/// keep, `None` not yet.
pub const fn confirm(event: Option<ButtonEvent>, samples: u32) -> Option<bool> {
    match event {
        Some(ButtonEvent::Restart) => Some(true),
        Some(ButtonEvent::NextLevel) => Some(false),
        _ if samples >= CONFIRM_TIMEOUT_SAMPLES => Some(false),
        _ => None,
    }
}

/// The confirmation under way (see the module doc): the buttons' debouncing
/// and the samples so far. `app::power_on::ask_clear` shows [`confirm_frame`]
/// and feeds it the buttons every sample until it answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Confirm {
    buttons: Buttons,
    samples: u32,
}

impl Confirm {
    /// A confirmation that has seen no sample, with the board's button timing.
    pub const fn new(buttons: ButtonConfig) -> Self {
        Self {
            buttons: Buttons::new(buttons),
            samples: 0,
        }
    }

    /// One sample of the buttons (`true`: pressed): [`confirm`]'s answer,
    /// once there is one.
    pub fn sample(&mut self, a_pressed: bool, b_pressed: bool) -> Option<bool> {
        self.samples = self.samples.saturating_add(1);
        let event = self.buttons.update(a_pressed, b_pressed);
        confirm(event, self.samples)
    }
}

/// The question mark the confirmation shows.
pub fn confirm_frame() -> Frame<5, 5> {
    const ROWS: [&[u8; 5]; 5] = [b".###.", b"...#.", b"..#..", b".....", b"..#.."];
    let mut frame = Frame::new();
    for (y, row) in ROWS.iter().enumerate() {
        for (x, &c) in row.iter().enumerate() {
            if c == b'#' {
                frame.set(x, y, MAX_BRIGHTNESS);
            }
        }
    }
    frame
}

/// Frames each LED is shown alone (1/16 s at 128 frames/s).
pub const SWEEP_FRAMES: u32 = 8;
/// Frames each brightness level is shown (1/4 s).
pub const LEVEL_FRAMES: u32 = 32;
/// Milli-g of tilt per pixel the dot moves (about 17° to the edge).
pub(crate) const DOT_MG_PER_PIXEL: i32 = 150;

/// Frame `n` of the self-test (see the module doc), with `reading` the
/// latest accelerometer reading (for the dot; `None` while the sensor is
/// down: the dot is then not shown).
pub fn self_test_frame(n: u32, reading: Option<AccelMg>) -> Frame<5, 5> {
    let mut frame = Frame::new();
    let sweep = 25 * SWEEP_FRAMES;
    if n < sweep {
        let led = (n / SWEEP_FRAMES) as usize;
        frame.set(led % 5, led / 5, MAX_BRIGHTNESS);
        return frame;
    }
    let level = (n - sweep) / LEVEL_FRAMES + 1;
    if level <= u32::from(MAX_BRIGHTNESS) {
        return Frame::filled(level as Brightness);
    }
    if let Some(AccelMg { x, z, .. }) = reading {
        let (col, row) = dot(x, z);
        frame.set(col, row, MAX_BRIGHTNESS);
    }
    frame
}

/// The self-test under way (see the module doc): the frame it is at, and
/// whether the sensor is up (the dot is shown only then).
/// `app::power_on::self_test` hands it the input events and, once a frame,
/// the latest reading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SelfTest {
    frame: u32,
    sensor_up: bool,
}

impl Default for SelfTest {
    fn default() -> Self {
        Self::new()
    }
}

impl SelfTest {
    /// The self-test's first frame, the sensor taken as up.
    pub const fn new() -> Self {
        Self {
            frame: 0,
            sensor_up: true,
        }
    }

    /// Takes one input event: `true` when it ends the self-test (**A**, which
    /// the buttons send as [`Command::Restart`]). The sensor going down hides
    /// the dot until it is up again.
    pub fn event(&mut self, event: InputEvent) -> bool {
        match event {
            InputEvent::Command(Command::Restart) => return true,
            InputEvent::SensorDown(_) => self.sensor_up = false,
            InputEvent::SensorUp => self.sensor_up = true,
            _ => {}
        }
        false
    }

    /// The next frame ([`self_test_frame`]), the dot from `reading`, the
    /// latest reading, while the sensor is up.
    pub fn next_frame(&mut self, reading: AccelMg) -> Frame<5, 5> {
        let frame = self_test_frame(self.frame, self.sensor_up.then_some(reading));
        self.frame = self.frame.saturating_add(1);
        frame
    }
}

/// Where the dot goes for a board-frame reading: the way the marble rolls
/// (gravity is the reading negated: `x < 0` rolls towards `+x`, the right),
/// one pixel per `DOT_MG_PER_PIXEL`, rounded, held on the matrix.
pub fn dot(x_mg: i32, z_mg: i32) -> (usize, usize) {
    let pixel = |mg: i32| {
        let g = mg.saturating_neg();
        let half = DOT_MG_PER_PIXEL / 2;
        let steps = if g >= 0 {
            (g.saturating_add(half)) / DOT_MG_PER_PIXEL
        } else {
            -((half.saturating_sub(g)) / DOT_MG_PER_PIXEL)
        };
        (2 + steps.clamp(-2, 2)) as usize
    };
    (pixel(x_mg), pixel(z_mg))
}

/// Frames from the end of the brightness steps on (the live dot): the
/// self-test's length before the dot.
pub const fn dot_from() -> u32 {
    25 * SWEEP_FRAMES + MAX_BRIGHTNESS as u32 * LEVEL_FRAMES
}
