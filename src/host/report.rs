//! What a `cargo sim` run produced ([`Report`]): the level, the outcome, the
//! steps and the state hash, every marble's state at the start and the end,
//! as one JSON line or a summary for a person.

use std::format;
use std::string::String;
use std::vec::Vec;

use super::{json_number, json_string};
use crate::physics::{Scalar, Vec3, World};

/// What a run produced.
#[derive(Clone, Debug)]
pub struct Report {
    /// The level's name.
    pub(crate) level: String,
    /// `won`, `fell` or `timeout`.
    pub outcome: &'static str,
    /// Frames played.
    pub frames: u32,
    /// Physics steps taken.
    pub(crate) steps: u64,
    /// Simulated seconds.
    pub(crate) sim_seconds: f64,
    /// Physics step (s).
    pub(crate) dt_s: f64,
    /// Steps per frame.
    pub(crate) substeps: u32,
    /// Scalar backend.
    pub(crate) backend: &'static str,
    /// Short tile width (mm).
    pub(crate) short_mm: f64,
    /// Long tile width (mm).
    pub(crate) long_mm: f64,
    /// Marble radius (mm).
    pub(crate) marble_radius_mm: f64,
    /// Marbles in the level.
    pub(crate) marbles: usize,
    /// `fixed` or `events`.
    pub(crate) stepping: &'static str,
    /// Every marble at the start.
    pub(crate) start: Vec<MarbleState>,
    /// Every marble at the end.
    pub(crate) end: Vec<MarbleState>,
    /// `Session::state_hash` at the end.
    pub state_hash: u64,
    /// Readings the tilt path rejected.
    pub(crate) tilt_errors: u32,
    /// Wall-clock seconds of the simulation loop.
    pub(crate) wall_s: f64,
    /// Rows written by `--trace`.
    pub(crate) trace_rows: u64,
    /// GIF frames written by `--gif`.
    pub gif_frames: usize,
}

/// One marble's state in the report (mm and mm/s, tile frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MarbleState {
    /// Centre.
    pub(crate) pos_mm: [f64; 3],
    /// Velocity.
    pub(crate) vel_mm_s: [f64; 3],
    /// Fallen through a hole or off the board.
    pub(crate) out: bool,
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

/// `start` and `final` in the JSON: marble 0's position at the top (what a
/// one-marble reader looks for), every marble's state in `marbles`.
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
    pub(crate) fn speed_x(&self) -> f64 {
        if self.wall_s > 0.0 {
            self.sim_seconds / self.wall_s
        } else {
            f64::INFINITY
        }
    }

    /// The `--json` line.
    pub(crate) fn json(&self) -> String {
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
    pub(crate) fn summary(&self) -> String {
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

/// Every marble's state in `w`, in mm and mm/s.
pub(super) fn states<S: Scalar, const M: usize>(w: &World<'_, S, M>) -> Vec<MarbleState> {
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
