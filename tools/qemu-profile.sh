#!/usr/bin/env bash
# Where the QEMU firmware's instructions go, by function:
#
#   bash tools/qemu-profile.sh [top-N]        (default 40)
#
# Builds the release `qemu` firmware, runs its headless demo under QEMU with
# the translation-block trace on (`-d in_asm,exec,nochain`: every executed
# block is logged, chaining off so none is skipped), and attributes every
# executed instruction to the function that holds it (llvm-nm symbols).
# Two tables: the demo itself (what the CPU-load figure measures) and the
# profiling replay that follows it (game work only), then the callers of the
# compiler's helper routines (memcpy, memcmp, 64-bit division).
#
# The trace is large (about 2 GB for the whole demo, in $PROFILE_DIR,
# default target/qemu-profile; deleted afterwards unless KEEP_TRACE=1) and
# the analysis takes about a minute. Needs python3 and llvm-nm (apt-get
# install llvm) besides what `cargo qemu` needs.
set -euo pipefail
cd "$(dirname "$0")/.."
top=${1:-40}
dir=${PROFILE_DIR:-target/qemu-profile}
mkdir -p "$dir"
cargo build --release --target thumbv7em-none-eabihf --features board-qemu --bin qemu >&2
target_dir=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')
elf=$target_dir/thumbv7em-none-eabihf/release/qemu
qemu-system-arm -machine mps2-an386 -cpu cortex-m4 -display none -monitor none -nodefaults \
    -semihosting-config enable=on,target=native,arg=qemu,arg=--headless,arg=--demo \
    -kernel "$elf" -icount shift=7,align=off,sleep=off -serial null \
    -d in_asm,exec,nochain -D "$dir/trace.log" >"$dir/defmt.bin"
python3 tools/qemu-profile.py "$elf" "$dir/trace.log" "$top"
[[ ${KEEP_TRACE:-0} == 1 ]] || rm -f "$dir/trace.log"
