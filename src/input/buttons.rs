//! Two-button input: debouncing and the A / B / A+B-hold combinations.
//!
//! Pure and board-agnostic: a board samples its two buttons at a fixed period
//! (e.g. every 10 ms) and feeds the raw "pressed" levels to
//! [`Buttons::update`], which returns at most one [`ButtonEvent`] per sample.
//!
//! * **B** pressed and released alone → [`ButtonEvent::NextLevel`].
//! * **A** pressed and released alone → [`ButtonEvent::Restart`].
//! * **A+B** held together for [`ButtonConfig::hold_samples`] →
//!   [`ButtonEvent::Calibrate`] (once per hold).
//! * **B** held alone for [`ButtonConfig::hold_samples`] →
//!   [`ButtonEvent::ToggleMute`] (once per hold; its release is then not
//!   NextLevel): the micro:bit has two buttons, and a long press is the one
//!   gesture left.
//!
//! Single-button events fire on *release*, and never once both buttons have
//! been down together during that press: pressing A then B to calibrate does
//! not also restart the level.
//!
//! All timing is counted in samples, not read from a clock, so that the logic
//! stays pure; the price is that the board must keep the sampling period.
//! A poll loop that catches up on missed periods back to back (an embassy
//! `Ticker` after a slow sensor re-init) squeezes the 30 ms debounce into a
//! millisecond; the micro:bit restarts its ticker after slow work instead.

/// A user command from the buttons.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ButtonEvent {
    /// Button B alone: go to the next level.
    NextLevel,
    /// Button A alone: restart the current level.
    Restart,
    /// A+B held: the current orientation becomes "level".
    Calibrate,
    /// B held alone: sound off, or back on.
    ToggleMute,
}

/// Timing of [`Buttons`], in samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ButtonConfig {
    /// Consecutive identical raw samples needed to accept a change (≥ 1).
    pub debounce_samples: u8,
    /// Samples both buttons must be (debounced) down to calibrate, or B
    /// alone to toggle the sound (≥ 1).
    pub hold_samples: u16,
}

impl ButtonConfig {
    /// For a 10 ms sampling period: 30 ms debounce, 1 s hold.
    pub(crate) const DEFAULT_10MS: Self = Self {
        debounce_samples: 3,
        hold_samples: 100,
    };
}

impl Default for ButtonConfig {
    fn default() -> Self {
        Self::DEFAULT_10MS
    }
}

/// One debounced input.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Debounced {
    pressed: bool,
    disagree: u8,
}

impl Debounced {
    /// Feeds one raw sample; returns the new stable state if it changed.
    fn update(&mut self, raw: bool, needed: u8) -> Option<bool> {
        if raw == self.pressed {
            self.disagree = 0;
            return None;
        }
        self.disagree = self.disagree.saturating_add(1);
        if self.disagree >= needed.max(1) {
            self.disagree = 0;
            self.pressed = raw;
            Some(raw)
        } else {
            None
        }
    }
}

/// Debouncer and combination detector for buttons A and B.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Buttons {
    config: ButtonConfig,
    a: Debounced,
    b: Debounced,
    /// Both were down together since the last time both were up.
    combo: bool,
    /// Samples both have been down in a row (saturating).
    both_held: u16,
    /// Samples B has been down alone in a row (saturating).
    b_held: u16,
    /// A hold (Calibrate or ToggleMute) already fired for this press.
    fired: bool,
}

impl Buttons {
    /// Both buttons released, nothing pending.
    pub const fn new(config: ButtonConfig) -> Self {
        Self {
            config,
            a: Debounced {
                pressed: false,
                disagree: 0,
            },
            b: Debounced {
                pressed: false,
                disagree: 0,
            },
            combo: false,
            both_held: 0,
            b_held: 0,
            fired: false,
        }
    }

    /// Debounced state of A.
    pub const fn a_pressed(&self) -> bool {
        self.a.pressed
    }

    /// Debounced state of B.
    pub const fn b_pressed(&self) -> bool {
        self.b.pressed
    }

    /// Whether a hold of `held` samples fires now: once it reaches
    /// [`ButtonConfig::hold_samples`], and only once per press.
    fn hold_fires(&mut self, held: u16) -> bool {
        let fires = !self.fired && held >= self.config.hold_samples.max(1);
        self.fired |= fires;
        fires
    }

    /// Feeds one raw sample (`true` = pressed; the board handles polarity).
    pub fn update(&mut self, a_raw: bool, b_raw: bool) -> Option<ButtonEvent> {
        let a_edge = self.a.update(a_raw, self.config.debounce_samples);
        let b_edge = self.b.update(b_raw, self.config.debounce_samples);
        let (a, b) = (self.a.pressed, self.b.pressed);

        let mut event = None;
        if a && b {
            self.combo = true;
            self.both_held = self.both_held.saturating_add(1);
            if self.hold_fires(self.both_held) {
                event = Some(ButtonEvent::Calibrate);
            }
        } else {
            self.both_held = 0;
            if b && !self.combo {
                self.b_held = self.b_held.saturating_add(1);
                if self.hold_fires(self.b_held) {
                    event = Some(ButtonEvent::ToggleMute);
                }
            } else {
                self.b_held = 0;
            }
            if !self.combo && !self.fired {
                if a_edge == Some(false) {
                    event = Some(ButtonEvent::Restart);
                } else if b_edge == Some(false) {
                    event = Some(ButtonEvent::NextLevel);
                }
            }
        }
        if !a && !b {
            self.combo = false;
            self.fired = false;
            self.b_held = 0;
        }
        event
    }
}

impl Default for Buttons {
    fn default() -> Self {
        Self::new(ButtonConfig::DEFAULT_10MS)
    }
}
