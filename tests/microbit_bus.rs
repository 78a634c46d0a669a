//! The micro:bit's I²C bus: the bus-clear sequence (`board::microbit::clear_bus`)
//! against a simulated bus with slaves stuck in every state, and the bus
//! constants (copy buffer, transfer deadline).
//!
//! What this cannot show is a real slave: the clear against a stuck
//! LSM303AGR is verified on hardware only.

use marble_rolling::board::microbit::{
    clear_bus, BusClear, BusLines, BUS_CLEAR_MAX_CLOCKS, BUS_CLEAR_STRETCH_LIMIT, I2C_KHZ,
    I2C_TIMEOUT_MS, INPUT_PERIOD_MS, LONGEST_TRANSFER_BITS, RTC_HZ, TWIM_COPY_BUFFER_BYTES,
};

/// A slave on the simulated bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slave {
    /// Waiting for a START (released SDA).
    Idle,
    /// Transmitting `byte` MSB first; `bit` 0..=7 is on SDA, 8 is the
    /// acknowledge slot (released), whose level is sampled on SCL's rising
    /// edge into `acked`.
    Tx { byte: u8, bit: u8, acked: bool },
    /// Receiving: `bit` 0..=7 are the master's data bits (released), 8 is its
    /// acknowledge (SDA pulled low).
    Rx { bit: u8 },
    /// Holds SDA low whatever happens (needs a power cycle).
    StuckSda,
}

impl Slave {
    fn pulls_sda_low(self) -> bool {
        match self {
            Slave::Tx { byte, bit, .. } if bit < 8 => byte & (0x80 >> bit) == 0,
            Slave::Rx { bit: 8 } | Slave::StuckSda => true,
            _ => false,
        }
    }

    /// SCL fell: shift on.
    fn falling(self) -> Slave {
        match self {
            Slave::Tx { byte, bit, acked } if bit < 8 => Slave::Tx {
                byte,
                bit: bit + 1,
                acked,
            },
            // Acknowledged: the next byte (the same one again); NACK: done.
            Slave::Tx {
                byte, acked: true, ..
            } => Slave::Tx {
                byte,
                bit: 0,
                acked: false,
            },
            Slave::Tx { .. } => Slave::Idle,
            Slave::Rx { bit } => Slave::Rx { bit: (bit + 1) % 9 },
            other => other,
        }
    }
}

/// An I²C bus with pull-ups, the master's open-drain pins and one slave.
struct Sim {
    master_scl: bool,
    master_sda: bool,
    slave: Slave,
    /// Reads of SCL for which a slave keeps stretching the clock after the
    /// master releases it (`u32::MAX`: forever).
    stretch: u32,
    holding_scl: u32,
    scl_line: bool,
    sda_line: bool,
    /// SCL rising edges.
    pulses: u32,
    stops: u32,
    starts: u32,
    /// The master pulled SDA low while SCL was high.
    master_violations: u32,
    half_periods: u32,
    /// Whether the last condition on the wire was a STOP with the bus idle.
    ended_with_stop: bool,
}

impl Sim {
    fn new(slave: Slave) -> Self {
        let mut sim = Sim {
            master_scl: true,
            master_sda: true,
            slave,
            stretch: 0,
            holding_scl: 0,
            scl_line: true,
            sda_line: true,
            pulses: 0,
            stops: 0,
            starts: 0,
            master_violations: 0,
            half_periods: 0,
            ended_with_stop: false,
        };
        sim.scl_line = sim.scl_level();
        sim.sda_line = sim.sda_level();
        sim
    }

    fn stretching(mut self, reads: u32) -> Self {
        self.stretch = reads;
        if reads == u32::MAX {
            self.holding_scl = u32::MAX;
            self.scl_line = false;
        }
        self
    }

    fn scl_level(&self) -> bool {
        self.master_scl && self.holding_scl == 0
    }

    fn sda_level(&self) -> bool {
        self.master_sda && !self.slave.pulls_sda_low()
    }

    /// Propagates the lines after a change and lets the slave react.
    fn settle(&mut self) {
        let scl = self.scl_level();
        if scl != self.scl_line {
            self.scl_line = scl;
            if scl {
                self.pulses += 1;
                if let Slave::Tx {
                    byte,
                    bit: 8,
                    acked: _,
                } = self.slave
                {
                    self.slave = Slave::Tx {
                        byte,
                        bit: 8,
                        acked: !self.sda_line,
                    };
                }
            } else {
                self.slave = self.slave.falling();
                self.ended_with_stop = false;
            }
        }
        let sda = self.sda_level();
        if sda != self.sda_line {
            self.sda_line = sda;
            if self.scl_line {
                if sda {
                    self.stops += 1;
                    if self.slave != Slave::StuckSda {
                        self.slave = Slave::Idle;
                    }
                    self.ended_with_stop = true;
                } else {
                    self.starts += 1;
                    self.ended_with_stop = false;
                }
            }
            // The slave may react to a STOP by releasing SDA.
            let sda = self.sda_level();
            if sda != self.sda_line {
                self.sda_line = sda;
            }
        }
    }
}

impl BusLines for Sim {
    fn set_scl(&mut self, high: bool) {
        if high && !self.master_scl && self.stretch > 0 {
            self.holding_scl = self.stretch;
        }
        self.master_scl = high;
        self.settle();
    }

    fn set_sda(&mut self, high: bool) {
        if !high && self.scl_line {
            self.master_violations += 1;
        }
        self.master_sda = high;
        self.settle();
    }

    fn scl(&mut self) -> bool {
        let level = self.scl_line;
        if self.holding_scl > 0 && self.holding_scl != u32::MAX {
            self.holding_scl -= 1;
            self.settle();
        }
        level
    }

    fn sda(&mut self) -> bool {
        self.sda_line
    }

    fn half_period(&mut self) {
        self.half_periods += 1;
    }
}

/// Runs the clear and checks what must hold whatever the slave did.
fn clear(sim: &mut Sim) -> BusClear {
    let outcome = clear_bus(sim);
    assert_eq!(sim.starts, 0, "the clear sent a START");
    assert_eq!(sim.master_violations, 0, "SDA pulled low under a high SCL");
    assert!(
        sim.pulses <= u32::from(BUS_CLEAR_MAX_CLOCKS) + 1,
        "{} pulses",
        sim.pulses
    );
    assert!(sim.master_scl && sim.master_sda, "lines left driven low");
    if outcome.is_clear() {
        assert!(sim.ended_with_stop, "no STOP at the end ({outcome:?})");
        assert!(sim.scl_line && sim.sda_line);
        assert!(matches!(sim.slave, Slave::Idle | Slave::Rx { .. }));
    }
    outcome
}

#[test]
fn an_idle_bus_gets_a_stop_and_no_clocks_before_it() {
    let mut sim = Sim::new(Slave::Idle);
    assert_eq!(clear(&mut sim), BusClear::Free);
    assert_eq!(sim.pulses, 1, "the STOP's own pulse only");
    assert_eq!(sim.stops, 1);
}

#[test]
fn a_receiver_holding_its_acknowledge_is_released_by_one_clock() {
    let mut sim = Sim::new(Slave::Rx { bit: 8 });
    assert_eq!(clear(&mut sim), BusClear::Released { clocks: 1 });
    assert_eq!(sim.slave, Slave::Idle);
}

#[test]
fn a_transmitter_sending_zeros_needs_one_clock_per_bit_left() {
    // Reset in the middle of reading 0x00: the slave holds SDA low for the
    // bits left, then releases it in the acknowledge slot.
    for bit in 0..8u8 {
        let mut sim = Sim::new(Slave::Tx {
            byte: 0x00,
            bit,
            acked: false,
        });
        let outcome = clear(&mut sim);
        assert_eq!(
            outcome,
            BusClear::Released { clocks: 8 - bit },
            "interrupted at bit {bit}"
        );
        assert!(outcome.is_clear());
        assert_eq!(sim.slave, Slave::Idle);
    }
}

#[test]
fn every_byte_interrupted_at_every_bit_is_cleared() {
    for byte in 0..=255u8 {
        for bit in 0..=8u8 {
            for acked in [false, true] {
                let mut sim = Sim::new(Slave::Tx { byte, bit, acked });
                let outcome = clear(&mut sim);
                assert!(
                    outcome.is_clear(),
                    "byte {byte:#04x} bit {bit} acked {acked}: {outcome:?}"
                );
                if let BusClear::Released { clocks } = outcome {
                    assert!((1..=BUS_CLEAR_MAX_CLOCKS).contains(&clocks));
                }
            }
        }
    }
    for bit in 0..=8u8 {
        let mut sim = Sim::new(Slave::Rx { bit });
        assert!(clear(&mut sim).is_clear(), "receiver at bit {bit}");
    }
}

#[test]
fn clocking_stops_as_soon_as_sda_is_released() {
    // 0b0011_1111 from bit 0: SDA low for two bits, then a 1, whose STOP
    // attempt ends the clear: no clocks beyond the two needed.
    let mut sim = Sim::new(Slave::Tx {
        byte: 0b0011_1111,
        bit: 0,
        acked: false,
    });
    assert_eq!(clear(&mut sim), BusClear::Released { clocks: 2 });
    assert_eq!(sim.pulses, 3);
}

#[test]
fn a_stop_swallowed_by_a_zero_bit_is_retried() {
    // On SDA a 1, then 0s: the first STOP's pulse shifts a 0 out, so SDA
    // stays low; the clear clocks on and stops the bus in the ACK slot.
    let mut sim = Sim::new(Slave::Tx {
        byte: 0b1000_0000,
        bit: 0,
        acked: false,
    });
    assert_eq!(clear(&mut sim), BusClear::Released { clocks: 8 });
    assert_eq!(sim.stops, 1);
}

#[test]
fn a_slave_that_never_lets_go_gets_nine_clocks() {
    let mut sim = Sim::new(Slave::StuckSda);
    assert_eq!(clear(&mut sim), BusClear::SdaStuck);
    assert_eq!(sim.pulses, u32::from(BUS_CLEAR_MAX_CLOCKS));
    assert!(!BusClear::SdaStuck.is_clear());
}

#[test]
fn a_stuck_clock_line_is_not_clocked() {
    let mut sim = Sim::new(Slave::Idle).stretching(u32::MAX);
    assert_eq!(clear(&mut sim), BusClear::SclStuck);
    assert_eq!(sim.pulses, 0);
    assert!(!BusClear::SclStuck.is_clear());
    // Bounded: it waited the stretch limit, not forever.
    assert!(sim.half_periods <= u32::from(BUS_CLEAR_STRETCH_LIMIT) + 1);
}

#[test]
fn clock_stretching_is_waited_for() {
    let mut sim = Sim::new(Slave::Tx {
        byte: 0x00,
        bit: 4,
        acked: false,
    })
    .stretching(u32::from(BUS_CLEAR_STRETCH_LIMIT) / 2);
    assert_eq!(clear(&mut sim), BusClear::Released { clocks: 4 });
}

#[test]
fn clock_stretching_beyond_the_limit_is_a_stuck_clock() {
    let mut sim = Sim::new(Slave::Tx {
        byte: 0x00,
        bit: 4,
        acked: false,
    })
    .stretching(u32::from(BUS_CLEAR_STRETCH_LIMIT) + 5);
    assert_eq!(clear(&mut sim), BusClear::SclStuck);
}

#[test]
fn the_copy_buffer_holds_the_drivers_largest_write() {
    // lsm303agr 1.1 writes a register as [address, value] and reads one
    // after writing its address: 2 bytes at most, from flash or not.
    const { assert!(TWIM_COPY_BUFFER_BYTES >= 2) };
    // Small: it is static RAM, and EasyDMA's MAXCNT on the nRF52833 is 16-bit.
    const { assert!(TWIM_COPY_BUFFER_BYTES <= 16) };
}

#[test]
fn the_transfer_deadline_is_far_above_a_transfer_and_below_a_poll() {
    const LONGEST_US: u32 = LONGEST_TRANSFER_BITS * 1000 / I2C_KHZ;
    const TIMEOUT_US: u32 = I2C_TIMEOUT_MS as u32 * 1000;
    const { assert!(LONGEST_US < 300) };
    const { assert!(TIMEOUT_US >= 10 * LONGEST_US) };
    // Several RTC ticks (30.5 us), so timer granularity does not matter.
    const { assert!(TIMEOUT_US >= 10 * 1_000_000 / RTC_HZ) };
    const { assert!(I2C_TIMEOUT_MS < INPUT_PERIOD_MS) };
}
