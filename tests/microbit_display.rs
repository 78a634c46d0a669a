//! micro:bit LED refresh budget and the fault pattern substitution.

use marble_rolling::board::microbit::{
    frame_columns, refresh_millihz, rtc_ticks_per_base_tick, FAULT_FRAME, HEIGHT, RTC_HZ, WIDTH,
};
use marble_rolling::matrix::{Frame, OnTimeIntegrator, Scanner, LEVELS};

#[test]
fn bcm_slices_fit_the_rtc_at_100_hz() {
    const { assert!(LEVELS >= 16) };
    let ticks = rtc_ticks_per_base_tick(100);
    assert_eq!(ticks, 4, "122 us shortest slice");
    let mhz = refresh_millihz(ticks);
    assert!(mhz >= 100_000, "refresh {mhz} mHz");
    assert_eq!(mhz, 109_226);
    // One more RTC tick per base tick would fall below 100 Hz.
    assert!(refresh_millihz(ticks + 1) < 100_000);
    // Shortest slice is at least 4 RTC ticks (1 tick of jitter <= 25 %).
    assert!(RTC_HZ / ticks <= 8192);
}

#[test]
fn degenerate_rates_do_not_panic() {
    assert_eq!(rtc_ticks_per_base_tick(0), 1);
    assert_eq!(rtc_ticks_per_base_tick(1_000_000), 1);
    assert_eq!(refresh_millihz(0), 0);
}

#[test]
fn fault_pattern_substitution_shows_the_fault_frame() {
    // Scan some other frame, but substitute the fault frame's columns per step:
    // what a viewer sees is exactly the fault frame.
    let mut scanner = Scanner::<WIDTH, HEIGHT>::with_frame(&Frame::filled(7));
    let mut seen = OnTimeIntegrator::<WIDTH, HEIGHT>::new();
    for _ in 0..3 * Scanner::<WIDTH, HEIGHT>::STEPS_PER_REFRESH {
        let mut step = scanner.next_step();
        step.columns = frame_columns(&FAULT_FRAME, step);
        seen.feed(step);
    }
    assert_eq!(seen.perceived(), FAULT_FRAME);
    assert!(!FAULT_FRAME.is_blank());
}

#[test]
fn frame_columns_matches_the_scanner_for_grey_levels() {
    let mut frame = Frame::<WIDTH, HEIGHT>::new();
    for (i, (x, y)) in (0..WIDTH)
        .flat_map(|x| (0..HEIGHT).map(move |y| (x, y)))
        .enumerate()
    {
        frame.set(x, y, (i % 16) as u8);
    }
    let mut scanner = Scanner::<WIDTH, HEIGHT>::with_frame(&frame);
    for _ in 0..2 * Scanner::<WIDTH, HEIGHT>::STEPS_PER_REFRESH {
        let step = scanner.next_step();
        assert_eq!(frame_columns(&frame, step), step.columns, "{step:?}");
    }
}
