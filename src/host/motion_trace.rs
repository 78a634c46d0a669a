//! The marbles' motion trace (`cargo sim -- --trace FILE`): every marble's
//! position and velocity, sampled between the game's frames.
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
//! Columns (`trace_header`): `step,t_s` (the step the instant ends or lies in,
//! 1-based, and the simulated time), then `x_mm,y_mm,z_mm,vx_mm_s,vy_mm_s,vz_mm_s`
//! for marble 0 and `xN_mm,yN_mm,zN_mm,vxN_mm_s,vyN_mm_s,vzN_mm_s` for each
//! further marble `N` — one row per instant, so marble–marble distances are read
//! off a single row.
//!

use std::format;
use std::io::Write;
use std::string::{String, ToString};
use std::vec::Vec;

use super::json_number;
use crate::game::level::MAX_MARBLES;
use crate::game::session::Session;
use crate::physics::{Marble, Scalar, Segment, StepObserver, Vec3, World};

/// The trace's header for `marbles` marbles (see the module doc).
pub(crate) fn trace_header(marbles: usize) -> String {
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
    pub(crate) flights: Vec<Vec<(S, S, Segment<S>)>>,
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
    pub(crate) fn clear(&mut self) {
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

/// Why a frame's replay wrote no rows.
pub(super) enum ReplayError {
    /// The trace could not be written.
    Io(std::io::Error),
    /// The replay did not end where the frame did.
    Diverged,
}

/// What a frame's replay starts from: the world as it was before the frame.
pub(super) struct FrameStart<'a, S: Scalar> {
    world: World<'a, S, MAX_MARBLES>,
}

impl<'a, S: Scalar> FrameStart<'a, S> {
    /// The world `w` as the next frame starts from it.
    pub(super) fn of(w: &World<'a, S, MAX_MARBLES>) -> Self {
        FrameStart { world: w.clone() }
    }
}

/// Replays the frame just played step by step (see the module docs) and writes
/// its rows; returns the rows written.
pub(super) fn replay_frame<S: Scalar>(
    session: &Session<'_, S>,
    start: &FrameStart<'_, S>,
    substeps: u32,
    dt: f64,
    log: &mut FlightLog<S>,
    out: &mut impl Write,
) -> Result<u64, ReplayError> {
    let game = session.game();
    let after = game.world();
    // The frame's pull and board motion, the state it started from: a marble
    // the frame left asleep is not woken (its flights would count against the
    // step's flight budget and could move the cut), and the edges the marbles
    // rolled round into the frame are the ones it went on round.
    let mut w = after.clone();
    w.rewind_to(&start.world);
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
