#!/usr/bin/env bash
# Cargo runner for thumbv7em-none-eabihf firmware (.cargo/config.toml):
#
#   tools/qemu-run.sh <elf> [firmware args...]     (keep this file executable)
#
# * An ELF named `microbit` is flashed and run on a micro:bit v2 with probe-rs.
# * Anything else runs in QEMU's mps2-an386 (Cortex-M4F), with the firmware's
#   defmt log (semihosting, which QEMU always writes to its stdout) piped into
#   `defmt-print -e <elf>`. QEMU's exit status (set by the firmware through
#   semihosting) is the runner's exit status.
#
# Two modes; the firmware learns which from its semihosting command line,
# where this script puts `--headless` or `--interactive` before the user's
# arguments:
#
# * headless, when `--demo` is given or stdin is not a terminal: UART0
#   discarded, `-icount shift=7,align=off,sleep=off` (virtual time: each
#   instruction is 2^7 ns, idle time is skipped, output is byte-identical
#   from run to run), defmt log on stdout. Killed after QEMU_TIMEOUT seconds
#   (default 600) in case the firmware hangs (e.g. a CPU lockup).
# * interactive: UART0 on the terminal (/dev/tty, raw mode), real time (no
#   -icount); the defmt log goes to target/qemu-defmt.log (or $QEMU_DEFMT_LOG)
#   and its tail is printed when the game ends. Quit with `q` (or Ctrl-C,
#   which the raw terminal hands to the game as a key); should the firmware
#   hang, kill qemu-system-arm from another terminal.
#
# The headless demo: the autopilot plays every built-in level; the firmware
# exits 0 when all were won (tools/check-demo.sh compares its per-level
# results with the host simulator's).
#
# Examples:  cargo qemu                 # play (arrows/WASD tilt, p autopilot, q quit)
#            cargo qemu -- --demo       # headless demo (also: cargo qemu --demo)
set -euo pipefail

if [[ $# -lt 1 ]]; then
    echo "usage: $0 <elf> [firmware args...]" >&2
    exit 2
fi
elf=$1
shift

# `cargo qemu -- --demo` reaches us as `<elf> -- --demo` (the alias already
# ends in `--`): drop separators.
args=()
for arg in "$@"; do
    [[ $arg == -- ]] || args+=("$arg")
done

need_cargo_tool() { # <binary> <crate>
    command -v "$1" >/dev/null 2>&1 && return 0
    echo "qemu-run: $1 not found; installing it with: cargo install $2 --locked" >&2
    cargo install "$2" --locked >&2 || {
        echo "qemu-run: failed; install it by hand: cargo install $2 --locked" >&2
        exit 127
    }
}

if [[ $(basename "$elf") == microbit ]]; then
    if ! command -v probe-rs >/dev/null 2>&1; then
        echo "qemu-run: probe-rs is needed to run the micro:bit firmware;" >&2
        echo "          install it with: cargo install probe-rs-tools --locked" >&2
        exit 127
    fi
    exec probe-rs run --chip nRF52833_xxAA "$elf" "${args[@]}"
fi

if ! command -v qemu-system-arm >/dev/null 2>&1; then
    if [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null 2>&1; then
        echo "qemu-run: qemu-system-arm not found; installing it with apt-get" >&2
        { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq qemu-system-arm; } >&2
    else
        echo "qemu-run: qemu-system-arm not found. Install it, e.g.:" >&2
        echo "          sudo apt-get install qemu-system-arm     (Debian/Ubuntu)" >&2
        echo "          sudo dnf install qemu-system-arm         (Fedora)" >&2
        echo "          brew install qemu                        (macOS)" >&2
        exit 127
    fi
fi
need_cargo_tool defmt-print defmt-print

headless=0
for arg in "${args[@]}"; do
    [[ $arg == --demo ]] && headless=1
done
[[ -t 0 ]] || headless=1

# Semihosting command line: program name, mode, the user's arguments
# (commas are doubled: QEMU's option syntax).
mode=--interactive
((headless)) && mode=--headless
semihosting="enable=on,target=native,arg=$(basename "$elf"),arg=$mode"
for arg in "${args[@]}"; do
    semihosting+=",arg=${arg//,/,,}"
done

qemu=(qemu-system-arm -machine mps2-an386 -cpu cortex-m4
    -display none -monitor none -nodefaults
    -semihosting-config "$semihosting"
    -kernel "$elf")

if ((headless)); then
    timeout --foreground "${QEMU_TIMEOUT:-600}" \
        "${qemu[@]}" -icount shift=7,align=off,sleep=off -serial null |
        defmt-print -e "$elf"
    exit
fi

if [[ ! -r /dev/tty || ! -w /dev/tty ]]; then
    echo "qemu-run: interactive mode needs a terminal (/dev/tty); use --demo" >&2
    exit 2
fi
log=${QEMU_DEFMT_LOG:-$(cd "$(dirname "$0")/.." && pwd)/target/qemu-defmt.log}
mkdir -p "$(dirname "$log")"
saved_tty=$(stty -g </dev/tty)
restore() {
    # QEMU's serial backend reprograms the line (speed etc.); on a pty not
    # every saved setting can be put back, which stty reports as an error.
    stty "$saved_tty" </dev/tty 2>/dev/null || stty sane </dev/tty 2>/dev/null || true
    printf '\e[0m\e[?25h' >/dev/tty || true
}
trap restore EXIT
stty raw -echo </dev/tty
status=0
"${qemu[@]}" -chardev serial,id=term,path=/dev/tty -serial chardev:term |
    defmt-print -e "$elf" >"$log" 2>&1 || status=$?
restore
trap - EXIT
echo
echo "qemu-run: defmt log in $log; last lines:"
tail -n 8 "$log"
exit "$status"
