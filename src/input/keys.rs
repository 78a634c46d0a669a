//! Terminal keys as an input: decoding raw-mode bytes into keys, and the key
//! tilt, a virtual accelerometer the arrow keys hold at a tilt. The QEMU
//! firmware and the host's terminal player (`cargo play`) both use it, so the
//! same keys give the same readings and the same game.

use super::axes::AccelMg;
use super::event::{Command, InputEvent};

/// Tilt added per key press, milli-g.
pub(crate) const KEY_TILT_STEP_MG: i32 = 100;
/// Largest tilt reachable with keys, milli-g per axis.
pub(crate) const KEY_TILT_MAX_MG: i32 = 500;

/// A key recognised by [`KeyDecoder`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Key {
    /// Arrow up or `w`: roll the marble up the screen (away from the player).
    Up,
    /// Arrow down or `s`.
    Down,
    /// Arrow left or `a`.
    Left,
    /// Arrow right or `d`.
    Right,
    /// Space: level the board.
    Level,
    /// `r`.
    Restart,
    /// `n`.
    Next,
    /// `c`: take the current tilt as level.
    Calibrate,
    /// `p`: autopilot on / off.
    Autopilot,
    /// `m`: sound off / on.
    Mute,
    /// `q` or Ctrl-C.
    Quit,
}

/// Escape-sequence state of [`KeyDecoder`].
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
enum Escape {
    #[default]
    None,
    /// After ESC.
    Esc,
    /// After `ESC [` or `ESC O`, inside a control sequence.
    Sequence,
}

/// Decodes terminal bytes (raw mode) into [`Key`]s: arrow keys (`ESC [ A`,
/// `ESC O A`, with or without modifiers like `ESC [ 1 ; 5 A`), WASD, space,
/// `r`, `n`, `c`, `p`, `q`, Ctrl-C. Other bytes are ignored.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeyDecoder {
    state: Escape,
}

impl KeyDecoder {
    /// A decoder outside any escape sequence.
    pub(crate) const fn new() -> Self {
        Self {
            state: Escape::None,
        }
    }

    /// Feeds one byte; returns a key when one is complete.
    pub(crate) fn feed(&mut self, byte: u8) -> Option<Key> {
        match self.state {
            Escape::None => Self::plain(byte, &mut self.state),
            Escape::Esc => {
                if byte == b'[' || byte == b'O' {
                    self.state = Escape::Sequence;
                    None
                } else {
                    self.state = Escape::None;
                    Self::plain(byte, &mut self.state)
                }
            }
            Escape::Sequence => match byte {
                // Parameters and intermediates: stay in the sequence.
                0x20..=0x3f => None,
                final_byte => {
                    self.state = Escape::None;
                    match final_byte {
                        b'A' => Some(Key::Up),
                        b'B' => Some(Key::Down),
                        b'C' => Some(Key::Right),
                        b'D' => Some(Key::Left),
                        _ => None,
                    }
                }
            },
        }
    }

    fn plain(byte: u8, state: &mut Escape) -> Option<Key> {
        match byte {
            0x1b => {
                *state = Escape::Esc;
                None
            }
            b'w' | b'W' => Some(Key::Up),
            b's' | b'S' => Some(Key::Down),
            b'a' | b'A' => Some(Key::Left),
            b'd' | b'D' => Some(Key::Right),
            b' ' => Some(Key::Level),
            b'r' | b'R' => Some(Key::Restart),
            b'n' | b'N' => Some(Key::Next),
            b'c' | b'C' => Some(Key::Calibrate),
            b'p' | b'P' => Some(Key::Autopilot),
            b'm' | b'M' => Some(Key::Mute),
            b'q' | b'Q' | 0x03 => Some(Key::Quit),
            _ => None,
        }
    }
}

/// A virtual accelerometer driven by keys: each arrow/WASD press tilts the
/// board one `KEY_TILT_STEP_MG` step further that way (up to
/// `KEY_TILT_MAX_MG`); space levels it. A terminal sends no key releases,
/// so the tilt stays until changed, like a board held tilted.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeyTilt {
    decoder: KeyDecoder,
    x: i32,
    z: i32,
}

impl KeyTilt {
    /// Flat, outside any escape sequence.
    pub const fn new() -> Self {
        Self {
            decoder: KeyDecoder::new(),
            x: 0,
            z: 0,
        }
    }

    /// Feeds one terminal byte; returns the event it completes, if any.
    pub fn feed(&mut self, byte: u8) -> Option<InputEvent> {
        let key = self.decoder.feed(byte)?;
        Some(self.press(key))
    }

    /// One key press (for a front end that decodes keys itself, like the
    /// host's terminal player): the event it makes.
    pub fn press(&mut self, key: Key) -> InputEvent {
        let step = KEY_TILT_STEP_MG;
        let (dx, dz) = match key {
            // Marble up the screen = towards -z: raise the near edge, z > 0.
            Key::Up => (0, step),
            Key::Down => (0, -step),
            // Marble right = towards +x: lower the right edge, x < 0.
            Key::Right => (-step, 0),
            Key::Left => (step, 0),
            Key::Level => (-self.x, -self.z),
            Key::Restart => return InputEvent::Command(Command::Restart),
            Key::Next => return InputEvent::Command(Command::NextLevel),
            Key::Calibrate => return InputEvent::Command(Command::Calibrate),
            Key::Autopilot => return InputEvent::Command(Command::ToggleAutopilot),
            Key::Mute => return InputEvent::Command(Command::ToggleMute),
            Key::Quit => return InputEvent::Command(Command::Quit),
        };
        let max = KEY_TILT_MAX_MG;
        self.x = (self.x + dx).clamp(-max, max);
        self.z = (self.z + dz).clamp(-max, max);
        InputEvent::Tilt(self.tilt())
    }

    /// The tilt the keys hold now (flat until the first tilt key).
    pub(crate) fn tilt(&self) -> AccelMg {
        AccelMg::from_xz(self.x, self.z)
    }
}
