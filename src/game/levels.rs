//! The built-in levels, parsed at compile time into flash. Rising difficulty; together
//! they use every effect (rolling everywhere; friction from 3; holes in 4, 7, 8;
//! several marbles in 5 and 8; board motion in 6 and 8) and storeys (2 in 9, 3 in
//! 10: listed top to bottom, a hole drops the marble one storey).

use super::level::LevelView;

macro_rules! builtin {
    ($src:expr) => {
        $crate::builtin_level!($src)
    };
}

/// Every built-in level, in playing order.
pub static LEVELS: [LevelView<'static>; if cfg!(feature = "storeys") { 10 } else { 8 }] = [
    builtin!(
        "name: first-roll
time_limit_s: 30
---
#########
#S.....G#
#########
"
    ),
    builtin!(
        "name: corner
time_limit_s: 30
---
#########
#S......#
#######.#
#G......#
#########
"
    ),
    builtin!(
        "name: switchback
effects: rolling, friction
time_limit_s: 60
---
#############
#S..........#
###########.#
#...........#
#.###########
#..........G#
#############
"
    ),
    builtin!(
        "name: stepping-stones
effects: rolling, friction
restitution: 0.4
time_limit_s: 60
---
#############
#S....O.....#
#.###.#.###.#
#.#O..#..O#.#
#.###.#.#####
#.....#....G#
#############
"
    ),
    builtin!(
        "name: two-marbles
effects: rolling, friction
time_limit_s: 60
---
###########
#S.......G#
#.#######.#
#S........#
###########
"
    ),
    builtin!(
        "name: rocking-board
effects: rolling, friction, board_motion
time_limit_s: 90
---
###############
#S............#
#.###########.#
#.#.........#.#
#.#.#######.#.#
#...#G......#.#
#####.#######.#
#.............#
###############
"
    ),
    builtin!(
        "name: cavern
effects: rolling, friction
restitution: 0.3
time_limit_s: 120
---
#################
#S....O.........#
#.###.#.#######.#
#.#O....O.....#.#
#.#.#########.#.#
#...#O......#.#.#
###.#.#####.#.#.#
#O..#...O.#...#G#
#################
"
    ),
    builtin!(
        "name: grand-tour
short_mm: 2
long_mm: 10
marble_radius_mm: 3.5
restitution: 0.5
effects: rolling, friction, board_motion
rolling_resistance: 0.015
time_limit_s: 180
---
###################
#S................#
#.###O#########.#.#
#...#...O.....#.#.#
###.#.#######.#.#.#
#O..#.#G....#...#.#
#.###.#####.#####.#
#S....O...........#
###################
"
    ),
    #[cfg(feature = "storeys")]
    builtin!(
        "name: two-floors
effects: rolling, friction
time_limit_s: 60
---
###########
#S........#
#########.#
#########O#
###########
===
###########
###########
###########
#G........#
###########
"
    ),
    #[cfg(feature = "storeys")]
    builtin!(
        "name: three-floors
effects: rolling, friction
time_limit_s: 90
---
###########
#S.......O#
###########
###########
###########
===
###########
#########.#
#########.#
#O........#
###########
===
###########
#........G#
#.#########
#.#########
###########
"
    ),
];

/// A built-in level by name.
pub fn by_name(name: &str) -> Option<(usize, LevelView<'static>)> {
    LEVELS
        .iter()
        .copied()
        .enumerate()
        .find(|(_, l)| l.info.name == name)
}
