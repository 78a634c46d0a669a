//! Sensor supervision, plausibility, the not-ready policy and the down/up
//! transitions (src/input/sensor.rs), as the micro:bit firmware uses them.

use marble_rolling::board::microbit::{ACCEL_ODR_HZ, AXIS_MAP, INPUT_PERIOD_MS, SUPERVISOR};
use marble_rolling::input::event::InputEvent;
use marble_rolling::input::sensor::{
    AccelMg, Action, AxisMap, Calibration, Fault, Plausibility, Read, SensorSupervisor, Step,
    SupervisorConfig, TiltPipeline, Transition,
};

const CFG: SupervisorConfig = SupervisorConfig {
    failures_before_reinit: 3,
    reinits_before_fault: 2,
    retry_period_when_down: 4,
    not_ready_before_fault: 3,
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
        not_ready_before_fault: 0,
    };
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, cfg);
    assert_eq!(s.check(Err(Fault::Bus)), Action::ShowFault);
    assert_eq!(s.check(Err(Fault::Bus)), Action::Reinit);
    s.reinit_done(Err(Fault::Bus));
    for _ in 0..100_000 {
        let _ = s.check(Err(Fault::Bus));
    }
    assert!(s.total_faults() > 100_000);
    // not_ready_before_fault 0 behaves as 1: every not-ready poll counts.
    let before = s.total_faults();
    let _ = s.not_ready();
    assert_eq!(s.total_faults(), before + 1);
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

/// Drives a pipeline until it is down, answering every re-init with `reinit`.
fn bring_down(p: &mut TiltPipeline, fault: Fault, reinit: Result<(), Fault>) -> Vec<Step> {
    let mut steps = Vec::new();
    for _ in 0..50 {
        let step = p.feed(Read::Failed(fault));
        if step.action == Action::Reinit {
            p.reinit_done(reinit);
        }
        steps.push(step);
        if p.is_down() {
            break;
        }
    }
    steps
}

#[test]
fn a_single_not_ready_poll_is_keep_last_and_not_counted() {
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, CFG);
    s.check(good(7));
    let last = AccelMg::new(7, 1000, 0);
    for _ in 0..1000 {
        assert_eq!(s.not_ready(), Action::KeepLast(last));
        assert_eq!(s.check(good(7)), Action::Use(last));
    }
    // Two in a row (one short of the limit) are still uncounted.
    for _ in 0..1000 {
        assert_eq!(s.not_ready(), Action::KeepLast(last));
        assert_eq!(s.not_ready(), Action::KeepLast(last));
        assert_eq!(s.check(good(7)), Action::Use(last));
    }
    assert_eq!(s.total_faults(), 0);
    assert_eq!(s.last_fault(), None);
}

#[test]
fn not_ready_for_several_polls_is_no_data() {
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, CFG);
    let k = Action::KeepLast(AccelMg::LEVEL);
    // Polls 1 and 2: not yet. From poll 3 on, each one is a NoData failure:
    // failures 1 and 2 keep the last sample, failure 3 asks for a re-init.
    assert_eq!(s.not_ready(), k);
    assert_eq!(s.not_ready(), k);
    assert_eq!(s.total_faults(), 0);
    assert_eq!(s.not_ready(), k);
    assert_eq!(s.last_fault(), Some(Fault::NoData));
    assert_eq!(s.not_ready(), k);
    assert_eq!(s.not_ready(), Action::Reinit);
    assert_eq!(s.total_faults(), 3);
    // After the re-init the sensor gets its grace again.
    s.reinit_done(Ok(()));
    assert_eq!(s.not_ready(), k);
    assert_eq!(s.not_ready(), k);
    assert_eq!(s.total_faults(), 3);
}

#[test]
fn not_ready_neither_counts_nor_forgives_failures() {
    // Bus, not-ready, Bus, not-ready, Bus: the re-init comes at the third bus
    // failure exactly as without the not-ready polls in between.
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, CFG);
    let k = Action::KeepLast(AccelMg::LEVEL);
    assert_eq!(s.check(Err(Fault::Bus)), k);
    assert_eq!(s.not_ready(), k);
    assert_eq!(s.check(Err(Fault::Bus)), k);
    assert_eq!(s.not_ready(), k);
    assert_eq!(s.check(Err(Fault::Bus)), Action::Reinit);
    assert_eq!(s.total_faults(), 3);
}

#[test]
fn not_ready_while_down_shows_the_fault_and_keeps_retrying() {
    let mut s = SensorSupervisor::new(AccelMg::LEVEL, CFG);
    for _ in 0..20 {
        if s.check(Err(Fault::Bus)) == Action::Reinit {
            s.reinit_done(Err(Fault::Bus));
        }
        if s.is_down() {
            break;
        }
    }
    assert!(s.is_down());
    assert_eq!(s.not_ready(), Action::ShowFault);
    assert_eq!(s.not_ready(), Action::ShowFault);
    // A sensor that never has data again still gets re-inits while down.
    let mut reinits = 0;
    for _ in 0..40 {
        if s.not_ready() == Action::Reinit {
            reinits += 1;
        }
    }
    assert!(reinits >= 5, "{reinits}");
    assert_eq!(s.down_fault(), Some(Fault::Bus));
    assert_eq!(s.check(good(1)), Action::Use(AccelMg::new(1, 1000, 0)));
    assert_eq!(s.down_fault(), None);
}

#[test]
fn read_from_result() {
    assert_eq!(Read::from(good(3)), Read::Sample(AccelMg::new(3, 1000, 0)));
    assert_eq!(
        Read::<AccelMg>::from(Err(Fault::Timeout)),
        Read::Failed(Fault::Timeout)
    );
    let mut s = SensorSupervisor::new(0u8, CFG);
    assert_eq!(s.poll(Read::Sample(9)), Action::Use(9));
    assert_eq!(s.poll(Read::NotReady), Action::KeepLast(9));
    assert_eq!(s.poll(Read::Failed(Fault::Bus)), Action::KeepLast(9));
}

#[test]
fn board_not_ready_limit_spans_several_sample_periods() {
    const SAMPLE_PERIOD_MS: u64 = 1000 / ACCEL_ODR_HZ as u64;
    const SPAN_MS: u64 = SUPERVISOR.not_ready_before_fault as u64 * INPUT_PERIOD_MS;
    // Missing for four sample periods at least before it is a fault…
    const { assert!(SPAN_MS >= 4 * SAMPLE_PERIOD_MS) };
    // …and a single poll without a sample is timing, never a fault.
    const { assert!(SUPERVISOR.not_ready_before_fault >= 2) };
}

#[test]
fn pipeline_maps_and_supervises_without_calibrating() {
    let mut p = TiltPipeline::new(AXIS_MAP, SUPERVISOR);
    // Nothing seen yet: level.
    assert_eq!(p.tilt(), AccelMg::LEVEL);

    // Raw reading of a board resting slightly right-edge-down and
    // near-edge-down: the board-frame sample, uncalibrated.
    let raw = AccelMg::new(100, -50, -990);
    let mapped = AccelMg::new(-100, 990, -50);
    assert_eq!(
        p.feed(Read::Sample(raw)),
        Step {
            action: Action::Use(mapped),
            transition: None
        }
    );
    assert_eq!(p.tilt(), mapped);
    // Implausible raw read: keep last.
    assert_eq!(
        p.feed(Read::Sample(AccelMg::default())).action,
        Action::KeepLast(mapped)
    );
    // Not ready: keep last, no transition.
    assert_eq!(
        p.feed(Read::NotReady),
        Step {
            action: Action::KeepLast(mapped),
            transition: None
        }
    );
    assert_eq!(
        p.feed(Read::Sample(AccelMg::new(400, -50, -900))).action,
        Action::Use(AccelMg::new(-400, 900, -50))
    );
}

#[test]
fn pipeline_reports_down_with_its_fault_once_then_up_once() {
    let mut p = TiltPipeline::new(AxisMap::IDENTITY, CFG);
    p.feed(Read::Sample(AccelMg::new(100, 1000, 0)));
    let steps = bring_down(&mut p, Fault::Timeout, Err(Fault::Timeout));
    assert!(p.is_down());
    let transitions: Vec<_> = steps.iter().filter_map(|s| s.transition).collect();
    assert_eq!(transitions, vec![Transition::Down(Fault::Timeout)]);
    assert_eq!(
        steps.last().map(|s| s.transition),
        Some(Some(Transition::Down(Fault::Timeout)))
    );
    // Staying down: no more transitions, whatever comes.
    for read in [
        Read::Failed(Fault::Bus),
        Read::NotReady,
        Read::Sample(AccelMg::default()),
        Read::Failed(Fault::NoData),
    ]
    .into_iter()
    .cycle()
    .take(200)
    {
        let step = p.feed(read);
        if step.action == Action::Reinit {
            p.reinit_done(Err(Fault::Bus));
        }
        assert_eq!(step.transition, None);
        assert!(p.is_down());
    }
    // The tilt stays the last good sample meanwhile.
    assert_eq!(p.tilt(), AccelMg::new(100, 1000, 0));
    // Back on the first good sample: Up, once.
    let back = p.feed(Read::Sample(AccelMg::new(0, 1000, 0)));
    assert_eq!(back.transition, Some(Transition::Up));
    assert_eq!(back.action, Action::Use(AccelMg::LEVEL));
    assert_eq!(p.feed(Read::Sample(AccelMg::LEVEL)).transition, None);
    // And down again later, with the new fault.
    let again = bring_down(&mut p, Fault::NoData, Ok(()));
    let transitions: Vec<_> = again.iter().filter_map(|s| s.transition).collect();
    assert_eq!(transitions, vec![Transition::Down(Fault::NoData)]);
}

#[test]
fn pipeline_down_from_missing_data_is_no_data() {
    let mut p = TiltPipeline::new(AxisMap::IDENTITY, CFG);
    let mut down = None;
    for _ in 0..100 {
        let step = p.feed(Read::NotReady);
        if step.action == Action::Reinit {
            p.reinit_done(Ok(()));
        }
        if let Some(t) = step.transition {
            down = Some(t);
            break;
        }
    }
    assert_eq!(down, Some(Transition::Down(Fault::NoData)));
}

#[test]
fn transitions_are_the_games_events() {
    assert_eq!(
        Transition::Down(Fault::Timeout).event(),
        InputEvent::SensorDown(Fault::Timeout)
    );
    assert_eq!(Transition::Up.event(), InputEvent::SensorUp);
}

#[test]
fn supervisor_never_panics_on_arbitrary_input() {
    // A cheap deterministic fuzz: xorshift-driven reads, faults and re-init
    // outcomes. Transitions alternate Down, Up, Down, … and match is_down.
    let mut p = TiltPipeline::new(AXIS_MAP, SUPERVISOR);
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut down = false;
    for _ in 0..200_000 {
        let r = next();
        let read = match r % 6 {
            0 => Read::Failed(Fault::Bus),
            1 => Read::Failed(Fault::Timeout),
            2 => Read::NotReady,
            3 => Read::Failed(Fault::Implausible),
            _ => Read::Sample(AccelMg::new(
                (next() as i32) >> (r % 31),
                (next() as i32) >> (r % 29),
                (next() as i32) >> (r % 23),
            )),
        };
        let step = p.feed(read);
        match step.action {
            Action::Reinit => p.reinit_done(if r & 8 == 0 { Ok(()) } else { Err(Fault::Bus) }),
            Action::Use(s) | Action::KeepLast(s) => {
                assert_eq!(s, p.tilt());
                assert!(Plausibility::DEFAULT.check(s) || s == AccelMg::LEVEL);
            }
            Action::ShowFault => assert!(p.is_down()),
        }
        match step.transition {
            Some(Transition::Down(_)) => {
                assert!(!down);
                down = true;
            }
            Some(Transition::Up) => {
                assert!(down);
                down = false;
            }
            None => {}
        }
        assert_eq!(down, p.is_down());
    }
}
