//! `cargo play`: the terminal player (see `marble_rolling::host::play`), or
//! with `--race` a race against another terminal (`marble_rolling::host::race`).

use marble_rolling::host::{parse_args, play, race};

fn main() {
    let status = match parse_args::<play::Args>() {
        Ok(args) if args.race => race::main(&args),
        Ok(args) => play::main(args),
        Err(status) => status,
    };
    std::process::exit(status);
}
