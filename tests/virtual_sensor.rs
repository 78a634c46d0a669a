//! The real `lsm303agr` driver (1.1, async) against the QEMU board's virtual
//! LSM303AGR on its virtual TWIM (src/board/qemu/virtual_lsm303agr.rs,
//! virtual_i2c.rs): identity, init, mode and rate, data-ready timing,
//! readings per mode and scale, each injected fault, and the nRF TWIM's DMA
//! rule. Futures run with embassy-futures' `block_on` / `poll_once`; time is a
//! `Cell` the tests step by hand.

use std::cell::Cell;
use std::pin::pin;

use embassy_futures::{block_on, poll_once};
use embedded_hal_async::i2c::I2c;
use lsm303agr::interface::I2cInterface;
use lsm303agr::mode::MagOneShot;
use lsm303agr::{AccelMode, AccelOutputDataRate, AccelScale, Lsm303agr};

use marble_rolling::board::microbit::{BusClear, ACCEL_BOOT_MS, LSM303AGR_READY_US};
use marble_rolling::board::qemu::virtual_i2c::{Ram, RamRange, TwimError, VirtualTwim};
use marble_rolling::board::qemu::{QEMU_RAM, SENSOR_AXIS_MAP, SUPERVISOR};
use marble_rolling::board::virtual_lsm303agr::{
    reg, AccelMode as ChipMode, ChipControl, InjectedFault, Placement, VirtualLsm303agr,
    ACCEL_ADDRESS, CTRL4_BDU, CTRL_REG1_A_RESET, MAG_ADDRESS, MICROBIT_V2,
};
use marble_rolling::input::sensor::{
    AccelMg, Action, Axis, AxisMap, AxisSource, Fault, Plausibility, Read, TiltPipeline, Transition,
};

/// The driver's mode changes take a blocking delay; the tests step time
/// themselves.
struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

/// "RAM" on the host: this thread's stack (within 4 MiB of a local of the
/// test), where the driver's futures and their payload arrays live under
/// `block_on`. The driver's `&[REGISTER]` constants are promoted into the
/// test binary's read-only data, far from any stack: "flash".
fn stack_ram(anchor: &u8) -> impl Fn(usize, usize) -> bool {
    let anchor = anchor as *const u8 as usize;
    move |start: usize, len: usize| len == 0 || start.abs_diff(anchor) < (4 << 20)
}

type Twim<'a, R> = VirtualTwim<'a, Box<dyn FnMut() -> u64 + 'a>, R>;
type Driver<'b, 'a, R> = Lsm303agr<I2cInterface<&'b mut Twim<'a, R>>, MagOneShot>;

fn twim<'a, R: Ram>(
    control: &'a ChipControl,
    copy: &'a mut [u8],
    clock: &'a Cell<u64>,
    ram: R,
) -> Twim<'a, R> {
    VirtualTwim::new(
        VirtualLsm303agr::placed(MICROBIT_V2),
        control,
        copy,
        Box::new(move || clock.get()),
        ram,
    )
}

/// Identity check, init, `mode` at `odr`: the micro:bit firmware's
/// `configure()`.
fn configure<R: Ram>(
    sensor: &mut Driver<'_, '_, R>,
    mode: AccelMode,
    odr: AccelOutputDataRate,
) -> Result<(), lsm303agr::Error<TwimError>> {
    block_on(async {
        let id = sensor.accelerometer_id().await?;
        assert!(id.is_correct(), "WHO_AM_I_A = {:#x}", id.raw());
        sensor.init().await?;
        sensor.set_accel_mode_and_odr(&mut NoDelay, mode, odr).await
    })
}

/// The micro:bit firmware's `read()`: status, then the sample (sensor frame).
fn read<R: Ram>(sensor: &mut Driver<'_, '_, R>) -> Read<AccelMg> {
    block_on(async {
        match sensor.accel_status().await {
            Ok(status) if !status.xyz_new_data() => return Read::NotReady,
            Ok(_) => {}
            Err(_) => return Read::Failed(Fault::Bus),
        }
        match sensor.acceleration().await {
            Ok(a) => {
                let (x, y, z) = a.xyz_mg();
                Read::Sample(AccelMg::new(x, y, z))
            }
            Err(_) => Read::Failed(Fault::Bus),
        }
    })
}

/// The sample of a read that must have one.
#[track_caller]
fn sample(read: Read<AccelMg>) -> AccelMg {
    match read {
        Read::Sample(sample) => sample,
        other => panic!("expected a sample, got {other:?}"),
    }
}

fn board(sample: AccelMg) -> AccelMg {
    SENSOR_AXIS_MAP.apply(sample)
}

fn comm(e: lsm303agr::Error<TwimError>) -> Option<TwimError> {
    match e {
        lsm303agr::Error::Comm(e) => Some(e),
        lsm303agr::Error::InvalidInputData => None,
    }
}

#[test]
fn identity_and_init() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    {
        let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
        let (accel, mag) = block_on(async {
            (
                sensor.accelerometer_id().await.map_err(comm),
                sensor.magnetometer_id().await.map_err(comm),
            )
        });
        let (accel, mag) = (accel.expect("accel id"), mag.expect("mag id"));
        assert_eq!(accel.raw(), 0x33);
        assert!(accel.is_correct());
        assert_eq!(mag.raw(), 0x40);
        assert!(mag.is_correct());
        block_on(sensor.init()).map_err(comm).expect("init");
    }
    let chip = bus.chip();
    assert_eq!(chip.register(ACCEL_ADDRESS, reg::CTRL_REG4_A), CTRL4_BDU);
    assert_eq!(chip.register(ACCEL_ADDRESS, reg::TEMP_CFG_REG_A), 0xC0);
    assert_eq!(chip.register(MAG_ADDRESS, reg::CFG_REG_C_M), 0x10);
    assert_eq!(
        chip.register(ACCEL_ADDRESS, reg::CTRL_REG1_A),
        CTRL_REG1_A_RESET
    );
    assert_eq!(chip.mode(), ChipMode::PowerDown);
    // Nobody else answers.
    let mut byte = [0u8];
    assert_eq!(
        block_on(bus.write_read(0x42, &[0x0F], &mut byte)),
        Err(TwimError::AddressNack)
    );
}

/// The v2's first `WHO_AM_I` comes [`ACCEL_BOOT_MS`] after power-up: a chip
/// that boots for CODAL's 6.4 ms ([`LSM303AGR_READY_US`]) answers it, and
/// the driver's identity check passes; a probe at the datasheet's 5 ms
/// would not be acknowledged.
#[test]
fn the_v2s_first_probe_comes_after_the_lsm303agr_is_ready() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    bus.chip_mut().set_ready_at_us(LSM303AGR_READY_US);
    let mut byte = [0u8];
    clock.set(5_000);
    assert_eq!(
        block_on(bus.write_read(ACCEL_ADDRESS, &[reg::WHO_AM_I_A], &mut byte)),
        Err(TwimError::AddressNack),
        "still booting at 5 ms"
    );
    clock.set(ACCEL_BOOT_MS * 1000);
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    let id = block_on(sensor.accelerometer_id())
        .map_err(comm)
        .expect("the first probe is answered");
    assert!(id.is_correct(), "WHO_AM_I_A = {:#x}", id.raw());
}

#[test]
fn mode_and_output_data_rate() {
    use AccelOutputDataRate as Odr;
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let cases = [
        (AccelMode::LowPower, Odr::Hz1, ChipMode::LowPower, 1),
        (AccelMode::Normal, Odr::Hz10, ChipMode::Normal, 10),
        (
            AccelMode::HighResolution,
            Odr::Hz25,
            ChipMode::HighResolution,
            25,
        ),
        (AccelMode::Normal, Odr::Hz50, ChipMode::Normal, 50),
        (
            AccelMode::HighResolution,
            Odr::Hz100,
            ChipMode::HighResolution,
            100,
        ),
        (
            AccelMode::HighResolution,
            Odr::Hz200,
            ChipMode::HighResolution,
            200,
        ),
        (AccelMode::LowPower, Odr::Hz400, ChipMode::LowPower, 400),
        (
            AccelMode::LowPower,
            Odr::Khz1_620LowPower,
            ChipMode::LowPower,
            1620,
        ),
        (
            AccelMode::LowPower,
            Odr::Khz5_376LowPower,
            ChipMode::LowPower,
            5376,
        ),
        (AccelMode::Normal, Odr::Khz1_344, ChipMode::Normal, 1344),
        (
            AccelMode::HighResolution,
            Odr::Khz1_344,
            ChipMode::HighResolution,
            1344,
        ),
    ];
    for (mode, odr, chip_mode, hz) in cases {
        {
            let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
            configure(&mut sensor, mode, odr).expect("configure");
        }
        assert_eq!(bus.chip().mode(), chip_mode, "{mode:?} {odr:?}");
        assert_eq!(bus.chip().odr_hz(), hz, "{mode:?} {odr:?}");
    }
    {
        let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
        block_on(sensor.set_accel_mode_and_odr(&mut NoDelay, AccelMode::PowerDown, None))
            .expect("power down");
    }
    assert_eq!(bus.chip().mode(), ChipMode::PowerDown);
    assert_eq!(bus.chip().odr_hz(), 0);
}

#[test]
fn data_ready_follows_the_output_data_rate() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(1_000);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    configure(
        &mut sensor,
        AccelMode::HighResolution,
        AccelOutputDataRate::Hz100,
    )
    .expect("configure");
    let mut at = |t: u64| {
        clock.set(1_000 + t);
        read(&mut sensor)
    };
    // Samples at 10 ms, 20 ms, ... after the rate was set (t = 0).
    assert_eq!(at(0), Read::NotReady);
    assert_eq!(at(9_999), Read::NotReady);
    assert_eq!(board(sample(at(10_000))), AccelMg::LEVEL);
    assert_eq!(at(10_001), Read::NotReady, "read clears ZYXDA");
    assert_eq!(at(19_999), Read::NotReady);
    sample(at(20_000));
    // Three periods without a read: the set was overwritten unread.
    clock.set(1_000 + 50_000);
    let status = block_on(sensor.accel_status()).expect("status");
    assert!(status.xyz_new_data() && status.xyz_overrun());
    sample(read(&mut sensor));
    let status = block_on(sensor.accel_status()).expect("status");
    assert!(!status.xyz_new_data() && !status.xyz_overrun());

    // 1344 Hz: a period of 744.05 µs, sample n at ceil(n / 1344 Hz).
    configure(
        &mut sensor,
        AccelMode::Normal,
        AccelOutputDataRate::Khz1_344,
    )
    .expect("1344 Hz");
    let t0 = clock.get();
    let mut at = |t: u64| {
        clock.set(t0 + t);
        read(&mut sensor)
    };
    assert_eq!(at(744), Read::NotReady);
    sample(at(745));
    assert_eq!(at(1_488), Read::NotReady);
    sample(at(1_489));
    // 1000 samples later, still on the grid: no drift (sample 999 at
    // 743 303.6 µs, 1000 at 744 047.6 µs).
    sample(at(743_304));
    assert_eq!(at(744_047), Read::NotReady);
    sample(at(744_048));
}

#[test]
fn readings_equal_the_set_tilt_within_one_lsb_in_every_mode_and_scale() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    let tilts = [
        AccelMg::LEVEL,
        AccelMg::from_xz(-200, 0),
        AccelMg::from_xz(300, -450),
        AccelMg {
            x: 1234,
            y: -1500,
            z: 1999,
        },
        AccelMg { x: -7, y: 3, z: -1 },
        AccelMg {
            x: 15_000,
            y: -9_000,
            z: 5_500,
        },
    ];
    let modes = [
        (AccelMode::LowPower, 8),
        (AccelMode::Normal, 10),
        (AccelMode::HighResolution, 12),
    ];
    let scales = [
        (AccelScale::G2, 2),
        (AccelScale::G4, 4),
        (AccelScale::G8, 8),
        (AccelScale::G16, 16),
    ];
    for (mode, bits) in modes {
        for (scale, g) in scales {
            configure(&mut sensor, mode, AccelOutputDataRate::Hz100).expect("configure");
            block_on(sensor.set_accel_scale(scale)).expect("scale");
            let lsb = ChipMode::mg_per_lsb(
                match mode {
                    AccelMode::LowPower => ChipMode::LowPower,
                    AccelMode::Normal => ChipMode::Normal,
                    _ => ChipMode::HighResolution,
                },
                g,
            );
            let max = ((1 << (bits - 1)) - 1) * lsb;
            let min = -(1 << (bits - 1)) * lsb;
            for tilt in tilts {
                control.set_tilt(tilt);
                clock.set(clock.get() + 10_000);
                let got = board(sample(read(&mut sensor)));
                let want = tilt;
                for (axis, (got, want)) in
                    got.to_array().into_iter().zip(want.to_array()).enumerate()
                {
                    // The chip saturates at its full scale.
                    let want = want.clamp(min, max);
                    assert!(
                        (got - want).abs() <= lsb,
                        "{mode:?} ±{g} g axis {axis}: read {got} mg for {want} mg (LSB {lsb} mg)"
                    );
                }
            }
        }
    }
}

#[test]
fn nak_fails_every_transfer_and_changes_nothing() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    {
        let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
        configure(&mut sensor, AccelMode::Normal, AccelOutputDataRate::Hz100).expect("configure");
        control.inject(InjectedFault::Nak);
        let before = control.transfers();
        let id = block_on(sensor.accelerometer_id()).map_err(comm);
        assert_eq!(id.err(), Some(Some(TwimError::AddressNack)));
        let scale = block_on(sensor.set_accel_scale(AccelScale::G16)).map_err(comm);
        assert_eq!(scale.err(), Some(Some(TwimError::AddressNack)));
        clock.set(20_000);
        assert_eq!(read(&mut sensor), Read::Failed(Fault::Bus));
        assert_eq!(control.transfers(), before + 3, "NAKs are bus traffic");
    }
    assert_eq!(
        bus.chip().full_scale_g(),
        2,
        "the refused write changed nothing"
    );
    control.inject(InjectedFault::Healthy);
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    assert!(block_on(sensor.accelerometer_id()).is_ok());
}

#[test]
fn a_stuck_bus_never_completes_until_the_caller_gives_up() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    configure(&mut sensor, AccelMode::Normal, AccelOutputDataRate::Hz100).expect("configure");
    control.inject(InjectedFault::StuckBus);
    clock.set(10_000);
    {
        let mut status = pin!(sensor.accel_status());
        for _ in 0..100 {
            assert!(poll_once(status.as_mut()).is_pending());
            clock.set(clock.get() + 1_000);
        }
        // Dropped here: the caller's timeout. Nothing was applied.
    }
    // A timeout as the firmware has one: select against a deadline.
    let deadline = async {
        for _ in 0..10 {
            embassy_futures::yield_now().await;
        }
    };
    let raced = block_on(embassy_futures::select::select(
        sensor.accelerometer_id(),
        deadline,
    ));
    assert!(matches!(raced, embassy_futures::select::Either::Second(())));
    assert!(bus.stuck());
    assert_eq!(
        bus.clear_bus(),
        BusClear::SdaStuck,
        "a wedged slave holds on"
    );
    assert!(bus.stuck());
    // Healthy again, but the slave still holds SDA low: stuck until cleared.
    control.inject(InjectedFault::Healthy);
    {
        let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
        let mut status = pin!(sensor.accel_status());
        for _ in 0..10 {
            assert!(
                poll_once(status.as_mut()).is_pending(),
                "the fault lifted does not free the bus"
            );
        }
    }
    assert!(
        matches!(bus.clear_bus(), BusClear::Released { clocks } if clocks <= 9),
        "nine clocks free it"
    );
    assert!(!bus.stuck());
    assert_eq!(bus.clears(), 2);
    assert_eq!(bus.clear_bus(), BusClear::Free, "a free bus: a STOP alone");
    // A fresh driver knows no mode: the firmware's re-init configures again.
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    configure(&mut sensor, AccelMode::Normal, AccelOutputDataRate::Hz100).expect("configure");
    let got = sample(read(&mut sensor));
    assert_eq!(
        board(got),
        AccelMg::LEVEL,
        "the sample the stuck transfer did not take"
    );
}

#[test]
fn a_chip_reset_frees_a_stuck_bus() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    control.inject(InjectedFault::StuckBus);
    {
        let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
        let mut id = pin!(sensor.accelerometer_id());
        assert!(poll_once(id.as_mut()).is_pending());
    }
    assert!(bus.stuck());
    // A brown-out resets the chip's I²C state machine with its registers.
    control.inject(InjectedFault::ChipReset);
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    configure(&mut sensor, AccelMode::Normal, AccelOutputDataRate::Hz100)
        .expect("the reset chip answers");
    assert!(!bus.stuck());
    assert_eq!(bus.clears(), 0, "freed without a bus clear");
}

#[test]
fn frozen_data_stops_the_output_and_a_reinit_does_not_help() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    configure(
        &mut sensor,
        AccelMode::HighResolution,
        AccelOutputDataRate::Hz100,
    )
    .expect("configure");
    control.set_tilt(AccelMg::from_xz(-300, 0));
    clock.set(10_000);
    let before = sample(read(&mut sensor));
    control.inject(InjectedFault::FrozenData);
    control.set_tilt(AccelMg::from_xz(400, 100));
    for t in (20_000..200_000).step_by(10_000) {
        clock.set(t);
        assert_eq!(read(&mut sensor), Read::NotReady);
    }
    let stale = block_on(sensor.acceleration()).expect("registers still read");
    let (x, y, z) = stale.xyz_mg();
    assert_eq!(
        AccelMg::new(x, y, z),
        before,
        "the output registers kept their values"
    );
    configure(
        &mut sensor,
        AccelMode::HighResolution,
        AccelOutputDataRate::Hz100,
    )
    .expect("re-init is accepted");
    clock.set(300_000);
    assert_eq!(read(&mut sensor), Read::NotReady, "and does not help");
    control.inject(InjectedFault::Healthy);
    clock.set(310_000);
    let after = board(sample(read(&mut sensor)));
    assert_eq!(after, AccelMg::from_xz(400, 100));
}

#[test]
fn garbage_is_new_data_and_always_implausible() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    for (mode, scale) in [
        (AccelMode::HighResolution, AccelScale::G2),
        (AccelMode::LowPower, AccelScale::G2),
        (AccelMode::Normal, AccelScale::G16),
    ] {
        configure(&mut sensor, mode, AccelOutputDataRate::Hz100).expect("configure");
        block_on(sensor.set_accel_scale(scale)).expect("scale");
        control.inject(InjectedFault::Garbage);
        let mut seen = Vec::new();
        for _ in 0..50 {
            clock.set(clock.get() + 10_000);
            let got = sample(read(&mut sensor));
            assert!(
                !Plausibility::DEFAULT.check(board(got)),
                "{mode:?} {scale:?}: {got:?} passed"
            );
            seen.push(got);
        }
        seen.sort_by_key(|s| (s.x, s.y, s.z));
        seen.dedup();
        assert!(seen.len() > 40, "random, not stuck");
        control.inject(InjectedFault::Healthy);
    }
}

#[test]
fn a_chip_reset_needs_a_reinit() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    {
        let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
        configure(
            &mut sensor,
            AccelMode::HighResolution,
            AccelOutputDataRate::Hz200,
        )
        .expect("configure");
        clock.set(5_000);
        sample(read(&mut sensor));
        control.inject(InjectedFault::ChipReset);
        assert_eq!(
            control.fault(),
            InjectedFault::Healthy,
            "a reset is an event"
        );
        for t in (10_000..500_000).step_by(5_000) {
            clock.set(t);
            assert_eq!(read(&mut sensor), Read::NotReady, "powered down at {t}");
        }
    }
    assert_eq!(control.resets_applied(), 1);
    let chip = bus.chip();
    assert_eq!(
        chip.register(ACCEL_ADDRESS, reg::CTRL_REG1_A),
        CTRL_REG1_A_RESET
    );
    assert_eq!(chip.register(ACCEL_ADDRESS, reg::CTRL_REG4_A), 0);
    assert_eq!(chip.register(ACCEL_ADDRESS, reg::STATUS_REG_A), 0);
    assert_eq!(chip.mode(), ChipMode::PowerDown);
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    configure(
        &mut sensor,
        AccelMode::HighResolution,
        AccelOutputDataRate::Hz200,
    )
    .expect("re-init");
    clock.set(clock.get() + 5_000);
    assert_eq!(board(sample(read(&mut sensor))), AccelMg::LEVEL);
}

#[test]
fn without_a_copy_buffer_the_drivers_reads_fail_before_reaching_the_bus() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut none: [u8; 0] = [];
    let mut bus = twim(&control, &mut none, &clock, stack_ram(&anchor));
    {
        let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
        // Reads address their register with a promoted `&[REG]`: "flash".
        let id = block_on(sensor.accelerometer_id()).map_err(comm);
        assert_eq!(id.err(), Some(Some(TwimError::RAMBufferTooSmall)));
        assert_eq!(control.transfers(), 0, "no bus traffic");
        assert_eq!(control.refused(), 1);
        // Writes send a payload array built in the future: RAM, fine.
        block_on(sensor.init())
            .map_err(comm)
            .expect("init writes from RAM");
        block_on(sensor.set_accel_mode_and_odr(
            &mut NoDelay,
            AccelMode::HighResolution,
            AccelOutputDataRate::Hz100,
        ))
        .map_err(comm)
        .expect("mode writes from RAM");
        assert_eq!(control.transfers(), 5);
        clock.set(10_000);
        let status = block_on(sensor.accel_status()).map_err(comm);
        assert_eq!(status.err(), Some(Some(TwimError::RAMBufferTooSmall)));
        let sample = block_on(sensor.acceleration()).map_err(comm);
        assert_eq!(sample.err(), Some(Some(TwimError::RAMBufferTooSmall)));
        assert_eq!(control.transfers(), 5);
        assert_eq!(control.refused(), 3);
    }
    assert_eq!(bus.last_error(), Some(TwimError::RAMBufferTooSmall));
    // The chip is configured and has data, but it never sees a read.
    assert_eq!(bus.chip().mode(), ChipMode::HighResolution);
}

#[test]
fn a_one_byte_copy_buffer_is_enough_for_the_driver() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 1];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    configure(
        &mut sensor,
        AccelMode::HighResolution,
        AccelOutputDataRate::Hz100,
    )
    .expect("configure");
    control.set_tilt(AccelMg::from_xz(-500, 250));
    clock.set(10_000);
    assert_eq!(
        board(sample(read(&mut sensor))),
        AccelMg::new(-500, 829, 250)
    );
    assert_eq!(control.refused(), 0);
}

/// CTRL_REG1_A ← 0x57 (100 Hz, normal), from a `static`: read-only data.
static FLASH_WRITE: [u8; 2] = [reg::CTRL_REG1_A, 0x57];

#[test]
fn a_write_from_flash_needs_a_copy_buffer_at_least_as_long() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut short = [0u8; 1];
    let mut bus = twim(&control, &mut short, &clock, stack_ram(&anchor));
    assert_eq!(
        block_on(bus.write(ACCEL_ADDRESS, &FLASH_WRITE)),
        Err(TwimError::RAMBufferTooSmall)
    );
    assert_eq!(control.transfers(), 0);
    assert_eq!(bus.chip().odr_hz(), 0, "nothing reached the chip");
    // The same bytes from RAM need no copy.
    let ram_copy = FLASH_WRITE;
    assert_eq!(block_on(bus.write(ACCEL_ADDRESS, &ram_copy)), Ok(()));
    assert_eq!(bus.chip().odr_hz(), 100);

    let control = ChipControl::new();
    let mut exact = [0u8; 2];
    let mut bus = twim(&control, &mut exact, &clock, stack_ram(&anchor));
    assert_eq!(block_on(bus.write(ACCEL_ADDRESS, &FLASH_WRITE)), Ok(()));
    assert_eq!(bus.chip().odr_hz(), 100);
    assert_eq!(bus.chip().mode(), ChipMode::Normal);
}

#[test]
fn ram_range_tests_like_embassy_nrf() {
    let ram = QEMU_RAM;
    assert!(ram.holds(0x2000_0000, 4));
    assert!(ram.holds(0x2001_fffe, 1));
    // embassy-nrf's `slice_in_ram`: the end is exclusive, strictly.
    assert!(!ram.holds(0x2001_ffff, 1));
    assert!(!ram.holds(0x1fff_ffff, 1));
    assert!(!ram.holds(0x0000_1000, 1), "flash");
    assert!(ram.holds(0x0000_1000, 0), "empty slices pass");
    let custom = RamRange {
        start: 0x100,
        end: 0x200,
    };
    assert!(custom.holds(0x100, 0xff));
    assert!(!custom.holds(0x100, 0x100));
}

#[test]
fn every_register_address_reads_and_writes_without_a_panic() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    for device in [ACCEL_ADDRESS, MAG_ADDRESS] {
        for sub in 0..=u8::MAX {
            let mut data = [0u8; 3];
            assert_eq!(block_on(bus.write_read(device, &[sub], &mut data)), Ok(()));
            assert_eq!(block_on(bus.write(device, &[sub, 0xA5, 0x5A])), Ok(()));
        }
    }
    // Reserved accelerometer addresses read 0; auto-increment wraps at 0x7F.
    let mut data = [0xFFu8; 3];
    assert_eq!(
        block_on(bus.write_read(ACCEL_ADDRESS, &[0x80 | 0x7F], &mut data)),
        Ok(())
    );
    assert_eq!(data, [0, 0, 0]);
}

#[test]
fn two_reads_in_a_row_are_refused_not_a_panic() {
    use embedded_hal_async::i2c::Operation;
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let (mut a, mut b) = ([0u8; 1], [0u8; 1]);
    let mut ops = [Operation::Read(&mut a), Operation::Read(&mut b)];
    assert_eq!(
        block_on(bus.transaction(ACCEL_ADDRESS, &mut ops)),
        Err(TwimError::Unsupported)
    );
    // Write, read, write: two chunks, as the TWIM runs them.
    let sub = [reg::WHO_AM_I_A];
    let mut id = [0u8; 1];
    let set = [reg::CTRL_REG1_A, 0x27];
    let mut ops = [
        Operation::Write(&sub),
        Operation::Read(&mut id),
        Operation::Write(&set),
    ];
    assert_eq!(block_on(bus.transaction(ACCEL_ADDRESS, &mut ops)), Ok(()));
    assert_eq!(id, [0x33]);
    assert_eq!(bus.chip().odr_hz(), 10);
    assert_eq!(control.transfers(), 2);
}

/// The micro:bit's whole input path on the virtual chip: driver, pipeline,
/// re-inits; each fault brings the sensor down (with its fault) and it comes
/// back when the fault ends, each transition reported once.
#[test]
fn the_pipeline_goes_down_on_each_fault_and_comes_back() {
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(0);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    let mut pipeline = TiltPipeline::new(SENSOR_AXIS_MAP, SUPERVISOR);
    let reinit = |sensor: &mut Driver<'_, '_, _>| {
        configure(
            sensor,
            AccelMode::HighResolution,
            AccelOutputDataRate::Hz200,
        )
        .map_err(|_| Fault::Bus)
    };
    pipeline.reinit_done(reinit(&mut sensor));
    // One 10 ms poll; a re-init's settling time is 40 ms.
    let poll = |pipeline: &mut TiltPipeline, sensor: &mut Driver<'_, '_, _>| {
        clock.set(clock.get() + 10_000);
        let step = pipeline.feed(read(sensor));
        if step.action == Action::Reinit {
            let outcome = reinit(sensor);
            clock.set(clock.get() + 40_000);
            pipeline.reinit_done(outcome);
        }
        step
    };
    control.set_tilt(AccelMg::from_xz(-200, 0));
    assert!(matches!(
        poll(&mut pipeline, &mut sensor).action,
        Action::Use(_)
    ));
    assert_eq!(pipeline.tilt(), AccelMg::new(-200, 979, 0));
    for (fault, expected) in [
        (InjectedFault::Nak, Fault::Bus),
        (InjectedFault::FrozenData, Fault::NoData),
        (InjectedFault::Garbage, Fault::Implausible),
    ] {
        control.inject(fault);
        let mut polls = 0;
        let down = loop {
            polls += 1;
            assert!(polls < 50, "{fault:?}: not down after {polls} polls");
            match poll(&mut pipeline, &mut sensor).transition {
                Some(Transition::Down(why)) => break why,
                None => {}
                Some(Transition::Up) => panic!("{fault:?}: up before down"),
            }
        };
        assert_eq!(down, expected, "{fault:?}");
        control.inject(InjectedFault::Healthy);
        let mut polls = 0;
        loop {
            polls += 1;
            assert!(polls < 60, "{fault:?}: not up after {polls} polls");
            match poll(&mut pipeline, &mut sensor).transition {
                Some(Transition::Up) => break,
                None => {}
                Some(other) => panic!("{fault:?}: {other:?} while down"),
            }
        }
        assert_eq!(pipeline.tilt(), AccelMg::new(-200, 979, 0), "{fault:?}");
    }
    // A chip reset: re-initialised before the sensor is declared down.
    control.inject(InjectedFault::ChipReset);
    let mut polls = 0;
    loop {
        polls += 1;
        assert!(polls < 60, "not back after a chip reset");
        let step = poll(&mut pipeline, &mut sensor);
        assert_eq!(step.transition, None, "a chip reset is not an outage");
        if let Action::Use(_) = step.action {
            break;
        }
    }
    assert_eq!(control.resets_applied(), 1);
}

#[test]
fn power_down_before_sleep_stops_the_samples_and_a_reinit_brings_them_back() {
    // The micro:bit v2's sleep: `input::lsm303::power_down` makes this driver
    // call (`PowerDown`, no rate); the wake-up is a reset, whose first poll
    // runs `configure` again.
    let anchor = 0u8;
    let control = ChipControl::new();
    let clock = Cell::new(1_000);
    let mut copy = [0u8; 8];
    let mut bus = twim(&control, &mut copy, &clock, stack_ram(&anchor));
    let mut sensor = Lsm303agr::new_with_i2c(&mut bus);
    configure(
        &mut sensor,
        AccelMode::HighResolution,
        AccelOutputDataRate::Hz200,
    )
    .expect("configure");
    clock.set(1_000 + 5_000);
    assert_eq!(board(sample(read(&mut sensor))), AccelMg::LEVEL);
    block_on(sensor.set_accel_mode_and_odr(&mut NoDelay, AccelMode::PowerDown, None))
        .expect("power down");
    assert_eq!(block_on(sensor.get_accel_mode()), AccelMode::PowerDown);
    // Asleep for a minute: not one conversion.
    for ms in (10..60_000).step_by(997) {
        clock.set(1_000 + ms * 1_000);
        assert_eq!(
            read(&mut sensor),
            Read::NotReady,
            "{ms} ms after power-down"
        );
    }
    let t0 = clock.get();
    configure(
        &mut sensor,
        AccelMode::HighResolution,
        AccelOutputDataRate::Hz200,
    )
    .expect("configure again");
    clock.set(t0 + 5_000);
    assert_eq!(board(sample(read(&mut sensor))), AccelMg::LEVEL);
}

#[test]
fn the_chips_placement_and_the_firmwares_axis_table_agree() {
    // Each tilt of the board, read by the chip placed as on the micro:bit v2
    // and turned back by the firmware's table: the tilt itself.
    for tilt in [
        AccelMg::LEVEL,
        AccelMg::new(1000, 0, 0),
        AccelMg::new(0, 0, 1000),
        AccelMg::new(-700, 700, 100),
    ] {
        let raw = MICROBIT_V2.raw(tilt);
        let read = SENSOR_AXIS_MAP.apply(AccelMg::from_array(raw));
        assert_eq!(read, tilt, "tilt {tilt:?}");
    }
    assert_eq!(Placement::assumed_by(&SENSOR_AXIS_MAP), MICROBIT_V2);
}

#[test]
fn a_sign_error_in_the_firmwares_table_shows() {
    // The firmware's table with one sign flipped at a time: the chip, which
    // keeps its own placement, no longer reads back the board's tilt.
    let flip = |s: AxisSource| AxisSource {
        negate: !s.negate,
        ..s
    };
    let m = SENSOR_AXIS_MAP;
    for wrong in [
        AxisMap { x: flip(m.x), ..m },
        AxisMap { y: flip(m.y), ..m },
        AxisMap { z: flip(m.z), ..m },
        AxisMap {
            x: AxisSource::pos(Axis::X),
            y: AxisSource::pos(Axis::Y),
            z: AxisSource::pos(Axis::Z),
        },
    ] {
        let caught = [
            AccelMg::new(1000, 0, 0),
            AccelMg::LEVEL,
            AccelMg::new(0, 0, 1000),
        ]
        .into_iter()
        .any(|tilt| wrong.apply(AccelMg::from_array(MICROBIT_V2.raw(tilt))) != tilt);
        assert!(caught, "{wrong:?} reads every tilt right");
        // A chip that took its placement from the wrong table would not
        // have caught it.
        let assumed = Placement::assumed_by(&wrong);
        let right = AccelMg::new(1000, 0, 0);
        assert_eq!(wrong.apply(AccelMg::from_array(assumed.raw(right))), right);
    }
}
