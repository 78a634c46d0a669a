#!/usr/bin/env bash
# Flash and static-RAM budget of the BBC micro:bit v2 firmware.
#
#   bash tools/size-report.sh [--no-build] [ELF]
#
# Builds the release firmware (unless --no-build), measures it with llvm-size
# from the rustup `llvm-tools` component (pinned in rust-toolchain.toml), and
# prints a markdown table on stdout. Exits 1 if a budget is exceeded, 2 on a
# usage or tooling error.
#
#   Flash      = text + data   (vector table, code, read-only data, and the
#                               initial values of .data, all stored in flash)
#   Static RAM = data + bss    (.data, .bss and .uninit: the defmt-RTT buffer,
#                               embassy task arenas, statics; the stack is not
#                               included: it takes the rest of RAM)
#
# Budgets (bytes) can be overridden: FLASH_BUDGET (default 65536 = 64 KiB) and
# RAM_BUDGET (default 16384 = 16 KiB). The build honours CARGO_TARGET_DIR.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

flash_budget=${FLASH_BUDGET:-65536}
ram_budget=${RAM_BUDGET:-16384}
target=thumbv7em-none-eabihf
build=1
elf=

for arg in "$@"; do
    case $arg in
        --no-build) build=0 ;;
        -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
        -*) echo "size-report: unknown option $arg" >&2; exit 2 ;;
        *) elf=$arg ;;
    esac
done

if [[ -z $elf ]]; then
    elf=${CARGO_TARGET_DIR:-$root/target}/$target/release/microbit
    if [[ $build == 1 ]]; then
        cargo build --release --target "$target" --features board-microbit --bin microbit >&2
    fi
fi
if [[ ! -f $elf ]]; then
    echo "size-report: $elf not found (build it, or drop --no-build)" >&2
    exit 2
fi

host=$(rustc -vV | sed -n 's/^host: //p')
llvm_size=$(rustc --print sysroot)/lib/rustlib/$host/bin/llvm-size
if [[ ! -x $llvm_size ]]; then
    echo "size-report: $llvm_size missing; run: rustup component add llvm-tools" >&2
    exit 2
fi

# Berkeley format: text (alloc, read-only), data (alloc, writable, loaded),
# bss (alloc, not loaded); non-alloc sections such as .defmt and debug info
# are not counted.
read -r text data bss < <("$llvm_size" -B "$elf" | awk 'NR == 2 { print $1, $2, $3 }')
if [[ -z ${bss:-} ]]; then
    echo "size-report: could not parse llvm-size output for $elf" >&2
    exit 2
fi
flash=$((text + data))
ram=$((data + bss))

kib() { awk -v b="$1" 'BEGIN { printf "%.1f KiB", b / 1024 }'; }
pct() { awk -v u="$1" -v b="$2" 'BEGIN { printf "%.0f %%", 100 * u / b }'; }
verdict() { if (($1 <= $2)); then echo ok; else echo "**OVER**"; fi; }

echo "| micro:bit v2 firmware | used | budget | share | |"
echo "| --- | ---: | ---: | ---: | --- |"
echo "| Flash (text + data) | $flash B ($(kib "$flash")) | $(kib "$flash_budget") | $(pct "$flash" "$flash_budget") | $(verdict "$flash" "$flash_budget") |"
echo "| Static RAM (data + bss) | $ram B ($(kib "$ram")) | $(kib "$ram_budget") | $(pct "$ram" "$ram_budget") | $(verdict "$ram" "$ram_budget") |"

status=0
if ((flash > flash_budget)); then
    echo "size-report: flash $flash B exceeds the budget of $flash_budget B" >&2
    status=1
fi
if ((ram > ram_budget)); then
    echo "size-report: static RAM $ram B exceeds the budget of $ram_budget B" >&2
    status=1
fi
exit $status
