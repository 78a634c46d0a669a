#!/usr/bin/env bash
# Linker wrapper for the firmware (.cargo/config.toml): flip-link, installed on first
# use so that `cargo qemu` works on a fresh machine. flip-link places the stack below
# .data/.bss, so a stack overflow faults instead of silently corrupting statics.
set -euo pipefail
if ! command -v flip-link >/dev/null 2>&1; then
    echo "flip-link not found; installing it: cargo install flip-link --locked" >&2
    cargo install flip-link --locked >&2 || {
        echo "could not install flip-link; install it by hand: cargo install flip-link --locked" >&2
        exit 127
    }
fi
exec flip-link "$@"
