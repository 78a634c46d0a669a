//! The micro:bit v1's pure half (`marble_rolling::board::microbit_v1`): the
//! LED table against the DAL's, the logical-to-electrical scan conversion
//! (a schedule played back and integrated shows the picture it was made
//! from), the command line, the CPU-load arithmetic and the accelerometer
//! probes.

use marble_rolling::board::microbit_v1::leds::{
    decode_levels, out_word, pixel_of, COLS, COL_PINS, DAL_MAP, DARK, LED_MAP, MATRIX_PINS, ROWS,
    ROW_PINS, SIZE, UNUSED,
};
use marble_rolling::board::microbit_v1::{
    electrical_frame, frame_from_refresh, identify, picture_of, rows_hex, schedule, schedule_steps,
    Accelerometer, Calibration, LoadReport, Options, Picture, Sample, BASE_TICK_US, DARK_SCHEDULE,
    PROBES, REFRESH_US, SLICES,
};
use marble_rolling::matrix::{OnTimeIntegrator, Scanner, MAX_BRIGHTNESS};

/// A picture with every level 0..=15 somewhere, and no symmetry.
fn test_picture() -> Picture {
    let mut picture = Picture::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            picture.set(x, y, ((7 * y + 3 * x + 1) % 16) as u8);
        }
    }
    picture
}

#[test]
fn every_led_has_its_own_crossing_and_two_are_unused() {
    let mut seen = [[false; COLS]; ROWS];
    for (y, row) in LED_MAP.iter().enumerate() {
        for (x, &(r, c)) in row.iter().enumerate() {
            let (r, c) = (usize::from(r), usize::from(c));
            assert!(r < ROWS && c < COLS, "pixel ({x}, {y}) has no crossing");
            assert!(!seen[r][c], "pixel ({x}, {y}) shares crossing ({r}, {c})");
            seen[r][c] = true;
            assert_eq!(pixel_of(r, c), Some((x as u8, y as u8)));
        }
    }
    let unused: Vec<(u8, u8)> = (0..ROWS)
        .flat_map(|r| (0..COLS).map(move |c| (r, c)))
        .filter(|&(r, c)| !seen[r][c])
        .map(|(r, c)| (r as u8, c as u8))
        .collect();
    assert_eq!(unused, UNUSED);
    for (r, c) in UNUSED {
        assert_eq!(DAL_MAP[usize::from(c)][usize::from(r)], None);
    }
    assert_eq!(DAL_MAP.iter().flatten().filter(|p| p.is_some()).count(), 25);
}

#[test]
fn the_table_is_the_dals() {
    // A few entries read straight off microbit-dal's `microbitDisplayMap`
    // (MICROBIT_SB2), `[column × 3 + row] = {x, y}`, and the nrf-rs
    // `microbit` crate's v1 `LED_LAYOUT` (`[y][x] = (row, column)`).
    assert_eq!(DAL_MAP[0], [Some((0, 0)), Some((4, 2)), Some((2, 4))]);
    assert_eq!(DAL_MAP[8], [Some((1, 2)), None, Some((3, 2))]);
    assert_eq!(LED_MAP[0], [(0, 0), (1, 3), (0, 1), (1, 4), (0, 2)]);
    assert_eq!(LED_MAP[1], [(2, 3), (2, 4), (2, 5), (2, 6), (2, 7)]);
    assert_eq!(LED_MAP[2], [(1, 1), (0, 8), (1, 2), (2, 8), (1, 0)]);
    assert_eq!(LED_MAP[3], [(0, 7), (0, 6), (0, 5), (0, 4), (0, 3)]);
    assert_eq!(LED_MAP[4], [(2, 2), (1, 6), (2, 0), (1, 5), (2, 1)]);
    assert_eq!(ROW_PINS, [13, 14, 15]);
    assert_eq!(COL_PINS, [4, 5, 6, 7, 8, 9, 10, 11, 12]);
}

#[test]
fn out_words_drive_one_row_and_the_lit_columns_low() {
    assert_eq!(MATRIX_PINS, 0xfff0);
    assert_eq!(DARK, 0x1ff << 4);
    assert_eq!(decode_levels(DARK), (0, 0));
    for (row, pin) in ROW_PINS.iter().enumerate() {
        for lit in [0, 1, 0x155, 0x1ff] {
            let word = out_word(row, lit);
            assert_eq!(word & !MATRIX_PINS, 0);
            assert_eq!(decode_levels(word), (1 << row, lit));
            assert_eq!(word >> pin & 1, 1);
        }
    }
    assert_eq!(decode_levels(out_word(ROWS, 0x1ff)), (0, 0x1ff));
}

#[test]
fn rewiring_is_a_bijection() {
    let picture = test_picture();
    let electrical = electrical_frame(&picture);
    assert_eq!(picture_of(&electrical), picture);
    for (r, c) in UNUSED {
        assert_eq!(electrical.get(usize::from(c), usize::from(r)), 0);
    }
    let lit: u32 = electrical
        .iter()
        .map(|(_, _, level)| u32::from(level))
        .sum();
    let drawn: u32 = picture.iter().map(|(_, _, level)| u32::from(level)).sum();
    assert_eq!(lit, drawn);
}

#[test]
fn one_refresh_of_the_logical_scan_gives_the_frame_back() {
    let picture = test_picture();
    let mut scanner = Scanner::<SIZE, SIZE>::with_frame(&picture);
    let steps = (0..Scanner::<SIZE, SIZE>::STEPS_PER_REFRESH).map(|_| scanner.next_step());
    assert_eq!(frame_from_refresh(steps), picture);
    let blank = Scanner::<SIZE, SIZE>::new().take(Scanner::<SIZE, SIZE>::STEPS_PER_REFRESH);
    assert_eq!(frame_from_refresh(blank), Picture::new());
}

#[test]
fn a_schedule_played_back_shows_its_picture() {
    for picture in [
        test_picture(),
        Picture::new(),
        Picture::filled(MAX_BRIGHTNESS),
    ] {
        let slices = schedule(&picture);
        assert_eq!(slices.len(), SLICES);
        let total: u32 = slices.iter().map(|slice| slice.us).sum();
        assert_eq!(total, REFRESH_US);
        // What the GPIO pins do, integrated as the xtask does from QEMU's trace.
        let mut integrator = OnTimeIntegrator::<COLS, ROWS>::new();
        integrator.feed_all(schedule_steps(&slices));
        assert_eq!(picture_of(&integrator.perceived()), picture);
        for slice in &slices {
            assert_eq!(slice.out & !MATRIX_PINS, 0);
            assert_eq!(slice.us % BASE_TICK_US, 0);
        }
    }
    assert!(DARK_SCHEDULE.iter().all(|slice| slice.out == DARK));
    let dark_total: u32 = DARK_SCHEDULE.iter().map(|slice| slice.us).sum();
    assert_eq!(dark_total, REFRESH_US);
}

#[test]
fn rows_as_hex() {
    let mut picture = Picture::new();
    picture.set(0, 0, 15);
    picture.set(4, 4, 3);
    picture.set(2, 1, 10);
    assert_eq!(rows_hex(&picture), [0xf0000, 0x00a00, 0, 0, 0x00003]);
}

#[test]
fn options() {
    assert_eq!(Options::parse([]), Options::default());
    assert!(!Options::default().headless());
    let demo = Options::parse(["microbit-v1", "--demo"]);
    assert!(demo.demo && demo.frame_log && demo.headless());
    let timed = Options::parse(["--seconds=5", "--no-frame-log", "--bogus"]);
    assert_eq!(timed.seconds, Some(5));
    assert!(!timed.frame_log && timed.headless() && !timed.demo);
    assert_eq!(Options::parse(["--seconds=x"]).seconds, None);
}

#[test]
fn cpu_load_arithmetic() {
    let nominal = Calibration::NOMINAL;
    assert!(nominal.matches_icount());
    assert_eq!(nominal.milli_us_per_instruction(), 128);
    // 80 000 instructions in 10 240 µs, as the firmware measures it.
    let measured = Calibration {
        instructions: 80_000,
        us: 10_240,
        overhead_us: 1,
    };
    assert!(measured.matches_icount());
    assert_eq!(measured.instructions(1_000_000), 7_812_500);
    // One second, a fifth of it busy: 1.5625 M instructions = 9.76 % of 16 MHz.
    let start = Sample::default();
    let end = Sample {
        total_us: 1_000_000,
        idle_us: 800_000,
    };
    let report = LoadReport::between(&measured, start, end).unwrap();
    assert_eq!(report.busy_instructions, 1_562_500);
    assert_eq!(report.instructions_per_second, 1_562_500);
    assert_eq!(report.centipercent_of_16mhz, 976);
    assert!(LoadReport::between(&measured, end, start).is_none());
    assert!(LoadReport::between(&measured, start, start).is_none());
}

#[test]
fn accelerometer_probes() {
    // Each chip's WHO_AM_I answer identifies it, and only it.
    for probe in &PROBES {
        assert_eq!(identify(probe, Some(probe.id)), Some(probe.chip));
        assert_eq!(identify(probe, None), None);
        for other in &PROBES {
            if other.id != probe.id {
                assert_eq!(identify(probe, Some(other.id)), None);
            }
        }
    }
    let chips: Vec<Accelerometer> = PROBES.iter().map(|probe| probe.chip).collect();
    assert_eq!(
        chips,
        [
            Accelerometer::Mma8653fc,
            Accelerometer::Lsm303agr,
            Accelerometer::Fxos8700cq
        ]
    );
    // QEMU's TWI stub answers 0x5A to the first read whatever the address:
    // the first probe, the MMA8653FC's, finds it.
    assert_eq!(
        identify(&PROBES[0], Some(0x5A)),
        Some(Accelerometer::Mma8653fc)
    );
}
