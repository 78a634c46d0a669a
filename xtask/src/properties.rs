//! The full property run: 10⁶ simulated shots across tests/properties.rs at
//! release speed with overflow checks on (profile `soak`); plain `cargo test`
//! runs a few hundred. One case of each property simulates 1–6 runs (backends ×
//! repeats) with each of the two steppers (fixed, events): 42 runs per case
//! across the suite, so 24 000 cases are 10⁶ shots.

use crate::error::{say, Outcome};
use crate::process;
use crate::workspace;

/// `cargo xtask properties [CASES]`.
pub fn run(cases: u64) -> Outcome {
    say!("PROPTEST_CASES={cases} (×42 simulated shots)");
    let mut cmd = workspace::cargo();
    cmd.env("PROPTEST_CASES", cases.to_string())
        .args([
            "test",
            "-p",
            "marble-rolling",
            "--profile",
            "soak",
            "--test",
            "properties",
        ])
        .args(["--", "--test-threads", "2"]);
    Ok(process::code(process::status(&mut cmd)?))
}
