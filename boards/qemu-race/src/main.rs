//! One of two QEMU mps2-an386 boards racing (`cargo xtask qemu-race`): the race
//! protocol (`marble_rolling::race`) over UART1, whose bytes QEMU's socket
//! character device hands to the xtask, which relays them to the other board
//! through its link model. The autopilot plays (after `--looks N` frames of a
//! flat board); the board logs its verdict, its own run and its replay of the
//! opponent's, then exits 0 (1 if the race did not finish in time).
//!
//! Each frame it also draws the race as QEMU's 19 × 9 matrix would show it
//! (`render::race::race_frame`: this board's marble, the opponent's replay at
//! the ghost's brightness) and counts the frames the opponent's marble is on
//! it; a picture of the matrix mid-race goes to the log for the xtask to show.
//!
//! The frame loop is paced at 128 frames/s on TIMER0 (virtual time under
//! `-icount`); everything between the UART and the race is `race::wire` and
//! `race::Race`, host-tested in `tests/race.rs`. UART1 is polled once a frame:
//! its receive register holds one byte, and QEMU's socket backend waits while
//! it is full, so nothing is lost, only later.
#![no_std]
#![no_main]

use core::fmt::Write as _;
use core::num::NonZeroU32;

use defmt_semihosting as _;
use marble_qemu as hw;
use marble_rolling::board::qemu::{HEIGHT, WIDTH};
use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::level::parse;
use marble_rolling::game::rules::Phase;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::sensor::Calibration;
use marble_rolling::race::wire::{self, Unframer, MAX_FRAME};
use marble_rolling::race::{self, MazeSpec, Race, RaceLink, Status, Verdict, MAX_PACKET};
use marble_rolling::render::race::race_frame;
use marble_rolling::render::Renderer;

/// CMSDK APB UART1 of the an386 image (UART0 is the terminal).
mod uart1 {
    const BASE: usize = 0x4000_5000;
    const DATA: usize = BASE;
    const STATE: usize = BASE + 0x04;
    const CTRL: usize = BASE + 0x08;
    const BAUDDIV: usize = BASE + 0x10;
    const STATE_TX_FULL: u32 = 1 << 0;
    const STATE_RX_FULL: u32 = 1 << 1;
    const CTRL_TX_EN: u32 = 1 << 0;
    const CTRL_RX_EN: u32 = 1 << 1;

    fn read(addr: usize) -> u32 {
        // SAFETY: a CMSDK UART register of the an386 memory map.
        unsafe { core::ptr::read_volatile(addr as *const u32) }
    }

    fn write(addr: usize, value: u32) {
        // SAFETY: as in `read`.
        unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
    }

    /// TX and RX on, no interrupts (polled), a divider QEMU accepts (≥ 16).
    pub fn init() {
        write(CTRL, 0);
        write(BAUDDIV, 16);
        write(CTRL, CTRL_TX_EN | CTRL_RX_EN);
        // A byte that reached QEMU before RX was on made its socket stop
        // offering more until the guest reads DATA: read it once.
        let _ = read(DATA);
    }

    /// The next received byte, if one is waiting.
    pub fn try_read() -> Option<u8> {
        (read(STATE) & STATE_RX_FULL != 0).then(|| read(DATA) as u8)
    }

    /// Sends `bytes`, waiting while the transmit register is full.
    pub fn write_bytes(bytes: &[u8]) {
        for &b in bytes {
            while read(STATE) & STATE_TX_FULL != 0 {}
            write(DATA, u32::from(b));
        }
    }
}

/// The semihosting command line: `--id N --looks N --seed S --size N
/// --storeys N --difficulty D --seconds N`.
struct Args {
    id: u32,
    looks: u32,
    offer: MazeSpec,
    seconds: u32,
}

fn args() -> Args {
    let mut a = Args {
        id: 1,
        looks: 0,
        offer: MazeSpec {
            seed: 1,
            size: 5,
            storeys: 1,
            difficulty: 1,
        },
        seconds: 120,
    };
    let Ok(line) = semihosting::experimental::env::args::<256>() else {
        hw::fatal("no semihosting command line");
    };
    // The iterator's position lives in `line` itself: one pass, each value
    // read with the key before it.
    let mut key: Option<&str> = None;
    for arg in (&line).filter_map(Result::ok) {
        let Some(k) = key.take() else {
            key = Some(arg);
            continue;
        };
        let Ok(n) = arg.parse::<u32>() else {
            key = Some(arg);
            continue;
        };
        let small = u8::try_from(n).unwrap_or(u8::MAX);
        match k {
            "--id" => a.id = n,
            "--looks" => a.looks = n,
            "--seed" => a.offer.seed = n,
            "--size" => a.offer.size = small,
            "--storeys" => a.offer.storeys = small,
            "--difficulty" => a.offer.difficulty = small,
            "--seconds" => a.seconds = n,
            _ => {}
        }
    }
    a
}

/// Ticks of the 25 MHz clock per frame (128 frames/s).
const FRAME_TICKS: u64 = 25_000_000 / 128;
/// Frames to keep answering after the verdict, so that the opponent hears
/// the acknowledgements it still needs.
const LINGER_FRAMES: u32 = 256;
/// The matrix picture goes to the log once this board's run is this many
/// frames old (and the opponent's marble is on it).
const PICTURE_AT: u32 = 256;
/// Level text and grid for the largest race maze this board accepts.
const TEXT: usize = race_text_bytes();
const WORDS: usize = 2048;

const fn race_text_bytes() -> usize {
    marble_rolling::game::generate::text_bytes(9, 2)
}

#[cortex_m_rt::entry]
fn main() -> ! {
    hw::clock::start();
    uart1::init();
    let a = args();
    let Some(id) = NonZeroU32::new(a.id) else {
        hw::fatal("--id 0: a board id is never 0");
    };
    defmt::info!(
        "race board {=u32}: offering maze {=u32} size {=u8} storeys {=u8} difficulty {=u8}",
        a.id,
        a.offer.seed,
        a.offer.size,
        a.offer.storeys,
        a.offer.difficulty
    );
    let mut link = RaceLink::new(id, a.offer, Calibration::NONE);
    let mut unframer = Unframer::new();
    let mut packet = [0u8; MAX_PACKET];
    let mut framed = [0u8; MAX_FRAME];
    let mut next = hw::clock::ticks();
    let limit = a.seconds.saturating_mul(128);
    let mut frames = 0u32;
    // Until paired.
    let spec = loop {
        pace(&mut next, |b| {
            if let Ok(p) = unframer.push(b) {
                let _ = link.receive(p);
            }
        });
        frames += 1;
        link.tick();
        if let Some(p) = link.transmit(&mut packet) {
            uart1::write_bytes(wire::frame(p, &mut framed));
        }
        if let Some((_, spec)) = link.paired() {
            break spec;
        }
        if frames > limit {
            let k = link.counters();
            defmt::error!(
                "no opponent: {=u32} packets sent, {=u32} received, {=u32} dropped",
                k.sent,
                k.received,
                k.dropped()
            );
            hw::exit(1);
        }
    };
    let Ok(maze) = race::maze(spec) else {
        hw::fatal("the agreed maze cannot be generated");
    };
    let mut text: heapless::String<TEXT> = heapless::String::new();
    if write!(text, "{maze}").is_err() {
        hw::fatal("the agreed maze is larger than this board takes");
    }
    let Ok(level) = parse::<WORDS>(&text) else {
        hw::fatal("the agreed maze does not parse");
    };
    let view = level.view();
    let mut autopilot = Autopilot::new(&view);
    let Ok(mut race) = Race::<marble_rolling::physics::Fx>::new(link, view) else {
        hw::fatal("the race cannot start");
    };
    defmt::info!(
        "paired with board {=u32}: maze {=u32} size {=u8} storeys {=u8} difficulty {=u8}",
        race.link().paired().map_or(0, |p| p.0),
        spec.seed,
        spec.size,
        spec.storeys,
        spec.difficulty
    );
    let mut linger = 0;
    // Frames the opponent's replay is behind: sum, samples, most.
    let mut lag = (0u64, 0u32, 0u32);
    // The race's picture, and the maze alone through a renderer that follows
    // the same marble: where they differ, the opponent is drawn.
    let (mut renderer, mut plain) = (
        Renderer::<WIDTH, HEIGHT>::new(),
        Renderer::<WIDTH, HEIGHT>::new(),
    );
    // Frames with both runs going on, and those with the opponent drawn.
    let mut drawn = (0u32, 0u32);
    let mut pictured = false;
    loop {
        pace(&mut next, |b| {
            if let Ok(p) = unframer.push(b) {
                let _ = race.receive(p);
            }
        });
        frames += 1;
        let looks = a.looks;
        race.frame(|s| {
            if s.game().frames() < looks {
                AccelMg::LEVEL
            } else {
                autopilot.reading_mg(s.game())
            }
        });
        if let Some(p) = race.transmit(&mut packet) {
            uart1::write_bytes(wire::frame(p, &mut framed));
        }
        let (own, opp) = (race.own_run(), race.opponent().run());
        let picture = race_frame(&mut renderer, &race);
        let maze_shown = match race.status() {
            Status::Countdown(_) => false,
            Status::Decided(_) => own.phase == Phase::Playing,
            _ => true,
        };
        if maze_shown {
            let maze = plain.render(race.own().game());
            if own.frames > 0 && own.phase == Phase::Playing && opp.phase == Phase::Playing {
                drawn.0 += 1;
                if picture != maze {
                    drawn.1 += 1;
                    if !pictured && own.frames >= PICTURE_AT {
                        pictured = true;
                        defmt::info!(
                            "race matrix at frame {=u32}, opponent at frame {=u32}: {}",
                            own.frames,
                            opp.frames,
                            picture.rows()
                        );
                    }
                }
            }
        }
        if own.frames > 0 && own.phase == Phase::Playing && opp.phase == Phase::Playing {
            // How far behind the opponent's marble is drawn.
            let behind = own.frames.saturating_sub(opp.frames);
            lag.0 += u64::from(behind);
            lag.1 += 1;
            lag.2 = lag.2.max(behind);
        }
        if race.finished() {
            linger += 1;
            if linger >= LINGER_FRAMES {
                break;
            }
        }
        if frames > limit {
            report(&race);
            hw::fatal("the race did not finish in time");
        }
    }
    report(&race);
    defmt::info!(
        "race matrix: the opponent drawn on {=u32} of {=u32} frames while both ran",
        drawn.1,
        drawn.0
    );
    defmt::info!(
        "race lag: the opponent drawn {=u64} frames behind on average, {=u32} at most ({=u32} frames sampled)",
        lag.0 / u64::from(lag.1.max(1)),
        lag.2,
        lag.1
    );
    hw::exit(0)
}

/// Waits for the next frame's time, handing `byte` every byte UART1 receives
/// meanwhile: its register holds one, and QEMU refills it between guest
/// instructions, so the wait polls it all along.
fn pace(next: &mut u64, mut byte: impl FnMut(u8)) {
    *next += FRAME_TICKS;
    loop {
        while let Some(b) = uart1::try_read() {
            byte(b);
        }
        if hw::clock::ticks() >= *next {
            return;
        }
    }
}

fn report(race: &Race<'_, marble_rolling::physics::Fx>) {
    let verdict = match race.status() {
        Status::Decided(Verdict::Won) => "won",
        Status::Decided(Verdict::Lost) => "lost",
        Status::Decided(Verdict::Draw) => "draw",
        _ => "none",
    };
    let (own, opp) = (race.own_run(), race.opponent().run());
    let k = race.link().counters();
    defmt::info!(
        "race: verdict {=str}; own {=str} in {=u32} frames, state_hash={=u64:016x}; opponent {=str} in {=u32} frames, state_hash={=u64:016x}, verified {=bool}",
        verdict,
        own.phase.as_str(),
        own.frames,
        race.own().state_hash(),
        opp.phase.as_str(),
        opp.frames,
        race.opponent().session().state_hash(),
        race.opponent().verified() == Some(true)
    );
    defmt::info!(
        "race link: {=u32} packets sent ({=u32} B), {=u32} received, {=u32} dropped",
        k.sent,
        k.sent_bytes,
        k.received,
        k.dropped()
    );
}
