//! A marble's way through an event step: the state the stepper keeps for it
//! ([`Flight`]) between one event and the next, the slice under way, and the
//! events that end a flight. Apart from the step (`events.rs`) so that the step
//! reads as the order of the work and this as what the work carries.

use super::super::super::dynamics::integrate::Kick;
use super::{Contact, Marble, Scalar, Segment, TileIndex, Vec3};

/// What ends a flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Event<S> {
    /// The flight's interval ends (the step's, or an effect's interval).
    End,
    /// A slice ends: the fixed step's contact passes push the marble out.
    SliceEnd,
    /// Touching tile `.1` (or the lid, [`LID`]).
    Touch(Contact<S>, TileIndex),
    /// Inside tile `.0` (it started there, or another marble pushed it there).
    Inside(TileIndex),
    /// Held face `bit` runs out of tile under the contact point.
    Release(u8),
    /// Rolling resistance brings the speed along its direction to zero.
    Stop,
    /// A search stopped short of a contact: search again from here.
    Later,
}

/// The lid, where a tile index is asked for.
pub(super) const LID: TileIndex = TileIndex::new(i32::MIN, 0, 0);
/// No tile: a blind slice (every tile left to the passes at its end).
pub(super) const EVERY: TileIndex = TileIndex::new(i32::MAX, 0, 0);

/// A slice under way (see the module doc).
#[derive(Clone, Copy, Debug)]
pub(super) struct Slice<S> {
    /// The tile its events leave out: the one the marble rolls around or is in.
    pub(super) skip: TileIndex,
    /// Where it started (the passes undo a step back to there, as fixed steps do).
    pub(super) start: Vec3<S>,
    /// When it started and ends (fractions of the step).
    pub(super) from: S,
    pub(super) to: S,
    /// A pivot slice (`pivot.rs`): `skip` is an edge the marble rolls around.
    pub(super) pivot: bool,
    /// A rail slice (`pivot.rs`): the marble rests on `skip` and another edge
    /// along the same axis; or a slice past edge `skip`, which the marble leaves
    /// (`pivot_len`). An event inside either makes the rest a plain slice.
    pub(super) rail: bool,
    /// A slice rolling on this still marble (`rest.rs`): the pull's part into
    /// it dropped, every tile searched (`skip` is [`EVERY`]: none left out).
    pub(super) on: Option<u8>,
}

/// How a slice asked for around a tile begins.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Around {
    /// A plain slice.
    Slice,
    /// A slow touch on an edge: a pivot slice if the edge holds the marble, else
    /// a plain slice.
    Touched,
    /// A pivot slice ended: another while the edge holds, else free flight.
    Rolling,
}

/// A flight's acceleration and how long it holds (`World::accel`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Accel<S> {
    /// The kick of a whole step, the held faces' normal parts dropped.
    pub(super) kick: Kick<S>,
    /// How long it holds (steps, at most the time left).
    pub(super) len: S,
    /// When rolling resistance stops the marble (steps), within `len`.
    pub(super) stop: Option<S>,
    /// Whether the pull alone cannot beat static friction.
    pub(super) holds: bool,
    /// Rolling resistance's direction, if it acts.
    pub(super) dir: Option<(S, S)>,
    /// The marble holds the faces its free region was built with, and its
    /// centre is inside it (`FreeRegion::under_held`, asked for a marble held
    /// on a face; a marble that holds none leaves it false).
    pub(super) backed: bool,
}

/// One marble's way through the step.
#[derive(Clone, Copy, Debug)]
pub(super) struct Flight<S> {
    /// How far into the step (steps, `0 ..= 1`).
    pub(super) t: S,
    /// The closed form from `t` on.
    pub(super) seg: Segment<S>,
    /// How long its acceleration holds (steps from `t`, at most `1 − t`).
    pub(super) len: S,
    /// When rolling resistance stops it (steps from `t`).
    pub(super) stop: Option<S>,
    /// Whether the pull alone cannot beat static friction.
    pub(super) holds: bool,
    /// Rolling resistance's direction (x', z').
    pub(super) dir: (S, S),
    /// Events so far in this step.
    pub(super) events: u32,
    /// Out of events at full restitution: impacts are inelastic.
    pub(super) inelastic: bool,
    /// A free region was built in this step (`free.rs`): one a step. A slow
    /// marble turning about in a maze's corridor left each region at its next
    /// flight, and its rebuilds were a quarter of the maze's worst frames.
    pub(super) built: bool,
    /// Events in a row with no time passing.
    pub(super) idle: u32,
    /// The next flight's acceleration is set already: the step's first, which
    /// the quiet frame (`quiet.rs`) prepared and could not finish.
    pub(super) prepared: bool,
    /// A slice asked for (around this tile), started at the next flight.
    pub(super) want: Option<TileIndex>,
    /// The edge a pivot slice rolled round when a second edge ended it: the
    /// slice asked for may be a rail slice on both (`pivot.rs`).
    pub(super) rail: Option<TileIndex>,
    /// How the slice asked for begins.
    pub(super) around: Around,
    /// A slice rolling on this still marble asked for (`rest.rs`).
    pub(super) roll: Option<u8>,
    /// The still marble it was last asked to roll on this step: a touch on it
    /// that neither rests nor rolls goes on as any pair's after that.
    pub(super) tried: Option<u8>,
    /// The still marble it rests on for the rest of the step (`rest.rs`): the
    /// pair is not tested again while that one stays still.
    pub(super) rest: Option<u8>,
    /// The slice under way.
    pub(super) slice: Option<Slice<S>>,
    /// Where `seg` puts the marble at the last search's limit (steps from `t`):
    /// a flight that ends there, as most do, takes it instead of the closed form
    /// again (`set_seg` and `fly` forget it).
    pub(super) end: Option<(S, Vec3<S>)>,
}

impl<S: Scalar> Flight<S> {
    /// A flight at the step's start, for the marbles flown together: `[START;
    /// M]` is one copy of an aligned block, where `[start(); M]` copied, for
    /// each marble, its options' undefined payload from a template at an odd
    /// offset (a misaligned `memcpy` of 66 bytes a marble).
    pub(super) const START: Self = Self::start();

    /// A flight at the step's start, every field set (what [`Flight::START`]
    /// holds). One marble's flight is [`Flight::begin`]: copied from `START` in
    /// flash it took 94 Cortex-M4 instructions more a step, and built in place
    /// by this, whose zeros the compiler merges into `memset` calls, 83 more.
    pub(super) const fn start() -> Self {
        Flight {
            t: S::ZERO,
            seg: Segment::still(Vec3::ZERO),
            len: S::ONE,
            stop: None,
            holds: false,
            dir: (S::ZERO, S::ZERO),
            events: 0,
            inelastic: false,
            built: false,
            idle: 0,
            prepared: false,
            want: None,
            rail: None,
            around: Around::Slice,
            roll: None,
            tried: None,
            rest: None,
            slice: None,
            end: None,
        }
    }

    /// One marble's flight at the step's start ([`Flight::start`]'s state),
    /// built by stores of only what is read before it is written. `prepare`
    /// sets the closed form, its interval, rolling resistance's stop, hold and
    /// direction and forgets the search's end before any of them is read; they
    /// get an opaque zero here, a value the compiler cannot see is zero and so
    /// stores as it is, where the constant zeros of `start` were merged with the
    /// rest into two `memset` calls (83 Cortex-M4 instructions a step).
    #[inline(always)]
    pub(super) fn begin() -> Self {
        let z = core::hint::black_box(S::ZERO);
        let v = Vec3::new(z, z, z);
        Flight {
            t: S::ZERO,
            seg: Segment {
                p: v,
                v,
                u: v,
                dv: v,
                h: v,
            },
            len: z,
            stop: None,
            holds: false,
            dir: (z, z),
            events: 0,
            inelastic: false,
            built: false,
            idle: 0,
            prepared: false,
            want: None,
            rail: None,
            around: Around::Slice,
            roll: None,
            tried: None,
            rest: None,
            slice: None,
            end: None,
        }
    }

    /// The flight of marble `m` from `t` on under `a` (`World::accel`; a step of
    /// `2^-k` s). Rolling resistance's direction is kept when `a` has none.
    #[inline]
    pub(super) fn set_accel(&mut self, m: &Marble<S>, a: &Accel<S>, k: u32) {
        self.stop = a.stop;
        self.holds = a.holds;
        if let Some(dir) = a.dir {
            self.dir = dir;
        }
        self.set_seg(Segment::new(m.pos, m.vel, a.kick.dv, a.kick.dp, k));
        self.len = a.len;
    }

    /// A new closed form from `t` on.
    #[inline]
    pub(super) fn set_seg(&mut self, seg: Segment<S>) {
        self.seg = seg;
        self.end = None;
    }

    /// The step's time after `s` more steps (exactly 1 at the end).
    #[inline]
    pub(super) fn after(&self, s: S) -> S {
        if s == S::ONE - self.t {
            S::ONE
        } else {
            self.t + s
        }
    }
}
