//! Idle sleep: System OFF, and the level kept across it (embassy-nrf and
//! PAC wiring only; the order of the register writes is
//! [`board::sleep`]'s, host-tested).

use embassy_nrf::pac;
use embassy_nrf::pac::gpio::vals::Sense;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;

use marble_rolling::app::Links;
use marble_rolling::board::microbit::{self as board, sleep};
use marble_rolling::matrix::Frame;

/// The level to start at: the one the toy fell asleep on when this reset is
/// the wake-up from [`system_off`], else the first. Clears the marker.
pub fn level_after_reset() -> u8 {
    let level = board::level_after_reset(pac::POWER.gpregret().read().gpregret());
    pac::POWER.gpregret().write(|w| w.set_gpregret(0));
    level
}

/// Port 0, the GPIOTE and POWER as [`sleep::SleepRegisters`].
struct NrfSleep;

impl sleep::SleepRegisters for NrfSleep {
    fn mask_interrupts(&mut self) {
        cortex_m::interrupt::disable();
    }

    fn disable_port_interrupt(&mut self) {
        pac::GPIOTE.intenclr(0).write(|w| w.set_port(true));
        pac::GPIOTE.events_port(0).write_value(0);
    }

    fn sense_low(&mut self, pin: usize) {
        pac::P0.pin_cnf(pin).modify(|w| w.set_sense(Sense::Low));
    }

    fn clear_latch(&mut self, bits: u32) {
        pac::P0.latch().write(|w| w.0 = bits);
    }

    fn system_off(&mut self) {
        pac::POWER.systemoff().write(|w| w.set_systemoff(true));
    }
}

/// The game task's request to sleep on a level, taken by the input task (which
/// owns the accelerometer and powers it down first): [`request_sleep`].
pub(crate) static SLEEP: Signal<CriticalSectionRawMutex, u8> = Signal::new();

/// Asks the input task to put the board in System OFF on `level`; the caller
/// (the game task) then waits forever. Should the input task never take it,
/// the game task's silence makes the watchdog reset the board.
pub async fn request_sleep(level: u8) -> ! {
    SLEEP.signal(level);
    core::future::pending().await
}

/// Sleeps in System OFF, the nRF52833's lowest state that keeps the flash
/// (the records) and GPREGRET: the display dark (its last frame blank for a
/// full refresh), level `level` kept in GPREGRET, buttons A and B armed
/// (`board::sleep::WAKE_PINS`) to wake it on a press. The wake-up is a reset
/// ([`level_after_reset`]), and the input task's first poll initialises the
/// accelerometer again. Called by the input task, the accelerometer already
/// powered down.
///
/// The register writes are [`board::sleep::enter_system_off`]'s, in the
/// order that wins the SENSE race against embassy-nrf's GPIOTE handler (that
/// module says why; `tests/microbit_sleep.rs` checks it).
pub(crate) async fn system_off(
    links: &'static Links<{ board::WIDTH }, { board::HEIGHT }>,
    level: u8,
) -> ! {
    links.frames.signal(Frame::new());
    // Two refreshes at 109 Hz: the blank frame is on, every row off.
    embassy_time::Timer::after_millis(25).await;
    pac::POWER
        .gpregret()
        .write(|w| w.set_gpregret(board::sleep_marker(level)));
    defmt::info!("System OFF on level {=u8}: a button wakes", level + 1);
    sleep::enter_system_off(&mut NrfSleep);
    // Under a debugger System OFF is only emulated, and the core runs on.
    loop {
        cortex_m::asm::wfe();
    }
}
