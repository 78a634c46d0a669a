//! The micro:bit watchdog's rule (`board::microbit::{Heartbeats, WatchdogGate}`):
//! the watchdog is petted only when every task has beaten since the last pet,
//! so one stalled task stops the pets and the board resets.
//!
//! The resets themselves happen on hardware only; here the decision is
//! checked, with the tasks' rates and the watchdog's timing as the firmware
//! has them.

use std::sync::Arc;
use std::thread;

use marble_rolling::board::microbit::{
    Heartbeats, Task, Tasks, Verdict, WatchdogGate, INPUT_PERIOD_MS, RTC_HZ, WATCHDOG_CHECK_MS,
    WATCHDOG_TIMEOUT_TICKS,
};
use marble_rolling::player::FRAME_HZ;

fn beat_all(h: &Heartbeats) {
    for task in Task::ALL {
        h.beat(task);
    }
}

#[test]
fn no_pet_before_every_task_beat() {
    let h = Heartbeats::new();
    let mut gate = WatchdogGate::new(h.snapshot());
    match gate.check(h.snapshot()) {
        Verdict::Wait { stalled, checks } => {
            assert_eq!(checks, 1);
            for task in Task::ALL {
                assert!(stalled.contains(task));
            }
        }
        Verdict::Pet => panic!("petted with no heartbeat at all"),
    }
    h.beat(Task::Input);
    h.beat(Task::Display);
    h.beat(Task::Sound);
    h.beat(Task::Records);
    match gate.check(h.snapshot()) {
        Verdict::Wait { stalled, checks } => {
            assert_eq!(checks, 2);
            assert!(stalled.contains(Task::Game));
            for task in Task::ALL.into_iter().filter(|&t| t != Task::Game) {
                assert!(!stalled.contains(task), "{task:?}");
            }
        }
        Verdict::Pet => panic!("petted without the game"),
    }
    h.beat(Task::Game);
    assert_eq!(gate.check(h.snapshot()), Verdict::Pet);
}

#[test]
fn every_task_must_beat_again_after_each_pet() {
    let h = Heartbeats::new();
    let mut gate = WatchdogGate::new(h.snapshot());
    beat_all(&h);
    assert_eq!(gate.check(h.snapshot()), Verdict::Pet);
    // Beats from before the pet do not count for the next one.
    assert!(matches!(gate.check(h.snapshot()), Verdict::Wait { .. }));
    beat_all(&h);
    assert_eq!(gate.check(h.snapshot()), Verdict::Pet);
}

#[test]
fn one_stalled_task_stops_the_pets_for_good() {
    for stalled_task in Task::ALL {
        let h = Heartbeats::new();
        let mut gate = WatchdogGate::new(h.snapshot());
        beat_all(&h);
        assert_eq!(gate.check(h.snapshot()), Verdict::Pet);
        // The others keep running, many times per check.
        for check in 1..=1000u16 {
            for _ in 0..10 {
                for task in Task::ALL.into_iter().filter(|&t| t != stalled_task) {
                    h.beat(task);
                }
            }
            match gate.check(h.snapshot()) {
                Verdict::Wait { stalled, checks } => {
                    assert_eq!(checks, check);
                    assert!(stalled.contains(stalled_task));
                    for task in Task::ALL.into_iter().filter(|&t| t != stalled_task) {
                        assert!(!stalled.contains(task), "{task:?}");
                    }
                }
                Verdict::Pet => panic!("petted with {stalled_task:?} stalled"),
            }
        }
        // It comes back: pets resume.
        h.beat(stalled_task);
        assert_eq!(gate.check(h.snapshot()), Verdict::Pet);
    }
}

#[test]
fn a_slow_task_delays_the_pet_without_losing_it() {
    // Input busy re-initialising the sensor for a few checks: no pet meanwhile,
    // a pet as soon as it beats (it must beat within the watchdog period).
    let h = Heartbeats::new();
    let mut gate = WatchdogGate::new(h.snapshot());
    for _ in 0..3 {
        h.beat(Task::Game);
        h.beat(Task::Display);
        h.beat(Task::Sound);
        h.beat(Task::Records);
        assert!(matches!(gate.check(h.snapshot()), Verdict::Wait { .. }));
    }
    h.beat(Task::Input);
    assert_eq!(gate.check(h.snapshot()), Verdict::Pet);
}

#[test]
fn counters_wrapping_around_still_count() {
    let start = [u32::MAX, u32::MAX - 1, 7, u32::MAX, 0];
    let mut gate = WatchdogGate::new(start);
    assert_eq!(
        gate.check([0, u32::MAX, 8, 0, 1]),
        Verdict::Pet,
        "a wrapped counter moved"
    );
}

#[test]
fn beats_from_other_threads_are_seen() {
    // Each counter has a single writer (its task), as on the board, where
    // the display beats from an interrupt executor.
    let h = Arc::new(Heartbeats::new());
    let mut gate = WatchdogGate::new(h.snapshot());
    let workers: Vec<_> = Task::ALL
        .into_iter()
        .map(|task| {
            let h = Arc::clone(&h);
            thread::spawn(move || {
                for _ in 0..1000 {
                    h.beat(task);
                }
            })
        })
        .collect();
    for worker in workers {
        worker.join().expect("worker");
    }
    assert_eq!(h.snapshot().counts, [1000; Task::ALL.len()]);
    assert_eq!(gate.check(h.snapshot()), Verdict::Pet);
}

#[test]
fn the_timing_leaves_every_task_room() {
    // Several checks per watchdog period, so one late task does not reset
    // the board; every task beats many times per check.
    const PERIOD_MS: u64 = WATCHDOG_TIMEOUT_TICKS as u64 * 1000 / RTC_HZ as u64;
    const { assert!(PERIOD_MS == 1000) };
    const { assert!(WATCHDOG_CHECK_MS * 5 <= PERIOD_MS) };
    const { assert!(INPUT_PERIOD_MS * 5 <= WATCHDOG_CHECK_MS) };
    const { assert!(FRAME_HZ as u64 * WATCHDOG_CHECK_MS / 1000 >= 5) };
    assert!(Tasks::NONE.is_empty());
}

#[test]
fn the_sound_and_records_tasks_are_watched() {
    assert!(Task::ALL.contains(&Task::Sound));
    assert!(Task::ALL.contains(&Task::Records));
}

/// The other tasks beat; `task` does what `act` says, once per check.
fn checks_with(task: Task, act: impl Fn(&Heartbeats, u32)) -> Vec<Verdict> {
    let h = Heartbeats::new();
    let mut gate = WatchdogGate::new(h.snapshot());
    (0..20)
        .map(|check| {
            for other in Task::ALL.into_iter().filter(|&t| t != task) {
                h.beat(other);
            }
            act(&h, check);
            gate.check(h.snapshot())
        })
        .collect()
}

#[test]
fn a_task_waiting_for_work_is_excused() {
    for task in [Task::Sound, Task::Records] {
        // Waiting from the start (the queue empty for minutes): every check pets.
        let verdicts = checks_with(task, |h, check| {
            if check == 0 {
                h.waiting(task);
            }
        });
        assert!(verdicts.iter().all(|v| *v == Verdict::Pet), "{task:?}");
    }
}

#[test]
fn a_working_task_that_stops_beating_stops_the_pets() {
    for task in [Task::Sound, Task::Records] {
        // Waits, gets work at check 5 (a sound, a win), and hangs there (a
        // note's timer that never ends, a flash operation that never returns).
        let verdicts = checks_with(task, |h, check| match check {
            0 => h.waiting(task),
            5 => h.working(task),
            _ => {}
        });
        assert!(verdicts[..6].iter().all(|v| *v == Verdict::Pet), "{task:?}");
        for (n, verdict) in verdicts[6..].iter().enumerate() {
            match verdict {
                Verdict::Wait { stalled, checks } => {
                    assert_eq!(*checks as usize, n + 1, "{task:?}");
                    assert!(stalled.contains(task), "{task:?}");
                }
                Verdict::Pet => panic!("{task:?} hung at work and the watchdog was petted"),
            }
        }
    }
}

#[test]
fn a_working_task_that_beats_and_then_waits_keeps_the_pets() {
    for task in [Task::Sound, Task::Records] {
        // Work from check 3 to 8 (a beat per note or flash operation), then
        // waiting again.
        let verdicts = checks_with(task, |h, check| match check {
            0 | 9 => h.waiting(task),
            3 => h.working(task),
            4..=8 => h.beat(task),
            _ => {}
        });
        assert!(
            verdicts.iter().all(|v| *v == Verdict::Pet),
            "{task:?}: {verdicts:?}"
        );
    }
}

#[test]
fn waiting_is_not_an_excuse_for_the_other_tasks() {
    // A task that never said it waits is held to the rule even while another
    // waits.
    let h = Heartbeats::new();
    let mut gate = WatchdogGate::new(h.snapshot());
    h.waiting(Task::Sound);
    h.waiting(Task::Records);
    h.beat(Task::Input);
    h.beat(Task::Display);
    match gate.check(h.snapshot()) {
        Verdict::Wait { stalled, .. } => {
            assert!(stalled.contains(Task::Game));
            assert!(!stalled.contains(Task::Sound));
            assert!(!stalled.contains(Task::Records));
        }
        Verdict::Pet => panic!("petted without the game"),
    }
}
