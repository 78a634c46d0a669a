//! The level's header: `key: value` lines up to `---`, read into the physics
//! spec, the effects, the name and the time limit, with the rules the physics
//! setup would refuse checked at the value that breaks them.

use super::errors::{err, LevelError, LevelErrorKind, NumberKey};
use super::scan::{decimal, eq_bytes, grid_start, line_end, skip_spaces, trim_end, Digits};
use crate::physics::dynamics::effects::Effects;
use crate::physics::geometry::tiles::{MAX_PITCH_UM, MIN_PITCH_UM};
use crate::physics::world::PhysicsSpec;

/// Where a header value was given: (line, line start, value start); line 0 if not.
type At = (usize, usize, usize);

/// The later of two header values (the one that completed a broken rule).
const fn later(a: At, b: At) -> At {
    if a.0 >= b.0 {
        a
    } else {
        b
    }
}

/// What a header says, and where the grid after it starts.
pub(super) struct Header<'a> {
    pub(super) name: &'a str,
    pub(super) spec: PhysicsSpec,
    pub(super) effects: Effects,
    pub(super) time_limit_s: u16,
    /// Byte offset of the grid's first line.
    pub(super) grid_at: usize,
    /// Its line number.
    pub(super) grid_line: usize,
}

/// Reads the header of `b` (the text without its byte-order mark).
pub(super) const fn header(b: &[u8]) -> Result<Header<'_>, LevelError> {
    if grid_start(b).is_none() {
        // Without `---` every grid row would read as a bad header line: say what is missing.
        let mut lines = 1;
        let mut p = 0;
        while p < b.len() {
            if b[p] == b'\n' && p + 1 < b.len() {
                lines += 1;
            }
            p += 1;
        }
        return Err(LevelError {
            line: lines + 1,
            column: 1,
            kind: LevelErrorKind::MissingSeparator,
        });
    }
    let mut spec = PhysicsSpec::DEFAULT;
    let mut effects = Effects {
        rolling: true,
        ..Effects::NONE
    };
    let mut name: &str = "untitled";
    let mut time_limit_s = 60u16;
    let mut short_at: At = (0, 0, 0);
    let mut long_at: At = (0, 0, 0);
    let mut radius_at: At = (0, 0, 0);
    let mut i = 0;
    let mut line: usize = 1;
    let mut separator = false;
    // Header.
    while i < b.len() {
        let e = line_end(b, i);
        let t = trim_end(b, i, e);
        let s = skip_spaces(b, i, t);
        if eq_bytes(b, s, t, b"---") {
            separator = true;
            i = if e < b.len() { e + 1 } else { e };
            line += 1;
            break;
        }
        if s < t {
            let mut colon = s;
            while colon < t && b[colon] != b':' {
                colon += 1;
            }
            if colon == t {
                return err(line, b, i, s, LevelErrorKind::MissingColon);
            }
            let kend = trim_end(b, s, colon);
            let v = skip_spaces(b, colon + 1, t);
            if eq_bytes(b, s, kend, b"name") {
                let (_, rest) = b.split_at(v);
                let (bytes, _) = rest.split_at(t - v);
                match core::str::from_utf8(bytes) {
                    Ok(n) => name = n,
                    Err(_) => return err(line, b, i, v, LevelErrorKind::BadName),
                }
            } else if eq_bytes(b, s, kend, b"effects") {
                // The exact list of what is on (holes and marbles follow from the grid).
                effects = Effects::NONE;
                let mut none_at = 0;
                let mut named = 0;
                let mut p = v;
                while p < t {
                    let p0 = skip_spaces(b, p, t);
                    let mut q = p0;
                    while q < t && b[q] != b',' {
                        q += 1;
                    }
                    let qe = trim_end(b, p0, q);
                    if eq_bytes(b, p0, qe, b"rolling") {
                        effects.rolling = true;
                    } else if eq_bytes(b, p0, qe, b"friction") {
                        effects.friction = true;
                    } else if eq_bytes(b, p0, qe, b"board_motion") {
                        effects.board_motion = true;
                    } else if eq_bytes(b, p0, qe, b"none") {
                        none_at = p0;
                    } else if qe > p0 {
                        return err(line, b, i, p0, LevelErrorKind::UnknownEffect);
                    }
                    if qe > p0 {
                        named += 1;
                    }
                    // `none` beside an effect says two things: neither is taken.
                    if none_at > 0 && named > 1 {
                        return err(line, b, i, none_at, LevelErrorKind::UnknownEffect);
                    }
                    p = q + 1;
                }
            } else {
                let Some(key) = NumberKey::find(b, s, kend) else {
                    return err(line, b, i, s, LevelErrorKind::UnknownKey);
                };
                // A minus sign makes a number below every key's range (none
                // starts under 0), which the person must be told, not that it
                // is no number at all; `-0` is 0.
                let negative = v < t && b[v] == b'-';
                let digits = if negative { v + 1 } else { v };
                let Some(n) = decimal(b, digits, t, key.decimals()) else {
                    return err(line, b, i, v, LevelErrorKind::BadNumber);
                };
                let (lo, hi) = key.range();
                // Past `decimal`'s bound the number is still a number: out of range.
                let n = match n {
                    Digits::Value(n) if n >= lo && n <= hi && (n == 0 || !negative) => n as u32,
                    _ => return err(line, b, i, v, LevelErrorKind::OutOfRange { key }),
                };
                match key {
                    NumberKey::ShortMm => {
                        spec.short_um = n;
                        short_at = (line, i, v);
                    }
                    NumberKey::LongMm => {
                        spec.long_um = n;
                        long_at = (line, i, v);
                    }
                    NumberKey::MarbleRadiusMm => {
                        spec.radius_um = n;
                        radius_at = (line, i, v);
                    }
                    NumberKey::Restitution => spec.restitution_milli = n,
                    NumberKey::RollingResistance => spec.rolling_resistance_ppm = n,
                    // 1 ..= 3600, checked above.
                    NumberKey::TimeLimitS => time_limit_s = n as u16,
                }
            }
        }
        i = e + 1;
        line += 1;
    }
    if !separator {
        return Err(LevelError {
            line: line as u32,
            column: 1,
            kind: LevelErrorKind::MissingSeparator,
        });
    }
    // What `Params::new` checks, in its order (each value is already 0.001 ..= 100 mm,
    // so no width is zero). A rule of two values is reported at the later one given.
    let pitch = spec.short_um as u64 + spec.long_um as u64;
    if pitch < MIN_PITCH_UM as u64 || pitch > MAX_PITCH_UM as u64 {
        let (l, ls, at) = later(short_at, long_at);
        let kind = LevelErrorKind::PitchOutOfRange {
            short_um: spec.short_um,
            long_um: spec.long_um,
        };
        return err(if l == 0 { 1 } else { l }, b, ls, at, kind);
    }
    if 2 * spec.radius_um as u64 >= spec.long_um as u64 {
        let (l, ls, at) = later(radius_at, long_at);
        let kind = LevelErrorKind::MarbleTooBig {
            radius_um: spec.radius_um,
            long_um: spec.long_um,
        };
        return err(if l == 0 { 1 } else { l }, b, ls, at, kind);
    }
    Ok(Header {
        name,
        spec,
        effects,
        time_limit_s,
        grid_at: i,
        grid_line: line,
    })
}
