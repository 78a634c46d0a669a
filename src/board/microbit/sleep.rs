//! The order in which the v2 enters System OFF with its buttons armed, apart
//! from the registers so the host can check it against the race it must win.
//!
//! A button wakes the nRF52833 from System OFF through its pin's SENSE: the
//! pin's DETECT signal, latched in `LATCH` in the latched detection mode
//! embassy-nrf 0.11 selects. embassy-nrf (feature `gpiote`) also enables the
//! GPIOTE PORT interrupt at init, and its handler (`gpiote.rs`,
//! `handle_gpiote_interrupt`) disables SENSE on every pin whose `LATCH` bit is
//! set and clears the bit: a button pressed or bouncing while the firmware
//! arms SENSE would be disarmed again, and the board would sleep with that
//! button dead. So the handler is shut out first — interrupts masked, for
//! good, and the PORT interrupt off — and only then is SENSE set; the latch is
//! cleared last, so that a button still held latches again and wakes the
//! board at once rather than never.
//!
//! `tests/microbit_sleep.rs` runs [`enter_system_off`] against a model of the
//! pins and of embassy-nrf's handler, with a button pressed at every step;
//! `boards/microbit/src/sleep.rs` implements [`SleepRegisters`] on the nRF's.

/// Button pins that wake the board (port 0): A (P0.14) and B (P0.23).
pub const WAKE_PINS: [usize; 2] = [14, 23];

/// The register writes the sleep entry makes.
pub trait SleepRegisters {
    /// Masks every interrupt (PRIMASK): no handler runs from here on.
    fn mask_interrupts(&mut self);
    /// Clears the GPIOTE PORT interrupt's enable and its pending event.
    fn disable_port_interrupt(&mut self);
    /// Sets SENSE on `pin` to wake on a low level.
    fn sense_low(&mut self, pin: usize);
    /// Writes `bits` to port 0's `LATCH` (a 1 clears that pin's bit, unless
    /// its condition still holds).
    fn clear_latch(&mut self, bits: u32);
    /// Writes `SYSTEMOFF`.
    fn system_off(&mut self);
}

/// Arms [`WAKE_PINS`] and enters System OFF, the handler shut out first.
pub fn enter_system_off<R: SleepRegisters>(registers: &mut R) {
    registers.mask_interrupts();
    registers.disable_port_interrupt();
    let mut bits = 0;
    for pin in WAKE_PINS {
        registers.sense_low(pin);
        bits |= 1 << pin;
    }
    registers.clear_latch(bits);
    registers.system_off();
}
