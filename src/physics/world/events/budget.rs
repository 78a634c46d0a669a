//! The step's flight budget: a hard cap on a frame's work.
//!
//! The events of a step are as many as the physics asks for, and some scenes ask
//! for many: a marble pressed on another flies plain pair slices, 32 or more a
//! step; four marbles shaken in a box re-check every pair at every flight. A step
//! may spend [`FLIGHT_BUDGET`] units of work, weighed by what each piece of work
//! costs (one unit is about 300 host instructions, 650 to 730 on the Cortex-M0;
//! `docs/performance.md` has the measurements): a search's fixed part, each
//! tile's time of impact in it, a slice's contact passes, every pair's test
//! (those its quick bounds reject too: four shaken marbles test 20 to 30 pairs
//! a frame), and its time of impact past those bounds, a pair slice. A free
//! region's building is not counted: it is a cache, and a step cuts at the same
//! place with or without it (`tests/free_region.rs`). Once they are spent, the
//! rest of the step is **carried over**: every marble still under way stays
//! where its last flight left it, with that flight's velocity, and goes on from
//! there in the next step, as if the clock had paused for it; only a marble
//! whose own plan runs to the step's end with no event, out of every other
//! marble's reach over the step by the pair tests' bound without a product,
//! finishes it (a marble rolling freely is not slowed with a pair pressed
//! together elsewhere on the board: `together.rs`, `cut_together`). Marbles
//! that may touch: from a step's second round a search, a pair's test with its
//! time of impact, and a pair slice with its marbles' searches is begun only
//! when what is left of the budget covers it (the first round, a search per
//! marble and a test per pair, is never cut, so that every marble's step gets
//! somewhere); so a step spends at most the larger of its first round and the
//! budget, past it only the tiles its last search tested and a slice's passes.
//! A marble on its own (`fly_each`) begins a flight while any of its share is
//! left, its first always: past the budget by at most a search and its tiles.
//! Whatever the scene, the scene that asks for more plays slower than real
//! time while it does.
//!
//! The budget is the slowest board's: the micro:bit v1 has 60 000 Cortex-M0
//! instructions for a frame's physics (issue 40), and four marbles shaken hard
//! spend about 730 a unit in their worst frames, so 80 units (four-shaken's
//! worst frame is then 58 844, `cargo xtask check-microbit-v1`). Where a unit
//! was begun whenever any budget was left, a pair slice begun on the last unit
//! overshot by 40 more, and the budget of 128 let four-shaken reach 101 719.
//!
//! What the cut keeps:
//! - **No penetration**: the marbles are left in a state the event stepper
//!   reached, between events; nothing is flown blind. A marble cut inside a slice
//!   gets the slice's contact passes there, as at the slice's end (a slice may
//!   sink it `2^-12·r` into the tile it leaves to them). A pair slice can leave
//!   two marbles ahead of the rest, which the pair tests took at the later time;
//!   when the cut leaves others short of it, every pair gets the fixed step's
//!   pair code twice (pushed apart where they overlap, eq. 1, the tile passes):
//!   four shaken marbles were otherwise left 2.1·10⁻³ pitch into each other.
//! - **No energy gained**: the state is kept as it is.
//! - **Determinism**: the budget counts work, the same on every target.
//! - **Sleep only when earned**: a marble whose partial step, of positive length,
//!   left it exactly as it was is at rest; one that has not flown at all this
//!   step stays awake. (A marble wedged at rest against another marble has its
//!   velocity zeroed, `together.rs`, so that the exact test can find it still.)
//!
//! Two fallbacks that fly the rest were measured and not kept: fixed pieces of an
//! eighth of the step, blind, each with the contact passes, sink a marble under a
//! 4 g pull up to `h·(1/8)²` before the passes push it out (the tight-corridor
//! hard case fails); and without the wedged rest a landed pair never sleeps (its
//! state at a cut never repeats). `docs/performance.md` has the figures.
//!
//! `StepStats::budget_cuts` counts the marble-steps it cut, `StepStats::work` the
//! units spent; no built-in level reaches the budget (at most 73 units in a
//! frame, `grand-tour`; the top-difficulty mazes 79: `tests/budget.rs`), the
//! stress scene of four marbles shaken does, and a landing on a marble does in
//! two frames as the top marble rolls off the hole's rim (in 44 before the
//! marble below was struck, rolled and rested on: `rest.rs`); so does a board
//! spun at the clamp of 16 rad/s, whose motion is held over 1/64 rad a flight.

use super::{Flight, Scalar, World};

/// Units of work a step may spend, all marbles together, unless
/// [`World::set_flight_budget`] sets another budget (see the module doc).
pub const FLIGHT_BUDGET: u32 = 80;

/// A search for a marble's next event, its fixed part (the swept box, the held
/// faces' supports, the flight's acceleration).
pub(super) const SEARCH: u32 = 8;

/// A tile's time of impact in a search.
pub(super) const TILE: u32 = 3;

/// A slice's end: the contact passes (180 to 710 host instructions in a
/// least-squares fit of every frame's count to its kinds of work).
pub(super) const SLICE_END: u32 = 2;

/// A pair's test, whatever ends it (a test its quick bounds end costs about
/// 230 host instructions: four-shaken, callgrind).
pub(super) const PAIR_TEST: u32 = 1;

/// A pair's time of impact past its quick bounds (`toi_box` about a point:
/// about 780 host instructions more).
pub(super) const PAIR_TOI: u32 = 3;

/// A pair slice: both marbles flown, their passes and the pair's push (each
/// marble's search for its first tile event is charged as a search).
pub(super) const PAIR_SLICE: u32 = 16;

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Sets the units of work a step may spend, all marbles together (at least 1;
    /// [`FLIGHT_BUDGET`] by default).
    pub fn set_flight_budget(&mut self, flights: u32) {
        self.flight_budget = flights.max(1);
    }

    /// The units of work a step may spend (see [`World::set_flight_budget`]).
    pub fn flight_budget(&self) -> u32 {
        self.flight_budget
    }

    /// Whether the step's budget is spent.
    #[inline]
    pub(super) fn out_of_flights(&self) -> bool {
        self.flights_left == 0
    }

    /// Whether what is left of the step's budget covers a piece of work of
    /// `units`: a piece it does not cover is not begun.
    #[inline]
    pub(super) fn affords(&self, units: u32) -> bool {
        self.flights_left >= units
    }

    /// Counts `flights` flights worth `units` of the step's budget.
    #[inline]
    pub(super) fn spend(&mut self, flights: u32, units: u32) {
        self.stats.flights = self.stats.flights.wrapping_add(flights);
        self.charge(units);
    }

    /// Counts `units` of work that are not a flight.
    #[inline]
    pub(super) fn charge(&mut self, units: u32) {
        self.stats.work = self.stats.work.wrapping_add(units);
        self.flights_left = self.flights_left.saturating_sub(units);
    }

    /// A marble's step cut at `f.t`: counted; whether it may still fall asleep
    /// (it flew a positive part of the step).
    #[inline]
    pub(super) fn cut(&mut self, f: &Flight<S>) -> bool {
        self.stats.budget_cuts = self.stats.budget_cuts.wrapping_add(1);
        f.t > S::ZERO
    }
}
