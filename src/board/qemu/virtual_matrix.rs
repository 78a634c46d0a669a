//! The virtual LED matrix: QEMU has no LEDs, so the scan steps of the shared
//! [`crate::matrix::Scanner`] are integrated per pixel
//! ([`OnTimeIntegrator`]) and the brightness a viewer would perceive is drawn
//! on the UART terminal with ANSI escapes (256-colour greys and shading
//! characters), or logged with defmt in headless runs.
//!
//! There is no real scan clock to wait for: each refresh's steps are
//! integrated at once and the display task then sleeps on a `Ticker` until
//! the next refresh (at [`REFRESH_HZ`]).

use core::fmt::Write as _;

use embassy_time::{Duration, Ticker};

use super::{HEIGHT, WIDTH};
use crate::app::{Console, Latest, MatrixOutput, FRAME_HZ, REFRESH_HZ};
use crate::game::levels::LEVELS;
use crate::game::player::Status;
use crate::matrix::{Brightness, Frame, OnTimeIntegrator, ScanStep, Scanner};

/// One picture of the virtual matrix.
type DisplayFrame = Frame<WIDTH, HEIGHT>;

/// Terminal redraws per second (at most; only changes are drawn).
pub const DRAW_HZ: u32 = 20;

/// Base ticks in one full refresh.
const TICKS_PER_REFRESH: u32 = Scanner::<WIDTH, HEIGHT>::TICKS_PER_REFRESH;

/// The virtual matrix, drawing on `C` (or only logging when `C` is absent).
pub struct VirtualMatrix<C: Console> {
    status: &'static Latest<Status>,
    integrator: OnTimeIntegrator<WIDTH, HEIGHT>,
    ticks_in_refresh: u32,
    refreshes: u32,
    ticker: Option<Ticker>,
    console: Option<C>,
    log_every: u32,
    drawn: Option<(DisplayFrame, Status)>,
    last_logged: Option<DisplayFrame>,
}

impl<C: Console> VirtualMatrix<C> {
    /// A matrix drawn on `console` (`None`: headless) with the game's
    /// `status` below it, that logs the perceived frame with defmt every
    /// `log_every` refreshes when it changed (0: never).
    pub fn new(status: &'static Latest<Status>, console: Option<C>, log_every: u32) -> Self {
        Self {
            status,
            integrator: OnTimeIntegrator::new(),
            ticks_in_refresh: 0,
            refreshes: 0,
            ticker: None,
            console,
            log_every,
            drawn: None,
            last_logged: None,
        }
    }

    /// Called after each full refresh.
    fn refreshed(&mut self) {
        self.refreshes = self.refreshes.wrapping_add(1);
        let draw_every = (REFRESH_HZ / DRAW_HZ).max(1);
        let log_due = self.log_every != 0 && self.refreshes.is_multiple_of(self.log_every);
        let draw_due = self.console.is_some() && self.refreshes.is_multiple_of(draw_every);
        if !(log_due || draw_due) {
            return;
        }
        // Perceived brightness over the refreshes since the last look.
        let frame = self.integrator.take_perceived();
        if log_due && self.last_logged != Some(frame) {
            self.last_logged = Some(frame);
            #[cfg(feature = "defmt")]
            defmt::info!("matrix {}", frame.rows());
        }
        if let (true, Some(console)) = (draw_due, self.console.as_mut()) {
            let mut status = self.status.get();
            // Redraw for whole tenths of a second only.
            status.frames -= status.frames % (FRAME_HZ / 10).max(1);
            let first = self.drawn.is_none();
            if self.drawn != Some((frame, status)) {
                draw(console, &frame, &status, first);
                self.drawn = Some((frame, status));
            }
        }
    }

    /// Waits for the next refresh slot (at [`REFRESH_HZ`]).
    async fn next_refresh(&mut self) {
        self.refreshed();
        let ticker = self
            .ticker
            .get_or_insert_with(|| Ticker::every(Duration::from_hz(u64::from(REFRESH_HZ))));
        ticker.next().await;
    }
}

impl<C: Console> MatrixOutput<WIDTH, HEIGHT> for VirtualMatrix<C> {
    async fn show(&mut self, step: ScanStep) {
        self.integrator.feed(step);
        self.ticks_in_refresh = self.ticks_in_refresh.saturating_add(step.ticks);
        if self.ticks_in_refresh < TICKS_PER_REFRESH {
            return;
        }
        self.ticks_in_refresh = 0;
        self.next_refresh().await;
    }

    /// The whole refresh into the integrator at once: no scan clock to wait
    /// for between steps.
    async fn show_refresh(&mut self, scanner: &mut Scanner<WIDTH, HEIGHT>) {
        for _ in 0..Scanner::<WIDTH, HEIGHT>::STEPS_PER_REFRESH {
            self.integrator.feed(scanner.next_step());
        }
        self.ticks_in_refresh = 0;
        self.next_refresh().await;
    }
}

/// `core::fmt` adapter for a [`Console`].
struct Out<'a, C: Console>(&'a mut C);

impl<C: Console> core::fmt::Write for Out<'_, C> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0.write(s.as_bytes());
        Ok(())
    }
}

/// 256-colour palette index for a brightness: greys 233..=255, 232 for off.
pub fn grey(level: Brightness) -> u8 {
    match level {
        0 => 232,
        level => 233 + ((u16::from(level.min(15)) - 1) * 22 / 14) as u8,
    }
}

/// Shading character for a brightness (so plain-text captures show it too):
/// with the renderer's levels, floor (1) `░`, wall (3) `▒`, lit goal (8)
/// `▓`, marble `█`.
pub fn shade(level: Brightness) -> &'static str {
    match level {
        0 => "\u{b7}",
        1..=2 => "\u{2591}",
        3..=5 => "\u{2592}",
        6..=10 => "\u{2593}",
        _ => "\u{2588}",
    }
}

/// Draws `frame` and a status line at the top left of the terminal; `clear`
/// first clears the screen and hides the cursor.
pub fn draw<C: Console>(console: &mut C, frame: &DisplayFrame, status: &Status, clear: bool) {
    let mut out = Out(console);
    if clear {
        out.0.write(b"\x1b[2J\x1b[?25l");
    }
    out.0.write(b"\x1b[H");
    let _ = write!(out, "  Marble Rolling (QEMU virtual matrix)\x1b[K\r\n\r\n");
    for row in frame.rows() {
        out.0.write(b"    ");
        for &level in row {
            let s = shade(level);
            let _ = write!(out, "\x1b[38;5;{}m{}{}", grey(level), s, s);
        }
        out.0.write(b"\x1b[0m\x1b[K\r\n");
    }
    let tenths = status.frames * 10 / FRAME_HZ.max(1);
    let [x, _, z] = status.reading;
    let _ = write!(
        out,
        "\r\n  level {}/{} {}: {} {}.{} s{}{}\x1b[K\r\n  tilt x {} z {} mg\x1b[K\r\n",
        usize::from(status.level) + 1,
        LEVELS.len(),
        LEVELS
            .get(usize::from(status.level))
            .map_or("?", |level| level.info.name),
        status.phase.as_str(),
        tenths / 10,
        tenths % 10,
        if status.autopilot {
            "  (autopilot)"
        } else {
            ""
        },
        if status.muted { "  (sound off)" } else { "" },
        x,
        z
    );
    // The level's record (feature `records`), and the news of a new one.
    #[cfg(feature = "records")]
    {
        match status.best {
            Some(frames) => {
                let cs = frames.saturating_mul(100) / FRAME_HZ.max(1);
                let _ = write!(out, "  best {}.{:02} s", cs / 100, cs % 100);
            }
            None => {
                let _ = write!(out, "  no record yet");
            }
        }
        let news = if status.new_record {
            "  NEW RECORD!"
        } else {
            ""
        };
        let _ = write!(out, "{news}\x1b[K\r\n");
    }
    let _ = write!(
        out,
        "  arrows/WASD tilt, space level, c calibrate, r restart, n next level,\x1b[K\r\n  p autopilot, m sound, q quit\x1b[K\r\n"
    );
}

/// Leaves the terminal usable: default colours, cursor shown, new line.
pub fn restore_terminal<C: Console>(console: &mut C) {
    console.write(b"\x1b[0m\x1b[?25h\r\n");
}
