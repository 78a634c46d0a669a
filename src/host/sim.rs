//! `cargo sim`: runs a level headless and reports how it ended.
//!
//! ```text
//! cargo sim -- --level corner --autopilot --json
//! cargo sim -- --level my.level --tilt-trace tilt.csv --trace steps.csv
//! cargo sim -- --level two-marbles --autopilot --stepping events --trace run.csv
//! cargo sim -- --level corner --autopilot --gif docs/corner.gif
//! cargo sim -- --check my.level
//! cargo sim -- --generate 7 --storeys 2 --print-level > maze.level
//! cargo sim -- --generate 7 --storeys 2 --autopilot
//! ```
//!
//! `--gif FILE` records the whole level as the matrix draws it (the followed
//! marble's storey), one LED per tile; a level with storeys gets every storey's
//! map beside it, top storey first ([`super::storey_maps`]).
//!
//! The run goes through [`Session`] exactly like the firmware and the terminal
//! player: one reading per frame (flat, from a tilt trace, or from the autopilot)
//! → tilt path → [`crate::game::rules::Game::frame`] (`substeps` physics steps,
//! then the judging). So the `state_hash` of a run is the firmware's for the same
//! inputs and backend. `--tilt-trace FILE` feeds recorded readings
//! (`super::tilt_trace`); `--trace FILE` writes the marbles' motion, sampled
//! between the game's frames ([`super::motion_trace`]); the outcome is a
//! [`Report`], a JSON line or a summary.
//!
//! # Exit status
//!
//! 0 for any outcome (`won`, `fell`, `timeout`); 2 for bad input (level, tilt
//! trace, backend, substeps, unwritable output) with a message on stderr; for
//! `--check`, 1 when the level is invalid (2 when the file cannot be read or is
//! not UTF-8). A message quotes at most 60 characters of the text it refuses
//! (`super::excerpt`).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::string::{String, ToString};
use std::time::Instant;
use std::vec::Vec;
use std::{eprintln, format, print, println};

use clap::Parser;

use super::gif_out::GifRecorder;
use super::motion_trace::{replay_frame, trace_header, FlightLog, FrameStart, ReplayError};
use super::report::{states, Report};
use super::tilt_trace::TiltTrace;
use super::{excerpt, load_level, Backend, WithScalar};
use crate::game::autopilot::Autopilot;
use crate::game::level::{LevelError, LevelView};
use crate::game::rules::{Game, GameConfig, Phase};
use crate::game::session::{Session, SYNTHETIC_TILT};
use crate::physics::{Scalar, SetupError, Stepping};

/// Seconds the last GIF image is held before the animation loops.
const GIF_HOLD_S: f64 = 1.5;

/// Command-line arguments of `cargo sim`.
#[derive(Parser, Debug)]
#[command(
    name = "sim",
    version,
    about = "Simulate a Marble Rolling level headless",
    after_help = "Exit status: 0 for any outcome (won, fell, timeout); 2 for bad input; \
                  --check: 1 for an invalid level, 2 for a file that is not UTF-8 text."
)]
pub struct Args {
    /// Level: a built-in name (first-roll, corner, ...) or a level file.
    #[arg(long, value_name = "FILE|NAME",
          required_unless_present_any = ["check", "list", "generate", "print_level"])]
    pub(crate) level: Option<String>,
    /// Tilt readings: CSV `t_s,ax_mg,ay_mg,az_mg` (board frame, flat = 0,1000,0;
    /// ax < 0 rolls towards +x'), each held until the next. Default: flat board.
    #[arg(long, value_name = "FILE", conflicts_with = "autopilot")]
    pub(crate) tilt_trace: Option<PathBuf>,
    /// Let the autopilot tilt the board.
    #[arg(long)]
    pub(crate) autopilot: bool,
    /// Stop after S seconds of simulated time (default: the level's time limit);
    /// a run stopped this way while still playing ends as `timeout`.
    #[arg(long, value_name = "S", value_parser = parse_seconds)]
    pub(crate) seconds: Option<f64>,
    /// Number type of the physics.
    #[arg(long, value_name = "NAME", default_value = "i8f24")]
    pub(crate) backend: String,
    /// Physics steps per frame: 1, 2, 4, 8 or 16 (the frame rate stays 128 Hz).
    /// Default: 8 with fixed steps, 1 (one step per frame) with events.
    #[arg(long, value_name = "N", value_parser = parse_substeps)]
    pub(crate) substeps: Option<u32>,
    /// How a step is crossed: `events` (each marble flies its closed form from
    /// event to event; what every board plays) or `fixed` (the closed form over
    /// the step, contacts at its end, speed capped; the study's baseline).
    #[arg(long, value_name = "MODE", default_value = "events", value_parser = parse_stepping)]
    pub(crate) stepping: Stepping,
    /// Write every marble's position (mm) and velocity (mm/s) to FILE as CSV: a
    /// row per 1/1024 s with events, a row per step with fixed steps.
    #[arg(long = "trace", value_name = "FILE")]
    pub(crate) motion_trace: Option<PathBuf>,
    /// Print one JSON line instead of the human summary.
    #[arg(long)]
    pub(crate) json: bool,
    /// Render the run to an animated GIF (a level with storeys: every storey's map
    /// beside the matrix, top storey first).
    #[arg(long, value_name = "FILE")]
    pub(crate) gif: Option<PathBuf>,
    /// GIF pixels per LED (tile).
    #[arg(long, value_name = "PX", default_value_t = 12, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub(crate) gif_scale: u32,
    /// A GIF image every N game frames (128 frames/s).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub(crate) gif_every: u32,
    /// Validate a level file: print `FILE:line:column: message` or `ok`.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["level", "list"])]
    pub(crate) check: Option<PathBuf>,
    /// List the built-in levels and backends.
    #[arg(long)]
    pub(crate) list: bool,
    /// A generated maze instead of `--level` (see `docs/generator.md`).
    #[command(flatten)]
    pub(crate) maze: super::generated::GenerateArgs,
    /// Print the generated maze's level text (for `--check` and `--level`) and stop.
    // Checked in `run`, not with clap's `requires`: clap would also ask for
    // `--level` (required unless `--generate`), which `--generate` refuses,
    // and lets `--level NAME --print-level` through as a success.
    #[arg(long, conflicts_with_all = ["check", "list"])]
    pub(crate) print_level: bool,
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 && x <= 86_400.0 => Ok(x),
        _ => Err(format!(
            "{} is not a number of seconds in (0, 86400]",
            excerpt(s)
        )),
    }
}

fn parse_substeps(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(n @ (1 | 2 | 4 | 8 | 16)) => Ok(n),
        _ => Err(format!("{} is not one of 1, 2, 4, 8, 16", excerpt(s))),
    }
}

fn parse_stepping(s: &str) -> Result<Stepping, String> {
    match s {
        "fixed" => Ok(Stepping::Fixed),
        "events" => Ok(Stepping::Events),
        _ => Err(format!("{} is not one of fixed, events", excerpt(s))),
    }
}

/// A stepping mode's name in the JSON and the summary.
pub(crate) fn stepping_name(s: Stepping) -> &'static str {
    match s {
        Stepping::Fixed => "fixed",
        Stepping::Events => "events",
    }
}

/// Where each frame's reading comes from.
enum Input {
    Flat,
    Tilts(TiltTrace),
    Autopilot,
}

/// One run, ready to go (everything that could fail on input has been checked).
struct Job<'o> {
    level: LevelView<'static>,
    config: GameConfig,
    max_frames: u64,
    input: Input,
    motion_out: Option<(&'o Path, BufWriter<File>)>,
    gif: Option<(&'o Path, GifRecorder, u32)>,
}

impl WithScalar for Job<'_> {
    type Output = Result<Report, String>;

    fn run<S: Scalar>(mut self) -> Result<Report, String> {
        let mut session = Session::<S>::new(self.level, self.config, SYNTHETIC_TILT)
            .map_err(|e| format!("level `{}` cannot be set up: {e}", self.level.info.name))?;
        let mut autopilot = match self.input {
            Input::Autopilot => Some(Autopilot::new(&self.level)),
            _ => None,
        };
        let hz = self.config.frame_hz() as f64;
        let substeps = 1u32 << self.config.substeps_log2;
        let start = states(session.game().world());
        let mut trace_rows = 0u64;
        let write_err = |p: &Path, e: std::io::Error| format!("cannot write {}: {e}", p.display());
        if let Some((p, w)) = &mut self.motion_out {
            writeln!(w, "{}", trace_header(start.len())).map_err(|e| write_err(p, e))?;
        }
        if let Some((p, gif, _)) = &mut self.gif {
            let (_, _, px) = super::storey_maps::game_image(session.game());
            gif.push(&px, 0.0).map_err(|e| write_err(p, e))?;
        }
        let dt = session.game().world().params().dt();
        let mut log = FlightLog::default();
        let started = Instant::now();
        let mut frames = 0u64;
        while session.game().phase() == Phase::Playing && frames < self.max_frames {
            let reading = match &mut self.input {
                Input::Flat => super::tilt_trace::FLAT,
                Input::Tilts(t) => t.reading_at(frames as f64 / hz),
                Input::Autopilot => autopilot
                    .as_mut()
                    .map_or(super::tilt_trace::FLAT, |a| a.reading_mg(session.game())),
            };
            let before = self
                .motion_out
                .is_some()
                .then(|| FrameStart::of(session.game().world()));
            session.frame(reading);
            frames += 1;
            if let (Some((p, w)), Some(start)) = (&mut self.motion_out, before) {
                trace_rows += replay_frame(&session, &start, substeps, dt, &mut log, w).map_err(
                    |e| match e {
                        ReplayError::Io(e) => write_err(p, e),
                        ReplayError::Diverged => {
                            "internal error: the per-step replay diverged from the frame"
                                .to_string()
                        }
                    },
                )?;
            }
            if let Some((p, gif, every)) = &mut self.gif {
                if frames.is_multiple_of(*every as u64) || session.game().phase() != Phase::Playing
                {
                    let (_, _, px) = super::storey_maps::game_image(session.game());
                    gif.push(&px, frames as f64 / hz)
                        .map_err(|e| write_err(p, e))?;
                }
            }
        }
        if let Some((p, w)) = &mut self.motion_out {
            w.flush().map_err(|e| write_err(p, e))?;
        }
        let wall_s = started.elapsed().as_secs_f64();
        let gif_frames = match self.gif {
            Some((p, gif, _)) => gif
                .finish(frames as f64 / hz, GIF_HOLD_S)
                .map_err(|e| write_err(p, e))?,
            None => 0,
        };
        let game = session.game();
        let phase = game.phase();
        let outcome = match phase {
            Phase::Playing => Phase::TimeUp.as_str(),
            p => p.as_str(),
        };
        let spec = &self.level.info.spec;
        Ok(Report {
            level: self.level.info.name.to_string(),
            outcome,
            frames: game.frames(),
            steps: game.steps(),
            sim_seconds: game.frames() as f64 / hz,
            dt_s: dt,
            substeps,
            backend: S::NAME,
            short_mm: spec.short_um as f64 / 1000.0,
            long_mm: spec.long_um as f64 / 1000.0,
            marble_radius_mm: spec.radius_um as f64 / 1000.0,
            marbles: game.world().marbles().len(),
            stepping: stepping_name(self.config.stepping),
            start,
            end: states(game.world()),
            state_hash: session.state_hash(),
            tilt_errors: session.tilt_errors().0,
            wall_s,
            trace_rows,
            gif_frames,
        })
    }
}

/// `--check FILE`: 0 and `ok`, or 1 and `FILE:line:column: message`; 2 for a
/// file that cannot be read or is not text (`FILE:line:column: not UTF-8 (byte
/// 0xNN)`), as `--level` refuses it.
fn check(path: &Path) -> i32 {
    let shown = path.display();
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{shown}: cannot read: {e}");
            return 2;
        }
    };
    let src = match crate::game::level::text(&bytes) {
        Ok(s) => s.to_string(),
        Err(e) => {
            eprintln!("{shown}:{e}");
            return 2;
        }
    };
    let view = match super::parse_runtime(src.clone()) {
        Ok(v) => v,
        Err(LevelError { line, column, kind }) => {
            eprintln!("{shown}:{line}:{column}: {kind}");
            return 1;
        }
    };
    // The parser refuses what `Params::new` would; the physics still checks that each
    // start is clear of the tiles with the firmware's scalar.
    if let Err(e) = Game::<crate::physics::Fx>::new(view, GameConfig::DEFAULT) {
        let (line, column) = match e {
            SetupError::BadStart(n) => nth_start(&src, n).unwrap_or((1, 1)),
            _ => (1, 1),
        };
        eprintln!("{shown}:{line}:{column}: the physics cannot set the level up: {e}");
        return 1;
    }
    println!("ok");
    0
}

/// Line and column (1-based, characters) of the `n`-th `S` of a level's grid.
fn nth_start(src: &str, n: usize) -> Option<(usize, usize)> {
    let mut lines = src.lines().enumerate();
    lines.find(|(_, l)| l.trim_start_matches('\u{feff}').trim() == "---")?;
    lines
        .flat_map(|(i, l)| l.chars().enumerate().map(move |(c, ch)| (i + 1, c + 1, ch)))
        .filter(|&(_, _, ch)| ch == 'S')
        .nth(n)
        .map(|(line, column, _)| (line, column))
}

/// The built-in levels, what each takes in the firmware's flash (its grid's
/// occupancy words, read in place: no RAM), and the backends.
fn list() {
    use crate::game::level::LevelView;
    use crate::physics::geometry::grid::words_for;
    println!("built-in levels:");
    let levels = &crate::game::levels::LEVELS;
    let mut grids = 0;
    for (i, l) in levels.iter().enumerate() {
        let t = &l.tiles;
        let grid = 4 * words_for(t.nx(), t.ny(), t.nz());
        grids += grid;
        println!(
            "  {}. {:<16} {}×{} tiles × {} storey(s), {} s, {} marble(s), grid {} B",
            i + 1,
            l.info.name,
            l.info.nx,
            l.info.nz,
            l.info.storeys,
            l.info.time_limit_s,
            l.info.starts().len(),
            grid
        );
    }
    let names: usize = levels.iter().map(|l| l.info.name.len()).sum();
    println!(
        "flash for the levels: grids {grids} B, names {names} B, and a descriptor each \
         (the firmware's `LEVELS`; {} B each on this host)",
        core::mem::size_of::<LevelView<'static>>()
    );
    println!(
        "the largest grid ({MAX}×{MAX} tiles × {} storeys): {} B",
        crate::physics::geometry::grid::MAX_STOREYS,
        4 * super::MAX_WORDS,
        MAX = crate::physics::geometry::grid::MAX_TILES_XZ
    );
    let names: Vec<_> = Backend::ALL.iter().map(|b| b.name()).collect();
    println!(
        "backends: {} (default {})",
        names.join(", "),
        Backend::I8F24
    );
}

/// Runs the CLI with the process arguments; returns the exit status.
pub fn main() -> i32 {
    let args = match super::parse_args::<Args>() {
        Ok(a) => a,
        Err(status) => return status,
    };
    run(&args)
}

/// Runs the CLI with parsed arguments; returns the exit status.
pub(crate) fn run(args: &Args) -> i32 {
    if args.print_level {
        return match args.maze.level() {
            Ok(Some((text, _))) => {
                print!("{text}");
                0
            }
            Ok(None) => {
                eprintln!("sim: error: --print-level needs --generate SEED");
                2
            }
            Err(msg) => {
                eprintln!("sim: error: {msg}");
                2
            }
        };
    }
    if let Some(path) = &args.check {
        return check(path);
    }
    if args.list {
        list();
        return 0;
    }
    match simulate(args) {
        Ok(report) => {
            if args.json {
                println!("{}", report.json());
            } else {
                println!("{}", report.summary());
            }
            0
        }
        Err(msg) => {
            eprintln!("sim: error: {msg}");
            2
        }
    }
}

/// Loads the inputs named by `args` and runs the level.
pub fn simulate(args: &Args) -> Result<Report, String> {
    let backend = Backend::from_name(&args.backend)?;
    let level = match args.maze.level()? {
        Some((_, view)) => view,
        None => load_level(args.level.as_deref().unwrap_or_default())?.view,
    };
    let base = GameConfig::stepped_by(args.stepping == Stepping::Events);
    let config = GameConfig {
        substeps_log2: args
            .substeps
            .map_or(base.substeps_log2, |n| n.trailing_zeros()),
        ..base
    };
    let input = if let Some(p) = &args.tilt_trace {
        let bytes =
            std::fs::read(p).map_err(|e| format!("cannot read tilt trace {}: {e}", p.display()))?;
        let t = TiltTrace::from_bytes(&bytes)
            .map_err(|e| format!("tilt trace {}:{}: {}", p.display(), e.line, e.message))?;
        Input::Tilts(t)
    } else if args.autopilot {
        Input::Autopilot
    } else {
        Input::Flat
    };
    let max_frames = match args.seconds {
        Some(s) => (s * config.frame_hz() as f64).ceil() as u64,
        None => u64::MAX,
    };
    let motion_out = match &args.motion_trace {
        Some(p) => {
            let f = File::create(p).map_err(|e| format!("cannot create {}: {e}", p.display()))?;
            Some((p.as_path(), BufWriter::with_capacity(1 << 16, f)))
        }
        None => None,
    };
    let gif = match &args.gif {
        Some(p) => {
            let (w, h) = super::storey_maps::image_size(&level);
            let g = GifRecorder::create(p, w, h, args.gif_scale as usize)
                .map_err(|e| format!("cannot create {}: {e}", p.display()))?;
            Some((p.as_path(), g, args.gif_every))
        }
        None => None,
    };
    backend.run(Job {
        level,
        config,
        max_frames,
        input,
        motion_out,
        gif,
    })
}
