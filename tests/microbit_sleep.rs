//! The micro:bit v2's sleep entry (`board::microbit::sleep`) against the SENSE
//! race: a model of port 0's SENSE and LATCH and of embassy-nrf 0.11's GPIOTE
//! handler, with a button pressed (briefly, or held) at every step of the
//! entry. The board must sleep with both buttons armed, or wake at once; never
//! sleep with a button dead. The order the firmware had before fails here.

use marble_rolling::board::microbit::sleep::{enter_system_off, SleepRegisters, WAKE_PINS};

/// How the entry ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Outcome {
    /// In System OFF with these pins armed (SENSE low), nothing latched.
    Asleep { armed: u32 },
    /// In System OFF with a pin latched: DETECT is high, the chip wakes (a
    /// reset) at once.
    WakesAtOnce,
}

/// A press of `pin` before register write number `at`, released before write
/// number `until` (never, if past the last).
#[derive(Clone, Copy, Debug)]
struct Press {
    pin: usize,
    at: usize,
    until: usize,
}

/// Port 0 and the GPIOTE as embassy-nrf leaves them, by these rules:
/// * latched detection: a pin whose SENSE is low and whose level is low sets
///   its `LATCH` bit (and the PORT event);
/// * while the PORT interrupt is enabled and interrupts are not masked, a set
///   latch runs embassy's handler at once: SENSE disabled on every latched
///   pin, and those bits cleared;
/// * writing 1 to a `LATCH` bit clears it, unless its condition still holds;
/// * `SYSTEMOFF` with a latch set wakes at once.
#[derive(Debug)]
struct Port {
    masked: bool,
    port_interrupt: bool,
    sense_low: u32,
    latch: u32,
    low: u32,
    press: Option<Press>,
    writes: usize,
    outcome: Option<Outcome>,
    handler_runs: u32,
}

impl Port {
    fn new(press: Option<Press>) -> Self {
        Self {
            masked: false,
            port_interrupt: true,
            sense_low: 0,
            latch: 0,
            low: 0,
            press,
            writes: 0,
            outcome: None,
            handler_runs: 0,
        }
    }

    fn settle(&mut self) {
        self.latch |= self.sense_low & self.low;
        if self.latch != 0 && self.port_interrupt && !self.masked {
            self.handler_runs += 1;
            self.sense_low &= !self.latch;
            self.latch = 0;
        }
    }

    /// Time passes before a write: the button moves, the hardware reacts.
    fn before_write(&mut self) {
        if let Some(press) = self.press {
            if self.writes == press.at {
                self.low |= 1 << press.pin;
            }
            if self.writes == press.until {
                self.low &= !(1 << press.pin);
            }
        }
        self.settle();
        self.writes += 1;
    }
}

impl SleepRegisters for Port {
    fn mask_interrupts(&mut self) {
        self.before_write();
        self.masked = true;
    }

    fn disable_port_interrupt(&mut self) {
        self.before_write();
        self.port_interrupt = false;
        self.settle();
    }

    fn sense_low(&mut self, pin: usize) {
        self.before_write();
        self.sense_low |= 1 << pin;
        self.settle();
    }

    fn clear_latch(&mut self, bits: u32) {
        self.before_write();
        self.latch &= !bits;
        self.settle();
    }

    fn system_off(&mut self) {
        self.before_write();
        self.outcome = Some(if self.latch != 0 {
            Outcome::WakesAtOnce
        } else {
            Outcome::Asleep {
                armed: self.sense_low,
            }
        });
    }
}

/// The order the firmware had before: SENSE set with embassy's handler live.
fn old_order(port: &mut Port) {
    for pin in WAKE_PINS {
        port.sense_low(pin);
    }
    port.system_off();
}

const BOTH: u32 = (1 << WAKE_PINS[0]) | (1 << WAKE_PINS[1]);

/// Every press: each button, starting before each write, lasting one write,
/// several, or held past the end.
fn every_press() -> Vec<Press> {
    let mut presses = Vec::new();
    for pin in WAKE_PINS {
        for at in 0..8 {
            for until in at + 1..10 {
                presses.push(Press { pin, at, until });
            }
        }
    }
    presses
}

fn run(order: fn(&mut Port), press: Option<Press>) -> (Outcome, Port) {
    let mut port = Port::new(press);
    order(&mut port);
    let outcome = port.outcome.expect("System OFF was entered");
    (outcome, port)
}

fn enter(port: &mut Port) {
    enter_system_off(port);
}

#[test]
fn untouched_the_board_sleeps_with_both_buttons_armed() {
    let (outcome, _) = run(enter, None);
    assert_eq!(outcome, Outcome::Asleep { armed: BOTH });
}

#[test]
fn a_press_at_any_step_never_leaves_a_button_dead() {
    for press in every_press() {
        let (outcome, port) = run(enter, Some(press));
        assert!(
            outcome == Outcome::Asleep { armed: BOTH } || outcome == Outcome::WakesAtOnce,
            "{press:?}: {outcome:?}"
        );
        assert_eq!(port.handler_runs, 0, "{press:?}: embassy's handler ran");
    }
}

#[test]
fn a_button_held_through_the_entry_wakes_the_board_at_once() {
    for pin in WAKE_PINS {
        let press = Press {
            pin,
            at: 0,
            until: usize::MAX,
        };
        assert_eq!(run(enter, Some(press)).0, Outcome::WakesAtOnce);
    }
}

#[test]
fn the_old_order_loses_a_button_to_the_race() {
    // A bounce on A while the firmware arms the buttons: embassy's handler
    // disarms A and clears its latch, and the board sleeps with A dead.
    let lost = every_press().into_iter().find_map(|press| {
        let (outcome, _) = run(old_order, Some(press));
        match outcome {
            Outcome::Asleep { armed } if armed != BOTH => Some((press, armed)),
            _ => None,
        }
    });
    let (press, armed) = lost.expect("the model let the old order win every race");
    assert_eq!(armed & (1 << press.pin), 0, "{press:?}");
}
