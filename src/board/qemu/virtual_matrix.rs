//! The virtual LED matrix: QEMU has no LEDs, so the scan steps of the shared
//! [`crate::matrix::Scanner`] are integrated per pixel
//! ([`OnTimeIntegrator`]) and the brightness a viewer would perceive is handed
//! to a [`Screen`] (the board's terminal, `super::terminal`), or logged with
//! defmt in headless runs. A model of the LEDs only: what the screen draws
//! beside them is the screen's, so this knows no game.
//!
//! There is no real scan clock to wait for: each refresh's steps are
//! integrated at once and the display task then sleeps on a `Ticker` until
//! the next refresh (at [`REFRESH_HZ`]).

use embassy_time::{Duration, Ticker};

use super::{HEIGHT, WIDTH};
use crate::matrix::output::{MatrixOutput, REFRESH_HZ};
use crate::matrix::{Frame, OnTimeIntegrator, ScanStep, Scanner};

/// One picture of the virtual matrix.
type DisplayFrame = Frame<WIDTH, HEIGHT>;

/// Terminal redraws per second (at most; only changes are drawn).
pub(crate) const DRAW_HZ: u32 = 20;

/// Base ticks in one full refresh.
const TICKS_PER_REFRESH: u32 = Scanner::<WIDTH, HEIGHT>::TICKS_PER_REFRESH;

/// Where a virtual matrix shows what a viewer would see, at most `DRAW_HZ`
/// times a second: the board's terminal.
pub trait Screen {
    /// Shows `frame`, the brightness a viewer perceives; whether to draw it
    /// again (nothing changed) is the screen's to decide.
    fn show(&mut self, frame: &DisplayFrame);
}

/// The virtual matrix, shown on `C` (or only logging when `C` is absent).
pub struct VirtualMatrix<C: Screen> {
    integrator: OnTimeIntegrator<WIDTH, HEIGHT>,
    ticks_in_refresh: u32,
    refreshes: u32,
    ticker: Option<Ticker>,
    screen: Option<C>,
    log_every: u32,
    last_logged: Option<DisplayFrame>,
}

impl<C: Screen> VirtualMatrix<C> {
    /// A matrix shown on `screen` (`None`: headless) that logs the perceived
    /// frame with defmt every `log_every` refreshes when it changed (0:
    /// never).
    pub fn new(screen: Option<C>, log_every: u32) -> Self {
        Self {
            integrator: OnTimeIntegrator::new(),
            ticks_in_refresh: 0,
            refreshes: 0,
            ticker: None,
            screen,
            log_every,
            last_logged: None,
        }
    }

    /// Called after each full refresh.
    fn refreshed(&mut self) {
        self.refreshes = self.refreshes.wrapping_add(1);
        let draw_every = (REFRESH_HZ / DRAW_HZ).max(1);
        let log_due = self.log_every != 0 && self.refreshes.is_multiple_of(self.log_every);
        let draw_due = self.screen.is_some() && self.refreshes.is_multiple_of(draw_every);
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
        if let (true, Some(screen)) = (draw_due, self.screen.as_mut()) {
            screen.show(&frame);
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

impl<C: Screen> MatrixOutput<WIDTH, HEIGHT> for VirtualMatrix<C> {
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
