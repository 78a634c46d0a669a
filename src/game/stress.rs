//! Stress scenes: the hard cases of a frame's cost, played with a scripted tilt.
//!
//! The built-in levels, played by the autopilot, are what a player meets; these
//! are what the event stepper's worst frame must also survive, each chosen for
//! the work it makes a frame do: many bounces (a marble rattling in a corner at
//! `e = 1`), many pairs (four marbles shaken in a box), a marble landing on
//! another (a drop through a hole onto a marble resting below it) and a long free
//! fall through two holes to the bottom of three storeys. The QEMU demo's
//! profile (`cargo qemu -- --demo`) and the micro:bit v1's (`cargo microbit-v1
//! -- --demo --profile`) count every frame's instructions on them as on the
//! levels (`app::profile_scenes`); `cargo xtask check-demo` holds both to the
//! same bound, `cargo xtask check-microbit-v1` too but for four-shaken, which it
//! reports against it;
//! `tests/stress.rs` checks on the host that each scene does what it is named
//! for. Beside them every board's profile (`app::profile_scenes`) plays
//! [`HARD_MAZES`], generated mazes at the top difficulty.

use super::endless::MazeArgs;
use super::level::LevelView;
use crate::input::axes::AccelMg;

/// A scene: a level and the reading for each of its frames.
#[derive(Clone, Copy, Debug)]
pub struct StressScene {
    /// The maze and its marbles.
    pub level: LevelView<'static>,
    /// Frames to play (128 a second).
    pub frames: u32,
    /// The reading at frame `n`.
    pub tilt: fn(u32) -> AccelMg,
}

/// Hard towards −x' and −z' (a reading's +x rolls the marble to −x'), a slight
/// shake every quarter second: the marble keeps bouncing between the corner's two
/// walls (nothing damps it at `e = 1`).
fn into_the_corner(frame: u32) -> AccelMg {
    let shake = if frame % 32 < 16 { 0 } else { 150 };
    AccelMg::new(600 - shake, 500, 600 + shake)
}

/// A new diagonal every eighth of a second, hard.
fn shaken(frame: u32) -> AccelMg {
    match (frame / 16) % 4 {
        0 => AccelMg::new(700, 400, 700),
        1 => AccelMg::new(-700, 400, 700),
        2 => AccelMg::new(-700, 400, -700),
        _ => AccelMg::new(700, 400, -700),
    }
}

/// Towards +x': into the hole, and the marble below against its wall.
fn towards_plus_x(_: u32) -> AccelMg {
    AccelMg::new(-300, 950, 0)
}

/// Every stress scene. Each goal lies where the scene's tilt never takes a
/// marble (a won attempt stops stepping).
pub static STRESS: [StressScene; 4] = [
    StressScene {
        level: crate::builtin_level!(
            "name: rattle-corner
restitution: 1
---
#####
#S..#
#...#
#..G#
#####
"
        ),
        frames: 512,
        tilt: into_the_corner,
    },
    StressScene {
        level: crate::builtin_level!(
            "name: four-shaken
restitution: 0.9
effects: rolling, friction
---
#########
#S.S.#.G#
#....#..#
#S.S.#..#
#########
"
        ),
        frames: 512,
        tilt: shaken,
    },
    StressScene {
        level: crate::builtin_level!(
            "name: drop-onto-marble
restitution: 0.5
effects: rolling, friction
---
#######
#S.O###
#######
===
#######
#G.S###
#######
"
        ),
        frames: 384,
        tilt: towards_plus_x,
    },
    StressScene {
        level: crate::builtin_level!(
            "name: long-fall
effects: rolling, friction
---
#######
#S.O###
#######
===
#######
#..O###
#######
===
#######
#G....#
#######
"
        ),
        frames: 384,
        tilt: towards_plus_x,
    },
];

/// The generated mazes profiled beside the stress scenes: 7 × 7 cells on two
/// storeys at the top difficulty (two or three marbles), as the endless run
/// reaches them; seeds 1 to 3. The autopilot plays each.
pub const HARD_MAZES: [MazeArgs; 3] = [hard_maze(1), hard_maze(2), hard_maze(3)];

/// One of [`HARD_MAZES`].
const fn hard_maze(seed: u32) -> MazeArgs {
    MazeArgs {
        seed,
        size: 7,
        storeys: 2,
        difficulty: 9,
    }
}
