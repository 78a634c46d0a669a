//! What a scene is, in integers ([`PhysicsSpec`]), and the same in the scalar the
//! world runs in ([`Params`]): the one place a scene's numbers are checked.

use super::{Effects, LayoutError, Scalar, TileLayout, MAX_MG, T_LOG2};

/// How [`World::step`] crosses its interval `dt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stepping {
    /// Discrete steps: the closed form over `dt`, then the contact passes at its end
    /// (time of impact solved inside the step); no tunnelling by the step bound, so
    /// the speed is capped at `min(r/4 per step, 64 pitch/s)` per axis.
    #[default]
    Fixed,
    /// Events: each marble flies the closed form to its next event — the end of the
    /// step, the instant it touches a tile, the lid or another marble, loses a
    /// face's support or stops under rolling resistance — as many as the physics
    /// has, in time order (see [`events`]). No speed cap but the number format's.
    /// `dt` is then the frame (2^7 ..= 2^10 steps/s).
    Events,
}

/// The physical description of a scene, in integers (independent of the scalar).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PhysicsSpec {
    /// Short tile width `s` (µm).
    pub short_um: u32,
    /// Long tile width `l` (µm).
    pub long_um: u32,
    /// Marble radius (µm).
    pub radius_um: u32,
    /// Coefficient of restitution `e` ×1000.
    pub restitution_milli: u32,
    /// Rolling-resistance coefficient ×10⁶ (used with the `friction` effect).
    pub rolling_resistance_ppm: u32,
    /// Restitution threshold: impacts slower than this (µm/s) are contacts.
    pub rest_threshold_um_s: u32,
    /// `log2` of the step rate: `dt = 2^-step_log2` s.
    pub step_log2: u32,
    /// The effects the scene needs.
    pub effects: Effects,
    /// Fixed steps or events.
    pub stepping: Stepping,
}

impl PhysicsSpec {
    /// The defaults: 2 mm walls, 10 mm cells, a 7 mm marble, `e = 0.5`, 1 % rolling
    /// resistance, 20 mm/s restitution threshold, 1024 steps/s, rolling on.
    pub const DEFAULT: PhysicsSpec = PhysicsSpec {
        short_um: 2_000,
        long_um: 10_000,
        radius_um: 3_500,
        restitution_milli: 500,
        rolling_resistance_ppm: 10_000,
        rest_threshold_um_s: 20_000,
        step_log2: 10,
        effects: Effects {
            rolling: true,
            friction: false,
            board_motion: false,
            holes: false,
            marbles: false,
        },
        stepping: Stepping::Fixed,
    };
}

impl Default for PhysicsSpec {
    fn default() -> Self {
        PhysicsSpec::DEFAULT
    }
}

/// Why a scene could not be set up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SetupError {
    /// The tile widths are unusable.
    Layout(LayoutError),
    /// The marble does not fit in a cell (`2r ≥ l`) or has zero radius.
    MarbleSize,
    /// `e` over 1, or the step rate outside 2^6 ..= 2^14 steps/s (events: 2^7 ..=
    /// 2^10).
    Parameter,
    /// More marbles than the world has room for, or none.
    MarbleCount,
    /// Marble number `.0` starts inside a tile or outside the board.
    BadStart(usize),
}

/// The spec turned into scalars.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params<S> {
    /// The tile layout.
    pub layout: TileLayout<S>,
    /// Marble radius (pitch).
    pub radius: S,
    /// Coefficient of restitution.
    pub restitution: S,
    /// Restitution threshold (pitch/T, the contact solver's unit).
    pub threshold: S,
    /// Per-axis speed cap (pitch/s): the step bound in fixed steps, the number
    /// format's range (128 pitch/s) with events.
    pub v_max: S,
    /// The largest pull per axis (milli-g): [`MAX_MG`], or with events less when a
    /// step's `a·dt` would not fit the number format (a pitch under 9.8 mm at 2^7
    /// steps/s).
    pub mg_max: i32,
    /// `dt = 2^-k` s.
    pub k: u32,
    /// Where the integers came from.
    pub spec: PhysicsSpec,
}

impl<S: Scalar> Params<S> {
    /// Validates a spec and converts it.
    pub fn new(spec: PhysicsSpec) -> Result<Self, SetupError> {
        let layout =
            TileLayout::<S>::from_um(spec.short_um, spec.long_um).map_err(SetupError::Layout)?;
        if spec.radius_um == 0 || 2 * spec.radius_um as u64 >= spec.long_um as u64 {
            return Err(SetupError::MarbleSize);
        }
        let events = spec.stepping == Stepping::Events;
        let rates = if events { 7..=10 } else { 6..=14 };
        if spec.restitution_milli > 1000 || !rates.contains(&spec.step_log2) {
            return Err(SetupError::Parameter);
        }
        let k = spec.step_log2;
        let radius = layout.from_um_len(spec.radius_um as i64);
        let threshold = S::ratio(
            spec.rest_threshold_um_s as i64,
            (layout.pitch_um as i64) << T_LOG2,
        );
        let (v_max, mg_max) = if events {
            // The format's range: 128 pitch/s (saturating at I8F24's largest value),
            // and a pull whose a·dt stays within it: mg ≤ 127 pitch/s · 2^k / (g per
            // mg in pitch/s²) = 127·2^k·pitch_um / 9806.65.
            let fits = (127i64 << k) * layout.pitch_um as i64 * 100 / 980_665;
            (S::from_int(128), fits.min(MAX_MG as i64) as i32)
        } else {
            let cap = S::from_int(64);
            (radius.shr(2).shl(k).min(cap), MAX_MG)
        };
        Ok(Params {
            layout,
            radius,
            restitution: S::ratio(spec.restitution_milli as i64, 1000),
            threshold,
            v_max,
            mg_max,
            k,
            spec,
        })
    }

    /// The step `dt` in seconds.
    pub fn dt(&self) -> f64 {
        1.0 / (1u64 << self.k) as f64
    }

    /// Whether the world steps by events.
    pub fn events(&self) -> bool {
        self.spec.stepping == Stepping::Events
    }
}
