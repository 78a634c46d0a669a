//! The level text as bytes: lines, spaces, the grid's shape and the header's
//! decimals, all `const fn`, so that a built-in level is read at compile time
//! by the very code that reads a file at run time.

/// The line between two storeys of the grid (listed top to bottom).
const STOREY_SEPARATOR: &[u8] = b"===";

/// The text after a leading UTF-8 byte-order mark (`EF BB BF`), if there is one:
/// editors on some systems save one, and it is not part of the first line.
pub(super) const fn without_bom(b: &[u8]) -> &[u8] {
    if b.len() >= 3 && b[0] == 0xEF && b[1] == 0xBB && b[2] == 0xBF {
        b.split_at(3).1
    } else {
        b
    }
}

pub(super) const fn line_end(b: &[u8], mut i: usize) -> usize {
    while i < b.len() && b[i] != b'\n' {
        i += 1;
    }
    i
}

/// The end of a line without a trailing `\r` and spaces.
pub(super) const fn trim_end(b: &[u8], start: usize, mut end: usize) -> usize {
    while end > start && (b[end - 1] == b'\r' || b[end - 1] == b' ' || b[end - 1] == b'\t') {
        end -= 1;
    }
    end
}

pub(super) const fn skip_spaces(b: &[u8], mut i: usize, end: usize) -> usize {
    while i < end && (b[i] == b' ' || b[i] == b'\t') {
        i += 1;
    }
    i
}

/// Byte offset of the first grid row (after the `---` line).
pub(super) const fn grid_start(b: &[u8]) -> Option<usize> {
    let mut i = 0;
    while i < b.len() {
        let e = line_end(b, i);
        let t = trim_end(b, i, e);
        if t - i == 3 && b[i] == b'-' && b[i + 1] == b'-' && b[i + 2] == b'-' {
            return Some(if e < b.len() { e + 1 } else { e });
        }
        i = e + 1;
    }
    None
}

/// Whether the line `[start, end)` (trimmed) separates two storeys.
pub(super) const fn is_separator(b: &[u8], start: usize, end: usize) -> bool {
    eq_bytes(b, start, end, STOREY_SEPARATOR)
}

/// Columns of the first row, rows of the first storey, and storeys (rows
/// before the first `===`, and one more storey per `===`).
pub(super) const fn grid_shape(b: &[u8], start: usize) -> (usize, usize, usize) {
    let mut i = start;
    let mut nx = 0;
    let mut nz = 0;
    let mut storeys = 0;
    while i < b.len() {
        let e = line_end(b, i);
        let t = trim_end(b, i, e);
        if t > i {
            if is_separator(b, i, t) {
                storeys += 1;
            } else {
                if nx == 0 && nz == 0 {
                    nx = count_chars(b, i, t);
                }
                if storeys == 0 {
                    nz += 1;
                }
            }
        }
        i = e + 1;
    }
    (nx, nz, storeys + 1)
}

pub(super) const fn count_chars(b: &[u8], start: usize, end: usize) -> usize {
    let mut n = 0;
    let mut i = start;
    while i < end {
        if b[i] & 0xC0 != 0x80 {
            n += 1;
        }
        i += 1;
    }
    n
}

pub(super) const fn eq_bytes(b: &[u8], start: usize, end: usize, word: &[u8]) -> bool {
    if end - start != word.len() {
        return false;
    }
    let mut i = 0;
    while i < word.len() {
        if b[start + i] != word[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// A well-formed header number: its value, or too many digits to hold (which is
/// out of any key's range, not "not a number").
pub(super) enum Digits {
    /// The value scaled by `10^decimals`.
    Value(u64),
    /// More than 10^12 before scaling.
    Huge,
}

/// A decimal with at most `decimals` fraction digits, scaled by `10^decimals`.
pub(super) const fn decimal(b: &[u8], start: usize, end: usize, decimals: u32) -> Option<Digits> {
    let mut i = start;
    let mut value: u64 = 0;
    let mut huge = false;
    let mut seen_digit = false;
    let mut frac: i32 = -1;
    while i < end {
        let c = b[i];
        if c == b'.' {
            if frac >= 0 {
                return None;
            }
            frac = 0;
        } else if c.is_ascii_digit() {
            if frac >= 0 {
                if frac as u32 >= decimals {
                    return None;
                }
                frac += 1;
            }
            if !huge {
                // At most 10^12 · 10 + 9: no overflow.
                value = value * 10 + (c - b'0') as u64;
                huge = value > 1_000_000_000_000;
            }
            seen_digit = true;
        } else {
            return None;
        }
        i += 1;
    }
    if !seen_digit {
        return None;
    }
    if huge {
        return Some(Digits::Huge);
    }
    let used = if frac < 0 { 0 } else { frac as u32 };
    let mut scale = used;
    while scale < decimals {
        value *= 10;
        scale += 1;
    }
    Some(Digits::Value(value))
}
