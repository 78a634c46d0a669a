//! The micro:bit v1's display rebuilt from QEMU's GPIO trace (see the parent
//! module's doc): the trace's lines, the timeline of pin levels, and the frames
//! the firmware says it showed.

use super::leds;

/// One line of QEMU's trace that matters here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceEvent {
    /// TIMER0 was captured: its 32-bit counter (µs).
    Time(u32),
    /// GPIO `line` changed: driven high (`Some(true)`), low (`Some(false)`),
    /// or released (`None`: QEMU's `-1`, an input or disconnected pin).
    Pin { line: u8, level: Option<bool> },
}

/// Parses `nrf51_timer_set_count timer 0 counter N count 0xHEX` (timer 0
/// only) and `nrf51_gpio_update_output_irq line N value V` (whatever QEMU
/// puts before the event name, e.g. a pid and time stamp, is skipped).
pub fn parse_trace_line(line: &str) -> Option<TraceEvent> {
    if let Some(at) = line.find("nrf51_timer_set_count ") {
        let mut words = line[at..].split_whitespace().skip(1);
        let (Some("timer"), Some(timer), Some("counter"), Some(_), Some("count"), Some(count)) = (
            words.next(),
            words.next(),
            words.next(),
            words.next(),
            words.next(),
            words.next(),
        ) else {
            return None;
        };
        if timer != "0" {
            return None;
        }
        let hex = count.strip_prefix("0x").unwrap_or(count);
        return u32::from_str_radix(hex, 16).ok().map(TraceEvent::Time);
    }
    let at = line.find("nrf51_gpio_update_output_irq ")?;
    let mut words = line[at..].split_whitespace().skip(1);
    let (Some("line"), Some(pin), Some("value"), Some(value)) =
        (words.next(), words.next(), words.next(), words.next())
    else {
        return None;
    };
    let level = match value {
        "1" => Some(true),
        "0" => Some(false),
        "-1" => None,
        _ => return None,
    };
    Some(TraceEvent::Pin {
        line: pin.parse().ok()?,
        level,
    })
}

/// The matrix pins' levels over time: `(µs, levels)` from that time on, in
/// order. `levels` holds a bit per GPIO: 1 = high or released, except that
/// a released row pin (never driven) counts as low — so that
/// [`leds::decode_levels`] reads it as the firmware means it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Timeline {
    pub(super) changes: Vec<(u64, u32)>,
}

/// Row pins, as a GPIO bit mask.
const ROW_BITS: u32 = leds::ROW_MASK << leds::FIRST_ROW_PIN;

impl Timeline {
    /// Builds the timeline from trace lines. Pin changes before the first
    /// time stamp are dated 0; the 32-bit clock is extended across wraps.
    pub fn from_lines<'a>(lines: impl IntoIterator<Item = &'a str>) -> Timeline {
        let mut changes: Vec<(u64, u32)> = Vec::new();
        // Everything dark: rows low, columns high.
        let mut levels = leds::DARK | !leds::MATRIX_PINS;
        let (mut now, mut last_raw) = (0u64, 0u32);
        for line in lines {
            match parse_trace_line(line) {
                Some(TraceEvent::Time(raw)) => {
                    let wrapped = u64::from(raw < last_raw) << 32;
                    now = ((now & !0xffff_ffff) + wrapped) | u64::from(raw);
                    last_raw = raw;
                }
                Some(TraceEvent::Pin { line, level }) if line < 32 => {
                    let bit = 1u32 << line;
                    let high = match level {
                        Some(high) => high,
                        None => bit & ROW_BITS == 0,
                    };
                    levels = if high { levels | bit } else { levels & !bit };
                    match changes.last_mut() {
                        Some((at, last)) if *at == now => *last = levels,
                        _ => changes.push((now, levels)),
                    }
                }
                _ => {}
            }
        }
        Timeline { changes }
    }

    /// The number of level changes.
    pub fn len(&self) -> usize {
        self.changes.len()
    }

    /// Whether no pin ever changed.
    pub fn is_empty(&self) -> bool {
        self.changes.is_empty()
    }

    /// The 5×5 picture a viewer sees over `[t0, t1)`: per LED, the time its
    /// row pin was high and its column pin low, over the time its row was
    /// driven, × 15, rounded half up (0 for a row never driven).
    pub fn perceived(&self, t0: u64, t1: u64) -> [[u8; leds::SIZE]; leds::SIZE] {
        let mut lit = [[0u64; leds::COLS]; leds::ROWS];
        let mut driven = [0u64; leds::ROWS];
        // The level in force at t0: that of the last change at or before it.
        let first = self.changes.partition_point(|&(at, _)| at <= t0);
        let mut at = t0;
        let mut levels = match first {
            0 => leds::DARK | !leds::MATRIX_PINS,
            n => self.changes[n - 1].1,
        };
        let mut add = |levels: u32, from: u64, to: u64| {
            let span = to.saturating_sub(from);
            let (rows, cols) = leds::decode_levels(levels);
            for (row, time) in driven.iter_mut().enumerate() {
                if rows & (1 << row) == 0 {
                    continue;
                }
                *time += span;
                for (col, on) in lit[row].iter_mut().enumerate() {
                    if cols & (1 << col) != 0 {
                        *on += span;
                    }
                }
            }
        };
        for &(change, next) in &self.changes[first..] {
            if change >= t1 {
                break;
            }
            add(levels, at, change);
            at = change;
            levels = next;
        }
        add(levels, at, t1);
        let mut picture = [[0u8; leds::SIZE]; leds::SIZE];
        for (y, row) in leds::LED_MAP.iter().enumerate() {
            for (x, &(r, c)) in row.iter().enumerate() {
                let (r, c) = (usize::from(r), usize::from(c));
                let (on, period) = (lit[r][c], driven[r]);
                if period > 0 {
                    picture[y][x] = ((2 * on * 15 + period) / (2 * period)).min(15) as u8;
                }
            }
        }
        picture
    }
}

/// One `display frame` line of the firmware's log.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoggedFrame {
    /// Index of the level (0-based) when it went up.
    pub level: u8,
    /// On the LEDs from (µs, TIMER0 time) …
    pub t0: u64,
    /// … until (exclusive).
    pub t1: u64,
    /// Brightness, `rows[y][x]`.
    pub rows: [[u8; leds::SIZE]; leds::SIZE],
}

impl LoggedFrame {
    /// Whether the frame shows the maze (not blank, not uniformly lit like
    /// the win flash).
    pub fn shows_the_maze(&self) -> bool {
        let first = self.rows[0][0];
        self.rows.iter().flatten().any(|&level| level != first)
    }
}

/// Parses `display frame level=L t0=T0 t1=T1 rows=R0 R1 R2 R3 R4` anywhere
/// in a line.
pub fn parse_frame(line: &str) -> Option<LoggedFrame> {
    let rest = &line[line.find("display frame level=")? + "display frame level=".len()..];
    let (level, rest) = rest.split_once(" t0=")?;
    let (t0, rest) = rest.split_once(" t1=")?;
    let (t1, rest) = rest.split_once(" rows=")?;
    let mut rows = [[0u8; leds::SIZE]; leds::SIZE];
    let mut words = rest.split_whitespace();
    for row in rows.iter_mut() {
        let word = words.next()?;
        if word.len() != leds::SIZE {
            return None;
        }
        for (level, digit) in row.iter_mut().zip(word.chars()) {
            *level = digit.to_digit(16)? as u8;
        }
    }
    Some(LoggedFrame {
        level: level.parse().ok()?,
        t0: t0.parse().ok()?,
        t1: t1.parse().ok()?,
        rows,
    })
}

/// The largest per-pixel difference of two pictures.
pub fn max_difference(
    a: &[[u8; leds::SIZE]; leds::SIZE],
    b: &[[u8; leds::SIZE]; leds::SIZE],
) -> u8 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

/// A picture as five rows of hex digits (as the firmware logs it).
pub fn hex_rows(rows: &[[u8; leds::SIZE]; leds::SIZE]) -> String {
    rows.iter()
        .map(|row| {
            row.iter()
                .map(|&level| format!("{level:x}"))
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join(" ")
}
