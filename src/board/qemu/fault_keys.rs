//! The QEMU terminal's keys: the game's keys ([`KeyTilt`]: arrows/WASD tilt,
//! space, `c`, `r`, `n`, `p`, `q`), plus the digits that inject faults into the
//! virtual accelerometer ([`InjectedFault`]): `1` NAK, `2` stuck bus, `3`
//! frozen data, `4` garbage, `5` chip reset, `0` healthy.
//!
//! Digits are also parameters inside an escape sequence (`ESC [ 1 ; 5 A` is
//! Ctrl+Up), so they inject a fault only outside one; the escape state is
//! tracked here exactly as [`KeyDecoder`](crate::input::keys::KeyDecoder)
//! tracks it.

use crate::board::virtual_lsm303agr::InjectedFault;
use crate::input::event::InputEvent;
use crate::input::keys::KeyTilt;

/// The status line's help for the fault keys (fits an 80-column terminal).
pub const FAULT_KEYS_HELP: &str =
    "fault keys: 1 NAK, 2 stuck bus, 3 frozen data, 4 garbage, 5 chip reset, 0 none";

/// A decoded QEMU terminal key.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum QemuKey {
    /// A game key: a tilt for the virtual chip, or a command for the game.
    Input(InputEvent),
    /// A fault to inject.
    Inject(InjectedFault),
}

#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
enum Escape {
    #[default]
    None,
    Esc,
    Sequence,
}

/// Decodes the QEMU terminal's bytes (see the module doc).
#[derive(Clone, Copy, Debug, Default)]
pub struct FaultKeys {
    keys: KeyTilt,
    escape: Escape,
}

impl FaultKeys {
    /// Flat, outside any escape sequence.
    pub const fn new() -> Self {
        Self {
            keys: KeyTilt::new(),
            escape: Escape::None,
        }
    }

    /// Feeds one byte; returns the key it completes, if any.
    pub fn feed(&mut self, byte: u8) -> Option<QemuKey> {
        let outside = match self.escape {
            Escape::None => true,
            // After a lone ESC the decoder takes the byte as a plain key.
            Escape::Esc => byte != b'[' && byte != b'O',
            Escape::Sequence => false,
        };
        self.escape = match (self.escape, byte) {
            (Escape::Sequence, 0x20..=0x3f) => Escape::Sequence,
            (Escape::Sequence, _) => Escape::None,
            (Escape::Esc, b'[' | b'O') => Escape::Sequence,
            (_, 0x1b) => Escape::Esc,
            _ => Escape::None,
        };
        if outside {
            if let Some(fault) = byte.checked_sub(b'0').and_then(InjectedFault::from_u8) {
                return Some(QemuKey::Inject(fault));
            }
        }
        self.keys.feed(byte).map(QemuKey::Input)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::axes::AccelMg;
    use crate::input::event::Command;

    fn feed_all(keys: &mut FaultKeys, bytes: &[u8]) -> heapless::Vec<QemuKey, 8> {
        let mut out = heapless::Vec::new();
        for &b in bytes {
            if let Some(key) = keys.feed(b) {
                let _ = out.push(key);
            }
        }
        out
    }

    #[test]
    fn digits_inject_outside_escape_sequences() {
        let mut keys = FaultKeys::new();
        assert_eq!(
            feed_all(&mut keys, b"102345"),
            [
                QemuKey::Inject(InjectedFault::Nak),
                QemuKey::Inject(InjectedFault::Healthy),
                QemuKey::Inject(InjectedFault::StuckBus),
                QemuKey::Inject(InjectedFault::FrozenData),
                QemuKey::Inject(InjectedFault::Garbage),
                QemuKey::Inject(InjectedFault::ChipReset),
            ]
        );
        // Ctrl+Right: the digits are parameters, the key is a tilt.
        let keys_out = feed_all(&mut keys, b"\x1b[1;5C");
        assert_eq!(keys_out.len(), 1);
        assert!(matches!(keys_out[0], QemuKey::Input(InputEvent::Tilt(_))));
        assert_eq!(
            feed_all(&mut keys, b"6q"),
            [QemuKey::Input(InputEvent::Command(Command::Quit))]
        );
        // Game keys tilt beside the fault keys.
        let mut keys = FaultKeys::new();
        assert_eq!(
            feed_all(&mut keys, b"d"),
            [QemuKey::Input(InputEvent::Tilt(AccelMg::from_xz(-100, 0)))]
        );
    }
}
