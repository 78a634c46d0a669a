#!/usr/bin/env bash
# The full property run: 10⁶ simulated shots across tests/properties.rs, in release
# speed with overflow checks on (profile `soak`). `cargo test` runs a few hundred.
#
#   bash tools/properties.sh [CASES]      (default 48000 cases per property)
#
# One case of each property simulates 1–6 runs (backends × repeats): 21 runs per
# case across the suite, so 48 000 cases are 10⁶ shots.
set -euo pipefail
cd "$(dirname "$0")/.."
cases=${1:-48000}
echo "properties: PROPTEST_CASES=$cases (×21 simulated shots)"
PROPTEST_CASES=$cases cargo test --profile soak --test properties -- --test-threads 2
