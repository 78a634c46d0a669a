//! How often the flight budget cuts a frame of the generated mazes a player
//! meets (docs/performance.md, issue 40): every maze of four shapes
//! (7×7×2 at difficulty 9, 5×5×3 at 6, 6×6×1 at 9, 4×4×2 at 4) for the seeds
//! asked, each played by the autopilot as the boards play it, up to
//! `--frames` frames or until it ends.
//!
//! `cargo run --release --features tools --example maze_cuts` prints, for
//! each maze with a cut, its name and cut frames, then the totals: frames
//! played, frames with a cut, marble-steps cut, and the most units of work a
//! frame spent. `--flight-budget N` plays with another budget.

use clap::Parser;
use marble_rolling::board::game_sizes::MAZE_REACH;
use marble_rolling::game::endless::{MazeArgs, MazeSlot};
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::SYNTHETIC_TILT;
use marble_rolling::input::axes::AccelMg;
use support::{set_flight_budget, stats, HostPlayer};

mod support;

/// Cells along a side, storeys, difficulty.
const SHAPES: [(u8, u8, u8); 4] = [(7, 2, 9), (5, 3, 6), (6, 1, 9), (4, 2, 4)];

#[derive(Parser)]
#[command(about = "Frames the flight budget cuts in generated mazes")]
struct Args {
    /// Seeds 1 ..= N of each shape.
    #[arg(long, default_value_t = 200)]
    seeds: u32,
    /// Frames to play a maze at most.
    #[arg(long, default_value_t = 1500)]
    frames: u32,
    /// Play with this flight budget (units) instead of the default.
    #[arg(long, value_name = "N")]
    flight_budget: Option<u32>,
}

/// What one maze's play came to.
#[derive(Default)]
struct Tally {
    frames: u64,
    cut_frames: u64,
    cuts: u64,
    worst_units: u32,
}

fn main() {
    let args = Args::parse();
    let (mut all, mut mazes, mut cut_mazes) = (Tally::default(), 0u32, 0u32);
    for (size, storeys, difficulty) in SHAPES {
        for seed in 1..=args.seeds {
            let maze = MazeArgs {
                seed,
                size,
                storeys,
                difficulty,
            };
            let Some(t) = play(maze, &args) else {
                eprintln!("maze_cuts: {maze} does not set up");
                continue;
            };
            mazes += 1;
            if t.cut_frames > 0 {
                cut_mazes += 1;
                println!(
                    "{maze}: {} frames cut, {} marble-steps",
                    t.cut_frames, t.cuts
                );
            }
            all.frames += t.frames;
            all.cut_frames += t.cut_frames;
            all.cuts += t.cuts;
            all.worst_units = all.worst_units.max(t.worst_units);
        }
    }
    println!(
        "{mazes} mazes, {} frames: {cut_mazes} mazes with a cut, {} frames cut ({:.3} %), \
         {} marble-steps cut, at most {} units of work in a frame",
        all.frames,
        all.cut_frames,
        100.0 * all.cut_frames as f64 / all.frames.max(1) as f64,
        all.cuts,
        all.worst_units
    );
}

/// Plays `maze` with the autopilot; `None` if it does not set up.
fn play(maze: MazeArgs, args: &Args) -> Option<Tally> {
    let mut slot: MazeSlot<{ MAZE_REACH.words() }, { MAZE_REACH.text_bytes() }> =
        MazeSlot::new(MAZE_REACH);
    let level = slot.make(maze).ok()?;
    let mut player = HostPlayer::single(level, SYNTHETIC_TILT, true).ok()?;
    set_flight_budget(&mut player, args.flight_budget);
    let mut t = Tally::default();
    for _ in 0..args.frames {
        let reading = player.reading(AccelMg::LEVEL);
        let before = stats(&player);
        let phase = player.session_mut().frame(reading);
        let after = stats(&player);
        t.frames += 1;
        t.worst_units = t.worst_units.max(after.work - before.work);
        let cuts = after.budget_cuts - before.budget_cuts;
        if cuts > 0 {
            t.cut_frames += 1;
            t.cuts += u64::from(cuts);
        }
        if phase != Phase::Playing {
            break;
        }
    }
    Some(t)
}
