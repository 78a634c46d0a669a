//! `cargo qemu -- --race --demo`: two QEMU mps2-an386 boards race one
//! generated maze (boards/qemu-race), their UART1s joined through this task,
//! which plays the radio between them: it cuts each board's byte stream into
//! packets (`race::wire`), drops and repeats some by a seeded link model, and
//! hands the rest to the other board. Headless, both autopilots (the second
//! looks at the maze for `LOOKS` frames first, so that one wins).
//!
//! It exits 0 only if both boards report a verdict, the two verdicts mirror
//! each other, each board's replay of its opponent ends on the opponent's own
//! frames and state hash (checked on the board, and here against the other
//! board's report), and the first board's run (the autopilot from the first
//! frame) has the host's state hash for the maze (`cargo sim -- --generate
//! SEED --size N --storeys S --difficulty D --autopilot`).
//!
//! The link model is the host tests' (`tests/race.rs`) without the delays: the
//! QEMU boards run on their own virtual clocks, so the order of the bytes is
//! the host's scheduling, and only the verdict and the hashes are fixed.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::thread;
use std::time::Duration;

use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::level::parse;
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::Session;
use marble_rolling::race::replay::{RACE_CONFIG, RACE_TILT};
use marble_rolling::race::wire::{self, Unframer, MAX_FRAME};
use marble_rolling::race::{self, MazeSpec};

use crate::boards;
use crate::error::{say, Failure, Outcome};
use crate::process;
use crate::runner::{self, Load};
use crate::workspace;

/// The two boards' ids; the lower proposes, so the race's maze is its offer.
const IDS: [u32; 2] = [7, 9];
/// The maze the first board offers.
const MAZE: MazeSpec = MazeSpec {
    seed: 11,
    size: 5,
    storeys: 1,
    difficulty: 1,
};
/// Frames the second board looks at the maze before its autopilot starts.
const LOOKS: u32 = 40;
/// The link model: a packet is lost with this chance, else repeated with the
/// next (per direction, seeded).
const LOSS: f64 = 0.2;
const REPEAT: f64 = 0.1;

/// One board's report, from its defmt log.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
struct Report {
    verdict: String,
    own: (String, u32, String),
    opponent: (String, u32, String),
    verified: bool,
    lag: String,
    /// Frames with both runs going on, and those with the opponent on the
    /// board's matrix picture.
    drawn: Option<(u32, u32)>,
    /// The matrix mid-race, a row of hex brightness digits a line.
    picture: Vec<String>,
}

/// `cargo qemu -- --race [--demo]`: `board`'s race firmware on its machine
/// (QEMU mps2-an386's).
pub fn run(board: &boards::Board) -> Outcome {
    let machine = board.machine()?;
    let Some(racer) = &board.race else {
        return Err(Failure::new(format!("the {} does not race", board.name)).status(2));
    };
    let limit = runner::timeout(racer.timeout)?;
    let tools = racer.qemu_tools()?;
    let elf = racer.build()?;
    let Some(defmt_print) = &tools.defmt_print else {
        return Err(Failure::new("defmt-print was not set up for the race"));
    };
    let target = workspace::target_dir()?;
    let listener = TcpListener::bind("127.0.0.1:0")
        .map_err(|e| Failure::new(format!("cannot listen on 127.0.0.1: {e}")))?;
    let port = listener
        .local_addr()
        .map_err(|e| Failure::new(format!("the link's port: {e}")))?
        .port();
    say!(
        "racing two QEMU {} boards on maze {} (size {}, storeys {}, difficulty {}), \
         their UART1s joined here with {:.0} % of packets lost and {:.0} % repeated",
        machine.name,
        MAZE.seed,
        MAZE.size,
        MAZE.storeys,
        MAZE.difficulty,
        LOSS * 100.0,
        REPEAT * 100.0
    );
    let mut boards = Vec::new();
    let mut streams = Vec::new();
    for (i, id) in IDS.into_iter().enumerate() {
        let log = target.join(format!("qemu-race-{id}.log"));
        let looks = if i == 0 { 0 } else { LOOKS };
        let line = [
            "--id".to_string(),
            id.to_string(),
            "--looks".into(),
            looks.to_string(),
            "--seed".into(),
            MAZE.seed.to_string(),
            "--size".into(),
            MAZE.size.to_string(),
            "--storeys".into(),
            MAZE.storeys.to_string(),
            "--difficulty".into(),
            MAZE.difficulty.to_string(),
        ];
        let mut qemu = runner::qemu(machine, &tools.qemu, &Load::Elf(&elf), "--race", &line);
        qemu.args(runner::ICOUNT)
            .args(["-serial", "null", "-serial"])
            .arg(format!("tcp:127.0.0.1:{port}"));
        let board = Board::start(&mut qemu, defmt_print, &elf, &log)?;
        boards.push(board);
        // QEMU connects before it runs the firmware: one board at a time, so
        // that the first connection is the first board's.
        let (stream, _) = listener
            .accept()
            .map_err(|e| Failure::new(format!("board {id} did not connect: {e}")))?;
        streams.push(stream);
    }
    let relays = [(0, 1), (1, 0)].map(|(from, to)| {
        let (r, w) = (clone(&streams[from]), clone(&streams[to]));
        let seed = 0x5eed_0000 + from as u64;
        thread::spawn(move || relay(r?, w?, seed))
    });
    let mut statuses = Vec::new();
    for board in &mut boards {
        statuses.push(board.wait(limit));
    }
    for s in &streams {
        let _ = s.shutdown(std::net::Shutdown::Both);
    }
    let counts: Vec<(u32, u32, u32)> = relays
        .into_iter()
        .map(|r| r.join().ok().and_then(Result::ok).unwrap_or_default())
        .collect();
    for (i, (packets, dropped, repeated)) in counts.iter().enumerate() {
        say!(
            "link {} -> {}: {packets} packets, {dropped} dropped, {repeated} repeated",
            IDS[i],
            IDS[1 - i]
        );
    }
    let reports: Vec<Option<Report>> = boards.iter().map(|b| read_report(&b.log)).collect();
    for (i, status) in statuses.into_iter().enumerate() {
        let code = status?;
        if code != 0 {
            return Err(Failure::new(format!(
                "board {} exited with status {code} (its log: {})",
                IDS[i],
                boards[i].log.display()
            )));
        }
    }
    let [Some(a), Some(b)] = [reports[0].clone(), reports[1].clone()] else {
        return Err(Failure::new("a board's log has no race report"));
    };
    check(&a, &b)?;
    for (id, r) in IDS.iter().zip([&a, &b]) {
        match r.drawn {
            Some((frames, drawn)) if drawn > 0 => say!(
                "board {id}'s matrix: the opponent drawn dimmer on {drawn} of the {frames} \
                 frames both ran"
            ),
            _ => {
                return Err(Failure::new(format!(
                    "board {id} never drew its opponent on its matrix ({:?})",
                    r.drawn
                )))
            }
        }
    }
    if !a.picture.is_empty() {
        say!(
            "board {}'s matrix mid-race (brightness 0-f: the marble f, the opponent {}, walls 3):",
            IDS[0],
            marble_rolling::render::race::OPPONENT
        );
        for row in &a.picture {
            say!("    {row}");
        }
    }
    let host = host_hash(MAZE)?;
    if a.own.2 != host.1 || a.own.1 != host.0 {
        return Err(Failure::new(format!(
            "board {}'s run ({} frames, state_hash={}) is not the host's ({} frames, \
             state_hash={})",
            IDS[0], a.own.1, a.own.2, host.0, host.1
        )));
    }
    for (id, r) in IDS.iter().zip([&a, &b]) {
        say!("board {id}: {}", r.lag);
    }
    say!(
        "OK: both boards agree: board {} {} ({} in {} frames), board {} {} ({} in {} frames); \
         each replay ends on its opponent's state_hash, and board {}'s is the host's ({})",
        IDS[0],
        a.verdict,
        a.own.0,
        a.own.1,
        IDS[1],
        b.verdict,
        b.own.0,
        b.own.1,
        IDS[0],
        host.1
    );
    Ok(0)
}

fn clone(s: &TcpStream) -> Result<TcpStream, Failure> {
    s.try_clone()
        .map_err(|e| Failure::new(format!("the link's socket: {e}")))
}

/// A QEMU board and its defmt-print, the log in a file.
struct Board {
    qemu: Child,
    decoder: Child,
    log: std::path::PathBuf,
}

impl Board {
    fn start(
        qemu: &mut Command,
        defmt_print: &Path,
        elf: &Path,
        log: &Path,
    ) -> Result<Board, Failure> {
        qemu.stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null());
        let mut child = process::spawn(qemu)?;
        let Some(pipe) = child.stdout.take() else {
            return Err(Failure::new("QEMU's stdout was not piped"));
        };
        let file = std::fs::File::create(log)
            .map_err(|e| Failure::new(format!("cannot create {}: {e}", log.display())))?;
        let err = file
            .try_clone()
            .map_err(|e| Failure::new(format!("{}: {e}", log.display())))?;
        let mut cmd = Command::new(defmt_print);
        cmd.arg("-e").arg(elf).stdin(pipe).stdout(file).stderr(err);
        let decoder = process::spawn(&mut cmd).inspect_err(|_| {
            let _ = child.kill();
        })?;
        Ok(Board {
            qemu: child,
            decoder,
            log: log.to_path_buf(),
        })
    }

    /// QEMU's exit status (the firmware's: 0 when its race finished).
    fn wait(&mut self, limit: Duration) -> Result<i32, Failure> {
        let status = runner::wait_at_most(&mut self.qemu, limit);
        let _ = self.decoder.wait();
        Ok(status?.code().unwrap_or(-1))
    }
}

/// Relays `from`'s packets to `to` through the link model; returns the
/// packets seen, dropped and repeated.
fn relay(mut from: TcpStream, mut to: TcpStream, seed: u64) -> Result<(u32, u32, u32), Failure> {
    let mut dice = seed;
    let mut roll = move || {
        dice = dice.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = dice;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut unframer = Unframer::new();
    let mut buf = [0u8; 4096];
    let mut framed = [0u8; MAX_FRAME];
    let (mut seen, mut dropped, mut repeated) = (0, 0, 0);
    loop {
        let n = match from.read(&mut buf) {
            Ok(0) | Err(_) => return Ok((seen, dropped, repeated)),
            Ok(n) => n,
        };
        for &byte in &buf[..n] {
            let Ok(packet) = unframer.push(byte) else {
                continue;
            };
            seen += 1;
            if roll() < LOSS {
                dropped += 1;
                continue;
            }
            let copies = if roll() < REPEAT {
                repeated += 1;
                2
            } else {
                1
            };
            let bytes = wire::frame(packet, &mut framed);
            for _ in 0..copies {
                if to.write_all(bytes).is_err() {
                    return Ok((seen, dropped, repeated));
                }
            }
        }
    }
}

/// The race report in a board's defmt log.
fn read_report(log: &Path) -> Option<Report> {
    let file = std::fs::File::open(log).ok()?;
    let mut report: Option<Report> = None;
    let mut lag = String::new();
    let mut drawn = None;
    let mut picture = Vec::new();
    for line in BufReader::new(file).lines().map_while(Result::ok) {
        if let Some(rest) = line.split("race: verdict ").nth(1) {
            report = parse_report(rest);
        }
        if let Some(rest) = line.split("race lag: ").nth(1) {
            lag = rest.to_string();
        }
        if let Some(rest) = line.split("race matrix: the opponent drawn on ").nth(1) {
            drawn = parse_drawn(rest);
        }
        if let Some(rest) = line.split("race matrix at ").nth(1) {
            picture = parse_picture(rest);
        }
    }
    report.map(|r| Report {
        lag,
        drawn,
        picture,
        ..r
    })
}

/// `12 of 500 frames while both ran`: (500, 12).
fn parse_drawn(rest: &str) -> Option<(u32, u32)> {
    let (drawn, rest) = rest.split_once(" of ")?;
    let (frames, _) = rest.split_once(' ')?;
    Some((frames.parse().ok()?, drawn.parse().ok()?))
}

/// `frame 256, opponent at frame 200: [[0, 3, …], […]]`: each row as hex
/// digits.
fn parse_picture(rest: &str) -> Vec<String> {
    let Some((_, rows)) = rest.split_once(": ") else {
        return Vec::new();
    };
    rows.split("], [")
        .map(|row| {
            row.trim_matches(|c| c == '[' || c == ']')
                .split(", ")
                .filter_map(|n| n.trim().parse::<u32>().ok())
                .filter_map(|n| char::from_digit(n, 16))
                .collect()
        })
        .collect()
}

/// `won; own won in 563 frames, state_hash=…; opponent won in 597 frames,
/// state_hash=…, verified true`
fn parse_report(rest: &str) -> Option<Report> {
    let mut parts = rest.split("; ");
    let verdict = parts.next()?.to_string();
    let run = |s: &str, who: &str| -> Option<(String, u32, String)> {
        let s = s.strip_prefix(who)?;
        let (phase, s) = s.split_once(" in ")?;
        let (frames, s) = s.split_once(" frames, state_hash=")?;
        let hash: String = s.chars().take_while(char::is_ascii_hexdigit).collect();
        Some((phase.to_string(), frames.parse().ok()?, hash))
    };
    let own = run(parts.next()?, "own ")?;
    let opp_text = parts.next()?;
    let opponent = run(opp_text, "opponent ")?;
    Some(Report {
        verdict,
        own,
        opponent,
        verified: opp_text.ends_with("verified true"),
        ..Report::default()
    })
}

/// The two reports mirror each other, and each replay is the other's run.
fn check(a: &Report, b: &Report) -> Result<(), Failure> {
    fn mirror(v: &str) -> &str {
        match v {
            "won" => "lost",
            "lost" => "won",
            other => other,
        }
    }
    if a.verdict == "none" || mirror(&a.verdict) != b.verdict {
        return Err(Failure::new(format!(
            "the boards disagree: board {} says {}, board {} says {}",
            IDS[0], a.verdict, IDS[1], b.verdict
        )));
    }
    for (me, them, id) in [(a, b, IDS[0]), (b, a, IDS[1])] {
        if !me.verified || me.opponent != them.own {
            return Err(Failure::new(format!(
                "board {id}'s replay of its opponent ({:?}, verified {}) is not the \
                 opponent's run ({:?})",
                me.opponent, me.verified, them.own
            )));
        }
    }
    Ok(())
}

/// The autopilot's run of `spec` on the host, as `cargo sim -- --generate
/// … --autopilot` plays it: its frames and state hash (16 hex digits).
fn host_hash(spec: MazeSpec) -> Result<(u32, String), Failure> {
    let maze = race::maze(spec).map_err(|e| Failure::new(format!("the race's maze: {e}")))?;
    let text = maze.to_string();
    let level = parse::<2048>(&text)
        .map_err(|e| Failure::new(format!("the race's maze does not parse: {e}")))?;
    let view = level.view();
    let mut session = Session::<marble_rolling::physics::Fx>::new(view, RACE_CONFIG, RACE_TILT)
        .map_err(|e| Failure::new(format!("the race's maze cannot be set up: {e:?}")))?;
    let mut autopilot = Autopilot::new(&view);
    while session.game().phase() == Phase::Playing {
        session.autopilot_frame(&mut autopilot);
    }
    Ok((
        session.game().frames(),
        format!("{:016x}", session.state_hash()),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_report_line_reads_back_and_mirrored_reports_pass() {
        let a = parse_report(
            "won; own won in 563 frames, state_hash=3be99b83f76c03e9; opponent won in 597 \
             frames, state_hash=a58fa76c6adf62d3, verified true",
        )
        .unwrap();
        assert_eq!(a.own, ("won".into(), 563, "3be99b83f76c03e9".into()));
        assert!(a.verified);
        let b = Report {
            verdict: "lost".into(),
            own: a.opponent.clone(),
            opponent: a.own.clone(),
            verified: true,
            ..Report::default()
        };
        assert!(check(&a, &b).is_ok());
        let wrong = Report {
            verdict: "won".into(),
            ..b.clone()
        };
        assert!(check(&a, &wrong).is_err(), "two winners");
        let other_hash = Report {
            opponent: ("won".into(), 563, "0000000000000000".into()),
            ..b
        };
        assert!(check(&a, &other_hash).is_err(), "a replay off the run");
    }

    #[test]
    fn the_matrix_lines_read_back() {
        assert_eq!(
            parse_drawn("412 of 520 frames while both ran"),
            Some((520, 412))
        );
        assert_eq!(parse_drawn("many"), None);
        let picture = parse_picture("frame 256, opponent at frame 201: [[0, 3, 15], [1, 5, 20]]");
        assert_eq!(picture, vec!["03f".to_string(), "15".to_string()]);
    }

    #[test]
    fn the_host_hash_is_the_autopilots() {
        let (frames, hash) = host_hash(MAZE).unwrap();
        assert_eq!(frames, 563);
        assert_eq!(hash.len(), 16);
    }
}
