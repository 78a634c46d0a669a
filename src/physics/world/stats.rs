//! What the steps did: counters per effect and the bounces a game may show. The
//! physics only adds to them; nothing in it reads them back.

use super::Scalar;

/// Counters of what the step did. Each effect's counter moves only when that
/// effect's code runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepStats {
    /// Steps taken.
    pub steps: u32,
    /// Marble–tile contacts resolved.
    pub contacts: u32,
    /// Of those, bounces (eq. 1 with `e`).
    pub collisions: u32,
    /// Steps undone because the end state overlapped a tile (should stay 0).
    pub reverts: u32,
    /// Marble-steps that ran the rolling-resistance code.
    pub friction_runs: u32,
    /// Marble-steps that ran the board-motion code.
    pub board_motion_runs: u32,
    /// Marble-steps that ran the 3-D (holes) code.
    pub space_runs: u32,
    /// Steps that ran the marble–marble code.
    pub pair_runs: u32,
    /// Events stepping: events handled (impacts, contacts, a face's support
    /// ending, stops, re-checks; not the step's end).
    pub events: u32,
    /// Events stepping: discrete slices flown instead of a closed form (a marble
    /// rolling around an edge, pressed against another marble, or starting inside
    /// a tile), see [`events`](super::events).
    pub slices: u32,
    /// Events stepping: marble-steps that ran out of events ([`events::MAX_EVENTS`](super::events::MAX_EVENTS))
    /// and finished in slices. Physics does not get there: 0 in every test.
    pub event_limits: u32,
    /// Events stepping: flights flown (each search for a marble's next event,
    /// and each marble's slice of a pair slice).
    pub flights: u32,
    /// Events stepping: searches a marble's free region answered without
    /// looking at a tile (`events/free.rs`).
    pub free_served: u32,
    /// Events stepping: the flight budget's units spent, each piece of work
    /// weighed by its cost (see [`events::FLIGHT_BUDGET`](super::events::FLIGHT_BUDGET)).
    pub work: u32,
    /// Events stepping: marble-steps whose rest was left unflown because the
    /// step's flight budget ran out (see [`events`](super::events)). 0 on every built-in level.
    pub budget_cuts: u32,
}

/// How many bounces between two [`World::take_impacts`](super::World::take_impacts) keep their speed.
pub const IMPACTS_KEPT: usize = 4;

/// The bounces against tiles and between marbles (eq. 1 with `e`, not the slow
/// impacts that become contacts) since the last [`World::take_impacts`](super::World::take_impacts), for
/// what a game plays or shows of them: a click per bounce, louder the harder it
/// hits. A bounce between two marbles counts once, at their closing speed.
///
/// Kept like [`StepStats`]: each bounce adds a count and, for the first
/// [`IMPACTS_KEPT`], its speed. No other code runs for it, whether anybody takes
/// them or not; the physics never reads them.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Impacts<S> {
    /// Bounces, all of them (saturating).
    pub count: u16,
    /// The normal speed at impact (pitch/s) of the first [`IMPACTS_KEPT`], in the
    /// order they happened.
    speeds: [S; IMPACTS_KEPT],
}

impl<S: Scalar> Impacts<S> {
    pub(super) fn record(&mut self, speed: S) {
        if let Some(slot) = self.speeds.get_mut(self.count as usize) {
            *slot = speed;
        }
        self.count = self.count.saturating_add(1);
    }

    /// The speeds kept (pitch/s), in order.
    pub fn speeds(&self) -> &[S] {
        &self.speeds[..(self.count as usize).min(IMPACTS_KEPT)]
    }
}
