//! Named hard cases, in the spirit of Box2D's samples: each a small scene with a
//! precise pass criterion, run for every scalar backend.
mod common;

use common::*;
use marble_rolling::physics::{Effects, PhysicsSpec, Scalar, Vec3, World};

type W4<'a, S> = World<'a, S, 4>;

fn space() -> Effects {
    Effects {
        holes: true,
        rolling: true,
        ..Effects::NONE
    }
}

/// **Ghost bumps, floor.** Rolling fast across the seams of a floor made of 2 × 63
/// tiles in full 3-D: the marble never leaves the floor (y' stays exactly `r`, v_y
/// exactly 0) and keeps its speed (no catch).
fn ghost_bumps_floor<S: Scalar>(st: Stepping) {
    let floor = open_floor(127);
    let p = params::<S>(spec_in(st, space()));
    let start = cell_centre(&p, 1, 63);
    let mut w: W4<'_, S> = world(p, &floor, &[start]);
    let v0 = S::from_int(40);
    w.marbles_mut()[0].vel = Vec3::new(v0, S::ZERO, S::from_int(1));
    for _ in 0..steps_of(&p, 1400) {
        w.step();
        let m = w.marbles()[0];
        assert_eq!(
            m.pos.y,
            p.radius,
            "{}: vertical kick at x = {:?}",
            S::NAME,
            m.pos.x
        );
        assert_eq!(m.vel.y, S::ZERO, "{}", S::NAME);
        assert_eq!(m.vel.x, v0, "{}: caught at x = {:?}", S::NAME, m.pos.x);
    }
    assert!(w.marbles()[0].pos.x.to_f64() > 50.0, "crossed ~100 seams");
}
for_each_backend_and_mode!(ghost_bumps_floor_seams, ghost_bumps_floor);

/// **Ghost bumps, wall.** Pressed against a wall of 60 alternating post and wall
/// tiles and rolled along it: no bounce away from the wall, no catch on the seams.
fn ghost_bumps_wall<S: Scalar>(st: Stepping) {
    let g = closed_box(31);
    let p = params::<S>(spec_in(st, Effects::NONE));
    let start = cell_centre(&p, 1, 1);
    let mut w: W4<'_, S> = world(p, &g, &[start]);
    // Push into the top wall (−z) and along it (+x).
    w.set_gravity_mg([0, -1000, -500]);
    for _ in 0..steps_of(&p, 200) {
        w.step();
    }
    let z_rest = w.marbles()[0].pos.z;
    let wall = p.layout.span_xz(0).1;
    let gap = (z_rest - wall - p.radius).to_f64().abs();
    assert!(gap < 1e-6, "{} resting {gap} off the wall", S::NAME);
    // Settling in bounced a few times; rolling along the wall must not bounce at all.
    let settling_bounces = w.stats.collisions;
    w.set_gravity_mg([100, -1000, -500]);
    let mut last_x = w.marbles()[0].pos.x;
    for _ in 0..steps_of(&p, 4000) {
        w.step();
        let m = w.marbles()[0];
        assert_eq!(
            m.pos.z,
            z_rest,
            "{}: left the wall at x = {:?}",
            S::NAME,
            m.pos.x
        );
        assert_eq!(m.vel.z, S::ZERO, "{}", S::NAME);
        assert!(m.pos.x >= last_x, "{}: caught at {:?}", S::NAME, m.pos.x);
        last_x = m.pos.x;
        if m.pos.x.to_f64() > 25.0 {
            break;
        }
    }
    assert!(
        last_x.to_f64() > 10.0,
        "{}: rolled only to {:?}",
        S::NAME,
        last_x
    );
    assert_eq!(w.stats.collisions, settling_bounces, "{}: bounced", S::NAME);
}
for_each_backend_and_mode!(ghost_bumps_along_a_multi_tile_wall, ghost_bumps_wall);

/// **Skinny wall.** A 0.2 mm wall (1/50 of a cell) hit head-on and diagonally at the
/// speed cap under an 8 g pull, at the lowest and highest step rates the engine
/// accepts: the centre never gets within `3r/4` of the wall, let alone through it.
///
/// With events the speed is the format's top speed (128 pitch/s, 1.2 m/s at this
/// 10.2 mm pitch) at 128 and 1024 steps/s, and the clearance never drops below
/// `r·(1 − 10⁻³)` (`10⁻²` for I16F16 and micromath's root).
fn skinny_wall<S: Scalar>(st: Stepping) {
    let g = grid(&["#####", "#...#", "#.#.#", "#...#", "#####"]);
    let rates: &[u32] = match st {
        Stepping::Fixed => &[6, 10, 14],
        Stepping::Events => &[7, 10],
    };
    for &step_log2 in rates {
        for (gx, gz) in [(8000, 0), (8000, 8000), (-8000, 3000)] {
            let sp = PhysicsSpec {
                short_um: 200,
                long_um: 10_000,
                step_log2,
                stepping: st,
                ..spec(Effects::NONE)
            };
            let p = params::<S>(sp);
            let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 1, 1)]);
            w.set_gravity_mg([gx, -1000, gz]);
            w.marbles_mut()[0].vel = Vec3::new(p.v_max, S::ZERO, p.v_max);
            let floor = match st {
                Stepping::Fixed => 0.75 * p.radius.to_f64() - 1e-6,
                Stepping::Events => p.radius.to_f64() * (1.0 - loose::<S>()),
            };
            for _ in 0..((3000u32 << step_log2) >> 10).max(300) {
                w.step();
                assert!(!w.marbles()[0].out, "{}: escaped", S::NAME);
                let c = min_clearance(&w, 0);
                assert!(c > floor, "{} 2^{step_log2} ({gx},{gz}): {c}", S::NAME);
            }
            assert_eq!(w.stats.reverts, 0);
        }
    }
}
for_each_backend_and_mode!(skinny_wall_is_never_tunnelled, skinny_wall);

/// **Corner pocket.** Pressed diagonally into a corner under a 2 g pull: comes to
/// rest within 2 s, then sits bit-for-bit still (no jitter), never penetrating.
fn corner_pocket<S: Scalar>(st: Stepping) {
    let g = closed_box(3);
    let p = params::<S>(spec_in(
        st,
        Effects {
            rolling: true,
            ..Effects::NONE
        },
    ));
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 3, 3)]);
    w.set_gravity_mg([2000, -1000, 2000]);
    let mut rest_at = None;
    for n in 0..(2 << p.k) {
        w.step();
        let m = w.marbles()[0];
        assert!(
            min_clearance(&w, 0) >= p.radius.to_f64() - 1e-9,
            "{}: penetrates",
            S::NAME
        );
        if m.vel == Vec3::ZERO && rest_at.is_none() {
            rest_at = Some(n);
        }
    }
    assert!(rest_at.is_some(), "{}: never came to rest", S::NAME);
    let still = w.marbles()[0];
    w.set_sleeping(false);
    for _ in 0..steps_of(&p, 10_000) {
        w.step();
        assert_eq!(w.marbles()[0], still, "{}: jitter", S::NAME);
    }
    let (ex, ez) = w.extent();
    let wall = p.layout.s;
    assert!(
        ((ex - wall - still.pos.x) - p.radius).abs().to_f64() < 1e-6,
        "{} x",
        S::NAME
    );
    assert!(
        ((ez - wall - still.pos.z) - p.radius).abs().to_f64() < 1e-6,
        "{} z",
        S::NAME
    );
}
for_each_backend_and_mode!(corner_pocket_comes_to_rest, corner_pocket);

/// **Wedge.** A corridor barely wider than the marble (a 9.9 mm marble in 10 mm
/// cells): it rolls through from end to end, touching both sides, never stuck,
/// never undone, never penetrating more than the resting tolerance.
fn wedge<S: Scalar>(st: Stepping) {
    let g = grid(&["#########", "#.......#", "#########"]);
    let sp = PhysicsSpec {
        radius_um: 4_950,
        ..spec_in(
            st,
            Effects {
                rolling: true,
                ..Effects::NONE
            },
        )
    };
    let p = params::<S>(sp);
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 1, 1)]);
    // Along the corridor and hard into its side, wobbling between the two sides.
    let quarter = steps_of(&p, 256);
    for n in 0..(4 << p.k) {
        if n % quarter == 0 {
            let side = if (n / quarter).is_multiple_of(2) {
                3000
            } else {
                -3000
            };
            w.set_gravity_mg([300, -1000, side]);
        }
        w.step();
        assert!(
            min_clearance(&w, 0) > p.radius.to_f64() - 1e-6,
            "{}: penetrates",
            S::NAME
        );
    }
    let end = cell_centre(&p, 7, 1).0;
    assert!(
        w.marbles()[0].pos.x.to_f64() > end.to_f64() - 0.05,
        "{}: stuck at {:?}",
        S::NAME,
        w.marbles()[0].pos.x
    );
    assert_eq!(w.stats.reverts, 0, "{}", S::NAME);
}
for_each_backend_and_mode!(wedge_barely_wider_than_the_marble, wedge);

/// **Restitution threshold.** `e = 0`: the first impact is a contact, no bounce at all.
/// `e = 1`: above the threshold it bounces back to the same height; below it, it
/// rests (no endless micro-bouncing).
fn restitution_threshold<S: Scalar>(st: Stepping) {
    let floor = open_floor(15);
    for e in [0, 1000] {
        let p = params::<S>(PhysicsSpec {
            restitution_milli: e,
            ..spec_in(st, space())
        });
        let mut w: W4<'_, S> = world(p, &floor, &[cell_centre(&p, 7, 7)]);
        w.marbles_mut()[0].pos.y = p.radius + S::from_f64(0.2);
        w.marbles_mut()[0].supported = false;
        let mut peak_after = 0.0f64;
        let mut landed = false;
        for _ in 0..(1 << p.k) {
            w.step();
            let m = w.marbles()[0];
            landed |= w.stats.contacts > 0;
            if landed {
                peak_after = peak_after.max(m.pos.y.to_f64() - p.radius.to_f64());
            }
        }
        if e == 0 {
            assert_eq!(w.stats.collisions, 0, "{}: e = 0 bounced", S::NAME);
            assert_eq!(peak_after, 0.0, "{}: e = 0 left the floor", S::NAME);
            assert_eq!(w.marbles()[0].vel.y, S::ZERO);
        } else {
            assert!(w.stats.collisions >= 1);
            assert!(
                (peak_after - 0.2).abs() < 0.2 * loose::<S>() * 5.0,
                "{}: e = 1 peak {peak_after}",
                S::NAME
            );
        }
    }
    // Slower than the threshold (20 mm/s): a contact even with e = 1.
    let p = params::<S>(PhysicsSpec {
        restitution_milli: 1000,
        ..spec_in(st, space())
    });
    let mut w: W4<'_, S> = world(p, &floor, &[cell_centre(&p, 7, 7)]);
    w.marbles_mut()[0].pos.y = p.radius + S::from_f64(0.0001);
    w.marbles_mut()[0].supported = false;
    for _ in 0..steps_of(&p, 200) {
        w.step();
    }
    assert_eq!(
        w.stats.collisions,
        0,
        "{}: bounced below the threshold",
        S::NAME
    );
    assert_eq!(w.marbles()[0].pos.y, p.radius);
}
for_each_backend_and_mode!(restitution_threshold_e0_and_e1, restitution_threshold);

/// **Shaking.** Random tilt up to ±4 g on every axis, changed every 8 ms, for two
/// simulated minutes in a closed maze with inner walls: the marble never leaves the
/// maze, never gets inside a wall, is never undone.
fn shaking<S: Scalar>(st: Stepping) {
    let g = grid(&[
        "#########",
        "#.......#",
        "#.#.###.#",
        "#.#...#.#",
        "#.###.#.#",
        "#.......#",
        "#########",
    ]);
    let p = params::<S>(spec_in(
        st,
        Effects {
            rolling: true,
            friction: true,
            ..Effects::NONE
        },
    ));
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 1, 1)]);
    let mut rng = Lcg(42);
    let minutes = 2;
    let (every, check) = (steps_of(&p, 8), steps_of(&p, 64));
    for n in 0..(minutes * 60) << p.k {
        if n % every == 0 {
            w.set_gravity_mg([
                rng.range(-4000, 4000),
                rng.range(-5000, 3000),
                rng.range(-4000, 4000),
            ]);
        }
        w.step();
        if n % check == 0 {
            assert!(!w.marbles()[0].out, "{}: escaped", S::NAME);
            assert!(
                min_clearance(&w, 0) > 0.75 * p.radius.to_f64(),
                "{}: inside a wall",
                S::NAME
            );
        }
    }
    assert_eq!(w.stats.reverts, 0, "{}", S::NAME);
}
for_each_backend_and_mode!(shaking_at_4g_never_escapes, shaking);

/// **Hole edges.** Rolling slowly onto a hole cell drops the marble in; rolling fast
/// across a one-cell hole, it dips by about `g·t²/2` (t = time over the gap) and rolls
/// on; a 2 mm gap between cells is crossed at any speed.
fn hole_edges<S: Scalar>(st: Stepping) {
    // Cells 1, 3, 7, 9 have floor; cell 5 is a hole.
    let g = grid(&["###########", "#....O....#", "###########"]);
    let p = params::<S>(spec_in(st, space()));
    // Slow: a gentle tilt from rest, straight into the hole cell (5, 1).
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 3, 1)]);
    w.set_gravity_mg([30, -1000, 0]);
    for _ in 0..(4 << p.k) {
        w.step();
    }
    assert!(
        w.marbles()[0].out,
        "{}: a slow marble should fall in",
        S::NAME
    );

    // Fast: 60 pitch/s (720 mm/s) over the hole cell (5, 1), no tilt.
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 3, 1)]);
    w.set_gravity_mg([0, -1000, 0]);
    w.marbles_mut()[0].vel.x = S::from_int(60);
    let mut lowest = p.radius.to_f64();
    for _ in 0..steps_of(&p, 60) {
        w.step();
        lowest = lowest.min(w.marbles()[0].pos.y.to_f64());
    }
    let m = w.marbles()[0];
    assert!(!m.out, "{}: a fast marble should cross", S::NAME);
    assert!(
        m.pos.x.to_f64() > cell_centre(&p, 7, 1).0.to_f64() - 0.5,
        "{}: stopped at {:?}",
        S::NAME,
        m.pos.x
    );
    // Free fall while the centre is over the gap: l = 0.833 pitch at 60 pitch/s.
    let t = p.layout.l.to_f64() / 60.0;
    let drop = 0.5 * 9806.65 / 12.0 * t * t;
    let dip = p.radius.to_f64() - lowest;
    assert!(
        dip > 0.0 && dip < 2.0 * drop,
        "{}: dip {dip} vs free fall {drop}",
        S::NAME
    );

    // The 2 mm gap (short tile 8 is a hole) at 3 pitch/s.
    let g2 = grid(&["###########", "#.......O.#", "###########"]);
    let mut w: W4<'_, S> = world(p, &g2, &[cell_centre(&p, 5, 1)]);
    w.marbles_mut()[0].vel.x = S::from_int(3);
    for _ in 0..(1 << p.k) {
        w.step();
    }
    assert!(!w.marbles()[0].out, "{}: fell through a 2 mm gap", S::NAME);
}
for_each_backend_and_mode!(hole_edges_slow_drops_fast_crosses, hole_edges);

/// **Far from origin.** The same roll near the origin and at the far corner of the
/// largest board: the displacements agree to the backend's resolution there.
fn far_from_origin<S: Scalar>(st: Stepping) {
    let floor = open_floor(127);
    let p = params::<S>(spec_in(
        st,
        Effects {
            rolling: true,
            ..Effects::NONE
        },
    ));
    let mut moved = Vec::new();
    for (i, k) in [(3, 3), (95, 95)] {
        let start = cell_centre(&p, i, k);
        let mut w: W4<'_, S> = world(p, &floor, &[start]);
        w.set_gravity_mg([37, -999, 23]);
        for _ in 0..(1 << p.k) {
            w.step();
        }
        let m = w.marbles()[0];
        moved.push(((m.pos.x - start.0).to_f64(), (m.pos.z - start.1).to_f64()));
    }
    let err = (moved[0].0 - moved[1].0)
        .abs()
        .max((moved[0].1 - moved[1].1).abs());
    let mm = err * 12.0;
    println!("{}: displacement mismatch {mm:.2e} mm", S::NAME);
    let bound_mm = match S::NAME {
        "f32" | "f32-micromath" => 0.2, // 60 pitches: one ULP is 0.09 µm, ~1000 steps
        "i16f16" => 0.2,
        _ => 1e-6,
    };
    assert!(mm < bound_mm, "{}: {mm} mm", S::NAME);
}
for_each_backend_and_mode!(far_from_origin_precision_holds, far_from_origin);

/// **Long rest.** Two simulated hours resting in a corner under a constant tilt and
/// on a flat board with friction: not one bit of drift.
fn long_rest<S: Scalar>(st: Stepping) {
    let g = closed_box(2);
    let p = params::<S>(spec_in(
        st,
        Effects {
            rolling: true,
            friction: true,
            ..Effects::NONE
        },
    ));
    for tilt in [[500, -1000, 300], [15, -1000, 8]] {
        let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 1, 1)]);
        w.set_sleeping(false); // the real step every time, not the skip
        w.set_gravity_mg(tilt);
        for _ in 0..(4 << p.k) {
            w.step();
        }
        let settled = w.marbles()[0];
        let hours = if S::NAME == "i8f24" { 2 } else { 1 };
        for _ in 0..(hours * 3600) << p.k {
            w.step();
        }
        assert_eq!(
            w.marbles()[0],
            settled,
            "{} tilt {tilt:?}: drifted",
            S::NAME
        );
    }
}
for_each_backend_and_mode!(long_rest_has_no_drift_or_creep, long_rest);

// ---------------------------------------------------------------------------
// Cases only event stepping makes possible: the format's top speed (128 pitch/s,
// over 1.5 m/s at a 12 mm pitch), no step bound, no speed cap.
// ---------------------------------------------------------------------------

/// Every backend at the event step's default: 128 frames/s.
fn events_spec(effects: Effects) -> PhysicsSpec {
    spec_in(Stepping::Events, effects)
}

/// The speed after `v0`, at most `|v0|`: an elastic bounce never adds speed (up to
/// the rounding of a slanted normal, 10⁻⁶ relative in fixed point).
fn speed<S: Scalar>(v: Vec3<S>) -> f64 {
    let v = v.to_f64();
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The top speed along a direction (pitch/s): 127, the format's range less one.
fn top<S: Scalar>(dx: f64, dz: f64) -> Vec3<S> {
    let n = (dx * dx + dz * dz).sqrt();
    Vec3::new(
        S::from_f64(127.0 * dx / n),
        S::ZERO,
        S::from_f64(127.0 * dz / n),
    )
}

/// **Skinny wall at top speed.** A 0.2 mm wall in a 12 mm pitch hit at 1.52 m/s
/// (the format's top speed), head-on and at angles, elastic and not, under 4 g:
/// never crossed, and the clearance never below `r·(1 − 10⁻³)` — after every step
/// and at the start, middle and end of every flight inside it.
fn skinny_wall_top_speed<S: Scalar>() {
    let g = grid(&["#####", "#...#", "#.#.#", "#...#", "#####"]);
    for e in [1000, 500] {
        for (dx, dz, gx, gz) in [
            (1.0, 0.0, 4000, 0),
            (1.0, 1.0, 0, 0),
            (1.0, 0.3, -4000, 2000),
            (0.2, 1.0, 3000, 3000),
        ] {
            let p = params::<S>(PhysicsSpec {
                short_um: 200,
                long_um: 11_800,
                restitution_milli: e,
                ..events_spec(Effects::NONE)
            });
            let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 1, 1)]);
            w.set_gravity_mg([gx, -1000, gz]);
            w.marbles_mut()[0].vel = top(dx, dz);
            let v0 = speed(w.marbles()[0].vel);
            assert!(
                v0 * 12.0 >= 1500.0,
                "{}: {v0} pitch/s is under 1.5 m/s",
                S::NAME
            );
            let floor = p.radius.to_f64() * (1.0 - loose::<S>());
            for n in 0..(1 << p.k) {
                let c = step_checked(&mut w, 0);
                assert!(!w.marbles()[0].out, "{}: escaped", S::NAME);
                assert!(
                    c >= floor,
                    "{} e {e} ({dx},{dz}) step {n}: clearance {c} < {floor}",
                    S::NAME
                );
                if gx == 0 && gz == 0 && e == 1000 {
                    let v = speed(w.marbles()[0].vel);
                    assert!(v <= v0 * (1.0 + 1e-6), "{}: sped up {v0} → {v}", S::NAME);
                }
            }
            assert!(
                w.stats.collisions > 5,
                "{}: bounced {}",
                S::NAME,
                w.stats.collisions
            );
            assert_eq!(w.stats.reverts, 0, "{}", S::NAME);
            assert_eq!(w.stats.event_limits, 0, "{}", S::NAME);
        }
    }
}
for_each_backend!(skinny_wall_at_top_speed, skinny_wall_top_speed);

/// **A corridor of posts.** Two corridors separated by a row of posts (2 mm posts,
/// 10 mm gaps: the 7 mm marble passes between them), shot diagonally at top speed
/// with `e = 1` on a level board: it bounces off walls, post faces and post corners
/// for two seconds — never inside a tile (at any flight's start, middle or end),
/// never out of the box, never faster than it started.
fn post_corridor<S: Scalar>() {
    let g = grid(&[
        "#########################",
        "#.......................#",
        "#.#.#.#.#.#.#.#.#.#.#.#.#",
        "#.......................#",
        "#########################",
    ]);
    for (dx, dz) in [(1.0, 0.31), (1.0, 0.07), (0.4, 1.0)] {
        let p = params::<S>(PhysicsSpec {
            restitution_milli: 1000,
            ..events_spec(Effects::NONE)
        });
        let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 1, 1)]);
        w.marbles_mut()[0].vel = top(dx, dz);
        let v0 = speed(w.marbles()[0].vel);
        let floor = p.radius.to_f64() * (1.0 - loose::<S>());
        for n in 0..(2 << p.k) {
            let c = step_checked(&mut w, 0);
            let m = w.marbles()[0];
            assert!(!m.out, "{}: escaped", S::NAME);
            assert!(
                c >= floor,
                "{} ({dx},{dz}) step {n}: clearance {c}",
                S::NAME
            );
            let v = speed(m.vel);
            let slack = if S::NAME == "f32-micromath" {
                1e-2
            } else {
                1e-5
            };
            assert!(v <= v0 * (1.0 + slack), "{}: sped up {v0} → {v}", S::NAME);
        }
        assert!(
            w.stats.collisions > 20,
            "{}: {} bounces",
            S::NAME,
            w.stats.collisions
        );
        assert_eq!(w.stats.reverts, 0, "{}", S::NAME);
        assert_eq!(w.stats.event_limits, 0, "{}", S::NAME);
    }
}
for_each_backend!(bounce_down_a_corridor_of_posts, post_corridor);

/// One post at tile (2, 1, 2), free space around it.
fn one_post() -> Grid {
    grid(&[
        "#########",
        "#.......#",
        "#.#.....#",
        "#.......#",
        "#.......#",
        "#########",
    ])
}

/// **Grazing a post's corner** at top speed: aimed to pass a post's corner 2 µm
/// clear it is not touched at all (same velocity to the bit, no contact); aimed
/// 2 µm into it, it is touched once and deflected, never inside the post, never
/// faster.
fn graze<S: Scalar>() {
    let g = one_post();
    let p = params::<S>(PhysicsSpec {
        restitution_milli: 1000,
        ..events_spec(Effects::NONE)
    });
    let post = p
        .layout
        .tile_box(marble_rolling::physics::TileIndex::new(2, 1, 2));
    let r = p.radius.to_f64();
    let um = 1.0 / 12_000.0; // a micrometre in pitches
    for clear in [2.0, -2.0] {
        // Along +x at z = post.max.z + r ± 2 µm, from x well before the post:
        // passing its +z face's far corner region (the corner at (min.x, max.z)).
        let z = post.max.z.to_f64() + r + clear * um;
        let x = post.min.x.to_f64() - 0.5;
        let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 1, 3)]);
        {
            let m = &mut w.marbles_mut()[0];
            m.pos.x = S::from_f64(x);
            m.pos.z = S::from_f64(z);
            m.vel = top(1.0, 0.0);
        }
        let v_in = w.marbles()[0].vel;
        let mut closest = f64::INFINITY;
        // Until it has passed the post (1.2 pitches at 127 pitch/s: 2 frames).
        for _ in 0..2 {
            closest = closest.min(step_checked(&mut w, 0));
        }
        let m = w.marbles()[0];
        if clear > 0.0 {
            assert_eq!(w.stats.contacts, 0, "{}: touched a post 2 µm away", S::NAME);
            assert_eq!(m.vel, v_in, "{}: deflected by a post 2 µm away", S::NAME);
        } else {
            assert_eq!(
                w.stats.contacts,
                1,
                "{}: {} contacts",
                S::NAME,
                w.stats.contacts
            );
            assert!(m.vel.z > S::ZERO, "{}: not deflected: {:?}", S::NAME, m.vel);
            assert!(
                speed(m.vel) <= speed(v_in) * (1.0 + 1e-5),
                "{}: sped up",
                S::NAME
            );
        }
        assert!(
            closest >= r * (1.0 - loose::<S>()),
            "{} clear {clear} µm: clearance {closest}",
            S::NAME
        );
    }
}
for_each_backend!(grazing_a_posts_corner, graze);

/// **The tight corridor.** A marble 20 µm narrower than its one-cell corridors
/// (s = 2, l = 12, r = 5.99 mm), `e = 1`, shaken hard (a random tilt up to ±4 g
/// every 8 ms) through a maze of such corridors for 20 simulated seconds: it bounces
/// from wall to wall in time order and never sinks — the clearance never below
/// `r·(1 − 10⁻³)` after any step or at any flight's start, middle or end — and
/// while a tilt holds, its energy (`½v² − a·p` in the rolling plane) never rises.
fn tight_corridor<S: Scalar>() {
    let g = grid(&[
        "#########",
        "#.......#",
        "#.#.###.#",
        "#.#...#.#",
        "#.###.#.#",
        "#.......#",
        "#########",
    ]);
    let p = params::<S>(PhysicsSpec {
        short_um: 2_000,
        long_um: 12_000,
        radius_um: 5_990,
        restitution_milli: 1000,
        ..events_spec(Effects {
            rolling: true,
            ..Effects::NONE
        })
    });
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 1, 1)]);
    let mut rng = Lcg(7);
    let floor = p.radius.to_f64() * (1.0 - loose::<S>());
    let pitch_mm = p.layout.pitch_um as f64 / 1000.0;
    let energy = |w: &W4<'_, S>, g: [i32; 3]| {
        let k = 9.80665 / pitch_mm * 5.0 / 7.0;
        let m = w.marbles()[0];
        let (v, q) = (m.vel.to_f64(), m.pos.to_f64());
        0.5 * (v[0] * v[0] + v[2] * v[2]) - k * (g[0] as f64 * q[0] + g[2] as f64 * q[2])
    };
    let mut tilt = [0, -1000, 0];
    let mut e0 = energy(&w, tilt);
    let mut most = 0u32;
    for n in 0..(20 << p.k) {
        if n % steps_of(&p, 8) == 0 {
            tilt = [rng.range(-4000, 4000), -1000, rng.range(-4000, 4000)];
            w.set_gravity_mg(tilt);
            e0 = energy(&w, tilt);
        }
        let before = w.stats.events;
        let c = step_checked(&mut w, 0);
        let events = w.stats.events - before;
        most = most.max(events);
        assert!(!w.marbles()[0].out, "{}: escaped", S::NAME);
        assert!(c >= floor, "{} step {n}: clearance {c} < {floor}", S::NAME);
        let e = energy(&w, tilt);
        // Rounding only: every flight ends in a position and a velocity rounded to
        // the format (a few LSB each), worth |a|·δp + |v|·δv of energy.
        let m = w.marbles()[0];
        let lsb = |x: f64| match S::NAME {
            "i8f24" => 2f64.powi(-24),
            "i16f16" => 2f64.powi(-16),
            "i32f32" => 2f64.powi(-32),
            "f64" => x.abs().max(1.0) * f64::EPSILON,
            _ => x.abs().max(1.0) * f32::EPSILON as f64,
        };
        let a = 9.80665 / pitch_mm * 5.0 / 7.0 * 4000.0 * 2f64.sqrt();
        let v = speed(m.vel);
        let per_event = 8.0 * (a * lsb(4.0) + v * lsb(v));
        let slack = (events + 1) as f64 * per_event;
        assert!(
            e <= e0 + slack,
            "{} step {n}: energy {e0} → {e} ({events} events, allowance {slack})",
            S::NAME
        );
    }
    println!(
        "{}: {} bounces, {} events (at most {most} in a step), {} slices",
        S::NAME,
        w.stats.collisions,
        w.stats.events,
        w.stats.slices
    );
    assert!(w.stats.collisions > 100, "{}", S::NAME);
    assert_eq!(w.stats.reverts, 0, "{}", S::NAME);
    assert_eq!(w.stats.event_limits, 0, "{}", S::NAME);
}
for_each_backend!(tight_corridor_elastic_never_sinks, tight_corridor);

/// **Over a slot.** A marble lying still across a 2 mm gap (short tile 8 is a
/// hole), on both of its edges, while a hand on the board changes the pull by a
/// few milli-g every frame: held on the two edges as on a rail, a couple of
/// slices a frame (plain slices bounded by the sink took 64, every frame, and it
/// never fell asleep), never sinking into either edge, never falling through.
fn slot_rest<S: Scalar>() {
    let g = grid(&["###########", "#.......O.#", "###########"]);
    let p = params::<S>(events_spec(space()));
    let (x0, _) = p.layout.span_xz(8);
    let (_, z) = cell_centre(&p, 1, 1);
    let at = Vec3::new(x0 + p.layout.s.half(), p.radius, z);
    let mut w: W4<'_, S> = World::with_centres(p, g.view(), &[at]).expect("valid world");
    w.set_gravity_mg([0, -1000, 0]);
    for _ in 0..256 {
        w.step();
    }
    let before = w.stats;
    let r = p.radius.to_f64();
    for i in 0..256 {
        w.set_gravity_mg([(i % 3) * 4, -1000, (i % 2) * 3 - 1]);
        w.step();
        let c = min_clearance(&w, 0);
        assert!(
            c >= r * (1.0 - 1e-3),
            "{} frame {i}: clearance {c} < r {r}",
            S::NAME
        );
        assert!(!w.marbles()[0].out, "{}: fell through the slot", S::NAME);
    }
    let slices = w.stats.slices - before.slices;
    let events = w.stats.events - before.events;
    println!(
        "{}: {slices} slices, {events} events in 256 frames",
        S::NAME
    );
    assert!(
        slices <= 4 * 256,
        "{}: {slices} slices in 256 frames",
        S::NAME
    );
    assert!(
        events <= 4 * 256,
        "{}: {events} events in 256 frames",
        S::NAME
    );
}
for_each_backend!(slot_rest_is_held_on_both_edges, slot_rest);

/// **Leaving a wall past a seam.** A marble rolling along a wall of many tiles,
/// touching it, its pull drawing it off the wall, crosses the seam between two of
/// the wall's tiles. Within the touching tolerance of the seam the next tile's
/// rounded edge reads as approached (its normal leans along the wall, against the
/// motion), and the ghost-bump rule hands that touch to the wall's face, which
/// the marble is leaving: no touch at all. The step takes at most two events
/// (five before: the touch came back with no time passing until the idle rule's
/// blind slices flew the rest), and the marble rolls on, off the wall, at its
/// speed.
fn leaving_a_wall_past_a_seam<S: Scalar>() {
    let g = closed_box(31);
    let p = params::<S>(events_spec(Effects::NONE));
    let r = p.radius;
    let wall = p.layout.span_xz(0).1;
    let seam = p.layout.span_xz(4).0;
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 3, 1)]);
    w.set_sleeping(false);
    // Off the top wall (+z), gently.
    w.set_gravity_mg([0, -1000, 50]);
    let v = S::from_int(4);
    {
        let m = &mut w.marbles_mut()[0];
        m.pos.x = seam - S::from_f64(0.002);
        m.pos.z = wall + r;
        m.vel = Vec3::new(v, S::ZERO, S::ZERO);
    }
    let (x0, z0) = (w.marbles()[0].pos.x, w.marbles()[0].pos.z);
    let events = w.stats.events;
    w.step();
    let m = w.marbles()[0];
    assert!(
        w.stats.events - events <= 2,
        "{}: {} events in one step past the seam",
        S::NAME,
        w.stats.events - events
    );
    let dt = p.dt().to_f64();
    let dx = (m.pos.x - x0).to_f64();
    assert!(
        (dx - v.to_f64() * dt).abs() < 1e-3 * dx,
        "{}: rolled {dx} pitch along the wall, not {}",
        S::NAME,
        v.to_f64() * dt
    );
    assert!(m.pos.z >= z0, "{}: into the wall", S::NAME);
    assert!(m.vel.z >= S::ZERO, "{}: towards the wall", S::NAME);
}
for_each_backend!(
    leaving_a_wall_past_a_seam_is_no_touch,
    leaving_a_wall_past_a_seam
);

/// **A 2 mm gap at walking pace.** Rolled at 5 pitch/s (60 mm/s) over the 2 mm gap
/// of a missing thin floor tile, the marble dips 0.15 mm (`r − √(r² − (s/2)²)`),
/// rolls round the near rim, strikes the far one and climbs out. A rim holds a
/// marble only while it presses on it: once the far rim's bounce sends it off the
/// near one, the near rim lets it go. (Holding it dropped the bounce's speed away
/// from the near rim and flew the marble back into the far one: it stayed in the
/// gap for good, about two events a step, in four of the six backends.)
fn gap_at_walking_pace<S: Scalar>() {
    let g = grid(&["###########", "#.......O.#", "###########"]);
    let p = params::<S>(events_spec(space()));
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 5, 1)]);
    w.set_sleeping(false);
    w.set_gravity_mg([0, -1000, 0]);
    w.marbles_mut()[0].vel.x = S::from_int(5);
    let beyond = cell_centre(&p, 9, 1).0;
    let mut steps = 0;
    while steps < steps_of(&p, 1000) && w.marbles()[0].pos.x < beyond {
        w.step();
        steps += 1;
    }
    let m = w.marbles()[0];
    assert!(
        !m.out && m.pos.x >= beyond,
        "{}: still at x = {:?} after {steps} steps",
        S::NAME,
        m.pos.x
    );
}
for_each_backend!(a_2_mm_gap_at_walking_pace_is_crossed, gap_at_walking_pace);

/// **Just too fast for a post's corner.** Rolling round the vertical edge of a post
/// 7 % faster than the pull towards the edge can hold it (`v² > r·a_n`), the pull
/// leaning back along the path: the marble leaves the edge, slowly at first, and
/// the pull's lean would bring it back only after the slice (the squared distance's
/// `s³` term, negative, is outweighed by its `s²` term over the slice's length). The
/// step takes at most three events (four or five in the fixed-point formats before:
/// a touch and a plain slice, again and again; sixteen in a step of
/// `maze-2-7x7x2-d9`), and the marble is never in the post.
fn just_too_fast_for_a_corner<S: Scalar>() {
    let g = one_post();
    let p = params::<S>(events_spec(Effects::NONE));
    let post = p
        .layout
        .tile_box(marble_rolling::physics::TileIndex::new(2, 1, 2));
    let r = p.radius.to_f64();
    let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let (nx, nz) = (c, s);
    let (tx, tz) = (-s, c);
    // Touching: within the touching tolerance (`r/16384` or four LSB) of the edge.
    let lsb = (S::ZERO - S::ZERO.next_down()).to_f64();
    let gap = 0.9 * (r / 16384.0).max(4.0 * lsb);
    let cx = post.max.x.to_f64() + (r + gap) * nx;
    let cz = post.max.z.to_f64() + (r + gap) * nz;
    let mut w: W4<'_, S> = world(p, &g, &[(S::from_f64(cx), S::from_f64(cz))]);
    w.set_sleeping(false);
    // 150 mg towards the edge, 100 mg back along the path.
    let (gx, gz) = (-150.0 * nx - 100.0 * tx, -150.0 * nz - 100.0 * tz);
    w.set_gravity_mg([gx.round() as i32, -1000, gz.round() as i32]);
    // The default spec's pitch: 2 mm + 10 mm.
    let pitch_mm = 12.0;
    let a_n = 0.150 * 9806.65 / pitch_mm;
    let v = 1.07 * (r * a_n).sqrt();
    w.marbles_mut()[0].vel = Vec3::new(S::from_f64(v * tx), S::ZERO, S::from_f64(v * tz));
    let events = w.stats.events;
    w.step();
    assert!(
        w.stats.events - events <= 3,
        "{}: {} events in one step",
        S::NAME,
        w.stats.events - events
    );
    assert!(
        min_clearance(&w, 0) > -1e-3 * r,
        "{}: {} pitch into the post",
        S::NAME,
        -min_clearance(&w, 0)
    );
}
for_each_backend!(just_too_fast_for_a_posts_corner, just_too_fast_for_a_corner);

/// **Round a rim from step to step.** A marble tilted gently off the rim of a hole
/// rolls round the rim's edge for several steps before it drops. A step that ends
/// in a pivot slice hands the edge to the next, which goes on round it as a step
/// does after a pivot slice of its own: the edge is touched when the marble comes
/// to it, not again at every step's start (9 touches before, where the roll and
/// the drop need 5), and the marble drops in at the same step.
#[test]
fn round_a_rim_from_step_to_step() {
    type S = marble_rolling::physics::Fx;
    let g = grid(&["###########", "#....O....#", "###########"]);
    let p = params::<S>(events_spec(space()));
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 3, 1)]);
    w.set_sleeping(false);
    w.set_gravity_mg([30, -1000, 0]);
    let mut steps = 0;
    while !w.marbles()[0].out && steps < steps_of(&p, 4000) {
        w.step();
        steps += 1;
    }
    assert!(w.marbles()[0].out, "never dropped in");
    assert!(
        w.stats.contacts <= 5,
        "{} touches in {steps} steps",
        w.stats.contacts
    );
}

/// A tilt past the level's bound is clamped axis by axis, whichever axes are
/// out of it and however far (the world's one clamp on the tilt path).
#[test]
fn a_tilt_past_the_bound_is_clamped_axis_by_axis() {
    let g = closed_box(3);
    type S = fixed::types::I8F24;
    let p = params::<S>(spec_in(Stepping::Events, Effects::NONE));
    let mut w: W4<'_, S> = world(p, &g, &[cell_centre(&p, 3, 3)]);
    let lim = p.mg_max;
    for (tilt, want) in [
        ([i32::MAX, -1000, i32::MIN], [lim, -1000, -lim]),
        ([lim + 1, -(lim + 1), 5], [lim, -lim, 5]),
        ([-lim, lim, 0], [-lim, lim, 0]),
        ([3, i32::MIN, -lim - 7], [3, -lim, -lim]),
        ([0, -1000, 0], [0, -1000, 0]),
    ] {
        w.set_gravity_mg(tilt);
        assert_eq!(w.gravity_mg(), want, "{tilt:?}");
    }
}
