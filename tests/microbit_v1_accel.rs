//! The micro:bit v1's sensor stack (board::microbit_v1: the probe, the NXP
//! driver, the bus-clear rule, the v2's supervision) against the virtual
//! MMA8653FC and FXOS8700CQ (board::microbit_v1::virtual_nxp): identity,
//! configuration in standby, data-ready at the data rate, the sample format,
//! the axis map against the chips' mounting, each injected fault, and the
//! game played through the chip. Every test runs for both chips: its name
//! says which (`mma8653_…`, `fxos8700_…`).
//!
//! The poll loop is the firmware's (`boards/microbit-v1/src/sensor.rs`,
//! `Input::next_event`): every 10 ms a read, fed to the pipeline; a
//! re-initialisation when the supervisor asks for one.

use std::cell::Cell;

use embassy_futures::block_on;
use embedded_hal_async::i2c::I2c;

use marble_rolling::board::microbit::{INPUT_PERIOD_MS, SUPERVISOR};
use marble_rolling::board::microbit_v1::accel::{nxp, Accelerometer, NxpChip};
use marble_rolling::board::microbit_v1::nxp_driver::{configure, probe, read};
use marble_rolling::board::microbit_v1::twi::{Recovering, TwiError};
use marble_rolling::board::microbit_v1::virtual_nxp::{VirtualNxp, VirtualTwi};
use marble_rolling::board::qemu::virtual_lsm303agr::{ChipControl, InjectedFault};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::player::Player;
use marble_rolling::input::event::Tilt;
use marble_rolling::input::sensor::{AccelMg, Action, Fault, Read, TiltPipeline, Transition};
use marble_rolling::input::tilt::TiltConfig;
use marble_rolling::physics::Scalar;

type Bus<'a> = Recovering<VirtualTwi<'a, Box<dyn Fn() -> u64 + 'a>>>;

/// The v1's stack over one virtual chip, with a hand-stepped clock.
struct Stack<'a> {
    bus: Bus<'a>,
    chip: &'static NxpChip,
    pipeline: TiltPipeline,
    clock: &'a Cell<u64>,
    reinits: u32,
    transitions: Vec<Transition>,
}

impl<'a> Stack<'a> {
    /// Probes, then configures what it found.
    fn up(chip: Accelerometer, control: &'a ChipControl, clock: &'a Cell<u64>) -> Self {
        let twi = VirtualTwi::new(
            VirtualNxp::new(chip),
            control,
            Box::new(move || clock.get()) as Box<dyn Fn() -> u64>,
        );
        let mut bus = Recovering::new(twi);
        let found = block_on(probe(&mut bus));
        assert_eq!(found, Some(chip), "the probe finds the chip on the bus");
        let chip = found.and_then(Accelerometer::nxp).expect("an NXP chip");
        let mut pipeline = TiltPipeline::new(chip.chip.axis_map(), SUPERVISOR);
        pipeline.reinit_done(block_on(configure(&mut bus, chip)));
        Self {
            bus,
            chip,
            pipeline,
            clock,
            reinits: 0,
            transitions: Vec::new(),
        }
    }

    /// One poll period later: read, supervise, re-initialise if asked.
    fn poll(&mut self) -> AccelMg {
        self.clock.set(self.clock.get() + INPUT_PERIOD_MS * 1000);
        let reading = block_on(read(&mut self.bus, self.chip));
        let step = self.pipeline.feed(reading);
        if let Action::Reinit = step.action {
            self.reinits += 1;
            let outcome = block_on(configure(&mut self.bus, self.chip));
            self.pipeline.reinit_done(outcome);
        }
        if let Some(transition) = step.transition {
            self.transitions.push(transition);
        }
        self.pipeline.tilt()
    }

    fn polls(&mut self, n: usize) -> AccelMg {
        let mut last = self.pipeline.tilt();
        for _ in 0..n {
            last = self.poll();
        }
        last
    }

    fn chip_state(&mut self) -> &VirtualNxp {
        self.bus.bus().chip()
    }
}

fn close(a: AccelMg, b: [i32; 3], tolerance: i32) -> bool {
    (a.x - b[0]).abs() <= tolerance
        && (a.y - b[1]).abs() <= tolerance
        && (a.z - b[2]).abs() <= tolerance
}

/// One count of the chip, mg (rounded up).
fn lsb_mg(chip: Accelerometer) -> i32 {
    match chip {
        Accelerometer::Fxos8700cq => 1,
        _ => 4,
    }
}

fn identity_and_configuration(chip: Accelerometer) {
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut stack = Stack::up(chip, &control, &clock);
    let state = stack.chip_state();
    assert!(state.active(), "configured: active");
    assert_eq!(state.full_scale_g(), 2);
    assert_eq!(state.period_us(), 5_000, "200 Hz");
    assert_eq!(
        state.register(nxp::CTRL_REG2),
        nxp::CTRL2_MODS_HIGH_RESOLUTION
    );
    // The other chips' addresses do not answer.
    let other = if chip == Accelerometer::Mma8653fc {
        0x1E
    } else {
        0x1D
    };
    let mut id = [0u8];
    let answer = block_on(stack.bus.write_read(other, &[nxp::WHO_AM_I], &mut id));
    assert_eq!(answer, Err(TwiError::AddressNack));
}

fn standby_rule(chip: Accelerometer) {
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut stack = Stack::up(chip, &control, &clock);
    let address = stack.chip.address;
    // Active: the range and the rate ignore writes.
    block_on(stack.bus.write(address, &[nxp::XYZ_DATA_CFG, 2])).unwrap();
    block_on(stack.bus.write(address, &[nxp::CTRL_REG1, 0x38 | 1])).unwrap();
    let state = stack.chip_state();
    assert_eq!(state.full_scale_g(), 2);
    assert_eq!(state.period_us(), 5_000);
    // Standby first, then they take.
    block_on(stack.bus.write(address, &[nxp::CTRL_REG1, 0])).unwrap();
    block_on(stack.bus.write(address, &[nxp::XYZ_DATA_CFG, 2])).unwrap();
    assert_eq!(stack.chip_state().full_scale_g(), 8);
    // Standby: no samples, whatever the time.
    let latched = stack.chip_state().latched();
    clock.set(clock.get() + 1_000_000);
    assert_eq!(block_on(read(&mut stack.bus, stack.chip)), Read::NotReady);
    assert_eq!(stack.chip_state().latched(), latched);
}

fn data_ready_follows_the_rate(chip: Accelerometer) {
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut stack = Stack::up(chip, &control, &clock);
    // Not before one period.
    clock.set(4_999);
    assert_eq!(block_on(read(&mut stack.bus, stack.chip)), Read::NotReady);
    clock.set(5_000);
    assert!(matches!(
        block_on(read(&mut stack.bus, stack.chip)),
        Read::Sample(_)
    ));
    // Read: data-ready cleared until the next sample.
    assert_eq!(block_on(read(&mut stack.bus, stack.chip)), Read::NotReady);
    clock.set(10_000);
    assert!(matches!(
        block_on(read(&mut stack.bus, stack.chip)),
        Read::Sample(_)
    ));
    // A burst of the status alone does not clear it; reading the three
    // MSBs does.
    clock.set(15_000);
    let address = stack.chip.address;
    let mut status = [0u8];
    block_on(stack.bus.write_read(address, &[nxp::STATUS], &mut status)).unwrap();
    assert_ne!(status[0] & nxp::STATUS_ZYXDR, 0);
    block_on(stack.bus.write_read(address, &[nxp::STATUS], &mut status)).unwrap();
    assert_ne!(status[0] & nxp::STATUS_ZYXDR, 0);
    // Two samples unread: overwrite flagged.
    clock.set(25_000);
    block_on(stack.bus.write_read(address, &[nxp::STATUS], &mut status)).unwrap();
    assert_ne!(status[0] & nxp::STATUS_ZYXOW, 0);
}

/// Six orientations (board-frame specific force, mg): the firmware's map
/// must give back what the chip, mounted as it is, felt.
fn orientations(chip: Accelerometer) {
    let cases = [
        ([0, 1000, 0], "flat, screen up"),
        ([0, -1000, 0], "flat, screen down"),
        ([-1000, 0, 0], "right edge down"),
        ([1000, 0, 0], "left edge down"),
        ([0, 0, -1000], "edge connector down"),
        ([0, 0, 1000], "logo down"),
        ([-500, 866, 0], "30° to the right"),
        ([250, 433, -866], "a tilt on every axis"),
    ];
    for (tilt, what) in cases {
        let control = ChipControl::new();
        control.set_tilt(Tilt {
            x: tilt[0] as i16,
            y: tilt[1] as i16,
            z: tilt[2] as i16,
        });
        let clock = Cell::new(0);
        let mut stack = Stack::up(chip, &control, &clock);
        let seen = stack.polls(3);
        assert!(
            close(seen, tilt, lsb_mg(chip)),
            "{chip:?} {what}: read {seen:?}, the board felt {tilt:?}"
        );
    }
}

/// Down on `fault`, back up once it is lifted.
fn fault_and_recovery(chip: Accelerometer, fault: InjectedFault) -> (u32, u32) {
    let control = ChipControl::new();
    control.set_tilt(Tilt {
        x: -300,
        y: 950,
        z: 0,
    });
    let clock = Cell::new(0);
    let mut stack = Stack::up(chip, &control, &clock);
    let good = stack.polls(5);
    assert!(close(good, [-300, 950, 0], 4), "{good:?}");
    assert!(stack.transitions.is_empty());
    control.inject(fault);
    stack.polls(60);
    if fault == InjectedFault::ChipReset {
        // A reset is an event: the stack must bring the chip back itself.
        assert!(stack.chip_state().active(), "{chip:?}: re-initialised");
        assert!(!stack.pipeline.is_down());
        let after = stack.polls(5);
        assert!(close(after, [-300, 950, 0], 4), "{after:?}");
        return (stack.reinits, stack.bus.clears());
    }
    let Some(Transition::Down(why)) = stack.transitions.first().copied() else {
        panic!(
            "{chip:?} {fault:?}: the sensor never went down ({:?})",
            stack.transitions
        );
    };
    let expected = match fault {
        InjectedFault::Nak => Fault::Bus,
        InjectedFault::StuckBus => Fault::Timeout,
        InjectedFault::FrozenData => Fault::NoData,
        _ => Fault::Implausible,
    };
    assert_eq!(why, expected, "{chip:?} {fault:?}");
    // While down the last good tilt is kept.
    assert!(close(stack.pipeline.tilt(), [-300, 950, 0], 4));
    control.inject(InjectedFault::Healthy);
    control.set_tilt(Tilt {
        x: 400,
        y: 900,
        z: 0,
    });
    // Retries come every retry period (50 polls) while down.
    let back = stack.polls(120);
    assert_eq!(
        stack.transitions.last(),
        Some(&Transition::Up),
        "{chip:?} {fault:?}: the sensor came back"
    );
    assert!(close(back, [400, 900, 0], 4), "{back:?}");
    (stack.reinits, stack.bus.clears())
}

/// The stuck bus stays stuck without a bus clear: the bare virtual bus
/// (no [`Recovering`]) never comes back, even with the slave healthy again.
fn a_stuck_bus_needs_a_clear(chip: Accelerometer) {
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut bare = VirtualTwi::new(VirtualNxp::new(chip), &control, || 0);
    let address = VirtualNxp::new(chip).address();
    let mut id = [0u8];
    control.inject(InjectedFault::StuckBus);
    let stuck = block_on(bare.write_read(address, &[nxp::WHO_AM_I], &mut id));
    assert_eq!(stuck, Err(TwiError::Timeout));
    control.inject(InjectedFault::Healthy);
    let still = block_on(bare.write_read(address, &[nxp::WHO_AM_I], &mut id));
    assert_eq!(still, Err(TwiError::Timeout), "stuck until cleared");
    // With the recovering bus: cleared after the failure, the next works.
    let _ = &clock;
    let mut bus = Recovering::new(bare);
    let first = block_on(bus.write_read(address, &[nxp::WHO_AM_I], &mut id));
    assert_eq!(first, Ok(()), "cleared before the first transfer");
    assert_eq!(id[0], VirtualNxp::new(chip).who_am_i());
    assert_eq!(bus.clears(), 1);
}

/// The game through the chip: tilted right (right edge down) the marble
/// rolls towards +x, tilted left towards −x.
fn drives_the_game(chip: Accelerometer) {
    let mut moved = [0.0f64; 2];
    for (i, x_mg) in [-500i16, 500].into_iter().enumerate() {
        let control = ChipControl::new();
        control.set_tilt(Tilt {
            x: x_mg,
            y: 866,
            z: 0,
        });
        let clock = Cell::new(0);
        let mut stack = Stack::up(chip, &control, &clock);
        let mut player = Player::<5, 5, false, true>::new(&LEVELS, 1, TiltConfig::DEFAULT, false)
            .expect("level");
        let start = player.game().world().marbles()[0].pos.x.to_f64();
        // 128 frames/s, a poll every 10 ms: one second of play.
        for frame in 0..128 {
            if frame % 13 == 0 || frame % 13 == 6 {
                stack.poll();
            }
            let t = stack.pipeline.tilt();
            player.tick([t.x, t.y, t.z], false);
        }
        moved[i] = player.game().world().marbles()[0].pos.x.to_f64() - start;
    }
    assert!(
        moved[0] > 0.0 && moved[1] < 0.0,
        "{chip:?}: right edge down moved the marble {}, left edge down {}",
        moved[0],
        moved[1]
    );
}

macro_rules! for_chip {
    ($chip:expr, $($name:ident => $body:expr;)*) => {
        $(
            #[test]
            fn $name() {
                let chip: Accelerometer = $chip;
                #[allow(clippy::redundant_closure_call)]
                ($body)(chip);
            }
        )*
    };
}

for_chip! {
    Accelerometer::Mma8653fc,
    mma8653_identity_and_configuration => identity_and_configuration;
    mma8653_configuration_only_in_standby => standby_rule;
    mma8653_data_ready_follows_the_rate => data_ready_follows_the_rate;
    mma8653_axis_map_matches_the_mounting => orientations;
    mma8653_a_stuck_bus_needs_a_clear => a_stuck_bus_needs_a_clear;
    mma8653_drives_the_game => drives_the_game;
    mma8653_nak_down_and_back => |c| { fault_and_recovery(c, InjectedFault::Nak); };
    mma8653_stuck_bus_down_and_back => |c| {
        let (_, clears) = fault_and_recovery(c, InjectedFault::StuckBus);
        assert!(clears > 1, "cleared after the timeouts ({clears})");
    };
    mma8653_frozen_data_down_and_back => |c| { fault_and_recovery(c, InjectedFault::FrozenData); };
    mma8653_garbage_down_and_back => |c| { fault_and_recovery(c, InjectedFault::Garbage); };
    mma8653_chip_reset_reinitialised => |c| {
        let (reinits, _) = fault_and_recovery(c, InjectedFault::ChipReset);
        assert!(reinits >= 1);
    };
}

for_chip! {
    Accelerometer::Fxos8700cq,
    fxos8700_identity_and_configuration => identity_and_configuration;
    fxos8700_configuration_only_in_standby => standby_rule;
    fxos8700_data_ready_follows_the_rate => data_ready_follows_the_rate;
    fxos8700_axis_map_matches_the_mounting => orientations;
    fxos8700_a_stuck_bus_needs_a_clear => a_stuck_bus_needs_a_clear;
    fxos8700_drives_the_game => drives_the_game;
    fxos8700_nak_down_and_back => |c| { fault_and_recovery(c, InjectedFault::Nak); };
    fxos8700_stuck_bus_down_and_back => |c| {
        let (_, clears) = fault_and_recovery(c, InjectedFault::StuckBus);
        assert!(clears > 1, "cleared after the timeouts ({clears})");
    };
    fxos8700_frozen_data_down_and_back => |c| { fault_and_recovery(c, InjectedFault::FrozenData); };
    fxos8700_garbage_down_and_back => |c| { fault_and_recovery(c, InjectedFault::Garbage); };
    fxos8700_chip_reset_reinitialised => |c| {
        let (reinits, _) = fault_and_recovery(c, InjectedFault::ChipReset);
        assert!(reinits >= 1);
    };
}

#[test]
fn mma8653_and_fxos8700_the_probe_finds_nothing_on_an_empty_bus() {
    let control = ChipControl::new();
    control.inject(InjectedFault::Nak);
    for chip in [Accelerometer::Mma8653fc, Accelerometer::Fxos8700cq] {
        let mut bus = Recovering::new(VirtualTwi::new(VirtualNxp::new(chip), &control, || 0));
        assert_eq!(block_on(probe(&mut bus)), None);
        // One clear before the first transfer, one after each failed probe.
        assert_eq!(bus.clears(), 4);
    }
}
