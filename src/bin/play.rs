//! `cargo play`: the terminal player (see `marble_rolling::host::play`).

fn main() {
    std::process::exit(marble_rolling::host::play::main());
}
