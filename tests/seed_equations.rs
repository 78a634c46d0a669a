//! The seed's equations, checked against independent computations.
mod common;

use marble_rolling::physics::dynamics::respond::restitution;
use marble_rolling::physics::geometry::broadphase::candidates;
use marble_rolling::physics::geometry::frame::Frame;
use marble_rolling::physics::geometry::narrowphase::{contact, distance, offset, overlaps};
use marble_rolling::physics::geometry::tiles::Aabb;
use marble_rolling::physics::{Scalar, TileIndex, TileLayout, Vec3};

/// Layouts in µm: the default, thin walls, thick walls, an odd ratio.
const LAYOUTS: [(u32, u32); 4] = [
    (2_000, 10_000),
    (200, 10_000),
    (5_000, 5_000),
    (1_700, 8_300),
];

/// Eq. 6 evaluated exactly on integers, as the seed writes it (`s`, `l`, `a` in µm).
fn eq6_exact(a: i64, s: i64, l: i64) -> i32 {
    let p = s + l;
    let m = a.div_euclid(p);
    // ⌊(a − s)/(s+l) − ⌊a/(s+l)⌋⌋ = ⌊(a − s − m·p)/p⌋
    (2 * m + (a - s - m * p).div_euclid(p) + 1) as i32
}

fn eq6_exact_y(b: i64, s: i64, l: i64) -> i32 {
    let p = s + l;
    let m = (b + s).div_euclid(p);
    (2 * m + (b - m * p).div_euclid(p) + 1) as i32
}

/// Eq. 5 → eq. 6 round trip on every boundary: the lower bound of tile `i` is in `i`,
/// the value just below it is in `i − 1`, the midpoint is in `i`. Negative indices
/// and indices far outside any grid included.
fn boundaries_round_trip<S: Scalar>() {
    for (s_um, l_um) in LAYOUTS {
        let lay = TileLayout::<S>::from_um(s_um, l_um).unwrap();
        for i in -40..=160 {
            let (lo, hi) = lay.span_xz(i);
            assert!(lo < hi, "{} tile {i} empty", S::NAME);
            assert_eq!(lay.index_xz(lo), i, "{} x lower bound of {i}", S::NAME);
            assert_eq!(
                lay.index_xz(lo.next_down()),
                i - 1,
                "{} just below {i}",
                S::NAME
            );
            assert_eq!(
                lay.index_xz(hi.next_down()),
                i,
                "{} just below upper bound of {i}",
                S::NAME
            );
            assert_eq!(
                lay.index_xz(lo + (hi - lo).half()),
                i,
                "{} midpoint of {i}",
                S::NAME
            );
            // The next tile starts where this one ends (edge to edge, eq. 5).
            assert_eq!(lay.span_xz(i + 1).0, hi);
        }
        for j in -10..=10 {
            let (lo, hi) = lay.span_y(j);
            assert_eq!(lay.index_y(lo), j, "{} y lower bound of {j}", S::NAME);
            assert_eq!(
                lay.index_y(lo.next_down()),
                j - 1,
                "{} y just below {j}",
                S::NAME
            );
            assert_eq!(
                lay.index_y(lo + (hi - lo).half()),
                j,
                "{} y midpoint {j}",
                S::NAME
            );
            assert_eq!(lay.span_y(j + 1).0, hi);
        }
        // The floor slab is [-s, 0), the wall layer [0, l).
        assert_eq!(lay.span_y(0), (-lay.s, S::ZERO));
        assert_eq!(lay.span_y(1), (S::ZERO, lay.l));
        assert_eq!(lay.span_xz(0), (S::ZERO, lay.s));
        assert_eq!(lay.span_xz(1), (lay.s, S::ONE));
    }
}
for_each_backend!(eq5_eq6_boundaries_round_trip, boundaries_round_trip);

/// Eq. 6 in pitch units agrees with the seed's formula evaluated exactly on integer
/// micrometres, for points inside and far outside the grid, negative ones included.
fn agrees_with_integer_eq6<S: Scalar>() {
    for (s_um, l_um) in LAYOUTS {
        let lay = TileLayout::<S>::from_um(s_um, l_um).unwrap();
        let p = (s_um + l_um) as i64;
        let mut a = -30 * p;
        while a <= 70 * p {
            let x = lay.from_um_len(a);
            // Floats round the point; skip the few µm where rounding may cross a boundary.
            let (lo, hi) = lay.span_xz(lay.index_xz(x));
            let (ylo, yhi) = lay.span_y(lay.index_y(x));
            let gap = [lo, hi, ylo, yhi]
                .iter()
                .map(|b| (x.to_f64() - b.to_f64()).abs())
                .fold(f64::INFINITY, f64::min);
            let near = gap * (p as f64) < 1e-3 && !S::NAME.starts_with('i');
            if !near {
                assert_eq!(
                    lay.index_xz(x),
                    eq6_exact(a, s_um as i64, l_um as i64),
                    "{} x at {a} µm",
                    S::NAME
                );
                assert_eq!(
                    lay.index_y(x),
                    eq6_exact_y(a, s_um as i64, l_um as i64),
                    "{} y at {a} µm",
                    S::NAME
                );
            }
            a += 137; // a step that is not a divisor of any layout: hits every phase
        }
    }
}
for_each_backend!(
    eq6_matches_exact_integer_evaluation,
    agrees_with_integer_eq6
);

/// Eq. 7: the candidates cover every tile the marble's bounding box touches, and
/// nothing further.
fn candidates_cover_bounding_box<S: Scalar>() {
    let lay = TileLayout::<S>::from_um(2_000, 10_000).unwrap();
    let r = lay.from_um_len(3_500);
    let mut seed = 12345u64;
    for _ in 0..2000 {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let fx = ((seed >> 33) % 100_000) as f64 / 1000.0 - 10.0;
        let fz = ((seed >> 13) % 100_000) as f64 / 1000.0 - 10.0;
        let fy = ((seed >> 43) % 3000) as f64 / 1000.0 - 1.0;
        let c = Vec3::new(S::from_f64(fx), S::from_f64(fy), S::from_f64(fz));
        let range = candidates(&lay, c, r);
        for t in range.iter() {
            assert!(t.i >= range.lo.i && t.i <= range.hi.i);
        }
        // The tile of every corner of the bounding box is inside the range.
        for (dx, dy, dz) in [(-1, -1, -1), (1, 1, 1), (-1, 1, 1), (1, -1, -1)] {
            let sgn = |d: i32| if d < 0 { -r } else { r };
            let p = Vec3::new(c.x + sgn(dx), c.y + sgn(dy), c.z + sgn(dz));
            let t = lay.index_of(p);
            assert!(
                t.i >= range.lo.i && t.i <= range.hi.i && t.j >= range.lo.j && t.j <= range.hi.j
            );
        }
        // And every tile in the range intersects the bounding box (closed).
        for t in range.iter() {
            let b = lay.tile_box(t);
            assert!(
                b.max.x >= c.x - r && b.min.x <= c.x + r,
                "{} tile {t:?} outside box",
                S::NAME
            );
        }
    }
}
for_each_backend!(
    eq7_candidates_cover_the_bounding_box,
    candidates_cover_bounding_box
);

/// Eq. 8 against a brute-force closest point: the minimum distance over a dense grid
/// of points of the box (surface and interior).
#[test]
fn eq8_matches_brute_force_closest_point() {
    let b = Aabb {
        min: Vec3::new(1.0, -0.25, 2.0),
        max: Vec3::new(1.5, 0.75, 2.25),
    };
    let n = 40;
    let mut seed = 7u64;
    for _ in 0..300 {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let u = |s: u64, lo: f64, hi: f64| lo + (s % 10_000) as f64 / 10_000.0 * (hi - lo);
        let c = Vec3::new(
            u(seed >> 11, 0.0, 2.5),
            u(seed >> 24, -1.0, 1.5),
            u(seed >> 37, 1.0, 3.0),
        );
        let r = 0.3;
        let mut brute = f64::INFINITY;
        for a in 0..=n {
            for bb in 0..=n {
                for cc in 0..=n {
                    let t = |lo: f64, hi: f64, q: i32| lo + (hi - lo) * q as f64 / n as f64;
                    let p = [
                        t(b.min.x, b.max.x, a),
                        t(b.min.y, b.max.y, bb),
                        t(b.min.z, b.max.z, cc),
                    ];
                    let d =
                        ((c.x - p[0]).powi(2) + (c.y - p[1]).powi(2) + (c.z - p[2]).powi(2)).sqrt();
                    brute = brute.min(d);
                }
            }
        }
        let grid_step = ((0.5f64 / n as f64).powi(2)
            + (1.0f64 / n as f64).powi(2)
            + (0.25f64 / n as f64).powi(2))
        .sqrt();
        let d = distance(c, r, &b) + r;
        assert!(
            d <= brute + 1e-12,
            "eq8 {d} larger than a point of the box {brute}"
        );
        assert!(brute - d <= grid_step, "eq8 {d} vs brute {brute}");
        assert_eq!(overlaps(c, r, &b), d < r);
    }
}

/// Eq. 8 per backend: the six per-face terms of the seed, summed, equal |offset|².
fn eq8_terms<S: Scalar>() {
    let lay = TileLayout::<S>::from_um(2_000, 10_000).unwrap();
    let b = lay.tile_box(TileIndex::new(3, 1, 4));
    for (x, y, z) in [
        (0.9, 0.3, 2.1),
        (1.5, 0.3, 2.1),
        (1.2, 1.0, 2.5),
        (1.0, -0.2, 1.9),
        (1.1, 0.3, 2.1),
    ] {
        let c = Vec3::new(S::from_f64(x), S::from_f64(y), S::from_f64(z));
        let pos = |v: S| if v > S::ZERO { v } else { S::ZERO };
        let terms = [
            pos(c.x - b.max.x),
            pos(b.min.x - c.x),
            pos(c.y - b.max.y),
            pos(b.min.y - c.y),
            pos(c.z - b.max.z),
            pos(b.min.z - c.z),
        ];
        let sum: f64 = terms.iter().map(|t| t.to_f64() * t.to_f64()).sum();
        let d2 = offset(c, &b).to_f64().iter().map(|v| v * v).sum::<f64>();
        assert!((sum - d2).abs() < 1e-9, "{}: {sum} vs {d2}", S::NAME);
    }
}
for_each_backend!(eq8_is_the_sum_of_the_six_face_terms, eq8_terms);

/// The contact normal and depth when the centre is on a face, an edge, a corner and
/// inside the box: always unit length, pointing out of an exposed face.
fn contact_on_features<S: Scalar>() {
    let g = common::grid(&["...", ".#.", "..."]);
    let lay = TileLayout::<S>::from_um(2_000, 10_000).unwrap();
    let r = lay.from_um_len(3_500);
    let t = TileIndex::new(1, 1, 1); // the wall tile in the middle
    let b = lay.tile_box(t);
    let f = S::from_f64;
    let mid = |lo: S, hi: S| (lo + hi).half();
    let cases = [
        // (centre, expected normal) — on the +x face, on the +x/+z edge, inside.
        (
            Vec3::new(b.max.x, mid(b.min.y, b.max.y), mid(b.min.z, b.max.z)),
            [1.0, 0.0, 0.0],
        ),
        (
            Vec3::new(
                b.min.x + f(0.01),
                mid(b.min.y, b.max.y),
                mid(b.min.z, b.max.z),
            ),
            [-1.0, 0.0, 0.0],
        ),
        (
            Vec3::new(b.max.x + f(0.1), mid(b.min.y, b.max.y), b.max.z + f(0.1)),
            [
                core::f64::consts::FRAC_1_SQRT_2,
                0.0,
                core::f64::consts::FRAC_1_SQRT_2,
            ],
        ),
        (
            Vec3::new(mid(b.min.x, b.max.x), b.max.y + f(0.01), b.min.z - f(0.05)),
            [0.0, 0.19611614, -0.98058068],
        ),
    ];
    for (c, want) in cases {
        let got = contact(c, r, t, &b, g.view()).expect("contact");
        let n = got.normal.to_f64();
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!(
            (len - 1.0).abs() < common::loose::<S>(),
            "{} normal length {len}",
            S::NAME
        );
        for a in 0..3 {
            assert!(
                (n[a] - want[a]).abs() < 2.0 * common::loose::<S>(),
                "{}: normal {n:?}, want {want:?}",
                S::NAME
            );
        }
        assert!(got.depth > S::ZERO);
    }
    // A corner exactly on the centre: still a unit normal and a positive depth.
    let c = Vec3::new(b.max.x, b.max.y, b.max.z);
    let got = contact(c, r, t, &b, g.view()).expect("corner contact");
    assert!(got.depth >= r);
}
for_each_backend!(
    contact_normals_on_faces_edges_corners_and_inside,
    contact_on_features
);

/// Eq. 1 worked examples, including a moving board.
fn eq1_examples<S: Scalar>() {
    let v = |x: f64, y: f64, z: f64| Vec3::new(S::from_f64(x), S::from_f64(y), S::from_f64(z));
    let close = |a: Vec3<S>, b: [f64; 3]| {
        let a = a.to_f64();
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-4)
    };
    let up = v(0.0, 1.0, 0.0);
    // Straight down onto a still board, e = 0.5: bounces up at half speed.
    assert!(close(
        restitution(v(0.0, -2.0, 0.0), v(0.0, 0.0, 0.0), up, S::from_f64(0.5)),
        [0.0, 1.0, 0.0]
    ));
    // Oblique, e = 1: the tangential part is kept, the normal part reversed.
    assert!(close(
        restitution(v(3.0, -2.0, 1.0), Vec3::ZERO, up, S::ONE),
        [3.0, 2.0, 1.0]
    ));
    // e = 0: the normal part is removed.
    assert!(close(
        restitution(v(3.0, -2.0, 1.0), Vec3::ZERO, up, S::ZERO),
        [3.0, 0.0, 1.0]
    ));
    // A board rising at 1 under a marble at rest, e = 1: v' = 0 − 2·(0 − 1)·n = 2 up.
    assert!(close(
        restitution(Vec3::ZERO, v(0.0, 1.0, 0.0), up, S::ONE),
        [0.0, 2.0, 0.0]
    ));
    // A board rising at 1, marble falling at 1, e = 0.5: (v−v_b)·n = −2 → v' = −1 + 3 = 2.
    assert!(close(
        restitution(v(0.0, -1.0, 0.0), v(0.0, 1.0, 0.0), up, S::from_f64(0.5)),
        [0.0, 2.0, 0.0]
    ));
    // A wall moving sideways (along its own plane) does nothing to the normal part.
    let wall = v(-1.0, 0.0, 0.0);
    assert!(close(
        restitution(v(-1.0, 0.0, 0.5), v(0.0, 0.0, 3.0), wall, S::ONE),
        [1.0, 0.0, 0.5]
    ));
    // A 45° normal.
    let h = 0.5f64.sqrt();
    let n = v(h, h, 0.0);
    assert!(close(
        restitution(v(-1.0, -1.0, 0.0), Vec3::ZERO, n, S::ONE),
        [1.0, 1.0, 0.0]
    ));
}
for_each_backend!(eq1_restitution_worked_examples, eq1_examples);

/// Eq. 4: world → tile → world round trip, orthonormality, and the transpose used
/// as the inverse.
fn eq4_frames<S: Scalar>() {
    let f = S::from_f64;
    let frame = Frame::rotated(
        Vec3::new(f(0.1), f(-0.05), f(0.2)),
        Vec3::new(f(3.0), f(0.0), f(2.0)),
    );
    for a in 0..3 {
        for b in 0..3 {
            let d = frame.basis[a].dot(frame.basis[b]).to_f64();
            let want = if a == b { 1.0 } else { 0.0 };
            assert!(
                (d - want).abs() < common::loose::<S>(),
                "{} basis {a}.{b} = {d}",
                S::NAME
            );
        }
    }
    for p in [[0.0, 0.0, 0.0], [1.0, 0.5, -2.0], [10.0, 0.3, 7.5]] {
        let w = Vec3::new(f(p[0]), f(p[1]), f(p[2]));
        let back = frame.to_world(frame.to_tile(w)).to_f64();
        for a in 0..3 {
            assert!(
                (back[a] - p[a]).abs() < 5.0 * common::loose::<S>(),
                "{} round trip {p:?} → {back:?}",
                S::NAME
            );
        }
    }
    // The pivot maps to itself.
    let pivot = frame.to_tile(Vec3::new(f(3.0), f(0.0), f(2.0))).to_f64();
    let tol = 10.0 * common::loose::<S>();
    assert!((pivot[0] - 3.0).abs() < tol && pivot[1].abs() < tol && (pivot[2] - 2.0).abs() < tol);
    // The identity frame is exact.
    let id = Frame::<S>::identity();
    let w = Vec3::new(f(1.25), f(-0.5), f(7.0));
    assert_eq!(id.to_tile(w), w);
}
for_each_backend!(eq4_world_tile_frame_round_trip, eq4_frames);
