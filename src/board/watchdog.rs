//! The watchdog's rule, for every board that runs the app's tasks: every task
//! proves it runs.
//!
//! A watchdog petted by one loop only proves that loop runs; a task parked
//! forever at an `await` (a display waiting on a dead timer, a game never
//! woken) would go unnoticed. So each task that must run bumps its own
//! counter in [`Heartbeats`], and the watchdog task pets only when
//! [`WatchdogGate`] has seen every counter move since the last pet. The
//! watchdog task itself runs in thread mode, so its pets also prove the
//! thread executor is not hogged.
//!
//! Some tasks wait for work that may not come for minutes (the sound task for
//! a sound, the records task for a win): a silent counter there is not a stall.
//! Such a task says when it waits ([`Heartbeats::waiting`]) and when it works
//! ([`Heartbeats::working`]); the gate excuses a waiting task and holds a
//! working one to the same rule as the others, so a sound whose timer never
//! ends, or a flash operation that never returns, stops the pets.

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

/// How often the watchdog task checks the heartbeats (and pets when all
/// moved), ms. Ten checks per watchdog period: a task may be late for nine
/// of them (a sensor re-init takes ~50 ms) before the board resets.
pub const WATCHDOG_CHECK_MS: u64 = 100;

/// A task the watchdog waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Task {
    /// Accelerometer and buttons (thread mode): beats once per poll.
    Input,
    /// The game (thread mode): beats each time it is polled — it awaits
    /// nothing but its frame ticker, so it is polled at the frame rate
    /// whether it plays, pauses for a downed sensor or shows a won level.
    Game,
    /// The LED matrix (interrupt executor): beats on every scan step.
    Display,
    /// The speaker (thread mode): waiting between sounds, beats at each note.
    Sound,
    /// The best times (thread mode): waiting between wins, beats at each
    /// flash operation.
    Records,
}

impl Task {
    /// Every task the watchdog waits for.
    pub const ALL: [Task; 5] = [
        Task::Input,
        Task::Game,
        Task::Display,
        Task::Sound,
        Task::Records,
    ];

    const fn index(self) -> usize {
        self as usize
    }
}

/// A set of [`Task`]s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tasks(u8);

impl Tasks {
    /// No task.
    pub const NONE: Tasks = Tasks(0);

    /// Whether `task` is in the set.
    pub const fn contains(self, task: Task) -> bool {
        self.0 & (1 << task.index()) != 0
    }

    /// Whether the set is empty.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    const fn with(self, task: Task) -> Tasks {
        Tasks(self.0 | (1 << task.index()))
    }
}

/// One counter per [`Task`], and whether it waits for work, shared between
/// executors (a `static`).
///
/// Each counter has a single writer, its task, so a load and a store suffice
/// (no read-modify-write atomics: this builds for Cortex-M0 too). Only a
/// change matters, not the count.
#[derive(Debug, Default)]
pub struct Heartbeats {
    counts: [AtomicU32; Task::ALL.len()],
    waiting: [AtomicBool; Task::ALL.len()],
}

/// What the watchdog task reads of [`Heartbeats`] at one check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Snapshot {
    /// The counters, indexed like [`Task::ALL`].
    pub counts: [u32; Task::ALL.len()],
    /// The tasks waiting for work.
    pub waiting: Tasks,
}

impl From<[u32; Task::ALL.len()]> for Snapshot {
    /// Counters only, no task waiting.
    fn from(counts: [u32; Task::ALL.len()]) -> Self {
        Snapshot {
            counts,
            waiting: Tasks::NONE,
        }
    }
}

impl Heartbeats {
    /// No beat yet, no task waiting.
    pub const fn new() -> Self {
        Self {
            counts: [const { AtomicU32::new(0) }; Task::ALL.len()],
            waiting: [const { AtomicBool::new(false) }; Task::ALL.len()],
        }
    }

    /// `task` ran. Call it only from `task` itself.
    pub fn beat(&self, task: Task) {
        let count = &self.counts[task.index()];
        count.store(
            count.load(Ordering::Relaxed).wrapping_add(1),
            Ordering::Relaxed,
        );
    }

    /// `task` waits for work (its queue is empty): excused until
    /// [`Heartbeats::working`]. Call it only from `task` itself.
    pub fn waiting(&self, task: Task) {
        self.waiting[task.index()].store(true, Ordering::Relaxed);
    }

    /// `task` has work: it beats, and must go on beating until it waits again.
    pub fn working(&self, task: Task) {
        self.waiting[task.index()].store(false, Ordering::Relaxed);
        self.beat(task);
    }

    /// The counters and the waiting tasks now.
    pub fn snapshot(&self) -> Snapshot {
        let mut waiting = Tasks::NONE;
        for task in Task::ALL {
            if self.waiting[task.index()].load(Ordering::Relaxed) {
                waiting = waiting.with(task);
            }
        }
        Snapshot {
            counts: core::array::from_fn(|i| self.counts[i].load(Ordering::Relaxed)),
            waiting,
        }
    }
}

/// What the watchdog task does after a check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verdict {
    /// Every task beat since the last pet: pet now.
    Pet,
    /// Do not pet: these tasks have not beaten since the last pet, for this
    /// many checks in a row (≥ 1).
    Wait {
        /// The tasks still to beat.
        stalled: Tasks,
        /// Checks without a pet.
        checks: u16,
    },
}

/// The watchdog task's rule: pet only when every task's counter moved since
/// the last pet, or the task waits for work. A working task parked forever
/// stops its counter, the pets stop, and the watchdog resets the board.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WatchdogGate {
    at_last_pet: [u32; Task::ALL.len()],
    checks_since_pet: u16,
}

impl WatchdogGate {
    /// Starts from the counters now (every task must beat, or wait, before
    /// the first pet).
    pub fn new(start: impl Into<Snapshot>) -> Self {
        Self {
            at_last_pet: start.into().counts,
            checks_since_pet: 0,
        }
    }

    /// One check with the heartbeats `now` ([`Heartbeats::snapshot`]).
    pub fn check(&mut self, now: impl Into<Snapshot>) -> Verdict {
        let now = now.into();
        let mut stalled = Tasks::NONE;
        for task in Task::ALL {
            if now.counts[task.index()] == self.at_last_pet[task.index()]
                && !now.waiting.contains(task)
            {
                stalled = stalled.with(task);
            }
        }
        if stalled.is_empty() {
            self.at_last_pet = now.counts;
            self.checks_since_pet = 0;
            Verdict::Pet
        } else {
            self.checks_since_pet = self.checks_since_pet.saturating_add(1);
            Verdict::Wait {
                stalled,
                checks: self.checks_since_pet,
            }
        }
    }
}
