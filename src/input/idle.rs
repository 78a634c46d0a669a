//! Idle detection: nobody has touched the toy for a while, so it may sleep.
//!
//! A pure state machine like [`super::buttons`]: fed every frame's tilt
//! reading and every command, it says when the toy has been idle for
//! `IdleConfig::timeout_frames`. What sleeping means is the board's (for the
//! micro:bit v2: display off, System OFF, woken by a button).
//!
//! Run by the app's game loop (`app::play`, feature `sleep`): every command
//! is activity, every frame's reading is ticked, and two minutes idle end
//! the game task with `GameExit::Asleep` for the board to power down: the
//! micro:bit v2 goes to System OFF (woken by a button, resuming at the start
//! of the level), QEMU darkens its matrix until a key. The micro:bit v1 leaves
//! the feature out: it has no RAM for it. The timer sits in the app's loop, not
//! in `Player::tick`, where it would cost the v1 2 KB of stack, over its 12 KiB
//! RAM budget.
//!
//! "No tilt change" cannot mean "the same reading": an accelerometer on a
//! table reads a few milli-g of noise every sample. It means the reading has
//! stayed within `IdleConfig::still_mg` of where it was at the last activity
//! on every axis; a tilt past that (about 3° at 60 mg) is someone handling the
//! toy, and starts the count again from the new reading. Counting in frames,
//! not reading a clock, keeps it pure; the game's frames are its clock.

use super::axes::AccelMg;

/// When the toy counts as idle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct IdleConfig {
    /// Frames with no activity before [`Idle::tick`] says sleep (≥ 1).
    pub(crate) timeout_frames: u32,
    /// A reading further than this from the last activity's, on any axis, is
    /// activity (milli-g).
    pub(crate) still_mg: i32,
}

impl IdleConfig {
    /// Two minutes at `frame_hz` frames per second, 60 mg.
    pub const fn two_minutes(frame_hz: u32) -> Self {
        IdleConfig {
            timeout_frames: 120 * frame_hz,
            still_mg: 60,
        }
    }
}

/// The idle timer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Idle {
    config: IdleConfig,
    /// The reading at the last activity (`None` before the first reading).
    anchor: Option<AccelMg>,
    /// Frames since the last activity.
    still: u32,
}

impl Idle {
    /// Nothing seen yet: the count starts at the first reading.
    pub const fn new(config: IdleConfig) -> Self {
        Idle {
            config,
            anchor: None,
            still: 0,
        }
    }

    /// A button or a command: activity, whatever the tilt.
    pub fn activity(&mut self) {
        self.still = 0;
        self.anchor = None;
    }

    /// One frame with the tilt reading `mg`: `true` once the toy has been idle
    /// for the timeout (and every frame after, until some activity).
    pub fn tick(&mut self, mg: AccelMg) -> bool {
        let moved = match self.anchor {
            None => true,
            Some(a) => {
                let still = self.config.still_mg;
                (mg.x - a.x).abs() > still
                    || (mg.y - a.y).abs() > still
                    || (mg.z - a.z).abs() > still
            }
        };
        if moved {
            self.anchor = Some(mg);
            self.still = 0;
            return false;
        }
        self.still = self.still.saturating_add(1);
        self.still >= self.config.timeout_frames.max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CONFIG: IdleConfig = IdleConfig::two_minutes(128);

    /// Frames until `tick` first says sleep, feeding `reading(frame)`.
    fn frames_to_sleep(
        idle: &mut Idle,
        reading: impl Fn(u32) -> AccelMg,
        limit: u32,
    ) -> Option<u32> {
        (0..limit).find(|&f| idle.tick(reading(f)))
    }

    #[test]
    fn a_still_board_sleeps_after_exactly_two_minutes() {
        let mut idle = Idle::new(CONFIG);
        let at = frames_to_sleep(&mut idle, |_| AccelMg::new(10, 990, -5), 20_000);
        // The first reading is the anchor; 120 s × 128 frames after it.
        assert_eq!(at, Some(120 * 128));
        assert!(
            idle.tick(AccelMg::new(10, 990, -5)),
            "still asleep-worthy a frame later"
        );
    }

    #[test]
    fn sensor_noise_is_not_activity() {
        let mut idle = Idle::new(CONFIG);
        // ±25 mg of noise (the LSM303AGR reads a few mg at rest; its zero-g
        // offset drifts by tens of mg with temperature).
        let noise = |f: u32| {
            let n = ((f.wrapping_mul(2_654_435_761) >> 16) % 51) as i32 - 25;
            AccelMg::new(n, 1000 - n / 2, -n)
        };
        assert_eq!(frames_to_sleep(&mut idle, noise, 20_000), Some(120 * 128));
    }

    #[test]
    fn a_tilt_or_a_button_starts_the_count_again() {
        let mut idle = Idle::new(CONFIG);
        let flat = AccelMg::LEVEL;
        assert_eq!(frames_to_sleep(&mut idle, |_| flat, 100 * 128), None);
        // A 5° tilt (87 mg on x) at 100 s: two more minutes from there.
        let tilted = AccelMg::new(87, 996, 0);
        assert_eq!(
            frames_to_sleep(&mut idle, |_| tilted, 20_000),
            Some(120 * 128)
        );
        // A button just before the end restarts it too.
        idle.activity();
        assert_eq!(frames_to_sleep(&mut idle, |_| tilted, 119 * 128), None);
        idle.activity();
        assert_eq!(
            frames_to_sleep(&mut idle, |_| tilted, 20_000),
            Some(120 * 128)
        );
    }

    #[test]
    fn a_zero_timeout_does_not_panic() {
        let mut idle = Idle::new(IdleConfig {
            timeout_frames: 0,
            still_mg: 0,
        });
        assert!(!idle.tick(AccelMg::new(0, 0, 0)));
        assert!(idle.tick(AccelMg::new(0, 0, 0)));
    }
}
