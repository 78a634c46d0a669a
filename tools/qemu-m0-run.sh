#!/usr/bin/env bash
# Cargo runner for thumbv6m-none-eabi (.cargo/config.toml): runs the Cortex-M0
# benchmark (src/bin/bench_m0.rs) in QEMU's `microbit` machine (nRF51822) under
# `-icount shift=7,align=off,sleep=off` (every instruction is 128 ns of virtual
# time, so the nRF51 TIMER0 counts instructions), with its semihosting output on
# stdout. QEMU's exit status is the benchmark's (0: all measured).
#
#   tools/qemu-m0-run.sh <elf> [--backends=MASK] [--rates=MASK]   (keep executable)
set -euo pipefail
if [[ $# -lt 1 ]]; then
    echo "usage: $0 <elf> [args...]" >&2
    exit 2
fi
elf=$1
shift
semihosting="enable=on,target=native,arg=$(basename "$elf")"
for arg in "$@"; do
    [[ $arg == -- ]] || semihosting+=",arg=${arg//,/,,}"
done
exec timeout --foreground "${QEMU_TIMEOUT:-900}" \
    qemu-system-arm -machine microbit -display none -monitor none -nodefaults \
    -semihosting-config "$semihosting" \
    -icount shift=7,align=off,sleep=off \
    -kernel "$elf"
