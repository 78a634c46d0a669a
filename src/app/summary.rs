//! What a board's demo summary says, derived once from [`GameExit`] and
//! [`DemoSummary`]: each board only prints it (the xtask greps those lines,
//! so the words stay the boards').

use super::mode::{DemoSummary, GameExit};
use crate::physics::world::SetupError;

impl GameExit {
    /// The totals a demo summary reports: the demo's own when it played every
    /// level, zeros when the game returned otherwise (the player quit, or the
    /// toy fell asleep), and the error when no level could be set up (the
    /// board logs it and exits 1).
    pub const fn demo_summary(self) -> Result<DemoSummary, SetupError> {
        match self {
            GameExit::DemoDone(summary) => Ok(summary),
            GameExit::SetupFailed(e) => Err(e),
            GameExit::Quit => Ok(DemoSummary::ZERO),
            #[cfg(feature = "sleep")]
            GameExit::Asleep { .. } => Ok(DemoSummary::ZERO),
        }
    }
}

/// A demo's verdict: the word its summary line ends with and the exit code.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct Verdict {
    /// The demo passed.
    pub(crate) pass: bool,
}

impl Verdict {
    /// `"PASS"` or `"FAIL"`, as the summary line ends.
    pub const fn as_str(self) -> &'static str {
        if self.pass {
            "PASS"
        } else {
            "FAIL"
        }
    }

    /// The exit code the board hands QEMU: 0 on a pass, 1 on a fail.
    pub const fn exit_code(self) -> i32 {
        if self.pass {
            0
        } else {
            1
        }
    }
}

/// The sensor's totals over a demo, as a summary reports them.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct SensorTotals {
    /// Re-initialisations after the first configuration.
    pub reinits: u32,
    /// Faults (failed or implausible reads).
    pub faults: u32,
}

impl SensorTotals {
    /// From the count of every configuration (the first one is not a
    /// re-init) and of faults.
    pub const fn from_configurations(configurations: u32, faults: u32) -> Self {
        Self {
            reinits: configurations.saturating_sub(1),
            faults,
        }
    }

    /// No re-init and no fault: what a fault-free demo shows (a long frame
    /// that starves the input task would show here).
    pub(crate) const fn clean(&self) -> bool {
        self.reinits == 0 && self.faults == 0
    }
}

impl DemoSummary {
    /// Zero totals: what a summary reports when the demo did not run to its
    /// end.
    pub(crate) const ZERO: Self = Self {
        levels: 0,
        won: 0,
        steps: 0,
        frames: 0,
    };

    /// Passed when every level played was won (`Self::all_won`).
    pub const fn verdict(&self) -> Verdict {
        Verdict {
            pass: self.all_won(),
        }
    }

    /// Passed when every level was won and the sensor stayed clean
    /// (`SensorTotals::clean`): the verdict of a demo that reads a sensor
    /// and fails on its faults.
    pub const fn verdict_with_sensor(&self, sensor: SensorTotals) -> Verdict {
        Verdict {
            pass: self.all_won() && sensor.clean(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WON: DemoSummary = DemoSummary {
        levels: 3,
        won: 3,
        steps: 100,
        frames: 50,
    };

    #[test]
    fn exits_give_the_totals_or_zeros_or_the_error() {
        assert_eq!(GameExit::DemoDone(WON).demo_summary(), Ok(WON));
        assert_eq!(GameExit::Quit.demo_summary(), Ok(DemoSummary::default()));
        #[cfg(feature = "sleep")]
        assert_eq!(
            GameExit::Asleep { level: 2 }.demo_summary(),
            Ok(DemoSummary::default())
        );
        let e = GameExit::SetupFailed(SetupError::MarbleSize);
        assert_eq!(e.demo_summary(), Err(SetupError::MarbleSize));
    }

    #[test]
    fn verdict_words_and_exit_codes() {
        assert_eq!(WON.verdict(), Verdict { pass: true });
        assert_eq!(
            (WON.verdict().as_str(), WON.verdict().exit_code()),
            ("PASS", 0)
        );
        let lost = DemoSummary { won: 2, ..WON };
        assert_eq!(
            (lost.verdict().as_str(), lost.verdict().exit_code()),
            ("FAIL", 1)
        );
        // No level played is no pass.
        assert!(!DemoSummary::ZERO.verdict().pass);
    }

    #[test]
    fn the_first_configuration_is_not_a_reinit() {
        let first_only = SensorTotals::from_configurations(1, 0);
        assert_eq!(
            first_only,
            SensorTotals {
                reinits: 0,
                faults: 0
            }
        );
        assert!(WON.verdict_with_sensor(first_only).pass);
        assert_eq!(SensorTotals::from_configurations(0, 0).reinits, 0);
        assert!(
            !WON.verdict_with_sensor(SensorTotals::from_configurations(2, 0))
                .pass
        );
        assert!(
            !WON.verdict_with_sensor(SensorTotals::from_configurations(1, 1))
                .pass
        );
        let lost = DemoSummary { won: 0, ..WON };
        assert!(!lost.verdict_with_sensor(first_only).pass);
    }
}
