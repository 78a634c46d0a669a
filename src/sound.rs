//! What the toy plays, decided from what the game did: a click for each bounce
//! against a wall, louder the harder it hits, a jingle on a win and a falling
//! tone on a loss. Pure and allocation-free like [`crate::input::buttons`]: the
//! game hands in the frame's [`Impacts`] and outcome, a board turns the
//! [`Sound`]s into whatever it has (PWM on a speaker, a log line, the terminal
//! bell).
//!
//! The loudness follows the impact's normal speed, the speed the marble loses
//! into the wall, because that is what a real marble's click follows. Below
//! [`CLICK_FROM_MM_S`] nothing plays: that is a marble settling against a wall,
//! not a hit (the restitution threshold, 20 mm/s by default, already turns the
//! slowest impacts into contacts with no bounce to report).

use crate::game::rules::Phase;
use crate::physics::{Impacts, Scalar, IMPACTS_KEPT};

/// The slowest impact that clicks (mm/s).
pub const CLICK_FROM_MM_S: u32 = 40;

/// The impact speed (mm/s) at and above which a click is at full loudness: a
/// marble thrown at a wall at about 0.6 m/s.
pub(crate) const CLICK_FULL_MM_S: u32 = 640;

/// The most sounds one frame makes: a click per kept impact, and the outcome.
pub(crate) const MAX_SOUNDS: usize = IMPACTS_KEPT + 1;

/// One sound to play.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sound {
    /// A bounce: `loudness` 1 (at [`CLICK_FROM_MM_S`]) to 255 (from
    /// `CLICK_FULL_MM_S`), growing with the impact speed.
    Click {
        /// 1..=255.
        loudness: u8,
    },
    /// The level was won.
    Win,
    /// The attempt was lost (a fall, or the time ran out).
    Loss,
}

/// A frame's sounds, in the order to play them (fixed capacity, `Copy`, so
/// that it travels in a frame's result like the picture does).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Sounds {
    list: [Option<Sound>; MAX_SOUNDS],
}

impl Sounds {
    /// No sound.
    pub(crate) const NONE: Sounds = Sounds {
        list: [None; MAX_SOUNDS],
    };

    fn push(&mut self, sound: Sound) {
        if let Some(slot) = self.list.iter_mut().find(|s| s.is_none()) {
            *slot = Some(sound);
        }
    }

    /// The sounds, in order.
    pub fn iter(&self) -> impl Iterator<Item = Sound> + '_ {
        self.list.iter().map_while(|s| *s)
    }

    /// Whether there is nothing to play.
    pub fn is_empty(&self) -> bool {
        self.list[0].is_none()
    }
}

/// The click for an impact at `speed_mm_s`: none below [`CLICK_FROM_MM_S`], then a
/// loudness rising linearly to 255 at `CLICK_FULL_MM_S`.
pub fn click(speed_mm_s: u32) -> Option<Sound> {
    if speed_mm_s < CLICK_FROM_MM_S {
        return None;
    }
    let above = speed_mm_s.min(CLICK_FULL_MM_S) - CLICK_FROM_MM_S;
    let span = CLICK_FULL_MM_S - CLICK_FROM_MM_S;
    let loudness = 1 + above * 254 / span;
    Some(Sound::Click {
        loudness: loudness as u8,
    })
}

/// `v` pitch/s in mm/s (rounded down; negative: 0) on a layout whose pitch is
/// `pitch_um`. Integer arithmetic only: the boards convert with no float code.
pub fn mm_per_s<S: Scalar>(v: S, pitch_um: u32) -> u32 {
    if v <= S::ZERO {
        return 0;
    }
    // v = whole + frac, in 1/64 pitch/s (frac·64 < 64 fits every format).
    let whole = v.floor_int();
    let frac = (v - S::from_int(whole)).shl(6).floor_int();
    let v64 = (whole as i64) * 64 + frac as i64;
    (v64 * pitch_um as i64 / 64_000).clamp(0, u32::MAX as i64) as u32
}

/// The sounds of one frame: a click for each kept impact fast enough to click,
/// in order, then the outcome if the attempt ended in this frame. Muted, none.
pub fn frame_sounds<S: Scalar>(
    impacts: &Impacts<S>,
    pitch_um: u32,
    finished: Option<Phase>,
    muted: bool,
) -> Sounds {
    let mut out = Sounds::NONE;
    if muted {
        return out;
    }
    for &v in impacts.speeds() {
        if let Some(c) = click(mm_per_s(v, pitch_um)) {
            out.push(c);
        }
    }
    match finished {
        Some(Phase::Won) => out.push(Sound::Win),
        Some(Phase::Fell | Phase::TimeUp) => out.push(Sound::Loss),
        Some(Phase::Playing) | None => {}
    }
    out
}

/// One tone of a speaker's rendition: a square wave of `hz` for `ms`, at
/// `level` (1..=255, the share of the loudest the speaker gives).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Note {
    /// Pitch, Hz.
    pub hz: u16,
    /// Length, ms.
    pub ms: u16,
    /// 1..=255.
    pub level: u8,
}

/// A click: one short burst, shorter than a frame (1/128 s), so that the
/// next frame's click is not delayed.
const CLICK: Note = Note {
    hz: 2_000,
    ms: 4,
    level: 255,
};

/// The win: C6 E6 G6 C7 rising.
const WIN: [Note; 4] = [
    Note {
        hz: 1047,
        ms: 90,
        level: 200,
    },
    Note {
        hz: 1319,
        ms: 90,
        level: 200,
    },
    Note {
        hz: 1568,
        ms: 90,
        level: 200,
    },
    Note {
        hz: 2093,
        ms: 180,
        level: 200,
    },
];

/// The loss: G5 to E4 falling.
const LOSS: [Note; 5] = [
    Note {
        hz: 784,
        ms: 80,
        level: 180,
    },
    Note {
        hz: 659,
        ms: 80,
        level: 180,
    },
    Note {
        hz: 523,
        ms: 80,
        level: 180,
    },
    Note {
        hz: 440,
        ms: 80,
        level: 180,
    },
    Note {
        hz: 330,
        ms: 200,
        level: 180,
    },
];

/// What a speaker plays for `sound`, in order.
pub fn notes(sound: Sound) -> heapless::Vec<Note, 5> {
    let mut out = heapless::Vec::new();
    let tune: &[Note] = match sound {
        Sound::Click { loudness } => {
            let _ = out.push(Note {
                level: loudness,
                ..CLICK
            });
            &[]
        }
        Sound::Win => &WIN,
        Sound::Loss => &LOSS,
    };
    for &n in tune {
        let _ = out.push(n);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clicks_start_at_the_threshold_and_grow_with_speed() {
        assert_eq!(click(CLICK_FROM_MM_S - 1), None);
        assert_eq!(click(CLICK_FROM_MM_S), Some(Sound::Click { loudness: 1 }));
        assert_eq!(click(CLICK_FULL_MM_S), Some(Sound::Click { loudness: 255 }));
        assert_eq!(
            click(10 * CLICK_FULL_MM_S),
            Some(Sound::Click { loudness: 255 })
        );
        let mut last = 0;
        for v in (CLICK_FROM_MM_S..=CLICK_FULL_MM_S).step_by(20) {
            let Some(Sound::Click { loudness }) = click(v) else {
                panic!("no click at {v} mm/s");
            };
            assert!(loudness > last, "{v} mm/s: {loudness} after {last}");
            last = loudness;
        }
    }

    #[test]
    fn the_win_rises_the_loss_falls_a_click_fits_a_frame() {
        let win = notes(Sound::Win);
        assert!(win.windows(2).all(|w| w[1].hz > w[0].hz));
        let loss = notes(Sound::Loss);
        assert!(loss.windows(2).all(|w| w[1].hz < w[0].hz));
        let soft = notes(Sound::Click { loudness: 10 });
        let hard = notes(Sound::Click { loudness: 200 });
        assert_eq!((soft.len(), hard.len()), (1, 1));
        assert!(hard[0].level > soft[0].level);
        assert!(
            u32::from(hard[0].ms) * 128 < 1000,
            "a click outlasts a frame"
        );
    }

    #[test]
    fn speeds_convert_without_floats() {
        type S = fixed::types::I8F24;
        // 12 mm pitch: 10 pitch/s is 120 mm/s, 0.5 pitch/s 6 mm/s.
        assert_eq!(mm_per_s(S::from_num(10), 12_000), 120);
        assert_eq!(mm_per_s(S::from_num(0.5), 12_000), 6);
        assert_eq!(mm_per_s(S::from_num(127.9), 12_000), 1534);
        assert_eq!(mm_per_s(-S::ONE, 12_000), 0);
        assert_eq!(mm_per_s(3.25f32, 10_000), 32);
        assert_eq!(mm_per_s(3.25f64, 10_000), 32);
    }
}
