use super::gpio_trace::{parse_trace_line, TraceEvent};
use super::log::{module_of, parse_profile, parse_ram, parse_watchdog};
use super::*;
use crate::demo::parse_cpu_load;

#[test]
fn trace_lines() {
    assert_eq!(
        parse_trace_line("nrf51_timer_set_count timer 0 counter 3 count 0x1fa9c49"),
        Some(TraceEvent::Time(0x1fa9c49))
    );
    assert_eq!(
        parse_trace_line("1234@1.5:nrf51_timer_set_count timer 0 counter 3 count 0x10"),
        Some(TraceEvent::Time(16))
    );
    assert_eq!(
        parse_trace_line("nrf51_timer_set_count timer 1 counter 3 count 0x10"),
        None
    );
    assert_eq!(
        parse_trace_line("nrf51_gpio_update_output_irq line 13 value 1"),
        Some(TraceEvent::Pin {
            line: 13,
            level: Some(true)
        })
    );
    assert_eq!(
        parse_trace_line("nrf51_gpio_update_output_irq line 4 value -1"),
        Some(TraceEvent::Pin {
            line: 4,
            level: None
        })
    );
    assert_eq!(
        parse_trace_line("nrf51_gpio_update_output_irq line x value 1"),
        None
    );
    assert_eq!(parse_trace_line("something else"), None);
}

/// Trace lines for one `OUT` word at time `t`.
fn write(lines: &mut Vec<String>, t: u32, out: u32) {
    lines.push(format!(
        "nrf51_timer_set_count timer 0 counter 3 count {t:#x}"
    ));
    for pin in 4..16 {
        let value = (out >> pin) & 1;
        lines.push(format!(
            "nrf51_gpio_update_output_irq line {pin} value {value}"
        ));
    }
}

/// One BCM refresh of `picture` as trace lines from `t`, slice lengths
/// in µs of `base` per tick; returns the end time.
fn refresh(lines: &mut Vec<String>, mut t: u32, picture: &[[u8; 5]; 5], base: u32) -> u32 {
    for row in 0..leds::ROWS {
        for bit in (0..4).rev() {
            let mut lit = 0;
            for (y, line) in leds::LED_MAP.iter().enumerate() {
                for (x, &(r, c)) in line.iter().enumerate() {
                    if usize::from(r) == row && picture[y][x] >> bit & 1 != 0 {
                        lit |= 1 << c;
                    }
                }
            }
            write(lines, t, leds::out_word(row, lit));
            t += base << bit;
        }
    }
    t
}

#[test]
fn a_bcm_scan_is_perceived_as_its_picture() {
    let picture = [
        [0, 1, 2, 3, 4],
        [5, 6, 7, 8, 9],
        [10, 11, 12, 13, 14],
        [15, 0, 15, 0, 15],
        [3, 3, 3, 3, 3],
    ];
    let mut lines = Vec::new();
    let mut t = 1_000;
    for _ in 0..10 {
        t = refresh(&mut lines, t, &picture, 222);
    }
    write(&mut lines, t, leds::DARK);
    let timeline = Timeline::from_lines(lines.iter().map(String::as_str));
    assert_eq!(timeline.perceived(1_000, t as u64), picture);
    // Jitter of a few µs at the edges stays within one level.
    let shifted = timeline.perceived(1_003, t as u64 + 2);
    assert!(max_difference(&shifted, &picture) <= 1);
    // Nothing was lit before the first write.
    assert_eq!(timeline.perceived(0, 1_000), [[0; 5]; 5]);
}

#[test]
fn the_clock_is_extended_across_wraps() {
    let mut lines = Vec::new();
    write(&mut lines, 0xffff_ff00, leds::out_word(0, 1));
    write(&mut lines, 0x0000_0100, leds::DARK);
    let timeline = Timeline::from_lines(lines.iter().map(String::as_str));
    assert_eq!(timeline.changes[1].0, 0x1_0000_0100);
    // LED (row 0, column 0) is pixel (0, 0): lit all the time its row was.
    assert_eq!(timeline.perceived(0xffff_ff00, 0x1_0000_0100)[0][0], 15);
}

#[test]
fn frame_lines() {
    let line = "26.1 INFO  display frame level=7 t0=26062629 t1=26192553 rows=33343 115b1 33333 01111 33333";
    let frame = parse_frame(line).unwrap();
    assert_eq!(frame.level, 7);
    assert_eq!((frame.t0, frame.t1), (26_062_629, 26_192_553));
    assert_eq!(frame.rows[1], [1, 1, 5, 11, 1]);
    assert!(frame.shows_the_maze());
    assert_eq!(hex_rows(&frame.rows), "33343 115b1 33333 01111 33333");
    let flash =
        parse_frame("display frame level=0 t0=1 t1=2 rows=fffff fffff fffff fffff fffff").unwrap();
    assert!(!flash.shows_the_maze());
    assert!(parse_frame("display frame level=0 t0=1 t1=2 rows=fffff").is_none());
}

#[test]
fn budget_lines() {
    let log = "x INFO  ram: statics 5084 B + stack high-water 8364 B = 13448 B of 16384 B (budget 12288 B)\n\
               x INFO  cpu load: 75141188 busy instructions in 25267360 us of firmware time = 2973844 instructions/s = 18.58 % of a 16 MHz Cortex-M0 (128 frames/s, 100 refreshes/s)\n";
    assert_eq!(parse_ram(log), Some((5084, 8364)));
    assert_eq!(parse_cpu_load(log), Some(1858));
    assert_eq!(parse_cpu_load("cpu load: x = 1.5 % of a 16 MHz"), None);
}

#[test]
fn watchdog_lines() {
    let log = "34.1 INFO  watchdog: longest wait without a pet 600 ms (it resets at 2000 ms)";
    assert_eq!(parse_watchdog(log), Some((600, 2000)));
    assert_eq!(
        parse_watchdog("watchdog: longest wait without a pet x ms"),
        None
    );
}

#[test]
fn profile_lines() {
    let line = "44.6 INFO  profile grand-tour: 293 frames, instructions per frame: physics 33309 (max 894523), autopilot 5558, render 2535";
    assert_eq!(
        parse_profile(line),
        Some(("grand-tour".to_string(), 293, 33309, 894523))
    );
    assert_eq!(parse_profile("profile x: 3 frames"), None);
}

#[test]
fn modules_of_symbols() {
    assert_eq!(
        module_of("marble_rolling::physics::world::events::<impl marble_rolling::physics::world::World<S, _>>::step_events"),
        "marble_rolling::physics"
    );
    assert_eq!(module_of("<core::fmt::Formatter>::pad"), "core::fmt");
    assert_eq!(
        module_of("TIMER0"),
        "(symbols without a path: vectors, handlers, builtins)"
    );
}
