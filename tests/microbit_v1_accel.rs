//! The micro:bit v1's sensor stack against the virtual MMA8653FC and
//! FXOS8700CQ (board::microbit_v1::virtual_nxp): identity, configuration in
//! standby, data-ready at the data rate, the sample format, the axis map
//! against the chips' mounting, and the game played through each chip, each
//! injected fault included. Every test runs for both chips: its name says
//! which (`mma8653_…`, `fxos8700_…`).
//!
//! The poll loop is the firmware's own (`board::microbit_v1::sensor::
//! PollLoop`, which `boards/microbit-v1/src/sensor.rs` runs on the nRF51's
//! TWI): probe by identity, configure, poll, supervise, re-initialise, clear
//! the bus after a failure. The tests only step the clock and hand the
//! transitions and the tilt to the game as the app does.

use std::cell::Cell;

use embassy_futures::block_on;
use embedded_hal_async::i2c::I2c;

use marble_rolling::board::i2c::Recovering;
use marble_rolling::board::microbit::{INPUT_PERIOD_MS, SUPERVISOR};
use marble_rolling::board::microbit_v1::accel::{identify, nxp, Accelerometer, NxpChip, PROBES};
use marble_rolling::board::microbit_v1::nxp_driver::{probe, read};
use marble_rolling::board::microbit_v1::sensor::{PollLoop, Polled, Probed};
use marble_rolling::board::microbit_v1::twi::{Pause, TwiError};
use marble_rolling::board::microbit_v1::virtual_nxp::{VirtualNxp, RESET_US};
use marble_rolling::board::microbit_v1::virtual_twi::{VirtualChip, VirtualTwi};
use marble_rolling::board::virtual_lsm303agr::{
    ChipControl, InjectedFault, VirtualLsm303agr, MICROBIT_V2,
};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::input::sensor::{AccelMg, Fault, Read, Transition};
use marble_rolling::input::tilt::TiltConfig;
use marble_rolling::physics::Scalar;
use marble_rolling::player::Player;
use marble_rolling::render::screens::fault_frame;

type Twi<'a> = VirtualTwi<'a, Box<dyn Fn() -> u64 + 'a>>;

/// The poll period, µs.
const PERIOD_US: u64 = INPUT_PERIOD_MS * 1000;

/// The firmware's poll loop over one virtual chip, with a hand-stepped clock.
struct Stack<'a> {
    sensor: PollLoop<Twi<'a>>,
    chip: &'static NxpChip,
    clock: &'a Cell<u64>,
    transitions: Vec<Transition>,
}

impl<'a> Stack<'a> {
    /// The firmware's bring-up: it must find `chip` by its identity.
    fn up(chip: Accelerometer, control: &'a ChipControl, clock: &'a Cell<u64>) -> Self {
        let twi = VirtualTwi::new(
            VirtualNxp::new(chip),
            control,
            Box::new(move || clock.get()) as Box<dyn Fn() -> u64>,
        );
        let mut sensor = PollLoop::new(twi);
        let probed = block_on(sensor.bring_up());
        assert_eq!(
            probed,
            Some(Probed::Found(chip)),
            "the probe finds the chip on the bus"
        );
        assert_eq!(sensor.found(), Some(chip));
        let nxp = chip.nxp().expect("an NXP chip");
        Self {
            sensor,
            chip: nxp,
            clock,
            transitions: Vec::new(),
        }
    }

    /// One poll period later: the firmware's poll.
    fn poll(&mut self) -> Polled {
        self.clock.set(self.clock.get() + PERIOD_US);
        let polled = block_on(self.sensor.poll());
        assert_eq!(polled.probed, None, "the chip stays known");
        if let Some(transition) = polled.transition {
            self.transitions.push(transition);
        }
        polled
    }

    fn polls(&mut self, n: usize) -> AccelMg {
        for _ in 0..n {
            self.poll();
        }
        self.sensor.tilt()
    }

    /// The recovering bus (an NXP chip has no driver owning it).
    fn bus(&mut self) -> &mut Recovering<Twi<'a>> {
        self.sensor.bus().expect("the NXP chips own no driver")
    }

    fn chip_state(&mut self) -> &VirtualNxp {
        self.bus().bus().nxp().expect("an NXP chip on the bus")
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
    let answer = block_on(stack.bus().write_read(other, &[nxp::WHO_AM_I], &mut id));
    assert_eq!(answer, Err(TwiError::AddressNack));
}

fn standby_rule(chip: Accelerometer) {
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut stack = Stack::up(chip, &control, &clock);
    let nxp = stack.chip;
    let address = nxp.address;
    // Active: the range and the rate ignore writes.
    block_on(stack.bus().write(address, &[nxp::XYZ_DATA_CFG, 2])).unwrap();
    block_on(stack.bus().write(address, &[nxp::CTRL_REG1, 0x38 | 1])).unwrap();
    let state = stack.chip_state();
    assert_eq!(state.full_scale_g(), 2);
    assert_eq!(state.period_us(), 5_000);
    // Standby first, then they take.
    block_on(stack.bus().write(address, &[nxp::CTRL_REG1, 0])).unwrap();
    block_on(stack.bus().write(address, &[nxp::XYZ_DATA_CFG, 2])).unwrap();
    assert_eq!(stack.chip_state().full_scale_g(), 8);
    // Standby: no samples, whatever the time.
    let latched = stack.chip_state().latched();
    clock.set(clock.get() + 1_000_000);
    assert_eq!(block_on(read(stack.bus(), nxp)), Read::NotReady);
    assert_eq!(stack.chip_state().latched(), latched);
}

fn data_ready_follows_the_rate(chip: Accelerometer) {
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut stack = Stack::up(chip, &control, &clock);
    let nxp = stack.chip;
    // Not before one period.
    clock.set(4_999);
    assert_eq!(block_on(read(stack.bus(), nxp)), Read::NotReady);
    clock.set(5_000);
    assert!(matches!(block_on(read(stack.bus(), nxp)), Read::Sample(_)));
    // Read: data-ready cleared until the next sample.
    assert_eq!(block_on(read(stack.bus(), nxp)), Read::NotReady);
    clock.set(10_000);
    assert!(matches!(block_on(read(stack.bus(), nxp)), Read::Sample(_)));
    // A burst of the status alone does not clear it; reading the three
    // MSBs does.
    clock.set(15_000);
    let address = nxp.address;
    let mut status = [0u8];
    block_on(stack.bus().write_read(address, &[nxp::STATUS], &mut status)).unwrap();
    assert_ne!(status[0] & nxp::STATUS_ZYXDR, 0);
    block_on(stack.bus().write_read(address, &[nxp::STATUS], &mut status)).unwrap();
    assert_ne!(status[0] & nxp::STATUS_ZYXDR, 0);
    // Two samples unread: overwrite flagged.
    clock.set(25_000);
    block_on(stack.bus().write_read(address, &[nxp::STATUS], &mut status)).unwrap();
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
        control.set_tilt(AccelMg::new(tilt[0], tilt[1], tilt[2]));
        let clock = Cell::new(0);
        let mut stack = Stack::up(chip, &control, &clock);
        let seen = stack.polls(3);
        assert!(
            close(seen, tilt, lsb_mg(chip)),
            "{chip:?} {what}: read {seen:?}, the board felt {tilt:?}"
        );
    }
}

/// Game frames per second (`app::FRAME_HZ`).
const FRAME_HZ: u64 = 128;

/// A game on "switchback" (no holes: nothing ends the attempt early), no
/// autopilot, event stepping (the v1's).
fn game() -> Player<'static, 5, 5, false, true> {
    Player::new(&LEVELS, 2, TiltConfig::DEFAULT, false).expect("built-in level")
}

/// The hand's tilt at game frame `frame`: half a second each way along the
/// first corridor, so the marble keeps moving.
fn scripted_tilt(frame: u64) -> AccelMg {
    const STEPS: [(i32, i32); 4] = [(-250, 0), (250, 60), (-250, -60), (250, 0)];
    let (x, z) = STEPS[(frame / (FRAME_HZ / 2)) as usize % STEPS.len()];
    AccelMg { x, y: 965, z }
}

/// What one game through a fault showed.
#[derive(Debug)]
struct Outage {
    /// The sensor's transitions, with the game frame they reached the game.
    transitions: Vec<(u64, Transition)>,
    /// Game frames the game stood still, the sensor down.
    paused_frames: u64,
    /// Frames the game played after it resumed.
    played_after: u64,
    reinits: u32,
    clears: u32,
}

/// Frame at which the fault is injected, and at which it is lifted.
const FAULT_FRAME: u64 = FRAME_HZ;
const HEALED_FRAME: u64 = 3 * FRAME_HZ;
/// Frames played in all.
const END_FRAME: u64 = 6 * FRAME_HZ;

/// The app's game loop fed by the firmware's poll loop over `chip`, with
/// `fault` injected from 1 s to 3 s: the transitions go to
/// [`Player::handle`], the tilt to [`Player::tick`], polls every 10 ms
/// between the frames (128 a second). While the sensor is down the game must
/// stand still (frame count and state hash unchanged, the fault picture
/// shown); whenever it plays it must be, frame count and state hash, a
/// reference game fed the same readings on the same frames with no outage
/// at all: a pause changes no bit of the game, and it resumes where it was.
fn through_the_game(chip: Accelerometer, fault: InjectedFault) -> Outage {
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut stack = Stack::up(chip, &control, &clock);
    let mut player = game();
    let mut reference = game();
    let start_hash = reference.session().state_hash();
    let mut outage = Outage {
        transitions: Vec::new(),
        paused_frames: 0,
        played_after: 0,
        reinits: 0,
        clears: 0,
    };
    let mut was_down = false;
    for frame in 0..END_FRAME {
        if frame == FAULT_FRAME {
            control.inject(fault);
        }
        if frame == HEALED_FRAME && fault != InjectedFault::ChipReset {
            control.inject(InjectedFault::Healthy);
        }
        control.set_tilt(scripted_tilt(frame));
        let now_us = frame * 1_000_000 / FRAME_HZ;
        while clock.get() + PERIOD_US <= now_us {
            if let Some(transition) = stack.poll().transition {
                outage.transitions.push((frame, transition));
                assert!(player.handle(transition.event()));
            }
        }
        let reading = stack.sensor.tilt();
        let (frames, hash) = (player.game().frames(), player.session().state_hash());
        let tick = player.tick(reading, true);
        let down = player.status().sensor_down;
        assert_eq!(
            down,
            stack.sensor.pipeline().is_down(),
            "{chip:?} {fault:?} frame {frame}: the game knows what the sensor is"
        );
        if down {
            assert_eq!(
                player.game().frames(),
                frames,
                "{chip:?} {fault:?}: the level clock stopped"
            );
            assert_eq!(
                player.session().state_hash(),
                hash,
                "{chip:?} {fault:?} frame {frame}: no physics while down"
            );
            if !was_down {
                assert_eq!(
                    tick.frame,
                    Some(fault_frame::<5, 5>()),
                    "{chip:?} {fault:?}: the fault picture is shown"
                );
            }
            outage.paused_frames += 1;
        } else {
            reference.tick(reading, false);
            assert_eq!(
                (player.game().frames(), player.session().state_hash()),
                (reference.game().frames(), reference.session().state_hash()),
                "{chip:?} {fault:?} frame {frame}: the game is the reference game"
            );
            if outage.paused_frames > 0 {
                outage.played_after += 1;
            }
        }
        was_down = down;
    }
    assert_ne!(
        reference.session().state_hash(),
        start_hash,
        "the marble moved: the hash comparisons compare something"
    );
    outage.reinits = stack.sensor.reinits();
    outage.clears = stack.bus().clears();
    outage
}

/// `fault` takes the sensor down for `why` within 1 s, the game pauses, and
/// within 0.5 s of the chip being healthy again the game resumes where it
/// was and plays on.
fn fault_pauses_the_game(chip: Accelerometer, fault: InjectedFault, why: Fault) -> Outage {
    let outage = through_the_game(chip, fault);
    let [(down_at, Transition::Down(seen)), (up_at, Transition::Up)] = outage.transitions[..]
    else {
        panic!("{chip:?} {fault:?}: not one outage: {outage:?}");
    };
    assert_eq!(seen, why, "{chip:?} {fault:?}: down for the fault's reason");
    assert!(
        (FAULT_FRAME..FAULT_FRAME + FRAME_HZ).contains(&down_at),
        "{chip:?} {fault:?}: down at frame {down_at}, injected at {FAULT_FRAME}"
    );
    assert!(
        (HEALED_FRAME..HEALED_FRAME + FRAME_HZ / 2).contains(&up_at),
        "{chip:?} {fault:?}: back at frame {up_at}, healthy at {HEALED_FRAME}"
    );
    assert_eq!(outage.paused_frames, up_at - down_at, "{outage:?}");
    assert_eq!(outage.played_after, END_FRAME - up_at, "{outage:?}");
    outage
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
    for (i, x_mg) in [-500i32, 500].into_iter().enumerate() {
        let control = ChipControl::new();
        control.set_tilt(AccelMg {
            x: x_mg,
            y: 866,
            z: 0,
        });
        let clock = Cell::new(0);
        let mut stack = Stack::up(chip, &control, &clock);
        let mut player = Player::<5, 5, false, true>::new(&LEVELS, 1, TiltConfig::DEFAULT, false)
            .expect("level");
        let start = player.game().world().marbles()[0].pos.x.to_f64();
        // One second of play: 128 frames, a poll every 10 ms between them.
        for frame in 0..FRAME_HZ {
            while clock.get() + PERIOD_US <= frame * 1_000_000 / FRAME_HZ {
                stack.poll();
            }
            let t = stack.sensor.tilt();
            player.tick(AccelMg::new(t.x, t.y, t.z), false);
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
    mma8653_nak_pauses_the_game_until_healthy => |c| {
        fault_pauses_the_game(c, InjectedFault::Nak, Fault::Bus);
    };
    mma8653_stuck_bus_pauses_the_game_until_cleared => |c| {
        let outage = fault_pauses_the_game(c, InjectedFault::StuckBus, Fault::Timeout);
        assert!(outage.clears > 1, "cleared after the timeouts ({outage:?})");
    };
    mma8653_frozen_data_pauses_the_game_until_healthy => |c| {
        fault_pauses_the_game(c, InjectedFault::FrozenData, Fault::NoData);
    };
    mma8653_garbage_pauses_the_game_until_healthy => |c| {
        fault_pauses_the_game(c, InjectedFault::Garbage, Fault::Implausible);
    };
    mma8653_chip_reset_reinitialised_without_a_pause => |c| {
        // A reset is an event: the stack brings the chip back itself, before
        // the supervisor would call the sensor down.
        let outage = through_the_game(c, InjectedFault::ChipReset);
        assert!(outage.transitions.is_empty(), "{outage:?}");
        assert_eq!(outage.paused_frames, 0);
        assert!(outage.reinits >= 1, "{outage:?}");
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
    fxos8700_nak_pauses_the_game_until_healthy => |c| {
        fault_pauses_the_game(c, InjectedFault::Nak, Fault::Bus);
    };
    fxos8700_stuck_bus_pauses_the_game_until_cleared => |c| {
        let outage = fault_pauses_the_game(c, InjectedFault::StuckBus, Fault::Timeout);
        assert!(outage.clears > 1, "cleared after the timeouts ({outage:?})");
    };
    fxos8700_frozen_data_pauses_the_game_until_healthy => |c| {
        fault_pauses_the_game(c, InjectedFault::FrozenData, Fault::NoData);
    };
    fxos8700_garbage_pauses_the_game_until_healthy => |c| {
        fault_pauses_the_game(c, InjectedFault::Garbage, Fault::Implausible);
    };
    fxos8700_chip_reset_reinitialised_without_a_pause => |c| {
        // A reset is an event: the stack brings the chip back itself, before
        // the supervisor would call the sensor down.
        let outage = through_the_game(c, InjectedFault::ChipReset);
        assert!(outage.transitions.is_empty(), "{outage:?}");
        assert_eq!(outage.paused_frames, 0);
        assert!(outage.reinits >= 1, "{outage:?}");
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

/// A chip silent at boot (NAK to every probe) is probed again at each
/// re-initialisation the supervisor asks for, found once it answers, and
/// then read with its own axis map.
#[test]
fn mma8653_and_fxos8700_found_when_they_answer_after_a_silent_boot() {
    for chip in [Accelerometer::Mma8653fc, Accelerometer::Fxos8700cq] {
        let control = ChipControl::new();
        control.inject(InjectedFault::Nak);
        control.set_tilt(AccelMg {
            x: -500,
            y: 866,
            z: 0,
        });
        let clock = Cell::new(0);
        let twi = VirtualTwi::new(
            VirtualNxp::new(chip),
            &control,
            Box::new(|| clock.get()) as Box<dyn Fn() -> u64>,
        );
        let mut sensor = PollLoop::new(twi);
        assert_eq!(block_on(sensor.bring_up()), Some(Probed::NoneAnswered));
        assert_eq!(sensor.found(), None);
        let mut probes = 0;
        let mut down = false;
        for _ in 0..200 {
            clock.set(clock.get() + PERIOD_US);
            let polled = block_on(sensor.poll());
            down |= polled.transition == Some(Transition::Down(Fault::Implausible));
            if polled.probed == Some(Probed::NoneAnswered) {
                probes += 1;
            }
        }
        assert!(down, "{chip:?}: no chip is a sensor down");
        assert!(probes >= 3, "{chip:?}: probed again while down ({probes})");
        control.inject(InjectedFault::Healthy);
        let mut found = None;
        let mut up = false;
        for _ in 0..100 {
            clock.set(clock.get() + PERIOD_US);
            let polled = block_on(sensor.poll());
            found = found.or(polled.probed);
            up |= polled.transition == Some(Transition::Up);
        }
        assert_eq!(found, Some(Probed::Found(chip)), "{chip:?}");
        assert!(up, "{chip:?}: the sensor came up");
        assert!(
            close(sensor.tilt(), [-500, 866, 0], lsb_mg(chip)),
            "{chip:?}: {:?}",
            sensor.tilt()
        );
    }
}

/// A v1.5 with an LSM303AGR: its magnetometer answers at 0x1E, the
/// FXOS8700CQ's address, where register 0x0D (the NXP `WHO_AM_I`) is
/// reserved and reads a byte no datasheet gives. For every value that byte
/// may take, the FXOS8700CQ's identity 0xC7 included, the firmware's probe
/// (the DAL's order: MMA8653FC, LSM303AGR, FXOS8700CQ) finds the LSM303AGR
/// and never addresses 0x1E.
#[test]
fn lsm303agr_v1_5_found_whatever_its_magnetometer_answers_at_0x1e() {
    let control = ChipControl::new();
    let fxos_probe = PROBES
        .iter()
        .find(|probe| probe.chip == Accelerometer::Fxos8700cq)
        .expect("an FXOS8700CQ probe");
    let mut mistaken = 0;
    for reserved in 0..=u8::MAX {
        let mut chip = VirtualLsm303agr::placed(MICROBIT_V2);
        chip.set_reserved_mag_read(reserved);
        // What an FXOS8700CQ probe would read on this board: 0x1E answers.
        let mut lone = VirtualTwi::new(chip.clone(), &control, || 0);
        let mut id = [0u8];
        block_on(lone.write_read(fxos_probe.address, &[fxos_probe.register], &mut id))
            .expect("the magnetometer acknowledges 0x1E");
        assert_eq!(id[0], reserved);
        if identify(fxos_probe, Some(id[0])).is_some() {
            mistaken += 1;
        }
        let mut bus = Recovering::new(VirtualTwi::new(chip, &control, || 0));
        assert_eq!(
            block_on(probe(&mut bus)),
            Some(Accelerometer::Lsm303agr),
            "reserved register reads {reserved:#04x}"
        );
        assert!(
            !bus.bus().addressed(0x1E),
            "{reserved:#04x}: the probe read the magnetometer"
        );
        assert!(bus.bus().addressed(0x1D) && bus.bus().addressed(0x19));
    }
    assert_eq!(
        mistaken, 1,
        "an FXOS8700CQ probe first would take this board for an FXOS8700CQ when 0x0D reads 0xC7"
    );
}

/// The poll loop's bring-up on each board: the chip found is the chip
/// fitted, and the probes stop at it (an MMA8653FC board sees no transfer
/// to 0x19 or 0x1E; an FXOS8700CQ board's probe went through 0x19 first).
#[test]
fn every_v1_board_is_found_by_the_probe_order_of_the_dal() {
    for chip in [
        Accelerometer::Mma8653fc,
        Accelerometer::Lsm303agr,
        Accelerometer::Fxos8700cq,
    ] {
        let control = ChipControl::new();
        let virtual_chip = VirtualChip::new(chip);
        assert_eq!(virtual_chip.kind(), chip);
        let mut sensor = PollLoop::new(VirtualTwi::new(virtual_chip, &control, || 0));
        assert_eq!(block_on(sensor.bring_up()), Some(Probed::Found(chip)));
        assert_eq!(sensor.found(), Some(chip));
        let Some(bus) = sensor.bus() else {
            // The LSM303AGR's driver owns the bus (feature `lsm303agr`).
            continue;
        };
        let twi = bus.bus();
        let expected: &[u8] = match chip {
            Accelerometer::Mma8653fc => &[0x1D],
            Accelerometer::Lsm303agr => &[0x1D, 0x19],
            Accelerometer::Fxos8700cq => &[0x1D, 0x19, 0x1E],
        };
        for address in [0x1D, 0x19, 0x1E] {
            assert_eq!(
                twi.addressed(address),
                expected.contains(&address),
                "{chip:?}: address {address:#04x}"
            );
        }
    }
}

/// What an earlier firmware left in the chip, written in standby and then
/// set running at 200 Hz for half a second: `writes` (register, value).
/// Returns the chip as the next firmware finds it: a reflash resets the
/// nRF, not the accelerometer.
fn left_by_an_earlier_firmware(
    chip: Accelerometer,
    writes: &[(u8, u8)],
    control: &ChipControl,
    clock: &Cell<u64>,
) -> VirtualNxp {
    let address = VirtualNxp::new(chip).address();
    let mut twi = VirtualTwi::new(VirtualNxp::new(chip), control, || clock.get());
    block_on(twi.write(address, &[nxp::CTRL_REG1, 0])).unwrap();
    for &(register, value) in writes {
        block_on(twi.write(address, &[register, value])).unwrap();
    }
    block_on(twi.write(
        address,
        &[nxp::CTRL_REG1, nxp::CTRL1_DR_200HZ | nxp::CTRL1_ACTIVE],
    ))
    .unwrap();
    let mut id = [0u8];
    for _ in 0..50 {
        clock.set(clock.get() + PERIOD_US);
        block_on(twi.write_read(address, &[nxp::WHO_AM_I], &mut id)).unwrap();
    }
    twi.nxp().expect("an NXP chip").clone()
}

/// The longest run of polls without a sample, and the last tilt read
/// (chip frame), over `polls` of the firmware's read on `bus`.
fn poll_reads(
    bus: &mut Recovering<VirtualTwi<'_, impl Fn() -> u64>>,
    chip: &NxpChip,
    clock: &Cell<u64>,
    polls: usize,
) -> (u16, Option<AccelMg>) {
    let (mut run, mut longest, mut last) = (0, 0, None);
    for _ in 0..polls {
        clock.set(clock.get() + PERIOD_US);
        match block_on(read(bus, chip)) {
            Read::Sample(sample) => {
                run = 0;
                last = Some(sample);
            }
            _ => {
                run += 1;
                longest = longest.max(run);
            }
        }
    }
    (longest, last)
}

/// An FXOS8700CQ left in FIFO mode by an earlier firmware (circular, so the
/// FIFO fills and register 0x00 reads `F_STATUS`): configured without a
/// reset, the data-ready bit the firmware reads is a bit of the FIFO's
/// sample count, and the polls go without a sample long enough for the
/// supervisor to call the sensor down (`NoData`); the firmware's own
/// bring-up (soft reset, wait, configure) leaves the FIFO off and plays
/// from the first second on, the tilt read right.
#[test]
fn fxos8700_left_in_fifo_mode_is_reset_by_the_bring_up() {
    let chip = Accelerometer::Fxos8700cq;
    let nxp_chip = chip.nxp().expect("NXP");
    let control = ChipControl::new();
    control.set_tilt(AccelMg {
        x: -500,
        y: 866,
        z: 0,
    });
    let clock = Cell::new(0);
    let left = left_by_an_earlier_firmware(chip, &[(nxp::F_SETUP, 0x40)], &control, &clock);
    assert!(left.fifo_on() && left.fifo_len() == 32, "the FIFO is full");

    // The configuration's writes alone, without the reset before them.
    let mut old = Recovering::new(VirtualTwi::new(left.clone(), &control, || clock.get()));
    for &(register, value) in nxp_chip.configuration() {
        block_on(old.write(nxp_chip.address, &[register, value])).unwrap();
    }
    let (no_sample, _) = poll_reads(&mut old, nxp_chip, &clock, 100);
    assert!(
        old.bus().nxp().expect("NXP").fifo_on(),
        "without a reset the FIFO stays on"
    );
    assert!(
        no_sample >= SUPERVISOR.not_ready_before_fault,
        "without a reset: at most {no_sample} polls in a row without a sample"
    );

    // The firmware's bring-up on the same chip.
    let mut sensor = PollLoop::new(VirtualTwi::new(left, &control, || clock.get()));
    assert_eq!(block_on(sensor.bring_up()), Some(Probed::Found(chip)));
    let mut transitions = Vec::new();
    for _ in 0..100 {
        clock.set(clock.get() + PERIOD_US);
        transitions.extend(block_on(sensor.poll()).transition);
    }
    assert!(transitions.is_empty(), "{transitions:?}");
    assert_eq!(sensor.faults(), 0);
    assert!(
        close(sensor.tilt(), [-500, 866, 0], lsb_mg(chip)),
        "{:?}",
        sensor.tilt()
    );
    let bus = sensor.bus().expect("NXP");
    let state = bus.bus().nxp().expect("NXP");
    assert!(!state.fifo_on(), "the reset turned the FIFO off");
    assert_eq!(state.register(nxp::F_SETUP), 0);
    let (no_sample, _) = poll_reads(bus, nxp_chip, &clock, 100);
    assert!(no_sample < SUPERVISOR.not_ready_before_fault, "{no_sample}");
}

/// An MMA8653FC that ran a DAL program before (data-ready routed to INT1:
/// `CTRL_REG4` = `CTRL_REG5` = 1, registers this firmware never writes)
/// keeps them across a reflash; the bring-up's soft reset clears them, the
/// configuration without it does not.
#[test]
fn mma8653_registers_an_earlier_firmware_set_are_reset_by_the_bring_up() {
    let chip = Accelerometer::Mma8653fc;
    let (ctrl_reg4, ctrl_reg5) = (0x2D, 0x2E);
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let left = left_by_an_earlier_firmware(
        chip,
        &[(ctrl_reg4, 0x01), (ctrl_reg5, 0x01)],
        &control,
        &clock,
    );
    assert_eq!((left.register(ctrl_reg4), left.register(ctrl_reg5)), (1, 1));

    let mut old = VirtualTwi::new(left.clone(), &control, || clock.get());
    let nxp_chip = chip.nxp().expect("NXP");
    for &(register, value) in nxp_chip.configuration() {
        block_on(old.write(nxp_chip.address, &[register, value])).unwrap();
    }
    let state = old.nxp().expect("NXP");
    assert_eq!(
        (state.register(ctrl_reg4), state.register(ctrl_reg5)),
        (1, 1)
    );

    let mut sensor = PollLoop::new(VirtualTwi::new(left, &control, || clock.get()));
    assert_eq!(block_on(sensor.bring_up()), Some(Probed::Found(chip)));
    let state = sensor.bus().expect("NXP").bus().nxp().expect("NXP");
    assert_eq!(
        (state.register(ctrl_reg4), state.register(ctrl_reg5)),
        (0, 0)
    );
    assert!(state.active() && state.period_us() == 5_000);
}

/// After `RST` a chip answers nothing for its reset time: configuring it at
/// once fails, after the firmware's pause it works. The FXOS8700CQ does not
/// acknowledge the reset byte itself; the MMA8653FC does.
#[test]
fn mma8653_and_fxos8700_answer_again_only_after_the_reset_wait() {
    for chip in [Accelerometer::Mma8653fc, Accelerometer::Fxos8700cq] {
        let control = ChipControl::new();
        let mut twi = VirtualTwi::new(VirtualNxp::new(chip), &control, || 0);
        let address = VirtualNxp::new(chip).address();
        let reset = block_on(twi.write(address, &[nxp::CTRL_REG2, nxp::CTRL2_RST]));
        let expected = match chip {
            Accelerometer::Fxos8700cq => Err(TwiError::DataNack),
            _ => Ok(()),
        };
        assert_eq!(reset, expected, "{chip:?}");
        let early = block_on(twi.write(address, &[nxp::XYZ_DATA_CFG, 0]));
        assert_eq!(
            early,
            Err(TwiError::AddressNack),
            "{chip:?} while resetting"
        );
        twi.pause_us(nxp::RESET_WAIT_US);
        assert!(u64::from(nxp::RESET_WAIT_US) >= RESET_US);
        let after = block_on(twi.write(address, &[nxp::XYZ_DATA_CFG, 0]));
        assert_eq!(after, Ok(()), "{chip:?} after the wait");
    }
}
