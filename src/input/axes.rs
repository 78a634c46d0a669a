//! One accelerometer sample ([`AccelMg`]) and the board frame it is handed on
//! in: how a sensor is mounted ([`AxisMap`]) decides which of its axes feeds
//! each board axis.
//!
//! Samples handed to the game are in milli-g in the **board frame**: `x` to
//! the right, `y` up out of the display, `z` towards the player. The sensor
//! reports the reaction to gravity, so a board lying flat reads
//! `(0, +1000, 0)`, and tilting the right edge down (the marble rolls towards
//! `+x`) makes `x` negative.

/// One g in milli-g.
pub(crate) const ONE_G_MG: i32 = 1000;

/// One accelerometer reading in milli-g (1000 = 1 g), board frame: the one
/// tilt type from the board's sensor, the keys, a phone, the autopilot, a
/// trace or a ghost through the app's links, the player and the session into
/// the tilt filter ([`crate::input::tilt::TiltFilter::push`]), which turns it
/// into a [`crate::input::tilt::GravityMg`] for the physics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AccelMg {
    /// X component, milli-g.
    pub x: i32,
    /// Y component, milli-g.
    pub y: i32,
    /// Z component, milli-g.
    pub z: i32,
}

impl AccelMg {
    /// A sample from its three components.
    pub const fn new(x: i32, y: i32, z: i32) -> Self {
        Self { x, y, z }
    }

    /// What a board lying flat and still reads in the board frame.
    pub const LEVEL: Self = Self::new(0, 1000, 0);

    /// A 1 g reading with the given `x` and `z` components (clamped to
    /// ±1000 mg together) and `y = +sqrt(1000² - x² - z²)`: what keys and a
    /// phone's screen tilt hand the game, so they enter the tilt path as a
    /// sensor sample would.
    pub fn from_xz(x: i32, z: i32) -> Self {
        let x = x.clamp(-ONE_G_MG, ONE_G_MG);
        let z = z.clamp(-ONE_G_MG, ONE_G_MG);
        let horizontal = x * x + z * z;
        let y = ((ONE_G_MG * ONE_G_MG - horizontal).max(0) as u32).isqrt();
        Self::new(x, y as i32, z)
    }

    /// A reading from its `[x, y, z]` components: for a format's boundary
    /// (a trace's or a ghost's file, a virtual chip's registers), where the
    /// axes are read one by one.
    pub const fn from_array([x, y, z]: [i32; 3]) -> Self {
        Self::new(x, y, z)
    }

    /// Its `[x, y, z]` components, for a format's boundary or a per-axis loop.
    pub const fn to_array(self) -> [i32; 3] {
        [self.x, self.y, self.z]
    }

    /// Squared magnitude in mg², saturating (never overflows).
    pub const fn magnitude_sq(&self) -> u64 {
        let x = self.x.unsigned_abs() as u64;
        let y = self.y.unsigned_abs() as u64;
        let z = self.z.unsigned_abs() as u64;
        // Each term is at most 2^62, so the sum of three cannot overflow.
        x * x + y * y + z * z
    }
}

/// One of the sensor's three axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axis {
    /// Sensor X.
    X,
    /// Sensor Y.
    Y,
    /// Sensor Z.
    Z,
}

/// Where one board axis comes from: a sensor axis, possibly negated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisSource {
    /// The sensor axis read.
    pub axis: Axis,
    /// Whether its value is negated.
    pub negate: bool,
}

impl AxisSource {
    /// `+axis`.
    pub const fn pos(axis: Axis) -> Self {
        Self {
            axis,
            negate: false,
        }
    }

    /// `-axis`.
    pub(crate) const fn neg(axis: Axis) -> Self {
        Self { axis, negate: true }
    }

    const fn pick(&self, raw: AccelMg) -> i32 {
        let v = match self.axis {
            Axis::X => raw.x,
            Axis::Y => raw.y,
            Axis::Z => raw.z,
        };
        if self.negate {
            v.saturating_neg()
        } else {
            v
        }
    }
}

/// How a sensor is mounted: for each board axis (x, y, z), which sensor axis
/// and sign feed it. One table per board, easy to correct on the bench.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisMap {
    /// Source of board `x` (right).
    pub x: AxisSource,
    /// Source of board `y` (up, out of the display).
    pub y: AxisSource,
    /// Source of board `z` (towards the player).
    pub z: AxisSource,
}

impl AxisMap {
    /// The sensor frame already is the board frame.
    pub const IDENTITY: Self = Self {
        x: AxisSource::pos(Axis::X),
        y: AxisSource::pos(Axis::Y),
        z: AxisSource::pos(Axis::Z),
    };

    /// A sensor sample expressed in the board frame.
    pub const fn apply(&self, raw: AccelMg) -> AccelMg {
        AccelMg {
            x: self.x.pick(raw),
            y: self.y.pick(raw),
            z: self.z.pick(raw),
        }
    }

    /// Whether every sensor axis is used exactly once (a permutation with
    /// signs). A table failing this is a typo.
    pub const fn is_permutation(&self) -> bool {
        let a = self.x.axis as u8;
        let b = self.y.axis as u8;
        let c = self.z.axis as u8;
        a != b && b != c && a != c
    }
}

/// "This orientation is level": the offset subtracted from later samples.
///
/// Small-angle model: the horizontal components (`x`, `z`) of the reference
/// sample are subtracted, `y` is kept. Exact for the tilt directions and
/// accurate to a few percent for reference tilts up to ~15°, which is what a
/// player calibrating "roughly flat" produces. The offset is clamped to
/// ±[`Calibration::MAX_OFFSET_MG`] so that calibrating while holding the board
/// on its side cannot make the game unplayable.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration {
    /// Offset subtracted from `x`, mg.
    pub offset_x: i32,
    /// Offset subtracted from `z`, mg.
    pub offset_z: i32,
}

impl Calibration {
    /// Largest offset accepted (about 30° of tilt).
    pub const MAX_OFFSET_MG: i32 = 500;

    /// No correction.
    pub const NONE: Self = Self {
        offset_x: 0,
        offset_z: 0,
    };

    /// The calibration that makes `reference` (a board-frame sample) level.
    pub const fn from_reference(reference: AccelMg) -> Self {
        Self {
            offset_x: clamp_i32(reference.x, Self::MAX_OFFSET_MG),
            offset_z: clamp_i32(reference.z, Self::MAX_OFFSET_MG),
        }
    }

    /// `s` corrected (saturating).
    pub const fn apply(&self, s: AccelMg) -> AccelMg {
        AccelMg {
            x: s.x.saturating_sub(self.offset_x),
            y: s.y,
            z: s.z.saturating_sub(self.offset_z),
        }
    }
}

const fn clamp_i32(v: i32, limit: i32) -> i32 {
    if v > limit {
        limit
    } else if v < -limit {
        -limit
    } else {
        v
    }
}
