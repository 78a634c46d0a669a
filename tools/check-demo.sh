#!/usr/bin/env bash
# End-to-end check that the firmware plays exactly like the host simulator:
#
#   bash tools/check-demo.sh
#
# 1. Runs the QEMU firmware's headless demo (`cargo qemu -- --demo`): the
#    autopilot plays every built-in level and the firmware logs, per level,
#      demo <n>/<total> level=<name> outcome=<won|fell|timeout> steps=<physics steps> state_hash=<16 hex>
# 2. Runs the host simulator on each of those levels
#    (`cargo sim -- --level <name> --autopilot --json`; its JSON has
#    `outcome`, `steps` and `state_hash`).
# 3. Prints a table and fails (exit 1) if QEMU failed, a level was not won, or
#    the outcome, step count or state hash of any level differ.
# 4. Fails if the demo's CPU load is over 3.00 % of a 64 MHz Cortex-M4
#    (CPU_BUDGET_CENTIPERCENT, default 300).
#
# Works on a fresh machine: the QEMU runner (tools/qemu-run.sh) installs
# qemu-system-arm and defmt-print when missing, the linker wrapper
# (tools/flip-link.sh) installs flip-link. Needs the thumbv7em-none-eabihf
# target (rust-toolchain.toml). The QEMU log is kept in
# target/check-demo-qemu.log (or $CHECK_DEMO_LOG).
set -uo pipefail

cd "$(dirname "$0")/.." || exit 2
log=${CHECK_DEMO_LOG:-target/check-demo-qemu.log}
mkdir -p "$(dirname "$log")"

fail=0
problem() {
    echo "check-demo: $*" >&2
    fail=1
}

echo "check-demo: running the QEMU demo (cargo qemu -- --demo) ..." >&2
cargo qemu -- --demo </dev/null >"$log" 2>&1
qemu_status=$?
# Strip colours, should defmt-print or cargo add any.
sed -i 's/\x1b\[[0-9;]*m//g' "$log"
if ((qemu_status != 0)); then
    problem "the QEMU demo exited with status $qemu_status (log: $log); its last lines:"
    tail -n 15 "$log" >&2
fi

# name outcome steps hash, one level per line, in playing order.
mapfile -t rows < <(sed -n \
    's/.*demo [0-9]*\/[0-9]* level=\([^ ]*\) outcome=\([^ ]*\) steps=\([0-9]*\) state_hash=\([0-9a-fA-F]*\).*/\1 \2 \3 \4/p' \
    "$log")
total=$(sed -n 's/.*demo [0-9]*\/\([0-9]*\) level=.*/\1/p' "$log" | head -n 1)
if ((${#rows[@]} == 0)); then
    problem "no per-level lines in the QEMU log ($log)"
    exit 1
fi
if [[ -n $total && ${#rows[@]} -ne $total ]]; then
    problem "the QEMU demo reported ${#rows[@]} of $total levels"
fi

echo "check-demo: building the host simulator (cargo sim) ..." >&2
if ! cargo build --quiet --release --features tools --bin sim >&2; then
    problem "cannot build the host simulator (src/bin/sim.rs, feature tools)"
    exit 1
fi

# One JSON field: a string's contents or a number.
field() { # <json> <name>
    sed -n "s/.*\"$2\"[[:space:]]*:[[:space:]]*\"\{0,1\}\([^\",}]*\).*/\1/p" <<<"$1" | head -n 1
}

fmt='%-16s %-8s %-8s %8s %8s %-16s %-16s %s\n'
printf "$fmt" level qemu sim "q.steps" "s.steps" "qemu hash" "sim hash" result
for row in "${rows[@]}"; do
    read -r name q_outcome q_steps q_hash <<<"$row"
    json=$(cargo --quiet sim -- --level "$name" --autopilot --json 2>/dev/null | grep '^{' | tail -n 1)
    s_outcome=$(field "$json" outcome)
    s_steps=$(field "$json" steps)
    s_hash=$(field "$json" state_hash)
    result=ok
    if [[ -z $json ]]; then
        result="SIM FAILED"
    elif [[ $q_outcome != won ]]; then
        result="NOT WON"
    elif [[ $q_outcome != "$s_outcome" || $q_steps != "$s_steps" || ${q_hash,,} != "${s_hash,,}" ]]; then
        result=MISMATCH
    fi
    [[ $result == ok ]] || fail=1
    printf "$fmt" "$name" "$q_outcome" "${s_outcome:--}" "$q_steps" "${s_steps:--}" \
        "$q_hash" "${s_hash:--}" "$result"
done

# The CPU-load budget (issue: <= 3 % of a 64 MHz Cortex-M4 at the default rates).
# Under -icount the count is exact and the same on every machine, so this is a
# report with a limit, like the flash budget, not a timing test.
budget=${CPU_BUDGET_CENTIPERCENT:-300}
load=$(sed -n 's/.*cpu load: .* = \([0-9]*\)\.\([0-9][0-9]\) % of a 64 MHz.*/\1\2/p' "$log" | head -n 1)
if [[ -z $load ]]; then
    problem "no cpu load line in the QEMU log ($log)"
elif ((10#$load > budget)); then
    problem "CPU load $((10#$load / 100)).$(printf %02d $((10#$load % 100))) % is over the budget of $((budget / 100)).$(printf %02d $((budget % 100))) % (bash tools/qemu-profile.sh shows where it goes)"
else
    echo "check-demo: CPU load $((10#$load / 100)).$(printf %02d $((10#$load % 100))) % of 64 MHz (budget $((budget / 100)).$(printf %02d $((budget % 100))) %)" >&2
fi

if ((fail)); then
    echo "check-demo: FAILED (QEMU log: $log)" >&2
    exit 1
fi
echo "check-demo: OK: ${#rows[@]} levels won, QEMU and the simulator agree on outcome, steps and state hash" >&2
