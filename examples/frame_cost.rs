//! Each frame's work in a scene as the boards play it, for measuring a frame's
//! cost on the host (docs/performance.md, issue 40).
//!
//! `cargo run --release --features tools --example frame_cost -- four-shaken`
//! prints one CSV row a frame: the flight budget's units spent
//! (`StepStats::work`), the flights, events and slices, the marble-steps cut.
//! The scene is a stress scene (`game::stress::STRESS`), a top-difficulty maze
//! (`hard-0` … `hard-2`, `game::stress::HARD_MAZES`, played by the autopilot)
//! or a built-in level (played by the autopilot). `--flight-budget N` plays
//! it with another budget. `--frame N` plays frame N alone through
//! `measured_frame`, so that callgrind counts that frame only:
//!
//! ```text
//! valgrind --tool=callgrind --toggle-collect='*measured_frame*' \
//!     target/release/examples/frame_cost four-shaken --frame 180
//! ```
//!
//! (with no `--frame`, every frame goes through it: the whole scene).

use clap::Parser;
use marble_rolling::board::game_sizes::MAZE_REACH;
use marble_rolling::game::endless::MazeSlot;
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::game::stress::{HARD_MAZES, STRESS};
use marble_rolling::input::axes::AccelMg;
use marble_rolling::physics::Fx;
use support::{set_flight_budget, stats, HostPlayer};

mod support;

#[derive(Parser)]
#[command(about = "Each frame's work in a scene, one CSV row a frame")]
struct Args {
    /// A stress scene, hard-0 … hard-2 (a top-difficulty maze) or a built-in level.
    scene: String,
    /// Play with this flight budget (units) instead of the default.
    #[arg(long, value_name = "N")]
    flight_budget: Option<u32>,
    /// Play only frame N through `measured_frame` (the others through a twin).
    #[arg(long, value_name = "N")]
    frame: Option<u32>,
}

/// The frame callgrind counts (`--toggle-collect='*measured_frame*'`).
#[inline(never)]
fn measured_frame(s: &mut Session<'_, Fx>, reading: AccelMg) -> Phase {
    s.frame(reading)
}

/// The frames it does not count. Not the same body, so that the linker does
/// not fold the two into one symbol.
#[inline(never)]
fn other_frame(s: &mut Session<'_, Fx>, reading: AccelMg) -> Phase {
    std::hint::black_box(());
    let phase = s.frame(reading);
    std::hint::black_box(phase)
}

fn main() {
    let args = Args::parse();
    let mut slot: MazeSlot<{ MAZE_REACH.words() }, { MAZE_REACH.text_bytes() }> =
        MazeSlot::new(MAZE_REACH);
    let scripted = STRESS.iter().find(|s| s.level.info.name == args.scene);
    let (level, frames, script) = if let Some(s) = scripted {
        (s.level, s.frames, Some(s.tilt))
    } else if let Some(k) = args.scene.strip_prefix("hard-") {
        let maze = k
            .parse::<usize>()
            .ok()
            .and_then(|k| HARD_MAZES.get(k))
            .unwrap_or_else(|| fail(&format!("no maze {}", args.scene)));
        let level = slot
            .make(*maze)
            .unwrap_or_else(|e| fail(&format!("{}: {e:?}", args.scene)));
        (level, 1024, None)
    } else {
        let level = LEVELS
            .iter()
            .find(|l| l.info.name == args.scene)
            .unwrap_or_else(|| fail(&format!("no scene or level {}", args.scene)));
        (*level, 1024, None)
    };
    let mut made = HostPlayer::single(level, SYNTHETIC_TILT, script.is_none());
    let Ok(player) = &mut made else {
        fail(&format!("{} does not set up", args.scene));
    };
    set_flight_budget(player, args.flight_budget);
    println!("frame,work,flights,events,slices,cuts");
    for n in 0..frames {
        let reading = match script {
            Some(tilt) => tilt(n),
            None => player.reading(AccelMg::LEVEL),
        };
        let before = stats(player);
        let session = player.session_mut();
        let phase = if args.frame.is_none_or(|f| f == n) {
            measured_frame(session, reading)
        } else {
            other_frame(session, reading)
        };
        let after = stats(player);
        println!(
            "{n},{},{},{},{},{}",
            after.work - before.work,
            after.flights - before.flights,
            after.events - before.events,
            after.slices - before.slices,
            after.budget_cuts - before.budget_cuts
        );
        if script.is_none() && phase != Phase::Playing {
            break;
        }
    }
}

fn fail(why: &str) -> ! {
    eprintln!("frame_cost: {why}");
    std::process::exit(2)
}
