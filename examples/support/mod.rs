//! What the measuring examples (`frame_cost`, `maze_cuts`) share: the host's
//! player as the tests play the levels, and the world's counters they read.

use marble_rolling::physics::StepStats;
use marble_rolling::player::Player;

/// The host's player, as the tests play the levels.
pub type HostPlayer<'a> = Player<'a, 19, 9, true, true>;

/// Plays with `budget` units of work a step, if given, instead of the default.
pub fn set_flight_budget(player: &mut HostPlayer<'_>, budget: Option<u32>) {
    if let Some(budget) = budget {
        player
            .session_mut()
            .game_mut()
            .world_mut()
            .set_flight_budget(budget);
    }
}

/// The world's step counters.
pub fn stats(player: &HostPlayer<'_>) -> StepStats {
    player.session().game().world().stats
}
