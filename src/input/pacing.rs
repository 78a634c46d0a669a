//! Poll pacing: a poll that comes late starts the period over.
//!
//! embassy's `Ticker` fires every missed period back to back once its task runs
//! again. After a stall — the input task's own slow work (a re-init, a timed-out
//! transfer), or another task holding the CPU (the records task: an nRF52 flash
//! page erase stalls the CPU for some 85 ms; on QEMU, sequential-storage
//! scanning a region of garbage) — that is a burst of polls of a sensor with no
//! new sample yet, and enough "not ready" in a row is what the supervisor calls
//! a sensor that stopped (`Fault::NoData`): a false re-init (ten in one QEMU
//! demo that recovered a garbage records region). So a board notes when it last
//! polled and, when a tick comes [`late`], polls once and resets its ticker.

/// Whether a poll at `now_us` (µs, any clock), the previous one at `last_us`,
/// comes after a stall: half a period or more later than the period.
pub const fn late(last_us: u64, now_us: u64, period_us: u64) -> bool {
    now_us.saturating_sub(last_us) >= period_us + period_us / 2
}

#[cfg(test)]
mod tests {
    use super::late;

    #[test]
    fn on_time_and_jittery_polls_are_not_late() {
        assert!(!late(0, 10_000, 10_000));
        assert!(!late(10_000, 24_999, 10_000));
        // A clock that went backwards (or the first poll) is no stall.
        assert!(!late(50_000, 40_000, 10_000));
    }

    #[test]
    fn a_stall_of_half_a_period_or_more_is_late() {
        assert!(late(0, 15_000, 10_000));
        assert!(late(10_000, 95_000, 10_000));
    }
}
