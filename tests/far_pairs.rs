//! Marbles far apart never touch: the pair search of the event stepper must not
//! square a separation beyond the number format's range (in I8F24 `|d|²` leaves
//! it past 11.3 pitch; squared and wrapped, a pair 16 pitches apart once read as
//! touching and took a 1.7 m/s kick). Pairs at the largest separations the level
//! format allows (a 127-tile grid: 63 pitches), along every combination of axes,
//! at the largest speed (127 pitch/s), on every backend, with overflow checks on
//! (the test profile's), in both steppers; the same across the four storeys of
//! the largest 3-D grid (127 × 8 × 127 tiles), where the vertical separation
//! adds to the horizontal ones; and random far pairs against f64.
mod common;

use common::*;
use marble_rolling::physics::geometry::grid::TileGrid;
use marble_rolling::physics::{Effects, Scalar, Vec3, World};
use proptest::prelude::*;

const EFFECTS: Effects = Effects {
    rolling: true,
    friction: false,
    board_motion: false,
    holes: false,
    marbles: true,
};

/// Kinetic energy per unit mass (pitch²/s²) of every marble, in f64.
fn energy<S: Scalar>(w: &World<'_, S, 4>) -> f64 {
    w.marbles()
        .iter()
        .map(|m| m.vel.to_f64().iter().map(|v| v * v).sum::<f64>())
        .sum()
}

/// Two marbles `(ia, ka)`, `(ib, kb)` cells apart on a level open floor of
/// `n × n` tiles, with velocities `va`, `vb` (pitch/s): one frame of steps.
/// Returns the energy before and after, and whether they ever came within
/// reach of each other (they must not, from that far).
fn fly_apart<S: Scalar>(
    stepping: Stepping,
    n: usize,
    a: (i32, i32),
    b: (i32, i32),
    va: [f64; 3],
    vb: [f64; 3],
) -> (f64, f64) {
    let g = open_floor(n);
    let p = params::<S>(spec_in(stepping, EFFECTS));
    let starts = [cell_centre(&p, a.0, a.1), cell_centre(&p, b.0, b.1)];
    let mut w = world(p, &g, &starts);
    w.set_gravity_mg([0, -1000, 0]);
    let v = |v: [f64; 3]| Vec3::new(S::from_f64(v[0]), S::ZERO, S::from_f64(v[2]));
    w.marbles_mut()[0].vel = v(va);
    w.marbles_mut()[1].vel = v(vb);
    let before = energy(&w);
    // One 1/128 s frame: nothing rolls far enough to meet the other marble.
    for _ in 0..steps_of(&p, 8) {
        w.step();
    }
    (before, energy(&w))
}

/// Rolling on a level floor the speed stays (nothing gains); a far "touch"
/// would swap or kick the velocities. `what` names the case.
fn no_far_kick<S: Scalar>(before: f64, after: f64, what: impl Fn() -> String) {
    assert!(
        after <= before * (1.0 + 1e-3) + 1e-6,
        "{} {}: energy {before} → {after}",
        S::NAME,
        what()
    );
    assert!(
        after >= before * 0.9,
        "{} {}: energy {before} → {after} (a far kick?)",
        S::NAME,
        what()
    );
}

fn far_pairs_keep_their_energy<S: Scalar>(stepping: Stepping) {
    // 127 tiles: cells 1 ..= 125 (odd), 62 pitches apart at most.
    let n = 127;
    // Each stepper's own top speed: the format's 127 pitch/s with events, the
    // step bound with fixed steps (faster would be capped, not kicked).
    let v_max = params::<S>(spec_in(stepping, EFFECTS)).v_max.to_f64();
    let top = v_max.min(127.0) / 2f64.sqrt();
    for (a, b) in [
        ((1, 1), (125, 1)),
        ((1, 1), (1, 125)),
        ((1, 1), (125, 125)),
        ((125, 1), (1, 125)),
        ((1, 63), (33, 63)),
    ] {
        // Closing along the line between them, at full and half speed: each
        // stays on the floor for the frame.
        let (dx, dz) = (f64::from(b.0 - a.0), f64::from(b.1 - a.1));
        let len = dx.hypot(dz);
        for speed in [top, top / 2.0] {
            let (ux, uz) = (speed * dx / len, speed * dz / len);
            let (va, vb) = ([ux, 0.0, uz], [-ux, 0.0, -uz]);
            let (before, after) = fly_apart::<S>(stepping, n, a, b, va, vb);
            no_far_kick::<S>(before, after, || {
                format!("{stepping:?} {a:?}–{b:?} at {va:?}/{vb:?}")
            });
        }
    }
}

/// The largest grid the level format takes: 127 × 127 tiles on each of four
/// storeys (slabs `j = 0, 2, 4, 6`, open floors, no walls).
const STOREYS_WORDS: usize = 4033;

fn four_storeys() -> TileGrid<STOREYS_WORDS> {
    let mut g = TileGrid::<STOREYS_WORDS>::new(127, 8, 127).expect("the largest grid");
    for j in [0, 2, 4, 6] {
        for k in 0..127 {
            for i in 0..127 {
                g.set(i, j, k, true);
            }
        }
    }
    g
}

/// Two marbles on the floors of storeys `sa`, `sb` at cells `a`, `b`, closing
/// along their horizontal line at `speed` (pitch/s) for one frame: the energy
/// before and after (pitch²/s²).
fn fly_apart_3d<S: Scalar>(
    stepping: Stepping,
    (a, sa): ((i32, i32), i32),
    (b, sb): ((i32, i32), i32),
    speed: f64,
) -> (f64, f64) {
    let g = four_storeys();
    let effects = Effects {
        holes: true,
        ..EFFECTS
    };
    let p = params::<S>(spec_in(stepping, effects));
    let centre = |c: (i32, i32), storey: i32| {
        let (x, z) = cell_centre(&p, c.0, c.1);
        Vec3::new(x, S::from_int(storey) + p.radius, z)
    };
    let mut w: World<'_, S, 4> = World::with_centres(p, g.view(), &[centre(a, sa), centre(b, sb)])
        .expect("marbles on open floors");
    w.set_gravity_mg([0, -1000, 0]);
    let (dx, dz) = (f64::from(b.0 - a.0), f64::from(b.1 - a.1));
    let len = dx.hypot(dz).max(1.0);
    let (ux, uz) = (speed * dx / len, speed * dz / len);
    let v = |x: f64, z: f64| Vec3::new(S::from_f64(x), S::ZERO, S::from_f64(z));
    w.marbles_mut()[0].vel = v(ux, uz);
    w.marbles_mut()[1].vel = v(-ux, -uz);
    let before = energy(&w);
    for _ in 0..steps_of(&p, 8) {
        w.step();
    }
    (before, energy(&w))
}

/// Every combination of axes at the largest separations of the largest 3-D grid
/// (x and z up to 62 pitches, y up to 3 storeys: `|d|²` up to 7 700 pitch², 60
/// times I8F24's range), at the stepper's top speed and half of it.
fn far_pairs_across_storeys<S: Scalar>(stepping: Stepping) {
    let v_max = params::<S>(spec_in(stepping, EFFECTS)).v_max.to_f64();
    let top = v_max.min(127.0) / 2f64.sqrt();
    let (lo, hi) = (1, 125);
    for (a, b) in [
        (((lo, lo), 0), ((hi, lo), 0)), // x
        (((lo, lo), 0), ((lo, hi), 0)), // z
        (((lo, lo), 0), ((lo, lo), 3)), // y
        (((lo, lo), 0), ((hi, hi), 0)), // x, z
        (((lo, lo), 0), ((hi, lo), 3)), // x, y
        (((lo, lo), 3), ((lo, hi), 0)), // z, y
        (((lo, lo), 0), ((hi, hi), 3)), // x, y, z
        (((hi, lo), 3), ((lo, hi), 0)), // x, y, z, crossed
        (((63, 63), 0), ((63, 63), 2)), // y only, two storeys
    ] {
        for speed in [top, top / 2.0] {
            let (before, after) = fly_apart_3d::<S>(stepping, a, b, speed);
            no_far_kick::<S>(before, after, || {
                format!("{stepping:?} {a:?}–{b:?} at {speed}")
            });
        }
    }
}

fn far_pairs_3d_events<S: Scalar>() {
    far_pairs_across_storeys::<S>(Stepping::Events);
}
fn far_pairs_3d_fixed<S: Scalar>() {
    far_pairs_across_storeys::<S>(Stepping::Fixed);
}
for_each_backend!(far_pairs_across_storeys_with_events, far_pairs_3d_events);
for_each_backend!(
    far_pairs_across_storeys_with_fixed_steps,
    far_pairs_3d_fixed
);

fn far_pairs_events<S: Scalar>() {
    far_pairs_keep_their_energy::<S>(Stepping::Events);
}
fn far_pairs_fixed<S: Scalar>() {
    far_pairs_keep_their_energy::<S>(Stepping::Fixed);
}
for_each_backend!(far_pairs_with_events, far_pairs_events);
for_each_backend!(far_pairs_with_fixed_steps, far_pairs_fixed);

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random pairs at least 3 pitches apart and 2 from the floor's edges, at
    /// random speeds: I8F24 with
    /// events ends the frame where f64 does (within the format's rounding), and
    /// neither changes the energy by more than rounding.
    #[test]
    fn far_pairs_agree_with_f64(
        ia in 2i32..60, ka in 2i32..60, ib in 2i32..60, kb in 2i32..60,
        vax in -120.0f64..120.0, vaz in -120.0f64..120.0,
        vbx in -120.0f64..120.0, vbz in -120.0f64..120.0,
    ) {
        let (a, b) = ((2 * ia + 1, 2 * ka + 1), (2 * ib + 1, 2 * kb + 1));
        prop_assume!((ia - ib).abs().max((ka - kb).abs()) >= 3);
        let (va, vb) = ([vax, 0.0, vaz], [vbx, 0.0, vbz]);
        let (b8, a8) = fly_apart::<fixed::types::I8F24>(Stepping::Events, 127, a, b, va, vb);
        let (b64, a64) = fly_apart::<f64>(Stepping::Events, 127, a, b, va, vb);
        prop_assert!((a8 - a64).abs() <= 1e-3 * b64.max(1.0), "{b8} → {a8} vs f64 {b64} → {a64}");
    }
}
