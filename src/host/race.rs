//! `cargo play -- --race`: a race between two terminals over UDP on this
//! machine ([`crate::race`] carries it; this module only moves its bytes and
//! draws it).
//!
//! A channel is a pair of ports on 127.0.0.1 (`--channel N`: 47 400 + 2N and
//! the next): the first player to start takes the first port and sends to the
//! second, the second player the other way round; a third finds both taken
//! and is told so. Each side offers a generated maze (`--generate SEED`
//! chooses it, else a new seed) and races the one the handshake agrees on.
//!
//! [`UdpBoard`] is one side without a terminal (`tests/race.rs` races two in
//! one process over real sockets); `run` is the terminal around it.

use std::io::{self, IsTerminal, Write};
use std::net::{SocketAddr, UdpSocket};
use std::string::{String, ToString};
use std::time::{Duration, Instant};
use std::vec::Vec;
use std::{eprintln, format};

use crossterm::event::{self, Event};
use crossterm::style::Print;
use crossterm::terminal::{self, Clear, ClearType};
use crossterm::{cursor, execute, queue};

use super::play::{key_of, Args, Picture, TerminalGuard};
use crate::game::autopilot::Autopilot;
use crate::game::level::LevelView;
use crate::game::session::Session;
use crate::input::axes::AccelMg;
use crate::input::event::InputEvent;
use crate::input::keys::{Key, KeyTilt};
use crate::input::sensor::Calibration;
use crate::physics::Fx as I8F24;
use crate::player::FRAME_HZ;
use crate::race::{self, LinkStage, MazeSpec, Race, RaceLink, Status, Verdict, MAX_PACKET};
use crate::render::tile_point;

/// The first port of channel 0.
pub(crate) const BASE_PORT: u16 = 47_400;

/// The ports of `channel`: the pair (`BASE_PORT + 2 channel`, the next).
pub fn channel_ports(channel: u16) -> Result<(u16, u16), String> {
    let first = channel
        .checked_mul(2)
        .and_then(|c| BASE_PORT.checked_add(c))
        .filter(|&p| p < u16::MAX)
        .ok_or_else(|| format!("channel {channel} is beyond the ports ({BASE_PORT} and up)"))?;
    Ok((first, first + 1))
}

/// This side's socket on `channel` and the other side's address: the first
/// port if free, else the second.
pub fn channel_socket(channel: u16) -> Result<(UdpSocket, SocketAddr), String> {
    let (a, b) = channel_ports(channel)?;
    let at = |p: u16| SocketAddr::from(([127, 0, 0, 1], p));
    match UdpSocket::bind(at(a)) {
        Ok(s) => Ok((s, at(b))),
        Err(_) => match UdpSocket::bind(at(b)) {
            Ok(s) => Ok((s, at(a))),
            Err(e) => Err(format!(
                "channel {channel}: ports {a} and {b} are both taken ({e}): two players \
                 already race on it; try --channel {}",
                channel.saturating_add(1)
            )),
        },
    }
}

/// A board id for this run: any non-zero number, different each start.
pub(crate) fn fresh_id() -> core::num::NonZeroU32 {
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64);
    let mixed = (t ^ (u64::from(std::process::id()) << 32)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    core::num::NonZeroU32::new((mixed >> 32) as u32).unwrap_or(core::num::NonZeroU32::MIN)
}

/// The generated maze of `spec`, parsed (leaked: one per race).
pub(crate) fn race_level(spec: MazeSpec) -> Result<LevelView<'static>, String> {
    let maze = race::maze(spec).map_err(|e| format!("the race's maze: {e}"))?;
    super::parse_runtime(maze.to_string())
        .map_err(|e| format!("internal error: the race's maze does not parse: {e}"))
}

enum Stage {
    Linking(std::boxed::Box<RaceLink>),
    Racing(std::boxed::Box<Race<'static, I8F24>>),
}

/// One side of a race over a UDP socket.
pub struct UdpBoard {
    socket: UdpSocket,
    peer: SocketAddr,
    stage: Stage,
    /// The autopilot of the race's maze, made when the race starts.
    pub(crate) autopilot: Option<Autopilot>,
}

impl UdpBoard {
    /// Board `id` offering `offer`, sending to `peer` from `socket` (made
    /// non-blocking).
    pub fn new(
        socket: UdpSocket,
        peer: SocketAddr,
        id: core::num::NonZeroU32,
        offer: MazeSpec,
    ) -> io::Result<UdpBoard> {
        socket.set_nonblocking(true)?;
        Ok(UdpBoard {
            socket,
            peer,
            stage: Stage::Linking(std::boxed::Box::new(RaceLink::new(
                id,
                offer,
                Calibration::NONE,
            ))),
            autopilot: None,
        })
    }

    /// The link.
    pub(crate) fn link(&self) -> &RaceLink {
        match &self.stage {
            Stage::Linking(l) => l,
            Stage::Racing(r) => r.link(),
        }
    }

    /// The race, once paired.
    pub fn race(&self) -> Option<&Race<'static, I8F24>> {
        match &self.stage {
            Stage::Racing(r) => Some(r),
            Stage::Linking(_) => None,
        }
    }

    /// One frame: takes every datagram waiting, plays the frame (the reading
    /// from `reading`, asked only when this side's run plays one), sends what
    /// is due. A send the network refuses is a lost packet, as on the radio.
    pub fn frame(
        &mut self,
        reading: impl FnOnce(&Session<'static, I8F24>, &mut Option<Autopilot>) -> AccelMg,
    ) -> Result<(), String> {
        let mut buf = [0u8; 2 * MAX_PACKET];
        loop {
            match self.socket.recv_from(&mut buf) {
                Ok((n, _)) => {
                    let _ = match &mut self.stage {
                        Stage::Linking(l) => l.receive(&buf[..n]),
                        Stage::Racing(r) => r.receive(&buf[..n]),
                    };
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                // A port with nobody on it yet answers on Linux with an error
                // on the next receive: nothing to take.
                Err(e) if e.kind() == io::ErrorKind::ConnectionRefused => continue,
                Err(e) => return Err(format!("receiving: {e}")),
            }
        }
        let mut out = [0u8; MAX_PACKET];
        let packet = match &mut self.stage {
            Stage::Linking(l) => {
                l.tick();
                let p = l.transmit(&mut out).map(<[u8]>::to_vec);
                if let Some((_, spec)) = l.paired() {
                    let level = race_level(spec)?;
                    self.autopilot = Some(Autopilot::new(&level));
                    let link = (**l).clone();
                    let race = Race::new(link, level).map_err(|e| e.to_string())?;
                    self.stage = Stage::Racing(std::boxed::Box::new(race));
                }
                p
            }
            Stage::Racing(r) => {
                let autopilot = &mut self.autopilot;
                r.frame(|s| reading(s, autopilot));
                r.transmit(&mut out).map(<[u8]>::to_vec)
            }
        };
        if let Some(p) = packet {
            let _ = self.socket.send_to(&p, self.peer);
        }
        Ok(())
    }
}

/// `cargo play -- --race`: checks the offer and the terminal, then races
/// (`run`); returns the exit status.
pub fn main(args: &Args) -> i32 {
    use super::generated::{DEFAULT_DIFFICULTY, DEFAULT_SIZE};
    let offer = crate::race::MazeSpec {
        seed: args.maze.generate.unwrap_or_else(|| fresh_id().get()),
        size: args.maze.size.unwrap_or(DEFAULT_SIZE),
        storeys: args.maze.storeys.unwrap_or(1),
        difficulty: args.maze.difficulty.unwrap_or(DEFAULT_DIFFICULTY),
    };
    if let Err(e) = crate::race::maze(offer) {
        eprintln!("play: error: {e}");
        return 2;
    }
    if !std::io::stdin().is_terminal() || !std::io::stdout().is_terminal() {
        eprintln!("play: error: standard input and output must be a terminal to race");
        return 2;
    }
    match run(args.channel, offer, args.autopilot) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("play: error: {e}");
            1
        }
    }
}

/// `cargo play -- --race`: races in the terminal on `channel`, offering
/// `offer`; `autopilot` starts with the autopilot at the controls.
pub(crate) fn run(channel: u16, offer: MazeSpec, autopilot: bool) -> Result<(), String> {
    let (socket, peer) = channel_socket(channel)?;
    let port = socket.local_addr().map(|a| a.port()).unwrap_or(0);
    let board = UdpBoard::new(socket, peer, fresh_id(), offer).map_err(|e| e.to_string())?;
    let guard = TerminalGuard::enter().map_err(|e| format!("cannot set up the terminal: {e}"))?;
    let mut screen = Screen {
        board,
        keys: KeyTilt::new(),
        autopilot,
        channel,
        port,
        out: io::stdout(),
        buf: Vec::with_capacity(1 << 16),
        view: None,
    };
    let r = screen.run().map_err(|e| e.to_string());
    drop(guard);
    r
}

struct Screen {
    board: UdpBoard,
    keys: KeyTilt,
    autopilot: bool,
    channel: u16,
    port: u16,
    out: io::Stdout,
    buf: Vec<u8>,
    view: Option<(i32, i32)>,
}

impl Screen {
    fn run(&mut self) -> io::Result<()> {
        let period = Duration::from_secs(1) / FRAME_HZ;
        let mut next = Instant::now();
        let mut frame = 0u32;
        execute!(self.out, Clear(ClearType::All))?;
        loop {
            let now = Instant::now();
            if now < next {
                if event::poll(next - now)? {
                    if let Event::Key(k) = event::read()? {
                        match key_of(k) {
                            Some(Key::Quit) => return Ok(()),
                            Some(Key::Autopilot) => self.autopilot = !self.autopilot,
                            // One run per race: no restart, next level or
                            // calibration in the middle of it.
                            Some(Key::Restart | Key::Next | Key::Calibrate) | None => {}
                            Some(key) => {
                                let _: InputEvent = self.keys.press(key);
                            }
                        }
                    }
                }
                continue;
            }
            let (keys, pilot) = (self.keys.tilt(), self.autopilot);
            self.board
                .frame(|s, a| match (pilot, a.as_mut()) {
                    (true, Some(a)) => a.reading_mg(s.game()),
                    _ => keys,
                })
                .map_err(io::Error::other)?;
            frame = frame.wrapping_add(1);
            if frame.is_multiple_of(4) {
                self.draw()?;
            }
            next += period;
            if now.saturating_duration_since(next) > Duration::from_millis(250) {
                next = now;
            }
        }
    }

    fn draw(&mut self) -> io::Result<()> {
        let (cols, rows) = terminal::size().unwrap_or((80, 24));
        let b = &mut self.buf;
        b.clear();
        let mut lines: Vec<String> = Vec::new();
        let hz = FRAME_HZ as f64;
        let link = self.board.link();
        let k = link.counters();
        match self.board.race() {
            None => {
                queue!(b, cursor::MoveTo(0, 0), Clear(ClearType::All))?;
                lines.push(match link.stage() {
                    LinkStage::Proposed => "found a board: pairing…".to_string(),
                    _ => format!(
                        "race on channel {} (port {}): waiting for an opponent — start \
                         `cargo play -- --race` in another terminal",
                        self.channel, self.port
                    ),
                });
            }
            Some(race) => {
                let h = draw_matrix(b, race, &mut self.view, cols, rows)?;
                queue!(b, cursor::MoveTo(0, h as u16 + 1))?;
                let (own, opp) = (race.own_run(), race.opponent().run());
                let status = match race.status() {
                    Status::Countdown(n) => format!("get ready: {:.0}…", (n as f64 / hz).ceil()),
                    Status::Racing => format!(
                        "you {:.2} s · opponent {:.2} s",
                        own.frames as f64 / hz,
                        opp.frames as f64 / hz
                    ),
                    Status::Waiting => format!(
                        "you: {} after {:.2} s · waiting for the opponent ({:.2} s so far)",
                        own.phase.as_str(),
                        own.frames as f64 / hz,
                        opp.frames as f64 / hz
                    ),
                    Status::Decided(v) => {
                        let gap = own.frames.abs_diff(opp.frames) as f64 / hz;
                        match v {
                            Verdict::Won => format!("YOU WON (by {gap:.2} s)"),
                            Verdict::Lost => format!("you lost (by {gap:.2} s)"),
                            Verdict::Draw => "a draw".to_string(),
                        }
                    }
                };
                let maze = link.paired().map_or(String::new(), |(_, s)| {
                    format!(
                        "maze {} size {} storeys {} difficulty {}",
                        s.seed, s.size, s.storeys, s.difficulty
                    )
                });
                lines.push(format!("race: {maze}  {status}"));
                if link.silent() {
                    lines.push(format!(
                        "opponent silent for {:.0} s: racing alone",
                        link.quiet_frames() as f64 / hz
                    ));
                } else if race.lost() {
                    lines.push("the opponent missed too much of your run: no verdict".to_string());
                } else {
                    lines.push(String::new());
                }
            }
        }
        let reading = self.keys.tilt();
        lines.push(format!(
            "tilt x {:+5} mg z {:+5} mg{}   packets sent {} received {} dropped {}",
            -reading.x,
            -reading.z,
            if self.autopilot { " [autopilot]" } else { "" },
            k.sent,
            k.received,
            k.dropped()
        ));
        lines.push("arrows/WASD tilt · space level · p autopilot · q quit".to_string());
        for l in lines {
            let shown: String = l.chars().take(cols as usize).collect();
            queue!(
                b,
                Print(shown),
                Clear(ClearType::UntilNewLine),
                Print("\r\n")
            )?;
        }
        self.out.write_all(b)?;
        self.out.flush()
    }
}

/// The own maze with both marbles (the opponent's dim), sized to the terminal;
/// returns the rows drawn.
fn draw_matrix(
    b: &mut Vec<u8>,
    race: &Race<'static, I8F24>,
    view: &mut Option<(i32, i32)>,
    cols: u16,
    rows: u16,
) -> io::Result<usize> {
    let game = race.own().game();
    let mut pic = Picture::of(game, view, cols, rows.saturating_sub(5));
    let layout = &game.world().params().layout;
    for m in race.opponent().session().game().world().marbles() {
        if !m.out {
            let (i, k) = tile_point(layout, m.pos.x, m.pos.z).tile();
            pic.dim(i, k, layout.storey_of(m.pos.y));
        }
    }
    pic.queue(b)?;
    Ok(pic.rows())
}
