//! `cargo sim`: the host simulator (see `marble_rolling::host::sim`).

fn main() {
    std::process::exit(marble_rolling::host::sim::main());
}
