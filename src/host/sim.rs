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
//! inputs and backend.
//!
//! # The trace
//!
//! `--trace FILE` writes at least one row per 1/1024 s of simulated time (with
//! fixed steps: see below), each with the exact state of **every** marble at that
//! instant, although the game steps a whole frame at a time: before each frame
//! the marbles are saved; after it the frame is replayed step by step on a copy
//! of the world that has the frame's gravity and board motion (everything a step
//! reads except the marbles, which the frame changed, and the counters). The
//! physics is deterministic, so the replay goes through exactly the frame's
//! states; the tool checks that the replay ends where the frame did and fails
//! loudly otherwise. The game itself, its judging and its hash are untouched by
//! tracing.
//!
//! * Fixed steps (`--stepping fixed`): one row per step, the state after it (at
//!   the default 8 substeps that is one row per 1/1024 s; fewer substeps give
//!   fewer rows — between two fixed steps the state is not defined).
//! * Event steps (`--stepping events`, one step per 1/128 s frame by default):
//!   the replay records every piece of closed-form flight
//!   ([`World::step_observed`] into a [`FlightLog`]) and samples it at every
//!   1/1024 s instant inside the step ([`sample`]); the row at the step's end is
//!   the world's state after the step. A state jump at an event instant (a
//!   bounce) belongs to the flight that starts there.
//!
//! Columns ([`trace_header`]): `step,t_s` (the step the instant ends or lies in,
//! 1-based, and the simulated time), then `x_mm,y_mm,z_mm,vx_mm_s,vy_mm_s,vz_mm_s`
//! for marble 0 and `xN_mm,yN_mm,zN_mm,vxN_mm_s,vyN_mm_s,vzN_mm_s` for each
//! further marble `N` — one row per instant, so marble–marble distances are read
//! off a single row.
//!
//! # Exit status
//!
//! 0 for any outcome (`won`, `fell`, `timeout`); 2 for bad input (level, tilt
//! trace, backend, substeps, unwritable output) with a message on stderr; for
//! `--check`, 1 when the level is invalid (2 when the file cannot be read or is
//! not UTF-8). A message quotes at most 60 characters of the text it refuses
//! ([`super::excerpt`]).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::string::{String, ToString};
use std::time::Instant;
use std::vec::Vec;
use std::{eprintln, format, print, println};

use clap::Parser;

use super::gif_out::GifRecorder;
use super::trace::TiltTrace;
use super::{excerpt, json_number, json_string, load_level, Backend, WithScalar};
use crate::game::autopilot::Autopilot;
use crate::game::level::{LevelError, LevelView};
use crate::game::rules::{Game, GameConfig, Phase};
use crate::game::session::{Session, SYNTHETIC_TILT};
use crate::physics::{Marble, Scalar, Segment, SetupError, StepObserver, Stepping, Vec3, World};

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
    #[arg(long, value_name = "FILE|NAME", required_unless_present_any = ["check", "list", "generate"])]
    pub level: Option<String>,
    /// Tilt readings: CSV `t_s,ax_mg,ay_mg,az_mg` (board frame, flat = 0,1000,0;
    /// ax < 0 rolls towards +x'), each held until the next. Default: flat board.
    #[arg(long, value_name = "FILE", conflicts_with = "autopilot")]
    pub tilt_trace: Option<PathBuf>,
    /// Let the autopilot tilt the board.
    #[arg(long)]
    pub autopilot: bool,
    /// Stop after S seconds of simulated time (default: the level's time limit);
    /// a run stopped this way while still playing ends as `timeout`.
    #[arg(long, value_name = "S", value_parser = parse_seconds)]
    pub seconds: Option<f64>,
    /// Number type of the physics.
    #[arg(long, value_name = "NAME", default_value = "i8f24")]
    pub backend: String,
    /// Physics steps per frame: 1, 2, 4, 8 or 16 (the frame rate stays 128 Hz).
    /// Default: 8 with fixed steps, 1 (one step per frame) with events.
    #[arg(long, value_name = "N", value_parser = parse_substeps)]
    pub substeps: Option<u32>,
    /// How a step is crossed: `events` (each marble flies its closed form from
    /// event to event; what every board plays) or `fixed` (the closed form over
    /// the step, contacts at its end, speed capped; the study's baseline).
    #[arg(long, value_name = "MODE", default_value = "events", value_parser = parse_stepping)]
    pub stepping: Stepping,
    /// Write every marble's position (mm) and velocity (mm/s) to FILE as CSV: a
    /// row per 1/1024 s with events, a row per step with fixed steps.
    #[arg(long, value_name = "FILE")]
    pub trace: Option<PathBuf>,
    /// Print one JSON line instead of the human summary.
    #[arg(long)]
    pub json: bool,
    /// Render the run to an animated GIF (a level with storeys: every storey's map
    /// beside the matrix, top storey first).
    #[arg(long, value_name = "FILE")]
    pub gif: Option<PathBuf>,
    /// GIF pixels per LED (tile).
    #[arg(long, value_name = "PX", default_value_t = 12, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub gif_scale: u32,
    /// A GIF image every N game frames (128 frames/s).
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub gif_every: u32,
    /// Validate a level file: print `FILE:line:column: message` or `ok`.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["level", "list"])]
    pub check: Option<PathBuf>,
    /// List the built-in levels and backends.
    #[arg(long)]
    pub list: bool,
    /// A generated maze instead of `--level` (see `docs/generator.md`).
    #[command(flatten)]
    pub maze: super::generated::GenerateArgs,
    /// Print the generated maze's level text (for `--check` and `--level`) and stop.
    #[arg(long, requires = "generate")]
    pub print_level: bool,
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
pub fn stepping_name(s: Stepping) -> &'static str {
    match s {
        Stepping::Fixed => "fixed",
        Stepping::Events => "events",
    }
}

/// Where each frame's reading comes from.
enum Input {
    Flat,
    Trace(TiltTrace),
    Autopilot,
}

/// What a run produced.
#[derive(Clone, Debug)]
pub struct Report {
    /// The level's name.
    pub level: String,
    /// `won`, `fell` or `timeout`.
    pub outcome: &'static str,
    /// Frames played.
    pub frames: u32,
    /// Physics steps taken.
    pub steps: u64,
    /// Simulated seconds.
    pub sim_seconds: f64,
    /// Physics step (s).
    pub dt_s: f64,
    /// Steps per frame.
    pub substeps: u32,
    /// Scalar backend.
    pub backend: &'static str,
    /// Short tile width (mm).
    pub short_mm: f64,
    /// Long tile width (mm).
    pub long_mm: f64,
    /// Marble radius (mm).
    pub marble_radius_mm: f64,
    /// Marbles in the level.
    pub marbles: usize,
    /// `fixed` or `events`.
    pub stepping: &'static str,
    /// Every marble at the start.
    pub start: Vec<MarbleState>,
    /// Every marble at the end.
    pub end: Vec<MarbleState>,
    /// `Session::state_hash` at the end.
    pub state_hash: u64,
    /// Readings the tilt path rejected.
    pub tilt_errors: u32,
    /// Wall-clock seconds of the simulation loop.
    pub wall_s: f64,
    /// Rows written by `--trace`.
    pub trace_rows: u64,
    /// GIF frames written by `--gif`.
    pub gif_frames: usize,
}

/// One marble's state in the report (mm and mm/s, tile frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarbleState {
    /// Centre.
    pub pos_mm: [f64; 3],
    /// Velocity.
    pub vel_mm_s: [f64; 3],
    /// Fallen through a hole or off the board.
    pub out: bool,
}

impl MarbleState {
    fn json(&self) -> String {
        let [x, y, z] = self.pos_mm.map(json_number);
        let [vx, vy, vz] = self.vel_mm_s.map(json_number);
        format!(
            r#"{{"x_mm":{x},"y_mm":{y},"z_mm":{z},"vx_mm_s":{vx},"vy_mm_s":{vy},"vz_mm_s":{vz},"out":{}}}"#,
            self.out
        )
    }
}

/// `start` and `final` in the JSON: marble 0's position at the top (the fields
/// of old), every marble's state in `marbles`.
fn marbles_json(ms: &[MarbleState]) -> String {
    let [x, y, z] = ms
        .first()
        .map_or([f64::NAN; 3], |m| m.pos_mm)
        .map(json_number);
    let list: Vec<String> = ms.iter().map(MarbleState::json).collect();
    format!(
        r#"{{"x_mm":{x},"y_mm":{y},"z_mm":{z},"marbles":[{}]}}"#,
        list.join(",")
    )
}

impl Report {
    /// Simulated seconds per wall-clock second (not deterministic).
    pub fn speed_x(&self) -> f64 {
        if self.wall_s > 0.0 {
            self.sim_seconds / self.wall_s
        } else {
            f64::INFINITY
        }
    }

    /// The `--json` line.
    pub fn json(&self) -> String {
        format!(
            "{{\"level\":{},\"outcome\":\"{}\",\"steps\":{},\"frames\":{},\"sim_seconds\":{},\"dt_s\":{},\
             \"substeps\":{},\"stepping\":\"{}\",\"backend\":\"{}\",\"short_mm\":{},\"long_mm\":{},\
             \"marble_radius_mm\":{},\"marbles\":{},\"start\":{},\"final\":{},\"state_hash\":\"{:016x}\",\
             \"tilt_errors\":{},\"wall_s\":{},\"speed_x\":{}}}",
            json_string(&self.level),
            self.outcome,
            self.steps,
            self.frames,
            json_number(self.sim_seconds),
            json_number(self.dt_s),
            self.substeps,
            self.stepping,
            self.backend,
            json_number(self.short_mm),
            json_number(self.long_mm),
            json_number(self.marble_radius_mm),
            self.marbles,
            marbles_json(&self.start),
            marbles_json(&self.end),
            self.state_hash,
            self.tilt_errors,
            json_number(self.wall_s),
            json_number(self.speed_x().min(1e12)),
        )
    }

    /// The human summary.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{}: {} after {:.3} s ({} frames, {} steps of 1/{} s, {} substeps, {} stepping, {})\n",
            self.level,
            self.outcome,
            self.sim_seconds,
            self.frames,
            self.steps,
            (1.0 / self.dt_s).round(),
            self.substeps,
            self.stepping,
            self.backend,
        );
        for (n, (a, b)) in self.start.iter().zip(&self.end).enumerate() {
            let (p, q) = (a.pos_mm, b.pos_mm);
            s.push_str(&format!(
                "marble {n}: start ({:.2}, {:.2}, {:.2}) mm → end ({:.2}, {:.2}, {:.2}) mm{}\n",
                p[0],
                p[1],
                p[2],
                q[0],
                q[1],
                q[2],
                if b.out { " (out)" } else { "" }
            ));
        }
        s.push_str(&format!(
            "state_hash {:016x}; {:.0}× real time",
            self.state_hash,
            self.speed_x()
        ));
        if self.tilt_errors > 0 {
            s.push_str(&format!(
                "\n{} readings rejected by the tilt path",
                self.tilt_errors
            ));
        }
        if self.trace_rows > 0 {
            s.push_str(&format!("\ntrace: {} rows", self.trace_rows));
        }
        if self.gif_frames > 0 {
            s.push_str(&format!("\ngif: {} frames", self.gif_frames));
        }
        s
    }
}

/// One run, ready to go (everything that could fail on input has been checked).
struct Job<'o> {
    level: LevelView<'static>,
    config: GameConfig,
    max_frames: u64,
    input: Input,
    trace_out: Option<(&'o Path, BufWriter<File>)>,
    gif: Option<(&'o Path, GifRecorder, u32)>,
}

fn states<S: Scalar, const M: usize>(w: &World<'_, S, M>) -> Vec<MarbleState> {
    let l = &w.params().layout;
    let mm = |v: Vec3<S>| [l.to_mm(v.x), l.to_mm(v.y), l.to_mm(v.z)];
    w.marbles()
        .iter()
        .map(|m| MarbleState {
            pos_mm: mm(m.pos),
            vel_mm_s: mm(m.vel),
            out: m.out,
        })
        .collect()
}

/// The trace's header for `marbles` marbles (see the module docs).
pub fn trace_header(marbles: usize) -> String {
    let mut h = String::from("step,t_s");
    for n in 0..marbles {
        let n = if n == 0 { String::new() } else { n.to_string() };
        for q in ["x", "y", "z"] {
            h.push_str(&format!(",{q}{n}_mm"));
        }
        for q in ["vx", "vy", "vz"] {
            h.push_str(&format!(",{q}{n}_mm_s"));
        }
    }
    h
}

/// Every flight of one step, per marble, in time order (a [`StepObserver`]).
#[derive(Clone, Debug)]
pub struct FlightLog<S> {
    /// Per marble: `(from, to, segment)`, fractions of the step.
    pub flights: Vec<Vec<(S, S, Segment<S>)>>,
}

impl<S> Default for FlightLog<S> {
    fn default() -> Self {
        FlightLog {
            flights: Vec::new(),
        }
    }
}

impl<S> FlightLog<S> {
    /// Forgets the flights so far (keeps the room).
    pub fn clear(&mut self) {
        for f in &mut self.flights {
            f.clear();
        }
    }
    /// Marble `n`'s flights.
    pub fn of(&self, n: usize) -> &[(S, S, Segment<S>)] {
        self.flights.get(n).map_or(&[][..], |f| &f[..])
    }
}

impl<S: Copy> StepObserver<S> for FlightLog<S> {
    fn flight(&mut self, marble: usize, from: S, to: S, seg: &Segment<S>) {
        if self.flights.len() <= marble {
            self.flights.resize_with(marble + 1, Vec::new);
        }
        self.flights[marble].push((from, to, *seg));
    }
}

/// A marble's position and velocity at `tau` (a fraction of the step) from its
/// `flights` in that step: on the flight with `from ≤ tau < to` (a jump at a
/// flight's end belongs to the next one); between flights (asleep for a while)
/// where the last one ended; before any, `start` (its state before the step).
pub fn sample<S: Scalar>(
    flights: &[(S, S, Segment<S>)],
    start: &Marble<S>,
    tau: S,
) -> (Vec3<S>, Vec3<S>) {
    match flights.iter().rev().find(|(from, _, _)| *from <= tau) {
        Some(&(from, to, ref seg)) => {
            let s = if tau < to { tau - from } else { to - from };
            (seg.pos_at(s), seg.vel_at(s))
        }
        None => (start.pos, start.vel),
    }
}

/// Trace rows per step: one per 1/1024 s with events (at least one), one per
/// step with fixed steps.
pub fn samples_per_step<S: Scalar, const M: usize>(w: &World<'_, S, M>) -> u32 {
    if w.params().events() {
        1 << 10u32.saturating_sub(w.params().k)
    } else {
        1
    }
}

/// Advances `w` by one step and returns `samples` rows: the instants `j/samples`
/// of the step (`j = 1 ..= samples`), every marble's position and velocity at
/// each (pitch, pitch/s). The last row is the world's state after the step; the
/// others are sampled from the step's flights ([`sample`]; only event steps have
/// flights, so with fixed steps ask for one sample).
pub fn step_sampled<S: Scalar, const M: usize>(
    w: &mut World<'_, S, M>,
    log: &mut FlightLog<S>,
    samples: u32,
) -> Vec<Vec<(Vec3<S>, Vec3<S>)>> {
    let before: Vec<Marble<S>> = w.marbles().to_vec();
    log.clear();
    w.step_observed(log);
    let mut rows = Vec::with_capacity(samples as usize);
    for j in 1..samples {
        let tau = S::from_int(j as i32).div(S::from_int(samples as i32));
        let row = before
            .iter()
            .enumerate()
            .map(|(n, m)| sample(log.of(n), m, tau))
            .collect();
        rows.push(row);
    }
    rows.push(w.marbles().iter().map(|m| (m.pos, m.vel)).collect());
    rows
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
        if let Some((p, w)) = &mut self.trace_out {
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
                Input::Flat => super::trace::FLAT,
                Input::Trace(t) => t.reading_at(frames as f64 / hz),
                Input::Autopilot => autopilot
                    .as_mut()
                    .map_or(super::trace::FLAT, |a| a.reading_mg(session.game())),
            };
            let before = self.trace_out.is_some().then(|| {
                let w = session.game().world();
                (w.marbles().to_vec(), w.stats)
            });
            session.frame(reading);
            frames += 1;
            if let (Some((p, w)), Some((marbles, stats))) = (&mut self.trace_out, before) {
                trace_rows += replay_frame(&session, &marbles, stats, substeps, dt, &mut log, w)
                    .map_err(|e| match e {
                        ReplayError::Io(e) => write_err(p, e),
                        ReplayError::Diverged => {
                            "internal error: the per-step replay diverged from the frame"
                                .to_string()
                        }
                    })?;
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
        if let Some((p, w)) = &mut self.trace_out {
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

enum ReplayError {
    Io(std::io::Error),
    Diverged,
}

/// Replays the frame just played step by step (see the module docs) and writes
/// its rows; returns the rows written.
fn replay_frame<S: Scalar>(
    session: &Session<'_, S>,
    before: &[Marble<S>],
    stats: crate::physics::StepStats,
    substeps: u32,
    dt: f64,
    log: &mut FlightLog<S>,
    out: &mut impl Write,
) -> Result<u64, ReplayError> {
    let game = session.game();
    let after = game.world();
    let mut w = after.clone();
    w.marbles_mut().copy_from_slice(before);
    // The frame's new pull woke the marbles before its first step, which the
    // copies from before it do not know. Waking them all is exact: a marble that
    // stayed asleep through the frame is one whose step changes nothing, and
    // stepping it falls asleep again with the same state.
    for m in w.marbles_mut() {
        m.asleep = false;
    }
    w.stats = stats;
    let layout = after.params().layout;
    let c = |v: S| layout.to_mm(v);
    let samples = samples_per_step(&w);
    let first_step = game.steps() - substeps as u64;
    let mut rows = 0u64;
    let mut line = String::new();
    for n in 1..=substeps as u64 {
        let step = first_step + n;
        for (j, row) in step_sampled(&mut w, log, samples).iter().enumerate() {
            let t = (step - 1) as f64 * dt + (j + 1) as f64 / samples as f64 * dt;
            line.clear();
            line.push_str(&format!("{step},{}", json_number(t)));
            for (p, v) in row {
                line.push_str(&format!(
                    ",{:.6},{:.6},{:.6},{:.6},{:.6},{:.6}",
                    c(p.x),
                    c(p.y),
                    c(p.z),
                    c(v.x),
                    c(v.y),
                    c(v.z)
                ));
            }
            writeln!(out, "{line}").map_err(ReplayError::Io)?;
            rows += 1;
        }
    }
    if w.marbles() != after.marbles() {
        return Err(ReplayError::Diverged);
    }
    Ok(rows)
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
pub fn run(args: &Args) -> i32 {
    if let Some(path) = &args.check {
        return check(path);
    }
    if args.list {
        list();
        return 0;
    }
    if args.print_level {
        return match args.maze.level() {
            Ok(Some((text, _))) => {
                print!("{text}");
                0
            }
            Ok(None) => 0,
            Err(msg) => {
                eprintln!("sim: error: {msg}");
                2
            }
        };
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
        Input::Trace(t)
    } else if args.autopilot {
        Input::Autopilot
    } else {
        Input::Flat
    };
    let max_frames = match args.seconds {
        Some(s) => (s * config.frame_hz() as f64).ceil() as u64,
        None => u64::MAX,
    };
    let trace_out = match &args.trace {
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
        trace_out,
        gif,
    })
}
