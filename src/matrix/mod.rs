//! Pin-agnostic LED-matrix frames and binary-coded-modulation (BCM) scanning.
//!
//! This module is shared by every board that has an LED matrix: the BBC
//! micro:bit v2 (5×5, rows active high, columns active low) and the QEMU
//! virtual matrix. It knows nothing about pins or polarity: a board asks the
//! [`Scanner`] for the next [`ScanStep`], drives "row `row` on, columns
//! `columns` lit" in whatever way its hardware needs, holds that for
//! `ticks` base ticks, then blanks and asks again.
//!
//! # Why this is written by hand
//!
//! No available crate does BCM scanning for an arbitrary matrix wired to
//! arbitrary pins: board crates hard-wire their own display drivers (usually
//! plain on/off or PWM per pixel with their own timers and pin types), and the
//! virtual matrix under QEMU has no pins at all. The scanner here is small,
//! allocation-free, panic-free and division-free per step (the Cortex-M0 has
//! no hardware divider), which a generic dependency could not promise.
//!
//! # Timing model
//!
//! Brightness `b` (0..=[`MAX_BRIGHTNESS`]) is split into [`BCM_BITS`] bits.
//! For every row, in turn, the scanner emits one step per bit ("slice"); the
//! slice for bit `k` lasts `2^k` base ticks and lights exactly the pixels of
//! that row whose brightness has bit `k` set. A row therefore lasts
//! [`TICKS_PER_ROW`] = `2^BCM_BITS - 1` ticks whatever its content, a pixel of
//! brightness `b` is lit for exactly `b` of them (0 → never, 15 → always), and
//! a full refresh lasts [`Scanner::TICKS_PER_REFRESH`] = `H × TICKS_PER_ROW`
//! ticks. To reach a refresh rate `f`, clock the base tick at
//! [`base_tick_hz`]`::<H>(f)` = `f × H × TICKS_PER_ROW` Hz (100 Hz on the
//! 5×5 micro:bit → 7500 Hz, a 133 µs base tick).
//!
//! # Slice order and flicker
//!
//! Slices are emitted in [`SLICE_ORDER`] (most significant first), the same
//! order in every row and every refresh. With row-at-a-time scanning each
//! pixel's light repeats exactly once per refresh whatever the order inside a
//! row, so the order cannot raise the flicker frequency: the refresh rate
//! (≥ 100 Hz) is what keeps the display steady. What the order *can* do is add
//! flicker: alternating orders between refreshes would move a pixel's light
//! around inside its row slot and add a half-refresh-rate component, so the
//! order is fixed. MSB first makes the one long slice start right after the
//! row switches on and leaves the short, timing-critical slices at the end of
//! the row, where a late interrupt only delays the next row's start.
//!
//! [`Scanner`]: crate::matrix::Scanner
//! [`ScanStep`]: crate::matrix::ScanStep
//! [`MAX_BRIGHTNESS`]: crate::matrix::MAX_BRIGHTNESS
//! [`BCM_BITS`]: crate::matrix::BCM_BITS
//! [`TICKS_PER_ROW`]: crate::matrix::TICKS_PER_ROW
//! [`Scanner::TICKS_PER_REFRESH`]: crate::matrix::Scanner::TICKS_PER_REFRESH
//! [`base_tick_hz`]: crate::matrix::base_tick_hz
//! [`SLICE_ORDER`]: crate::matrix::SLICE_ORDER

pub mod output;

/// One pixel's brightness level: 0 (off) ..= [`MAX_BRIGHTNESS`] (fully on).
pub type Brightness = u8;

/// Number of BCM bits (time slices per row).
pub const BCM_BITS: usize = 4;

/// Number of distinct brightness levels (`2^BCM_BITS` = 16).
pub const LEVELS: usize = 1 << BCM_BITS;

/// The brightest level; larger values are clamped to it.
pub const MAX_BRIGHTNESS: Brightness = (LEVELS - 1) as Brightness;

/// Base ticks one row is displayed for in each refresh (`2^BCM_BITS - 1`).
pub const TICKS_PER_ROW: u32 = (1 << BCM_BITS) - 1;

/// Order in which a row's BCM slices (bit numbers) are emitted.
pub const SLICE_ORDER: [u8; BCM_BITS] = [3, 2, 1, 0];

/// Widest supported matrix: a row's column pattern is a `u32` bitmask.
pub(crate) const MAX_WIDTH: usize = 32;

/// Base tick frequency (Hz) that gives `refresh_hz` full refreshes per second
/// of an `H`-row matrix: `refresh_hz × H × TICKS_PER_ROW` (saturating).
pub const fn base_tick_hz<const H: usize>(refresh_hz: u32) -> u32 {
    let per_refresh = (H as u32).saturating_mul(TICKS_PER_ROW);
    refresh_hz.saturating_mul(per_refresh)
}

/// Clamps a brightness to `0..=MAX_BRIGHTNESS`.
const fn clamp(level: Brightness) -> Brightness {
    if level > MAX_BRIGHTNESS {
        MAX_BRIGHTNESS
    } else {
        level
    }
}

/// A `W`×`H` image of brightness levels. Pixel `(x, y)`: `x` is the column
/// (left → right), `y` the row (top → bottom). Every stored level is within
/// `0..=MAX_BRIGHTNESS`.
///
/// Word-aligned: a frame is copied on its way from the game to the display
/// (a signal in, a signal out), and word copies are about three times
/// cheaper than the byte copies an align-1 array gets.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(C, align(4))]
pub struct Frame<const W: usize, const H: usize> {
    rows: [[Brightness; W]; H],
}

impl<const W: usize, const H: usize> Default for Frame<W, H> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const W: usize, const H: usize> Frame<W, H> {
    /// Width in pixels (columns).
    pub const WIDTH: usize = W;
    /// Height in pixels (rows).
    pub const HEIGHT: usize = H;

    /// A blank (all off) frame.
    pub const fn new() -> Self {
        Self { rows: [[0; W]; H] }
    }

    /// A blank (all off) frame; same as [`Frame::new`].
    pub const fn blank() -> Self {
        Self::new()
    }

    /// A frame with every pixel at `level` (clamped).
    pub const fn filled(level: Brightness) -> Self {
        Self {
            rows: [[clamp(level); W]; H],
        }
    }

    /// A frame from rows of levels, `rows[y][x]`; levels are clamped.
    pub const fn from_rows(rows: [[Brightness; W]; H]) -> Self {
        let mut rows = rows;
        let mut y = 0;
        while y < H {
            let mut x = 0;
            while x < W {
                rows[y][x] = clamp(rows[y][x]);
                x += 1;
            }
            y += 1;
        }
        Self { rows }
    }

    /// The level at `(x, y)`, or 0 when out of range.
    pub fn get(&self, x: usize, y: usize) -> Brightness {
        self.rows
            .get(y)
            .and_then(|row| row.get(x))
            .copied()
            .unwrap_or(0)
    }

    /// Sets `(x, y)` to `level` (clamped to `MAX_BRIGHTNESS`); ignored when
    /// out of range.
    pub fn set(&mut self, x: usize, y: usize, level: Brightness) {
        if let Some(pixel) = self.rows.get_mut(y).and_then(|row| row.get_mut(x)) {
            *pixel = clamp(level);
        }
    }

    /// Sets every pixel to `level` (clamped).
    pub fn fill(&mut self, level: Brightness) {
        *self = Self::filled(level);
    }

    /// Turns every pixel off.
    pub fn clear(&mut self) {
        self.fill(0);
    }

    /// Whether every pixel is off.
    pub fn is_blank(&self) -> bool {
        self.rows.iter().flatten().all(|&level| level == 0)
    }

    /// The rows of levels, `rows()[y][x]`.
    pub const fn rows(&self) -> &[[Brightness; W]; H] {
        &self.rows
    }

    /// Every pixel as `(x, y, level)`, row by row, left to right.
    pub fn iter(&self) -> impl Iterator<Item = (usize, usize, Brightness)> + '_ {
        self.rows
            .iter()
            .enumerate()
            .flat_map(|(y, row)| row.iter().enumerate().map(move |(x, &level)| (x, y, level)))
    }
}

/// One thing for a board to display: light row `row` with the columns whose
/// bits are set in `columns` (bit `x` = column `x`), hold it for `ticks` base
/// ticks, then blank.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ScanStep {
    /// Row to drive, `0..H`.
    pub row: usize,
    /// Column on-pattern: bit `x` set = column `x` lit.
    pub columns: u32,
    /// How long to hold the pattern, in base ticks (a power of two).
    pub ticks: u32,
}

/// Per-row, per-bit column masks: `[y][k]` has bit `x` set when pixel
/// `(x, y)` has bit `k` of its brightness set.
type Planes<const H: usize> = [[u32; BCM_BITS]; H];

/// The bit planes of one row of levels (each `≤ MAX_BRIGHTNESS`, so four
/// bits): `[k]` has bit `x` set when level `x` has bit `k` set.
///
/// Four pixels at a time: four bytes of the row are put in a little-endian word,
/// `(word >> k) & 0x01010101` keeps bit `k` of each byte, and multiplying by
/// `0x01020408` moves byte `i`'s bit to bit `24 + i` (the other partial
/// products land on bits 3, 10, 11, 17, 18, 19 or above 31, all apart, so
/// nothing carries into bits 24..=27). About six instructions per pixel
/// where a pixel-by-pixel loop takes sixteen: a frame is loaded up to a
/// hundred times a second.
fn row_planes<const W: usize>(levels: &[Brightness; W]) -> [u32; BCM_BITS] {
    const _: () = assert!(BCM_BITS == 4, "row_planes builds exactly four planes");
    const LOW_BITS: u32 = 0x0101_0101;
    const GATHER: u32 = 0x0102_0408;
    let gather = |word: u32| (word & LOW_BITS).wrapping_mul(GATHER) >> 24;
    // Four accumulators, not an array: they stay in registers.
    let (mut b0, mut b1, mut b2, mut b3) = (0u32, 0u32, 0u32, 0u32);
    let mut x = 0;
    while x < W.min(MAX_WIDTH) {
        let word = match levels.get(x..x + 4) {
            Some(&[p0, p1, p2, p3]) => u32::from_le_bytes([p0, p1, p2, p3]),
            // The last, partial group (W not a multiple of four).
            _ => levels
                .iter()
                .skip(x)
                .rev()
                .fold(0, |word, &level| (word << 8) | u32::from(level)),
        };
        b0 |= gather(word) << x;
        b1 |= gather(word >> 1) << x;
        b2 |= gather(word >> 2) << x;
        b3 |= gather(word >> 3) << x;
        x += 4;
    }
    [b0, b1, b2, b3]
}

/// Double-buffered BCM scanner for a `W`×`H` matrix (`1 ≤ W ≤ 32`, `H ≥ 1`).
///
/// [`Scanner::load`] converts a frame into bit planes in the back buffer; the
/// back buffer becomes visible only at the start of the next full refresh, so
/// a refresh never mixes two frames. [`Scanner::next_step`] (also the
/// endless [`Iterator`]) walks rows top to bottom and each row's slices in
/// [`SLICE_ORDER`], using only indexing, shifts and compares.
#[derive(Clone, Debug)]
pub struct Scanner<const W: usize, const H: usize> {
    buffers: [Planes<H>; 2],
    front: usize,
    pending: bool,
    row: usize,
    slot: usize,
}

impl<const W: usize, const H: usize> Default for Scanner<W, H> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const W: usize, const H: usize> Scanner<W, H> {
    /// Compile-time check of the supported sizes.
    const VALID_SIZE: () = assert!(
        W >= 1 && W <= MAX_WIDTH && H >= 1,
        "Scanner needs 1 <= W <= 32 and H >= 1"
    );

    /// Base ticks in one full refresh: `H × TICKS_PER_ROW`.
    pub const TICKS_PER_REFRESH: u32 = H as u32 * TICKS_PER_ROW;

    /// Steps in one full refresh: `H × BCM_BITS`.
    pub const STEPS_PER_REFRESH: usize = H * BCM_BITS;

    /// A scanner showing a blank frame, positioned at the start of a refresh.
    pub const fn new() -> Self {
        let () = Self::VALID_SIZE;
        Self {
            buffers: [[[0; BCM_BITS]; H]; 2],
            front: 0,
            pending: false,
            row: 0,
            slot: 0,
        }
    }

    /// A scanner already showing `frame`.
    pub fn with_frame(frame: &Frame<W, H>) -> Self {
        let mut scanner = Self::new();
        scanner.load(frame);
        scanner
    }

    /// Queues `frame` for display from the start of the next full refresh
    /// (immediately if no step of the current refresh has been taken yet).
    /// Loading again before then replaces the queued frame; loading the frame
    /// already on show queues nothing (and cancels a queued one), so a caller
    /// need not compare frames itself.
    pub fn load(&mut self, frame: &Frame<W, H>) {
        let [zero, one] = &mut self.buffers;
        let (shown, back) = if self.front == 0 {
            (&*zero, one)
        } else {
            (&*one, zero)
        };
        // Whether any plane differs from the one on show, found while writing.
        let mut differ = 0;
        for ((masks, old), levels) in back.iter_mut().zip(shown.iter()).zip(frame.rows.iter()) {
            for ((mask, &old), new) in masks.iter_mut().zip(old).zip(row_planes(levels)) {
                differ |= old ^ new;
                *mask = new;
            }
        }
        self.pending = differ != 0;
    }

    /// Whether a loaded frame is waiting for the next refresh.
    pub const fn has_pending(&self) -> bool {
        self.pending
    }

    /// Whether the next step is the first of a refresh.
    pub const fn at_refresh_start(&self) -> bool {
        self.row == 0 && self.slot == 0
    }

    /// Restarts scanning at the top of a refresh (a queued frame is shown).
    pub fn restart(&mut self) {
        self.row = 0;
        self.slot = 0;
    }

    /// The next step in display order. Never panics, allocates or divides.
    #[inline]
    pub fn next_step(&mut self) -> ScanStep {
        if self.at_refresh_start() && self.pending {
            self.front = (self.front ^ 1) & 1;
            self.pending = false;
        }
        let bit = SLICE_ORDER.get(self.slot).copied().unwrap_or(0);
        let columns = self
            .buffers
            .get(self.front)
            .and_then(|planes| planes.get(self.row))
            .and_then(|masks| masks.get(usize::from(bit)))
            .copied()
            .unwrap_or(0);
        let step = ScanStep {
            row: self.row,
            columns,
            ticks: 1 << bit,
        };
        self.slot += 1;
        if self.slot >= BCM_BITS {
            self.slot = 0;
            self.row += 1;
            if self.row >= H {
                self.row = 0;
            }
        }
        step
    }
}

impl<const W: usize, const H: usize> Iterator for Scanner<W, H> {
    type Item = ScanStep;

    /// Always `Some`: scanning never ends.
    fn next(&mut self) -> Option<ScanStep> {
        Some(self.next_step())
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (usize::MAX, None)
    }
}

/// `on × MAX_BRIGHTNESS / period` rounded half up, clamped (`period > 0`).
fn perceived_level(on: u32, period: u32) -> Brightness {
    let max = u32::from(MAX_BRIGHTNESS);
    let rounded = if period < 1 << 27 && on <= period {
        // Fits in 32 bits: a hardware divide, not a 64-bit library call.
        (2 * on * max + period) / (2 * period)
    } else {
        let period = u64::from(period);
        let scaled = u64::from(on) * u64::from(max);
        u32::try_from((2 * scaled + period) / (2 * period)).unwrap_or(u32::MAX)
    };
    Brightness::try_from(rounded).map_or(MAX_BRIGHTNESS, clamp)
}

/// Bits of an [`OnTimeIntegrator`] counter: a pixel's on-time saturates at
/// `u32::MAX` base ticks.
const COUNTER_BITS: usize = 32;

/// Accumulates the on-time of every pixel from a stream of [`ScanStep`]s and
/// turns it back into the frame a viewer would perceive: what the virtual
/// (QEMU) matrix shows in place of real LEDs.
///
/// # Bit-sliced counters
///
/// A scan step lights up to `W` pixels of one row for the same time, and the
/// virtual matrix takes thousands of steps a second, while the perceived
/// frame is read a few times a second. So the counters are stored the way
/// the steps arrive: for each row, counter bit `j` of every column in one
/// word (bit `x` = column `x`). Adding `2^k` ticks to all lit columns at once
/// is a ripple-carry add of the column mask into words `k, k+1, …`, which
/// stops as soon as no column carries — a handful of instructions per step
/// however many pixels are lit (adding pixel by pixel cost five per lit
/// pixel, the largest single item of the QEMU firmware's CPU load). Reading
/// a pixel back gathers its bits from the words.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OnTimeIntegrator<const W: usize, const H: usize> {
    /// `on[y][j]`: bit `j` of the on-time of every column of row `y`.
    on: [[u32; COUNTER_BITS]; H],
    row_ticks: [u32; H],
}

impl<const W: usize, const H: usize> Default for OnTimeIntegrator<W, H> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const W: usize, const H: usize> OnTimeIntegrator<W, H> {
    /// The column bits of a row (`W ≤ 32`; wider columns are never counted).
    const COLUMNS: u32 = if W >= MAX_WIDTH {
        u32::MAX
    } else {
        (1u32 << W) - 1
    };

    /// An integrator with nothing accumulated.
    pub const fn new() -> Self {
        Self {
            on: [[0; COUNTER_BITS]; H],
            row_ticks: [0; H],
        }
    }

    /// Forgets everything accumulated.
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    /// Adds one step: its row is driven for `ticks`, and each lit column of
    /// it is on for `ticks`. Rows `≥ H` and column bits `≥ W` are ignored;
    /// counters saturate.
    #[inline]
    pub fn feed(&mut self, step: ScanStep) {
        let (Some(row_total), Some(counters)) =
            (self.row_ticks.get_mut(step.row), self.on.get_mut(step.row))
        else {
            return;
        };
        *row_total = row_total.saturating_add(step.ticks);
        let lit = step.columns & Self::COLUMNS;
        if lit == 0 {
            return;
        }
        // One ripple-carry add per set bit of `ticks` (one for scan steps,
        // whose ticks are powers of two).
        let mut ticks = step.ticks;
        while ticks != 0 {
            let mut j = ticks.trailing_zeros() as usize;
            ticks &= ticks - 1;
            let mut carry = lit;
            while carry != 0 {
                if let Some(bits) = counters.get_mut(j) {
                    let sum = *bits ^ carry;
                    carry &= *bits;
                    *bits = sum;
                    j += 1;
                } else {
                    // Carried out of the top bit: those columns saturate.
                    for bits in counters.iter_mut() {
                        *bits |= carry;
                    }
                    break;
                }
            }
        }
    }

    /// Feeds every step of `steps`.
    pub fn feed_all<I: IntoIterator<Item = ScanStep>>(&mut self, steps: I) {
        steps.into_iter().for_each(|step| self.feed(step));
    }

    /// Ticks pixel `(x, y)` has been on (0 when out of range).
    pub fn on_ticks(&self, x: usize, y: usize) -> u32 {
        self.row_on_ticks(y).get(x).copied().unwrap_or(0)
    }

    /// The on-times of row `y`'s pixels (zeros when out of range): each
    /// counter word's set bits added to their columns, so the cost follows
    /// the bits set rather than `W × 32`.
    fn row_on_ticks(&self, y: usize) -> [u32; W] {
        let mut on = [0u32; W];
        if let Some(counters) = self.on.get(y) {
            for (j, &bits) in counters.iter().enumerate() {
                let mut rest = bits;
                while rest != 0 {
                    if let Some(ticks) = on.get_mut(rest.trailing_zeros() as usize) {
                        *ticks |= 1 << j;
                    }
                    rest &= rest - 1;
                }
            }
        }
        on
    }

    /// Ticks row `y` has been driven (0 when out of range).
    pub fn row_ticks(&self, y: usize) -> u32 {
        self.row_ticks.get(y).copied().unwrap_or(0)
    }

    /// The perceived frame: each pixel's level is
    /// `on_ticks × MAX_BRIGHTNESS / row_ticks` of its row, rounded half up
    /// (0 for a row never driven).
    pub fn perceived(&self) -> Frame<W, H> {
        let mut frame = Frame::new();
        for (y, (levels, &period)) in frame.rows.iter_mut().zip(self.row_ticks.iter()).enumerate() {
            if period == 0 {
                continue;
            }
            for (level, on) in levels.iter_mut().zip(self.row_on_ticks(y)) {
                *level = perceived_level(on, period);
            }
        }
        frame
    }

    /// The perceived frame, then [`reset`](Self::reset) (e.g. once per refresh).
    pub fn take_perceived(&mut self) -> Frame<W, H> {
        let frame = self.perceived();
        self.reset();
        frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slice_order_covers_every_bit_once() {
        let mut seen = [false; BCM_BITS];
        for &bit in &SLICE_ORDER {
            let slot = &mut seen[usize::from(bit)];
            assert!(!*slot, "bit {bit} repeated");
            *slot = true;
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn constants_agree() {
        assert_eq!(LEVELS, 16);
        assert_eq!(MAX_BRIGHTNESS, 15);
        assert_eq!(TICKS_PER_ROW, 15);
        let sum: u32 = SLICE_ORDER.iter().map(|&b| 1u32 << b).sum();
        assert_eq!(sum, TICKS_PER_ROW);
    }

    #[test]
    fn restart_goes_back_to_the_top() {
        let mut scanner = Scanner::<3, 3>::new();
        scanner.next_step();
        scanner.next_step();
        assert!(!scanner.at_refresh_start());
        scanner.restart();
        assert!(scanner.at_refresh_start());
        assert_eq!(scanner.next_step().row, 0);
    }
}
