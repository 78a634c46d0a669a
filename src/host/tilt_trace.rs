//! Tilt traces: recorded accelerometer readings for the simulator.
//!
//! ```text
//! t_s,ax_mg,ay_mg,az_mg
//! 0,0,1000,0
//! 0.5,-200,980,0        ← from 0.5 s on: tilted so the marble rolls towards +x'
//! ```
//!
//! Readings are in the board frame (x' right, y' up, z' towards the player; a flat
//! board reads `(0, +1000, 0)`; `ax < 0` rolls the marble towards +x'), exactly what
//! the accelerometer hands [`crate::game::session::Session::frame`]. Each sample
//! holds until the next one; before the first one the board lies flat. Times must
//! not decrease. Blank lines and lines starting with `#` are ignored; numbers may
//! have decimals (readings are rounded to whole milli-g). A leading UTF-8
//! byte-order mark (some editors save one) is skipped. A file that is not UTF-8
//! is refused at the line of its first bad byte ([`TiltTrace::from_bytes`]);
//! an error quotes at most 60 characters of the text it refuses.

use std::format;
use std::string::String;
use std::vec::Vec;

use super::excerpt;
use crate::input::axes::AccelMg;

/// The required header.
pub(crate) const HEADER: &str = "t_s,ax_mg,ay_mg,az_mg";

/// Largest reading magnitude accepted per axis (mg): anything beyond the widest
/// accelerometer range is a typo.
pub const MAX_READING_MG: f64 = 16_000.0;

/// A flat board's reading.
pub(crate) const FLAT: AccelMg = AccelMg::LEVEL;

/// A parsed trace.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TiltTrace {
    samples: Vec<(f64, AccelMg)>,
    next: usize,
}

/// A problem with a trace: the 1-based line and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct TraceError {
    /// 1-based line.
    pub(crate) line: usize,
    /// What is wrong.
    pub(crate) message: String,
}

impl core::fmt::Display for TraceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl TiltTrace {
    /// Parses a trace read as bytes: [`Self::parse`] once they are UTF-8, else
    /// an error at the line of the first bad byte, naming it and its column.
    pub(crate) fn from_bytes(bytes: &[u8]) -> Result<TiltTrace, TraceError> {
        match core::str::from_utf8(bytes) {
            Ok(text) => Self::parse(text),
            Err(e) => {
                let (valid, rest) = bytes.split_at(e.valid_up_to());
                let start = valid.iter().rposition(|&c| c == b'\n').map_or(0, |n| n + 1);
                // The valid prefix ends on a character boundary; a BOM is a character.
                let column = core::str::from_utf8(&valid[start..])
                    .map_or(1, |l| l.trim_start_matches('\u{feff}').chars().count() + 1);
                Err(TraceError {
                    line: valid.iter().filter(|&&c| c == b'\n').count() + 1,
                    message: format!(
                        "not UTF-8 (byte 0x{:02X}, column {column})",
                        rest.first().copied().unwrap_or_default()
                    ),
                })
            }
        }
    }

    /// Parses a trace's text.
    /// A leading UTF-8 byte-order mark is skipped.
    pub(crate) fn parse(text: &str) -> Result<TiltTrace, TraceError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut samples = Vec::new();
        let mut header = false;
        let names = ["t_s", "ax_mg", "ay_mg", "az_mg"];
        for (n, raw) in text.lines().enumerate() {
            let line = n + 1;
            let l = raw.trim();
            if l.is_empty() || l.starts_with('#') {
                continue;
            }
            let err = |message: String| TraceError { line, message };
            if !header {
                let cols: Vec<&str> = l.split(',').map(str::trim).collect();
                if cols != names {
                    return Err(err(format!(
                        "expected the header `{HEADER}`, found {}",
                        excerpt(l)
                    )));
                }
                header = true;
                continue;
            }
            let fields: Vec<&str> = l.split(',').map(str::trim).collect();
            if fields.len() != 4 {
                return Err(err(format!(
                    "expected 4 comma-separated fields ({HEADER}), found {}",
                    fields.len()
                )));
            }
            let mut v = [0f64; 4];
            for (i, f) in fields.iter().enumerate() {
                v[i] = match f.parse::<f64>() {
                    Ok(x) if x.is_finite() => x,
                    _ => return Err(err(format!("{}: {} is not a number", names[i], excerpt(f)))),
                };
            }
            // Numbers are quoted as written: `{}` of an f64 writes 1e300 in 301 digits.
            let t = v[0];
            if t < 0.0 {
                return Err(err(format!("t_s: {} is negative", excerpt(fields[0]))));
            }
            if let Some(&(prev, _, prev_text)) = samples.last() {
                if t < prev {
                    return Err(err(format!(
                        "t_s: {} is earlier than the previous sample's {}",
                        excerpt(fields[0]),
                        excerpt(prev_text)
                    )));
                }
            }
            let mut mg = [0i32; 3];
            for i in 0..3 {
                if v[i + 1].abs() > MAX_READING_MG {
                    return Err(err(format!(
                        "{}: {} is beyond ±{MAX_READING_MG} mg",
                        names[i + 1],
                        excerpt(fields[i + 1])
                    )));
                }
                mg[i] = v[i + 1].round() as i32;
            }
            samples.push((t, AccelMg::from_array(mg), fields[0]));
        }
        if !header {
            return Err(TraceError {
                line: 1,
                message: format!("empty trace: expected the header `{HEADER}`"),
            });
        }
        let samples = samples.into_iter().map(|(t, mg, _)| (t, mg)).collect();
        Ok(TiltTrace { samples, next: 0 })
    }

    /// The reading in force at `t` seconds: the last sample at or before `t`, or a
    /// flat board before the first one. Calls must come with non-decreasing `t`
    /// (the simulator's frames); an earlier `t` starts the search over.
    pub(crate) fn reading_at(&mut self, t: f64) -> AccelMg {
        if self.next > 0 && self.samples[self.next - 1].0 > t {
            self.next = 0;
        }
        while self.next < self.samples.len() && self.samples[self.next].0 <= t {
            self.next += 1;
        }
        if self.next == 0 {
            FLAT
        } else {
            self.samples[self.next - 1].1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_samples() {
        let mut t =
            TiltTrace::parse("t_s,ax_mg,ay_mg,az_mg\n0.5,-200,980,0\n1,0,1000,10.4\n").unwrap();
        assert_eq!(t.reading_at(0.0), FLAT);
        assert_eq!(t.reading_at(0.5), AccelMg::new(-200, 980, 0));
        assert_eq!(t.reading_at(0.99), AccelMg::new(-200, 980, 0));
        assert_eq!(t.reading_at(7.0), AccelMg::new(0, 1000, 10));
        assert_eq!(t.reading_at(0.1), FLAT);
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        let plain = "t_s,ax_mg,ay_mg,az_mg\n0.5,-200,980,0\n";
        let with_bom = TiltTrace::parse(&format!("\u{feff}{plain}")).unwrap();
        assert_eq!(with_bom, TiltTrace::parse(plain).unwrap());
        // Only at the very start: anywhere else it is still a bad header or number.
        assert!(TiltTrace::parse(&format!("\u{feff}\u{feff}{plain}")).is_err());
    }

    #[test]
    fn bytes_that_are_not_utf8_are_refused_at_their_line_and_column() {
        let plain = b"t_s,ax_mg,ay_mg,az_mg\n0.5,-200,980,0\n";
        assert_eq!(
            TiltTrace::from_bytes(plain),
            TiltTrace::parse(core::str::from_utf8(plain).unwrap())
        );
        for (bytes, line, message) in [
            (
                &b"t_s,ax_mg,ay_mg,az_mg\n\n0,1\xff"[..],
                3,
                "byte 0xFF, column 4",
            ),
            // The column counts characters, after a byte-order mark on line 1.
            (b"\xef\xbb\xbf\xc3\xa9\xc3", 1, "byte 0xC3, column 2"),
        ] {
            let e = TiltTrace::from_bytes(bytes).unwrap_err();
            assert_eq!(e.line, line);
            assert_eq!(e.message, format!("not UTF-8 ({message})"));
        }
    }

    #[test]
    fn reports_lines() {
        let e =
            TiltTrace::parse("t_s,ax_mg,ay_mg,az_mg\n\n0,0,1000,0\n0.1,x,1000,0\n").unwrap_err();
        assert_eq!(e.line, 4);
        assert!(e.message.contains("ax_mg"), "{e}");
        assert_eq!(TiltTrace::parse("t,x,y,z\n").unwrap_err().line, 1);
        assert_eq!(
            TiltTrace::parse("t_s,ax_mg,ay_mg,az_mg\n1,0,0\n")
                .unwrap_err()
                .line,
            2
        );
        assert_eq!(
            TiltTrace::parse("t_s,ax_mg,ay_mg,az_mg\n1,0,0,0\n0.5,0,0,0")
                .unwrap_err()
                .line,
            3
        );
    }
}
