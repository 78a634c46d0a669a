//! The tilt input path (src/input/tilt.rs): accelerometer reading → gravity.

use marble_rolling::input::sensor::{AccelMg, Axis, Calibration, Fault, Plausibility};
use marble_rolling::input::tilt::{GravityMg, TiltConfig, TiltError, TiltFilter, MAX_READING_MG};
use marble_rolling::physics::range::MAX_MG;
use proptest::prelude::*;

/// Tiny zero-mean in-plane noise (±2 mg, a period of 5 samples) so that a long run
/// of a steady pose is not taken for a stuck sensor, as on real hardware.
fn noisy(r: AccelMg, n: usize) -> AccelMg {
    const NOISE: [i32; 5] = [0, 1, -2, 2, -1];
    AccelMg::new(r.x + NOISE[n % 5], r.y, r.z + NOISE[(n + 2) % 5])
}

/// Feeds `n` noisy samples of `r`, all of which must be accepted.
fn settle(f: &mut TiltFilter, r: AccelMg, n: usize) -> GravityMg {
    let mut g = f.gravity_mg();
    for i in 0..n {
        g = f.push(noisy(r, i)).expect("good sample");
    }
    g
}

/// No dead zone, no stuck check, ±16 g accepted: the bare low-pass.
fn bare(shift: u8) -> TiltFilter {
    TiltFilter::new(TiltConfig {
        plausibility: Some(Plausibility {
            max_axis_mg: 16_000,
            min_total_mg: 300,
            max_total_mg: 30_000,
        }),
        filter_shift: shift,
        dead_zone_mg: 0,
        stuck_samples: 0,
        ..TiltConfig::DEFAULT
    })
}

#[test]
fn level_before_first_sample() {
    let f = TiltFilter::default();
    assert_eq!(f.gravity_mg(), GravityMg::new(0, -1000, 0));
    assert_eq!(f.filtered_reading_mg(), AccelMg::new(0, 1000, 0));
}

#[test]
fn flat_board_settles_to_down() {
    let mut f = TiltFilter::default();
    // Start tilted, then lie flat: the filter must forget the tilt.
    settle(&mut f, AccelMg::new(-300, 950, 200), 10);
    assert_ne!(f.gravity_mg(), GravityMg::new(0, -1000, 0));
    let g = settle(&mut f, AccelMg::new(0, 1000, 0), 200);
    assert_eq!(g, GravityMg::new(0, -1000, 0));
    assert_eq!(f.gravity_mg(), g);
}

#[test]
fn negative_x_reading_rolls_towards_plus_x() {
    let mut f = TiltFilter::default();
    let g = settle(&mut f, AccelMg::new(-300, 950, 0), 100);
    assert!(g.x > 0, "{g:?}");
    assert_eq!(g.x, 300, "the reading itself: no dead zone");
    assert_eq!(g.z, 0);
    assert_eq!(g.y, -950);
    let g = settle(&mut f, AccelMg::new(300, 950, 0), 100);
    assert!(g.x < 0, "{g:?}");
}

#[test]
fn negative_z_reading_rolls_towards_plus_z() {
    let mut f = TiltFilter::default();
    let g = settle(&mut f, AccelMg::new(0, 950, -300), 100);
    assert!(g.z > 0, "{g:?}");
    assert_eq!(g.x, 0);
    let g = settle(&mut f, AccelMg::new(0, 950, 300), 100);
    assert!(g.z < 0, "{g:?}");
}

#[test]
fn calibrating_a_tilted_board_makes_it_level() {
    let mut f = TiltFilter::default();
    let tilted = AccelMg::new(-259, 966, 150); // ~15° right edge down, a little towards the player
    settle(&mut f, tilted, 100);
    assert!(f.gravity_mg().x > 200);
    let c = f.calibrate(tilted).expect("plausible");
    assert_eq!(
        c,
        Calibration {
            offset_x: -259,
            offset_z: 150
        }
    );
    assert_eq!(f.calibration(), c);
    // Takes effect at once, and stays level while the board stays there.
    assert_eq!(f.gravity_mg(), GravityMg::new(0, -966, 0));
    assert_eq!(settle(&mut f, tilted, 100), GravityMg::new(0, -966, 0));
    // Tilting further from the new level rolls as usual.
    let g = settle(&mut f, AccelMg::new(-459, 900, 150), 100);
    assert_eq!(g.x, 200);
    // Calibrating again replaces the offset instead of stacking it.
    f.calibrate(AccelMg::new(0, 1000, 0)).unwrap();
    assert_eq!(f.calibration(), Calibration::NONE);
    // Levelling the filtered (noise-free) orientation works the same way.
    settle(&mut f, tilted, 100);
    f.calibrate(f.filtered_reading_mg()).unwrap();
    assert_eq!(f.gravity_mg(), GravityMg::new(0, -966, 0));
}

#[test]
fn calibration_is_clamped_and_refuses_garbage() {
    let mut f = TiltFilter::default();
    let c = f.calibrate(AccelMg::new(-900, 400, 0)).unwrap();
    assert_eq!(c.offset_x, -Calibration::MAX_OFFSET_MG);
    f.set_calibration(Calibration {
        offset_x: 7,
        offset_z: -3,
    });
    for bad in [
        AccelMg::new(0, 0, 0),
        AccelMg::new(i32::MIN, 1000, 0),
        AccelMg::new(0, 100, 0),
    ] {
        assert!(f.calibrate(bad).is_err(), "{bad:?}");
        assert_eq!(
            f.calibration(),
            Calibration {
                offset_x: 7,
                offset_z: -3
            }
        );
    }
    f.set_calibration(Calibration {
        offset_x: i32::MIN,
        offset_z: i32::MAX,
    });
    assert_eq!(
        f.calibration(),
        Calibration {
            offset_x: -Calibration::MAX_OFFSET_MG,
            offset_z: Calibration::MAX_OFFSET_MG
        }
    );
}

#[test]
fn default_path_passes_every_tilt_unchanged() {
    // No dead zone by default: every in-plane reading, however small, reaches the
    // physics as it is (a resting marble is held by rolling resistance instead).
    assert_eq!(TiltConfig::DEFAULT.dead_zone_mg, 0);
    let mut f = TiltFilter::new(TiltConfig {
        filter_shift: 0,
        stuck_samples: 0,
        ..TiltConfig::DEFAULT
    });
    for x in -600..=600 {
        let g = f.push(AccelMg::new(x, 1000, -x)).unwrap();
        assert_eq!(g, GravityMg::new(-x, -1000, x), "x = {x}");
    }
}

#[test]
fn dead_zone_zeroes_small_tilts_and_ramps_back_to_identity() {
    let cfg = TiltConfig {
        filter_shift: 0,
        stuck_samples: 0,
        dead_zone_mg: 20,
        ..TiltConfig::DEFAULT
    };
    let mut f = TiltFilter::new(cfg);
    let mut prev: Option<i32> = None;
    for x in -100..=100i32 {
        let g = f.push(AccelMg::new(x, 1000, -x)).unwrap();
        // 0 inside ±20, 2(|x| − 20) from 20 to 40, the reading itself beyond.
        let mag = match x.abs() {
            a if a <= 20 => 0,
            a if a < 40 => 2 * (a - 20),
            a => a,
        };
        let expect = -x.signum() * mag;
        assert_eq!(g.x, expect, "x = {x}");
        assert_eq!(g.z, -expect, "z = {}", -x);
        if x.abs() >= 40 {
            assert_eq!(g.x, -x, "identity beyond twice the width, x = {x}");
        }
        // Never further from the identity than the width.
        assert!((g.x + x).abs() <= 20, "x = {x}");
        // Continuous: the ramp's slope is 2, so 1 mg in moves at most 2 mg out.
        if let Some(p) = prev {
            assert!((g.x - p).abs() <= 2, "jump at x = {x}");
        }
        prev = Some(g.x);
    }
    // Just inside / outside the edges.
    assert_eq!(f.push(AccelMg::new(-20, 1000, 0)).unwrap().x, 0);
    assert_eq!(f.push(AccelMg::new(-21, 1000, 0)).unwrap().x, 2);
    assert_eq!(f.push(AccelMg::new(-39, 1000, 0)).unwrap().x, 38);
    assert_eq!(f.push(AccelMg::new(-40, 1000, 0)).unwrap().x, 40);
}

/// Samples until the output first reaches 63.2 % of a step from 0 to 1000.
fn samples_to_63_percent(shift: u8, sign: i32) -> usize {
    let mut f = bare(shift);
    f.push(AccelMg::new(0, 1000, 0)).unwrap();
    for n in 1..10_000 {
        let g = f.push(AccelMg::new(-sign * 1000, 1000, 0)).unwrap();
        if g.x * sign >= 632 {
            return n;
        }
    }
    panic!("never reached 63 %");
}

#[test]
fn step_response_reaches_63_percent_after_time_constant() {
    for shift in 0..=6u8 {
        let cfg = TiltConfig {
            filter_shift: shift,
            ..TiltConfig::DEFAULT
        };
        // The documented τ in samples (period 1 000 000 µs = 1 sample).
        let tau = cfg.time_constant_us(1_000_000) as f64 / 1e6;
        for sign in [1, -1] {
            let n = samples_to_63_percent(shift, sign) as f64;
            assert!(
                (n - tau).abs() <= 1.0,
                "shift {shift}: τ {tau}, reached after {n}"
            );
        }
    }
    // The default: 75 ms at 100 Hz.
    assert_eq!(TiltConfig::DEFAULT.time_constant_us(10_000), 75_000);
}

#[test]
fn low_pass_converges_exactly_without_truncation_error() {
    for shift in [1u8, 3, 5, 8] {
        for target in [1, -1, 7, -7, 333, -333, 1999, -1999, 4000, -4000] {
            for start in [0, 1, -1, 2000, -2000] {
                let mut f = bare(shift);
                f.push(AccelMg::new(start, 1000, -start)).unwrap();
                let mut g = GravityMg::LEVEL;
                for _ in 0..20_000 {
                    g = f.push(AccelMg::new(target, 1000, -target)).unwrap();
                }
                assert_eq!(
                    g,
                    GravityMg::new(-target, -1000, target),
                    "shift {shift}, {start} → {target}"
                );
                assert_eq!(f.filtered_reading_mg(), AccelMg::new(target, 1000, -target));
            }
        }
    }
}

#[test]
fn slow_low_pass_has_no_dead_band() {
    // With a long time constant, a truncating step (floor of d · 2^-k) would
    // stall up to 2^k fractional units short of a target approached from
    // below (≈ 1 mg at shift 12, 8 mg at shift 15).
    for shift in [12u8, 15] {
        for target in [1, -1, 333, -333] {
            for start in [0, 1000, -1000] {
                let mut f = bare(shift);
                f.push(AccelMg::new(start, 1000, 0)).unwrap();
                for _ in 0..(20usize << shift) {
                    f.push(AccelMg::new(target, 1000, 0)).unwrap();
                }
                assert_eq!(
                    f.filtered_reading_mg().x,
                    target,
                    "shift {shift}, {start} → {target}"
                );
                assert_eq!(f.gravity_mg().x, -target);
            }
        }
    }
}

#[test]
fn output_rounds_to_nearest_mg_symmetrically() {
    for sign in [1, -1] {
        let mut f = bare(1);
        f.push(AccelMg::new(0, 1000, 0)).unwrap();
        // Half way to 1 mg: 0.5 mg rounds away from zero, both signs.
        assert_eq!(f.push(AccelMg::new(sign, 1000, 0)).unwrap().x, -sign);
        assert_eq!(f.filtered_reading_mg().x, sign);
    }
}

#[test]
fn implausible_samples_are_rejected_and_output_unchanged() {
    let mut f = TiltFilter::default();
    let before = settle(&mut f, AccelMg::new(-300, 950, 100), 50);
    let cases: [([i32; 3], TiltError); 7] = [
        ([0, 0, 0], TiltError::AllZero),
        (
            [4001, 0, 0],
            TiltError::OutOfRange {
                axis: Axis::X,
                value: 4001,
            },
        ),
        (
            [0, -4001, 0],
            TiltError::OutOfRange {
                axis: Axis::Y,
                value: -4001,
            },
        ),
        (
            [0, 1000, i32::MIN],
            TiltError::OutOfRange {
                axis: Axis::Z,
                value: i32::MIN,
            },
        ),
        (
            [i32::MAX, i32::MAX, i32::MAX],
            TiltError::OutOfRange {
                axis: Axis::X,
                value: i32::MAX,
            },
        ),
        (
            [0, 100, 0],
            TiltError::Magnitude {
                squared_mg2: 10_000,
            },
        ),
        (
            [2500, 2500, 0],
            TiltError::Magnitude {
                squared_mg2: 12_500_000,
            },
        ),
    ];
    for (bad, err) in cases {
        let snapshot = f;
        assert_eq!(f.push(AccelMg::from_array(bad)), Err(err), "{bad:?}");
        assert_eq!(f.gravity_mg(), before);
        assert_eq!(f.filtered_reading_mg(), snapshot.filtered_reading_mg());
    }
    assert_eq!(Fault::from(TiltError::AllZero), Fault::Implausible);
    assert_eq!(Fault::from(TiltError::Stuck), Fault::NoData);
}

#[test]
fn stuck_sensor_is_reported_and_last_good_kept() {
    let mut f = TiltFilter::default();
    settle(&mut f, AccelMg::new(-300, 950, 100), 30);
    let frozen = AccelMg::new(-150, 980, 40);
    let mut last = f.gravity_mg();
    for i in 1..=120 {
        let r = f.push(frozen);
        if i < 50 {
            last = r.expect("not stuck yet");
        } else {
            assert_eq!(r, Err(TiltError::Stuck), "sample {i}");
            assert!(f.is_stuck());
            assert_eq!(f.gravity_mg(), last, "last good gravity stays");
        }
    }
    // The sensor comes back: the first different sample is used.
    assert!(f.push(AccelMg::new(-151, 980, 40)).is_ok());
    assert!(!f.is_stuck());
    // Disabled when stuck_samples < 2.
    let mut f = TiltFilter::new(TiltConfig {
        stuck_samples: 1,
        ..TiltConfig::DEFAULT
    });
    for _ in 0..1000 {
        assert!(f.push(frozen).is_ok());
    }
}

#[test]
fn saturated_full_scale_readings_are_consistent() {
    // The firmware's ±2 g range saturates at -2048..=2047 mg: always accepted
    // per axis, and passed through exactly.
    let mut f = bare(0);
    assert_eq!(
        f.push(AccelMg::new(-2048, 1000, 0)),
        Ok(GravityMg::new(2048, -1000, 0))
    );
    assert_eq!(
        f.push(AccelMg::new(2047, 1000, -2048)),
        Ok(GravityMg::new(-2047, -1000, 2048))
    );
    // Exactly at the configured full scale: accepted; one above: rejected,
    // the same on every axis and both signs.
    let p = Plausibility {
        max_axis_mg: 2000,
        min_total_mg: 300,
        max_total_mg: 3000,
    };
    let mut f = TiltFilter::new(TiltConfig {
        plausibility: Some(p),
        filter_shift: 0,
        dead_zone_mg: 0,
        ..TiltConfig::DEFAULT
    });
    for axis in 0..3 {
        for s in [1, -1] {
            let mut r = [0, 0, 0];
            r[axis] = 2000 * s;
            r[(axis + 1) % 3] = 500;
            let [x, y, z] = r.map(|v| -v);
            assert_eq!(
                f.push(AccelMg::from_array(r)),
                Ok(GravityMg::new(x, y, z)),
                "{r:?}"
            );
            r[axis] = 2001 * s;
            let ax = [Axis::X, Axis::Y, Axis::Z][axis];
            assert_eq!(
                f.push(AccelMg::from_array(r)),
                Err(TiltError::OutOfRange {
                    axis: ax,
                    value: 2001 * s
                })
            );
            assert_eq!(f.gravity_mg().to_array()[axis], -2000 * s, "last good kept");
        }
    }
    // A full scale beyond what the physics takes, less the largest calibration
    // offset, is capped: such a reading is not believed, and the largest one
    // believed, calibrated the other way, is the physics' largest pull.
    let wide = Plausibility {
        max_axis_mg: u32::MAX,
        min_total_mg: 0,
        max_total_mg: u32::MAX,
    };
    let mut f = TiltFilter::new(TiltConfig {
        plausibility: Some(wide),
        filter_shift: 0,
        ..TiltConfig::DEFAULT
    });
    assert_eq!(MAX_READING_MG as i32, MAX_MG - Calibration::MAX_OFFSET_MG);
    assert_eq!(
        f.push(AccelMg::new(-7_500, 0, 0)),
        Ok(GravityMg::new(7_500, 0, 0))
    );
    f.set_calibration(Calibration {
        offset_x: 500,
        offset_z: 0,
    });
    assert_eq!(
        f.push(AccelMg::new(-7_500, 0, 0)),
        Ok(GravityMg::new(MAX_MG, 0, 0))
    );
    assert!(matches!(
        f.push(AccelMg::new(7_501, 0, 0)),
        Err(TiltError::OutOfRange { .. })
    ));
    assert!(matches!(
        f.push(AccelMg::new(-16_000, 0, 0)),
        Err(TiltError::OutOfRange { .. })
    ));
}

#[test]
fn garbage_interleaved_with_good_samples_keeps_last_good() {
    let mut f = TiltFilter::default();
    let garbage: [[i32; 3]; 6] = [
        [0, 0, 0],
        [i32::MIN, i32::MIN, i32::MIN],
        [i32::MAX, 0, i32::MIN],
        [-1, -1, -1],
        [4095, 4095, 4095],
        [0, -i32::MAX, 0],
    ];
    let good = AccelMg::new(-400, 900, 200);
    let mut reference = TiltFilter::default();
    for i in 0..300 {
        let r = noisy(good, i);
        let want = reference.push(r).unwrap();
        assert_eq!(f.push(r), Ok(want));
        for g in &garbage[..(i % garbage.len()) + 1] {
            assert!(f.push(AccelMg::from_array(*g)).is_err());
            assert_eq!(f.gravity_mg(), want, "after {g:?}");
        }
    }
    assert_eq!(f.gravity_mg(), GravityMg::new(400, -900, -200));
}

#[test]
fn reset_forgets_state_but_keeps_calibration() {
    let mut f = TiltFilter::default();
    settle(&mut f, AccelMg::new(-300, 950, 0), 20);
    f.calibrate(AccelMg::new(-100, 990, 0)).unwrap();
    f.reset();
    assert_eq!(f.gravity_mg(), GravityMg::new(0, -1000, 0));
    assert_eq!(f.calibration().offset_x, -100);
    assert_eq!(
        f.push(AccelMg::new(-100, 990, 0)),
        Ok(GravityMg::new(0, -990, 0))
    );
}

fn any_config() -> impl Strategy<Value = TiltConfig> {
    (
        any::<u32>(),
        any::<u32>(),
        any::<u32>(),
        any::<u8>(),
        any::<u32>(),
        any::<u16>(),
        any::<i32>(),
        any::<i32>(),
    )
        .prop_map(|(ax, lo, hi, k, dz, stuck, cx, cz)| TiltConfig {
            plausibility: Some(Plausibility {
                max_axis_mg: ax,
                min_total_mg: lo,
                max_total_mg: hi,
            }),
            filter_shift: k,
            dead_zone_mg: dz,
            stuck_samples: stuck,
            calibration: Calibration {
                offset_x: cx,
                offset_z: cz,
            },
        })
}

fn edge_i32() -> impl Strategy<Value = i32> {
    prop_oneof![
        any::<i32>(),
        Just(i32::MIN),
        Just(i32::MAX),
        Just(0),
        -20_000i32..20_000,
        -3000i32..3000,
    ]
}

proptest! {
    #[test]
    fn arbitrary_samples_never_panic_and_stay_in_range(
        cfg in prop_oneof![Just(TiltConfig::DEFAULT), any_config()],
        samples in proptest::collection::vec([edge_i32(), edge_i32(), edge_i32()], 1..200),
        cal in proptest::option::of([edge_i32(), edge_i32(), edge_i32()]),
    ) {
        let mut f = TiltFilter::new(cfg);
        for (i, s) in samples.iter().enumerate() {
            let before = f.gravity_mg();
            match f.push(AccelMg::from_array(*s)) {
                Ok(g) => prop_assert_eq!(g, f.gravity_mg()),
                Err(_) => prop_assert_eq!(f.gravity_mg(), before),
            }
            for v in f.gravity_mg().to_array() {
                prop_assert!((-MAX_MG..=MAX_MG).contains(&v));
            }
            if i == samples.len() / 2 {
                if let Some(c) = cal {
                    let _ = f.calibrate(AccelMg::from_array(c));
                }
            }
            let _ = f.push(AccelMg::new(s[1], s[2], s[0]));
        }
        for v in f.gravity_mg().to_array() {
            prop_assert!((-MAX_MG..=MAX_MG).contains(&v));
        }
        let _ = f.config().time_constant_us(u32::MAX);
    }
}
