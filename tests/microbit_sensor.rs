//! Sensor supervision, plausibility and calibration (src/sensor.rs), as the
//! micro:bit firmware uses them.

use marble_rolling::board::microbit::{AXIS_MAP, SUPERVISOR};
use marble_rolling::input::sensor::{
    AccelMg, Action, AxisMap, Calibration, Fault, Plausibility, SensorSupervisor, SupervisorConfig,
    TiltPipeline,
};

const CFG: SupervisorConfig = SupervisorConfig {
    failures_before_reinit: 3,
    reinits_before_fault: 2,
    retry_period_when_down: 4,
};

fn good(x: i32) -> Result<AccelMg, Fault> {
    Ok(AccelMg::new(x, 1000, 0))
}

#[test]
fn plausibility_bounds() {
    let p = Plausibility::DEFAULT;
    assert!(p.check(AccelMg::LEVEL));
    assert!(p.check(AccelMg::new(700, 700, 0)));
    assert!(
        !p.check(AccelMg::new(0, 0, 0)),
        "all-zero = lost configuration"
    );
    assert!(!p.check(AccelMg::new(0, 100, 0)));
    assert!(!p.check(AccelMg::new(0, 5000, 0)), "axis out of range");
    assert!(!p.check(AccelMg::new(2500, 2500, 0)), "total too large");
    assert!(!p.check(AccelMg::new(i32::MIN, i32::MIN, i32::MIN)));
    assert!(!p.check(AccelMg::new(i32::MAX, i32::MAX, i32::MAX)));
}

#[test]
fn good_samples_are_used() {
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, CFG);
    assert_eq!(s.check(good(10)), Action::Use(AccelMg::new(10, 1000, 0)));
    assert_eq!(s.last_good(), AccelMg::new(10, 1000, 0));
    assert!(!s.is_down());
}

#[test]
fn transient_errors_keep_the_last_good_sample() {
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, CFG);
    s.check(good(42));
    let last = AccelMg::new(42, 1000, 0);
    assert_eq!(s.check(Err(Fault::Bus)), Action::KeepLast(last));
    assert_eq!(s.check(Ok(AccelMg::default())), Action::KeepLast(last));
    // A good sample resets the count.
    assert_eq!(s.check(good(43)), Action::Use(AccelMg::new(43, 1000, 0)));
    assert_eq!(
        s.check(Err(Fault::NoData)),
        Action::KeepLast(AccelMg::new(43, 1000, 0))
    );
}

#[test]
fn repeated_errors_ask_for_reinit_then_fault_then_periodic_retries() {
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, CFG);
    let mut actions = Vec::new();
    for _ in 0..20 {
        let a = s.check(Err(Fault::Bus));
        if a == Action::Reinit {
            s.reinit_done(Ok(()));
        }
        actions.push(a);
    }
    let k = Action::KeepLast(AccelMg::LEVEL);
    use Action::{Reinit as R, ShowFault as F};
    assert_eq!(
        actions,
        vec![
            k, k, R, // first window of 3 failures
            k, k, R, // second
            k, k, F, // reinits exhausted: down
            F, F, F, R, // retry every 4 failures while down
            F, F, F, R, F, F, F,
        ]
    );
    assert!(s.is_down());
    // Recovery on the first good sample.
    assert_eq!(s.check(good(5)), Action::Use(AccelMg::new(5, 1000, 0)));
    assert!(!s.is_down());
    assert_eq!(
        s.check(Err(Fault::Bus)),
        Action::KeepLast(AccelMg::new(5, 1000, 0))
    );
}

#[test]
fn failed_reinit_escalates_at_the_next_failure() {
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, CFG);
    for _ in 0..2 {
        s.check(Err(Fault::Bus));
    }
    assert_eq!(s.check(Err(Fault::Bus)), Action::Reinit);
    s.reinit_done(Err(Fault::Bus));
    assert_eq!(s.check(Err(Fault::Bus)), Action::Reinit);
    s.reinit_done(Err(Fault::Bus));
    assert_eq!(s.check(Err(Fault::Bus)), Action::ShowFault);
    assert!(s.is_down());
}

#[test]
fn degenerate_config_never_panics() {
    let cfg = SupervisorConfig {
        failures_before_reinit: 0,
        reinits_before_fault: 0,
        retry_period_when_down: 0,
    };
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, cfg);
    assert_eq!(s.check(Err(Fault::Bus)), Action::ShowFault);
    assert_eq!(s.check(Err(Fault::Bus)), Action::Reinit);
    s.reinit_done(Err(Fault::Bus));
    for _ in 0..100_000 {
        let _ = s.check(Err(Fault::Bus));
    }
    assert!(s.total_faults() > 100_000);
}

#[test]
fn calibration_subtracts_and_clamps() {
    let c = Calibration::from_reference(AccelMg::new(120, 990, -80));
    assert_eq!(
        c.apply(AccelMg::new(120, 990, -80)),
        AccelMg::new(0, 990, 0)
    );
    assert_eq!(
        c.apply(AccelMg::new(0, 1000, 0)),
        AccelMg::new(-120, 1000, 80)
    );
    let side = Calibration::from_reference(AccelMg::new(1000, 0, -1000));
    assert_eq!(side.offset_x, Calibration::MAX_OFFSET_MG);
    assert_eq!(side.offset_z, -Calibration::MAX_OFFSET_MG);
    assert_eq!(
        Calibration::from_reference(AccelMg::new(i32::MIN, 0, i32::MAX)).apply(AccelMg::new(
            i32::MAX,
            0,
            i32::MIN
        )),
        AccelMg::new(i32::MAX, 0, i32::MIN)
    );
}

#[test]
fn pipeline_maps_supervises_and_calibrates() {
    let mut p = TiltPipeline::new(AXIS_MAP, SUPERVISOR);
    // Nothing seen yet: level, calibration refused.
    assert_eq!(p.tilt(), AccelMg::LEVEL);
    assert!(!p.calibrate());

    // Raw reading of a board resting slightly right-edge-down and near-edge-down.
    let raw = AccelMg::new(100, -50, -990);
    assert_eq!(p.feed(Ok(raw)), Action::Use(AccelMg::new(-100, 990, -50)));
    assert!(p.calibrate());
    assert_eq!(p.tilt(), AccelMg::new(0, 990, 0));
    assert_eq!(p.feed(Ok(raw)), Action::Use(AccelMg::new(0, 990, 0)));
    // Calibrating again does not stack.
    assert!(p.calibrate());
    assert_eq!(p.tilt(), AccelMg::new(0, 990, 0));
    // Implausible raw read: keep last, calibrated.
    assert_eq!(
        p.feed(Ok(AccelMg::default())),
        Action::KeepLast(AccelMg::new(0, 990, 0))
    );
    // Tilting right from the calibrated pose.
    assert_eq!(
        p.feed(Ok(AccelMg::new(400, -50, -900))),
        Action::Use(AccelMg::new(-300, 900, 0))
    );
}

#[test]
fn pipeline_refuses_calibration_while_down() {
    let mut p = TiltPipeline::new(AxisMap::IDENTITY, CFG);
    p.feed(Ok(AccelMg::new(100, 1000, 0)));
    for _ in 0..50 {
        if p.feed(Err(Fault::Bus)) == Action::Reinit {
            p.reinit_done(Err(Fault::Bus));
        }
    }
    assert!(p.is_down());
    assert!(!p.calibrate());
    assert_eq!(p.tilt(), AccelMg::new(100, 1000, 0));
}

#[test]
fn supervisor_never_panics_on_arbitrary_input() {
    // A cheap deterministic fuzz: xorshift-driven reads, faults and re-init outcomes.
    let mut p = TiltPipeline::new(AXIS_MAP, SUPERVISOR);
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for _ in 0..200_000 {
        let r = next();
        let read = match r % 4 {
            0 => Err(Fault::Bus),
            1 => Err(Fault::Implausible),
            _ => Ok(AccelMg::new(
                (next() as i32) >> (r % 31),
                (next() as i32) >> (r % 29),
                (next() as i32) >> (r % 23),
            )),
        };
        match p.feed(read) {
            Action::Reinit => p.reinit_done(if r & 8 == 0 { Ok(()) } else { Err(Fault::Bus) }),
            Action::Use(s) | Action::KeepLast(s) => {
                assert!(Plausibility::DEFAULT.check(p.supervisor().last_good()) || s == p.tilt());
            }
            Action::ShowFault => assert!(p.is_down()),
        }
        if r % 1000 == 0 {
            p.calibrate();
        }
    }
}
