//! Helpers shared by the host tests.
#![allow(dead_code)]

use marble_rolling::physics::geometry::grid::TileGrid;
use marble_rolling::physics::geometry::tiles::Aabb;
pub use marble_rolling::physics::Stepping;
use marble_rolling::physics::{
    Effects, Params, PhysicsSpec, Scalar, Segment, StepObserver, TileIndex, Vec3, World,
};

/// Room for a 127 × 2 × 127 grid.
pub const WORDS: usize = 1016;
pub type Grid = TileGrid<WORDS>;

/// Runs `$body::<S>()` as one `#[test]` per scalar backend.
#[macro_export]
macro_rules! for_each_backend {
    ($name:ident, $body:ident) => {
        mod $name {
            use super::*;
            #[test]
            fn i8f24() {
                $body::<fixed::types::I8F24>();
            }
            #[test]
            fn i16f16() {
                $body::<fixed::types::I16F16>();
            }
            #[test]
            fn i32f32() {
                $body::<fixed::types::I32F32>();
            }
            #[test]
            fn f32() {
                $body::<f32>();
            }
            #[test]
            fn f32_micromath() {
                $body::<marble_rolling::physics::MicroF32>();
            }
            #[test]
            fn f64() {
                $body::<f64>();
            }
        }
    };
}

/// Runs `$body::<S>(stepping)` as one `#[test]` per scalar backend and stepping
/// mode (`fixed::…`, `events::…`).
#[macro_export]
macro_rules! for_each_backend_and_mode {
    ($name:ident, $body:ident) => {
        mod $name {
            use super::*;
            mod fixed {
                use super::*;
                $crate::backend_tests!($body, Stepping::Fixed);
            }
            mod events {
                use super::*;
                $crate::backend_tests!($body, Stepping::Events);
            }
        }
    };
}

/// One `#[test]` per backend calling `$body::<S>($arg)`.
#[macro_export]
macro_rules! backend_tests {
    ($body:ident, $arg:expr) => {
        #[test]
        fn i8f24() {
            $body::<::fixed::types::I8F24>($arg);
        }
        #[test]
        fn i16f16() {
            $body::<::fixed::types::I16F16>($arg);
        }
        #[test]
        fn i32f32() {
            $body::<::fixed::types::I32F32>($arg);
        }
        #[test]
        fn f32() {
            $body::<f32>($arg);
        }
        #[test]
        fn f32_micromath() {
            $body::<marble_rolling::physics::MicroF32>($arg);
        }
        #[test]
        fn f64() {
            $body::<f64>($arg);
        }
    };
}

/// The default spec in a stepping mode: fixed steps at 1024 steps/s, or events
/// at the firmware's 128 frames/s.
pub fn spec_in(stepping: Stepping, effects: Effects) -> PhysicsSpec {
    stepped(spec(effects), stepping)
}

/// `spec` (a level's, say) in a stepping mode, at that mode's rate as in
/// [`spec_in`].
pub fn stepped(spec: PhysicsSpec, stepping: Stepping) -> PhysicsSpec {
    PhysicsSpec {
        stepping,
        step_log2: match stepping {
            Stepping::Fixed => 10,
            Stepping::Events => 7,
        },
        ..spec
    }
}

/// `n` steps at 1024 steps/s, as steps of `p` (at least 1).
pub fn steps_of<S: Scalar>(p: &Params<S>, n: u32) -> u32 {
    ((n << p.k) >> 10).max(1)
}

/// The distance from point `c` to box `b` (pitch, in f64: the reference the
/// fixed-point geometry is checked against).
fn box_distance<S: Scalar>(c: [f64; 3], b: &Aabb<S>) -> f64 {
    let (lo, hi) = (b.min.to_f64(), b.max.to_f64());
    let d2: f64 = (0..3)
        .map(|a| {
            let v = (lo[a] - c[a]).max(c[a] - hi[a]).max(0.0);
            v * v
        })
        .sum();
    d2.sqrt()
}

/// The centre's distance to the nearest solid tile (pitch), for a centre at `c`.
pub fn clearance_at<S: Scalar>(w: &World<'_, S, 4>, c: Vec3<S>) -> f64 {
    let p = w.params();
    let c = c.to_f64();
    let mut best = f64::INFINITY;
    let t = w.tiles();
    let (i0, i1) = (
        p.layout.index_xz(S::from_f64(c[0]) - p.radius) - 1,
        p.layout.index_xz(S::from_f64(c[0]) + p.radius) + 1,
    );
    let (k0, k1) = (
        p.layout.index_xz(S::from_f64(c[2]) - p.radius) - 1,
        p.layout.index_xz(S::from_f64(c[2]) + p.radius) + 1,
    );
    for k in k0..=k1 {
        for j in 0..t.ny() as i32 {
            for i in i0..=i1 {
                let ti = TileIndex::new(i, j, k);
                if !t.is_solid(ti) {
                    continue;
                }
                best = best.min(box_distance(c, &p.layout.tile_box(ti)));
            }
        }
    }
    best
}

/// Records an event step's flights: the closed form between events, for checks
/// at instants inside a step.
#[derive(Default)]
pub struct Flights<S> {
    pub flights: Vec<(usize, S, S, Segment<S>)>,
}

impl<S: Scalar> StepObserver<S> for Flights<S> {
    fn flight(&mut self, marble: usize, from: S, to: S, seg: &Segment<S>) {
        self.flights.push((marble, from, to, *seg));
    }
}

impl<S: Scalar> Flights<S> {
    /// Every flight's centre at its start, middle and end (pitch), per marble.
    pub fn samples(&self) -> Vec<(usize, Vec3<S>)> {
        let mut v = Vec::new();
        for &(n, from, to, seg) in &self.flights {
            let len = to - from;
            for s in [S::ZERO, len.half(), len] {
                v.push((n, seg.pos_at(s)));
            }
        }
        v
    }
}

/// One step, and the smallest clearance (pitch) of marble `idx` at the end and —
/// with events — at the start, middle and end of every flight inside the step.
pub fn step_checked<S: Scalar>(w: &mut World<'_, S, 4>, idx: usize) -> f64 {
    let mut obs = Flights::default();
    w.step_observed(&mut obs);
    let mut c = min_clearance(w, idx);
    for (n, pos) in obs.samples() {
        if n == idx {
            c = c.min(clearance_at(w, pos));
        }
    }
    c
}

/// A grid from a picture, one character per tile column `[i, *, k]` (row = k):
/// `#` wall (floor and wall tile), `.` floor, `O` hole (nothing).
pub fn grid(rows: &[&str]) -> Grid {
    let nz = rows.len();
    let nx = rows[0].len();
    let mut g = Grid::new(nx, 2, nz).expect("grid dims");
    for (k, row) in rows.iter().enumerate() {
        for (i, ch) in row.bytes().enumerate() {
            match ch {
                b'#' => {
                    g.set(i, 0, k, true);
                    g.set(i, 1, k, true);
                }
                b'.' => {
                    g.set(i, 0, k, true);
                }
                _ => {}
            }
        }
    }
    g
}

/// An open floor of `n × n` tiles with no walls.
pub fn open_floor(n: usize) -> Grid {
    let mut g = Grid::new(n, 2, n).expect("grid dims");
    for k in 0..n {
        for i in 0..n {
            g.set(i, 0, k, true);
        }
    }
    g
}

/// A closed box of `cells × cells` cells with no inner walls.
pub fn closed_box(cells: usize) -> Grid {
    let n = 2 * cells + 1;
    let mut g = open_floor(n);
    for k in 0..n {
        for i in 0..n {
            if i == 0 || k == 0 || i == n - 1 || k == n - 1 {
                g.set(i, 1, k, true);
            }
        }
    }
    g
}

pub fn spec(effects: Effects) -> PhysicsSpec {
    PhysicsSpec {
        effects,
        ..PhysicsSpec::DEFAULT
    }
}

pub fn params<S: Scalar>(spec: PhysicsSpec) -> Params<S> {
    Params::new(spec).expect("valid spec")
}

/// The centre of cell `[i, k]` (both odd) in pitches.
pub fn cell_centre<S: Scalar>(p: &Params<S>, i: i32, k: i32) -> (S, S) {
    let (x0, x1) = p.layout.span_xz(i);
    let (z0, z1) = p.layout.span_xz(k);
    ((x0 + x1).half(), (z0 + z1).half())
}

pub fn world<'a, S: Scalar>(p: Params<S>, g: &'a Grid, starts: &[(S, S)]) -> World<'a, S, 4> {
    World::new(p, g.view(), starts).expect("valid world")
}

/// Whether the marble's centre is closer than `r - tol` to any solid tile.
pub fn min_clearance<S: Scalar>(w: &World<'_, S, 4>, idx: usize) -> f64 {
    let m = w.marbles()[idx];
    let p = w.params();
    let c = m.pos.to_f64();
    let mut best = f64::INFINITY;
    let t = w.tiles();
    for k in 0..t.nz() as i32 {
        for j in 0..t.ny() as i32 {
            for i in 0..t.nx() as i32 {
                let ti = TileIndex::new(i, j, k);
                if !t.is_solid(ti) {
                    continue;
                }
                best = best.min(box_distance(c, &p.layout.tile_box(ti)));
            }
        }
    }
    best
}

/// A tolerance for quantities that go through a square root or a division: the
/// 16-fraction-bit format squares small numbers coarsely and micromath's root is an
/// approximation, so they get a looser bound than the other backends.
pub fn loose<S: Scalar>() -> f64 {
    match S::NAME {
        "i16f16" => 1e-2,
        "f32-micromath" => 5e-2,
        _ => 1e-3,
    }
}

/// A small deterministic generator (no dependency on a seed crate's version).
pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) as u32
    }
    /// Uniform in `lo ..= hi`.
    pub fn range(&mut self, lo: i32, hi: i32) -> i32 {
        lo + (self.next() % (hi - lo + 1) as u32) as i32
    }
}
