//! What the tasks know about each board, in one place: the firmware crates
//! that run on it, how it runs (a QEMU machine, a probe-rs chip, both), how
//! its log is read and what it is held to. The runners ([`crate::runner`],
//! [`crate::game::play`]), the demo checks, the profile, the size report and
//! the .hex files take a [`Board`] or a [`Firmware`] instead of naming
//! crates, targets and machines themselves: a new board is a constant here,
//! its firmware crate, and a task in main.rs that hands the constant to
//! those (docs/boards.md, "Adding a board").

use std::path::PathBuf;

use marble_rolling::board::levels_region;

use crate::error::Failure;
use crate::firmware::{self, Artifact};
use crate::hex;
use crate::setup;
use crate::workspace;

/// Cortex-M4F: QEMU mps2-an386 and the micro:bit v2.
pub const M4: &str = "thumbv7em-none-eabihf";
/// Cortex-M0: the micro:bit v1 (nRF51822), in QEMU's `microbit` machine too.
pub const M0: &str = "thumbv6m-none-eabi";

/// How a firmware's log leaves the chip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Log {
    /// defmt frames: through semihosting (QEMU's stdout), decoded here by
    /// defmt-print; over RTT on a board, decoded by probe-rs.
    Defmt,
    /// Text on semihosting's console (SYS_WRITE0, which QEMU writes to its
    /// stderr): the Cortex-M0 benchmark, which the study parses.
    Console,
}

/// A firmware binary: the crate it is in, the target it is built for.
#[derive(Debug)]
pub struct Firmware {
    pub package: &'static str,
    pub bin: &'static str,
    pub target: &'static str,
    pub log: Log,
    /// Seconds a headless run may take before it is killed (QEMU_TIMEOUT
    /// overrides): a hung firmware (a CPU lockup) never exits.
    pub timeout: u64,
    /// The cargo feature a `--profile` run needs, if the image for a board
    /// leaves the profile's code out (the micro:bit v1's flash).
    pub profile: Option<&'static str>,
}

impl Firmware {
    /// `bin` of `package` for `target`, its log defmt, its limit 600 s.
    const fn new(package: &'static str, bin: &'static str, target: &'static str) -> Firmware {
        Firmware {
            package,
            bin,
            target,
            log: Log::Defmt,
            timeout: 600,
            profile: None,
        }
    }

    /// Installs what building it needs (its target's standard library, and
    /// flip-link, its linker in .cargo/config.toml) and builds it, release.
    pub fn build(&self) -> Result<PathBuf, Failure> {
        self.build_with(None)
    }

    /// [`Firmware::build`] with cargo `features`.
    fn build_with(&self, features: Option<&str>) -> Result<PathBuf, Failure> {
        setup::target(self.target)?;
        setup::flip_link()?;
        firmware::build(&Artifact {
            features,
            ..Artifact::firmware(self.package, self.bin, self.target)
        })
    }

    /// Builds it for a `--profile` run: with its [`Firmware::profile`]
    /// feature, copied to `<bin>-profile` beside the plain build (the two share
    /// cargo's output path, and the checks use both). Without such a feature,
    /// the plain build.
    pub fn build_profiled(&self) -> Result<PathBuf, Failure> {
        let Some(feature) = self.profile else {
            return self.build();
        };
        let elf = self.build_with(Some(feature))?;
        let copy = elf.with_file_name(format!("{}-profile", self.bin));
        std::fs::copy(&elf, &copy).map_err(|e| {
            Failure::new(format!(
                "cannot copy {} to {}: {e}",
                elf.display(),
                copy.display()
            ))
        })?;
        Ok(copy)
    }

    /// Where cargo puts it (for `--no-build`).
    pub fn built(&self) -> Result<PathBuf, Failure> {
        Ok(workspace::target_dir()?
            .join(self.target)
            .join("release")
            .join(self.bin))
    }

    /// The tools a headless QEMU run of it needs (defmt-print only for a
    /// defmt log), installed on first use.
    pub fn qemu_tools(&self) -> Result<setup::Qemu, Failure> {
        setup::target(self.target)?;
        setup::qemu_tools(self.log == Log::Defmt)
    }
}

/// The QEMU machine a board is, or stands in for.
#[derive(Debug)]
pub struct Machine {
    /// `-machine`, also in messages ("QEMU mps2-an386").
    pub name: &'static str,
    /// `-cpu`, where the machine's default is not the firmware's core.
    pub cpu: Option<&'static str>,
    /// Its firmware reads how it was started (`--headless`,
    /// `--interactive`, `--race`) first on its semihosting command line.
    pub modes: bool,
    /// What a headless run adds: a UART the game would otherwise write to
    /// discarded.
    pub headless: &'static [&'static str],
    /// It can be played on the terminal (its UART0 there).
    pub interactive: bool,
}

/// A budget: a figure from the environment (`var`), else `default`.
#[derive(Debug)]
pub struct Budget {
    pub var: &'static str,
    pub default: u64,
}

impl Budget {
    pub fn get(&self) -> Result<u64, Failure> {
        workspace::env_number(self.var, self.default)
    }
}

/// `var`'s figure, else `default`.
const fn budget(var: &'static str, default: u64) -> Option<Budget> {
    Some(Budget { var, default })
}

/// What a board's firmware is held to (what is not measured there is `None`).
#[derive(Debug)]
pub struct Budgets {
    /// Flash (text + data), bytes.
    pub flash: Option<Budget>,
    /// RAM (statics, plus the stack high-water where the demo measures it), bytes.
    pub ram: Option<Budget>,
    /// The demo's CPU load, hundredths of a percent.
    pub cpu: Option<Budget>,
    /// The worst physics frame of a level, the core's instructions.
    pub frame: Option<Budget>,
}

/// Where a board's image goes in the micro:bit universal hex.
#[derive(Debug)]
pub struct HexSection {
    /// `v1`, `v2`: in file names and messages.
    pub name: &'static str,
    /// Its block type in the universal hex.
    pub block: u16,
    /// Where its levels region starts.
    pub region: u32,
}

/// A board: its game firmware and how it is run and checked.
#[derive(Debug)]
pub struct Board {
    /// In messages ("micro:bit v1").
    pub name: &'static str,
    /// The game.
    pub game: Firmware,
    /// The QEMU machine it runs in, if any.
    pub qemu: Option<Machine>,
    /// probe-rs's name for its chip, if it is real hardware.
    pub chip: Option<&'static str>,
    /// Its core, in the figures' messages ("M4", "M0").
    pub core: &'static str,
    /// The name of its demo's rows in the simulator comparison.
    pub tag: &'static str,
    pub budgets: Budgets,
    /// Its section in the universal hex (the micro:bits).
    pub hex: Option<HexSection>,
    /// Its firmware for racing another board of its kind in QEMU, if any
    /// (`--race`).
    pub race: Option<Firmware>,
    /// The study's benchmark for its core, run in its QEMU machine, if any.
    pub bench: Option<Firmware>,
}

impl Board {
    /// Its QEMU machine, or why it has none.
    pub fn machine(&self) -> Result<&Machine, Failure> {
        self.qemu
            .as_ref()
            .ok_or_else(|| Failure::new(format!("the {} has no QEMU machine", self.name)).status(2))
    }

    /// One of its budgets (`self.budgets.…`), from the environment or its
    /// default; a check asking for one the board lacks is this table's
    /// mistake.
    pub fn budget(&self, budget: &Option<Budget>) -> Result<u64, Failure> {
        match budget {
            Some(budget) => budget.get(),
            None => Err(Failure::new(format!(
                "the {} has no such budget in xtask/src/boards.rs",
                self.name
            ))),
        }
    }
}

const MPS2: Machine = Machine {
    name: "mps2-an386",
    cpu: Some("cortex-m4"),
    modes: true,
    headless: &["-serial", "null"],
    interactive: true,
};

const NRF51: Machine = Machine {
    name: "microbit",
    cpu: None,
    modes: false,
    headless: &[],
    interactive: false,
};

const NONE: Budgets = Budgets {
    flash: None,
    ram: None,
    cpu: None,
    frame: None,
};

/// QEMU mps2-an386 (`boards/qemu`): `cargo qemu`, `cargo xtask check-demo`.
pub const QEMU: Board = Board {
    name: "QEMU mps2-an386",
    game: Firmware::new("marble-qemu", "qemu", M4),
    qemu: Some(MPS2),
    chip: None,
    core: "M4",
    tag: "qemu",
    budgets: Budgets {
        // 3.00 % of a 64 MHz Cortex-M4.
        cpu: budget("CPU_BUDGET_CENTIPERCENT", 300),
        frame: budget("WORST_FRAME_M4", 64_000),
        ..NONE
    },
    hex: None,
    // boards/qemu-race: one of two boards whose UART1s the task joins.
    race: Some(Firmware {
        timeout: 300,
        ..Firmware::new("marble-qemu-race", "qemu-race", M4)
    }),
    // The study's Cortex-M4F benchmark (`cargo xtask bench-m4`).
    bench: Some(Firmware::new("marble-qemu", "bench", M4)),
};

/// The micro:bit v2 (`boards/microbit`, nRF52833): `cargo microbit`,
/// `cargo xtask size-report`.
pub const MICROBIT: Board = Board {
    name: "micro:bit v2",
    game: Firmware::new("marble-microbit", "microbit", M4),
    qemu: None,
    chip: Some("nRF52833_xxAA"),
    core: "M4",
    tag: "v2",
    budgets: Budgets {
        // Of the nRF52833's 512 KiB (144 KiB since issue 40's resting pairs:
        // 128 KiB before, the race and the ghost had taken it to 128 892 B).
        flash: budget("FLASH_BUDGET", 144 * 1024),
        ram: budget("RAM_BUDGET", 16 * 1024),
        ..NONE
    },
    hex: Some(HexSection {
        name: "v2",
        block: hex::BOARD_V2,
        region: levels_region::V2.start,
    }),
    race: None,
    bench: None,
};

/// The micro:bit v1 (`boards/microbit-v1`, nRF51822), in QEMU's `microbit`
/// machine too: `cargo microbit-v1`, `cargo xtask check-microbit-v1`.
pub const MICROBIT_V1: Board = Board {
    name: "micro:bit v1",
    game: Firmware {
        profile: Some("profile"),
        ..Firmware::new("marble-microbit-v1", "microbit-v1", M0)
    },
    qemu: Some(NRF51),
    chip: Some("nRF51822_xxAA"),
    core: "M0",
    tag: "v1",
    budgets: Budgets {
        // Of the nRF51822's 256 KiB, the levels region (its last 4 KiB) apart
        // (144 KiB since issue 40's resting pairs: 128 KiB before, 1 084 B left).
        flash: budget("V1_FLASH_BUDGET", 144 * 1024),
        // Statics + stack high-water, of 16 KiB.
        ram: budget("V1_RAM_BUDGET", 12 * 1024),
        // 20 % of 16 MHz.
        cpu: budget("V1_CPU_BUDGET_CENTIPERCENT", 2000),
        // A level's, top-difficulty maze's or stress scene's worst frame
        // over it fails the check (issue 40).
        frame: budget("WORST_FRAME_M0", 60_000),
    },
    hex: Some(HexSection {
        name: "v1",
        block: hex::BOARD_V1,
        region: levels_region::V1.start,
    }),
    race: None,
    // The study's Cortex-M0 benchmark (`cargo xtask bench-m0`, study/bench-m0):
    // under -icount the nRF51's TIMER0 counts instructions; it prints on
    // semihosting's console, which the study parses.
    bench: Some(Firmware {
        log: Log::Console,
        timeout: 900,
        ..Firmware::new("marble-bench-m0", "bench_m0", M0)
    }),
};

/// Every board, in `cargo xtask setup`'s order (its targets installed so).
pub const ALL: [&Board; 3] = [&QEMU, &MICROBIT, &MICROBIT_V1];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_board_runs_somewhere_and_its_firmware_is_its_own() {
        let boards = ALL;
        for board in boards {
            assert!(
                board.qemu.is_some() || board.chip.is_some(),
                "{} runs nowhere",
                board.name
            );
            assert_eq!(board.machine().is_ok(), board.qemu.is_some());
            assert_eq!(board.game.log, Log::Defmt, "the demo checks decode defmt");
            assert!(
                board.qemu.is_some() || (board.race.is_none() && board.bench.is_none()),
                "{}: a race or a benchmark runs in QEMU",
                board.name
            );
        }
        let mut packages: Vec<(&str, &str)> = boards
            .iter()
            .flat_map(|b| [Some(&b.game), b.race.as_ref(), b.bench.as_ref()])
            .flatten()
            .map(|f| (f.package, f.bin))
            .collect();
        packages.sort_unstable();
        packages.dedup();
        assert_eq!(packages.len(), 6, "two firmwares with one binary");
        let sections: Vec<u16> = boards
            .iter()
            .filter_map(|b| b.hex.as_ref().map(|h| h.block))
            .collect();
        assert_eq!(sections, [hex::BOARD_V2, hex::BOARD_V1]);
    }

    /// A firmware's profile feature is one its crate declares (else `cargo
    /// build --features` fails only when a check runs), and a firmware without
    /// one keeps the profile in every image.
    #[test]
    fn a_profile_feature_is_declared_by_its_crate() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        for board in ALL {
            let Some(feature) = board.game.profile else {
                continue;
            };
            let folder = match board.game.package {
                "marble-microbit-v1" => "microbit-v1",
                other => panic!("{other}: which folder under boards/?"),
            };
            let manifest =
                std::fs::read_to_string(root.join("boards").join(folder).join("Cargo.toml"))
                    .expect("the board's manifest");
            let features = manifest
                .split("[features]")
                .nth(1)
                .expect("a [features] table")
                .split("\n[")
                .next()
                .unwrap_or_default();
            assert!(
                features
                    .lines()
                    .any(|l| l.trim_start().starts_with(&format!("{feature} ="))),
                "{}: no `{feature}` feature in boards/{folder}/Cargo.toml",
                board.name
            );
        }
        assert_eq!(MICROBIT_V1.game.profile, Some("profile"));
        assert_eq!(QEMU.game.profile, None, "QEMU's image keeps its profile");
    }

    #[test]
    fn budgets_come_from_the_environment_else_their_default() {
        let budget = Budget {
            var: "XTASK_TEST_BUDGET_UNSET",
            default: 42,
        };
        assert_eq!(budget.get().expect("the default"), 42);
        assert_eq!(
            MICROBIT_V1.budgets.ram.as_ref().map(|b| b.default),
            Some(12 * 1024)
        );
        assert!(QEMU.budgets.flash.is_none() && MICROBIT.budgets.cpu.is_none());
    }
}
