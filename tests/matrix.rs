//! Host tests for the LED-matrix frame, BCM scanner and on-time integrator.

use marble_rolling::matrix::{
    base_tick_hz, Brightness, Frame, OnTimeIntegrator, ScanStep, Scanner, BCM_BITS, LEVELS,
    MAX_BRIGHTNESS, SLICE_ORDER, TICKS_PER_ROW,
};
use proptest::prelude::*;

/// Takes exactly one full refresh worth of steps from `scanner`.
fn one_refresh<const W: usize, const H: usize>(scanner: &mut Scanner<W, H>) -> Vec<ScanStep> {
    (0..Scanner::<W, H>::STEPS_PER_REFRESH)
        .map(|_| scanner.next_step())
        .collect()
}

/// Integrates `refreshes` full refreshes of `frame` through a fresh scanner.
fn integrate<const W: usize, const H: usize>(
    frame: &Frame<W, H>,
    refreshes: u32,
) -> OnTimeIntegrator<W, H> {
    let mut scanner = Scanner::with_frame(frame);
    let mut integrator = OnTimeIntegrator::new();
    for _ in 0..refreshes {
        integrator.feed_all(one_refresh(&mut scanner));
    }
    assert!(scanner.at_refresh_start());
    integrator
}

/// Checks on-time, row time and perceived frame for `frame` over 1 and 3 refreshes.
fn assert_round_trip<const W: usize, const H: usize>(frame: &Frame<W, H>) {
    for refreshes in [1, 3] {
        let integrator = integrate(frame, refreshes);
        for (x, y, level) in frame.iter() {
            assert_eq!(
                integrator.on_ticks(x, y),
                u32::from(level) * refreshes,
                "on-ticks of ({x}, {y}) over {refreshes} refreshes"
            );
        }
        for y in 0..H {
            assert_eq!(
                integrator.row_ticks(y),
                TICKS_PER_ROW * refreshes,
                "row {y}"
            );
        }
        assert_eq!(&integrator.perceived(), frame);
    }
}

fn frame_strategy<const W: usize, const H: usize>() -> impl Strategy<Value = Frame<W, H>> {
    proptest::collection::vec(0..=MAX_BRIGHTNESS, W * H).prop_map(|levels| {
        let mut frame = Frame::new();
        for (i, level) in levels.into_iter().enumerate() {
            frame.set(i % W, i / W, level);
        }
        frame
    })
}

// ---------------------------------------------------------------- Frame

#[test]
fn frame_starts_blank_and_default_is_blank() {
    let frame = Frame::<5, 5>::new();
    assert!(frame.is_blank());
    assert_eq!(frame, Frame::default());
    assert_eq!(frame, Frame::blank());
    assert!(frame.iter().all(|(_, _, level)| level == 0));
    assert_eq!(frame.iter().count(), 25);
}

#[test]
fn frame_set_get_uses_x_column_y_row() {
    let mut frame = Frame::<8, 4>::new();
    frame.set(7, 1, 9);
    assert_eq!(frame.get(7, 1), 9);
    assert_eq!(frame.rows()[1][7], 9);
    assert_eq!(frame.get(1, 7), 0);
    assert!(!frame.is_blank());
    let lit: Vec<_> = frame.iter().filter(|&(_, _, l)| l != 0).collect();
    assert_eq!(lit, vec![(7, 1, 9)]);
}

#[test]
fn frame_out_of_range_is_ignored_and_reads_zero() {
    let mut frame = Frame::<5, 5>::filled(3);
    let before = frame;
    frame.set(5, 0, 15);
    frame.set(0, 5, 15);
    frame.set(usize::MAX, usize::MAX, 15);
    assert_eq!(frame, before);
    assert_eq!(frame.get(5, 0), 0);
    assert_eq!(frame.get(0, 5), 0);
    assert_eq!(frame.get(usize::MAX, 0), 0);
    assert_eq!(frame.get(4, 4), 3);
}

#[test]
fn frame_levels_are_clamped() {
    let mut frame = Frame::<2, 2>::new();
    frame.set(0, 0, 200);
    assert_eq!(frame.get(0, 0), MAX_BRIGHTNESS);
    frame.fill(16);
    assert!(frame.iter().all(|(_, _, l)| l == MAX_BRIGHTNESS));
    let frame = Frame::<2, 1>::from_rows([[255, 4]]);
    assert_eq!((frame.get(0, 0), frame.get(1, 0)), (MAX_BRIGHTNESS, 4));
}

#[test]
fn frame_fill_clear_and_iteration_order() {
    let mut frame = Frame::<3, 2>::new();
    frame.fill(7);
    assert!(frame.iter().all(|(_, _, l)| l == 7));
    let coords: Vec<_> = frame.iter().map(|(x, y, _)| (x, y)).collect();
    assert_eq!(coords, vec![(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 1)]);
    frame.clear();
    assert!(frame.is_blank());
    assert_eq!(Frame::<3, 2>::WIDTH, 3);
    assert_eq!(Frame::<3, 2>::HEIGHT, 2);
    assert!(format!("{frame:?}").contains("Frame"));
}

// ---------------------------------------------------------------- Scanner

#[test]
fn at_least_sixteen_levels() {
    let distinct: std::collections::BTreeSet<Brightness> = (0..=u8::MAX)
        .map(|level| Frame::<1, 1>::filled(level).get(0, 0))
        .collect();
    assert!(distinct.len() >= 16, "{distinct:?}");
    assert_eq!(usize::from(MAX_BRIGHTNESS) + 1, LEVELS);
}

#[test]
fn refresh_timing_constants() {
    assert_eq!(Scanner::<5, 5>::TICKS_PER_REFRESH, 75);
    assert_eq!(Scanner::<5, 5>::STEPS_PER_REFRESH, 5 * BCM_BITS);
    assert_eq!(Scanner::<16, 16>::TICKS_PER_REFRESH, 16 * 15);
    assert_eq!(base_tick_hz::<5>(100), 7_500);
    assert_eq!(base_tick_hz::<5>(u32::MAX), u32::MAX);
    let mut scanner = Scanner::<5, 5>::with_frame(&Frame::filled(15));
    let total: u32 = one_refresh(&mut scanner).iter().map(|s| s.ticks).sum();
    assert_eq!(total, Scanner::<5, 5>::TICKS_PER_REFRESH);
}

#[test]
fn steps_come_row_by_row_in_slice_order() {
    let mut scanner = Scanner::<5, 5>::new();
    for _ in 0..2 {
        assert!(scanner.at_refresh_start());
        let steps = one_refresh(&mut scanner);
        for (i, step) in steps.iter().enumerate() {
            assert_eq!(step.row, i / BCM_BITS, "step {i}");
            assert_eq!(step.ticks, 1 << SLICE_ORDER[i % BCM_BITS], "step {i}");
        }
    }
}

#[test]
fn columns_bit_x_is_column_x_of_row_y() {
    for y in 0..4 {
        for x in 0..8 {
            let mut frame = Frame::<8, 4>::new();
            frame.set(x, y, MAX_BRIGHTNESS);
            let mut scanner = Scanner::with_frame(&frame);
            for step in one_refresh(&mut scanner) {
                let expected = if step.row == y { 1 << x } else { 0 };
                assert_eq!(step.columns, expected, "pixel ({x}, {y}), step {step:?}");
            }
        }
    }
}

#[test]
fn each_level_lights_exactly_its_bits() {
    for level in 0..=MAX_BRIGHTNESS {
        let mut scanner = Scanner::<1, 1>::with_frame(&Frame::filled(level));
        let on: u32 = one_refresh(&mut scanner)
            .iter()
            .filter(|s| s.columns & 1 != 0)
            .map(|s| s.ticks)
            .sum();
        assert_eq!(on, u32::from(level), "level {level}");
    }
}

#[test]
fn every_level_integrates_exactly() {
    for level in 0..=MAX_BRIGHTNESS {
        assert_round_trip(&Frame::<5, 5>::filled(level));
    }
    // All 16 levels side by side in one frame, in both orientations.
    let mut gradient = Frame::<16, 2>::new();
    for x in 0..16 {
        gradient.set(x, 0, x as Brightness);
        gradient.set(x, 1, (15 - x) as Brightness);
    }
    assert_round_trip(&gradient);
}

#[test]
fn zero_is_fully_off_and_full_is_always_on() {
    let mut frame = Frame::<5, 5>::filled(MAX_BRIGHTNESS);
    frame.set(2, 3, 0);
    let mut scanner = Scanner::with_frame(&frame);
    for step in one_refresh(&mut scanner) {
        let expected = if step.row == 3 { 0b11011 } else { 0b11111 };
        assert_eq!(step.columns, expected, "{step:?}");
    }
}

#[test]
fn blank_frame_never_lights_a_column() {
    let mut scanner = Scanner::<5, 5>::new();
    assert!(scanner.by_ref().take(100).all(|s| s.columns == 0));
    scanner.load(&Frame::blank());
    let steps: Vec<_> = scanner.by_ref().take(100).collect();
    assert!(steps.iter().all(|s| s.columns == 0));
    assert_eq!(steps.iter().map(|s| s.ticks).sum::<u32>(), 5 * 75);
    let integrator = integrate(&Frame::<16, 16>::blank(), 2);
    assert!(integrator.perceived().is_blank());
}

#[test]
fn frame_loaded_mid_refresh_waits_for_next_refresh() {
    let old = Frame::<5, 5>::filled(15);
    let mut new = Frame::<5, 5>::new();
    new.set(1, 1, 5);
    let mut scanner = Scanner::with_frame(&old);
    let mut integrator = OnTimeIntegrator::new();
    for _ in 0..7 {
        integrator.feed(scanner.next_step());
    }
    scanner.load(&new);
    assert!(scanner.has_pending());
    while !scanner.at_refresh_start() {
        integrator.feed(scanner.next_step());
    }
    assert_eq!(
        integrator.take_perceived(),
        old,
        "old frame must finish untorn"
    );
    integrator.feed_all(one_refresh(&mut scanner));
    assert!(!scanner.has_pending());
    assert_eq!(integrator.perceived(), new);
}

#[test]
fn frame_loaded_at_refresh_start_shows_immediately_and_last_load_wins() {
    let mut scanner = Scanner::<3, 2>::new();
    scanner.load(&Frame::filled(1));
    scanner.load(&Frame::filled(9));
    let mut integrator = OnTimeIntegrator::<3, 2>::new();
    integrator.feed_all(one_refresh(&mut scanner));
    assert_eq!(integrator.perceived(), Frame::filled(9));
}

#[test]
fn sizes_from_1x1_to_32_wide() {
    assert_round_trip(&Frame::<1, 1>::filled(6));
    assert_round_trip(&Frame::<8, 4>::filled(11));
    assert_round_trip(&Frame::<16, 16>::filled(13));
    let mut wide = Frame::<32, 2>::new();
    wide.set(31, 1, 15);
    wide.set(0, 0, 1);
    let mut scanner = Scanner::with_frame(&wide);
    let steps = one_refresh(&mut scanner);
    assert!(steps.iter().any(|s| s.row == 1 && s.columns == 1 << 31));
    assert_round_trip(&wide);
}

#[test]
fn loading_the_frame_on_show_queues_nothing_and_cancels_a_queued_one() {
    let shown = Frame::<19, 9>::filled(3);
    let mut other = shown;
    other.set(18, 8, 4);
    let mut scanner = Scanner::with_frame(&shown);
    let mut integrator = OnTimeIntegrator::new();
    integrator.feed_all(one_refresh(&mut scanner));
    scanner.load(&shown);
    assert!(
        !scanner.has_pending(),
        "the frame on show is not queued again"
    );
    scanner.load(&other);
    assert!(
        scanner.has_pending(),
        "a frame differing in its last pixel is queued"
    );
    scanner.load(&shown);
    assert!(
        !scanner.has_pending(),
        "back to the frame on show: nothing to swap"
    );
    integrator.reset();
    integrator.feed_all(one_refresh(&mut scanner));
    assert_eq!(integrator.perceived(), shown);
}

// ---------------------------------------------------------------- Integrator

#[test]
fn integrator_rounds_half_up_per_row_period() {
    let mut integrator = OnTimeIntegrator::<3, 2>::new();
    // Row 0 driven 30 ticks; column 0 on 15 (7.5 → 8), column 1 on 1 (0.5 → 1),
    // column 2 on 0.
    integrator.feed(ScanStep {
        row: 0,
        columns: 0b011,
        ticks: 1,
    });
    integrator.feed(ScanStep {
        row: 0,
        columns: 0b001,
        ticks: 14,
    });
    integrator.feed(ScanStep {
        row: 0,
        columns: 0,
        ticks: 15,
    });
    // Row 1 driven 15 ticks, column 2 on 14 of them.
    integrator.feed(ScanStep {
        row: 1,
        columns: 0b100,
        ticks: 14,
    });
    integrator.feed(ScanStep {
        row: 1,
        columns: 0,
        ticks: 1,
    });
    assert_eq!(integrator.row_ticks(0), 30);
    assert_eq!(integrator.on_ticks(0, 0), 15);
    let frame = integrator.perceived();
    assert_eq!(frame, Frame::from_rows([[8, 1, 0], [0, 0, 14]]));
}

#[test]
fn integrator_ignores_out_of_range_and_resets() {
    let mut integrator = OnTimeIntegrator::<2, 2>::new();
    integrator.feed(ScanStep {
        row: 2,
        columns: u32::MAX,
        ticks: 8,
    });
    integrator.feed(ScanStep {
        row: 0,
        columns: 0b100,
        ticks: 8,
    });
    assert_eq!(integrator.row_ticks(0), 8);
    assert_eq!(integrator.row_ticks(2), 0);
    assert!(integrator.perceived().is_blank());
    integrator.feed(ScanStep {
        row: 1,
        columns: 0b10,
        ticks: 4,
    });
    assert_eq!(integrator.perceived().get(1, 1), MAX_BRIGHTNESS);
    integrator.reset();
    assert_eq!(integrator, OnTimeIntegrator::new());
    assert!(integrator.perceived().is_blank());
}

#[test]
fn integrator_counters_saturate_per_pixel() {
    let mut integrator = OnTimeIntegrator::<3, 1>::new();
    integrator.feed(ScanStep {
        row: 0,
        columns: 0b001,
        ticks: u32::MAX - 5,
    });
    integrator.feed(ScanStep {
        row: 0,
        columns: 0b011,
        ticks: 8,
    });
    assert_eq!(integrator.on_ticks(0, 0), u32::MAX, "saturated");
    assert_eq!(integrator.on_ticks(1, 0), 8, "its neighbour counts on");
    assert_eq!(integrator.on_ticks(2, 0), 0);
    integrator.feed(ScanStep {
        row: 0,
        columns: 0b011,
        ticks: 1,
    });
    assert_eq!(integrator.on_ticks(0, 0), u32::MAX, "stays saturated");
    assert_eq!(integrator.on_ticks(1, 0), 9);
    assert_eq!(integrator.row_ticks(0), u32::MAX);
}

// ---------------------------------------------------------------- Properties

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_5x5_frames_integrate_exactly(frame in frame_strategy::<5, 5>()) {
        assert_round_trip(&frame);
    }

    #[test]
    fn random_8x4_frames_integrate_exactly(frame in frame_strategy::<8, 4>()) {
        assert_round_trip(&frame);
    }

    #[test]
    fn random_16x16_frames_integrate_exactly(frame in frame_strategy::<16, 16>()) {
        assert_round_trip(&frame);
    }

    #[test]
    fn random_1x1_frames_integrate_exactly(frame in frame_strategy::<1, 1>()) {
        assert_round_trip(&frame);
    }

    /// The bit-sliced counters against plain saturating per-pixel counters,
    /// for any steps (ticks not only powers of two, columns past the width).
    #[test]
    fn integrator_matches_plain_counters(
        steps in proptest::collection::vec(
            (0usize..5, any::<u32>(), prop_oneof![1u32..=8, any::<u32>()]),
            0..40,
        ),
    ) {
        let mut integrator = OnTimeIntegrator::<7, 4>::new();
        let mut on = [[0u32; 7]; 4];
        let mut rows = [0u32; 4];
        for &(row, columns, ticks) in &steps {
            integrator.feed(ScanStep { row, columns, ticks });
            if row < 4 {
                rows[row] = rows[row].saturating_add(ticks);
                for (x, pixel) in on[row].iter_mut().enumerate() {
                    if columns >> x & 1 != 0 {
                        *pixel = pixel.saturating_add(ticks);
                    }
                }
            }
        }
        for (y, (pixels, &row_ticks)) in on.iter().zip(&rows).enumerate() {
            prop_assert_eq!(integrator.row_ticks(y), row_ticks);
            for (x, &pixel) in pixels.iter().enumerate() {
                prop_assert_eq!(integrator.on_ticks(x, y), pixel, "pixel ({}, {})", x, y);
            }
        }
    }

    #[test]
    fn every_row_gets_equal_total_time(frame in frame_strategy::<5, 5>(), refreshes in 1u32..4) {
        let mut scanner = Scanner::with_frame(&frame);
        let mut per_row = [0u32; 5];
        for _ in 0..refreshes {
            for step in one_refresh(&mut scanner) {
                per_row[step.row] += step.ticks;
            }
        }
        prop_assert!(per_row.iter().all(|&t| t == TICKS_PER_ROW * refreshes), "{per_row:?}");
    }

    #[test]
    fn no_tearing_whenever_the_load_happens(
        old in frame_strategy::<5, 5>(),
        new in frame_strategy::<5, 5>(),
        split in 1usize..Scanner::<5, 5>::STEPS_PER_REFRESH,
        warmup in 0usize..3,
    ) {
        let mut scanner = Scanner::with_frame(&old);
        for _ in 0..warmup {
            one_refresh(&mut scanner);
        }
        let mut integrator = OnTimeIntegrator::new();
        for _ in 0..split {
            integrator.feed(scanner.next_step());
        }
        scanner.load(&new);
        for _ in split..Scanner::<5, 5>::STEPS_PER_REFRESH {
            integrator.feed(scanner.next_step());
        }
        prop_assert!(scanner.at_refresh_start());
        prop_assert_eq!(integrator.take_perceived(), old);
        integrator.feed_all(one_refresh(&mut scanner));
        prop_assert_eq!(integrator.perceived(), new);
    }
}
