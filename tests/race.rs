//! The race protocol (`race`) between boards on a simulated channel: every
//! packet a board sends reaches every other board, each copy lost, repeated
//! or delayed on its own (so reordered), with garbage between. Whatever the
//! channel does, both boards reach the same verdict and each replay of the
//! opponent ends on the opponent's own state hash; a third board, a board
//! restarted mid-race and random bytes are dropped and counted.
//!
//! `cargo test --test race -- --nocapture` prints the bytes per second of play.

use std::num::NonZeroU32;

use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::endless::{MazeError, MazeSlot, Reach};
use marble_rolling::game::level::{parse, Level, LevelView};
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::Session;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::event::Command;
use marble_rolling::input::race_setup::{
    race_at_power_on, Field, RaceSetup, Tuning, FIRST_CHANNEL, GROUPS, LAST_CHANNEL,
};
use marble_rolling::input::sensor::Calibration;
use marble_rolling::matrix::{Frame, MAX_BRIGHTNESS};
use marble_rolling::player::race::{RaceRound, RoundEvent, RoundExit};
use marble_rolling::race::air::{self, AirDrop, AIR_FRAME};
use marble_rolling::race::packet::{self, Drop, End, MazeSpec, Writer, BLOCK_BYTES, MAX_PACKET};
use marble_rolling::race::replay::{decide, Run, Verdict};
use marble_rolling::race::session::{COUNTDOWN_FRAMES, SILENCE_FRAMES};
use marble_rolling::race::stream::{LEAN_EARLY_BLOCKS, LEAN_INBOX_READINGS, LEAN_OUT_BLOCKS};
use marble_rolling::race::wire::{self, Unframed, Unframer, MAX_FRAME};
use marble_rolling::race::{maze, offer, race_id, LeanLink, LinkStage, Race, RaceLink, Status};
use marble_rolling::render::race::{
    countdown_frame, race_frame, searching_frame, setup_frame, verdict_frame, OPPONENT,
};
use marble_rolling::render::{Renderer, GHOST};
use proptest::prelude::*;

type Fx = fixed::types::I8F24;
const WORDS: usize = 512;
const HZ: u64 = 128;

const SPEC: MazeSpec = MazeSpec {
    seed: 11,
    size: 5,
    storeys: 1,
    difficulty: 1,
};
const SPEC_2: MazeSpec = MazeSpec {
    seed: 4,
    size: 4,
    storeys: 2,
    difficulty: 2,
};

/// A small deterministic generator (splitmix64): the channel's dice.
struct Dice(u64);

impl Dice {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }
    fn below(&mut self, n: u64) -> u64 {
        if n == 0 {
            0
        } else {
            self.next() % n
        }
    }
}

/// What the channel does to each copy of a packet.
#[derive(Clone, Copy, Debug)]
struct Weather {
    loss: f64,
    duplicate: f64,
    /// Each copy arrives after 0 ..= this many frames.
    max_delay: u64,
    /// Chance per frame of a garbage packet (random bytes, or a real packet
    /// with a flipped bit).
    garbage: f64,
    /// Frames of the channel during which every packet is lost.
    blackout: (u64, u64),
}

const CLEAR: Weather = Weather {
    loss: 0.0,
    duplicate: 0.0,
    max_delay: 0,
    garbage: 0.0,
    blackout: (0, 0),
};

/// A board: looking for an opponent, or racing; and the player at its tilt
/// (flat for `looks` frames of its run, then the autopilot).
enum Stage<'a> {
    Linking(Box<RaceLink>),
    Racing(Box<Race<'a, Fx>>),
}

struct Board<'a> {
    stage: Stage<'a>,
    looks: u32,
    autopilot: Option<Autopilot>,
}

/// The generated mazes a board may be asked to race on, parsed once.
struct Mazes {
    levels: Vec<(MazeSpec, Level<'static, WORDS>)>,
}

impl Mazes {
    fn new(specs: &[MazeSpec]) -> Mazes {
        let levels = specs
            .iter()
            .map(|&s| {
                let text: &'static str = Box::leak(maze(s).unwrap().to_string().into_boxed_str());
                (s, parse::<WORDS>(text).unwrap())
            })
            .collect();
        Mazes { levels }
    }
    fn view(&self, spec: MazeSpec) -> LevelView<'_> {
        self.levels
            .iter()
            .find(|(s, _)| *s == spec)
            .expect("a maze offered in the test")
            .1
            .view()
    }
}

impl<'a> Board<'a> {
    fn new(id: u32, offer: MazeSpec, looks: u32) -> Board<'a> {
        Board {
            stage: Stage::Linking(Box::new(RaceLink::new(
                NonZeroU32::new(id).unwrap(),
                offer,
                Calibration::NONE,
            ))),
            looks,
            autopilot: None,
        }
    }

    fn race(&self) -> Option<&Race<'a, Fx>> {
        match &self.stage {
            Stage::Racing(r) => Some(r),
            _ => None,
        }
    }

    fn link(&self) -> Option<&RaceLink> {
        match &self.stage {
            Stage::Linking(l) => Some(l),
            Stage::Racing(r) => Some(r.link()),
        }
    }

    fn receive(&mut self, bytes: &[u8]) {
        let _ = match &mut self.stage {
            Stage::Linking(l) => l.receive(bytes),
            Stage::Racing(r) => r.receive(bytes),
        };
    }

    fn frame(&mut self, mazes: &'a Mazes, out: &mut Vec<Vec<u8>>) {
        let mut buf = [0u8; MAX_PACKET];
        match &mut self.stage {
            Stage::Linking(l) => {
                l.tick();
                if let Some(p) = l.transmit(&mut buf) {
                    out.push(p.to_vec());
                }
                if let Some((_, spec)) = l.paired() {
                    let level = mazes.view(spec);
                    let link = (**l).clone();
                    self.autopilot = Some(Autopilot::new(&level));
                    self.stage = Stage::Racing(Box::new(Race::new(link, level).unwrap()));
                }
            }
            Stage::Racing(r) => {
                let (looks, autopilot) = (self.looks, &mut self.autopilot);
                r.frame(|s: &Session<'_, Fx>| {
                    if s.game().frames() < looks {
                        AccelMg::LEVEL
                    } else {
                        autopilot.as_mut().unwrap().reading_mg(s.game())
                    }
                });
                if let Some(p) = r.transmit(&mut buf) {
                    out.push(p.to_vec());
                }
            }
        }
    }
}

/// Boards on one channel.
struct Channel<'a> {
    boards: Vec<Board<'a>>,
    /// (arrival frame, addressee, bytes)
    flying: Vec<(u64, usize, Vec<u8>)>,
    weather: Weather,
    dice: Dice,
    now: u64,
    garbage_sent: u32,
    /// Board 0's view while both runs go on: its frames ahead of its replay
    /// of board 1 (how far the opponent's marble is drawn behind).
    lags: Vec<i64>,
}

impl<'a> Channel<'a> {
    fn new(boards: Vec<Board<'a>>, weather: Weather, seed: u64) -> Channel<'a> {
        Channel {
            boards,
            flying: Vec::new(),
            weather,
            dice: Dice(seed),
            now: 0,
            garbage_sent: 0,
            lags: Vec::new(),
        }
    }

    fn frame(&mut self, mazes: &'a Mazes) {
        self.now += 1;
        let now = self.now;
        let mut arrived = Vec::new();
        self.flying.retain(|(at, to, bytes)| {
            if *at <= now {
                arrived.push((*to, bytes.clone()));
                false
            } else {
                true
            }
        });
        for (to, bytes) in arrived {
            self.boards[to].receive(&bytes);
        }
        if self.dice.chance(self.weather.garbage) {
            let to = self.dice.below(self.boards.len() as u64) as usize;
            let bytes = self.garbage();
            self.garbage_sent += 1;
            self.boards[to].receive(&bytes);
        }
        if let (Some(a), Some(b)) = (
            self.boards[0].race(),
            self.boards.get(1).and_then(Board::race),
        ) {
            let (own, opp) = (a.own_run(), a.opponent().run());
            if own.frames > 0 && own.phase == Phase::Playing && b.own_run().phase == Phase::Playing
            {
                self.lags
                    .push(i64::from(own.frames) - i64::from(opp.frames));
            }
        }
        for from in 0..self.boards.len() {
            let mut out = Vec::new();
            self.boards[from].frame(mazes, &mut out);
            for bytes in out {
                for to in (0..self.boards.len()).filter(|&t| t != from) {
                    self.send(to, &bytes);
                }
            }
        }
    }

    fn send(&mut self, to: usize, bytes: &[u8]) {
        let w = self.weather;
        if self.dice.chance(w.loss) || (w.blackout.0..w.blackout.1).contains(&self.now) {
            return;
        }
        let copies = if self.dice.chance(w.duplicate) { 2 } else { 1 };
        for _ in 0..copies {
            let at = self.now + 1 + self.dice.below(w.max_delay + 1);
            self.flying.push((at, to, bytes.to_vec()));
        }
    }

    /// Random bytes of a random length, or a packet in flight with one bit flipped.
    fn garbage(&mut self) -> Vec<u8> {
        if !self.flying.is_empty() && self.dice.chance(0.5) {
            let i = self.dice.below(self.flying.len() as u64) as usize;
            let mut b = self.flying[i].2.clone();
            let bit = self.dice.below(b.len() as u64 * 8) as usize;
            b[bit / 8] ^= 1 << (bit % 8);
            return b;
        }
        let n = self.dice.below(MAX_PACKET as u64 + 8) as usize;
        (0..n).map(|_| self.dice.next() as u8).collect()
    }

    /// Runs until every racing board is done (its verdict reached and its
    /// link complete) or `limit` frames.
    fn run(&mut self, mazes: &'a Mazes, limit: u64, done: impl Fn(&Channel<'a>) -> bool) {
        while self.now < limit && !done(self) {
            self.frame(mazes);
        }
    }
}

fn lag_line(lags: &[i64]) -> String {
    let mut l = lags.to_vec();
    l.sort_unstable();
    let at = |q: f64| {
        l.get(((l.len() as f64 - 1.0) * q) as usize)
            .copied()
            .unwrap_or(0)
    };
    format!(
        "opponent drawn behind by {:.2} s median, {:.2} s at the 95th percentile, {:.2} s at most",
        at(0.5) as f64 / HZ as f64,
        at(0.95) as f64 / HZ as f64,
        at(1.0) as f64 / HZ as f64
    )
}

fn describe(b: &Board<'_>) -> String {
    match b.race() {
        Some(r) => {
            let (o, i) = (r.link().outbox(), r.link().inbox());
            format!(
                "{:?} own {:?} opp {:?} verified {:?} out {}/{} acked, {} blocks, end {:?} in have {} end {:?} {:?}",
                r.status(),
                r.own_run(),
                r.opponent().run(),
                r.opponent().verified(),
                o.acked(),
                o.frames(),
                o.unacked_blocks(),
                o.end_to_send(),
                i.have(),
                i.end(),
                r.link().counters()
            )
        }
        None => format!("{:?}", b.link().map(|l| l.handshake())),
    }
}

fn settled(b: &Board<'_>) -> bool {
    b.race().is_some_and(Race::finished)
}

/// What a finished race between boards `a` and `b` must show: mirrored
/// verdicts, and each replay ending on the other's own run and state hash.
fn check_agreement(c: &Channel<'_>, a: usize, b: usize) -> Verdict {
    check_pair(&c.boards[a], &c.boards[b])
}

fn check_pair(a: &Board<'_>, b: &Board<'_>) -> Verdict {
    let (ra, rb) = (a.race().unwrap(), b.race().unwrap());
    let (va, vb) = (ra.verdict().unwrap(), rb.verdict().unwrap());
    assert_eq!(va, vb.mirrored(), "the boards disagree");
    for (me, them) in [(ra, rb), (rb, ra)] {
        let replay = me.opponent();
        assert_eq!(replay.verified(), Some(true), "the replay missed the end");
        assert_eq!(replay.run(), them.own_run());
        assert_eq!(replay.session().state_hash(), them.own().state_hash());
        assert_eq!(me.link().paired().unwrap().0, them.link().me());
    }
    va
}

/// Two boards on a clear channel race to a verdict; the first's run is the
/// autopilot's from the first frame, which `cargo sim --generate --autopilot`
/// plays too: the opponent's replay ends on the simulator's hash.
#[test]
fn two_boards_on_a_clear_channel_agree() {
    let mazes = Mazes::new(&[SPEC]);
    let boards = vec![Board::new(7, SPEC, 0), Board::new(9, SPEC, 40)];
    let mut c = Channel::new(boards, CLEAR, 1);
    c.run(&mazes, 40 * HZ, |c| c.boards.iter().all(settled));
    let v = check_agreement(&c, 0, 1);
    let (a, b) = (c.boards[0].race().unwrap(), c.boards[1].race().unwrap());
    assert_eq!(a.own_run().phase, Phase::Won);
    assert_eq!(v, Verdict::Won, "the board that did not wait won");
    assert_eq!(a.status(), Status::Decided(Verdict::Won));
    assert_eq!(b.status(), Status::Decided(Verdict::Lost));
    for r in [a, b] {
        assert_eq!(r.link().counters().dropped(), 0);
    }
    // Bytes per second of play: each board's packets, from its first hello
    // to the end of the longer run (the countdown included).
    let seconds = c.now as f64 / HZ as f64;
    let play = a.own_run().frames.max(b.own_run().frames) as f64 / HZ as f64;
    for (name, r) in [("a", a), ("b", b)] {
        let k = r.link().counters();
        println!(
            "board {name}: {} packets, {} B in {seconds:.2} s ({play:.2} s of play): {:.0} B/s, {:.1} B a packet",
            k.sent,
            k.sent_bytes,
            k.sent_bytes as f64 / seconds,
            k.sent_bytes as f64 / k.sent as f64
        );
    }
    println!("{}", lag_line(&c.lags));
    println!(
        "board a's run: {} frames in {} blocks",
        a.own_run().frames,
        b.link().counters().blocks_taken
    );
    let hash_a = a.own().state_hash();
    assert_eq!(b.opponent().session().state_hash(), hash_a);
    #[cfg(feature = "tools")]
    {
        use clap::Parser;
        let args = marble_rolling::host::sim::Args::parse_from([
            "sim",
            "--generate",
            &SPEC.seed.to_string(),
            "--size",
            &SPEC.size.to_string(),
            "--storeys",
            &SPEC.storeys.to_string(),
            "--difficulty",
            &SPEC.difficulty.to_string(),
            "--autopilot",
        ]);
        let report = marble_rolling::host::sim::simulate(&args).unwrap();
        assert_eq!(report.state_hash, hash_a, "cargo sim's hash");
        assert_eq!(report.frames, a.own_run().frames);
    }
}

/// Half the packets lost, one in five repeated, every copy delayed up to two
/// seconds (so reordered), and garbage on the channel: still one verdict and
/// exact replays, on several channels' dice and mazes with storeys.
#[test]
fn two_boards_agree_through_loss_reordering_duplication_delays_and_garbage() {
    let mazes = Mazes::new(&[SPEC, SPEC_2]);
    let weather = Weather {
        loss: 0.5,
        duplicate: 0.2,
        max_delay: 2 * HZ,
        garbage: 0.05,
        ..CLEAR
    };
    let mut verdicts = Vec::new();
    for seed in 0..6u64 {
        let (offer_a, offer_b) = if seed % 2 == 0 {
            (SPEC, SPEC_2)
        } else {
            (SPEC_2, SPEC)
        };
        let looks = [(0, 60), (60, 0), (30, 30)][seed as usize % 3];
        let boards = vec![
            Board::new(100 + seed as u32, offer_a, looks.0),
            Board::new(200 + seed as u32, offer_b, looks.1),
        ];
        let mut c = Channel::new(boards, weather, seed);
        c.run(&mazes, 120 * HZ, |c| c.boards.iter().all(settled));
        assert!(
            c.boards.iter().all(settled),
            "seed {seed}: not settled after {} frames: {}",
            c.now,
            c.boards.iter().map(describe).collect::<Vec<_>>().join("\n")
        );
        let v = check_agreement(&c, 0, 1);
        let a = c.boards[0].race().unwrap();
        assert_eq!(
            a.link().paired().unwrap().1,
            offer_a,
            "the lower id's offer"
        );
        let k: Vec<_> = c
            .boards
            .iter()
            .map(|b| *b.link().unwrap().counters())
            .collect();
        let dropped: u32 = k
            .iter()
            .map(|k| k.crc + k.length + k.foreign + k.malformed)
            .sum();
        assert!(
            dropped > 0 && c.garbage_sent > 0,
            "seed {seed}: no garbage seen"
        );
        assert!(
            k.iter().any(|k| k.replayed > 0),
            "seed {seed}: no repeat seen"
        );
        println!(
            "seed {seed}: {v:?} after {:.1} s of channel; {}; board a sent {:.0} B/s; {:?}",
            c.now as f64 / HZ as f64,
            lag_line(&c.lags),
            k[0].sent_bytes as f64 * HZ as f64 / c.now as f64,
            k[0]
        );
        verdicts.push(v);
    }
    assert!(verdicts.contains(&Verdict::Won) && verdicts.contains(&Verdict::Lost));
}

/// Five seconds without a packet in the middle of a race: each board says
/// it is alone and plays on; when the channel comes back they catch up and
/// agree. (`RaceLink` and `Race` sizes are printed: a board keeps one.)
#[test]
fn a_blackout_mid_race_leaves_each_board_alone_then_they_agree() {
    println!(
        "RaceLink {} B, Race {} B",
        std::mem::size_of::<RaceLink>(),
        std::mem::size_of::<Race<'static, Fx>>()
    );
    let mazes = Mazes::new(&[SPEC_2]);
    let boards = vec![Board::new(1, SPEC_2, 0), Board::new(2, SPEC_2, 100)];
    let mut c = Channel::new(boards, CLEAR, 9);
    c.run(&mazes, 30 * HZ, |c| {
        c.boards
            .iter()
            .all(|b| b.race().is_some_and(|r| r.own_run().frames > 64))
    });
    let from = c.now;
    c.weather.blackout = (from, from + 5 * HZ);
    let mut alone = [false; 2];
    while c.now < from + 5 * HZ {
        c.frame(&mazes);
        for (i, b) in c.boards.iter().enumerate() {
            alone[i] |= b.race().unwrap().link().silent();
        }
    }
    assert_eq!(alone, [true, true], "both said they were alone");
    for b in &c.boards {
        let r = b.race().unwrap();
        assert!(r.own_run().frames > 5 * 128, "it played on alone");
    }
    c.run(&mazes, from + 60 * HZ, |c| c.boards.iter().all(settled));
    check_agreement(&c, 0, 1);
    assert!(c.boards.iter().all(|b| !b.race().unwrap().link().silent()));
}

/// A blackout longer than the outbox holds: the second board looks at the
/// maze for 3 000 frames (a flat board: blocks of 16 frames, 2 048 frames
/// in the outbox) while nothing gets through for 30 s, so its run outgrows
/// the outbox and can no longer reach the other whole. Nothing stalls: both
/// runs go on to their end, and whatever verdicts the boards still reach
/// (the runs they hold may settle it) mirror each other.
#[test]
fn a_blackout_longer_than_the_outbox_stalls_nothing() {
    let mazes = Mazes::new(&[SPEC_2]);
    let boards = vec![Board::new(1, SPEC_2, 0), Board::new(2, SPEC_2, 3000)];
    let mut c = Channel::new(boards, CLEAR, 5);
    c.run(&mazes, 30 * HZ, |c| {
        c.boards
            .iter()
            .all(|b| b.race().is_some_and(|r| r.own_run().frames > 64))
    });
    let from = c.now;
    c.weather.blackout = (from, from + 30 * HZ);
    c.run(&mazes, from + 60 * HZ, |_| false);
    let races: Vec<_> = c.boards.iter().map(|b| b.race().unwrap()).collect();
    for r in &races {
        assert_ne!(
            r.own_run().phase,
            Phase::Playing,
            "its run went on to its end"
        );
    }
    assert!(
        races[1].lost() && !races[0].lost(),
        "the long run outgrew its outbox"
    );
    if let (Some(a), Some(b)) = (races[0].verdict(), races[1].verdict()) {
        assert_eq!(a, b.mirrored());
    }
    println!("{}\n{}", describe(&c.boards[0]), describe(&c.boards[1]));
}

/// A board restarted in the middle of a race is a new board: its opponent
/// says it is alone after three seconds of silence, plays its run to its end
/// and claims no verdict; the restarted board never joins the old race; once
/// the survivor looks again, the two race anew and agree.
#[test]
fn a_board_restarted_mid_race_leaves_its_opponent_alone_then_races_again() {
    let mazes = Mazes::new(&[SPEC]);
    let weather = Weather {
        loss: 0.2,
        duplicate: 0.1,
        max_delay: HZ / 4,
        ..CLEAR
    };
    let boards = vec![Board::new(10, SPEC, 0), Board::new(20, SPEC, 0)];
    let mut c = Channel::new(boards, weather, 3);
    // Until both race, and one second more.
    c.run(&mazes, 30 * HZ, |c| {
        c.boards
            .iter()
            .all(|b| b.race().is_some_and(|r| r.own_run().frames > 128))
    });
    c.boards[1] = Board::new(5, SPEC, 0);
    let restarted_at = c.now;
    c.run(&mazes, restarted_at + 60 * HZ, |c| {
        c.boards[0]
            .race()
            .is_some_and(|r| r.own_run().phase != Phase::Playing && r.link().silent())
    });
    let a = c.boards[0].race().unwrap();
    assert!(a.link().silent(), "the survivor noticed the silence");
    assert!(c.now - restarted_at >= u64::from(SILENCE_FRAMES));
    assert_eq!(a.own_run().phase, Phase::Won, "it carried on alone");
    assert_eq!(a.verdict(), None, "no verdict without the opponent's run");
    assert_eq!(a.status(), Status::Waiting);
    assert_eq!(a.link().paired().unwrap().0, 20);
    assert!(
        c.boards[1].race().is_none(),
        "the restarted board never joined"
    );
    let restarted = c.boards[1].link().unwrap().counters();
    assert!(
        restarted.not_ours > 0,
        "the restarted board heard the old race"
    );
    // The survivor looks again: a new race with the restarted board.
    c.boards[0] = Board::new(30, SPEC, 50);
    let again = c.now;
    c.run(&mazes, again + 60 * HZ, |c| c.boards.iter().all(settled));
    assert_eq!(check_agreement(&c, 0, 1), Verdict::Lost);
}

/// Three boards on one channel: two race, the third hears their packets and
/// drops them; it never claims a verdict, and the two still agree.
#[test]
fn a_third_board_on_the_channel_changes_nothing() {
    let mazes = Mazes::new(&[SPEC, SPEC_2]);
    let weather = Weather {
        loss: 0.3,
        duplicate: 0.1,
        max_delay: HZ / 2,
        garbage: 0.01,
        ..CLEAR
    };
    for seed in 0..3u64 {
        let boards = vec![
            Board::new(50, SPEC, 0),
            Board::new(60, SPEC_2, 20),
            Board::new(70, SPEC, 40),
        ];
        let mut c = Channel::new(boards, weather, 40 + seed);
        c.run(&mazes, 90 * HZ, |c| {
            c.boards.iter().filter(|b| settled(b)).count() == 2
        });
        let racing: Vec<usize> = (0..3).filter(|&i| c.boards[i].race().is_some()).collect();
        assert_eq!(racing.len(), 2, "seed {seed}: exactly two boards race");
        check_agreement(&c, racing[0], racing[1]);
        let third = (0..3).find(|i| !racing.contains(i)).unwrap();
        let l = c.boards[third].link().unwrap();
        assert_ne!(l.stage(), LinkStage::Racing);
        assert!(
            l.counters().not_ours > 0,
            "seed {seed}: the third board heard the race"
        );
    }
}

/// A repeated packet is taken once: the second copy is counted as replayed
/// and changes nothing.
#[test]
fn a_repeated_packet_is_dropped_and_counted() {
    let id = |n| NonZeroU32::new(n).unwrap();
    let mut a = RaceLink::new(id(1), SPEC, Calibration::NONE);
    let mut b = RaceLink::new(id(2), SPEC, Calibration::NONE);
    let mut buf = [0u8; MAX_PACKET];
    // b's hello makes a (the lower id) propose; its proposal pairs b.
    let hello = loop {
        b.tick();
        if let Some(p) = b.transmit(&mut buf) {
            break p.to_vec();
        }
    };
    a.receive(&hello).unwrap();
    a.tick();
    let proposal = a.transmit(&mut buf).unwrap().to_vec();
    b.receive(&proposal).unwrap();
    assert_eq!(b.paired(), Some((1, SPEC)));
    assert_eq!(b.receive(&proposal), Err(Drop::Replayed));
    assert_eq!(b.counters().replayed, 1);
    // A packet of b's race from a board not in it.
    let mut w = Writer::race(&mut buf, 3, 2, 0, SPEC, Calibration::NONE, 0, false, None);
    assert!(w.block(0, &[1, 2]));
    let stranger = w.finish().to_vec();
    assert_eq!(b.receive(&stranger), Err(Drop::NotOurs));
    // The same packet from a, with another calibration: a contradiction.
    let w = Writer::race(
        &mut buf,
        1,
        2,
        9,
        SPEC,
        Calibration {
            offset_x: 3,
            offset_z: 0,
        },
        0,
        false,
        None,
    );
    assert!(!w.is_empty());
    let contradiction = w.finish().to_vec();
    assert_eq!(b.receive(&contradiction), Err(Drop::Inconsistent));
    assert_eq!(b.counters().dropped(), 3);
}

#[test]
fn packets_round_trip_and_fail_their_checks() {
    let mut buf = [0u8; MAX_PACKET];
    let hello = Writer::hello(&mut buf, 77, 5, SPEC_2).finish().to_vec();
    assert_eq!(hello.len(), packet::HELLO_BYTES);
    let p = packet::parse(&hello).unwrap();
    assert_eq!(
        (p.from, p.to, p.seq, p.maze, p.race),
        (77, 0, 5, SPEC_2, None)
    );

    let cal = Calibration {
        offset_x: -120,
        offset_z: 45,
    };
    let end = End {
        frames: 1234,
        hash: 0x0123_4567_89ab_cdef,
    };
    let mut w = Writer::race(&mut buf, 77, 78, 65535, SPEC, cal, 300, true, Some(end));
    assert!(w.block(300, &[3, 4, 5]));
    assert!(w.block(1 << 20, &[7; BLOCK_BYTES]));
    assert!(
        !w.block(0, &[0; BLOCK_BYTES + 1]),
        "a block longer than BLOCK_BYTES"
    );
    assert!(!w.block(0, &[]), "an empty block");
    let race = w.finish().to_vec();
    assert!(race.len() <= MAX_PACKET);
    let p = packet::parse(&race).unwrap();
    let body = p.race.unwrap();
    assert_eq!((p.from, p.to, p.seq), (77, 78, 65535));
    assert_eq!(
        (body.calibration, body.ack, body.have_end, body.end),
        (cal, 300, true, Some(end))
    );
    let blocks: Vec<_> = body.blocks().collect();
    assert_eq!(
        blocks,
        [(300, &[3u8, 4, 5][..]), (1 << 20, &[7u8; BLOCK_BYTES][..])]
    );

    // Every single bit flipped is caught.
    for bit in 0..race.len() * 8 {
        let mut b = race.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        assert_eq!(packet::parse(&b), Err(Drop::Crc), "bit {bit}");
    }
    assert_eq!(packet::parse(&race[..10]), Err(Drop::Length));
    assert_eq!(packet::parse(&[0u8; MAX_PACKET + 1]), Err(Drop::Length));
    assert_eq!(packet::parse(&race[..race.len() - 1]), Err(Drop::Crc));
    // Another version, another protocol, with their CRCs right.
    let resealed = |mut b: Vec<u8>, at: usize, v: u8| {
        b[at] = v;
        let n = b.len() - 2;
        let crc = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740).checksum(&b[..n]);
        b[n..].copy_from_slice(&crc.to_le_bytes());
        b
    };
    assert_eq!(
        packet::parse(&resealed(hello.clone(), 2, 2)),
        Err(Drop::Version)
    );
    assert_eq!(
        packet::parse(&resealed(hello.clone(), 0, b'X')),
        Err(Drop::Foreign)
    );
    assert_eq!(
        packet::parse(&resealed(hello.clone(), 3, 9)),
        Err(Drop::Foreign)
    );
    assert!(matches!(
        packet::parse(&resealed(race.clone(), 21 + 4, 0x80)),
        Err(Drop::Malformed { .. })
    ));
}

/// A board's link fed random bytes, and random bodies behind a right header
/// and CRC, in every stage: it drops them (or, for a sound packet, takes it)
/// without a panic, and counts every one.
fn link_in_stage(stage: u8) -> RaceLink {
    let id = |n| NonZeroU32::new(n).unwrap();
    let mut a = RaceLink::new(id(1), SPEC, Calibration::NONE);
    if stage == 0 {
        return a;
    }
    let mut b = RaceLink::new(id(2), SPEC, Calibration::NONE);
    let mut buf = [0u8; MAX_PACKET];
    let hello = Writer::hello(&mut buf, 2, 0, SPEC).finish().to_vec();
    a.receive(&hello).unwrap();
    a.tick();
    let p = a.transmit(&mut buf).unwrap().to_vec();
    b.receive(&p).unwrap();
    for f in 0..COUNTDOWN_FRAMES + 200 {
        b.tick();
        if b.stage() == LinkStage::Racing {
            b.push_own(AccelMg::new(f as i32 % 7, 1000, -(f as i32 % 5)))
                .unwrap();
        }
        if let Some(p) = b.transmit(&mut buf) {
            a.receive(p).unwrap();
        }
        a.tick();
    }
    a
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn random_bytes_never_panic_and_are_counted(
        stage in 0u8..2,
        packets in prop::collection::vec(prop::collection::vec(any::<u8>(), 0..200), 1..20),
    ) {
        let mut link = link_in_stage(stage);
        let before = *link.counters();
        for p in &packets {
            let _ = link.receive(p);
        }
        let after = link.counters();
        prop_assert_eq!(after.received - before.received, packets.len() as u32);
        prop_assert_eq!(
            (after.accepted - before.accepted) + (after.dropped() - before.dropped()),
            packets.len() as u32
        );
    }

    #[test]
    fn random_bodies_behind_a_sound_header_never_panic(
        stage in 0u8..2,
        from in prop::sample::select(vec![1u32, 2, 3]),
        body in prop::collection::vec(any::<u8>(), 0..150),
        seq in any::<u16>(),
    ) {
        let mut link = link_in_stage(stage);
        let mut buf = [0u8; MAX_PACKET];
        let w = Writer::race(&mut buf, from, 1, seq, SPEC, Calibration::NONE, 0, false, None);
        let head = w.len();
        let mut bytes = buf[..head].to_vec();
        // The fixed fields of the body and then the random rest.
        bytes.truncate(21);
        bytes.extend_from_slice(&body);
        bytes.truncate(MAX_PACKET - 2);
        let crc = crc::Crc::<u16>::new(&crc::CRC_16_IBM_3740).checksum(&bytes);
        bytes.extend_from_slice(&crc.to_le_bytes());
        let _ = link.receive(&bytes);
        let mut out = [0u8; MAX_PACKET];
        for _ in 0..8 {
            link.tick();
            let _ = link.transmit(&mut out);
        }
        let k = link.counters();
        prop_assert_eq!(k.accepted + k.dropped(), k.received);
    }

    /// The verdict from two runs as far as they are known is the whole runs'
    /// verdict or none, and each side's is the other's mirrored.
    #[test]
    fn an_early_verdict_is_the_final_one(
        fa in 1u32..2000, fb in 1u32..2000,
        ea in 0u8..3, eb in 0u8..3,
        sa in 0u32..2000, sb in 0u32..2000,
    ) {
        let phase = |e| [Phase::Won, Phase::Fell, Phase::TimeUp][e as usize];
        let whole_a = Run { frames: fa, phase: phase(ea) };
        let whole_b = Run { frames: fb, phase: phase(eb) };
        let part = |whole: Run, seen: u32| if seen >= whole.frames {
            whole
        } else {
            Run { frames: seen, phase: Phase::Playing }
        };
        let final_v = decide(whole_a, whole_b).unwrap();
        let (pa, pb) = (part(whole_a, sa), part(whole_b, sb));
        let early = decide(pa, pb);
        prop_assert!(early.is_none() || early == Some(final_v));
        prop_assert_eq!(decide(pb, pa), early.map(Verdict::mirrored));
    }
}

/// The ghost's token writer, as the blocks use it: a frame that does not fit
/// leaves the run of repeated readings before it to `finish`, which writes it.
#[test]
fn a_full_block_keeps_the_run_before_the_frame_that_did_not_fit() {
    use marble_rolling::game::ghost::{Readings, TokenWriter};
    let mut buf = [0u8; 4];
    let before = AccelMg::LEVEL;
    let mut w = TokenWriter::new(&mut buf, before);
    w.push(AccelMg::new(1, 1000, 0)).unwrap(); // 2 bytes
    w.push(AccelMg::new(1, 1000, 0)).unwrap(); // a run, written later
    w.push(AccelMg::new(1, 1000, 0)).unwrap();
    assert!(
        w.push(AccelMg::new(900, -900, 900)).is_err(),
        "3 changes of 2 bytes do not fit"
    );
    assert_eq!(w.frames(), 3);
    let tokens = w.finish().unwrap();
    let back: Vec<_> = Readings::from_tokens(tokens, before)
        .map(Result::unwrap)
        .collect();
    assert_eq!(back, [AccelMg::new(1, 1000, 0); 3]);
}

/// `cargo play -- --race`'s sides over real UDP sockets on localhost, in one
/// process: they pair, race the lower id's offer with the autopilot, and
/// agree, each replay on the other's hash.
#[cfg(feature = "tools")]
#[test]
fn two_sides_race_over_localhost_udp() {
    use marble_rolling::host::race::UdpBoard;
    use std::net::UdpSocket;
    let (sa, sb) = (
        UdpSocket::bind("127.0.0.1:0").unwrap(),
        UdpSocket::bind("127.0.0.1:0").unwrap(),
    );
    let (aa, ab) = (sa.local_addr().unwrap(), sb.local_addr().unwrap());
    let id = |n| NonZeroU32::new(n).unwrap();
    let mut a = UdpBoard::new(sa, ab, id(3), SPEC).unwrap();
    let mut b = UdpBoard::new(sb, aa, id(4), SPEC_2).unwrap();
    let done = |u: &UdpBoard| u.race().is_some_and(Race::finished);
    let pilot = |looks: u32| {
        move |s: &Session<'static, Fx>, ap: &mut Option<Autopilot>| {
            if s.game().frames() < looks {
                AccelMg::LEVEL
            } else {
                ap.as_mut().unwrap().reading_mg(s.game())
            }
        }
    };
    let mut frames = 0;
    while !(done(&a) && done(&b)) && frames < 60 * HZ {
        a.frame(pilot(0)).unwrap();
        b.frame(pilot(30)).unwrap();
        frames += 1;
        // A real socket hands a datagram over within microseconds; a short
        // pause now and then keeps the loop from outrunning it.
        if frames % 64 == 0 {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }
    let (ra, rb) = (a.race().unwrap(), b.race().unwrap());
    assert!(
        ra.finished() && rb.finished(),
        "not finished in {frames} frames"
    );
    assert_eq!(ra.link().paired().unwrap().1, SPEC, "the lower id's offer");
    assert_eq!(ra.verdict().unwrap(), rb.verdict().unwrap().mirrored());
    assert_eq!(ra.verdict(), Some(Verdict::Won));
    assert_eq!(rb.opponent().session().state_hash(), ra.own().state_hash());
    assert_eq!(ra.opponent().session().state_hash(), rb.own().state_hash());
    assert_eq!(ra.opponent().verified(), Some(true));
    assert_eq!(rb.opponent().verified(), Some(true));
}

/// A channel's two ports: the first side takes one, the second the other,
/// each sending to the other's; a third is refused with the ports named.
#[cfg(feature = "tools")]
#[test]
fn a_channel_takes_two_sides_and_refuses_a_third() {
    use marble_rolling::host::race::{channel_ports, channel_socket};
    let channel = 1234;
    let (p, q) = channel_ports(channel).unwrap();
    let (s1, to1) = channel_socket(channel).unwrap();
    let (s2, to2) = channel_socket(channel).unwrap();
    assert_eq!(s1.local_addr().unwrap().port(), p);
    assert_eq!(
        (to1.port(), s2.local_addr().unwrap().port(), to2.port()),
        (q, q, p)
    );
    let e = channel_socket(channel).err().unwrap();
    assert!(
        e.contains(&format!("ports {p} and {q} are both taken")),
        "{e}"
    );
    assert!(channel_ports(u16::MAX).is_err());
}

/// The race over a byte stream, as a UART between two boards carries it
/// (`race::wire`): each side joins the other's stream mid-frame, and bytes
/// are lost (0.3 %), flipped (0.3 %) or inserted (0.1 %). A damaged frame is
/// dropped by COBS or the packet's CRC; the boards agree.
#[test]
fn two_boards_agree_over_a_faulty_byte_stream() {
    let mazes = Mazes::new(&[SPEC]);
    let mut boards = [Board::new(5, SPEC, 0), Board::new(6, SPEC, 25)];
    let mut unframers = [Unframer::new(), Unframer::new()];
    let mut dice = Dice(77);
    let (mut bytes, mut damaged, mut packets) = (0u64, 0u32, 0u32);
    // The first bytes of each stream are not heard: a frame's tail comes first.
    let mut deaf = [5usize, 11];
    for _ in 0..60 * HZ {
        for from in 0..2 {
            let mut out = Vec::new();
            boards[from].frame(&mazes, &mut out);
            let to = 1 - from;
            for p in out {
                let mut buf = [0u8; MAX_FRAME];
                for &byte in wire::frame(&p, &mut buf) {
                    bytes += 1;
                    if deaf[to] > 0 {
                        deaf[to] -= 1;
                        continue;
                    }
                    let mut heard = Vec::with_capacity(2);
                    if dice.chance(0.001) {
                        heard.push(dice.next() as u8);
                    }
                    if !dice.chance(0.003) {
                        let flip = if dice.chance(0.003) {
                            1 << dice.below(8)
                        } else {
                            0
                        };
                        heard.push(byte ^ flip);
                    }
                    for b in heard {
                        match unframers[to].push(b) {
                            Ok(packet) => {
                                let packet = packet.to_vec();
                                packets += 1;
                                boards[to].receive(&packet);
                            }
                            Err(Unframed::Nothing) => {}
                            Err(Unframed::TooLong | Unframed::Invalid) => damaged += 1,
                        }
                    }
                }
            }
        }
        if boards.iter().all(settled) {
            break;
        }
    }
    assert!(boards.iter().all(settled), "not settled");
    check_pair(&boards[0], &boards[1]);
    let unframed = damaged;
    for b in &boards {
        let k = b.link().unwrap().counters();
        damaged += k.crc + k.length + k.foreign + k.version + k.malformed;
    }
    assert!(
        unframed > 0 && damaged > unframed,
        "damage caught by COBS and by the CRC"
    );
    println!("{bytes} bytes framed, {packets} packets unframed, {damaged} damaged frames dropped");
}

#[test]
fn a_framed_packet_unframes_whole_and_a_long_frame_is_dropped() {
    let mut buf = [0u8; MAX_PACKET];
    let mut w = Writer::race(&mut buf, 1, 2, 0, SPEC, Calibration::NONE, 0, false, None);
    assert!(w.block(0, &[0, 0, 5, 0]));
    let packet = w.finish().to_vec();
    let mut framed = [0u8; MAX_FRAME];
    let bytes = wire::frame(&packet, &mut framed).to_vec();
    assert_eq!(
        bytes.iter().filter(|&&b| b == 0).count(),
        1,
        "one 0, at the end"
    );
    let mut u = Unframer::new();
    let (last, body) = bytes.split_last().unwrap();
    for &b in body {
        assert_eq!(u.push(b), Err(Unframed::Nothing));
    }
    assert_eq!(u.push(*last), Ok(&packet[..]));
    for _ in 0..MAX_FRAME + 1 {
        let _ = u.push(7);
    }
    assert_eq!(u.push(0), Err(Unframed::TooLong));
    assert_eq!(u.push(0), Err(Unframed::Nothing), "an empty frame");
    for &b in &bytes {
        let _ = u.push(b);
    }
    assert_eq!(packet::parse(&packet).unwrap().from, 1);
}

proptest! {
    /// Random bytes into the unframer never panic; whatever comes out is at
    /// most a packet long.
    #[test]
    fn random_bytes_into_the_unframer_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        let mut u = Unframer::new();
        for b in bytes {
            if let Ok(p) = u.push(b) {
                prop_assert!(p.len() <= MAX_PACKET);
            }
        }
    }
}

// The micro:bit v2's race: its links of the lean sizes over a radio of groups
// (`race::air`), the chooser of channel and group, and the race on its matrix.

type LeanRace = Race<'static, Fx, LEAN_OUT_BLOCKS, LEAN_INBOX_READINGS, LEAN_EARLY_BLOCKS>;

/// A board of the lean sizes in a group: looking for an opponent, or racing
/// with the autopilot at its tilt (flat for `looks` frames first).
enum LeanBoard {
    Linking(Box<LeanLink>),
    Racing(Box<(LeanRace, Autopilot)>),
}

struct OnAir {
    board: LeanBoard,
    group: u8,
    looks: u32,
    /// Frames dropped before the protocol: another group's.
    other_group: u32,
}

impl OnAir {
    fn new(id: u32, group: u8, looks: u32) -> OnAir {
        let id = NonZeroU32::new(id).unwrap();
        OnAir {
            board: LeanBoard::Linking(Box::new(LeanLink::sized(id, offer(id), Calibration::NONE))),
            group,
            looks,
            other_group: 0,
        }
    }

    fn race(&self) -> Option<&LeanRace> {
        match &self.board {
            LeanBoard::Racing(r) => Some(&r.0),
            LeanBoard::Linking(_) => None,
        }
    }

    fn hear(&mut self, frame: &[u8]) {
        match air::unframe(self.group, frame) {
            Ok(p) => {
                let _ = match &mut self.board {
                    LeanBoard::Linking(l) => l.receive(p),
                    LeanBoard::Racing(r) => r.0.receive(p),
                };
            }
            Err(AirDrop::OtherGroup) => self.other_group += 1,
            Err(AirDrop::Length) => panic!("a frame of a wrong length on the air"),
        }
    }

    /// One frame; the frame to put on the air, if any.
    fn frame(&mut self) -> Option<Vec<u8>> {
        let mut buf = [0u8; MAX_PACKET];
        let mut out = [0u8; AIR_FRAME];
        let packet = match &mut self.board {
            LeanBoard::Linking(l) => {
                l.tick();
                let p = l.transmit(&mut buf).map(<[u8]>::to_vec);
                if let Some((_, spec)) = l.paired() {
                    let text: &'static str =
                        Box::leak(maze(spec).unwrap().to_string().into_boxed_str());
                    let level: &'static Level<'static, WORDS> =
                        Box::leak(Box::new(parse::<WORDS>(text).unwrap()));
                    let view = level.view();
                    let race = Race::new((**l).clone(), view).unwrap();
                    self.board = LeanBoard::Racing(Box::new((race, Autopilot::new(&view))));
                }
                p
            }
            LeanBoard::Racing(racing) => {
                let (r, autopilot) = &mut **racing;
                let looks = self.looks;
                r.frame(|s| {
                    if s.game().frames() < looks {
                        AccelMg::LEVEL
                    } else {
                        autopilot.reading_mg(s.game())
                    }
                });
                r.transmit(&mut buf).map(<[u8]>::to_vec)
            }
        };
        packet.map(|p| {
            assert!(p.len() <= MAX_PACKET);
            air::frame(self.group, &p, &mut out).unwrap().to_vec()
        })
    }
}

/// Two boards of the lean sizes race in group 3 through a radio that loses
/// a third of the frames, repeats one in five and delays each copy up to a
/// quarter second, while a third board in group 5 on the same channel calls
/// for an opponent: the two agree, each replay on the other's hash, and the
/// third hears none of them (nor they it) past the group byte.
#[test]
fn lean_links_race_over_a_lossy_radio_beside_another_group() {
    for seed in 1..=3u64 {
        let mut boards = vec![
            OnAir::new(7, 3, 0),
            OnAir::new(9, 3, 40),
            OnAir::new(11, 5, 0),
        ];
        let mut dice = Dice(seed);
        let mut flying: Vec<(u64, usize, Vec<u8>)> = Vec::new();
        let mut now = 0u64;
        let done = |b: &[OnAir]| b[..2].iter().all(|b| b.race().is_some_and(Race::finished));
        while now < 60 * HZ && !done(&boards) {
            now += 1;
            let (arrived, rest): (Vec<_>, Vec<_>) = flying.drain(..).partition(|f| f.0 <= now);
            flying = rest;
            for (_, to, bytes) in arrived {
                boards[to].hear(&bytes);
            }
            for from in 0..boards.len() {
                let Some(frame) = boards[from].frame() else {
                    continue;
                };
                for to in (0..boards.len()).filter(|&t| t != from) {
                    if dice.chance(0.33) {
                        continue;
                    }
                    let copies = if dice.chance(0.2) { 2 } else { 1 };
                    for _ in 0..copies {
                        flying.push((now + 1 + dice.below(32), to, frame.clone()));
                    }
                }
            }
        }
        assert!(done(&boards), "seed {seed}: not settled in a minute");
        let (a, b) = (boards[0].race().unwrap(), boards[1].race().unwrap());
        assert_eq!(a.verdict().unwrap(), b.verdict().unwrap().mirrored());
        for (me, them) in [(a, b), (b, a)] {
            assert_eq!(me.opponent().verified(), Some(true));
            assert_eq!(me.opponent().run(), them.own_run());
            assert_eq!(
                me.opponent().session().state_hash(),
                them.own().state_hash()
            );
        }
        let third = &boards[2];
        assert!(third.race().is_none(), "the other group's board raced");
        assert!(third.other_group > 0 && boards[0].other_group > 0);
        println!(
            "seed {seed}: {:?} in {} frames; group 5's board dropped {} frames, group 3's {} and {}",
            a.verdict().unwrap(),
            now,
            third.other_group,
            boards[0].other_group,
            boards[1].other_group
        );
    }
}

#[test]
fn a_packet_on_the_air_carries_its_group() {
    let mut buf = [0u8; MAX_PACKET];
    let mut w = Writer::race(&mut buf, 1, 2, 0, SPEC, Calibration::NONE, 0, false, None);
    assert!(w.block(0, &[0, 0, 5, 0]));
    let packet = w.finish().to_vec();
    let mut out = [0u8; AIR_FRAME];
    let frame = air::frame(9, &packet, &mut out).unwrap().to_vec();
    assert_eq!(frame[0], 9);
    assert_eq!(air::unframe(9, &frame), Ok(&packet[..]));
    assert_eq!(air::unframe(8, &frame), Err(AirDrop::OtherGroup));
    assert_eq!(air::unframe(9, &[]), Err(AirDrop::Length));
    assert_eq!(
        air::unframe(9, &[9; AIR_FRAME + 1]),
        Err(AirDrop::Length),
        "longer than a radio frame"
    );
    let longest = [0u8; MAX_PACKET];
    assert_eq!(
        air::frame(1, &longest, &mut out).map(<[u8]>::len),
        Some(AIR_FRAME)
    );
    assert_eq!(air::frame(1, &[0u8; MAX_PACKET + 1], &mut out), None);
}

/// A counts up, B chooses: the channel, then the group; both wrap round, and
/// the long presses choose nothing.
#[test]
fn the_chooser_counts_with_a_and_chooses_with_b() {
    let lit = |s: &RaceSetup| {
        let d = s.dots();
        let count = d[..4].iter().flatten().filter(|&&x| x).count();
        let marker: Vec<usize> = (0..5).filter(|&x| d[4][x]).collect();
        (count, marker)
    };
    let mut s = RaceSetup::new(Tuning::DEFAULT);
    assert_eq!((s.field(), s.count()), (Field::Channel, 1));
    assert_eq!(lit(&s), (1, vec![0]));
    for _ in 0..3 {
        assert_eq!(s.command(Command::Restart), None);
    }
    assert_eq!(s.tuning().channel, 14);
    assert_eq!(lit(&s), (4, vec![0]));
    for c in [
        Command::Calibrate,
        Command::ToggleMute,
        Command::ToggleAutopilot,
        Command::Quit,
    ] {
        assert_eq!(s.command(c), None);
    }
    assert_eq!((s.field(), s.tuning().channel), (Field::Channel, 14));
    assert_eq!(s.command(Command::NextLevel), None);
    assert_eq!((s.field(), s.count()), (Field::Group, 1));
    assert_eq!(lit(&s), (1, vec![4]));
    for _ in 0..17 {
        s.command(Command::Restart);
    }
    assert_eq!(s.tuning().group, 1, "16 groups, wrapping");
    assert_eq!(
        s.command(Command::NextLevel),
        Some(Tuning {
            channel: 14,
            group: 1
        })
    );
    // The channel wraps from 26 to 11; its sixteen values take the four rows.
    let mut s = RaceSetup::new(Tuning::new(26, 15).unwrap());
    assert_eq!(lit(&s), (16, vec![0]));
    s.command(Command::Restart);
    assert_eq!(s.tuning().channel, FIRST_CHANNEL);
    assert_eq!(Tuning::new(LAST_CHANNEL + 1, 0), None);
    assert_eq!(Tuning::new(FIRST_CHANNEL, GROUPS), None);
    // A start out of range starts from the default's value for that field.
    let s = RaceSetup::new(Tuning {
        channel: 3,
        group: 2,
    });
    assert_eq!(s.tuning(), Tuning::new(11, 2).unwrap());
    let s = RaceSetup::new(Tuning {
        channel: 200,
        group: 200,
    });
    assert_eq!(s.tuning(), Tuning::DEFAULT);
}

#[test]
fn a_alone_at_power_on_asks_for_a_race_unless_waking() {
    assert!(race_at_power_on(true, false, false));
    assert!(
        !race_at_power_on(true, false, true),
        "the wake-up resumes the game"
    );
    assert!(!race_at_power_on(true, true, false), "A+B: the records");
    assert!(!race_at_power_on(false, true, false), "B: the self-test");
    assert!(!race_at_power_on(false, false, false));
}

#[test]
fn each_race_of_a_board_has_a_new_id_and_maze() {
    let ids: std::collections::BTreeSet<u32> =
        (0..1000).map(|n| race_id(0xDEAD_BEEF, n).get()).collect();
    assert_eq!(ids.len(), 1000);
    assert_ne!(race_id(1, 0), race_id(2, 0));
    let id = race_id(5, 0);
    assert_eq!(offer(id).seed, id.get());
    assert!(maze(offer(id)).is_ok(), "the offer is a maze");
}

/// The race on a 5×5 matrix: bars counting down, then the maze with the
/// opponent's marble added at OPPONENT brightness (or, while the opponent is
/// silent, the bottom-right pixel blinking instead), then the verdict.
#[test]
fn the_race_on_a_matrix_draws_the_opponent_dimmer() {
    assert_eq!(OPPONENT, GHOST);
    let bars = |f: &Frame<5, 5>| (0..5).filter(|&x| f.get(x, 0) > 0).count();
    assert_eq!(bars(&countdown_frame::<5, 5>(COUNTDOWN_FRAMES)), 3);
    assert_eq!(bars(&countdown_frame::<5, 5>(200)), 2);
    assert_eq!(bars(&countdown_frame::<5, 5>(1)), 1);
    assert_ne!(
        verdict_frame::<5, 5>(Verdict::Won),
        verdict_frame(Verdict::Lost)
    );
    let lit = |f: Frame<5, 5>| f.iter().filter(|p| p.2 > 0).count();
    assert_eq!(lit(searching_frame(0)), 1);
    assert_ne!(searching_frame::<5, 5>(0), searching_frame(16));
    assert_eq!(lit(setup_frame(&RaceSetup::new(Tuning::DEFAULT))), 2);

    let mut boards = [OnAir::new(7, 0, 0), OnAir::new(9, 0, 40)];
    // The race's renderer, and one that draws the maze alone: both follow
    // the same marble through the same frames.
    let (mut renderer, mut plain_renderer) = (Renderer::<5, 5>::new(), Renderer::<5, 5>::new());
    let (mut countdown, mut with_opponent, mut verdicts) = (0, 0, 0);
    for now in 0..40 * HZ {
        for from in 0..2 {
            if let Some(f) = boards[from].frame() {
                boards[1 - from].hear(&f);
            }
        }
        let Some(r) = boards[1].race() else {
            continue;
        };
        let frame = race_frame(&mut renderer, r);
        match r.status() {
            Status::Countdown(left) => {
                assert_eq!(frame, countdown_frame(left));
                countdown += 1;
            }
            Status::Decided(v) if r.own().game().phase() != Phase::Playing => {
                assert_eq!(frame, verdict_frame(v));
                verdicts += 1;
            }
            _ => {
                // The maze as the game draws it, and the opponent on top.
                let plain = plain_renderer.render(r.own().game());
                let added: i32 = frame
                    .iter()
                    .map(|(x, y, b)| i32::from(b) - i32::from(plain.get(x, y)))
                    .sum();
                assert!(frame.iter().all(|(x, y, b)| b >= plain.get(x, y)));
                assert!(added <= i32::from(OPPONENT), "at {now}: {added}");
                if added > 0 {
                    with_opponent += 1;
                }
            }
        }
        if boards.iter().all(|b| b.race().is_some_and(Race::finished)) {
            break;
        }
    }
    assert!(countdown > 0 && verdicts > 0, "{countdown} {verdicts}");
    assert!(
        with_opponent > 100,
        "the opponent drawn on {with_opponent} frames"
    );
}

/// A silent opponent is not drawn: the bottom-right pixel blinks.
#[test]
fn a_silent_opponent_is_not_drawn() {
    let mut boards = [OnAir::new(7, 0, 0), OnAir::new(9, 0, 0)];
    let (mut renderer, mut plain_renderer) = (Renderer::<5, 5>::new(), Renderer::<5, 5>::new());
    let (mut silent, mut blinks) = (0, 0);
    for _ in 0..20 * HZ {
        // Board 1 goes on alone once the race starts: nothing reaches it.
        let started = boards[1]
            .race()
            .is_some_and(|r| r.link().stage() == LinkStage::Racing);
        for from in 0..2 {
            if let Some(f) = boards[from].frame() {
                if !started {
                    boards[1 - from].hear(&f);
                }
            }
        }
        let Some(r) = boards[1].race() else {
            continue;
        };
        if !r.link().silent() || r.own().game().phase() != Phase::Playing {
            continue;
        }
        let frame = race_frame(&mut renderer, r);
        let plain = plain_renderer.render(r.own().game());
        for (x, y, b) in frame.iter() {
            if (x, y) != (4, 4) {
                assert_eq!(b, plain.get(x, y));
            }
        }
        if frame.get(4, 4) == MAX_BRIGHTNESS && plain.get(4, 4) < MAX_BRIGHTNESS {
            blinks += 1;
        }
        silent += 1;
    }
    assert!(silent > HZ as i32, "silent for {silent} frames");
    assert!(
        blinks > 0 && blinks < silent,
        "the corner lit on {blinks} of {silent} frames"
    );
}

// The round a board's race task plays (`player::race::RaceRound`).

const V2_REACH: Reach = marble_rolling::board::microbit::MAZE_REACH;
type V2Slot = MazeSlot<{ V2_REACH.words() }, { V2_REACH.text_bytes() }>;
type V2Round<'a> = RaceRound<
    'a,
    Fx,
    LEAN_OUT_BLOCKS,
    LEAN_INBOX_READINGS,
    LEAN_EARLY_BLOCKS,
    { V2_REACH.words() },
    { V2_REACH.text_bytes() },
    5,
    5,
>;

/// Two rounds linked directly: they pair, count down, race (the autopilots;
/// the second looks for 40 frames first) and report the verdict; the
/// buttons do nothing during the run, then A and B end the rounds.
#[test]
fn a_round_looks_pairs_races_and_ends_on_a_button() {
    let (mut slot_a, mut slot_b) = (V2Slot::new(V2_REACH), V2Slot::new(V2_REACH));
    let mut rounds = [
        V2Round::new(NonZeroU32::new(7).unwrap(), &mut slot_a),
        V2Round::new(NonZeroU32::new(9).unwrap(), &mut slot_b),
    ];
    let mut pilots: [Option<Autopilot>; 2] = [None, None];
    let mut events: [Vec<RoundEvent>; 2] = [Vec::new(), Vec::new()];
    let mut exits = [None, None];
    let mut buf = [0u8; MAX_PACKET];
    for now in 0..60 * HZ {
        for i in 0..2 {
            if exits[i].is_some() {
                continue;
            }
            let looking = rounds[i].race().is_none();
            if looking {
                let now = rounds[i].link().unwrap().now();
                assert_eq!(rounds[i].picture(), searching_frame(now));
            }
            let over = rounds[i]
                .race()
                .is_some_and(|r| r.own().game().phase() != Phase::Playing);
            // During the run the buttons do nothing; once it is over and
            // both boards are done, A on one and B on the other.
            let finished = rounds.iter().all(|r| r.race().is_some_and(Race::finished));
            let command = match (over, finished) {
                (true, true) => Some([Command::Restart, Command::NextLevel][i]),
                (false, _) if !looking => Some([Command::NextLevel, Command::Restart][i]),
                _ => None,
            };
            let pilot = &mut pilots[i];
            match rounds[i].frame(command, |s| {
                let p = pilot.get_or_insert_with(|| Autopilot::new(s.game().level()));
                if i == 1 && s.game().frames() < 40 {
                    AccelMg::LEVEL
                } else {
                    p.reading_mg(s.game())
                }
            }) {
                Ok(Some(e)) => events[i].push(e),
                Ok(None) => {}
                Err(exit) => exits[i] = Some(exit),
            }
            if let Some(p) = rounds[i].transmit(&mut buf) {
                let _ = rounds[1 - i].receive(p);
            }
            let _ = rounds[i].picture();
        }
        if exits.iter().all(Option::is_some) {
            println!("both rounds over after {now} frames");
            break;
        }
    }
    assert_eq!(exits, [Some(RoundExit::Again), Some(RoundExit::Choose)]);
    let verdicts: Vec<Verdict> = events
        .iter()
        .map(|e| {
            assert!(matches!(e[0], RoundEvent::Paired { .. }), "{e:?}");
            assert_eq!(e[1], RoundEvent::Go, "{e:?}");
            // Decided as soon as no frame to come can change it: maybe
            // before the replay reaches the opponent's end.
            match e.last() {
                Some(RoundEvent::Verdict { verdict, .. }) => *verdict,
                other => panic!("no verdict: {other:?}"),
            }
        })
        .collect();
    assert_eq!(verdicts, [Verdict::Won, Verdict::Lost]);
    for (me, them) in [(0, 1), (1, 0)] {
        let (me, them) = (rounds[me].race().unwrap(), rounds[them].race().unwrap());
        assert_eq!(me.opponent().verified(), Some(true));
        assert_eq!(
            me.opponent().session().state_hash(),
            them.own().state_hash()
        );
    }
    let RoundEvent::Paired { peer, maze } = events[1][0] else {
        unreachable!()
    };
    assert_eq!((peer, maze), (7, offer(NonZeroU32::new(7).unwrap())));
}

#[test]
fn b_while_looking_ends_the_round_for_the_chooser() {
    let mut slot = V2Slot::new(V2_REACH);
    let mut round = V2Round::new(NonZeroU32::new(3).unwrap(), &mut slot);
    assert_eq!(
        round.frame(Some(Command::Restart), |_| AccelMg::LEVEL),
        Ok(None)
    );
    assert_eq!(round.frame(None, |_| AccelMg::LEVEL), Ok(None));
    assert_eq!(
        round.frame(Some(Command::NextLevel), |_| AccelMg::LEVEL),
        Err(RoundExit::Choose)
    );
}

/// The opponent's maze is larger than this board keeps: the round says so
/// and ends, to look for another race; nothing panics.
#[test]
fn a_maze_beyond_the_boards_reach_ends_the_round() {
    const SMALL: Reach = Reach {
        size: 4,
        storeys: 1,
    };
    let mut small = MazeSlot::<{ SMALL.words() }, { SMALL.text_bytes() }>::new(SMALL);
    let mut big = V2Slot::new(V2_REACH);
    // The lower id proposes its offer (5 cells a side): the higher cannot hold it.
    let mut proposer = V2Round::new(NonZeroU32::new(2).unwrap(), &mut big);
    let mut refuser = RaceRound::<
        Fx,
        LEAN_OUT_BLOCKS,
        LEAN_INBOX_READINGS,
        LEAN_EARLY_BLOCKS,
        { SMALL.words() },
        { SMALL.text_bytes() },
        5,
        5,
    >::new(NonZeroU32::new(8).unwrap(), &mut small);
    let mut buf = [0u8; MAX_PACKET];
    let mut refused = None;
    for _ in 0..10 * HZ {
        let _ = proposer.frame(None, |_| AccelMg::LEVEL);
        if let Some(p) = proposer.transmit(&mut buf) {
            let _ = refuser.receive(p);
        }
        match refuser.frame(None, |_| AccelMg::LEVEL) {
            Ok(Some(RoundEvent::Refused(e))) => refused = Some(e),
            Ok(_) => {}
            Err(exit) => {
                assert_eq!(exit, RoundExit::Again);
                break;
            }
        }
        if let Some(p) = refuser.transmit(&mut buf) {
            let _ = proposer.receive(p);
        }
    }
    assert!(
        matches!(refused, Some(MazeError::BeyondReach(_))),
        "{refused:?}"
    );
    assert_eq!(refuser.picture(), Frame::<5, 5>::new());
}
