//! micro:bit LED refresh budget and the fault picture on its 5×5 matrix.

use marble_rolling::board::microbit::{
    refresh_millihz, rtc_ticks_per_base_tick, HEIGHT, RTC_HZ, WIDTH,
};
use marble_rolling::matrix::{OnTimeIntegrator, Scanner, LEVELS, MAX_BRIGHTNESS};
use marble_rolling::render::screens::fault_frame;

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
fn a_downed_sensor_shows_a_cross_on_the_5x5() {
    // The game's fault picture, scanned like any frame: what a viewer sees is
    // the two diagonals at full brightness and nothing else.
    let cross = fault_frame::<WIDTH, HEIGHT>();
    let mut scanner = Scanner::<WIDTH, HEIGHT>::with_frame(&cross);
    let mut seen = OnTimeIntegrator::<WIDTH, HEIGHT>::new();
    for _ in 0..3 * Scanner::<WIDTH, HEIGHT>::STEPS_PER_REFRESH {
        seen.feed(scanner.next_step());
    }
    let perceived = seen.perceived();
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let on = x == y || x == WIDTH - 1 - y;
            let level = perceived.rows()[y][x];
            assert_eq!(level == MAX_BRIGHTNESS, on, "pixel ({x}, {y}): {level}");
            assert!(on || level == 0, "pixel ({x}, {y}): {level}");
        }
    }
}
