//! The step's flight budget: a hard cap on a frame's work.
//!
//! The events of a step are as many as the physics asks for, and some scenes ask
//! for many: a marble pressed on another flies plain pair slices, 32 or more a
//! step; four marbles shaken in a box re-check every pair at every flight. A step
//! may spend [`FLIGHT_BUDGET`] units of work, weighed by what each piece of work
//! costs (one unit is about 300 host instructions, 650 on the Cortex-M0: the
//! weights below were fitted to callgrind's count of every frame of the levels,
//! the top-difficulty mazes and the stress scenes, `docs/performance.md`): a
//! search's fixed part, each tile's time of impact in it, a slice's contact
//! passes, every pair's time of impact (those its quick bound
//! rejects too: four shaken marbles test 20 to 30 pairs a frame, and only those
//! past the bound counted before), a pair slice. A free region's building is
//! not counted: it is a cache, and a step cuts at the same place with or without
//! it (`tests/free_region.rs`). Once they are spent, the rest
//! of the step is **carried over**: every marble still under way stays where its
//! last flight left it, with that flight's velocity, and goes on from there in
//! the next step, as if the clock had paused for it; only a marble whose own
//! plan runs to the step's end with no event, out of every other marble's reach
//! over the step by the pair tests' bound without a product, finishes it (a
//! marble rolling freely is not slowed with a pair pressed together elsewhere on
//! the board: `together.rs`, `cut_together`). The check is made before
//! each unit from a step's second round (the first, a search per marble and a
//! time of impact per pair, is never cut, so that every marble's step gets
//! somewhere), so a step spends at most the first round, or `FLIGHT_BUDGET − 1`
//! and the last unit (a search and the tiles it tested, or a pair slice and
//! its marbles' searches),
//! whatever the scene; the scene that asks for more plays slower than real time
//! while it does.
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
//! units spent; no built-in level reaches the budget (at most 86 units in a
//! frame, `grand-tour`; the top-difficulty mazes 103: `tests/budget.rs`), the
//! stress scene of four marbles shaken does (a landing on a marble did until the
//! marble below was struck, rolled and rested on: `rest.rs`).

use super::{Flight, Scalar, World};

/// Units of work a step may spend, all marbles together, unless
/// [`World::set_flight_budget`] sets another budget (see the module doc).
pub const FLIGHT_BUDGET: u32 = 16 * SEARCH;

/// A search for a marble's next event, its fixed part (the swept box, the held
/// faces' supports, the flight's acceleration).
pub(super) const SEARCH: u32 = 8;

/// A tile's time of impact in a search.
pub(super) const TILE: u32 = 3;

/// A slice's end: the contact passes.
pub(super) const SLICE_END: u32 = 5;

/// A pair's time of impact, whatever ends it.
pub(super) const PAIR_TEST: u32 = 2;

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
